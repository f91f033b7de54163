"""The retired scan kernel: an independent reference for asymmetric limits."""

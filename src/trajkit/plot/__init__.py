"""Figures (matplotlib), imported lazily: ``import trajkit.plot.profiles`` etc.

Nothing in the math layers imports this package. Every function takes planned
objects and returns a :class:`matplotlib.figure.Figure` (and writes it when
given a path); matplotlib is an optional dependency (``pip install trajkit[plot]``).
"""


def require_matplotlib():
    """Import matplotlib with the Agg backend, or raise a clear ImportError."""
    try:
        import matplotlib
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError(
            "plotting needs matplotlib: pip install 'trajkit[plot]'"
        ) from exc
    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "ps", "cairo"):
        try:
            matplotlib.use("Agg")
        except Exception:  # pragma: no cover
            pass
    import matplotlib.pyplot as plt

    return plt

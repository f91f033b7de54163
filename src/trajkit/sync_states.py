"""Alias module: :func:`plan_ptp_states` is defined in :mod:`trajkit.sync.states`."""

from __future__ import annotations

from .sync.states import COLLINEAR_RTOL, STATE_SYNC_MODES, SYNC_MAX_ROUNDS, plan_ptp_states

__all__ = ["STATE_SYNC_MODES", "COLLINEAR_RTOL", "SYNC_MAX_ROUNDS", "plan_ptp_states"]

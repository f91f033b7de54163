"""Exception tree of trajkit.

Every error raised on purpose by trajkit derives from :class:`TrajkitError`.
Bad input is an :class:`InvalidInputError`, which is also a :class:`ValueError`
so that generic callers can catch it the usual way. Messages always name the
field, the axis (where there is one), the offending value and the bound.
"""

from __future__ import annotations

__all__ = [
    "TrajkitError",
    "InvalidInputError",
    "InfeasibleError",
    "UnreachableError",
    "SafetyFault",
]


class TrajkitError(Exception):
    """Base class of every error trajkit raises on purpose."""


class InvalidInputError(TrajkitError, ValueError):
    """An argument is malformed, out of range, NaN, infinite where not allowed, ..."""


class InfeasibleError(TrajkitError):
    """The request is well-formed but cannot be met within the limits.

    Attributes
    ----------
    minimum : float or None
        Where it applies, the smallest feasible value of the requested
        quantity (e.g. the minimum duration [s]).
    """

    def __init__(self, message: str, minimum: float | None = None):
        super().__init__(message)
        self.minimum = minimum


class UnreachableError(TrajkitError):
    """A pose or point lies outside the workspace of a machine or robot."""


class SafetyFault(TrajkitError):
    """A runtime monitor tripped (overspeed, over-travel, following error, ...)."""

"""Geometric paths parameterised by arc length, and their chord discretisation.

All lengths in metres. ``Line``, ``Arc3`` (3-point spatial arc, Jiang 1987),
``CompositePath`` and ``SaddleCurve`` (pipe intersections, Chen et al. 2013)
share
the :class:`Path` interface: ``length``, ``point(s)``, ``tangent(s)``,
``curvature(s)`` vectorised in arc length ``s``.
"""

from .arc import Arc3, circle_through
from .base import Path
from .chords import (
    ChordSet,
    arc_step_for_tolerance,
    chord_deviations,
    chord_error,
    discretize,
    max_chord_length,
    uniform_chord_count,
)
from .composite import CompositePath
from .line import Line
from .saddle import SaddleCurve

__all__ = [
    "Path",
    "Line",
    "Arc3",
    "circle_through",
    "CompositePath",
    "SaddleCurve",
    "ChordSet",
    "chord_error",
    "max_chord_length",
    "arc_step_for_tolerance",
    "chord_deviations",
    "discretize",
    "uniform_chord_count",
]

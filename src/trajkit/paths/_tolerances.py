"""Named tolerances of the paths and interpolation layers (SI units)."""

from __future__ import annotations

#: Supported range of path geometry [m]: every coordinate, radius and offset
#: lies within +-MAX_COORDINATE (1000 km), ...
MAX_COORDINATE = 1e6

#: ... and every segment length, arc radius and pipe radius is at least
#: MIN_FEATURE (1 nm) ...
MIN_FEATURE = 1e-9

#: ... and at least this fraction of the largest coordinate of its points (a
#: 1 um arc 10 km from the origin has points known to 2e-12 m only). Inside
#: these ranges the geometry is exact to about 1e-9 relative; outside them
#: construction is refused (InvalidInputError).
MIN_RELATIVE_FEATURE = 1e-6

#: Arc points whose cross product |(p2-p1) x (p3-p1)| is below this fraction of
#: |p2-p1| |p3-p1| are collinear (the sine of the angle at p1); no arc.
COLLINEAR_SIN = 1e-9

#: Two points closer than this [m] coincide (zero-length line, repeated arc point).
COINCIDENT_DIST = 1e-12

#: Consecutive segments of a composite path must meet within this distance [m].
JOIN_DIST = 1e-9

#: Tangent jump [rad] above which a composite-path junction is a corner where
#: the feed must stop.
CORNER_ANGLE = 1e-6

#: Relative accuracy promised for saddle arc lengths (checked at construction
#: by comparing two Gauss-Legendre tables of different size).
SADDLE_LENGTH_RTOL = 1e-12

#: Saddle arc length inside a table interval as a Chebyshev series (the
#: inverse map theta(s) uses it): ds/dtheta's coefficients are kept down to
#: this fraction of the first one (the mean speed; round-off is ~1e-16 of it) ...
SADDLE_FIT_CHOP = 4e-16

#: ... and the series must give the Gauss-Legendre partial arc lengths of its
#: interval within this fraction of the interval's arc length (checked at
#: construction; measured <= 1e-15, the sums' round-off), else the interval
#: keeps the quadrature. An interval's arc length is below the whole length,
#: so the series is within ARC_INVERSION_RTOL / 2 of the length; theta(s)
#: moves by at most this fraction of the interval's angle times its mean
#: speed over the local one (~1e-16 rad on 64-interval tables).
SADDLE_FIT_RTOL = 4e-15

#: Newton iterations converge when the arc-length residual is below this
#: fraction of the path length.
ARC_INVERSION_RTOL = 1e-14

#: Newton stops after the step that follows a residual below this fraction
#: of the branch radius: the step squares it (error ~ 1e-18 r, checked in tests).
NEWTON_LAST_STEP = 1e-9

#: Maximum Newton iterations when mapping arc length to the curve parameter.
ARC_INVERSION_MAX_ITER = 40

#: Gauss-Legendre order used inside each table interval.
GAUSS_ORDER = 16

#: Relative slack allowed on an arc-length argument outside [0, length]
#: (round-off); beyond it the argument is an error.
S_RANGE_RTOL = 1e-12

#: A step ending closer than this fraction of itself to a forced node (corner,
#: end) is stretched to it, so no sliver chord remains.
SNAP_FRACTION = 1e-9

#: Angle slack [rad] on a theta argument outside its one-turn range (round-off).
THETA_RANGE_ATOL = 1e-12

#: Fraction of the tolerance that the adaptive chord stepper aims at (the
#: rest absorbs the curvature sampling error; violators are split).
CHORD_TARGET_FRACTION = 0.98

#: Samples per chord of the dense chord-error check (before the local refinement).
CHORD_CHECK_SAMPLES = 33

#: Golden-section iterations of the local refinement of a chord's deviation.
CHORD_REFINE_ITER = 24

"""The 4-axis cylindrical palletizing robot of Cao et al. (2012).

Joints (internal units SI):

* ``A`` = theta [rad], waist rotation about the vertical;
* ``B`` = Z [m], vertical stroke;
* ``C`` = R [m], horizontal reach;
* ``D`` = gripper rotation about the vertical [rad].

The axes are decoupled: ``(x, y, z) = (R cos theta, R sin theta, Z)`` and the
yaw of the gripped box in the world is ``theta + D``. A pose is
``(x, y, z, yaw)`` [m, m, m, rad]; a joint vector is ``(theta, z, r, d)``
[rad, m, m, rad]. Every function accepts one vector, shape (4,), or a batch,
shape (n, 4).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import check_array
from ..errors import InvalidInputError, UnreachableError
from ..limits import AxisLimits

__all__ = [
    "JOINT_NAMES",
    "CylindricalPalletizer",
    "default_palletizer",
    "DEFAULT_JOINT_TABLE",
]

#: Joint names, in order: waist theta, vertical Z, reach R, wrist rotation.
JOINT_NAMES = ("A", "B", "C", "D")

_DEG = math.pi / 180.0
_MM = 1e-3

#: The default palletizer, in the table's units (deg and mm): per joint
#: ``(v_max, a_max, j_max, range_min, range_max)``. Cao et al. (2012) give no
#: joint limits; these are trajkit's defaults for their robot.
DEFAULT_JOINT_TABLE: dict[str, tuple[float, float, float, float, float]] = {
    "A": (160.0, 620.0, 5400.0, -180.0, 180.0),       # deg/s, deg/s^2, deg/s^3, deg
    "B": (1300.0, 5200.0, 45000.0, 0.0, 2000.0),      # mm/s, mm/s^2, mm/s^3, mm
    "C": (1300.0, 5200.0, 45000.0, 300.0, 2200.0),    # mm
    "D": (315.0, 1550.0, 13600.0, -180.0, 180.0),     # deg
}

#: Unit factor from the table units (deg, mm) to SI (rad, m), per joint.
TABLE_TO_SI = {"A": _DEG, "B": _MM, "C": _MM, "D": _DEG}


def _wrap_pi(a: np.ndarray) -> np.ndarray:
    """Wrap angles to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class CylindricalPalletizer:
    """Kinematic model of a 4-axis cylindrical palletizer (A theta, B Z, C R, D wrist).

    Parameters
    ----------
    limits : sequence of 4 AxisLimits
        Per-joint limits in SI units (A and D in rad, B and C in m); the
        position range of each is the joint range. Names are set to
        ``"A".."D"`` when missing.
    name : str
        Robot name (reports).

    Raises
    ------
    InvalidInputError
        Not four AxisLimits, a joint range without finite bounds on B or C,
        or a reach range below zero.
    """

    limits: tuple[AxisLimits, AxisLimits, AxisLimits, AxisLimits]
    name: str = "cylindrical palletizer"

    def __post_init__(self) -> None:
        lims = tuple(self.limits)
        if len(lims) != 4 or not all(isinstance(x, AxisLimits) for x in lims):
            raise InvalidInputError(
                f"limits must be 4 AxisLimits (joints A, B, C, D), got {self.limits!r}"
            )
        lims = tuple(
            lim.with_name(n) if lim.name is None else lim for lim, n in zip(lims, JOINT_NAMES)
        )
        if lims[2].position_min < 0.0:
            raise InvalidInputError(
                f"reach range minimum position_min of joint C must be >= 0 m, "
                f"got {lims[2].position_min!r}"
            )
        object.__setattr__(self, "limits", lims)

    # ------------------------------------------------------------ construct
    @classmethod
    def from_table(
        cls,
        table: Mapping[str, Sequence[float]] | None = None,
        decel: Mapping[str, Sequence[float | None]] | None = None,
        name: str = "cylindrical palletizer",
    ) -> CylindricalPalletizer:
        """Build a robot from a table in deg and mm (the units of :data:`DEFAULT_JOINT_TABLE`).

        Parameters
        ----------
        table : dict, optional
            ``{"A": (v_max, a_max, j_max, min, max), ...}`` in deg/s, deg/s^2,
            deg/s^3, deg for A and D and mm/s, mm/s^2, mm/s^3, mm for B and
            C. Defaults to :data:`DEFAULT_JOINT_TABLE`.
        decel : dict, optional
            ``{"B": (a_max_decel, j_max_decel), ...}`` in the same units for
            joints with asymmetric limits; a ``None`` entry takes the accel
            leg's limit.
        """
        rows: Mapping[str, Sequence[float]] = DEFAULT_JOINT_TABLE if table is None else table
        decel = decel or {}
        lims = []
        for jn in JOINT_NAMES:
            if jn not in rows:
                raise InvalidInputError(f"joint table has no row for joint {jn}")
            row = tuple(rows[jn])
            if len(row) != 5:
                raise InvalidInputError(
                    f"joint table row of joint {jn} must be (v_max, a_max, j_max, min, max), "
                    f"got {row!r}"
                )
            ad, jd = (None, None)
            if jn in decel:
                ad, jd = decel[jn]
            lim = AxisLimits(row[0], row[1], row[2], ad, jd, row[3], row[4], name=jn)
            lims.append(lim.scaled(TABLE_TO_SI[jn]))
        a, b, c, d = lims  # one per joint of JOINT_NAMES
        return cls((a, b, c, d), name=name)

    # ------------------------------------------------------------ properties
    @property
    def joint_names(self) -> tuple[str, ...]:
        """``("A", "B", "C", "D")``."""
        return JOINT_NAMES

    @property
    def joint_ranges(self) -> np.ndarray:
        """Joint ranges, shape (4, 2): rows A..D, columns min, max [rad or m]."""
        return np.array([[lim.position_min, lim.position_max] for lim in self.limits])

    @property
    def z_top(self) -> float:
        """Highest position of joint B [m] (``Z_top`` of Cao et al., 2012)."""
        return self.limits[1].position_max

    # ------------------------------------------------------------ kinematics
    def pose_from_joints(self, joints: Any) -> np.ndarray:
        """Forward kinematics.

        Parameters
        ----------
        joints : array_like, shape (4,) or (n, 4)
            ``(theta [rad], z [m], r [m], d [rad])``.

        Returns
        -------
        ndarray, shape like ``joints``
            ``(x, y, z [m], yaw [rad])`` with ``yaw = theta + d`` (not wrapped).
        """
        q = _as_batch(joints, "joints")
        th, z, r, d = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
        out = np.stack([r * np.cos(th), r * np.sin(th), z, th + d], axis=-1)
        return out

    def joints_from_pose(
        self,
        pose: Any,
        wrist_reference: Any = 0.0,
        yaw_period: float = 2.0 * math.pi,
        check: bool = True,
    ) -> np.ndarray:
        """Inverse kinematics.

        ``theta = atan2(y, x)`` in (-pi, pi], ``r = hypot(x, y)``, ``z = z``,
        and the wrist angle ``d = yaw - theta + k * yaw_period`` is the one
        closest to ``wrist_reference`` inside the D range (a box that looks
        the same turned by 180 degrees has ``yaw_period = pi``).

        Parameters
        ----------
        pose : array_like, shape (4,) or (n, 4)
            ``(x [m], y [m], z [m], yaw [rad])``.
        wrist_reference : float or array_like, shape (n,)
            Wrist angle [rad] the solution should be near (the previous one).
        yaw_period : float
            Symmetry period of the gripped object's yaw [rad]; ``2 pi`` for
            none, ``pi`` for a rectangular box.
        check : bool
            Raise when a joint falls outside its range.

        Returns
        -------
        ndarray, shape like ``pose``
            ``(theta [rad], z [m], r [m], d [rad])``.

        Raises
        ------
        UnreachableError
            A pose on the vertical axis (theta undefined), or a joint outside
            its range (the message names the joint, the value and the range).
        """
        p = _as_batch(pose, "pose")
        if not (math.isfinite(yaw_period) and yaw_period > 0.0):
            raise InvalidInputError(f"yaw_period must be finite and > 0 rad, got {yaw_period!r}")
        x, y, z, yaw = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
        r = np.hypot(x, y)
        if np.any(r == 0.0):
            raise UnreachableError("pose on the vertical axis (x = y = 0): theta is undefined")
        th = np.arctan2(y, x)
        ref = np.broadcast_to(np.asarray(wrist_reference, dtype=float), th.shape)
        d0 = yaw - th
        lo, hi = self.limits[3].position_min, self.limits[3].position_max
        # candidates d0 + k*period; take the one nearest ref within range
        k0 = np.round((ref - d0) / yaw_period)
        best = np.full(th.shape, np.nan)
        best_cost = np.full(th.shape, np.inf)
        for dk in range(-4, 5):
            cand = d0 + (k0 + dk) * yaw_period
            ok = (cand >= lo) & (cand <= hi)
            cost = np.where(ok, np.abs(cand - ref), np.inf)
            better = cost < best_cost
            best = np.where(better, cand, best)
            best_cost = np.where(better, cost, best_cost)
        if np.any(np.isnan(best)):
            i = int(np.flatnonzero(np.isnan(np.atleast_1d(best)))[0])
            raise UnreachableError(
                f"no wrist angle of joint D inside [{math.degrees(lo):g}, {math.degrees(hi):g}] deg "
                f"for pose {i}"
            )
        q = np.stack([th, z, r, best], axis=-1)
        if check:
            self.check_joints(q, "pose")
        return q

    def check_joints(self, joints: Any, field: str = "joints") -> np.ndarray:
        """Raise :class:`UnreachableError` unless every joint is inside its range.

        Parameters
        ----------
        joints : array_like, shape (4,) or (n, 4)
        field : str
            Name used in the message.

        Returns
        -------
        ndarray
            The joints as float64.
        """
        q = _as_batch(joints, field)
        qq = np.atleast_2d(q)
        rng = self.joint_ranges
        for k, jn in enumerate(JOINT_NAMES):
            col = qq[:, k]
            bad = (col < rng[k, 0]) | (col > rng[k, 1])
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                unit, f = ("deg", 180.0 / math.pi) if jn in ("A", "D") else ("mm", 1000.0)
                where = f"{field}[{i}]" if q.ndim == 2 else field
                raise UnreachableError(
                    f"{where}: joint {jn} = {col[i] * f:.6g} {unit} is outside its range "
                    f"[{rng[k, 0] * f:g}, {rng[k, 1] * f:g}] {unit}"
                )
        return q

    def to_dict(self) -> dict:
        """JSON-ready description in the table units (deg, mm)."""
        out = {}
        for jn, lim in zip(JOINT_NAMES, self.limits):
            f = 1.0 / TABLE_TO_SI[jn]
            out[jn] = {
                "v_max": lim.v_max * f, "a_max": lim.a_max * f, "j_max": lim.j_max * f,
                "a_max_decel": lim.a_max_decel * f, "j_max_decel": lim.j_max_decel * f,
                "min": lim.position_min * f, "max": lim.position_max * f,
                "unit": "deg" if jn in ("A", "D") else "mm",
            }
        return out


def default_palletizer() -> CylindricalPalletizer:
    """The default palletizer (table :data:`DEFAULT_JOINT_TABLE`, converted to SI)."""
    return CylindricalPalletizer.from_table(DEFAULT_JOINT_TABLE, name="default palletizer")


def _as_batch(value: Any, field: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float) if not isinstance(value, np.ndarray) else value.astype(float)
    if arr.ndim not in (1, 2) or arr.shape[-1] != 4:
        raise InvalidInputError(f"{field} must have shape (4,) or (n, 4), got shape {arr.shape}")
    return check_array(arr, field, ndim=arr.ndim)

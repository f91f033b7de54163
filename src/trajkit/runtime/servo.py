"""Servo-axis simulation: motor + load with a cascaded position/velocity loop.

Each axis is a rigid motor and load (inertia ratio ``rho`` = actual /
nominal inertia; ``rho = 1`` means the drive knows the load exactly) driven
by a cascaded controller with feedforward::

    v_cmd = ff_velocity * v_ref + kp * (x_ref - x_measured)          position loop (P)
    u     = ff_acceleration * a_ref + kv * (v_cmd - v) + I            velocity loop (PI)
    dI/dt = ki * (v_cmd - v)
    dv/dt = u / rho,   dx/dt = v                                       motor and load

``u`` is the acceleration the drive commands [unit/s^2] (torque over the
nominal inertia), limited to ``a_drive``. Within one control period the
reference is the setpoint extrapolated at constant acceleration
(``x_ref(s) = x_k + v_k s + a_k s^2 / 2``), as a drive's fine interpolator
would do, so with ``rho = 1`` and full feedforward the following error is
only what the jerk leaves (``O(j dt^3)``). The linear closed loop is
discretised exactly (matrix exponential) once per period length; when the
drive limit ``a_drive`` would be hit the period is integrated in
``substeps`` explicit steps with the limit applied instead.

Emergency stop: the drive is disabled and the holding brake decelerates
the axis at ``brake_deceleration`` until it stops.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import expm

from .._validate import check_finite, check_positive
from ..errors import InvalidInputError

__all__ = ["ServoBank", "ServoParams"]


@dataclass(frozen=True)
class ServoParams:
    """Parameters of one simulated servo axis (documented defaults).

    Parameters
    ----------
    kp : float
        Position-loop gain [1/s] (velocity command per unit of error).
    kv : float
        Velocity-loop gain [1/s] (acceleration command per velocity error).
    ki : float
        Velocity-loop integral gain [1/s^2].
    ff_velocity, ff_acceleration : float
        Feedforward fractions in [0, 1].
    inertia_ratio : float
        Actual / nominal inertia (> 0); 1 is a perfectly known load, > 1 a
        heavier one (e.g. the 100 kg payload of Cao et al., 2012).
    a_drive : float
        Largest acceleration the drive can command [unit/s^2] (``inf``: none).
    brake_deceleration : float
        Deceleration of the holding brake on an emergency stop [unit/s^2].
    in_position : float
        In-position window [unit]: ``|following error|`` at or below it.
    settle_cycles : int
        Consecutive periods inside the window that count as "in position".
    settle_timeout : float
        Longest wait for in-position at an exact stop [s]; then the
        ``"in position"`` monitor trips.
    substeps : int
        Explicit sub-steps per period when the drive limit is active.
    """

    kp: float = 40.0
    kv: float = 400.0
    ki: float = 20000.0
    ff_velocity: float = 1.0
    ff_acceleration: float = 1.0
    inertia_ratio: float = 1.0
    a_drive: float = math.inf
    brake_deceleration: float = 20.0
    in_position: float = 1e-4
    settle_cycles: int = 5
    settle_timeout: float = 2.0
    substeps: int = 8

    def __post_init__(self) -> None:
        for f in ("kp", "kv", "inertia_ratio", "brake_deceleration", "in_position",
                  "settle_timeout"):
            check_positive(getattr(self, f), f)
        check_positive(self.a_drive, "a_drive", allow_inf=True)
        if check_finite(self.ki, "ki") < 0:
            raise InvalidInputError(f"ki must be >= 0, got {self.ki!r}")
        for f in ("ff_velocity", "ff_acceleration"):
            x = check_finite(getattr(self, f), f)
            if not 0.0 <= x <= 1.0:
                raise InvalidInputError(f"{f} must be in [0, 1], got {x!r}")
        for f in ("settle_cycles", "substeps"):
            x = getattr(self, f)
            if not isinstance(x, int) or x < 1:
                raise InvalidInputError(f"{f} must be an integer >= 1, got {x!r}")

    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """Continuous closed loop ``dz/dt = F z + G a_ref`` with ``z = (x, v, I, x_ref, v_ref)``.

        Returns
        -------
        F : ndarray, shape (5, 5)
        G : ndarray, shape (5,)
        """
        kp, kv, ki, r = self.kp, self.kv, self.ki, self.inertia_ratio
        fv, fa = self.ff_velocity, self.ff_acceleration
        F = np.array([
            [0.0, 1.0, 0.0, 0.0, 0.0],
            [-kv * kp / r, -kv / r, 1.0 / r, kv * kp / r, kv * fv / r],
            [-ki * kp, -ki, 0.0, ki * kp, ki * fv],
            [0.0, 0.0, 0.0, 0.0, 1.0],
            [0.0, 0.0, 0.0, 0.0, 0.0],
        ])
        G = np.array([0.0, fa / r, 0.0, 0.0, 1.0])
        return F, G


class ServoBank:
    """The simulated servo axes of a machine, advanced one control period at a time.

    Parameters
    ----------
    params : ServoParams or sequence of ServoParams
        One for all axes, or one per axis.
    n_axes : int
    period : float
        Control period [s].
    position : array_like, shape (n_axes,)
        Initial actual position [unit] (at rest, in position).

    Attributes
    ----------
    x, v : ndarray, shape (n_axes,)
        Actual position [unit] and velocity [unit/s] of the load.
    encoder_offset : ndarray, shape (n_axes,)
        Error added to the measured position (fault injection) [unit].
    braking : bool
        True after :meth:`engage_brake` (drive disabled).
    """

    def __init__(self, params: ServoParams | Sequence[ServoParams], n_axes: int,
                 period: float, position: Any) -> None:
        if isinstance(params, ServoParams):
            params = [params] * n_axes
        self.params = tuple(params)
        if len(self.params) != n_axes:
            raise InvalidInputError(
                f"servo params must be one or {n_axes} ServoParams, got {len(self.params)}"
            )
        self.n = n_axes
        self.period = check_positive(period, "period")
        self._z = np.zeros((n_axes, 5))
        self._z[:, 0] = np.array(position, dtype=float).reshape(n_axes)
        self.encoder_offset = np.zeros(n_axes)
        self.braking = False
        phi = np.empty((n_axes, 5, 5))
        gam = np.empty((n_axes, 5))
        for k, p in enumerate(self.params):
            F, G = p.matrices()
            M = np.zeros((6, 6))
            M[:5, :5] = F * self.period
            M[:5, 5] = G * self.period
            E = expm(M)
            phi[k] = E[:5, :5]
            gam[k] = E[:5, 5]
        self._phi = phi
        self._gam = gam
        self._a_drive = np.array([p.a_drive for p in self.params])
        self._limited = bool(np.isfinite(self._a_drive).any())
        self._brake = np.array([p.brake_deceleration for p in self.params])
        self.window = np.array([p.in_position for p in self.params])
        self.settle_cycles = max(p.settle_cycles for p in self.params)
        self.settle_timeout = max(p.settle_timeout for p in self.params)
        self._gains = np.array([[p.kp, p.kv, p.ki, p.ff_velocity, p.ff_acceleration,
                                 p.inertia_ratio] for p in self.params])
        self._sub = max(p.substeps for p in self.params)

    @property
    def x(self) -> np.ndarray:
        """Actual load position, shape (n_axes,) [unit]."""
        return self._z[:, 0]

    @x.setter
    def x(self, value) -> None:
        self._z[:, 0] = value

    @property
    def v(self) -> np.ndarray:
        """Actual velocity, shape (n_axes,) [unit/s]."""
        return self._z[:, 1]

    @v.setter
    def v(self, value) -> None:
        self._z[:, 1] = value

    @property
    def integ(self) -> np.ndarray:
        """Velocity-loop integrator state, shape (n_axes,) [unit/s^2]."""
        return self._z[:, 2]

    @integ.setter
    def integ(self, value) -> None:
        self._z[:, 2] = value

    @property
    def measured(self) -> np.ndarray:
        """Measured position (actual + encoder offset), shape (n_axes,) [unit]."""
        return self.x + self.encoder_offset

    def inject_encoder_jump(self, axis: int, delta: float) -> None:
        """Add ``delta`` [unit] to the measured position of ``axis`` from now on."""
        self.encoder_offset[axis] += delta

    def engage_brake(self) -> None:
        """Disable the drives and engage the holding brakes (emergency stop)."""
        self.braking = True
        self._z[:, 2] = 0.0

    def release_brake(self, resync: bool = True) -> None:
        """Re-enable the drives (after a reset)."""
        self.braking = False
        self._z[:, 2] = 0.0

    def step(self, x_ref: np.ndarray, v_ref: np.ndarray, a_ref: np.ndarray) -> None:
        """Advance one period from the setpoint ``(x_ref, v_ref, a_ref)`` (n_axes,) each."""
        h = self.period
        if self.braking:
            b = self._brake
            sp = np.abs(self.v)
            t_stop = np.minimum(sp / b, h)
            sgn = np.sign(self.v)
            self.x = self.x + sgn * (sp * t_stop - 0.5 * b * t_stop * t_stop)
            self.v = sgn * np.maximum(sp - b * h, 0.0)
            return
        xr = x_ref - self.encoder_offset
        if self._limited:
            kp, kv, _, fv, fa, _ = self._gains.T
            u = fa * a_ref + kv * (fv * v_ref + kp * (xr - self.x) - self.v) + self.integ
            if np.any(np.abs(u) > self._a_drive):
                self._step_saturated(xr, v_ref, a_ref)
                return
        z = self._z
        z[:, 3] = xr
        z[:, 4] = v_ref
        zn = np.matmul(self._phi, z[:, :, None])[:, :, 0]
        zn += self._gam * a_ref[:, None]
        self._z = zn

    def _step_saturated(self, xr, vr, ar) -> None:
        kp, kv, ki, fv, fa, rho = self._gains.T
        n = self._sub
        h = self.period / n
        x, v, integ = self.x.copy(), self.v.copy(), self.integ.copy()
        for i in range(n):
            s = i * h
            xs = xr + s * (vr + 0.5 * s * ar)
            vs = vr + s * ar
            vc = fv * vs + kp * (xs - x)
            u_raw = fa * ar + kv * (vc - v) + integ
            u = np.clip(u_raw, -self._a_drive, self._a_drive)
            # anti-windup: integrate only while the drive is not at its limit
            integ = np.where(u == u_raw, integ + ki * (vc - v) * h, integ)
            v_new = v + u / rho * h
            x = x + 0.5 * (v + v_new) * h
            v = v_new
        self.x, self.v, self.integ = x, v, integ


def cao2012_servo(robot: Any = None, inertia_ratio: float = 1.3) -> list[ServoParams]:
    """Servo parameters for the palletizing comparison with Cao et al. (2012) (joints A, B, C, D).

    The paper gives none. These describe a moderately tuned industrial drive:
    position gain 20 1/s, velocity loop 200 1/s with integral 5000 1/s^2,
    full velocity feedforward and half acceleration feedforward, computed for
    the nominal (empty-gripper) inertia, a load ``inertia_ratio`` times
    heavier (the 100 kg payload), an in-position window of 0.1 mm on the
    linear axes B, C and 0.1 mrad on the rotary axes A, D (about 0.14 mm at
    the 1.4 m reach), held for 5 ms. They were the second of three sets
    tried (see docs/runtime.md), not fitted to the paper.

    Parameters
    ----------
    robot : CylindricalPalletizer, optional
        Only its number of joints is used (4 by default).
    inertia_ratio : float
        Actual / nominal inertia.

    Returns
    -------
    list of ServoParams, one per joint
    """
    n = len(getattr(robot, "joint_kinds", range(4)))
    return [ServoParams(kp=20.0, kv=200.0, ki=5000.0, ff_velocity=1.0, ff_acceleration=0.5,
                        inertia_ratio=inertia_ratio, in_position=1e-4, settle_cycles=5)
            for _ in range(n)]

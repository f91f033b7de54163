"""Independent references and case generators for the state-to-state tests.

* :func:`ruckig_duration` -- ruckig (PyPI, test dependency only) for
  symmetric limits.
* :func:`double_s_duration` -- an independent minimum-time formula for
  one-direction moves between cruise states (``a0 = af = 0``,
  ``v0, vf >= 0``, no reversal) under ASYMMETRIC limits: the peak velocity
  is found by bisection on the distance, each velocity ramp by the textbook
  closed form (Biagiotti & Melchiorri's double-S with non-zero boundary
  velocities, extended to separate accel/decel limits).
* :func:`dense_check` -- limits and continuity on dense samples (independent
  of the kernel's exact verification).
* :func:`random_case` -- seeded random states over the hard corners;
  :func:`random_brake_case` -- starts outside the limits.
"""

from __future__ import annotations

import math

import numpy as np

#: Relative tolerance of the reference bisection.
REF_RTOL = 1e-14


def _ruckig_run(start, V, A, J, goal=None, goal_va=None, minimum_duration=None,
                catch_errors=False):
    """Duration of one ``Ruckig(1).calculate`` (symmetric limits), ``None`` if it fails.

    ``goal`` (p, v, a) for the position interface, ``goal_va`` (v, a) for the
    velocity interface; ``minimum_duration`` asks for at least that long;
    ``catch_errors`` turns ruckig's own ``RuckigError`` into ``None``.
    """
    traj = _ruckig_trajectory(start, V, A, J, goal, goal_va, minimum_duration, catch_errors)
    return None if traj is None else traj.duration


def _ruckig_trajectory(start, V, A, J, goal=None, goal_va=None, minimum_duration=None,
                       catch_errors=False):
    """ruckig's ``Trajectory`` of one ``Ruckig(1).calculate`` (see :func:`_ruckig_run`),
    ``None`` if it fails."""
    from ruckig import ControlInterface, InputParameter, Result, Ruckig, RuckigError, Trajectory

    inp = InputParameter(1)
    inp.current_position = [start[0]]
    inp.current_velocity = [start[1]]
    inp.current_acceleration = [start[2]]
    if goal_va is not None:
        inp.control_interface = ControlInterface.Velocity
        inp.target_velocity = [goal_va[0]]
        inp.target_acceleration = [goal_va[1]]
    else:
        inp.target_position = [goal[0]]
        inp.target_velocity = [goal[1]]
        inp.target_acceleration = [goal[2]]
    inp.max_velocity = [V]
    inp.max_acceleration = [A]
    inp.max_jerk = [J]
    if minimum_duration is not None:
        inp.minimum_duration = minimum_duration
    traj = Trajectory(1)
    try:
        res = Ruckig(1).calculate(inp, traj)
    except RuckigError:  # ruckig's own numerical failure
        if not catch_errors:
            raise
        return None
    if res not in (Result.Working, Result.Finished):
        return None
    return traj


def ruckig_goal_miss(start, goal, V, A, J):
    """How far ruckig's own profile ends from the goal position [m]: its phases
    (brake included) integrated in exact rational arithmetic. ruckig accepts a
    profile whose end lies within an absolute 1e-8 of the goal, which is coarse
    for a motion of a few nanometres."""
    from fractions import Fraction

    traj = _ruckig_trajectory(start, V, A, J, goal=goal)
    prof = traj.profiles[0][0]
    p, v, a = (Fraction(x) for x in start)
    for t, j in zip(list(prof.brake.t) + list(prof.t), list(prof.brake.j) + list(prof.j)):
        t, j = Fraction(t), Fraction(j)
        p, v, a = p + v * t + a * t * t / 2 + j * t**3 / 6, v + a * t + j * t * t / 2, a + j * t
    return abs(float(p - Fraction(goal[0])))


def ruckig_duration(start, goal, V, A, J, catch_errors=False):
    """Minimum duration from ruckig's ``Ruckig(1).calculate`` (symmetric limits).

    ``None`` where ruckig finds no profile; ``catch_errors`` also turns
    ruckig's ``RuckigError`` into ``None``.
    """
    return _ruckig_run(start, V, A, J, goal=goal, catch_errors=catch_errors)


def _ramp(dv, a, j):
    """Duration and distance factor of a rest-acceleration velocity ramp of size dv >= 0."""
    if dv <= 0.0:
        return 0.0
    if dv * j >= a * a:  # trapezoidal acceleration
        return dv / a + a / j
    return 2.0 * math.sqrt(dv / j)


def double_s_duration(d, v0, vf, V, A1, J1, A2, J2):
    """Minimum duration of a one-direction move with a0 = af = 0 (asymmetric).

    Requires ``d > 0`` large enough that no reversal is needed; returns
    ``None`` when the move needs more than "accelerate, cruise, decelerate"
    (i.e. the distance is below the one of the direct velocity ramp).
    Speeding up uses ``(A1, J1)``, slowing down ``(A2, J2)``.
    """
    def legs(vp):
        # from v0 up (or down) to vp, then from vp to vf
        t1 = _ramp(abs(vp - v0), A1 if vp >= v0 else A2, J1 if vp >= v0 else J2)
        t2 = _ramp(abs(vp - vf), A2 if vp >= vf else A1, J2 if vp >= vf else J1)
        return t1, t2, 0.5 * (v0 + vp) * t1 + 0.5 * (vp + vf) * t2

    lo = max(v0, vf)
    t1, t2, dist = legs(lo)
    if dist > d:
        return None
    t1, t2, dist = legs(V)
    if dist <= d:
        return t1 + t2 + (d - dist) / V
    hi = V
    for _ in range(400):
        mid = 0.5 * (lo + hi)
        if legs(mid)[2] > d:
            hi = mid
        else:
            lo = mid
        if hi - lo <= REF_RTOL * hi:
            break
    t1, t2, _ = legs(0.5 * (lo + hi))
    return t1 + t2


def dense_check(prof, limits, n=2001, rtol=1e-9):
    """Sample a profile densely; return a failure string or None."""
    t = np.linspace(0.0, prof.duration, n)
    s = prof.sample(t)
    tb = prof.brake_duration
    m = t >= tb
    v, a, j = s.velocity[m], s.acceleration[m], s.jerk[m]
    if np.any(np.abs(v) > limits.v_max * (1 + rtol)):
        return f"velocity {np.abs(v).max()} > {limits.v_max}"
    speeding = v * a > 0
    amax = np.where(speeding, limits.a_max, limits.a_max_decel)
    if np.any(np.abs(a) > amax * (1 + rtol) + 1e-12):
        return "acceleration limit"
    # jerk: the regime's limit; where v*a == 0 the regime is about to be set
    # by the jerk itself, so either limit
    jmax = np.where(speeding, limits.j_max,
                    np.where(v * a < 0, limits.j_max_decel,
                             max(limits.j_max, limits.j_max_decel)))
    if np.any(np.abs(j) > jmax * (1 + rtol)):
        return "jerk limit"
    # continuity of position and velocity (finite differences vs samples)
    if n > 2 and prof.duration > 0:
        # exact for a cubic: dp = dt (v0 + v1)/2 + dt^2 (a0 - a1)/12; a jerk
        # change inside a sample interval costs at most |dj| dt^3 / 12
        dt = t[1] - t[0]
        herm = dt * 0.5 * (s.velocity[1:] + s.velocity[:-1]) + dt * dt * (
            s.acceleration[:-1] - s.acceleration[1:]) / 12.0
        dp = np.diff(s.position)
        jm = max(np.abs(np.asarray(prof.jerks, dtype=float)).max(initial=0.0), np.abs(s.jerk).max())
        scale = np.abs(s.position).max() + np.abs(s.velocity).max() * prof.duration
        if np.any(np.abs(dp - herm) > jm * dt ** 3 / 2.0 + 1e-12 * scale):
            return "position not continuous with velocity"
        vh = dt * 0.5 * (s.acceleration[1:] + s.acceleration[:-1])
        if np.any(np.abs(np.diff(s.velocity) - vh) > jm * dt ** 2 + 1e-12 * scale):
            return "velocity not continuous with acceleration"
    return None


def random_case(rng, symmetric=True, scale=1.0):
    """A random (start, goal, (V, A1, J1, A2, J2)) over the hard corners.

    Limits log-uniform; states at the limits, at rest, or random inside;
    distances random, tiny (1e-6 of the natural scale) or zero; the
    velocity always leaves the natural velocity within v_max so that no
    brake is needed.
    """
    V = 10 ** rng.uniform(-1, 1) * scale
    A = 10 ** rng.uniform(-1, 1) * scale
    J = 10 ** rng.uniform(-1, 1.5) * scale
    if symmetric:
        A2, J2 = A, J
    else:
        A2 = A * 10 ** rng.uniform(-0.7, 0.7)
        J2 = J * 10 ** rng.uniform(-0.7, 0.7)
    Jm = min(J, J2)

    def state(kind_v, kind_a, goal):
        for _ in range(200):
            v = {0: 0.0, 1: V, 2: -V, 3: rng.uniform(-V, V)}[kind_v]
            a = {0: 0.0, 1: min(A, A2), 2: -min(A, A2), 3: rng.uniform(-1, 1) * min(A, A2)}[kind_a]
            vn = v - a * abs(a) / (2 * Jm) if goal else v + a * abs(a) / (2 * Jm)
            if abs(vn) <= V and abs(v) <= V:
                return v, a
            kind_v, kind_a = 3, 3
        return 0.0, 0.0

    pick = lambda: int(rng.choice([0, 1, 2, 3, 3, 3]))
    v0, a0 = state(pick(), pick(), False)
    vf, af = state(pick(), pick(), True)
    p0 = rng.uniform(-1, 1) * V
    kind = rng.integers(0, 6)
    if kind == 0:
        pf = p0
    elif kind == 1:
        pf = p0 + rng.uniform(-1, 1) * 1e-6 * V * V / A
    else:
        pf = p0 + rng.uniform(-3, 3) * V * max(V / A, A / J)
    return (p0, v0, a0), (pf, vf, af), (V, A, J, A2, J2)


def random_brake_case(rng, symmetric=True):
    """A random (start, goal, limits) whose start state lies outside the limits.

    Four kinds of start: faster than v_max; accelerating beyond a_max; inside
    the velocity and acceleration limits but accelerating so hard that the
    velocity must pass v_max before the acceleration can be ramped to zero;
    anything within twice the limits. Goals are valid states (rest or moving).
    """
    V = 10 ** rng.uniform(-1, 1)
    A = 10 ** rng.uniform(-1, 1)
    J = 10 ** rng.uniform(-1, 1.5)
    if symmetric:
        A2, J2 = A, J
    else:
        A2 = A * 10 ** rng.uniform(-0.7, 0.7)
        J2 = J * 10 ** rng.uniform(-0.7, 0.7)
    Am, Jm = min(A, A2), min(J, J2)
    for _ in range(1000):
        kind = rng.integers(0, 4)
        if kind == 0:  # overspeed
            v0 = rng.choice([-1, 1]) * V * rng.uniform(1.0, 2.0)
            a0 = rng.uniform(-1.5, 1.5) * Am
        elif kind == 1:  # acceleration beyond the limit
            v0 = rng.uniform(-1, 1) * V
            a0 = rng.choice([-1, 1]) * max(A, A2) * rng.uniform(1.0, 2.0)
        elif kind == 2:  # the acceleration carries the velocity past v_max
            v0 = rng.choice([-1, 1]) * V * rng.uniform(0.5, 1.0)
            a0 = np.sign(v0) * Am * rng.uniform(0.3, 1.0)
        else:
            v0 = rng.uniform(-2, 2) * V
            a0 = rng.uniform(-2, 2) * Am
        J0 = J if v0 * a0 >= 0 else J2
        A0 = A if v0 * a0 >= 0 else A2
        if abs(v0) > V or abs(a0) > A0 or abs(v0 + a0 * abs(a0) / (2 * J0)) > V:
            break
    p0 = rng.uniform(-1, 1) * V
    for _ in range(1000):
        vf = rng.uniform(-1, 1) * V if rng.random() < 0.7 else 0.0
        af = rng.uniform(-1, 1) * Am if rng.random() < 0.5 else 0.0
        if abs(vf - af * abs(af) / (2 * Jm)) <= V:
            break
    pf = p0 + rng.uniform(-3, 3) * V * max(V / A, A / J)
    return (p0, float(v0), float(a0)), (pf, vf, af), (V, A, J, A2, J2)


def exact_check(prof, limits, rtol=1e-9):
    """Independent exact limit check of a StateProfile; failure string or None.

    Works on the profile's public data only (boundary states, phase
    durations and jerks): in every phase after the brake pre-phase it finds
    the zeros of the acceleration (velocity extrema) and of the velocity
    (regime changes), and checks |v| <= v_max at the extrema and the
    boundaries, and |a| and |j| against the limits of the regime
    (speeding up: a_max/j_max, slowing down: decel limits) on each piece.
    """
    b = prof.boundary_states()
    tol_v = limits.v_max * rtol
    vref = max(np.abs(b[:, 1]).max(), 1e-300)
    for k in range(prof.n_brake_phases, prof.n_phases):
        p, v, a = b[k]
        dt, j = prof.phase_durations[k], prof.jerks[k]
        cuts = [0.0, dt]
        # a root within round-off of a phase end is that end (no sliver piece
        # whose leg would be decided by the sign of round-off)
        edge = 1e-9 * dt
        if j != 0.0 and edge < -a / j < dt - edge:
            cuts.append(-a / j)
        if j != 0.0:
            roots = np.roots([0.5 * j, a, v])
        elif a != 0.0:
            roots = np.array([-v / a])
        else:
            roots = np.array([])
        cuts += [float(r.real) for r in np.atleast_1d(roots)
                 if abs(r.imag) == 0.0 and edge < r.real < dt - edge]
        cuts.sort()
        for t in cuts:
            vt = v + a * t + 0.5 * j * t * t
            if abs(vt) > limits.v_max + tol_v:
                return f"phase {k}: |v| {abs(vt)!r} > v_max {limits.v_max!r}"
        for t0, t1 in zip(cuts[:-1], cuts[1:]):
            if t1 <= t0:
                continue
            tm = 0.5 * (t0 + t1)
            vm = v + a * tm + 0.5 * j * tm * tm
            am = a + j * tm
            if abs(vm) <= 1e-12 * vref:
                A = max(limits.a_max, limits.a_max_decel)
                J = max(limits.j_max, limits.j_max_decel)
            elif vm * am >= 0.0:
                A, J = limits.a_max, limits.j_max
            else:
                A, J = limits.a_max_decel, limits.j_max_decel
            for t in (t0, t1):
                if abs(a + j * t) > A * (1 + rtol) + 1e-12 * max(A, abs(a)):
                    return f"phase {k}: |a| {abs(a + j * t)!r} > {A!r}"
            if abs(j) > J * (1 + rtol):
                return f"phase {k}: |j| {abs(j)!r} > {J!r}"
    return None


def integrate_public(prof):
    """End state by integrating the public phase data independently (numpy)."""
    p, v, _ = prof.start_state
    for dt, j, a in zip(prof.phase_durations, prof.jerks, prof.phase_accelerations):
        p = p + v * dt + a * dt ** 2 / 2 + j * dt ** 3 / 6
        v = v + a * dt + j * dt ** 2 / 2
        a = a + j * dt
    if prof.n_phases == 0:
        a = prof.start_state[2]
    return p, v, a


def goal_error(prof):
    """Relative error of the reached goal state (position, velocity, acceleration)."""
    pe, ve, ae = integrate_public(prof)
    pg, vg, ag = prof.goal_state
    T = prof.duration
    b = prof.boundary_states()
    as_ = max(np.abs(b[:, 2]).max(), 1e-300)
    # the velocity scale counts what the accelerations do inside the phases
    vs = max(np.abs(b[:, 1]).max(), as_ * T, 1e-300)
    ps = max(abs(pg - prof.start_state[0]), vs * T, as_ * T * T, 1e-300)
    floor = 64 * 2.2e-16 * max(abs(pg), abs(prof.start_state[0]))
    return max(max(abs(pe - pg) - floor, 0.0) / ps, abs(ve - vg) / vs, abs(ae - ag) / as_)


def ruckig_fixed(start, goal, V, A, J, T):
    """Duration ruckig gives when asked for at least ``T`` s (symmetric limits).

    Equal to ``T`` when ``T`` is feasible; larger when ``T`` lies in a
    blocked interval (ruckig then returns the next feasible duration);
    ``None`` when ruckig finds nothing or raises (it does, rarely, on
    reversals between states at the limits with durations far above the
    minimum).
    """
    return _ruckig_run(start, V, A, J, goal=goal, minimum_duration=T, catch_errors=True)


def ruckig_velocity_duration(start, goal_v, goal_a, V, A, J):
    """Minimum duration of ruckig's velocity interface (position free)."""
    return _ruckig_run(start, V, A, J, goal_va=(goal_v, goal_a))

"""An independent oracle for ``plan_waypoints``: the jerk-limited minimum-time motion
through the same joint-space waypoints as a nonlinear program (CasADi + IPOPT).

``plan_waypoints`` chooses a path through the waypoints and then times it; the
true problem has no path: every joint may move as it likes between two
waypoints, as long as all of them pass every waypoint at the same instant
(within ``blend`` of it, the Euclidean joint distance) and keep their
velocity, acceleration and jerk limits. This program solves that problem by
direct transcription in time:

- unknowns: the duration ``h_k`` of one time step in each stretch ``k``
  between two waypoints (:data:`STEPS` equal steps per stretch), every
  joint's position, velocity and acceleration at every step's end and one
  constant jerk per step and joint; the steps are tied by the exact
  constant-jerk integration;
- constraints: ``|v| <= v_max`` at every node and at the middle of every step
  (the exact state there), ``|a| <= a_max`` at the nodes (exact: ``a`` is
  linear in a step), ``|j| <= j_max`` (exact), rest at both ends, every inner
  waypoint passed at the node ending its stretch (exactly, or within
  ``blend``);
- objective: the duration ``sum_k STEPS h_k``; IPOPT (MUMPS), started from
  trajkit's own trajectory (its samples at the waypoints' passing times and
  between) and from stopping at every waypoint (ruckig rest-to-rest per
  stretch, the benchmark's reference); the faster verified result is kept.

Every result is verified independently of the program: the motion is
integrated again in closed form from rest with the program's jerks and step
durations, every step's velocity checked at its exact extremum (where the
acceleration crosses zero), the largest miss of a waypoint (beyond ``blend``)
reported; a limit exceeded by the ratio ``r`` scales the duration by ``r``
(``r^(1/2)``, ``r^(1/3)`` for acceleration and jerk). The ``NLP`` time is then
a verified feasible time, an upper bound of the true optimum (a local
optimum of a program whose jerk is constant over ``STEPS`` equal steps of a
stretch: not a lower bound).

Run (CasADi is in the ``bench`` extra)::

    python benchmarks/waypoint_oracle.py                # the benchmark's 8 sets, both blends
    python benchmarks/waypoint_oracle.py --blend 0      # through every waypoint only
    python benchmarks/waypoint_oracle.py --steps 48     # finer steps

Columns: waypoints, blend, stopping (ruckig rest-to-rest per stretch),
trajkit, the program's verified time, the ratios of trajkit and the program to
stopping, trajkit / program, the worst waypoint miss, the verification's time
scale (1: no limit exceeded) and which start won; each start's time goes to
stderr.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_paths import WAYPOINT_LIMITS, stopping_at_each, waypoint_sets  # noqa: E402
from nlp_oracle import IPOPT_MAX_ITER, IPOPT_TOL, WARM  # noqa: E402

from trajkit import AxisLimits  # noqa: E402
from trajkit.timing import plan_waypoints  # noqa: E402

#: Equal time steps per stretch between two waypoints (one constant jerk per step).
STEPS = 24

#: The benchmark's limits (``bench_paths.WAYPOINT_LIMITS``): every joint alike.
V_MAX, A_MAX, J_MAX = WAYPOINT_LIMITS

#: The program's waypoint balls are this much smaller than ``blend`` [rad] (IPOPT meets
#: its constraints to its tolerance; the verification then finds no miss).
BLEND_MARGIN = 1e-7

#: Samples per stretch for the passing times of trajkit's trajectory (closest approach).
PASS_SAMPLES = 2000


# --------------------------------------------------------------------------- starts
def _on_grid(sample, times: np.ndarray, steps: int):
    """Node states and step jerks of a trajectory ``sample(t) -> (q, v, a)`` (each (n, m))
    on ``steps`` equal steps between consecutive passing ``times``."""
    t = np.concatenate([np.linspace(times[k], times[k + 1], steps + 1)[:-1]
                        for k in range(times.size - 1)] + [times[-1:]])
    q, v, a = sample(t)
    J = np.diff(a, axis=0) / np.diff(t)[:, None]
    return np.diff(times) / steps, q, v, a, J


def start_from_trajkit(tr, W: np.ndarray, steps: int):
    """trajkit's trajectory on the program's grid; its passing times are those of its
    closest approach to each waypoint (in order)."""
    times = [0.0]
    for k in range(1, W.shape[0] - 1):
        # the closest approach after the previous one, within the rest of the motion
        t = np.linspace(times[-1], tr.duration, PASS_SAMPLES * (W.shape[0] - k))
        d = np.linalg.norm(tr.sample(t).position - W[k], axis=1)
        times.append(float(t[int(np.argmin(d))]))
    times.append(tr.duration)

    def sample(t):
        smp = tr.sample(t)
        return smp.position, smp.velocity, smp.acceleration
    return _on_grid(sample, np.array(times), steps)


def start_from_stopping(W: np.ndarray, steps: int):
    """Stopping at every waypoint (ruckig rest-to-rest per stretch) on the program's grid,
    and its duration."""
    m = W.shape[1]
    trajs = stopping_at_each(W)
    times = np.concatenate([[0.0], np.cumsum([tj.duration for tj in trajs])])

    def sample(t):
        q, v, a = (np.zeros((t.size, m)) for _ in range(3))
        for i, ti in enumerate(t):
            k = min(int(np.searchsorted(times, ti, side="right")) - 1, len(trajs) - 1)
            q[i], v[i], a[i] = trajs[k].at_time(float(ti - times[k]))
        return q, v, a
    return _on_grid(sample, times, steps), float(times[-1])


# --------------------------------------------------------------------------- program
def solve(W: np.ndarray, blend: float, start, steps: int, options: dict | None = None):
    """The program from ``start`` (h (n-1,), q, v, a (P, m), J (P-1, m)); its h and J,
    IPOPT's status and seconds."""
    import casadi as ca

    n, m = W.shape
    P = (n - 1) * steps + 1
    h = ca.SX.sym("h", n - 1)
    Q, V, A = (ca.SX.sym(nm, P, m) for nm in "QVA")
    J = ca.SX.sym("J", P - 1, m)
    # every step's duration: its stretch's h
    Hs = ca.mtimes(ca.DM(np.kron(np.eye(n - 1), np.ones((steps, 1)))), h)
    H = ca.repmat(Hs, 1, m)
    q0, v0, a0 = Q[:-1, :], V[:-1, :], A[:-1, :]
    g = [Q[1:, :] - (q0 + v0 * H + a0 * H**2 / 2 + J * H**3 / 6),
         V[1:, :] - (v0 + a0 * H + J * H**2 / 2),
         A[1:, :] - (a0 + J * H)]
    g = [ca.reshape(e, -1, 1) for e in g]
    lbg = [np.zeros(e.shape[0]) for e in g]
    ubg = [np.zeros(e.shape[0]) for e in g]
    vmid = ca.reshape(v0 + a0 * H / 2 + J * H**2 / 8, -1, 1)
    g.append(vmid)
    lbg.append(np.full(vmid.shape[0], -V_MAX))
    ubg.append(np.full(vmid.shape[0], V_MAX))
    inner = np.arange(1, n - 1) * steps
    lq, uq = np.full((P, m), -np.inf), np.full((P, m), np.inf)
    lq[0], uq[0], lq[-1], uq[-1] = W[0], W[0], W[-1], W[-1]
    if blend > 0.0:
        for k, node in enumerate(inner, start=1):
            g.append(ca.sumsqr(Q[int(node), :] - W[k].reshape(1, -1)))
            lbg.append(np.zeros(1))
            ubg.append(np.array([(blend - BLEND_MARGIN)**2]))
    else:
        lq[inner], uq[inner] = W[1:-1], W[1:-1]
    lv, uv = np.full((P, m), -V_MAX), np.full((P, m), V_MAX)
    la, ua = np.full((P, m), -A_MAX), np.full((P, m), A_MAX)
    lv[[0, -1]] = uv[[0, -1]] = la[[0, -1]] = ua[[0, -1]] = 0.0

    def flat(*mats):  # column-major, as casadi's reshape
        return np.concatenate([np.asarray(x, dtype=float).reshape(-1, order="F") for x in mats])

    z = ca.vertcat(h, ca.reshape(Q, -1, 1), ca.reshape(V, -1, 1), ca.reshape(A, -1, 1),
                   ca.reshape(J, -1, 1))
    lbz = flat(np.full(n - 1, 1e-5), lq, lv, la, np.full((P - 1, m), -J_MAX))
    ubz = flat(np.full(n - 1, 10.0), uq, uv, ua, np.full((P - 1, m), J_MAX))
    h0, qs, vs, as_, js = start
    x0 = np.clip(flat(h0, qs, vs, as_, js), lbz, ubz)
    opts = {"ipopt.tol": IPOPT_TOL, "ipopt.max_iter": IPOPT_MAX_ITER, "ipopt.print_level": 0,
            "print_time": False, "ipopt.linear_solver": "mumps", "ipopt.sb": "yes",
            "ipopt.mu_strategy": "adaptive"}
    opts.update(options or {})
    solver = ca.nlpsol("waypoints", "ipopt", {"x": z, "f": steps * ca.sum1(h), "g": ca.vertcat(*g)},
                       opts)
    t0 = time.perf_counter()
    res = solver(x0=x0, lbx=lbz, ubx=ubz, lbg=np.concatenate(lbg), ubg=np.concatenate(ubg))
    secs = time.perf_counter() - t0
    x = np.asarray(res["x"]).ravel()
    hh = x[:n - 1]
    jj = x[n - 1 + 3 * P * m:].reshape((P - 1, m), order="F")
    return hh, jj, solver.stats()["return_status"], secs


# --------------------------------------------------------------------------- verification
def verify(W: np.ndarray, blend: float, hh: np.ndarray, jj: np.ndarray, steps: int):
    """The motion integrated from rest with the steps ``hh`` and jerks ``jj``: its
    verified duration (scaled where a limit is exceeded) and largest waypoint miss
    (beyond ``blend``, at the passing node)."""
    m = W.shape[1]
    q, v, a = W[0].astype(float), np.zeros(m), np.zeros(m)
    vmax = amax = 0.0
    miss = 0.0
    for i, j in enumerate(jj):
        dt = hh[i // steps]
        # the velocity's extremum inside the step (where the acceleration crosses zero)
        with np.errstate(divide="ignore", invalid="ignore"):
            tau = np.where(j != 0.0, -a / j, -1.0)
        inside = (tau > 0.0) & (tau < dt)
        vx = v + a * tau + j * tau**2 / 2
        vmax = max(vmax, float(np.max(np.abs(np.where(inside, vx, v)))))
        q, v, a = (q + v * dt + a * dt**2 / 2 + j * dt**3 / 6, v + a * dt + j * dt**2 / 2, a + j * dt)
        vmax = max(vmax, float(np.max(np.abs(v))))
        amax = max(amax, float(np.max(np.abs(a))))
        if (i + 1) % steps == 0:
            k = (i + 1) // steps
            dist = float(np.linalg.norm(q - W[k]))
            miss = max(miss, dist - (blend if 0 < k < W.shape[0] - 1 else 0.0))
    end = float(max(np.max(np.abs(v)), np.max(np.abs(a))))  # rest at the end
    jmax = float(np.max(np.abs(jj)))
    scale = max(1.0, vmax / V_MAX, math.sqrt(amax / A_MAX), (jmax / J_MAX) ** (1.0 / 3.0))
    return steps * float(np.sum(hh)) * scale, max(miss, 0.0), end, scale


def oracle(W: np.ndarray, blend: float, steps: int) -> dict:
    lims = [AxisLimits(V_MAX, A_MAX, J_MAX) for _ in range(W.shape[1])]
    tr = plan_waypoints(W, lims, blend=blend)
    stop_start, stop = start_from_stopping(W, steps)
    best = None
    for name, start, opts in (("trajkit", start_from_trajkit(tr, W, steps), WARM),
                              ("stopping", stop_start, None)):
        hh, jj, status, secs = solve(W, blend, start, steps, opts)
        if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
            print(f"  ({name} start: IPOPT {status} after {secs:.1f} s)", file=sys.stderr)
            continue
        T, miss, end, scale = verify(W, blend, hh, jj, steps)
        if miss > 1e-6 or end > 1e-6:
            print(f"  ({name} start: misses a waypoint by {miss:.2g} or the end rest by {end:.2g})",
                  file=sys.stderr)
            continue
        print(f"  ({name} start: {T:.4f} s, IPOPT {secs:.1f} s)", file=sys.stderr)
        if best is None or T < best["nlp"]:
            best = dict(nlp=T, miss=miss, scale=scale, start=name, secs=secs)
    if best is None:
        best = dict(nlp=math.nan, miss=math.nan, scale=math.nan, start="-", secs=math.nan)
    return dict(n=W.shape[0], blend=blend, stop=stop, trajkit=tr.duration, **best)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blend", type=float, action="append", help="blend(s) [rad], default 0 and 0.1")
    ap.add_argument("--steps", type=int, default=STEPS, help="time steps per stretch")
    ap.add_argument("--sets", type=int, default=8, help="how many of the benchmark's sets")
    args = ap.parse_args(argv)
    blends = args.blend or [0.0, 0.1]
    rows = []
    print(f"{'waypoints':>9s} {'blend':>5s} {'stopping [s]':>12s} {'trajkit [s]':>11s} {'NLP [s]':>9s} "
          f"{'trajkit/stop':>12s} {'NLP/stop':>8s} {'trajkit/NLP':>11s} {'miss':>8s} {'scaled':>8s} {'start':>8s}")
    for W in waypoint_sets(args.sets):
        for blend in blends:
            r = oracle(W, blend, args.steps)
            rows.append(r)
            print(f"{r['n']:9d} {blend:5g} {r['stop']:12.4f} {r['trajkit']:11.4f} {r['nlp']:9.4f} "
                  f"{r['trajkit'] / r['stop']:12.3f} {r['nlp'] / r['stop']:8.3f} "
                  f"{r['trajkit'] / r['nlp']:11.4f} {r['miss']:8.1e} {r['scale']:8.6f} {r['start']:>8s}", flush=True)
    for blend in blends:
        sel = [r for r in rows if r["blend"] == blend and math.isfinite(r["nlp"])]
        if sel:
            print(f"blend {blend:g}: trajkit / NLP mean {statistics.mean(r['trajkit'] / r['nlp'] for r in sel):.4f}, "
                  f"largest {max(r['trajkit'] / r['nlp'] for r in sel):.4f}; NLP shorter than stopping "
                  f"by {100 * (1 - statistics.mean(r['nlp'] / r['stop'] for r in sel)):.1f} % (mean), "
                  f"worst {100 * (1 - max(r['nlp'] / r['stop'] for r in sel)):.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())

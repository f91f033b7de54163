"""An independent oracle for the path-timing engine: the jerk-limited minimum-time
timing of the same joint path as a nonlinear program (CasADi + IPOPT).

For every arm motion of ``benchmarks/bench_paths.py`` (UR5 and Panda), the
joint path ``q(s)`` that trajkit times (the chain's ``ChainJointPath``, the
same inverse kinematics and derivatives the engine gets) is timed again by a
direct transcription in *time*, with the jerk constraints exact (not
linearised):

- unknowns: on a time grid of ``K`` intervals of equal duration ``h`` (one
  unknown per interval, tied by equalities, which keeps the KKT matrix
  banded; ``T = K h``), the path state ``s, sdot, sddot`` at every node and one
  constant path jerk ``J`` per interval; the nodes are tied by the exact
  constant-jerk integration (``s+ = s + sdot h + sddot h^2/2 + J h^3/6`` ...);
- constraints at every node (the jerk with the jerks of both intervals
  around it) and at the middle of every interval (its exact state there):
  every joint's ``|q' sdot| <= v``, ``|q'' sdot^2 + q' sddot| <= a``,
  ``|q''' sdot^3 + 3 q'' sdot sddot + q' J| <= j``, the path's speed cap,
  tangential acceleration (norm with the tool's curvature) and jerk;
  rest at both ends;
- ``q'``, ``q''`` are cubic B-splines and ``q'''`` the piecewise-linear
  interpolation of the path's own derivatives tabulated at
  :data:`TABLE_POINTS` values of ``s`` (plus both sides of every
  breakpoint);
- objective ``T``; IPOPT (MUMPS), started from trajkit's timing (a feasible
  point: IPOPT's warm-start options) and from TOPP-RA's jerk-free timing
  by continuation in the jerk limits (on a coarse grid with the jerk limits
  100x the true ones, then 30x, 10x, ... 1x, each solution slowed down
  uniformly until it keeps the next limits and used as the next start;
  then the fine grid); the faster verified result of a successful solve is
  kept.

Every result is verified independently of the NLP: ``s(t)`` is integrated in
closed form from the pieces, sampled every :data:`VERIFY_DT` s, the joint
positions ``q(s(t))`` taken from the path, and the joint velocity,
acceleration and jerk computed by central finite differences of those
positions. If a limit is exceeded by the ratio ``r`` the duration is scaled
by ``r`` (``r^(1/2)``, ``r^(1/3)`` for acceleration and jerk): the reported
``NLP`` time is then a *verified feasible* time of the path, an upper bound of
its true jerk-limited optimum (the NLP is solved to a local optimum, so it is
not a lower bound). trajkit's timing gets the same finite-difference check
(``trajkit fd`` column: its largest use of any limit).

Run (CasADi is in the ``bench`` extra: ``pip install -e .[bench]``)::

    python benchmarks/nlp_oracle.py                     # every arm row, both starts (~40 min)
    python benchmarks/nlp_oracle.py --starts trajkit    # from trajkit's timing only (~5 min)
    python benchmarks/nlp_oracle.py --rows "ur5: CIRC"  # rows whose "arm: label" contains this
    python benchmarks/nlp_oracle.py --K 1600            # a finer time grid

(one core; ``K`` is raised to twice trajkit's grid nodes where that is more)

Columns: TOPP-RA (no jerk limit, a lower bound), trajkit, the NLP's verified
time, trajkit / NLP, the NLP's time before the verification scaled it, the
uses of the limits found by the finite-difference check and which start won.
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

from bench_paths import arm_suite  # noqa: E402

from trajkit.robot import run_motions  # noqa: E402

#: Values of ``s`` at which the path's derivatives are tabulated for the NLP.
TABLE_POINTS = 20001

#: Time intervals of the transcription (at least twice trajkit's grid nodes).
K_DEFAULT = 800

#: Time step of the independent finite-difference check [s].
VERIFY_DT = 2.5e-4

#: Time intervals of the first solves from TOPP-RA's timing (then refined to K).
K_COARSE = 300

#: The jerk limits' factors of the continuation from TOPP-RA's (jerk-free) timing.
JERK_HOMOTOPY = (100.0, 30.0, 10.0, 4.0, 2.0, 1.4, 1.0)

#: IPOPT's tolerance and most iterations.
IPOPT_TOL = 1e-9
IPOPT_MAX_ITER = 3000


class PathData:
    """The joint path and every limit of one motion, in plain arrays.

    Parameters
    ----------
    path : JointPath
        The chain's joint path (``derivatives(s)`` -> q, q', q'', q''').
    limits : list of AxisLimits
    speed : callable
        Speed cap of the path at ``s`` (n,) -> (n,).
    a_path, j_path : float
        Tangential acceleration (norm with the curvature) and jerk limits.
    curvature : callable or None
        Tool-path curvature at ``s`` (n,) -> (n,).
    """

    def __init__(self, path, limits, speed, a_path, j_path, curvature=None):
        self.path = path
        self.L = float(path.length)
        self.m = int(path.n_joints)
        self.v = np.array([lm.v_max for lm in limits])
        self.a = np.array([min(lm.a_max, lm.a_max_decel) for lm in limits])
        self.j = np.array([min(lm.j_max, lm.j_max_decel) for lm in limits])
        for lm in limits:
            if lm.a_max != lm.a_max_decel or lm.j_max != lm.j_max_decel:
                raise ValueError("the oracle handles symmetric limits only (accel = decel legs)")
        self.speed = speed
        self.a_path = float(a_path)
        self.j_path = float(j_path)
        self.curvature = curvature
        L = self.L
        br = np.asarray(getattr(path, "breakpoints", np.zeros(0)), dtype=float)
        br = br[(br > 0.0) & (br < L)]
        h = L / (TABLE_POINTS - 1)
        g = np.linspace(0.0, L, TABLE_POINTS)
        # both sides of a breakpoint (q''' may step there): the value from below just before it
        g = g[np.min(np.abs(g[:, None] - br[None, :]), axis=1, initial=np.inf) > 0.05 * h] if br.size else g
        self.table = np.unique(np.concatenate([g, br, br - 1e-6 * h]))
        _, self.d1, self.d2, self.d3 = path.derivatives(self.table)
        # the value just below a breakpoint from the left limit
        if br.size:
            left = path.derivatives(np.nextafter(br, -np.inf))
            idx = np.searchsorted(self.table, br - 1e-6 * h)
            self.d1[idx], self.d2[idx], self.d3[idx] = left[1], left[2], left[3]
        self.cap = np.asarray(speed(self.table), dtype=float)
        self.kappa = (np.zeros(self.table.size) if curvature is None
                      else np.abs(np.asarray(curvature(self.table), dtype=float)))


# --------------------------------------------------------------------------- pieces
def sample_pieces(T: float, s, v, a, J, t: np.ndarray):
    """``s, sdot, sddot`` at times ``t`` of the constant-jerk pieces of a uniform grid
    (node states ``s, v, a`` (K + 1,), jerks ``J`` (K,)); rest outside ``[0, T]``."""
    K = J.size
    h = T / K
    tc = np.clip(t, 0.0, T)
    k = np.minimum((tc / h).astype(int), K - 1)
    d = tc - k * h
    ss = s[k] + v[k] * d + a[k] * d**2 / 2 + J[k] * d**3 / 6
    vv = v[k] + a[k] * d + J[k] * d**2 / 2
    aa = a[k] + J[k] * d
    ss = np.where(t <= 0.0, s[0], np.where(t >= T, s[-1], ss))
    vv = np.where((t <= 0.0) | (t >= T), 0.0, vv)
    aa = np.where((t <= 0.0) | (t >= T), 0.0, aa)
    return ss, vv, aa


def fd_check(data: PathData, T: float, sample, dt: float = VERIFY_DT) -> dict:
    """Largest use of every limit by finite differences of ``q(s(t))``.

    ``sample(t)`` -> (s, sdot, sddot) at times ``t``; joint velocity, acceleration
    and jerk by central differences of the path's joint positions at the sampled
    ``s`` (every ``dt``), the path speed and acceleration from the pieces.
    """
    n = int(math.ceil(T / dt))
    t = np.linspace(0.0, T, n + 1)
    tt = np.concatenate([t[0] - dt * np.arange(3, 0, -1), t, t[-1] + dt * np.arange(1, 4)])
    dtt = tt[1] - tt[0]
    s, sd, sdd = sample(tt)
    s = np.clip(s, 0.0, data.L)
    q = data.path.derivatives(s)[0]
    qd = (q[2:] - q[:-2]) / (2 * dtt)
    qdd = (q[2:] - 2 * q[1:-1] + q[:-2]) / dtt**2
    qddd = (q[4:] - 2 * q[3:-1] + 2 * q[1:-3] - q[:-4]) / (2 * dtt**3)
    kap = np.interp(s, data.table, data.kappa)
    acc = np.hypot(sdd, kap * sd**2)
    cap = np.interp(s, data.table, data.cap)
    return dict(v=float(np.max(np.abs(qd) / data.v)), a=float(np.max(np.abs(qdd) / data.a)),
                j=float(np.max(np.abs(qddd) / data.j)), speed=float(np.max(sd / cap)),
                path_acc=float(np.max(acc) / data.a_path))


def feasible_scale(use: dict) -> float:
    """The uniform time scale that brings every use found to 1 (1 if none is above)."""
    return max(1.0, use["v"], use["speed"], math.sqrt(use["a"]), math.sqrt(use["path_acc"]),
               use["j"] ** (1.0 / 3.0))


# --------------------------------------------------------------------------- starts
def start_from_timing(tm, K: int):
    """Node states of trajkit's timing on the uniform time grid (T, s, v, a, J)."""
    T = float(tm.duration)
    t = np.linspace(0.0, T, K + 1)
    s, v, a, _ = tm.sample(t)
    J = np.diff(a) / (T / K)
    return T, s, v, a, J


def start_from_toppra(data: PathData, K: int, grid: int = 2000):
    """TOPP-RA's jerk-free timing (same path, v/a limits, speed cap) on the time grid."""
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    ta.setup_logging("WARNING")
    L = data.L
    ss = np.linspace(0.0, L, 2001)
    q = data.path.derivatives(ss)[0]
    q = np.column_stack([q, ss])
    vv = np.append(data.v, float(np.min(data.cap)))
    aa = np.append(data.a, data.a_path)
    inst = algo.TOPPRA([constraint.JointVelocityConstraint(np.column_stack([-vv, vv])),
                        constraint.JointAccelerationConstraint(np.column_stack([-aa, aa]))],
                       ta.SplineInterpolator(ss, q), gridpoints=np.linspace(0.0, L, grid),
                       parametrizer="ParametrizeConstAccel")
    traj = inst.compute_trajectory()
    gp = np.asarray(inst.problem_data.gridpoints)
    sd = np.maximum(np.asarray(inst.problem_data.sd_vec), 0.0)
    ds = np.diff(gp)
    tg = np.concatenate([[0.0], np.cumsum(2.0 * ds / np.maximum(sd[:-1] + sd[1:], 1e-12))])
    T = float(tg[-1])
    t = np.linspace(0.0, T, K + 1)
    s = np.interp(t, tg, gp)
    v = np.interp(t, tg, sd)
    a = np.gradient(v, t)
    a[0] = a[-1] = 0.0
    v[0] = v[-1] = 0.0
    J = np.diff(a) / (T / K)
    return T, s, v, a, J, float(traj.duration)


# --------------------------------------------------------------------------- NLP
def solve_nlp(data: PathData, start, K: int, verbose: bool = False, options: dict | None = None,
              jerk_factor: float = 1.0):
    """Minimum time on a uniform time grid of K constant-jerk intervals from ``start``
    (T, s, v, a, J), the joint jerk limits multiplied by ``jerk_factor``.
    Returns (T, s, v, a, J, status, seconds)."""
    import casadi as ca

    m = data.m
    grid = [data.table]
    q1 = ca.interpolant("q1", "bspline", grid, data.d1.T.ravel(order="F"))
    q2 = ca.interpolant("q2", "bspline", grid, data.d2.T.ravel(order="F"))
    q3 = ca.interpolant("q3", "linear", grid, data.d3.T.ravel(order="F"))
    const_cap = bool(np.all(data.cap == data.cap[0]))
    capf = None if const_cap else ca.interpolant("cap", "linear", grid, data.cap)
    has_kappa = bool(np.any(data.kappa > 0)) and math.isfinite(data.a_path)
    kapf = ca.interpolant("kappa", "linear", grid, data.kappa) if has_kappa else None

    # per-point limit uses (normalised): joint v, a, jerk (with two jerks), path limits
    ps, pv, pa, pJ1, pJ2 = (ca.MX.sym(nm) for nm in ("s", "v", "a", "J1", "J2"))
    d1, d2, d3 = q1(ps), q2(ps), q3(ps)
    vlim, alim, jlim = (ca.DM(x) for x in (data.v, data.a, data.j * jerk_factor))
    g_v = d1 * pv / vlim
    g_a = (d2 * pv**2 + d1 * pa) / alim
    base = d3 * pv**3 + 3 * d2 * pv * pa
    g_j1 = (base + d1 * pJ1) / jlim
    g_j2 = (base + d1 * pJ2) / jlim
    extra = []
    if capf is not None:
        extra.append(pv / capf(ps))  # <= 1
    if has_kappa:
        extra.append((pa**2 + (kapf(ps) * pv**2) ** 2) / data.a_path**2)  # <= 1
    g_pt = ca.vertcat(g_v, g_a, g_j1, g_j2, *extra)
    fpt = ca.Function("fpt", [ps, pv, pa, pJ1, pJ2], [g_pt])
    n_pt = g_pt.size1()
    lo_pt = np.concatenate([-np.ones(4 * m), np.zeros(len(extra))])
    hi_pt = np.ones(n_pt)

    H = ca.MX.sym("H", K)  # the step of every interval, all equal (a banded KKT matrix)
    S = ca.MX.sym("S", K + 1)
    V = ca.MX.sym("V", K + 1)
    A = ca.MX.sym("A", K + 1)
    Jv = ca.MX.sym("J", K)
    h = H
    s0, v0, a0 = S[:-1], V[:-1], A[:-1]
    dyn = ca.vertcat(S[1:] - (s0 + v0 * h + a0 * h**2 / 2 + Jv * h**3 / 6),
                     V[1:] - (v0 + a0 * h + Jv * h**2 / 2),
                     A[1:] - (a0 + Jv * h))
    # nodes: the jerks of the intervals on both sides (the ends: the one interval twice)
    Jl = ca.vertcat(Jv[0], Jv)
    Jr = ca.vertcat(Jv, Jv[-1])
    fmap = fpt.map(K + 1)
    g_nodes = fmap(S.T, V.T, A.T, Jl.T, Jr.T)
    # the middle of every interval
    hm = h / 2
    Sm = s0 + v0 * hm + a0 * hm**2 / 2 + Jv * hm**3 / 6
    Vm = v0 + a0 * hm + Jv * hm**2 / 2
    Am = a0 + Jv * hm
    g_mid = fpt.map(K)(Sm.T, Vm.T, Am.T, Jv.T, Jv.T)
    g = ca.vertcat(dyn, H[1:] - H[:-1], ca.vec(g_nodes), ca.vec(g_mid))
    lbg = np.concatenate([np.zeros(4 * K - 1), np.tile(lo_pt, K + 1), np.tile(lo_pt, K)])
    ubg = np.concatenate([np.zeros(4 * K - 1), np.tile(hi_pt, K + 1), np.tile(hi_pt, K)])

    z = ca.vertcat(H, S, V, A, Jv)
    inf = np.inf
    vmax = float(np.max(data.cap)) if math.isfinite(np.max(data.cap)) else inf
    lbz = np.concatenate([np.full(K, 1e-9), np.zeros(K + 1), np.zeros(K + 1), -np.full(K + 1, data.a_path),
                          -np.full(K, data.j_path)])
    ubz = np.concatenate([np.full(K, inf), np.full(K + 1, data.L), np.full(K + 1, vmax if const_cap else inf),
                          np.full(K + 1, data.a_path), np.full(K, data.j_path)])
    # boundary states: rest at both ends (z = H[0..K-1], S[0..K], V[0..K], A[0..K], J[0..K-1])
    iS, iV, iA = K, 2 * K + 1, 3 * K + 2
    for arr in (lbz, ubz):
        arr[iS], arr[iS + K] = 0.0, data.L
        arr[iV] = arr[iV + K] = arr[iA] = arr[iA + K] = 0.0
    T0, s_i, v_i, a_i, J_i = start
    z0 = np.concatenate([np.full(K, T0 / K), np.clip(s_i, 0, data.L), np.maximum(v_i, 0.0), a_i, J_i])
    z0 = np.clip(z0, lbz, ubz)
    opts = {"ipopt.tol": IPOPT_TOL, "ipopt.max_iter": IPOPT_MAX_ITER,
            "ipopt.print_level": 5 if verbose else 0, "print_time": False,
            "ipopt.linear_solver": "mumps", "ipopt.mu_strategy": "adaptive",
            "ipopt.nlp_scaling_method": "gradient-based", "ipopt.sb": "yes"}
    opts.update(options or {})
    solver = ca.nlpsol("oracle", "ipopt", {"x": z, "f": ca.sum1(H), "g": g}, opts)
    t0 = time.perf_counter()
    res = solver(x0=z0, lbx=lbz, ubx=ubz, lbg=lbg, ubg=ubg)
    secs = time.perf_counter() - t0
    st = solver.stats()["return_status"]
    zz = np.asarray(res["x"]).ravel()
    T = float(np.sum(zz[:K]))
    s = zz[iS:iS + K + 1]
    v = zz[iV:iV + K + 1]
    a = zz[iA:iA + K + 1]
    J = zz[iA + K + 1:]
    return T, s, v, a, J, st, secs


#: IPOPT's options from trajkit's timing (a feasible point close to the optimum: a small
#: barrier parameter and the start kept, which takes 3x fewer iterations).
WARM = {"ipopt.mu_init": 1e-5, "ipopt.warm_start_init_point": "yes", "ipopt.bound_push": 1e-9,
        "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9}

#: Wall-clock limit of the solve from TOPP-RA's timing [s] (it violates the jerk limits
#: by far and takes IPOPT's default path: tens to hundreds of iterations).
COLD_SECONDS = 150.0


def oracle(data: PathData, tm, K: int, starts=("trajkit", "toppra"), verbose: bool = False) -> dict:
    """The NLP from trajkit's timing and from TOPP-RA's, each verified; the fastest verified
    result of a successful solve kept."""
    results = []
    topp = start_from_toppra(data, 10)[5]
    for name in starts:
        if name == "trajkit":
            start, opts = start_from_timing(tm, K), WARM
            T, s, v, a, J, status, secs = solve_nlp(data, start, K, verbose, opts)
        else:
            # from TOPP-RA's jerk-free timing, by continuation in the jerk limits: on a
            # coarse grid with the jerk limits JERK_HOMOTOPY[0] times the true ones
            # (TOPP-RA's timing is close to that problem's solution), then each solution,
            # slowed down uniformly until it keeps the next factor's jerk limits (a
            # feasible start, as trajkit's), the start of the next; then the fine grid
            Kc = min(K, K_COARSE)
            cur = start_from_toppra(data, Kc)[:5]
            secs = 0.0
            prev = None
            for f in JERK_HOMOTOPY:
                if prev is None:
                    opts = {"ipopt.max_wall_time": COLD_SECONDS, "ipopt.bound_push": 1e-8,
                            "ipopt.bound_frac": 1e-8, "ipopt.mu_init": 1e-3}
                else:
                    k = (prev / f) ** (1.0 / 3.0)
                    T0, s0, v0, a0, J0 = cur
                    cur = (T0 * k, s0, v0 / k, a0 / k**2, J0 / k**3)
                    opts = {**WARM, "ipopt.max_wall_time": COLD_SECONDS}
                T, s, v, a, J, status, dt = solve_nlp(data, cur, Kc, verbose, opts, f)
                secs += dt
                cur = (T, s, v, a, J)
                prev = f
            if Kc < K:
                t = np.linspace(0.0, T, K + 1)
                s1, v1, a1 = sample_pieces(T, s, v, a, J, t)
                fine = (T, s1, v1, a1, np.diff(a1) / (T / K))
                T, s, v, a, J, status, secs2 = solve_nlp(data, fine, K, verbose,
                                                         {**WARM, "ipopt.max_wall_time": COLD_SECONDS})
                secs += secs2
        use = fd_check(data, T, lambda t, T=T, s=s, v=v, a=a, J=J: sample_pieces(T, s, v, a, J, t))
        k = feasible_scale(use)
        results.append(dict(start=name, T_raw=T, T=T * k, use=use, status=status, secs=secs))
    ok = [r for r in results if r["status"] in ("Solve_Succeeded", "Solved_To_Acceptable_Level")]
    best = min(ok or results, key=lambda r: r["T"])
    best = dict(best)
    best["all"] = results
    best["toppra"] = topp
    return best


# --------------------------------------------------------------------------- suite
def arm_rows(names=("ur5", "panda"), select: str | None = None):
    """(label, robot, chain) of every arm motion of the bench suite."""
    for name in names:
        rob, suite = arm_suite(name)
        for label, q0, mots, first in suite:
            full = f"{name}: {label}"
            if select and select.lower() not in full.lower():
                continue
            if first is not None:
                q0 = rob.ik_near(first, q0)
            run = run_motions(rob, mots, q0)
            for sg in run.segments:
                if sg.kind == "CP":
                    yield full, rob, sg.chain


def chain_data(rob, chain) -> PathData:
    """The limits the engine got for a chain (speed caps per piece, tool acc./jerk)."""
    from trajkit.robot._cartesian import _tool_curvature

    path = chain.path
    caps = np.array([pc.cap for pc in chain.pieces])

    def speed(ss):
        return np.minimum(caps[path.piece_of(ss)], caps[path.piece_of(ss, side="left")])

    return PathData(path, rob.limits, speed, rob.cartesian_accel, rob.cartesian_jerk,
                    lambda ss: _tool_curvature(path, ss))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", default=None, help="only rows whose 'arm: label' contains this")
    ap.add_argument("--K", type=int, default=K_DEFAULT, help="time intervals of the NLP")
    ap.add_argument("--starts", default="trajkit,toppra",
                    help="comma-separated starts of the NLP: trajkit (its timing), toppra (jerk-free)")
    ap.add_argument("--verbose", action="store_true", help="IPOPT's iterations")
    args = ap.parse_args(argv)
    print(f"{'motion':48s} {'TOPP-RA':>8s} {'trajkit':>8s} {'NLP':>8s} {'tk/NLP':>7s} "
          f"{'NLP raw':>8s} {'NLP fd v/a/j':>17s} {'trajkit fd v/a/j':>17s} {'start':>8s} "
          f"{'IPOPT [s]':>9s}")
    ratios = []
    for label, rob, chain in arm_rows(select=args.rows):
        tm = chain.timing
        data = chain_data(rob, chain)
        K = max(args.K, 2 * tm.grid.size)
        res = oracle(data, tm, K, tuple(args.starts.split(",")), args.verbose)
        tk_use = fd_check(data, tm.duration, lambda t, tm=tm: tm.sample(t)[:3])
        u, w = res["use"], tk_use
        ratio = tm.duration / res["T"]
        ratios.append(ratio)
        print(f"{label:48s} {res['toppra']:8.4f} {tm.duration:8.5f} {res['T']:8.5f} {ratio:7.4f} "
              f"{res['T_raw']:8.4f} {u['v']:5.3f}/{u['a']:5.3f}/{u['j']:5.3f} "
              f"{w['v']:5.3f}/{w['a']:5.3f}/{w['j']:5.3f} {res['start']:>8s} "
              f"{sum(r['secs'] for r in res['all']):9.1f}", flush=True)
        for r in res["all"]:
            print(f"    start {r['start']:8s}: T {r['T_raw']:.5f} ({r['status']}), verified {r['T']:.5f}",
                  flush=True)
    if ratios:
        print(f"\ntrajkit / NLP: mean {statistics.mean(ratios):.4f}, largest {max(ratios):.4f}, "
              f"smallest {min(ratios):.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

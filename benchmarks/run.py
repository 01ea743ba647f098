"""Work-precision benchmark of orbatt's integrators (issue 4).

    python benchmarks/run.py            # a few minutes on 2 cores
    python benchmarks/run.py --quick    # smaller ensembles, fewer repeats (~1 minute)

Cases (docs/design.md §9, the paper's Sect. 6):

* **Keplerian**: gravity gradient on a Keplerian orbit (a = 7000 km, e = 0.2, i = pi/6,
  raan = pi/4, argp = pi/12, f(t0) = 0), inertia (400, 500, 600) kg km^2, 10 orbits
  (58 285 s). Reference: orbatt's DOP853 at rtol 3e-15 (cross-checked against the 6th-order
  splitting at a small step and, when installed, heyoka at tol 1e-15).
* **torque-free**: inertia (1.25, 1.0, 0.75), dimensionless, t = 100. Reference: the exact
  solution (orbatt.analytic.torque_free).

Both start from the paper's printed q(t0), Q(t0) (the 1e-7 radial part of Q removed).

For each method and each target (final attitude error 1e-6 and 1e-9 rad) the loosest
tolerance (adaptive methods; atol = rtol, the state components being of order 1: measured
~12 % less work than atol = rtol / 100 at the same error) or the fewest steps (fixed-step methods)
reaching it, and the median wall time over repeats of the whole call; ratios to baselines
measured in the same run:

(a) the classical model a user would write: Euler's equations + quaternion kinematics,
    numpy right-hand side (Kepler's equation by a Python Newton loop), solve_ivp DOP853;
(b) the same with the quaternion right-hand side (eq. 7) in numpy;
(c) heyoka (Taylor method; ``pip install heyoka``), when installed;
(d) Basilisk (``pip install bsk``), when installed (Keplerian case): spacecraft hub, point-mass
    Earth, GravityGradientEffector, RKF78 and RK4 at the largest task step reaching the target
    (plus the issue's settings RKF78 30 s, 10 s and RK4 1 s); time = ExecuteSimulation alone.

Beside the ``dop853`` row of each case and target, the end-to-end row: ``load_scenario(path).run()``
on a scenario file of the case at the same tolerance (parsing, building, the propagation and
the xarray Dataset; ``end_to_end.py``). Then first runs in a fresh process: ``orbatt run`` of
the shipped Keplerian scenario with an empty ``NUMBA_CACHE_DIR`` (interpreted kernels while a
background warm-up compiles them), warm, and with an empty cache waiting for the compiler,
beside heyoka's first result in a fresh process (``--no-first-runs`` skips them: ~1-2 minutes
of compilation).

Then ensemble throughput: DOP853 body-orbits per second at <= 1e-9 rad after one orbit, and
splitting body-steps per second, for N = 1e3 and 1e5 members; and an ensemble of cubesats with
the gravity gradient plus drag, SRP and a residual dipole beside the gravity gradient alone.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import time

import numpy as np

import orbatt
from orbatt import analytic
from orbatt import quaternion as qt
from orbatt.core import kepler
from orbatt.core import potentials as kp

try:  # optional baseline (c)
    import heyoka as hy
except Exception:  # pragma: no cover - optional
    hy = None

try:  # optional baseline (d); its import time is reported
    _t_import = time.perf_counter()
    from Basilisk import __version__ as BSK_VERSION
    from Basilisk.simulation import GravityGradientEffector as bsk_gg
    from Basilisk.simulation import spacecraft as bsk_spacecraft
    from Basilisk.simulation import svIntegrators as bsk_integrators
    from Basilisk.utilities import RigidBodyKinematics as bsk_rbk
    from Basilisk.utilities import SimulationBaseClass as bsk_sim
    from Basilisk.utilities import orbitalMotion as bsk_orbit
    from Basilisk.utilities import simIncludeGravBody as bsk_grav
    BSK_IMPORT_S = time.perf_counter() - _t_import
except Exception as _exc:  # pragma: no cover - optional
    BSK_VERSION, BSK_IMPORT_S, BSK_ERROR = None, None, f"{type(_exc).__name__}: {_exc}"

from heyoka_model import A, ARGP, ECC, GM, INC, N_MEAN, P0, PERIOD, Q0, RAAN  # noqa: E402  (the problem)
import heyoka_model  # noqa: E402

import end_to_end  # noqa: E402

TARGETS = (1e-6, 1e-9)
#: heyoka's loosest tolerance reaching each target, by (case kind, target) (the first-run peer)
HEYOKA_TOL = {}


class Spec:
    """Kernel specification of a potential (what orbatt.GravityGradient(KeplerOrbit(...))
    builds; written out here so the benchmark depends on the kernel contract only)."""

    def __init__(self, kind, params):
        self.kind, self.params, self.table = kind, np.asarray(params, dtype=float), np.zeros((0, 0))


ORB = kepler.orbit_vector(A, ECC, INC, RAAN, ARGP, 0.0, N_MEAN)
GG = Spec(kp.GRAVITY_GRADIENT_KEPLER, np.concatenate([[GM], ORB]))


def angle(q, qref):
    w = qt.mul(qt.conj(np.asarray(qref)), np.asarray(q))
    return float(2 * np.arctan2(np.linalg.norm(w[..., 1:]), abs(w[..., 0])))


def median_time(fn, repeats, budget_s=1.5):
    """Median of wall times of ``fn()`` (at least one, at most ``repeats``, stopping once
    ``budget_s`` is spent)."""
    times = []
    spent = 0.0
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t0
        times.append(dt)
        spent += dt
        if spent > budget_s and len(times) >= 1:
            break
    return statistics.median(times), out


# ---------------------------------------------------------------------------------------
# The cases


class Case:
    def __init__(self, name, body, potential, T, qref, inertia, kind):
        self.name, self.body, self.potential, self.T, self.qref = name, body, potential, T, qref
        self.inertia, self.kind = inertia, kind
        self.state = orbatt.State(body, Q0, P0)


def kepler_case():
    import astropy.units as u

    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    T = 10 * PERIOD
    s0 = orbatt.State(body, Q0, P0)
    ref = orbatt.propagate(body, s0, GG, [0.0, T], rtol=3e-15, atol=1e-18).q[-1]
    check = orbatt.propagate(body, s0, GG, [0.0, T], method="splitting6", step=T / 40000).q[-1]
    case = Case("Keplerian gravity gradient, 10 orbits", body, GG, T, ref, body.inertia_value, 2)
    case.ref_note = f"reference: dop853 rtol 3e-15; splitting6 with 40000 steps differs by {angle(check, ref):.1e} rad"
    return case


def free_case():
    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    T = 100.0
    qref, _ = analytic.torque_free(body.inertia_value, Q0, P0, np.array([T]))
    case = Case("torque-free, t = 100", body, orbatt.TorqueFree(), T, qref[0], body.inertia_value, 0)
    case.ref_note = "reference: exact solution (orbatt.analytic.torque_free)"
    return case


# ---------------------------------------------------------------------------------------
# Baselines (a), (b): numpy right-hand sides in solve_ivp


def _kepler_newton(M, e):
    E = M if e < 0.8 else math.pi
    for _ in range(50):
        d = (E - e * math.sin(E) - M) / (1 - e * math.cos(E))
        E -= d
        if abs(d) < 1e-15:
            break
    return E


def _radial(t):
    """Orbit radius and radial unit vector (inertial), as a user would code it."""
    E = _kepler_newton(N_MEAN * t, ECC)
    r = A * (1 - ECC * math.cos(E))
    f = 2 * math.atan2(math.sqrt(1 + ECC) * math.sin(E / 2), math.sqrt(1 - ECC) * math.cos(E / 2))
    u = ARGP + f
    cO, sO, ci, si, cu, su = math.cos(RAAN), math.sin(RAAN), math.cos(INC), math.sin(INC), math.cos(u), math.sin(u)
    return r, np.array([cO * cu - sO * su * ci, sO * cu + cO * su * ci, su * si])


def _qmul(a, b):
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return np.array([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0])


def _conj(a):
    return np.array([a[0], -a[1], -a[2], -a[3]])


def classical_rhs(case):
    I = case.inertia
    gg = case.kind == 2

    def f(t, x):
        q = x[:4]
        w = x[4:]
        tau = np.zeros(3)
        if gg:
            r, xs = _radial(t)
            xb = _qmul(_qmul(_conj(q), np.concatenate([[0.0], xs])), q)[1:]
            tau = 3 * GM / r**3 * np.cross(xb, I * xb)
        dw = (np.cross(I * w, w) + tau) / I
        dq = 0.5 * _qmul(q, np.concatenate([[0.0], w]))
        return np.concatenate([dq, dw])

    x0 = np.concatenate([Q0, case.state.omega])
    return f, x0


def quaternion_rhs(case):
    I = case.inertia
    inv = np.concatenate([[0.0], 1 / I])
    gg = case.kind == 2

    def f(t, y):
        q = y[:4]
        Q = y[4:]
        a = inv * _qmul(_conj(q), Q)
        dq = 0.25 * _qmul(q, a)
        dQ = 0.25 * _qmul(Q, a)
        if gg:
            r, xs = _radial(t)
            X = np.concatenate([[0.0], xs])
            xb = _qmul(_qmul(_conj(q), X), q)
            Y = np.concatenate([[0.0], I * xb[1:]])
            graw = -6 * GM / r**3 * _qmul(_qmul(X, q), Y)
            n2 = q @ q
            dQ = dQ - (graw - (q @ graw) / n2 * q) / n2**2
        return np.concatenate([dq, dQ])

    return f, np.concatenate([Q0, P0])


def run_scipy_model(case, model, rtol):
    from scipy.integrate import solve_ivp

    f, x0 = model(case)
    sol = solve_ivp(f, (0.0, case.T), x0, method="DOP853", rtol=rtol, atol=rtol)
    return sol.y[:4, -1], sol.nfev


# ---------------------------------------------------------------------------------------
# Baseline (c): heyoka


def heyoka_integrator(case, tol):
    """Eq. (7) with the tangential gradient (and heyoka's kepE for the orbit):
    :func:`heyoka_model.integrator`."""
    return heyoka_model.integrator(case.inertia, case.kind == 2, tol)


def run_heyoka(ta, case):
    return heyoka_model.propagate(ta, case.T)


# ---------------------------------------------------------------------------------------
# Baseline (d): Basilisk


def basilisk_sim(case, integrator, n, tol=None):
    """The Keplerian case as a Basilisk simulation (SI units), ``n`` task steps over ``case.T``
    (adaptive integrators: relTol = tol, absTol = tol / 100 when ``tol`` is given; with
    Basilisk's defaults, relTol 1e-4 and absTol 1e-8, RKF78 takes one step per task step here).

    Spacecraft hub with the body's inertia (kg m^2; principal axes = body axes, centre of mass
    at B), point-mass Earth (mu = GM, no spherical harmonics), GravityGradientEffector with the
    Earth as planet, the orbit from the same elements (Basilisk integrates it numerically with
    the same integrator; orbatt uses Kepler's equation). Attitude: sigma_BN = MRP of q0 (orbatt's
    q maps body to inertial components, i.e. it is Basilisk's beta_BN), omega_BN_B = g / I.
    The task period is an integer number of ns: the run ends at t_end = n * dt_ns, within
    n/2 ns of case.T; the error is measured against the reference at t_end.
    Returns (sim, spacecraft, t_end)."""
    T_ns = round(case.T * 1e9)
    dt_ns = round(T_ns / n)
    sim = bsk_sim.SimBaseClass()
    proc = sim.CreateNewProcess("dyn")
    proc.addTask(sim.CreateNewTask("dynTask", dt_ns))
    sc = bsk_spacecraft.Spacecraft()
    sc.ModelTag = "orbatt-kepler"
    sc.hub.mHub = 1000.0  # irrelevant: no force depends on it
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = np.diag(np.asarray(case.inertia) * 1e6).tolist()  # kg km^2 -> kg m^2
    grav = bsk_grav.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = GM * 1e9  # km^3/s^2 -> m^3/s^2: the benchmark's GM exactly
    grav.addBodiesTo(sc)
    oe = bsk_orbit.ClassicElements()
    oe.a, oe.e, oe.i, oe.Omega, oe.omega, oe.f = A * 1e3, ECC, INC, RAAN, ARGP, 0.0
    r0, v0 = bsk_orbit.elem2rv(GM * 1e9, oe)
    sc.hub.r_CN_NInit = np.reshape(r0, (3, 1)).tolist()
    sc.hub.v_CN_NInit = np.reshape(v0, (3, 1)).tolist()
    sc.hub.sigma_BNInit = np.reshape(bsk_rbk.EP2MRP(Q0 / np.linalg.norm(Q0)), (3, 1)).tolist()
    sc.hub.omega_BN_BInit = np.reshape(case.state.omega, (3, 1)).tolist()  # rad/s
    gg = bsk_gg.GravityGradientEffector()
    gg.ModelTag = "gravityGradient"
    gg.addPlanetName(earth.planetName)
    sc.addDynamicEffector(gg)
    integ = getattr(bsk_integrators, integrator)(sc)
    if tol is not None:
        integ.relTol, integ.absTol = tol, tol / 100
    sc.setIntegrator(integ)
    sim.AddModelToTask("dynTask", sc)
    sim.AddModelToTask("dynTask", gg)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(n * dt_ns)
    return sim, sc, n * dt_ns * 1e-9


_BSK_REFS = {}


def basilisk_reference(case, t_end):
    """The benchmark's tight reference (dop853 rtol 3e-15), at Basilisk's final time."""
    if t_end not in _BSK_REFS:
        _BSK_REFS[t_end] = orbatt.propagate(case.body, case.state, case.potential, [0.0, t_end], rtol=3e-15,
                                            atol=1e-18).q[-1]
    return _BSK_REFS[t_end]


def run_basilisk(case, integrator, n, tol=None):
    """One Basilisk run: (final attitude quaternion (scalar first), info dict)."""
    t0 = time.perf_counter()
    sim, sc, t_end = basilisk_sim(case, integrator, n, tol)
    t1 = time.perf_counter()
    sim.ExecuteSimulation()
    t2 = time.perf_counter()
    st = sc.scStateOutMsg.read()
    q = np.asarray(bsk_rbk.MRP2EP(st.sigma_BN), dtype=float)
    r_kep, x_kep = _radial(t_end)
    dr = float(np.linalg.norm(np.asarray(st.r_BN_N) / 1e3 - r_kep * x_kep))  # km
    return q, {"t_end": t_end, "setup_s": t1 - t0, "exec_s": t2 - t1, "dr_km": dr}


def basilisk_error(case):
    def error(q, info):
        return float(qt.angle_between(q, basilisk_reference(case, info["t_end"])))
    return error


def basilisk_rows(case, target, repeats):
    """Rows (d) for one target: RKF78 and RK4 at the largest task step reaching it (step
    search as for orbatt's fixed-step methods), RKF78 adaptive (600 s task steps) at the
    loosest tolerance reaching it, plus, at 1e-9, the issue's settings."""
    label = f"(d) Basilisk {BSK_VERSION}"
    error = basilisk_error(case)
    rows, setups = [], []

    def timed(run, n):
        """Median of ExecuteSimulation alone over fresh simulations (setup reported apart)."""
        execs = []
        for _ in range(max(1, min(repeats, 5))):
            q, info = run(n)
            execs.append(info["exec_s"])
            setups.append(info["setup_s"])
            if sum(execs) > 2.0:
                break
        return statistics.median(execs), q, info

    # adaptive RKF78: tolerance search, task step 600 s
    n600 = round(case.T / 600)
    tols = [10.0 ** (-k / 4) for k in range(24 if target > 1e-7 else 40, 65)]  # from 1e-6 / 1e-10 to 1e-16
    for tol in tols:
        q, info = run_basilisk(case, "svIntegratorRKF78", n600, tol)
        if error(q, info) <= target:
            break
    else:
        tol = None
    if tol is None:
        rows.append((target, f"{label} RKF78 adaptive", "not reached", None, None, None, None))
    else:
        tm, q, info = timed(lambda n: run_basilisk(case, "svIntegratorRKF78", n, tol), n600)
        rows.append((target, f"{label} RKF78 adaptive", f"relTol {tol:.1e}, 600 s", error(q, info),
                     f"dr {info['dr_km']:.0e} km", tm, None))
    runs = [("RKF78", "svIntegratorRKF78", None, 8, max(1, round(case.T / 120))),
            ("RK4", "svIntegratorRK4", None, 4, max(1, round(case.T / 8)))]
    if target < 1e-7:
        runs += [("RKF78", "svIntegratorRKF78", 30.0, None, None), ("RKF78", "svIntegratorRKF78", 10.0, None, None),
                 ("RK4", "svIntegratorRK4", 1.0, None, None)]
    for name, integ, dt, order, n0 in runs:
        def run(n, integ=integ):
            return run_basilisk(case, integ, n)
        if dt is None:
            n, err, info = search_steps(run, case, target, order, n0, error=error)
            if n is None:
                rows.append((target, f"{label} {name}", "not reached", None, None, None, None))
                continue
            method = f"{label} {name}"
        else:
            n = round(case.T / dt)
            method = f"{label} {name} {dt:.0f} s (issue)"
        tm, q, info = timed(run, n)
        rows.append((target, method, f"dt {case.T / n:.1f} s", error(q, info), f"{n} st, dr {info['dr_km']:.0e} km",
                     tm, None))
    return rows, statistics.median(setups) if setups else None


# ---------------------------------------------------------------------------------------
# Searches


RTOLS = [10.0 ** (-k / 4) for k in range(16, 57)]  # 1e-4 .. 1e-14, 4 per decade


def search_tolerance(run, case, target, start=0):
    """Loosest rtol of the grid with error <= target: ``run(rtol) -> (q, info)``."""
    for i in range(start, len(RTOLS)):
        q, info = run(RTOLS[i])
        err = angle(q, case.qref)
        if err <= target:
            return i, RTOLS[i], err, info
    return None, None, None, None


def search_steps(run, case, target, order, n0, error=None):
    """Fewest steps (to 3 %) with error <= target, from the error at ``n0`` and the order.
    ``error(q, info)``: the final attitude error (default: the angle to ``case.qref``)."""
    if error is None:
        def error(q, info):
            return angle(q, case.qref)
    q, info = run(n0)
    e0 = error(q, info)
    n = n0 if e0 <= target else int(n0 * (e0 / target) ** (1.0 / order) * 1.02) + 1
    for _ in range(12):
        q, info = run(n)
        err = error(q, info)
        if err <= target:
            # walk down while it still meets the target
            while n > 16:
                m = int(n / 1.03)
                q2, info2 = run(m)
                e2 = error(q2, info2)
                if e2 > target:
                    break
                n, err, info = m, e2, info2
            return n, err, info
        n = int(n * 1.15) + 1
    return None, None, None


# ---------------------------------------------------------------------------------------
# Report


def fmt_t(s):
    if s is None:
        return "-"
    if s < 1e-3:
        return f"{s * 1e6:.0f} us"
    if s < 1:
        return f"{s * 1e3:.2f} ms"
    return f"{s:.2f} s"


def work_precision(case, args, heyoka_available):
    print(f"\n## {case.name}\n{case.ref_note}\n")
    rows = []
    repeats = args.repeats

    def orbatt_adaptive(method, **options):
        def run(rtol):
            tr = orbatt.propagate(case.body, case.state, case.potential, [0.0, case.T], method=method, rtol=rtol,
                                  atol=rtol, **options)
            return tr.q[-1], tr
        return run

    def orbatt_fixed(method):
        def run(n):
            tr = orbatt.propagate(case.body, case.state, case.potential, [0.0, case.T], method=method,
                                  step=case.T / n)
            return tr.q[-1], tr
        return run

    fixed = [("rk4", 4, 2000), ("splitting2", 2, 20000), ("splitting4-yoshida", 4, 4000),
             ("splitting4-suzuki", 4, 2000), ("splitting4", 4, 2000), ("splitting6-yoshida", 6, 1000),
             ("splitting6", 6, 1000)]
    for target in TARGETS:
        # adaptive, compiled and scipy
        # on the Keplerian orbit dop853 integrates in the eccentric anomaly (the default); the
        # time form (0.1.0's, independent_variable = "time") beside it
        adaptive = [("dop853", "dop853", {}), ("vern98", "vern98", {}), ("scipy-DOP853", "scipy-DOP853", {})]
        if case.kind == 2:
            adaptive.insert(1, ("dop853", "dop853 in time", {"independent_variable": "time"}))
        for method, label, options in adaptive:
            run = orbatt_adaptive(method, **options)
            i, rtol, err, tr = search_tolerance(run, case, target)
            if rtol is None:
                rows.append((target, method, "not reached", None, None, None, None))
                continue
            tm, tr = median_time(lambda: run(rtol)[1], repeats)
            integ = tr.stats["wall_time_s"]
            work = f"{tr.stats['steps']} st / {tr.stats['rhs_evaluations']} f"
            rows.append((target, label, f"rtol=atol {rtol:.1e}", err, work, tm, integ))
            if label in ("dop853", "vern98"):  # what a user calls: the scenario file to the Dataset
                orbit = (GM, A, ECC, INC, RAAN, ARGP) if case.kind == 2 else None
                rows.append(end_to_end.end_to_end_row(case, target, rtol, repeats, median_time, angle, Q0, P0,
                                                      orbit, method=label))
        if case.kind == 0:  # the closed form (method "exact"): nothing to tune, the same call at every target
            tm, tr = median_time(lambda: orbatt.propagate(case.body, case.state, case.potential, [0.0, case.T],
                                                          method="exact"), repeats)
            rows.append((target, "exact", "closed form", angle(tr.q[-1], case.qref), "0 st / 0 f", tm,
                         tr.stats["wall_time_s"]))
            rows.append(end_to_end.end_to_end_row(case, target, 1e-10, repeats, median_time, angle, Q0, P0,
                                                  method="exact"))  # (the file's rtol, unused)
        for method, order, n0 in fixed:
            if method == "splitting2" and target < 1e-7 and not args.full:
                # ~2.5e7 steps (5 s per run): estimated from the 1e-6 row, not run
                prev = [r for r in rows if r[1] == method and r[0] == 1e-6]
                if prev and prev[0][3] is not None:
                    n6 = int(prev[0][2].split()[0])
                    n9 = int(n6 * (prev[0][3] / target) ** 0.5)
                    rows.append((target, method, f"~{n9} steps (est.)", None, "not run (--full runs it)",
                                 prev[0][5] * n9 / n6, None))
                continue
            run = orbatt_fixed(method)
            n, err, tr = search_steps(run, case, target, order, n0)
            if n is None:
                rows.append((target, method, "not reached", None, None, None, None))
                continue
            tm, tr = median_time(lambda: run(n)[1], repeats)
            ev = tr.stats.get("kicks", tr.stats.get("rhs_evaluations"))
            rows.append((target, method, f"{n} steps", err, f"{ev} {'kicks' if 'kicks' in tr.stats else 'f'}", tm,
                         tr.stats["wall_time_s"]))
        # baselines (a), (b)
        for label, model in (("(a) Euler+kinematics, numpy, solve_ivp", classical_rhs),
                             ("(b) eq. 7, numpy, solve_ivp", quaternion_rhs)):
            def run(rtol, model=model):
                return run_scipy_model(case, model, rtol)
            i, rtol, err, nfev = search_tolerance(run, case, target, start=8 if target < 1e-7 else 0)
            if rtol is None:
                rows.append((target, label, "not reached", None, None, None, None))
                continue
            tm, _ = median_time(lambda: run(rtol), min(repeats, 3), budget_s=3.0)
            rows.append((target, label, f"rtol=atol {rtol:.1e}", err, f"{nfev} f", tm, None))
        # (c) heyoka
        if heyoka_available:
            found = None
            for tol in [10.0 ** (-k / 4) for k in range(20, 61)]:
                _, ta = heyoka_integrator(case, tol)
                q = run_heyoka(ta, case)
                err = angle(q, case.qref)
                if err <= target:
                    found = (tol, ta, err)
                    break
            if found:
                tol, ta, err = found
                HEYOKA_TOL[(case.kind, target)] = tol
                tm, _ = median_time(lambda: run_heyoka(ta, case), repeats)
                rows.append((target, f"(c) heyoka {hy.__version__}", f"tol {tol:.1e}", err, f"order {ta.order}", tm,
                             tm))
            else:
                rows.append((target, "(c) heyoka", "not reached", None, None, None, None))
        # (d) Basilisk (the Keplerian case only)
        if case.kind == 2 and BSK_VERSION is not None:
            brows, bsk_setup = basilisk_rows(case, target, repeats)
            rows += brows
    # print
    base = {}
    for r in rows:
        if r[1].startswith("(a)") or r[1].startswith("(b)") or r[1].startswith("(c)"):
            base[(r[0], r[1][:3])] = r[5]
        elif r[1].startswith("(d)") and r[3] is not None and r[3] <= r[0] and r[5]:
            # Basilisk's best (fastest row reaching the target)
            key = (r[0], "(d)")
            base[key] = min(base.get(key, math.inf), r[5])
    hdr = (f"{'target':>7}  {'method':<40} {'setting':<22} {'error':>8}  {'work':<26} {'time':>9} {'integr.':>9}"
           f" {'vs (a)':>7} {'vs (b)':>7} {'vs (c)':>7} {'vs (d)':>7}")
    print(hdr)
    print("-" * len(hdr))
    for target, method, setting, err, work, tm, integ in rows:
        ratios = []
        for key in ("(a)", "(b)", "(c)", "(d)"):
            b = base.get((target, key))
            ratios.append(f"{b / tm:7.1f}" if (b and tm) else f"{'-':>7}")
        print(f"{target:7.0e}  {method:<40} {setting:<22} {('%.1e' % err) if err is not None else '-':>8}  "
              f"{work or '-':<26} {fmt_t(tm):>9} {fmt_t(integ):>9} {' '.join(ratios)}")
    if case.kind == 2 and BSK_VERSION is not None:
        print(f"(d) Basilisk {BSK_VERSION}: time = ExecuteSimulation alone (median over fresh simulations); import "
              f"{BSK_IMPORT_S:.2f} s (once), setup (build + InitializeSimulation) {fmt_t(bsk_setup)} per run, not "
              "included; dr = Basilisk's numerically integrated orbit position minus Kepler's at the final time; "
              "error against the reference at Basilisk's final time n * dt (integer ns, within 3e-5 s of T)")
        for target in TARGETS:
            best = base.get((target, "(d)"))
            for label in ("dop853", "vern98"):
                dop = [r for r in rows if r[0] == target and r[1] == label and r[5]]
                e2e = [r for r in rows if r[0] == target and r[1] == f"{label}, load_scenario().run()" and r[5]]
                if best and dop:
                    bname = min((r for r in rows if r[0] == target and r[1].startswith("(d)") and r[5] == best),
                                key=lambda r: r[5])
                    print(f"{label} vs Basilisk's best at {target:.0e} rad ({bname[1][4:]}, {bname[2]}, "
                          f"{fmt_t(best)}): "
                          + (f"{best / e2e[0][5]:.0f}x (load_scenario().run() {fmt_t(e2e[0][5])}), " if e2e else "")
                          + f"{best / dop[0][5]:.0f}x (propagate {fmt_t(dop[0][5])}), "
                          f"{best / dop[0][6]:.0f}x (compiled loop {fmt_t(dop[0][6])})")
    return rows


def ns_per_step(case, repeats):
    """Cost of one step: Strang (1 gradient + 5 rotations) and the RHS via RK4 (4 RHS)."""
    out = {}
    n = 200_000
    T = case.T
    for method in ("splitting2", "splitting4", "splitting6", "rk4"):
        tm, tr = median_time(lambda: orbatt.propagate(case.body, case.state, case.potential, [0.0, T],
                                                      method=method, step=T / n), repeats)
        out[method] = tr.stats["wall_time_s"] / n * 1e9
    tm, tr = median_time(lambda: orbatt.propagate(case.body, case.state, case.potential, [0.0, T], rtol=1e-11,
                                                  atol=1e-13), repeats)
    out["dop853 per RHS"] = tr.stats["wall_time_s"] / tr.stats["rhs_evaluations"] * 1e9
    return out


def ensemble_states(body, n, seed=1):
    """The paper's case perturbed: random attitude (uniform), body momentum = the paper's
    g(t0) + 10 % isotropic noise."""
    rng = np.random.default_rng(seed)
    q = qt.normalize(rng.normal(size=(n, 4)))
    g0 = 0.5 * qt.vector(qt.mul(qt.conj(Q0), P0))
    g = g0 + 0.1 * np.linalg.norm(g0) * rng.normal(size=(n, 3))
    return q, g


def ensembles(case, sizes, repeats):
    print("\n## Ensembles (Keplerian case, one orbit)\n")
    import numba

    body = case.body
    T = PERIOD
    # settings for <= 1e-9 rad after one orbit, checked on a sample of 24 members
    qs, gs = ensemble_states(body, 24, seed=99)
    sample = orbatt.State.from_momentum(body, qs, gs)
    ref = orbatt.propagate(body, sample, GG, [0.0, T], rtol=3e-15, atol=1e-18).q[:, -1]

    def sample_error(**kw):
        tr = orbatt.propagate(body, sample, GG, [0.0, T], **kw)
        return max(angle(tr.q[e, -1], ref[e]) for e in range(24))

    settings = {}
    for method in ("dop853", "dop853-lanes"):
        for rtol in RTOLS:
            err = sample_error(method=method, rtol=rtol, atol=rtol)
            if err <= 1e-9:
                settings[method] = ({"rtol": rtol, "atol": rtol}, f"rtol = atol {rtol:.1e}", err)
                break
    for n in (100, 120, 150, 180, 220, 270, 330, 400, 500, 600, 800, 1000):
        err = sample_error(method="splitting6", step=T / n)
        if err <= 1e-9:
            settings["splitting6"] = ({"step": T / n}, f"{n} steps/orbit", err)
            break
    n2 = 2000
    settings["splitting2"] = ({"step": T / n2}, f"{n2} steps/orbit", sample_error(method="splitting2", step=T / n2))
    print("members: the paper's state with a uniformly random attitude and the body momentum perturbed by 10 % "
          f"(isotropic); numba threads: {numba.get_num_threads()}")
    for method, (kw, label, err) in settings.items():
        print(f"  {method:<13} {label:<20} max error on 24 sampled members {err:.1e} rad")
    print(f"\n{'N':>7}  {'method':<13} {'time':>9} {'body-orbits/s':>14} {'body-steps/s':>13} {'steps/member':>13}")
    results = []
    for N in sizes:
        q, g = ensemble_states(body, N)
        states = orbatt.State.from_momentum(body, q, g)
        for method, (kw, label, err) in settings.items():
            small = orbatt.State.from_momentum(body, q[:64], g[:64])
            orbatt.propagate(body, small, GG, [0.0, T], method=method, **kw)  # compile / warm up
            tm, tr = median_time(lambda: orbatt.propagate(body, states, GG, [0.0, T], method=method, **kw),
                                 repeats if N <= 10_000 else 1, budget_s=3.0)
            wall = tr.stats["wall_time_s"]
            bo = f"{N / wall:14.0f}" if err <= 1e-9 else f"{'(%.0e rad)' % err:>14}"
            print(f"{N:7d}  {method:<13} {fmt_t(wall):>9} {bo} {tr.stats['steps'] / wall:13.3g} "
                  f"{tr.stats['steps'] / N:13.1f}")
            results.append((N, method, wall, N / wall, tr.stats["steps"] / wall))
    # one thread, for a per-core comparison (heyoka's batch mode below runs on one thread)
    N = sizes[0]
    q, g = ensemble_states(body, N)
    states = orbatt.State.from_momentum(body, q, g)
    nthreads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        for method in ("dop853", "dop853-lanes", "splitting2"):
            kw, label, err = settings[method]
            tm, tr = median_time(lambda: orbatt.propagate(body, states, GG, [0.0, T], method=method, **kw), repeats,
                                 budget_s=3.0)
            wall = tr.stats["wall_time_s"]
            bo = f"{N / wall:14.0f}" if err <= 1e-9 else f"{'(%.0e rad)' % err:>14}"
            print(f"{N:7d}  {method:<13} {fmt_t(wall):>9} {bo} {tr.stats['steps'] / wall:13.3g} "
                  f"{tr.stats['steps'] / N:13.1f}   (1 thread)")
    finally:
        numba.set_num_threads(nthreads)
    return results


def heyoka_ensemble(case, sizes, repeats):
    """heyoka's batch mode (SIMD lanes) over the same ensemble, threads over batches."""
    body = case.body
    T = PERIOD
    qs, gs = ensemble_states(body, 24, seed=99)
    sample = orbatt.State.from_momentum(body, qs, gs)
    ref = orbatt.propagate(body, sample, GG, [0.0, T], rtol=3e-15, atol=1e-18).q[:, -1]
    sys_, _ = heyoka_integrator(case, 1e-9)
    bs = hy.recommended_simd_size()
    for tol in [10.0 ** (-k / 2) for k in range(12, 30)]:
        ta = hy.taylor_adaptive(sys_, list(Q0) + list(P0), tol=tol)
        errs = []
        for e in range(24):
            ta.time = 0.0
            ta.state[:] = list(qs[e]) + list(sample.Q[e])
            ta.propagate_until(T)
            errs.append(angle(np.array(ta.state[:4]), ref[e]))
        if max(errs) <= 1e-9:
            break
    print(f"\nheyoka {hy.__version__} batch mode (SIMD width {bs}), tol {tol:.1e}: max error {max(errs):.1e} rad")
    for N in sizes:
        q, g = ensemble_states(body, N)
        st = orbatt.State.from_momentum(body, q, g)
        y0 = np.concatenate([st.q, st.Q], axis=1)
        nb = N // bs
        tab = hy.taylor_adaptive_batch(sys_, np.ascontiguousarray(y0[:bs].T), tol=tol)
        # one batch integrator reused in a Python loop (heyoka's ensemble_propagate_until_batch
        # copies the integrator for every batch and measured 10x slower here): one thread
        t0 = time.perf_counter()
        for i in range(nb):
            tab.set_time(0.0)
            tab.state[:] = y0[i * bs:(i + 1) * bs].T
            tab.propagate_until(T)
        wall = time.perf_counter() - t0
        print(f"{N:7d}  {'heyoka batch':<13} {fmt_t(wall):>9} {nb * bs / wall:14.0f}   (1 thread; x2 for 2 cores)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="N = 1e3 and 1e4 ensembles, fewer repeats")
    ap.add_argument("--full", action="store_true", help="also run Strang at 1e-9 (~2.5e7 steps)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--no-ensembles", action="store_true")
    ap.add_argument("--no-first-runs", action="store_true",
                    help="skip the fresh-process rows (orbatt run with an empty numba cache, its background warm-up, "
                         "and a first run waiting for the compiler: 1-2 minutes)")
    args = ap.parse_args(argv)
    if args.quick:
        args.repeats = 3
    import numba

    print("# orbatt integrator benchmark")
    print(f"orbatt {orbatt.__version__}, numpy {np.__version__}, numba {numba.__version__}, python "
          f"{platform.python_version()}, {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"numba threads {numba.get_num_threads()}")
    print("time: median wall time of the whole call (orbatt.propagate / solve_ivp / heyoka propagate_until); "
          "integr.: orbatt's compiled loop alone (stats['wall_time_s'])")
    if hy is None:
        print("(c) heyoka: not installed - skipped (pip install heyoka)")
    if BSK_VERSION is None:
        print(f"(d) Basilisk: not importable - skipped (pip install bsk; {BSK_ERROR})")
    t_start = time.time()
    # warm up the compiled kernels (first call compiles or loads the cache)
    free = free_case()
    for m, kw in (("dop853", {}), ("exact", {}), ("splitting2", {"step": 1.0}), ("rk4", {"step": 1.0})):
        orbatt.propagate(free.body, free.state, free.potential, [0.0, 1.0], method=m, **kw)
    kep = kepler_case()
    for case in (kep, free):
        work_precision(case, args, hy is not None)
    if not args.no_first_runs:
        end_to_end.print_first_runs(end_to_end.first_runs(HEYOKA_TOL.get((2, 1e-9))), fmt_t)
    print("\n## Cost per step, Keplerian case (ns)")
    for k, v in ns_per_step(kep, args.repeats).items():
        print(f"  {k:<16} {v:7.0f} ns")
    if not args.no_ensembles:
        sizes = (1000, 10_000) if args.quick else (1000, 100_000)
        ensembles(kep, sizes, args.repeats)
        if hy is not None:
            heyoka_ensemble(kep, sizes, args.repeats)
        n_ens = 10_000 if args.quick else 100_000
        end_to_end.print_ensemble_dataset(end_to_end.ensemble_dataset(n_ens, args.repeats, median_time), n_ens, fmt_t)
        n_env = 200 if args.quick else 1000  # the environment needs rtol 1e-14 .. 3e-15 for 1e-6 rad (end_to_end.py)
        end_to_end.print_environment_ensemble(
            end_to_end.environment_ensemble(n_env, args.repeats, median_time, angle, RTOLS), n_env, fmt_t)
    print(f"\ntotal benchmark time {time.time() - t_start:.0f} s")


if __name__ == "__main__":
    main()

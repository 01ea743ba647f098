"""What a user calls, timed beside the compiled loop (issue 15), for ``run.py``:

* the end-to-end row of each case: ``orbatt.load_scenario(path).run()`` on a scenario file of
  the case (the benchmark's state, outputs at the start and the end), at the tolerance the
  ``dop853`` row found: parsing, building the orbit and potential, the propagation and the
  xarray Dataset;
* first runs in a fresh process: ``orbatt run scenarios/paper-keplerian.toml -o tmp`` with an
  empty numba cache (``NUMBA_CACHE_DIR`` a new temporary folder: the kernels run interpreted
  while a background warm-up compiles them, ``orbatt.coldstart``), the warm-up's time, the run
  again with that cache warm, a first run that waits for the compiler
  (``ORBATT_COLD_START=compile``: every kernel it needs is compiled), beside heyoka's first result in a fresh process
  (import, JIT compilation of the Taylor integrator, the Keplerian case over 10 orbits at the
  tolerance reaching 1e-9 rad: ``heyoka_model.py``);
* an ensemble with the gravity gradient plus environment torques (drag, SRP, a residual
  dipole on six facets: ``torques.py``'s cubesat) beside the same ensemble with the gravity
  gradient alone.
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import orbatt
from orbatt import quaternion as qt

ROOT = Path(__file__).resolve().parent.parent


def _floats(x):
    return "[" + ", ".join(repr(float(v)) for v in x) + "]"


def scenario_text(case, rtol, q0, p0, orbit=None):
    """The scenario file of ``case`` (``kind`` 2: Keplerian gravity gradient, with ``orbit`` =
    ``(gm, a, e, i, raan, argp)`` in km, rad; 0: torque-free, dimensionless) at ``rtol = atol``,
    outputs at 0 and ``case.T``."""
    lines = [f'name = "benchmark-{"keplerian" if case.kind == 2 else "torque-free"}"']
    if case.kind == 2:
        gm, a, e, inc, raan, argp = orbit
        lines += ["[body]", "inertia = [" + ", ".join(f'"{v!r} kg km2"' for v in map(float, case.inertia)) + "]",
                  "[potential]", 'kind = "gravity-gradient"',
                  "[orbit]", 'provider = "kepler"', f'gm = "{gm!r} km3 / s2"', f'a = "{a!r} km"', f"e = {e!r}",
                  f'i = "{inc!r} rad"', f'raan = "{raan!r} rad"', f'argp = "{argp!r} rad"', 'true_anomaly = "0 rad"']
        span = f'"{case.T!r} s"'
    else:
        lines += ["[body]", f"inertia = {_floats(case.inertia)}", "[potential]", 'kind = "torque-free"']
        span = repr(float(case.T))
    lines += ["[initial]", f"q = {_floats(q0)}", f"Q = {_floats(p0)}",
              "[integration]", 'method = "dop853"', f"rtol = {rtol!r}", f"atol = {rtol!r}",
              f"t_end = {span}", f"output_step = {span}"]
    return "\n".join(lines) + "\n"


def end_to_end_row(case, target, rtol, repeats, median_time, angle, q0, p0, orbit=None, method="dop853"):
    """The row ``(target, method, setting, error, work, time, integr.)`` of
    ``load_scenario(path).run()`` at ``rtol = atol`` (with ``method``, e.g. ``"exact"``, for the
    file's ``[integration] method``)."""
    folder = tempfile.mkdtemp(prefix="orbatt-bench-")
    path = Path(folder) / "case.toml"
    path.write_text(scenario_text(case, rtol, q0, p0, orbit))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        orbatt.load_scenario(path).run(method)  # compiled kernels loaded
        tm, ds = median_time(lambda: orbatt.load_scenario(path).run(method), repeats)
    stats = ds.orbatt.stats
    err = angle(ds["q"].values[-1], case.qref)
    setting = "closed form" if method == "exact" else f"rtol=atol {rtol:.1e}"
    return (target, f"{method}, load_scenario().run()", setting, err,
            f"{stats['steps']} st / {stats['rhs_evaluations']} f", tm, stats["wall_time_s"])


def _wall(cmd, env):
    start = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tempfile.gettempdir())
    return time.perf_counter() - start


def _wait_for_stamp(folder, timeout=600.0):
    """Seconds until a warm stamp of :mod:`orbatt.coldstart` appears in ``folder`` (None: not
    within ``timeout``)."""
    start = time.perf_counter()
    while time.perf_counter() - start < timeout:
        if any(Path(folder).glob("warm-*.json")):
            return time.perf_counter() - start
        time.sleep(0.2)
    return None


def first_runs(heyoka_tol=None, warm_repeats=3):
    """``[(label, seconds)]``: ``orbatt run`` of the shipped Keplerian scenario in a fresh
    process with an empty numba cache (by default: interpreted kernels while a background
    warm-up compiles them, :mod:`orbatt.coldstart`), the warm-up's time to its stamp, the run
    warm (best of ``warm_repeats``), a first run that waits for the compiler
    (``ORBATT_COLD_START=compile``), and heyoka's first result in a fresh process (best of 3)
    when ``heyoka_tol`` is given."""
    orbatt_cmd = [sys.executable, "-m", "orbatt.cli", "run", str(ROOT / "scenarios" / "paper-keplerian.toml")]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    env.pop("ORBATT_COLD_START", None)
    rows = []
    with tempfile.TemporaryDirectory(prefix="orbatt-numba-") as cache, \
            tempfile.TemporaryDirectory(prefix="orbatt-out-") as out:
        env["NUMBA_CACHE_DIR"] = cache
        cmd = orbatt_cmd + ["-o", os.path.join(out, "r.nc"), "--quiet"]
        first = _wall(cmd, env)
        rows.append(("orbatt run, empty numba cache (first run, interpreted)", first))
        waited = _wait_for_stamp(Path(cache) / "orbatt")
        if waited is not None:
            rows.append(("  its background warm-up, done after", first + waited))
        rows.append(("orbatt run, warm numba cache", min(_wall(cmd, env) for _ in range(warm_repeats))))
    with tempfile.TemporaryDirectory(prefix="orbatt-numba-") as cache, \
            tempfile.TemporaryDirectory(prefix="orbatt-out-") as out:
        env["NUMBA_CACHE_DIR"] = cache
        cmd = orbatt_cmd + ["-o", os.path.join(out, "r.nc"), "--quiet"]
        rows.append(("orbatt run, empty cache, ORBATT_COLD_START=compile", _wall(cmd, dict(env, ORBATT_COLD_START="compile"))))
    if heyoka_tol is not None:
        hcmd = [sys.executable, str(ROOT / "benchmarks" / "heyoka_model.py"), repr(heyoka_tol)]
        rows.append((f"heyoka: import + JIT + 10 orbits (tol {heyoka_tol:.1e})", min(_wall(hcmd, env) for _ in range(3))))
    return rows


#: attitude error the environment-torque ensemble is run to: the tabulated environment (cubic
#: splines, the shadow function's kinks at umbra and penumbra entry) keeps even a run at
#: rtol 1e-14 about 2e-7 rad from the tight reference, so 1e-9 rad is out of reach here
ENV_TARGET = 1e-6


def environment_ensemble(n_members, repeats, median_time, angle, rtols):
    """``[(label, setting, max error, seconds, body-orbits/s)]``: ``dop853`` over one orbit of
    ``n_members`` cubesats (random attitudes and rates) with the gravity gradient alone and
    with drag, SRP and a residual dipole on six facets, each at the loosest tolerance for which
    24 sampled members end within :data:`ENV_TARGET` of a tight run."""
    from astropy import units as u
    from astropy.time import Time

    from orbatt.environment.atmosphere import ExponentialAtmosphere
    from orbatt.environment.magnetic import DipoleField
    from orbatt.orbits import KeplerOrbit
    from orbatt.torques import EnvironmentTorques
    from torques import facets

    epoch = Time("2025-03-20T00:00:00", scale="utc")
    orbit = KeplerOrbit(6778.137 * u.km, 0.0005, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, true_anomaly=0 * u.deg,
                        epoch=epoch)
    T = orbit.period_value
    body = orbatt.RigidBody([0.0387, 0.0387, 0.0067] * u.kg * u.m**2)
    env = EnvironmentTorques(orbit, T * u.s, facets=facets(), drag=True, srp=True,
                             residual_dipole=[0.005, 0.0, 0.002] * u.A * u.m**2,
                             atmosphere=ExponentialAtmosphere(3e-12 * u.kg / u.m**3, 400 * u.km, 60 * u.km),
                             magnetic_field=DipoleField(epoch))
    rng = np.random.default_rng(7)

    def members(n):
        q = qt.normalize(rng.normal(size=(n, 4)))
        w = rng.normal(size=(n, 3)) * math.radians(0.5)  # rad/s
        return orbatt.State.from_omega(body, q, w * u.rad / u.s)

    sample, states = members(24), members(n_members)
    out = []
    for label, pot in (("gravity gradient alone", orbatt.GravityGradient(orbit)),
                       ("+ drag, SRP, magnetic (6 facets)", env)):
        ref = orbatt.propagate(body, sample, pot, [0.0, T], rtol=3e-15, atol=1e-18).q[:, -1]
        # the tabulated environment (cubic splines in time, knots where the third derivative
        # jumps) converges erratically: the grid goes on to the smallest rtol float64 allows
        for rtol in [*rtols, 3e-15]:
            q = orbatt.propagate(body, sample, pot, [0.0, T], rtol=rtol, atol=rtol).q[:, -1]
            err = max(angle(q[e], ref[e]) for e in range(24))
            if err <= ENV_TARGET:
                break
        tm, tr = median_time(lambda: orbatt.propagate(body, states, pot, [0.0, T], rtol=rtol, atol=rtol), repeats,
                             budget_s=3.0)
        wall = tr.stats["wall_time_s"]
        setting = f"rtol = atol {rtol:.1e}" + ("" if err <= ENV_TARGET else " (target not reached)")
        out.append((label, setting, err, wall, n_members / wall))
    return out


def print_first_runs(rows, fmt_t):
    print("\n## First runs in a fresh process (Keplerian case, shipped scenario: 2 orbits, 1166 outputs)\n")
    peer = rows[-1][1] if rows[-1][0].startswith("heyoka") else None
    print(f"{'what':<58} {'wall':>9} {'vs heyoka first result':>24}")
    for label, s in rows:
        ratio = f"{peer / s:23.2f}x" if peer else f"{'-':>24}"
        print(f"{label:<58} {fmt_t(s):>9} {ratio}")


def print_environment_ensemble(rows, n_members, fmt_t):
    print(f"\n## Ensemble with environment torques (cubesat in LEO, one orbit, N = {n_members}, dop853, "
          f"<= {ENV_TARGET:.0e} rad on 24 sampled members)\n")
    print(f"{'model':<34} {'setting':<42} {'max error':>9} {'time':>9} {'body-orbits/s':>14} {'vs GG alone':>12}")
    base = rows[0][4]
    for label, setting, err, wall, rate in rows:
        print(f"{label:<34} {setting:<42} {err:9.1e} {fmt_t(wall):>9} {rate:14.0f} {rate / base:11.2f}x")
    print("  (peer: the same members with the gravity gradient alone, same run; heyoka has no tabulated "
          "environment to compare with)")


def ensemble_dataset(n_members, repeats, median_time):
    """What a user of an ensemble calls: ``propagate`` (``dop853-lanes``, the shipped
    ``paper-keplerian`` over one orbit, 11 outputs) and ``to_dataset`` of its result, beside the
    Dataset's energy and torques by one call per member (``potentials.energy_and_torques``, the
    path before ``potentials.evaluate_members``) and by the one compiled call. Rows ``(what,
    time)``."""
    from orbatt.dataset import to_dataset
    from orbatt.potentials import energy_and_torques, evaluate_members, member_body

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = orbatt.load_scenario("paper-keplerian")
    rng = np.random.default_rng(1)
    q0 = qt.normalize(rng.normal(size=(n_members, 4)))
    g0 = sc.state0.g * (1.0 + 0.1 * rng.normal(size=(n_members, 3)))
    states = orbatt.State.from_momentum(sc.body, q0, g0)
    period = sc.orbit.period_value
    t = np.linspace(0.0, period, 11)
    kw = {"method": "dop853-lanes", "rtol": 1e-10, "atol": 1e-10}
    tr = orbatt.propagate(sc.body, states, sc.potential, t, **kw)
    to_dataset(tr)  # compiled kernels loaded
    tp, _ = median_time(lambda: orbatt.propagate(sc.body, states, sc.potential, t, **kw), repeats, budget_s=3.0)
    td, _ = median_time(lambda: to_dataset(tr), repeats, budget_s=3.0)
    inertia = np.broadcast_to(sc.body.inertia_value, (n_members, 3)).copy()

    def per_member():
        return [energy_and_torques(sc.potential, member_body(sc.body, inertia[e]), tr.t, tr.q[e], True)
                for e in range(n_members)]

    tm, _ = median_time(per_member, repeats, budget_s=3.0)
    te, _ = median_time(lambda: evaluate_members(sc.potential, sc.body, inertia, tr.t, tr.q, True), repeats,
                        budget_s=3.0)
    return [("propagate (dop853-lanes, rtol 1e-10)", tp), ("to_dataset", td),
            ("  its energy and torques: a call per member", tm), ("  its energy and torques: one compiled call", te)]


def print_ensemble_dataset(rows, n_members, fmt_t):
    print(f"\n## Ensemble end to end (paper-keplerian, {n_members} members, one orbit, 11 outputs)\n")
    base = rows[2][1]
    for what, tm in rows:
        ratio = f"{base / tm:8.1f}x" if what.startswith("  its") else ""
        print(f"{what:<48} {fmt_t(tm):>10} {ratio}")
    print(f"{'propagate + to_dataset':<48} {fmt_t(rows[0][1] + rows[1][1]):>10}")

"""The day-long 3U CubeSat against Basilisk 2.12, in-process and as whole processes (issue 25).

Run from a checkout: ``python benchmarks/basilisk_day.py`` (about 3-4 min on 2 cores, much of it
the classical reference over the day and Basilisk; ``--quick``: fewer repeats and the classical
reference over 6 h only). Basilisk (``pip install bsk``) is optional: without it only orbatt's
rows are printed.

The case is that of ``benchmarks/basilisk_environment.py`` (a 3U CubeSat tumbling at
|omega| = 3.9e-3 rad/s on a 400 km dawn-dusk orbit in full Sun; gravity gradient, facet drag in
an exponential atmosphere without co-rotation, facet SRP), over one day (86400 s), outputs every
60 s. Its functions build the case in orbatt, in the classical model (scipy) and in Basilisk.

Accuracy. The reference is orbatt at rtol 1e-14 (atol 1e-16), checked against the classical
model (scipy DOP853, rtol 1e-13) over the day. The case is chaotic: a relative change of 1e-12
in the initial rate grows to ~1e-2 rad within the day (the script prints the growth), so over
the whole day no float64 integration, the two references included, is defined to better than
~1e-3 rad. Each row's error is therefore the largest attitude angle to the reference at the
60 s outputs over two spans: **one orbit** (5580 s: the integrator's own accuracy, before the
chaos amplifies it) and the **certified span** (the longest start of the day over which the
two references agree to 1e-8 rad, about 5 h); the error over the whole day is printed too. The
tolerance searches: the loosest orbatt rtol of a grid (4 per decade, as ``benchmarks/run.py``'s
``search_tolerance``) and the largest Basilisk task step of a list (RKF78 with its default
tolerances, one step per task step; RK4) whose error meets the target.

Times (median of ``--repeats``; orbatt's in-process times, milliseconds, of at least 21), all
over the whole day:

* in-process: ``orbatt.propagate`` (kernels warm, the case's tables sampled; the set-up,
  :func:`orbatt_setup`, separately) against Basilisk's ``ExecuteSimulation()`` (its set-up, the simulation
  built and initialized, separately);
* whole processes: ``orbatt run CASE.toml -o X.nc --quiet`` (``python -m orbatt.cli``) on a
  scenario file of the case written by the script (warm numba cache: one run first, discarded)
  against a fresh ``python basilisk_day.py --basilisk-case JSON`` that imports Basilisk, builds
  the simulation, executes it and saves the attitude at the outputs (``.npy``); the processes
  run without ``PYTHONDONTWRITEBYTECODE`` (:func:`child_env`); a discarded Basilisk process
  first too.

Basilisk's Sun: ``facetSRPDynamicEffector`` reads a Sun message; the script writes astropy's
Sun into it at the midpoint of every 60 s (Basilisk's pip package ships no SPICE kernels; the
Sun moves 1.2e-5 rad in 60 s), the Basilisk process reads those positions from a ``.npy`` file
written by the script (no astropy in that process).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import basilisk_environment as be  # noqa: E402

DAY = 86400.0
OUT_STEP = 60.0
SUN_EVERY = 60.0                    # s: Basilisk's Sun message is rewritten every SUN_EVERY s
TERMS = ("gravity_gradient", "drag", "srp")
TARGETS = (1e-3, 1e-6)
RTOLS = [10.0 ** (-k / 4) for k in range(8, 57)]   # 1e-2 .. 1e-14, 4 per decade
REF_RTOL = 1e-14
AGREE = 1e-8                        # rad: the references' agreement over the certified span
#: the imports of a process that only imports (orbatt run's and the Basilisk case's)
IMPORTS = {"orbatt": "import orbatt.cli",
           "Basilisk": "import numpy; from Basilisk.simulation import spacecraft, svIntegrators, GravityGradientEffector, "
                       "exponentialAtmosphere, facetDragDynamicEffector, facetSRPDynamicEffector; "
                       "from Basilisk.utilities import SimulationBaseClass, simIncludeGravBody, RigidBodyKinematics; "
                       "from Basilisk.architecture import messaging"}
#: RHS evaluations per step (Basilisk's RKF78 at its default tolerances takes one step per task step)
STAGES = {"rkf78": 13, "rk4": 4}
DTS = {"rkf78": (8.0, 4.0, 2.0, 1.0, 0.5), "rk4": (8.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.125)}


def child_env(**extra):
    """The environment of a timed process: this one's without ``PYTHONDONTWRITEBYTECODE`` (set
    on some machines; with it every process of an editable install compiles orbatt's ~100
    modules again, ~0.2 s, where an installed package has its bytecode), plus ``extra``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return {**env, **extra}


# --- the scenario file of the case (orbatt run)
def _vec(x, unit):
    return "[" + ", ".join(f'"{float(c)!r} {unit}"' for c in x) + "]"


def _plain(x):
    return "[" + ", ".join(repr(float(c)) for c in x) + "]"


def scenario_toml(rtol, t_end=DAY):
    """The TOML text of the case as an ``orbatt run`` scenario (dop853 at ``rtol``, atol
    ``rtol * 1e-2`` as :func:`orbatt_propagate`, outputs every 60 s over ``t_end`` s)."""
    lines = ['name = "basilisk-day-3u"', "", "[body]", f"inertia = {_vec(be.INERTIA, 'kg m2')}", ""]
    for k in range(6):
        lines += ["[[body.facets]]", f'area = "{float(be.AREA[k])!r} m2"', f"normal = {_plain(be.N[k])}",
                  f"position = {_vec(be.P[k], 'm')}", f"drag_coefficient = {float(be.CD[k])!r}",
                  f"specular = {float(be.CS[k])!r}", f"diffuse = {float(be.CDIFF[k])!r}", ""]
    lines += ["[torques]", "drag = true", "srp = true", "", "[environment]", 'atmosphere = "exponential"',
              f'density0 = "{be.DENSITY0!r} kg/m3"', f'altitude0 = "{be.ALTITUDE0!r} m"',
              f'scale_height = "{be.SCALE_HEIGHT!r} m"', "corotation = false", 'shadow = "none"', "",
              "[initial]", 'frame = "inertial"', f"q = {_plain(be.Q0)}", f"omega = {_vec(be.OMEGA0, 'rad/s')}", "",
              "[potential]", 'kind = "gravity-gradient"', "", "[orbit]", 'provider = "kepler"',
              f'gm = "{be.GM!r} m3/s2"', f'a = "{be.A!r} m"', f"e = {be.ECC!r}", f'i = "{be.INC!r} rad"',
              f'raan = "{be.RAAN!r} rad"', f'argp = "{be.ARGP!r} rad"', f'true_anomaly = "{be.NU0!r} rad"',
              f'epoch = "{be.EPOCH}"', "", "[integration]", 'method = "dop853"', f"rtol = {rtol!r}",
              f"atol = {rtol * 1e-2!r}", f't_end = "{t_end!r} s"', f'output_step = "{OUT_STEP!r} s"']
    return "\n".join(lines) + "\n"


def orbatt_process(toml, folder, warm=False):
    """Wall and CPU times (s, :func:`_process`) of ``orbatt run`` on the scenario text ``toml``
    in a fresh process, the attitude it wrote ``(N, 4)`` and its ``integration_stats``. ``warm``: the discarded first
    run (``ORBATT_COLD_START=compile`` fills numba's cache, as ``benchmarks/startup.py``)."""
    import netCDF4

    path, out = Path(folder) / "case.toml", Path(folder) / "orbatt.nc"
    path.write_text(toml)
    env = child_env(**({"ORBATT_COLD_START": "compile"} if warm else {}))
    wall = _process([sys.executable, "-m", "orbatt.cli", "run", str(path), "-o", str(out), "--quiet"], env=env,
                    cwd=folder, stdout=subprocess.DEVNULL)
    with netCDF4.Dataset(out) as f:
        q = np.array(f.variables["q"][:], dtype=float)
        stats = json.loads(f.getncattr("integration_stats"))
    return wall, q * np.sign(q[:, :1]), stats


def _process(argv, **kw):
    """``(wall, cpu)`` seconds of one process: the wall time, and the child's user + system CPU
    time (what a quiet machine would show as wall time, roughly, for a one-thread process)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, **kw)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


# --- orbatt in-process
def orbatt_propagate(case, t_out, rtol):
    """``(q (N, 4), Trajectory.stats)`` of ``orbatt.propagate`` on ``case`` = ``(body, state0,
    potential)`` at ``rtol`` (atol ``rtol * 1e-2``)."""
    import orbatt

    body, state0, env = case
    traj = orbatt.propagate(body, state0, env, t_out, rtol=rtol, atol=rtol * 1e-2)
    q = np.asarray(traj.q)
    return q * np.sign(q[:, :1]), dict(traj.stats)


def orbatt_setup(t_out, rtol):
    """orbatt's set-up: the case built anew (``EnvironmentTorques``) and propagated over the
    first output interval only, which samples its tables over the day (the Sun, the orbit) and
    loads the kernels (warm): what precedes the integration of the day."""
    orbatt_propagate(be.orbatt_case(DAY, TERMS), t_out[:2], rtol)


# --- Basilisk
class SunTable:
    """Basilisk's Sun: the positions (m) at the midpoints of the ``SUN_EVERY`` s intervals,
    looked up by time (``basilisk_run`` asks at those midpoints)."""

    def __init__(self, positions):
        self.positions = np.asarray(positions, dtype=float)

    @classmethod
    def of(cls, sun, t_end):
        return cls(sun((np.arange(int(math.ceil(t_end / SUN_EVERY))) + 0.5) * SUN_EVERY))

    def __call__(self, t):
        return self.positions[min(int(t // SUN_EVERY), len(self.positions) - 1)]


def basilisk_in_process(t_out, dt, method, sun_table):
    """``(q (N, 4), {"setup": s, "execute": s})`` of Basilisk over ``t_out``."""
    timings = {}
    q, _ = be.basilisk_run(t_out, TERMS, dt, sun=sun_table, method=method, sun_every=SUN_EVERY, timings=timings)
    return q, timings


def basilisk_case(case):
    """Run one Basilisk case in this process (the ``--basilisk-case`` mode): ``case`` holds
    ``dt``, ``method``, ``t_end``, ``sun`` (a ``.npy`` of :class:`SunTable`'s positions) and
    ``out`` (the ``.npy`` the attitude at the 60 s outputs is saved to)."""
    t_out = np.arange(0.0, case["t_end"] + 0.5 * OUT_STEP, OUT_STEP)
    q, _ = be.basilisk_run(t_out, TERMS, case["dt"], sun=SunTable(np.load(case["sun"])), method=case["method"],
                           sun_every=SUN_EVERY)
    np.save(case["out"], q)


def basilisk_process(dt, method, folder, sun_table, t_end=DAY):
    """Wall and CPU times (s, :func:`_process`) of a fresh ``python basilisk_day.py
    --basilisk-case JSON`` (imports, set-up, execution, the attitude saved) and the attitude it
    saved."""
    sun_path, out = Path(folder) / "sun.npy", Path(folder) / "basilisk.npy"
    np.save(sun_path, sun_table.positions)
    case = json.dumps({"dt": dt, "method": method, "t_end": t_end, "sun": str(sun_path), "out": str(out)})
    wall = _process([sys.executable, __file__, "--basilisk-case", case], cwd=folder, env=child_env())
    return wall, np.load(out)


# --- accuracy
def errors(q, qref, spans, t_out):
    """The largest angle (rad) between ``q`` and ``qref`` over each span ``[0, s]`` of ``spans``
    (a dict name -> s), for the rows of ``q`` that ``t_out`` covers."""
    n = len(q)
    a = be._series(q, qref[:n])
    return {name: float(a[t_out[:n] <= s + 1e-9].max()) if s <= t_out[n - 1] + 1e-9 else float("nan")
            for name, s in spans.items()}


def references(t_out, t_classical):
    """The reference (orbatt at rtol 1e-14), the classical check over ``[0, t_classical]`` and
    the chaos: returns ``(qref, case, span, notes)``, ``span`` the certified span (s)."""
    case = be.orbatt_case(DAY, TERMS)
    qref, stats = orbatt_propagate(case, t_out, REF_RTOL)
    q13, _ = orbatt_propagate(case, t_out, 1e-13)
    notes = []
    w = time.perf_counter()
    n_c = int(np.searchsorted(t_out, t_classical + 1e-9))
    qc = be.classical_run(t_out[:n_c], TERMS, sun=be.sun_spline(float(t_out[n_c - 1])), rtol=1e-13)
    w = time.perf_counter() - w
    a = be._series(qc, qref[:n_c])
    over = np.nonzero(np.maximum.accumulate(a) > AGREE)[0]
    span = float(t_out[over[0] - 1]) if len(over) else float(t_out[n_c - 1])
    hours = list(range(0, int(t_out[n_c - 1] // 3600) + 1, 2))
    per_h = ", ".join(f"{h} h {a[int(h * 3600 / OUT_STEP)]:.1e}" for h in hours)
    notes.append(f"reference: orbatt dop853 rtol {REF_RTOL:g} ({stats['steps']} steps, {stats['rejected_steps']} "
                 f"rejected); classical DOP853 rtol 1e-13 over {t_out[n_c - 1]:.0f} s ({w:.0f} s) against it: {per_h}")
    b = be._series(q13, qref)
    notes.append("orbatt rtol 1e-13 against it: " + ", ".join(
        f"{h} h {b[int(h * 3600 / OUT_STEP)]:.1e}" for h in range(0, 25, 4)))
    import orbatt
    from astropy import units as u

    body, _, env = case
    moved = orbatt.State.from_omega(body, be.Q0, be.OMEGA0 * (1 + 1e-12) * u.rad / u.s)
    qp = np.asarray(orbatt.propagate(body, moved, env, t_out, rtol=REF_RTOL, atol=REF_RTOL * 1e-2).q)
    c = be._series(qp * np.sign(qp[:, :1]), qref)
    notes.append("chaos: the initial rate times (1 + 1e-12), same rtol, against the reference: " + ", ".join(
        f"{h} h {c[int(h * 3600 / OUT_STEP)]:.1e}" for h in range(0, 25, 4)))
    notes.append(f"certified span: {span:.0f} s ({span / 3600:.1f} h), the references within {AGREE:g} rad")
    return qref, case, span, notes


def search_orbatt(case, t_out, qref, spans):
    """Every rtol of :data:`RTOLS` over the day: ``[(rtol, errors dict, stats)]``."""
    rows = []
    for rtol in RTOLS:
        try:
            q, stats = orbatt_propagate(case, t_out, rtol)
        except Exception as exc:   # a grid point may fail: record it, go on
            print(f"orbatt rtol {rtol:.1e} failed: {exc}")
            continue
        rows.append((rtol, errors(q, qref, spans, t_out), stats))
    return rows


def search_basilisk(t_span, qref, spans, sun_table):
    """Basilisk over ``t_span`` (the outputs up to the certified span) for each method and task
    step of :data:`DTS`, the steps decreasing until the error over every span meets 1e-3 rad:
    ``[(method, dt, errors dict, execute s)]``."""
    rows = []
    for method, dts in DTS.items():
        for dt in dts:
            q, timings = basilisk_in_process(t_span, dt, method, sun_table)
            err = errors(q, qref, spans, t_span)
            rows.append((method, dt, err, timings["execute"]))
            if all(not e > TARGETS[0] for e in err.values()):
                break
    return rows


def median_time(fn, repeats):
    return statistics.median(fn() for _ in range(repeats))


def _fmt(x, spec=".2g"):
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="one repeat, the classical check over 6 h")
    ap.add_argument("--repeats", type=int, default=3, help="timed repeats of each row (median)")
    ap.add_argument("--basilisk-case", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.basilisk_case:   # one Basilisk case in this fresh interpreter (timed by the parent)
        basilisk_case(json.loads(args.basilisk_case))
        return 0
    repeats = 1 if args.quick else args.repeats
    try:
        import Basilisk  # noqa: F401
        basilisk = True
    except ImportError:
        basilisk = False
        print("Basilisk is not installed (pip install bsk): its rows are skipped")
    t_out = np.arange(0.0, DAY + 0.5 * OUT_STEP, OUT_STEP)
    sun = be.sun_spline(DAY)
    print(f"3U CubeSat (benchmarks/basilisk_environment.py's case), gravity gradient + facet drag + facet SRP, "
          f"{DAY:.0f} s from {be.EPOCH}; smallest conical shadow function: {be.check_sunlight(t_out, sun):.3f}; "
          f"{os.cpu_count()} CPUs, load average at start {os.getloadavg()[0]:.1f}")
    qref, case, span, notes = references(t_out, 6 * 3600.0 if args.quick else DAY)
    print("\n".join(f"- {n}" for n in notes))
    spans = {"orbit": 5580.0, "certified": span, "day": DAY}
    grid = search_orbatt(case, t_out, qref, spans)
    sun_table = SunTable.of(sun, DAY)
    t_span = t_out[t_out <= span + 1e-9]
    bsk = search_basilisk(t_span, qref, spans, sun_table) if basilisk else []
    if bsk:
        t_orbit = t_out[t_out <= spans["orbit"]]
        q_each, _ = be.basilisk_run(t_orbit, TERMS, 2.0, sun=sun, method="rk4")
        q_held, _ = basilisk_in_process(t_orbit, 2.0, "rk4", sun_table)
        print(f"- Basilisk's Sun message every {SUN_EVERY:g} s against every task step (RK4, 2 s, one orbit): "
              f"{be._angle(q_each, q_held):.1g} rad apart")
        print(f"\nBasilisk's search over the certified span ({span:.0f} s), largest angle to the reference:\n")
        print("| integrator | task step (s) | over one orbit (rad) | over the certified span (rad) | "
              "ExecuteSimulation over the span (s) |\n|---|---|---|---|---|")
        for method, dt, err, wall in bsk:
            print(f"| {method.upper()} | {dt:g} | {err['orbit']:.2g} | {err['certified']:.2g} | {wall:.2f} |")

    picks = []   # (target, span name, orbatt grid row or None, [Basilisk rows], Basilisk best row)
    for target in TARGETS:
        for name in ("orbit", "certified"):
            mine = next((r for r in grid if r[1][name] <= target), None)
            theirs = [max((r for r in bsk if r[0] == m and r[2][name] <= target), key=lambda r: r[1], default=None)
                      for m in DTS]   # each integrator's largest task step meeting the target
            best = min(bsk, key=lambda r: r[2][name]) if bsk else None
            picks.append((target, name, mine, [r for r in theirs if r is not None], best))

    # times over the day
    import orbatt  # noqa: F401  (the kernels warm before timing)

    inproc, setup, proc, cpu, share, same = {}, {}, {}, {}, {}, {}
    rtols = sorted({p[2][0] for p in picks if p[2] is not None}, reverse=True)
    with tempfile.TemporaryDirectory() as tmp:
        if rtols:
            orbatt_process(scenario_toml(rtols[0]), tmp, warm=True)
        for rtol in rtols:
            orbatt_propagate(case, t_out, rtol)
            # milliseconds: more repeats, so that a preemption on a loaded machine does not set the median
            inproc[rtol] = median_time(lambda: _timed(orbatt_propagate, case, t_out, rtol), max(repeats, 21))
            setup[rtol] = median_time(lambda: _timed(orbatt_setup, t_out, rtol), max(repeats, 21))
            runs = [orbatt_process(scenario_toml(rtol), tmp) for _ in range(repeats)]
            proc[rtol] = statistics.median(r[0][0] for r in runs)
            cpu[rtol] = statistics.median(r[0][1] for r in runs)
            share[rtol] = statistics.median(r[2]["wall_time_s"] / r[0][0] for r in runs)
            same[rtol] = be._angle(runs[0][1], orbatt_propagate(case, t_out, rtol)[0])
        rows_b = {(r[0], r[1]) for p in picks for r in p[3]}
        for method, dt in sorted(rows_b):
            runs = [basilisk_in_process(t_out, dt, method, sun_table) for _ in range(repeats)]
            inproc[method, dt] = statistics.median(r[1]["execute"] for r in runs)
            setup[method, dt] = statistics.median(r[1]["setup"] for r in runs)
            basilisk_process(dt, method, tmp, sun_table)   # discarded: file caches warm, as orbatt's
            pruns = [basilisk_process(dt, method, tmp, sun_table) for _ in range(repeats)]
            proc[method, dt] = statistics.median(r[0][0] for r in pruns)
            cpu[method, dt] = statistics.median(r[0][1] for r in pruns)
            same[method, dt] = be._angle(pruns[0][1], runs[0][0])
            share[method, dt] = inproc[method, dt] / proc[method, dt]
            same[method, dt, "day"] = be._angle(runs[0][0], qref)
        imports = {name: median_time(lambda: _process([sys.executable, "-c", code],
                                                        env=child_env())[0], repeats)
                   for name, code in IMPORTS.items() if basilisk or name == "orbatt"}

    print(f"\n### The day ({DAY:.0f} s): times (median of {repeats}) and ratios (Basilisk's fastest row reaching "
          f"the target over the span / the row)\n")
    print("| target (rad) | over | model | setting | error over the span (rad) | error over the day (rad) | "
          "steps (rejected) | RHS evaluations | set-up (s) | in-process (s) | ratio | whole process (s) | ratio | "
          "its CPU (s) | ratio | integration share of the process |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for target, name, mine, theirs, best in picks:
        over = "one orbit" if name == "orbit" else f"{span / 3600:.1f} h"
        keys = [(r[0], r[1]) for r in theirs]
        b_in = min((inproc[k] for k in keys), default=None)
        b_pr = min((proc[k] for k in keys), default=None)
        b_cpu = min((cpu[k] for k in keys), default=None)
        if mine is None:
            print(f"| {target:g} | {over} | orbatt | no rtol of the grid reaches it |" + " |" * 12)
        else:
            rtol, err, st = mine
            print(f"| {target:g} | {over} | **orbatt** | dop853 rtol {rtol:.1e} | {err[name]:.2g} | {err['day']:.2g} | "
                  f"{st['steps']} ({st['rejected_steps']}) | {st['rhs_evaluations']} | {setup[rtol]:.3f} | "
                  f"{inproc[rtol]:.4f} | {_fmt(b_in and b_in / inproc[rtol], '.0f')} | {proc[rtol]:.2f} | "
                  f"{_fmt(b_pr and b_pr / proc[rtol], '.1f')} | {cpu[rtol]:.2f} | "
                  f"{_fmt(b_cpu and b_cpu / cpu[rtol], '.1f')} | {share[rtol]:.0%} |")
        for method, dt, err, _ in theirs:
            key = (method, dt)
            print(f"| {target:g} | {over} | Basilisk | {method.upper()} task step {dt:g} s | {err[name]:.2g} | "
                  f"{same[method, dt, 'day']:.2g} | {int(round(DAY / dt))} | {int(round(DAY / dt)) * STAGES[method]} | "
                  f"{setup[key]:.3f} | {inproc[key]:.2f} | {b_in / inproc[key]:.2f} | {proc[key]:.2f} | "
                  f"{b_pr / proc[key]:.2f} | {cpu[key]:.2f} | {b_cpu / cpu[key]:.2f} | {share[key]:.0%} |")
        if not theirs and best is not None:
            method, dt, err, _ = best
            print(f"| {target:g} | {over} | Basilisk | cannot reach it: best of the search {method.upper()} "
                  f"{dt:g} s | {err[name]:.2g} |" + " |" * 11)
    print("\n- orbatt run's file against orbatt.propagate at the same rtol (largest angle): "
          + ", ".join(f"rtol {r:.1e} {same[r]:.1g}" for r in rtols))
    if rows_b:
        print("- the Basilisk process's attitude against the in-process run: "
              + ", ".join(f"{m.upper()} {dt:g} s {same[m, dt]:.1g}" for m, dt in sorted(rows_b)))
    print("- a fresh python that only imports: " + ", ".join(f"{k} {v:.2f} s" for k, v in imports.items()))
    print("- ratio: Basilisk's fastest row meeting the target (in-process: ExecuteSimulation; whole processes) over "
          "the row's time; integration share: the compiled loop's wall_time_s (orbatt) or ExecuteSimulation "
          "(Basilisk) over the whole process")
    print(f"- load average at the end {os.getloadavg()[0]:.1f}")
    return 0


def _timed(fn, *a, **kw):
    t0 = time.perf_counter()
    fn(*a, **kw)
    return time.perf_counter() - t0


if __name__ == "__main__":
    sys.exit(main())

"""Monte Carlo at study scale (issue 35 item 1): a one-day Monte Carlo of a 6U against its
single run, whole processes, ratios against baselines measured in the same run.

    python benchmarks/study_scale.py            # about 6-10 minutes on 2 idle cores
    python benchmarks/study_scale.py --quick    # no cluster rows, no 1,000-case run (~3 min)
    python benchmarks/study_scale.py --full     # also the 1,000 cases, measured (+3-6 min)

The study: a 6U CubeSat (12 kg, inertia 0.185/0.144/0.061 kg m2, six facets) on a
sun-synchronous orbit given as a TLE (97.59 deg, 15.18 rev/day: ~550 km), holding the orbital
frame with a PD law on three reaction wheels, under the gravity gradient, NRLMSIS drag
(co-rotating), SRP (conical shadow) and a residual dipole in IGRF, for one day (output every
60 s), DOP853 at rtol = atol = 1e-10. The Monte Carlo varies the three principal moments by
path (``body.inertia[k]``, 2 %), the three initial rates (+-0.5 deg/s) and ``control.kd``
(+-20 %): every case is its own model (its own kd), so nothing but the environment is shared.

Rows (each a fresh ``orbatt`` process, the numba cache warm: a first run of each command,
untimed, compiles what it needs):

* **single run**: ``orbatt run SIXU.toml -o one.nc --quiet``: the baseline (1x);
* **16 cases, default**: ``orbatt sweep MC16.toml -o mc.nc --quiet``: the scheduler chosen by
  the work (printed: in-process, or a local cluster);
* **16 cases, synchronous** and **16 cases, local cluster** (``--workers 2``), for the choice;
* **N cases, default** (``--cases``, 96 by default): the time per case at scale, and the
  projection of 1,000 cases in one process: ``T(16) + 984 x (C(N) - C(16)) / (N - 16)``, the
  marginal cost of a case from the CPU times ``C`` of the two sizes (the wall times' difference
  drowns in the noise of a shared machine), the set-up counted once; a cluster would divide
  the 984 cases' part by up to the number of cores;
* with ``--full``: **1,000 cases, default**, measured.

Then where the time goes (in-process, this process): loading the scenario (the TLE's SGP4
samples), the environment tables (density, Sun, field: sampled once), a case's integration
(the compiled loop: ``integration_stats`` ``wall_time_s``) and the rest of a case (parsing its
scenario, building its potential and model, its outputs).

Timings on the shared 2-core sandbox are noisy (other jobs run beside): the ratios are
measured in one run and each row prints its CPU time (user + system of the process and its
children) beside the wall time.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

warnings.simplefilter("ignore")

TLE = ["SIXU-SSO", "1 99999U 25001A   25244.50000000  .00000800  00000-0  40000-4 0  9991",
       "2 99999  97.5900  10.0000 0010000  90.0000 270.0000 15.18000000000002"]


def _facet(area, normal, position, specular, diffuse):
    return (f'[[body.facets]]\narea = "{area} m2"\nnormal = {normal}\nposition = ["{position[0]} m", '
            f'"{position[1]} m", "{position[2]} m"]\ndrag_coefficient = 2.2\nspecular = {specular}\n'
            f'diffuse = {diffuse}\n')


def _wheel(axis):
    return (f'[[body.wheels]]\naxis = {axis}\ninertia = "2e-5 kg m2"\nspeed = "0 rpm"\nmax_torque = "2e-3 N m"\n'
            'max_speed = "6000 rpm"\n')


def sixu_text():
    """The single run's scenario (TOML)."""
    facets = "\n".join([
        _facet(0.083, [1.0, 0.0, 0.0], (0.05, 0, 0.01), 0.1, 0.3),
        _facet(0.083, [-1.0, 0.0, 0.0], (-0.05, 0, 0.01), 0.1, 0.3),
        _facet(0.037, [0.0, 1.0, 0.0], (0, 0.113, 0.01), 0.1, 0.3),
        _facet(0.037, [0.0, -1.0, 0.0], (0, -0.113, 0.01), 0.1, 0.3),
        _facet(0.023, [0.0, 0.0, 1.0], (0, 0, 0.183), 0.0, 0.2),
        _facet(0.023, [0.0, 0.0, -1.0], (0, 0, -0.17), 0.0, 0.2)])
    wheels = "\n".join(_wheel(a) for a in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]))
    tle = ",\n".join(f'  "{line}"' for line in TLE)
    return f'''name = "sixu-sso-day"
description = "A 6U on a sun-synchronous TLE orbit holding LVLH with PD on three wheels; drag, SRP, dipole; one day."

[body]
inertia = ["0.185 kg m2", "0.144 kg m2", "0.061 kg m2"]

{facets}
{wheels}
[control]
law = "pd"
target = "orbital"
kp = "4e-4 N m"
kd = "1e-2 N m s"
max_torque = "2e-3 N m"
actuator = "wheels"

[torques]
drag = true
srp = true
residual_dipole = ["0.01 A m2", "0.005 A m2", "0.01 A m2"]

[environment]
atmosphere = "nrlmsis"
f107 = 150
f107a = 150
ap = 4
magnetic_field = "igrf"

[initial]
frame = "orbital"
q = [0.9961946980917455, 0.08715574274765817, 0.0, 0.0]
omega = ["0.5 deg/s", "-0.3 deg/s", "0.2 deg/s"]

[potential]
kind = "gravity-gradient"

[orbit]
provider = "tle"
tle = [
{tle},
]

[integration]
method = "dop853"
rtol = 1e-10
atol = 1e-10
t_end = "86400 s"
output_step = "60 s"
'''


def sweep_text(samples):
    """The Monte Carlo: inertia by path, initial rates, control.kd."""
    return sixu_text() + f'''
[sweep]
samples = {samples}
seed = 35
outputs = ["final_state", "pointing_error", "max_wheel_speed", "max_control_torque"]

[sweep.parameters]
"body.inertia[0]" = {{ distribution = "normal", std = "0.0037 kg m2" }}
"body.inertia[1]" = {{ distribution = "normal", std = "0.0029 kg m2" }}
"body.inertia[2]" = {{ distribution = "normal", std = "0.0012 kg m2" }}
"initial.omega[0]" = {{ distribution = "uniform", low = "-0.5 deg/s", high = "0.5 deg/s" }}
"initial.omega[1]" = {{ distribution = "uniform", low = "-0.5 deg/s", high = "0.5 deg/s" }}
"initial.omega[2]" = {{ distribution = "uniform", low = "-0.5 deg/s", high = "0.5 deg/s" }}
"control.kd" = {{ distribution = "uniform", low = "0.8e-2 N m s", high = "1.2e-2 N m s" }}
'''


def _cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(args, cwd):
    """``(wall s, cpu s, sweep_run or None)`` of one ``orbatt`` process."""
    c0, t0 = _cpu(), time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], cwd=cwd, capture_output=True,
                       text=True)
    wall, cpu = time.perf_counter() - t0, _cpu() - c0
    if r.returncode:
        raise SystemExit(f"orbatt {' '.join(map(str, args))} failed:\n{r.stderr[-3000:]}")
    run = None
    if args[0] == "sweep":
        import xarray as xr

        with xr.open_dataset(Path(cwd) / args[args.index("-o") + 1]) as ds:
            run = json.loads(ds.attrs["sweep_run"])
            run["integration_wall_s"] = json.loads(ds.attrs["integration_stats"]).get("wall_time_s")
        os.remove(Path(cwd) / args[args.index("-o") + 1])
    return wall, cpu, run


def breakdown(folder):
    """Where the time goes, in this process: load, environment tables, per case."""
    import orbatt.torques as torques
    from orbatt.sweep import load_sweep
    from orbatt.sweep.case_groups import clear_environments

    spent = {"tables": 0.0}
    original = torques.tabulate_along_orbit

    def counted(*a, **k):
        t0 = time.perf_counter()
        try:
            return original(*a, **k)
        finally:
            spent["tables"] += time.perf_counter() - t0

    t0 = time.perf_counter()
    sw = load_sweep(folder / "mc16.toml")
    load_s = time.perf_counter() - t0
    sw.compute(0, 1)  # the kernels loaded, the xarray imports done
    clear_environments()
    sw = load_sweep(folder / "mc16.toml")
    torques.tabulate_along_orbit = counted
    try:
        t0 = time.perf_counter()
        ds = sw.compute()
        total = time.perf_counter() - t0
    finally:
        torques.tabulate_along_orbit = original
    integ = json.loads(ds.attrs["integration_stats"])["wall_time_s"]
    n = sw.cases
    return {"load_s": load_s, "tables_s": spent["tables"], "total_s": total, "integration_s": integ,
            "rest_per_case_s": (total - spent["tables"] - integ) / n, "integration_per_case_s": integ / n, "n": n}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="no cluster rows, no N-case row")
    ap.add_argument("--full", action="store_true", help="also measure 1,000 cases")
    ap.add_argument("--cases", type=int, default=96, help="the N of the scale row (default 96)")
    args = ap.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="orbatt-study-scale-"))
    (folder / "sixu.toml").write_text(sixu_text())
    (folder / "mc16.toml").write_text(sweep_text(16))
    (folder / f"mc{args.cases}.toml").write_text(sweep_text(args.cases))
    (folder / "mc1000.toml").write_text(sweep_text(1000))
    print(f"cores: {os.cpu_count()}; load average {os.getloadavg()[0]:.2f} (timings are noisy when other jobs run)")
    env = dict(os.environ, ORBATT_COLD_START="compile")
    os.environ.update(env)
    # warm-ups, untimed: the kernels of the single run and of the sweep compiled into the cache
    timed(["run", "sixu.toml", "-o", "one.nc", "--quiet"], folder)
    timed(["sweep", "mc16.toml", "-o", "warm.nc", "--quiet", "--scheduler", "synchronous", "--chunk-size", "2"],
          folder)
    rows = []
    one = min(timed(["run", "sixu.toml", "-o", "one.nc", "--quiet"], folder)[:2] for _ in range(2))
    rows.append(("single run (whole process)", 1, one[0], one[1], None))
    for label, extra, quick in (("16 cases, default (auto)", [], True),
                                ("16 cases, --scheduler synchronous", ["--scheduler", "synchronous"], True),
                                ("16 cases, --workers 2 (local cluster)", ["--workers", "2"], False)):
        if args.quick and not quick:
            continue
        w, c, run = timed(["sweep", "mc16.toml", "-o", "mc.nc", "--quiet", *extra], folder)
        rows.append((label, 16, w, c, run))
    scale = []
    if not args.quick:
        n = args.cases
        w, c, run = timed(["sweep", f"mc{n}.toml", "-o", "mc.nc", "--quiet"], folder)
        rows.append((f"{n} cases, default (auto)", n, w, c, run))
        scale.append((n, w, c))
    if args.full:
        w, c, run = timed(["sweep", "mc1000.toml", "-o", "mc.nc", "--quiet"], folder)
        rows.append(("1000 cases, default (auto)", 1000, w, c, run))
    print(f"\n{'row':40s} {'cases':>5s} {'wall s':>8s} {'cpu s':>8s} {'vs single':>9s}  scheduler (choice)")
    for label, n, w, c, run in rows:
        where = "" if run is None else f"{run['scheduler']}, {run['workers']} w ({run.get('scheduler_choice', '')})"
        print(f"{label:40s} {n:5d} {w:8.1f} {c:8.1f} {w / one[0]:8.2f}x  {where}")
    t16 = rows[1][2]
    print(f"\ngoal: 16 cases within 4x the single run's whole process: {t16 / one[0]:.2f}x "
          f"({'met' if t16 <= 4 * one[0] else 'missed'})")
    if scale:
        n, tn, cn = scale[0]
        marginal = (cn - rows[1][3]) / (n - 16)
        proj = t16 + (1000 - 16) * marginal
        print(f"1,000 cases projected in one process from 16 and {n}: {marginal:.3f} CPU s per case beyond the "
              f"set-up -> {proj:.0f} s ({proj / 60:.1f} min; goal 5 min: {'met' if proj <= 300 else 'missed'})")
    if args.full:
        t1000 = rows[-1][2]
        print(f"1,000 cases measured: {t1000:.0f} s ({t1000 / 60:.1f} min; goal 5 min: "
              f"{'met' if t1000 <= 300 else 'missed'})")
    b = breakdown(folder)
    print(f"\nwhere the time goes (in-process, {b['n']} cases, this process): loading the scenario (SGP4) "
          f"{b['load_s']:.2f} s; the environment tables (once) {b['tables_s']:.2f} s; a case: integration "
          f"{b['integration_per_case_s']:.3f} s + the rest {b['rest_per_case_s']:.3f} s "
          f"(its scenario parsed, its potential and model built, its outputs)")


if __name__ == "__main__":
    main()

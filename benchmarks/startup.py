"""Start-up benchmark of ``orbatt run`` (issue 25, item 3): the wall time of a warm run.

    python benchmarks/startup.py                       # this tree, 7 runs of each
    python benchmarks/startup.py --baseline /work/main --repeats 9

For each scenario, ``orbatt run SCENARIO -o TMP --quiet`` in a fresh process (``python -m
orbatt.cli``), warm: one run first with ``ORBATT_COLD_START=compile`` fills numba's cache and the
Earth-orientation cache, then the median (and min, max) wall time of ``--repeats`` runs, each a
new process; and the import of ``orbatt.cli`` alone. The last column is the integration's share
of the wall time: the file's ``integration_stats`` ``wall_time_s`` (the compiled loop) over the
process's wall time, median over the runs. The trivial run (``paper-torque-free``, :data:`TRIVIAL`)
is timed too: its absolute wall time, each scenario's ratio to it (issue 34 item 6: the disturbed
day and the B-dot detumble <= 1.5x the trivial run; the trivial run itself <= 1 s), and its
breakdown, from a probe process (:data:`PHASES`) that does what ``orbatt run`` does with a clock
between the steps: interpreter start (``python -c pass``), imports (``orbatt.cli``, the Dataset
and scenario packages, numba), set-up (scenario read and checked, output path checked),
integration (``propagate``: the compiled loop and numba's load of the cached kernels), Dataset
(the result's content: derived variables), write (the NetCDF file), after (the warm stamp).
With ``--baseline TREE`` the same
commands run, interleaved run by run, with ``TREE``'s ``orbatt`` package first on
``PYTHONPATH`` (another checkout, e.g. ``main``), and the table shows the ratio. Interleaving
keeps the two columns comparable on a loaded machine; compare medians, not single runs.

Goals of issue 25 (on the issue's machine class): cubesat-3u-disturbances <= 1.5 s,
cubesat-bdot-detumble and lvlh-hold-wheels <= 1 s.
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ("cubesat-3u-disturbances", "cubesat-bdot-detumble", "lvlh-hold-wheels")
#: the trivial run every other is compared with (and whose time is broken down)
TRIVIAL = "paper-torque-free"
#: the breakdown probe: ``orbatt run``'s steps (orbatt/cli.py ``_run``) with a clock between them
PHASES = """
import json, sys, time
t0 = time.perf_counter()
scenario, out = sys.argv[1], sys.argv[2]
from orbatt import cli, coldstart
from orbatt.dataset import write_netcdf
from orbatt.scenario import load_scenario
import orbatt.scenario.load as load
import numba
t1 = time.perf_counter()
warm = coldstart.plan(scenario) is None
sc = load_scenario(scenario)
cli._output_path(type("Args", (), {"output": out})(), sc)
t2 = time.perf_counter()
spent = []
propagate = load.propagate
def timed(*a, **k):
    s = time.perf_counter()
    try:
        return propagate(*a, **k)
    finally:
        spent.append(time.perf_counter() - s)
load.propagate = timed
content = sc.run_content()
t3 = time.perf_counter()
write_netcdf(content, out)
t4 = time.perf_counter()
coldstart.mark_warm(scenario)
t5 = time.perf_counter()
print(json.dumps({"warm": warm, "import": t1 - t0, "set-up": t2 - t1, "integration": spent[0],
                  "Dataset": t3 - t2 - spent[0], "write": t4 - t3, "after": t5 - t4}))
"""
PHASE_NAMES = ("interpreter", "import", "set-up", "integration", "Dataset", "write", "after")


def tree_env(tree, baseline):
    """The environment of a process running ``tree``'s package: its folder first on
    ``PYTHONPATH``, and for the baseline a compile cache of its own (``$NUMBA_CACHE_DIR-baseline``;
    without ``NUMBA_CACHE_DIR`` each tree's ``orbatt/core/__pycache__``): the warm stamps of
    :mod:`orbatt.coldstart` live there and carry the sources' fingerprint, so two trees sharing
    one folder would overwrite each other's stamps and every run would start cold (interpreted,
    with a warm-up behind it)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    if baseline and env.get("NUMBA_CACHE_DIR"):
        env["NUMBA_CACHE_DIR"] = env["NUMBA_CACHE_DIR"].rstrip("/") + "-baseline"
    return env


def command(tree, scenario, out, baseline=False):
    """The argv and environment of one ``orbatt run`` of ``tree``'s package."""
    env = tree_env(tree, baseline)
    argv = [sys.executable, "-m", "orbatt.cli", "run", str(ROOT / "scenarios" / f"{scenario}.toml"), "-o", out,
            "--quiet"]
    return argv, env


def wall(argv, env, cwd):
    """Wall and CPU (user + system, the child's) seconds of one process."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(argv, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL)
    w = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return w, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def integration_time(path):
    """``wall_time_s`` of the file's ``integration_stats`` (the compiled loop's time)."""
    import json

    import netCDF4

    with netCDF4.Dataset(path) as f:
        return float(json.loads(f.getncattr("integration_stats"))["wall_time_s"])


def phases(tree, out, cwd, baseline=False):
    """The trivial run's breakdown (s): :data:`PHASES` in a fresh process, and the interpreter's
    own start (``python -c pass``) beside it."""
    import json

    env = tree_env(tree, baseline)
    w, _ = wall([sys.executable, "-c", "pass"], env, cwd)
    r = subprocess.run([sys.executable, "-c", PHASES, str(ROOT / "scenarios" / f"{TRIVIAL}.toml"), out], env=env,
                       cwd=cwd, check=True, capture_output=True, text=True)
    d = json.loads(r.stdout.strip().splitlines()[-1])
    if not d.pop("warm"):
        raise SystemExit(f"{TRIVIAL}: no warm stamp; the breakdown would time an interpreted run")
    return {"interpreter": w, **d}


def import_argv(tree, baseline=False):
    return [sys.executable, "-c", "import orbatt.cli"], tree_env(tree, baseline)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--baseline", help="another checkout whose orbatt/ to time beside this one")
    ap.add_argument("--scenarios", nargs="*", default=list(SCENARIOS))
    ap.add_argument("--cwd", help="the folder the processes run in (default: a temporary folder; give a clone's "
                                  "root to time what a user there sees)")
    args = ap.parse_args()
    args.scenarios = [TRIVIAL, *[s for s in args.scenarios if s != TRIVIAL]]
    trees = {"this": ROOT}
    if args.baseline:
        trees["baseline"] = Path(args.baseline).resolve()
    times = {(name, s): [] for name in trees for s in [*args.scenarios, "import orbatt.cli"]}
    cpu = {key: [] for key in times}
    share = {s: [] for s in args.scenarios}
    parts = {name: {p: [] for p in PHASE_NAMES} for name in trees}
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "x.nc")
        cwd = args.cwd or tmp
        for s in args.scenarios:            # warm: compiled kernels cached, stamps written
            for name, tree in trees.items():
                argv, env = command(tree, s, out, name == "baseline")
                for first in (True, False):  # compiled and stamped, then one plain warm run
                    subprocess.run(argv, env={**env, "ORBATT_COLD_START": "compile"} if first else env, cwd=cwd,
                                   check=True, stdout=subprocess.DEVNULL)
        for _ in range(args.repeats):
            for s in [*args.scenarios, "import orbatt.cli"]:
                for name, tree in trees.items():
                    base = name == "baseline"
                    argv, env = import_argv(tree, base) if s.startswith("import") else command(tree, s, out, base)
                    w, c = wall(argv, env, cwd)
                    times[name, s].append(w)
                    cpu[name, s].append(c)
                    if name == "this" and not s.startswith("import"):
                        share[s].append(integration_time(out) / times[name, s][-1])
            for name, tree in trees.items():
                for p, v in phases(tree, out, cwd, name == "baseline").items():
                    parts[name][p].append(v)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    for what, table in (("wall time", times), ("CPU time (user + system)", cpu)):
        print(f"orbatt run, warm, {what} of a fresh process (s): median [min, max] of {args.repeats}; "
              f"{os.cpu_count()} CPUs, load average {load:.1f}")
        head = (f"{'':28s}" + "".join(f"{name:>26s}" for name in trees)
                + ("   this / baseline" if len(trees) > 1 else "") + ("   integration share (this)" if table is times else ""))
        print(head)
        for s in [*args.scenarios, "import orbatt.cli"]:
            row = f"{s:28s}"
            med = {}
            for name in trees:
                v = table[name, s]
                med[name] = statistics.median(v)
                row += f"{med[name]:12.2f} [{min(v):5.2f}, {max(v):5.2f}]"
            if len(trees) > 1:
                row += f"   {med['this'] / med['baseline']:15.2f}"
            if s in share and table is times:
                row += f"   {statistics.median(share[s]):20.0%}"
            print(row)
        print()
    print(f"ratio to the trivial run ({TRIVIAL}), median wall times (goal of issue 34: <= 1.5x; the trivial run "
          "itself <= 1 s)")
    for s in args.scenarios[1:]:
        print(f"{s:28s}" + "".join(f"{statistics.median(times[name, s]) / statistics.median(times[name, TRIVIAL]):26.2f}"
                                   for name in trees))
    print()
    print(f"{TRIVIAL}: where the time goes (s, median of {args.repeats} probe processes; on a loaded machine "
          "the wall time above exceeds their sum: compare with the CPU time)")
    print(f"{'':28s}" + "".join(f"{name:>26s}" for name in trees))
    for p in PHASE_NAMES:
        print(f"{p:28s}" + "".join(f"{statistics.median(parts[name][p]):26.3f}" for name in trees))
    print(f"{'sum':28s}" + "".join(f"{sum(statistics.median(parts[name][p]) for p in PHASE_NAMES):26.3f}"
                                   for name in trees))
    for what, table in (("wall time (orbatt run)", times), ("CPU time (orbatt run)", cpu)):
        print(f"{what:28s}" + "".join(f"{statistics.median(table[name, TRIVIAL]):26.3f}" for name in trees))


if __name__ == "__main__":
    main()

"""Start-up benchmark of ``orbatt run`` (issue 25, item 3): the wall time of a warm run.

    python benchmarks/startup.py                       # this tree, 7 runs of each
    python benchmarks/startup.py --baseline /work/main --repeats 9

For each scenario, ``orbatt run SCENARIO -o TMP --quiet`` in a fresh process (``python -m
orbatt.cli``), warm: one run first with ``ORBATT_COLD_START=compile`` fills numba's cache and the
Earth-orientation cache, then the median (and min, max) wall time of ``--repeats`` runs, each a
new process; and the import of ``orbatt.cli`` alone. The last column is the integration's share
of the wall time: the file's ``integration_stats`` ``wall_time_s`` (the compiled loop) over the
process's wall time, median over the runs. With ``--baseline TREE`` the same
commands run, interleaved run by run, with ``TREE``'s ``orbatt`` package first on
``PYTHONPATH`` (another checkout, e.g. ``main``), and the table shows the ratio. Interleaving
keeps the two columns comparable on a loaded machine; compare medians, not single runs.

Goals of issue 25 (on the issue's machine class): cubesat-3u-disturbances <= 1.5 s,
cubesat-bdot-detumble and lvlh-hold-wheels <= 1 s.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ("cubesat-3u-disturbances", "cubesat-bdot-detumble", "lvlh-hold-wheels")


def command(tree, scenario, out):
    """The argv and environment of one ``orbatt run`` of ``tree``'s package (None: installed)."""
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    argv = [sys.executable, "-m", "orbatt.cli", "run", str(ROOT / "scenarios" / f"{scenario}.toml"), "-o", out,
            "--quiet"]
    return argv, env


def wall(argv, env, cwd):
    t0 = time.perf_counter()
    subprocess.run(argv, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def integration_time(path):
    """``wall_time_s`` of the file's ``integration_stats`` (the compiled loop's time)."""
    import json

    import netCDF4

    with netCDF4.Dataset(path) as f:
        return float(json.loads(f.getncattr("integration_stats"))["wall_time_s"])


def import_argv(tree):
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    return [sys.executable, "-c", "import orbatt.cli"], env


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--baseline", help="another checkout whose orbatt/ to time beside this one")
    ap.add_argument("--scenarios", nargs="*", default=list(SCENARIOS))
    args = ap.parse_args()
    trees = {"this": ROOT}
    if args.baseline:
        trees["baseline"] = Path(args.baseline).resolve()
    times = {(name, s): [] for name in trees for s in [*args.scenarios, "import orbatt.cli"]}
    share = {s: [] for s in args.scenarios}
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "x.nc")
        for s in args.scenarios:            # warm: compiled kernels cached, stamps written
            for tree in trees.values():
                argv, env = command(tree, s, out)
                subprocess.run(argv, env={**env, "ORBATT_COLD_START": "compile"}, cwd=tmp, check=True,
                               stdout=subprocess.DEVNULL)
        for _ in range(args.repeats):
            for s in [*args.scenarios, "import orbatt.cli"]:
                for name, tree in trees.items():
                    argv, env = import_argv(tree) if s.startswith("import") else command(tree, s, out)
                    times[name, s].append(wall(argv, env, tmp))
                    if name == "this" and not s.startswith("import"):
                        share[s].append(integration_time(out) / times[name, s][-1])
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"orbatt run, warm, wall time of a fresh process (s): median [min, max] of {args.repeats}; "
          f"{os.cpu_count()} CPUs, load average {load:.1f}")
    head = (f"{'':28s}" + "".join(f"{name:>26s}" for name in trees) + ("   this / baseline" if len(trees) > 1 else "")
            + "   integration share (this)")
    print(head)
    for s in [*args.scenarios, "import orbatt.cli"]:
        row = f"{s:28s}"
        med = {}
        for name in trees:
            v = times[name, s]
            med[name] = statistics.median(v)
            row += f"{med[name]:12.2f} [{min(v):5.2f}, {max(v):5.2f}]"
        if len(trees) > 1:
            row += f"   {med['this'] / med['baseline']:15.2f}"
        if s in share:
            row += f"   {statistics.median(share[s]):20.0%}"
        print(row)


if __name__ == "__main__":
    main()

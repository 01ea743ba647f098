"""Basilisk's ``MonteCarlo.Controller`` run offline for the benchmarks against Basilisk
(``basilisk_fine_pointing.py``, ``basilisk_fsw.py``): the pool with dispersions and a retention
function, and the fresh process it runs in."""
from __future__ import annotations

import json
import subprocess
import sys
import time


def run_controller(create, execute, retain, cases, workers, folder, dispersions):
    """Run ``cases`` cases with Basilisk's ``MonteCarlo.Controller`` on ``workers`` processes:
    ``create()`` builds a case's simulation, ``execute(sim)`` runs it (the dispersed attributes
    set on ``sim``), ``retain(sim)`` returns the dict kept of it; ``dispersions``: ``[(attribute,
    (low, high))]``, uniform; the modules' seeds dispersed; archives under ``folder``. Functions
    at module level (pickled by reference). Returns (wall s, retained dicts)."""
    from Basilisk.utilities.MonteCarlo.Controller import Controller
    from Basilisk.utilities.MonteCarlo.Dispersions import UniformDispersion
    from Basilisk.utilities.MonteCarlo.RetentionPolicy import RetentionPolicy

    mc = Controller()
    mc.setSimulationFunction(create)
    mc.setExecutionFunction(execute)
    mc.setExecutionCount(cases)
    mc.setThreadCount(workers)
    mc.setShouldDisperseSeeds(True)
    mc.setArchiveDir(str(folder) + "/")
    mc.setVerbose(False)
    for name, bounds in dispersions:
        mc.addDispersion(UniformDispersion(name, bounds))
    policy = RetentionPolicy()
    policy.addRetentionFunction(retain)
    mc.addRetentionPolicy(policy)
    t0 = time.perf_counter()
    failed = mc.executeSimulations()
    wall = time.perf_counter() - t0
    if failed:
        raise RuntimeError(f"Basilisk Controller: cases {failed} failed")
    kept = [mc.getRetainedData(k)["custom"] for k in range(cases)]
    return wall, kept


def controller_subprocess(script, arg):
    """Run ``python script --controller arg`` (a benchmark's child that prints the JSON of
    ``{"wall": s, "kept": [...]}`` as its last line) and return ``(wall, kept)``. The
    Controller's pool forks: forking a process where numba's threads have started can hang the
    children, hence a fresh process."""
    out = subprocess.run([sys.executable, str(script), "--controller", arg], check=True, capture_output=True,
                         text=True).stdout
    res = json.loads(out.strip().splitlines()[-1])
    return res["wall"], res["kept"]

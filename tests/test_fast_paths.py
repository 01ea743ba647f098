"""One switch, ``ORBATT_FAST_PATHS=0``, turns off every fast path that leans on another
library's internals (:mod:`orbatt.fast_paths`, issue 22): the public ways give the same bits."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "paper-torque-free.toml"

CODE = """
import json, sys, warnings
import orbatt
hook_deferred = "xarray" not in sys.modules
from orbatt import coldstart, fast_paths
plan = coldstart.plan(sys.argv[1])   # before numba is imported: a first run would interpret
warnings.simplefilter("ignore")
ds = orbatt.load_scenario(sys.argv[1]).run()
print(json.dumps({"active": fast_paths.active(), "hook_deferred": hook_deferred, "plans_interpreted": plan is not None,
                  "variables": list(ds.variables), "dims": dict(ds.sizes), "indexes": list(ds.indexes),
                  "q": ds["q"].values.tobytes().hex(), "time": ds["time"].values.astype("int64").tolist(),
                  "elapsed": ds["elapsed"].values.tobytes().hex(), "attrs": sorted(ds.attrs)}))
"""


def _run(tmp_path, switch):
    env = {k: v for k, v in os.environ.items() if k not in ("ORBATT_COLD_START", "ORBATT_FAST_PATHS")}
    if switch is not None:
        env["ORBATT_FAST_PATHS"] = switch
        # kernels compiled without borrowed arrays: their own cache (the stamp differs; numba
        # would otherwise replace the suite's entries)
        env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba-public")
    r = subprocess.run([sys.executable, "-c", CODE, str(SCENARIO)], capture_output=True, text=True, env=env,
                       timeout=900)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fast-paths")
    return _run(tmp, None), _run(tmp, "0")


def test_the_switch_turns_every_fast_path_off(runs):
    on, off = runs
    assert set(on["active"]) == set(off["active"]) == {"numba-cache-loads", "borrowed-arrays", "xarray-direct",
                                                       "accessor-hook", "interpreted-first", "rebound-particles"}
    assert not any(off["active"].values()), off["active"]
    # where the libraries are the ones they were written for (the versions pinned here), all on
    assert all(on["active"].values()), on["active"]
    assert on["hook_deferred"] and not off["hook_deferred"]  # off: import orbatt imports xarray
    assert not off["plans_interpreted"]                       # off: every run compiles


def test_the_public_ways_give_the_same_bits_and_the_same_dataset(runs):
    on, off = runs
    for key in ("variables", "dims", "indexes", "q", "time", "elapsed", "attrs"):
        assert on[key] == off[key], key

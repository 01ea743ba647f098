"""Test configuration shared by the whole suite."""
from hypothesis import settings

# The first call of a numba kernel compiles it (or loads its cache), which can take longer
# than hypothesis' default 200 ms deadline on a loaded 2-core CI machine: no deadline.
settings.register_profile("orbatt", deadline=None)
settings.load_profile("orbatt")


import importlib.util
import os
import warnings
from pathlib import Path

import pytest

# `orbatt run` in a subprocess runs compiled, as in-process: a first run's interpreted kernels
# and background warm-up (orbatt.coldstart) are tested on their own (tests/test_coldstart.py)
os.environ.setdefault("ORBATT_COLD_START", "compile")
# ... and imports the orbatt this process imported: without this, `python -m orbatt.cli` and
# `python -c` started from a clone's root put the source tree ./orbatt first on sys.path, so that
# with a non-editable install the subprocesses ran (and compiled, into a cache of their own) the
# source tree, not the installed package the suite tests (Python >= 3.11, as `python -P`)
os.environ.setdefault("PYTHONSAFEPATH", "1")

SHIPPED = Path(__file__).parent.parent / "scenarios"
BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


def pytest_collection_modifyitems(config, items):
    """Tests marked ``cache_check`` (kernels load from numba's cache in a fresh process, whose
    first pass compiles what the cache lacks) go last: by then the workers have cached the
    kernel families and the first pass only loads (2.7-8 s). Collected first they compiled what
    the workers were compiling too (47-64 s); collected last they also compiled, while concurrent
    compiles could lose cache entries (numba's unlocked index updates, :mod:`orbatt.core._jit`)
    and while their subprocesses imported the source tree ./orbatt of a clone's root instead of
    the installed package (``PYTHONSAFEPATH`` above)."""
    last = [item for item in items if item.get_closest_marker("cache_check")]
    if last:
        items[:] = [item for item in items if not item.get_closest_marker("cache_check")] + last


@pytest.fixture(scope="session")
def load_benchmark():
    """``load(name)``: the module of the script ``benchmarks/<name>.py`` (the test is skipped
    outside a source checkout)."""
    def load(name):
        script = BENCHMARKS / f"{name}.py"
        if not script.exists():
            pytest.skip(f"{script} not found (tests run outside a source checkout)")
        spec = importlib.util.spec_from_file_location(name, script)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


@pytest.fixture(scope="session")
def shipped_outputs(tmp_path_factory):
    """``{name: path}``: the NetCDF file of every shipped scenario's run (written once per
    session; the nominal case of a sweep scenario)."""
    import orbatt

    out = tmp_path_factory.mktemp("shipped")
    files = {}
    for toml in sorted(SHIPPED.glob("*.toml")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # e.g. the paper's periapsis inside the Earth
            ds = orbatt.load_scenario(toml).run()
        files[toml.stem] = out / f"{toml.stem}.nc"
        ds.orbatt.to_netcdf(files[toml.stem])
    return files

"""What ``orbatt run`` imports (issue 25, item 3: a run that starts in a second): only the
libraries its scenario needs. Checked in a fresh process on ``sys.modules`` after the whole
command (interpreted kernels, ``NUMBA_DISABLE_JIT=1``: the same imports as a compiled run, no
compilation)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCENARIOS = Path(__file__).parent.parent / "scenarios"

#: never needed by a run that writes a NetCDF file (plots, xarray, sweeps, other orbits)
NEVER = ("scipy.interpolate", "scipy.special", "scipy.integrate", "scipy.linalg", "scipy.optimize", "scipy.stats",
         "pandas", "xarray", "matplotlib", "dask", "h5netcdf", "rebound", "sgp4", "ppigrf")
#: needed only with an epoch (frames, the environment's libraries)
EPOCH_ONLY = ("astropy.time", "astropy.coordinates", "astropy.table", "astropy.utils.iers", "erfa", "pymsis")

CODE = """
import sys
from orbatt.cli import main
code = main(["run", sys.argv[1], "-o", sys.argv[2], "--quiet"])
assert not code, code
print(" ".join(sorted(sys.modules)))
"""


def _imported(scenario, tmp_path):
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run([sys.executable, "-c", CODE, str(scenario), str(tmp_path / "out.nc")], env=env,
                         cwd=tmp_path, capture_output=True, text=True, check=True).stdout
    assert (tmp_path / "out.nc").is_file()
    return set(out.split())


def _loaded(modules, names):
    return sorted(n for n in names if any(m == n or m.startswith(n + ".") for m in modules))


def test_a_torque_free_run_imports_no_heavy_library(tmp_path):
    modules = _imported(SCENARIOS / "paper-torque-free.toml", tmp_path)
    assert _loaded(modules, NEVER + EPOCH_ONLY) == []
    assert "netCDF4" in modules and "numba" in modules     # what it does need


@pytest.mark.parametrize("field", ["igrf", "dipole"])
def test_an_environment_run_imports_no_scipy_pandas_or_ppigrf(tmp_path, field):
    """The disturbed CubeSat over two minutes: NRLMSIS, IGRF (or its dipole), SRP, drag."""
    text = (SCENARIOS / "cubesat-3u-disturbances.toml").read_text()
    text = text.replace('t_end = "1 d"', 't_end = "120 s"').replace('magnetic_field = "igrf"',
                                                                    f'magnetic_field = "{field}"')
    assert 't_end = "120 s"' in text
    (tmp_path / "short.toml").write_text(text)
    modules = _imported(tmp_path / "short.toml", tmp_path)
    assert _loaded(modules, NEVER) == []
    assert "pymsis" in modules and "erfa" in modules

"""The direct netCDF-4 writer (issue 15): the same file as xarray's ``to_netcdf``, byte for
byte, without importing dask; what it does not cover goes to xarray."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.dataset import netcdf as N
from orbatt.dataset import netcdf_direct as direct
from orbatt.dataset.build import dataset_content

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _xarray_file(ds, path):
    enc_ds = N.encode(ds)
    enc_ds.to_netcdf(path, engine="netcdf4", format="NETCDF4", unlimited_dims=["time"],
                     encoding=N.encoding(enc_ds, 1, N.DEFAULT_CHUNK_TIME))


@pytest.mark.parametrize("fixture", ["free_ds", "orbit_ds"])
def test_the_file_is_xarrays_byte_for_byte(fixture, request, tmp_path):
    ds = request.getfixturevalue(fixture)
    _xarray_file(ds, tmp_path / "xarray.nc")
    N.write_netcdf(ds, tmp_path / "direct.nc")
    assert (tmp_path / "direct.nc").read_bytes() == (tmp_path / "xarray.nc").read_bytes()
    assert orbatt.open_dataset(tmp_path / "direct.nc", load=True).identical(ds)


def test_an_ensemble_with_a_kepler_orbit_and_its_content(tmp_path):
    sc = orbatt.load_scenario(SCENARIOS / "paper-keplerian.toml")
    ds = sc.run()
    _xarray_file(ds, tmp_path / "xarray.nc")
    N.write_netcdf(ds, tmp_path / "direct.nc")
    assert (tmp_path / "direct.nc").read_bytes() == (tmp_path / "xarray.nc").read_bytes()
    body = sc.body
    q = np.array([[1.0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5]])
    states = orbatt.State.from_momentum(body, q, np.array([[0.01, 0.0, 0.02], [0.0, 0.01, 0.0]]))
    tr = orbatt.propagate(body, states, sc.potential, np.linspace(0.0, 600.0, 4))
    content = dataset_content(tr)
    _xarray_file(content.to_dataset(), tmp_path / "ens_xarray.nc")
    N.write_netcdf(content, tmp_path / "ens_direct.nc")
    assert (tmp_path / "ens_direct.nc").read_bytes() == (tmp_path / "ens_xarray.nc").read_bytes()


def test_what_the_direct_writer_does_not_cover_goes_to_xarray(orbit_ds, tmp_path):
    ds = orbit_ds.copy()
    ds.attrs["listed"] = ["a", "b"]  # a list attribute: xarray writes it as NC_STRING
    ds["flag"] = ("time", np.ones(ds.sizes["time"], dtype=bool))
    assert not direct.writable(N._file_content(ds).variables, ds.attrs, {})
    N.write_netcdf(ds, tmp_path / "x.nc")
    back = orbatt.open_dataset(tmp_path / "x.nc", load=True)
    assert list(back.attrs["listed"]) == ["a", "b"] and back["flag"].dtype == bool


def test_orbatt_run_imports_neither_xarray_nor_dask(tmp_path):
    """The command line goes from the scenario to the file without xarray, pandas or dask."""
    code = ("import sys; from orbatt.cli import main; "
            f"rc = main(['run', {str(SCENARIOS / 'paper-torque-free.toml')!r}, '-o', {str(tmp_path / 'o.nc')!r}, "
            "'--quiet']); "
            "print(rc, sorted(m for m in ('xarray', 'pandas', 'dask', 'distributed') if m in sys.modules))")
    # the kernels interpreted (the imports are the question: a cold cache made this fresh
    # process compile the dop853 family, ~30 s, beside the tests compiling it)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    assert out.stdout.strip() == "0 []"
    assert orbatt.open_dataset(tmp_path / "o.nc")["q"].shape == (1001, 4)


def test_the_command_line_summary_reads_the_content_as_the_dataset():
    from orbatt.cli import summary

    sc = orbatt.load_scenario(SCENARIOS / "paper-torque-free.toml")
    content = sc.run_content()
    assert summary(content, title="t", wall=1.0) == summary(content.to_dataset(), title="t", wall=1.0)
    assert "q" in content and content["q"].values.shape == (1001, 4) and content.sizes["time"] == 1001


@pytest.mark.parametrize("order", ["orbatt first", "xarray first"])
def test_the_accessor_is_registered_whoever_imports_xarray_first(order):
    """import orbatt does not import xarray; ds.orbatt is there once xarray is imported."""
    first, second = ("orbatt", "xarray") if order == "orbatt first" else ("xarray", "orbatt")
    code = (f"import sys; import {first}; import {second}; import xarray as xr; "
            "print(type(xr.Dataset(attrs={'method_settings': '{}'}).orbatt).__name__, "
            "xr.Dataset(attrs={'method_settings': '{\"a\": 1}'}).orbatt.settings)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "OrbattAccessor {'a': 1}"
    bare = subprocess.run([sys.executable, "-c", "import sys, orbatt; print('xarray' in sys.modules)"],
                          capture_output=True, text=True, check=True)
    assert bare.stdout.strip() == "False"

"""The direct Dataset assembly (issue 15): the same Dataset as xarray's public constructor,
without importing dask."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from orbatt.dataset import assembly


def _parts(orbit_ds):
    data = {k: orbit_ds.variables[k].copy(deep=False) for k in orbit_ds.data_vars}
    coords = {k: orbit_ds.variables[k].to_base_variable() for k in orbit_ds.coords}
    return data, coords, dict(orbit_ds.attrs)


def test_direct_assembly_equals_the_public_constructor(orbit_ds, free_ds):
    for ds in (orbit_ds, free_ds):
        direct = assembly.assemble(*_parts(ds))
        public = assembly.assemble(*_parts(ds), direct=False)
        assert direct.identical(public)
        assert list(direct.variables) == list(public.variables)
        assert list(direct.dims) == list(public.dims)
        assert list(direct.xindexes) == list(public.xindexes)
        for name in public.xindexes:
            assert direct.xindexes[name].equals(public.xindexes[name])
            assert direct[name].dtype == public[name].dtype
        for name in public.variables:
            assert type(direct.variables[name]) is type(public.variables[name]), name


def test_assembled_datasets_do_not_share_attributes(orbit_ds):
    a = assembly.assemble(*_parts(orbit_ds))
    b = assembly.assemble(*_parts(orbit_ds))
    a["quat"].attrs["long_name"] = "changed"
    assert b["quat"].attrs["long_name"] != "changed"
    assert a.xindexes["quat"].equals(b.xindexes["quat"])


def test_disagreeing_dimension_sizes_are_refused():
    v1 = assembly.variable(("time",), np.zeros(3), {})
    v2 = assembly.variable(("time",), np.zeros(4), {})
    with pytest.raises(ValueError, match="'time' has size 4"):
        assembly.assemble({"a": v1, "b": v2}, {}, {})


def test_variable_wraps_arrays_and_converts_the_rest():
    a = np.arange(3.0)
    assert assembly.variable(("x",), a, {"units": "1"}).data is a
    v = assembly.variable(("x",), [1, 2, 3], {})
    assert v.dtype.kind == "i" and v.attrs == {}


def test_a_run_imports_no_dask():
    """Building a run's Dataset does not import dask (or pint, sparse: xarray's duck-array
    checks import them the first time a Variable is made the usual way, ~0.5 s)."""
    path = Path(__file__).resolve().parents[2] / "scenarios" / "paper-torque-free.toml"
    code = ("import sys, warnings; warnings.simplefilter('ignore'); import orbatt; "
            f"orbatt.load_scenario({str(path)!r}).run(); "
            "print(sorted(m for m in ('dask', 'pint', 'sparse', 'distributed') if m in sys.modules))")
    # the kernels interpreted (what is imported is the question, not the compiler: a cold cache
    # made this fresh process compile the dop853 family, ~30 s, beside the tests compiling it)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("direct", [True, False])
def test_variables_made_without_xarrays_constructor_are_its_variables(orbit_ds, monkeypatch, direct):
    """The direct variables and index-variable copies (checked at import) give the Dataset of
    the public constructor, and so does the fallback through xarray's constructors."""
    assert assembly.DIRECT  # this xarray passes the import check
    monkeypatch.setattr(assembly, "DIRECT", direct)
    for _ in range(2):  # the second time from the cached indexes (time included: 2 outputs)
        ds = assembly.assemble(*_parts(orbit_ds))
        assert ds.identical(assembly.assemble(*_parts(orbit_ds), direct=False))
        for name, var in ds.variables.items():
            assert var.encoding == orbit_ds.variables[name].encoding
            assert var.attrs is not orbit_ds.variables[name].attrs


def test_cached_time_indexes_are_shared_read_only_and_per_values():
    """A small float ``time`` coordinate's index is reused by the next Dataset with the same
    times: pandas holds its own read-only copy, so changing the caller's array changes
    neither Dataset."""
    t = np.array([0.0, 1.5])
    make = lambda: assembly.assemble({"x": assembly.variable(("time",), np.arange(2.0), {})},  # noqa: E731
                                     {"time": assembly.variable(("time",), t, {"units": "s"})}, {})
    a, b = make(), make()
    t[0] = 7.0
    for ds in (a, b):
        assert list(ds["time"].values) == [0.0, 1.5] and not ds["time"].values.flags.writeable
    c = make()
    assert list(c["time"].values) == [7.0, 1.5] and list(a["time"].values) == [0.0, 1.5]
    a["time"].attrs["units"] = "h"
    assert b["time"].attrs["units"] == "s"


def test_shared_index_coordinates_cannot_be_edited_into_the_next_run():
    """``run_content`` hands out the index coordinates' shared values (no copy per run): they
    are read-only, so an edit in place raises instead of changing every later result."""
    import warnings

    import orbatt

    sc = orbatt.load_scenario(Path(__file__).resolve().parents[2] / "scenarios" / "paper-torque-free.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        content = sc.run_content()
    for name in ("quat", "axis"):
        values = content.coords[name].values
        with pytest.raises(ValueError, match="read-only"):
            values[0] = 7
    np.testing.assert_array_equal(sc.run()["quat"].values, [0, 1, 2, 3])

"""Appending a run's later samples to its file keeps the later part's eclipses (they were
dropped: the ``eclipse`` dimension was fixed and the append wrote only variables along
``time``); an eclipse under way at the boundary stays one eclipse."""
import warnings
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.core import switches as ksw
from orbatt.dataset.netcdf import write_netcdf
from orbatt.errors import InputError

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "iss-tle-disturbances.toml"


@pytest.fixture(scope="module")
def run():
    """The ISS over two orbits (the scenario's one, twice as long): two eclipses."""
    from orbatt.scenario import Scenario, parse

    text = SCENARIO.read_text().replace('t_end = "1 orbits"', 't_end = "2 orbits"')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = Scenario(parse(text, SCENARIO.stem))
        ds = sc.run_content().to_dataset()
    return sc, ds


def _part(ds, sc, a, b):
    """Samples ``a:b`` of ``ds`` with the eclipses of their own span (as a piece of a run
    written as it goes has)."""
    part = ds.isel(time=slice(a, b), eclipse=slice(0, 0))
    t = ds["elapsed"].values[a:b]
    entry, exit_ = (np.round(x, 6) for x in ksw.eclipse_times(*sc.potential.kernel_model(), float(t[0]),
                                                                float(t[-1])))
    epoch = np.datetime64(ds.attrs["epoch"].rstrip("Z"), "ns")

    def dates(s):
        out = epoch + np.round(np.nan_to_num(s) * 1e6).astype("timedelta64[us]").astype("timedelta64[ns]")
        out[np.isnan(s)] = np.datetime64("NaT")
        return out

    part = part.drop_vars(["eclipse_entry", "eclipse_exit"]).drop_dims("eclipse", errors="ignore")
    for name, s in (("eclipse_entry", entry), ("eclipse_exit", exit_)):
        part[name] = ("eclipse", dates(s), ds[name].attrs)
        part[name].encoding = dict(ds[name].encoding)
    return part


@pytest.mark.parametrize("engine", ["netCDF4", "h5netcdf"])
def test_appended_parts_keep_every_eclipse(run, tmp_path, engine):
    pytest.importorskip(engine)
    engine = engine.lower()
    sc, ds = run
    entry, exit_ = ds["eclipse_entry"].values, ds["eclipse_exit"].values
    both = ~np.isnat(entry) & ~np.isnat(exit_)
    assert both.sum() >= 2
    # split inside the first complete eclipse, and again after the second one's entry
    t = ds["time"].values
    k1 = int(np.searchsorted(t, entry[both][0] + (exit_[both][0] - entry[both][0]) / 2))
    k2 = int(np.searchsorted(t, entry[both][1])) + 3
    parts = [_part(ds, sc, 0, k1 + 1), _part(ds, sc, k1, k2 + 1), _part(ds, sc, k2, len(t))]
    assert np.isnat(parts[0]["eclipse_exit"].values[-1]) and np.isnat(parts[1]["eclipse_entry"].values[0])
    path = tmp_path / "run.nc"
    write_netcdf(parts[0], path, engine=engine)
    for p in parts[1:]:
        write_netcdf(p, path, engine=engine, append=True)
    with orbatt.open_dataset(path) as back:
        np.testing.assert_array_equal(back["eclipse_entry"].values, entry)
        np.testing.assert_array_equal(back["eclipse_exit"].values, exit_)
        np.testing.assert_array_equal(back["time"].values, t)


def test_a_file_with_a_fixed_eclipse_dimension_refuses_more_eclipses(run, tmp_path):
    sc, ds = run
    t = ds["time"].values
    k = int(np.searchsorted(t, ds["eclipse_exit"].values[0])) + 3  # after the first eclipse
    first, later = _part(ds, sc, 0, k + 1), _part(ds, sc, k, len(t))
    assert first.sizes["eclipse"] == 1 and later.sizes["eclipse"] == 1
    path = tmp_path / "old.nc"
    # as orbatt wrote it before: only time unlimited
    from orbatt.dataset.netcdf import encode, encoding

    enc = encode(first)
    enc.to_netcdf(path, format="NETCDF4", unlimited_dims=["time"], encoding=encoding(enc, 1, 64))
    size = path.stat().st_size
    with pytest.raises(InputError, match=r"old\.nc holds a fixed number of eclipses"):
        write_netcdf(later, path, append=True)
    assert path.stat().st_size == size

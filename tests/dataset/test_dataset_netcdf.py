"""NetCDF export/import (issue 5): bitwise round trips with both engines, plain xarray and
netCDF4 reads, the CF checker, appends."""
import numpy as np
import pytest
import xarray as xr
from astropy import units as u

import orbatt
from orbatt import dataset as D
from orbatt.errors import InputError
from orbatt.trajectory import Trajectory

from dataset_support import ENGINES, SCENARIO, assert_bitwise_identical


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("which", ["free", "orbit"])
def test_netcdf_round_trip_is_bitwise(engine, which, free_ds, orbit_ds, tmp_path):
    ds = free_ds if which == "free" else orbit_ds
    path = tmp_path / f"{which}.nc"
    ds.orbatt.to_netcdf(path, engine=engine)
    back = D.open_dataset(path, engine=engine, load=True)
    assert_bitwise_identical(ds, back)
    assert back.orbatt.scenario == SCENARIO
    for name in ds.variables:
        assert back[name].attrs.get("units") == ds[name].attrs.get("units")
    # and through the top-level entry point, with the other engine reading
    other = "h5netcdf" if engine == "netcdf4" else "netcdf4"
    if other in [e for e in ENGINES if isinstance(e, str)]:
        assert_bitwise_identical(ds, orbatt.open_dataset(path, engine=other, load=True))


def test_file_opens_with_plain_xarray_and_netcdf4(orbit_ds, free_ds, tmp_path):
    netCDF4 = pytest.importorskip("netCDF4")
    path = tmp_path / "orbit.nc"
    orbit_ds.orbatt.to_netcdf(path)
    # plain xarray decodes the CF time reference to datetimes at the epoch
    with xr.open_dataset(path) as plain:
        t0 = plain["time"].values[0]
        assert np.issubdtype(plain["time"].dtype, np.datetime64)
        assert str(t0).startswith("2024-03-20T03:06:00")
        step = (plain["time"].values[1] - t0) / np.timedelta64(1, "ns") * 1e-9
        assert abs(step - orbit_ds["elapsed"].values[1]) < 1e-6
        # the same time axis as the Dataset itself: datetimes, elapsed seconds
        assert np.array_equal(plain["time"].values, orbit_ds["time"].values)
        assert np.array_equal(plain["elapsed"].values, orbit_ds["elapsed"].values)
        assert plain["omega"].attrs["units"] == "rad s^-1"
        assert np.array_equal(plain["q"].values, orbit_ds["q"].values)
    # the raw file: CF attributes that matter
    with netCDF4.Dataset(path) as nc:
        assert nc.getncattr("Conventions") == "CF-1.11"
        assert nc.getncattr("scenario") == SCENARIO
        tv = nc.variables["time"]
        assert tv.getncattr("units") == "seconds since 2024-03-20T03:06:00.000000000Z"
        assert tv.getncattr("calendar") == "standard"
        assert tv.getncattr("units_metadata") == "leap_seconds: utc"  # SI seconds, astropy's UTC
        assert tv.getncattr("standard_name") == "time" and tv.getncattr("axis") == "T"
        assert nc.dimensions["time"].isunlimited()
        for name, var in nc.variables.items():
            if name.endswith("_label"):
                assert var.dtype == np.dtype("S1")  # CF char labels
                continue
            assert "long_name" in var.ncattrs(), name
            units = var.getncattr("units")
            if name != "time":
                u.Unit(units)
            assert "_FillValue" not in var.ncattrs(), name
            if "time" in var.dimensions and var.dtype == np.float64:
                assert var.filters()["zlib"] and var.filters()["shuffle"], name
                chunks = var.chunking()
                assert chunks[var.dimensions.index("time")] == D.DEFAULT_CHUNK_TIME, name
        for name in ["q", "Q", "p", "q_orbital"]:
            assert nc.variables[name].getncattr("quaternion_order") == "w x y z"
    # dimensionless: time units "1", no reference, plain xarray keeps numbers
    p2 = tmp_path / "free.nc"
    free_ds.orbatt.to_netcdf(p2)
    with xr.open_dataset(p2) as plain:
        assert plain["time"].attrs["units"] == "1"
        assert np.array_equal(plain["time"].values, free_ds["time"].values)


_STD_TABLE = """<?xml version="1.0"?><standard_name_table><version_number>local</version_number>
<last_modified>local</last_modified><entry id="time"><canonical_units>s</canonical_units>
<description>time</description></entry></standard_name_table>"""


_LIST_TABLE = """<?xml version="1.0"?><{0}><version_number>local</version_number><date>local</date>
<entry id="x"></entry></{0}>"""


def test_cf_checker(orbit_ds, tmp_path):
    """cfchecker (CF <= 1.8 only: the file is checked under that label), where installed."""
    cfchecks = pytest.importorskip("cfchecker.cfchecks")
    netCDF4 = pytest.importorskip("netCDF4")
    path = tmp_path / "cf.nc"
    orbit_ds.orbatt.to_netcdf(path)
    with netCDF4.Dataset(path, "a") as nc:
        nc.setncattr("Conventions", "CF-1.8")
    (tmp_path / "std.xml").write_text(_STD_TABLE)
    (tmp_path / "area.xml").write_text(_LIST_TABLE.format("area_type_table"))
    (tmp_path / "region.xml").write_text(_LIST_TABLE.format("standardized_region_list"))
    checker = cfchecks.CFChecker(cfStandardNamesXML=str(tmp_path / "std.xml"),
                                 cfAreaTypesXML=str(tmp_path / "area.xml"),
                                 cfRegionNamesXML=str(tmp_path / "region.xml"),
                                 version=cfchecks.CFVersion((1, 8)), silent=True)
    res = checker.checker(str(path))
    errors = [m for v in [res["global"], *res["variables"].values()] for m in v["FATAL"] + v["ERROR"]]
    assert errors == []


@pytest.mark.parametrize("engine", ENGINES)
def test_appendable_writing(engine, orbit_traj, tmp_path):
    full = D.to_dataset(orbit_traj, scenario_text=SCENARIO)
    n = orbit_traj.t.size
    cuts = [(0, 50), (49, 100), (99, n)]  # pieces share their end points, as segment runs do
    path = tmp_path / "long.nc"
    with D.NetCDFWriter(path, engine=engine, chunk_time=16) as w:
        for a, b in cuts:
            piece = Trajectory(body=orbit_traj.body, potential=orbit_traj.potential, t=orbit_traj.t[a:b],
                               q=orbit_traj.q[a:b], Q=orbit_traj.Q[a:b], inertia=orbit_traj.inertia,
                               method=orbit_traj.method, settings=orbit_traj.settings,
                               stats={"steps": 10, "rhs_evaluations": 120, "wall_time_s": 0.5})
            w.append(D.to_dataset(piece, scenario_text=SCENARIO))
            assert w.samples == b
    back = D.open_dataset(path, engine=engine, load=True)
    assert back.sizes["time"] == n
    for name, var in full.data_vars.items():
        assert np.asarray(back[name].values).tobytes() == np.asarray(var.values).tobytes(), name
        assert back[name].attrs == var.attrs, name
    assert np.array_equal(back["time"].values, full["time"].values)
    stats = back.orbatt.stats
    assert stats["steps"] == 30 and stats["rhs_evaluations"] == 360 and abs(stats["wall_time_s"] - 1.5) < 1e-12
    assert "date_modified" in back.attrs and back.attrs["history"].count("appended") == 2
    assert back.orbatt.scenario == SCENARIO
    # an earlier time is refused; so is a different set of variables
    early = D.to_dataset(Trajectory(body=orbit_traj.body, potential=orbit_traj.potential, t=orbit_traj.t[:3],
                                    q=orbit_traj.q[:3], Q=orbit_traj.Q[:3], inertia=orbit_traj.inertia,
                                    method="x"))
    with pytest.raises(InputError, match="not after"):
        D.write_netcdf(early, path, engine=engine, append=True)
    late = D.to_dataset(Trajectory(body=orbit_traj.body, potential=orbit_traj.potential,
                                   t=orbit_traj.t[-2:] + 1e4, q=orbit_traj.q[-2:], Q=orbit_traj.Q[-2:],
                                   inertia=orbit_traj.inertia, method="x"))
    with pytest.raises(InputError, match="variables"):
        D.write_netcdf(late.drop_vars("euler_321"), path, engine=engine, append=True)
    # append=True on a missing file creates it
    p2 = tmp_path / "new.nc"
    D.write_netcdf(full, p2, engine=engine, append=True)
    assert_bitwise_identical(full, D.open_dataset(p2, engine=engine, load=True))


def test_bad_engine(free_ds, tmp_path):
    with pytest.raises(InputError, match="engine"):
        free_ds.orbatt.to_netcdf(tmp_path / "x.nc", engine="scipy")

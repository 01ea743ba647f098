"""Every variable of every shipped scenario's output file reads in the unit libraries of the
tools users open it with: astropy, UDUNITS-2 (CF) and pint (also through pint-xarray)."""
import numpy as np
import pytest
import xarray as xr
from astropy import units as u

import orbatt
from orbatt.units import parse_unit

from unit_support import same_in_pint, udunits_parses


def _unit_attrs(path):
    with xr.open_dataset(path, decode_times=False) as ds:
        return {k: v.attrs["units"] for k, v in ds.variables.items() if "units" in v.attrs}


def test_every_variable_parses_in_astropy_udunits_and_pint(shipped_outputs):
    for name, path in shipped_outputs.items():
        for var, s in _unit_attrs(path).items():
            unit = parse_unit(s)
            assert udunits_parses(s), (name, var, s)
            if " since " in s:  # the CF time reference "seconds since <epoch>": pint reads its unit
                s = s.split(" since ")[0]
            else:
                assert u.Unit(s) == unit, (name, var, s)
            assert same_in_pint(s, unit), (name, var, s)


def test_pint_xarray_quantifies_every_variable(shipped_outputs):
    pytest.importorskip("pint_xarray")
    for name, path in shipped_outputs.items():
        with xr.open_dataset(path) as ds:
            q = ds.pint.quantify()
            ours = orbatt.open_dataset(path)
            for var in ("Q", "omega", "energy"):
                expect = ours.orbatt.quantity(var)
                got = q[var].data
                np.testing.assert_array_equal(got.magnitude, expect.value)
                assert same_in_pint(str(got.units), expect.unit), (name, var)


def test_time_is_cf_and_round_trips_in_xarray_and_orbatt(shipped_outputs):
    from astropy.time import Time

    from orbatt.dataset.netcdf import NOMINAL_REFERENCE

    for name, path in shipped_outputs.items():
        ours = orbatt.open_dataset(path, load=True)
        assert ours["time"].attrs["units"] in ("s", "1")
        assert ours["time"].attrs["standard_name"] == "time" and ours["time"].attrs["axis"] == "T"
        with xr.open_dataset(path, decode_times=False) as raw:
            units = raw["time"].attrs["units"]
        if "epoch" in ours.attrs:
            assert units == f"seconds since {ours.attrs['epoch']}"
            with xr.open_dataset(path) as ds:  # plain xarray decodes UTC datetimes
                dates = Time(ds["time"].values[[0, -1]].astype("datetime64[ns]"), scale="utc")
            expect = Time(ours.attrs["epoch"], scale="utc") + ours["time"].values[[0, -1]] * u.s
            # cftime ignores leap seconds (units_metadata says how orbatt counts them): none
            # falls inside a shipped run, so the dates agree to the microsecond
            assert np.all(np.abs((dates - expect).to_value(u.s)) < 1e-6), name
        elif units != "1":
            assert units == f"seconds since {NOMINAL_REFERENCE}" and "epoch" not in ours.attrs, name

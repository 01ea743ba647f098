"""Every variable of every shipped scenario's output file reads in the unit libraries of the
tools users open it with: astropy, UDUNITS-2 (CF) and pint (also through pint-xarray)."""
import warnings

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
    """One time axis (issue 26): orbatt.open_dataset and plain xarray give the same ``time``
    (datetime64 UTC, on the nominal epoch without one) and ``elapsed`` (float seconds),
    without a warning; a normalized scenario keeps plain numbers in both."""
    from astropy.time import Time

    from orbatt.dataset.build import NOMINAL_EPOCH

    for name, path in shipped_outputs.items():
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            ours = orbatt.open_dataset(path, load=True)
            with xr.open_dataset(path) as plain:
                plain = plain.load()
        with xr.open_dataset(path, decode_times=False) as raw:
            units = raw["time"].attrs["units"]
            assert np.array_equal(raw["time"].values, ours["elapsed"].values), name  # the file: elapsed s
        assert ours["time"].attrs["axis"] == "T"
        assert ours["time"].dtype == plain["time"].dtype and ours["time"].attrs == plain["time"].attrs, name
        assert np.array_equal(ours["time"].values, plain["time"].values), name
        assert np.array_equal(ours["elapsed"].values, plain["elapsed"].values), name
        if units == "1":
            assert ours["time"].dtype == np.float64 and ours["elapsed"].attrs["units"] == "1", name
            continue
        assert ours["time"].dtype == np.dtype("datetime64[ns]") and ours["time"].attrs["standard_name"] == "time"
        assert ours["elapsed"].attrs["units"] == "s"
        if "epoch" in ours.attrs:
            assert units == f"seconds since {ours.attrs['epoch']}"
            dates = Time(ours["time"].values[[0, -1]], scale="utc")
            expect = Time(ours.attrs["epoch"], scale="utc") + ours["elapsed"].values[[0, -1]] * u.s
            # datetime64 ignores leap seconds (units_metadata says how orbatt counts them): none
            # falls inside a shipped run, so the dates agree to the microsecond
            assert np.all(np.abs((dates - expect).to_value(u.s)) < 1e-6), name
        else:
            assert units == f"seconds since {NOMINAL_EPOCH}" and "epoch" not in ours.attrs, name
            assert ours["time"].values[0] == np.datetime64(NOMINAL_EPOCH.rstrip("Z"), "ns") + \
                np.timedelta64(int(round(ours["elapsed"].values[0] * 1e9)), "ns")

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


def _quantifies(path):
    """pint-xarray's ``quantify()`` reads every variable of the file at ``path``, each in the unit
    astropy reads from its ``units`` (compared as SI factor and dimension)."""
    with xr.open_dataset(path) as ds:
        q = ds.pint.quantify()  # raised "'m2' is not defined" on a path's "kg m2" (issue 35 item 3)
        n = 0
        for name, var in ds.variables.items():
            s = var.attrs.get("units")
            if s is None or name not in q.variables:
                continue
            got = q[name].data
            assert hasattr(got, "units"), (path.name, name, s)
            assert same_in_pint(str(got.units), parse_unit(s)), (path.name, name, s, got.units)
            n += 1
        return q, n


def test_pint_xarray_quantifies_a_run_a_path_sweep_and_a_binary_sweep(tmp_path):
    """Every file kind (issue 35 item 3): a single run, a sweep whose parameters are scenario paths
    in the units the TOML writes ("kg m2", "deg/s", "A m2 s / T") and a binary sweep."""
    pytest.importorskip("pint_xarray")
    import re
    from pathlib import Path

    from orbatt.scenario import Scenario, parse
    from orbatt.sweep import Sweep, run_sweep

    scen = Path(__file__).resolve().parent.parent / "scenarios"
    bdot = re.sub(r"^t_end = .*$", 't_end = "300 s"', (scen / "cubesat-bdot-detumble.toml").read_text(), flags=re.M)
    one = Scenario(parse(bdot, "bdot.toml")).run()
    one.orbatt.to_netcdf(tmp_path / "run.nc")
    q, n = _quantifies(tmp_path / "run.nc")
    assert n > 10 and str(q["omega"].data.units) == "radian / second"

    table = ('samples = 2\noutputs = ["final_state", "detumble_time"]\ndetumble_rate = "2 deg/s"\n'
             '[sweep.parameters]\n'
             '"body.inertia[2]" = { distribution = "uniform", low = "0.006 kg m2", high = "0.008 kg m2" }\n'
             '"initial.omega[0]" = { distribution = "uniform", low = "-5 deg/s", high = "5 deg/s" }\n'
             '"control.gain" = { distribution = "normal", std = "5e3 A m2 s / T" }\n')
    sw = Sweep(Scenario(parse(bdot + "\n[sweep]\n" + table, "paths.toml")), seed=7)
    run_sweep(sw, tmp_path / "paths.nc", scheduler="synchronous")
    q, _ = _quantifies(tmp_path / "paths.nc")
    with xr.open_dataset(tmp_path / "paths.nc") as raw:
        assert raw["body_inertia_2"].attrs["units"] == "kg m^2"
        np.testing.assert_array_equal(q["body_inertia_2"].data.to("kg m^2").magnitude, raw["body_inertia_2"].values)
    assert str(q["initial_omega_0"].data.units) == "degree / second"

    mc = (scen / "didymos-dimorphos-montecarlo.toml").read_text()
    mc = re.sub(r"^samples = .*$", "samples = 2", mc, flags=re.M)
    mc = re.sub(r"^t_end = .*$", 't_end = "2 h"', mc, flags=re.M)
    mc = re.sub(r'^time = "86400 s"', 'time = "3600 s"', mc, flags=re.M)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sw = Sweep(Scenario(parse(mc, "dart-mc.toml")))
    run_sweep(sw, tmp_path / "binary.nc", scheduler="synchronous")
    q, _ = _quantifies(tmp_path / "binary.nc")
    assert str(q["body_inertia_0"].data.units) == "kilogram * meter ** 2"
    assert str(q["orbit_impulses_0_delta_v_1"].data.units) == "meter / second"

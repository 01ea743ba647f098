"""SI outputs and one time axis (issue 26, item 3).

The attitude family comes out in SI (kg m^2, kg m^2 s^-1, J) and agrees with the physics
computed from the Dataset's own variables; ``time`` is ``datetime64[ns]`` UTC with an
``elapsed`` coordinate in seconds, the same from ``run()``, :func:`orbatt.open_dataset` and
plain :func:`xarray.open_dataset`, with and without an epoch, for a single run, an ensemble
and a sweep, and without any warning; files of earlier versions open in the same form with
their values scaled exactly (``tests/data/legacy``, written by ``make_legacy.py``).
"""
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from astropy import units as u

import orbatt
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.cli import summary
from orbatt.dataset.build import NOMINAL_EPOCH
from orbatt.scenario import Scenario, parse
from orbatt.units import LEGACY_OUTPUT

ROOT = Path(__file__).resolve().parents[2]
SCEN = ROOT / "scenarios"
LEGACY = ROOT / "tests" / "data" / "legacy"
SI = {"Q": "kg m^2 s^-1", "g": "kg m^2 s^-1", "G": "kg m^2 s^-1", "qQ": "kg m^2 s^-1", "inertia": "kg m^2",
      "energy": "J", "kinetic_energy": "J", "potential_energy": "J"}


def shortened(name, t_end, step, extra=""):
    text = (SCEN / f"{name}.toml").read_text()
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    text = re.sub(r"^output_step = .*$", f"output_step = {step}", text, flags=re.M)
    return text + extra


def run(name, t_end, step):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the paper's periapsis inside the Earth
        return Scenario(parse(shortened(name, t_end, step), f"{name}.toml")).run()


@pytest.fixture(scope="module")
def wheels():
    """A dimensional run without an epoch: a gyrostat (wheels) under control."""
    return run("lvlh-hold-wheels", '"200 s"', '"20 s"')


@pytest.fixture(scope="module")
def tle():
    """A run with an epoch (the TLE's)."""
    return run("iss-tle-gravity-gradient", '"300 s"', '"30 s"')


def read_all_ways(ds, path):
    """``(orbatt.open_dataset, plain xarray)`` of ``ds`` written to ``path``, with every
    warning an error."""
    ds.orbatt.to_netcdf(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ours = orbatt.open_dataset(path, load=True)
        with xr.open_dataset(path) as plain:
            plain = plain.load()
    return ours, plain


def assert_one_time_axis(*forms):
    first = forms[0]
    for other in forms[1:]:
        for name in ("time", "elapsed"):
            assert other[name].dtype == first[name].dtype, name
            assert other[name].dims == ("time",) and name in other.coords
            assert np.array_equal(other[name].values, first[name].values), name
            assert other[name].attrs == first[name].attrs, (name, other[name].attrs, first[name].attrs)


# ---------------------------------------------------------------------------------------
# SI units and the physics in them


def test_attitude_family_in_si_and_the_physics_holds(wheels, tle):
    for ds in (wheels, tle):
        for name, unit in SI.items():
            assert ds[name].attrs["units"] == unit, name
        assert ds["r"].attrs["units"] == "km" and ds["position"].attrs["units"] == "km"  # orbit: km
        assert ds.attrs["unit_system"].startswith("SI")
    # a rigid body: T = 1/2 omega . I omega, and g = 1/2 Im(q~ Q) = I omega, all in SI
    I, w, q, Q = (tle[k].values for k in ("inertia", "omega", "q", "Q"))
    np.testing.assert_allclose(tle["kinetic_energy"].values, 0.5 * np.sum(w * I * w, axis=-1), rtol=1e-13)
    g = 0.5 * qt.mul(qt.conj(q), Q)[..., 1:]
    np.testing.assert_allclose(g, I * w, rtol=1e-13, atol=1e-13 * np.abs(g).max())
    np.testing.assert_allclose(tle["g"].values, g, rtol=1e-14, atol=1e-15 * np.abs(g).max())
    # the gyrostat: T = 1/2 (g - h) . omega + sum h_k^2 / (2 Iw_k), in J from kg m^2 values
    h = np.einsum("tk,ki->ti", wheels["wheel_momentum"].values, wheels["wheel_axis"].values)
    hk, iw = wheels["wheel_momentum"].values, wheels["wheel_inertia"].values
    assert wheels["wheel_momentum"].attrs["units"] == "kg m^2 s^-1"
    assert wheels["wheel_inertia"].attrs["units"] == "kg m^2"
    T = 0.5 * np.sum((wheels["g"].values - h) * wheels["omega"].values, axis=-1) + np.sum(hk**2 / (2 * iw), axis=-1)
    np.testing.assert_allclose(wheels["kinetic_energy"].values, T, rtol=1e-12)
    # the scenario's own numbers: 1.8 kg m2 and 4e-4 kg m2
    np.testing.assert_allclose(wheels["inertia"].values, [1.8, 2.2, 1.2], rtol=1e-14)
    np.testing.assert_allclose(iw, 4e-4, rtol=1e-14)
    # the energy is H = T + U in J
    np.testing.assert_allclose(wheels["energy"].values, T + wheels["potential_energy"].values, rtol=1e-12)


def test_state_and_info_print_si(wheels):
    body = orbatt.RigidBody([1.8, 2.2, 1.2] * u.kg * u.m**2)
    st = orbatt.State.from_omega(body, [1.0, 0, 0, 0], [0.1, 0.0, 0.0] * u.rad / u.s)
    # g = I omega = 0.18 kg m^2 s^-1: Q = 2 q g has 0.36 on x
    assert repr(st).endswith("kg m^2 s^-1)") and "0.36" in repr(st)
    text = summary(wheels)
    assert " J (relative" in text and "0 .. 200 s" in text and "kg m^2 s^-1 (initial" in text


# ---------------------------------------------------------------------------------------
# one time axis


def test_run_open_and_plain_xarray_give_one_time_axis_with_an_epoch(tle, tmp_path):
    ours, plain = read_all_ways(tle, tmp_path / "tle.nc")
    assert_one_time_axis(tle, ours, plain)
    assert tle["time"].dtype == np.dtype("datetime64[ns]") and tle["elapsed"].attrs["units"] == "s"
    assert str(tle["time"].values[0]).startswith("2019-12-09T17:38:29")
    assert (tle["time"].values[-1] - tle["time"].values[0]) == np.timedelta64(300, "s")
    assert np.array_equal(tle["elapsed"].values, np.arange(0.0, 301.0, 30.0))
    # exact absolute times (astropy, leap seconds counted) from elapsed
    assert abs((tle.orbatt.times()[-1] - tle.orbatt.epoch).to_value(u.s) - 300.0) < 1e-9


def test_run_open_and_plain_xarray_give_one_time_axis_without_an_epoch(wheels, tmp_path):
    ours, plain = read_all_ways(wheels, tmp_path / "wheels.nc")
    assert_one_time_axis(wheels, ours, plain)
    assert "epoch" not in ours.attrs and ours.orbatt.epoch is None
    assert wheels["time"].values[0] == np.datetime64(NOMINAL_EPOCH.rstrip("Z"), "ns")
    assert "nominal" in wheels["time"].attrs["comment"]
    # the file itself: elapsed seconds from the nominal epoch in time, CF-clean
    with xr.open_dataset(tmp_path / "wheels.nc", decode_times=False) as raw:
        assert raw["time"].attrs["units"] == f"seconds since {NOMINAL_EPOCH}"
        assert np.array_equal(raw["time"].values, wheels["elapsed"].values)


def test_the_two_writers_and_the_append_keep_the_time_axis(tle, tmp_path):
    """The Content (what `orbatt run` writes) and the Dataset give one file; appended
    pieces keep both coordinates."""
    D.write_netcdf(tle.isel(time=slice(0, 6)), tmp_path / "a.nc")
    D.write_netcdf(tle.isel(time=slice(5, None)), tmp_path / "a.nc", append=True)
    back = orbatt.open_dataset(tmp_path / "a.nc", load=True)
    assert_one_time_axis(tle, back)
    D.write_netcdf(tle, tmp_path / "h5.nc", engine="h5netcdf")
    assert_one_time_axis(tle, orbatt.open_dataset(tmp_path / "h5.nc", load=True))


def test_an_ensemble_has_the_same_time_axis(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the paper's periapsis inside the Earth
        sc = orbatt.load_scenario(SCEN / "paper-keplerian.toml")
        q = np.array([[1.0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5]])
        states = orbatt.State.from_momentum(sc.body, q, np.array([[0.01, 0.0, 0.02], [0.0, 0.01, 0.0]]))
        tr = orbatt.propagate(sc.body, states, sc.potential, np.linspace(0.0, 600.0, 4))
    ens = D.to_dataset(tr)
    assert ens["Q"].dims == ("case", "time", "quat") and ens["Q"].attrs["units"] == "kg m^2 s^-1"
    ours, plain = read_all_ways(ens, tmp_path / "ens.nc")
    assert_one_time_axis(ens, ours, plain)
    assert ens["time"].dtype == np.dtype("datetime64[ns]")


def test_a_sweep_file_has_the_same_time_axis_and_si(tmp_path):
    from orbatt.sweep import Sweep, run_sweep

    text = shortened("gg-leo-dispersion", '"200 s"', '"20 s"')
    text = re.sub(r"^samples = .*$", "samples = 3", text, flags=re.M)
    text = re.sub(r"^chunk_size = .*$", "chunk_size = 3", text, flags=re.M)
    text = re.sub(r"^outputs = \[", 'outputs = ["trajectory", ', text, flags=re.M)
    sw = Sweep(Scenario(parse(text, "gg-leo-dispersion.toml")))
    mem = sw.compute()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ours = run_sweep(sw, tmp_path / "s.nc", scheduler="synchronous").load()
        with xr.open_dataset(tmp_path / "s.nc") as plain:
            plain = plain.load()
    assert_one_time_axis(mem, ours, plain)
    for ds in (mem, ours):
        assert ds["Q_final"].attrs["units"] == "kg m^2 s^-1" and ds["inertia1"].attrs["units"] == "kg m^2"
        np.testing.assert_array_equal(ds["Q_final"].values, ds["Q"].values[:, -1])
        np.testing.assert_array_equal(ds["inertia1"].values, ds["inertia"].values[:, 0])
    assert 0.5 < float(ours["inertia1"].mean()) < 50  # kg m^2, not kg km^2


def test_a_normalized_run_keeps_plain_numbers(tmp_path):
    norm = run("mercury-3-2-normalized", "0.5", "0.05")
    assert norm["time"].dtype == np.float64 and norm["time"].attrs["units"] == "1"
    assert np.array_equal(norm["time"].values, norm["elapsed"].values) and norm["elapsed"].attrs["units"] == "1"
    assert norm["Q"].attrs["units"] == "1" and norm["energy"].attrs["units"] == "1"
    ours, plain = read_all_ways(norm, tmp_path / "norm.nc")
    assert_one_time_axis(norm, ours, plain)
    assert ours.orbatt.dimensionless


# ---------------------------------------------------------------------------------------
# files written before


LEGACY_FILES = ["lvlh-hold-wheels", "iss-tle-gravity-gradient", "mercury-3-2-normalized", "gg-leo-dispersion-sweep"]


@pytest.mark.parametrize("name", LEGACY_FILES)
def test_a_file_written_before_opens_in_the_new_form(name):
    path = LEGACY / f"{name}.nc"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = orbatt.open_dataset(path, load=True)
    with xr.open_dataset(path, decode_times=False) as raw:
        raw = raw.load()
    assert raw.attrs["orbatt_version"] == "0.3.0.dev0" and "elapsed" not in raw.variables
    converted = 0
    for k, var in raw.variables.items():
        old = var.attrs.get("units")
        if old in LEGACY_OUTPUT:  # kernel units: scaled exactly, relabelled in SI
            assert new[k].attrs["units"] == LEGACY_OUTPUT[old][0], k
            assert np.array_equal(new[k].values, var.values * 1e6), k
            converted += 1
        elif k != "time":
            assert new[k].attrs.get("units") == old, k
            assert np.array_equal(new[k].values, var.values), k
    np.testing.assert_array_equal(new["elapsed"].values, raw["time"].values)
    if name.endswith("normalized"):
        assert converted == 0 and new["time"].dtype == np.float64 and new["elapsed"].attrs["units"] == "1"
        return
    assert converted >= 8 and new.attrs["unit_system"].startswith("SI")
    assert new["time"].dtype == np.dtype("datetime64[ns]")
    # the time form of a file written now: the same attributes and decoding
    epoch = raw.attrs.get("epoch")
    t0 = np.datetime64((epoch or NOMINAL_EPOCH).rstrip("Z"), "ns")
    assert new["time"].values[0] == t0 and new["elapsed"].attrs["units"] == "s"
    expect = {k: v for k, v in D.build.cf_time_attrs(epoch, False).items() if k not in ("units", "calendar")}
    assert new["time"].attrs == expect
    assert (new.orbatt.epoch is None) == (epoch is None)


def test_the_sweep_parameters_attribute_is_in_si():
    """``sweep_parameters`` (the distributions, JSON) gives the inertia in kg m^2, as the case
    coordinates are written (it gave the kernel's kg km^2)."""
    import json

    from orbatt.sweep import load_sweep

    sw = load_sweep(Path(__file__).resolve().parents[2] / "scenarios" / "gg-leo-dispersion.toml")
    desc = json.loads(sw.attrs()["sweep_parameters"])
    assert desc["inertia1"]["units"] == "kg m^2"
    assert desc["inertia1"]["mean"] == pytest.approx(12.0) and desc["inertia1"]["std"] == pytest.approx(0.6)
    assert desc["omega1"]["units"] == "rad s^-1"  # already SI: unchanged

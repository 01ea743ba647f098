"""Sweeps of a binary asteroid (``[orbit] provider = "coupled"``, issue 23 item 1): every case
equals ``orbatt run`` of its own scenario (``Sweep.case_text``) bit for bit, on any chunking;
the secondary's mass, inertia, the initial separation and an impulse vary by their paths;
bad paths and outputs are refused naming them; the per-case outputs hold the physics."""
from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from orbatt.errors import InputError
from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.sweep import Sweep, load_sweep, run_sweep
from orbatt.sweep.binary_chunk import libration_angle, relative_drift

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
MC = SCEN / "didymos-dimorphos-montecarlo.toml"
DD = (SCEN / "didymos-dimorphos.toml").read_text()


def _dd(t_end='"1 d"', impulse_time='"43200 s"'):
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", DD, flags=re.M)
    return re.sub(r'^time = "86400 s"', f"time = {impulse_time}", text, flags=re.M)


def _sweep(table, text=None, seed=3):
    return Sweep(Scenario(parse((text or _dd()) + "\n[sweep]\n" + table, "binary-sweep.toml")), seed=seed)


TABLE = ('samples = 4\n[sweep.parameters]\n'
         '"body.mass" = { distribution = "uniform", low = "3e9 kg", high = "6e9 kg" }\n'
         '"body.inertia[2]" = { distribution = "normal", std = "4e11 kg m2" }\n'
         '"orbit.position[0]" = { distribution = "uniform", low = "1.17 km", high = "1.21 km" }\n'
         '"orbit.impulses[0].delta_v[1]" = { values = ["-2e-3 m/s", "-3e-3 m/s"] }\n')


@pytest.fixture(scope="module")
def swept():
    sw = _sweep(TABLE)
    return sw, run_sweep(sw, scheduler="synchronous", chunk_size=3)


def test_each_case_is_its_single_run_bit_for_bit(swept):
    sw, ds = swept
    assert sw.cases == 8 and int(ds["integration_failed"].sum()) == 0
    for k in (0, 5, 7):  # cases of different chunks (chunk_size 3) and grid values
        one = Scenario(parse(sw.case_text(k), "case.toml")).run()
        assert np.array_equal(ds["q_final"].values[k], one["q"].values[-1]), k
        assert np.array_equal(ds["omega_final"].values[k], one["omega"].values[-1]), k
        assert np.array_equal(ds["position_final"].values[k], one["position"].values[-1]), k
        assert np.array_equal(ds["velocity_final"].values[k], one["velocity"].values[-1]), k
        assert np.array_equal(ds["q_primary_final"].values[k], one["q_primary"].values[-1]), k
        assert np.array_equal(ds["orbit_period_final"].values[k], one["orbit_period"].values[-1]), k
        assert ds["min_separation"].values[k] == one["separation"].values.min()
        # the case's scenario holds its sampled values, as written in the coordinates
        case = parse(sw.case_text(k), "case.toml")
        assert case.sweep is None
        assert case.mass == ds["body_mass"].values[k]
        assert case.orbit["position"][0] == ds["orbit_position_0"].values[k]
        assert case.impulses[0][1][1] * 1e3 == pytest.approx(ds["orbit_impulses_0_delta_v_1"].values[k], rel=1e-15)


def test_chunking_does_not_change_a_bit(swept):
    sw, ds = swept
    again = sw.compute(2, 6)
    for name in ("q_final", "position_final", "max_energy_error", "max_libration_angle", "orbit_a_final"):
        assert np.array_equal(again[name].values, ds[name].values[2:6]), name


def test_path_coordinates_carry_key_units_and_long_name(swept):
    _, ds = swept
    for coord, key, unit in (("body_mass", "body.mass", "kg"), ("body_inertia_2", "body.inertia[2]", "kg m^2"),
                             ("orbit_position_0", "orbit.position[0]", "km"),
                             ("orbit_impulses_0_delta_v_1", "orbit.impulses[0].delta_v[1]", "m s^-1")):
        a = ds[coord].attrs
        assert ds[coord].dims == ("case",)
        assert a["scenario_key"] == key and a["units"] == unit and key in a["long_name"]
    assert set(np.unique(ds["orbit_impulses_0_delta_v_1"].values)) == {-2e-3, -3e-3}
    assert 3e9 <= ds["body_mass"].values.min() and ds["body_mass"].values.max() <= 6e9


def test_binary_outputs_hold_the_physics(swept):
    sw, ds = swept
    q = ds["q_final"].values
    assert np.allclose(np.sqrt(np.sum(q * q, axis=1)), 1.0, atol=1e-12)
    # the coupled potential conserves H and L after the impulse: tight tolerances
    assert np.all(ds["max_energy_error"].values < 1e-9)
    assert np.all(ds["max_angular_momentum_error"].values < 1e-9)
    # the separation starts at the sampled position; the smallest distance is at most that
    assert np.all(ds["min_separation"].values <= ds["orbit_position_0"].values)
    lib = ds["max_libration_angle"].values
    assert np.all((lib > 0) & (lib < np.pi / 2))
    assert ds.attrs["sweep_cases"] == 8 and "binary" in ds.attrs and "[sweep]" in ds.attrs["scenario"]


def test_dask_workers_give_the_same_bits(swept):
    sw, ds = swept
    on_dask = run_sweep(sw, workers=2, chunk_size=2)
    for name in ds.data_vars:
        assert np.array_equal(on_dask[name].values, ds[name].values, equal_nan=True), name
    assert '"scheduler": "local cluster"' in on_dask.attrs["sweep_run"]


def test_an_interrupted_binary_sweep_resumes(swept, tmp_path):
    sw, ds = swept
    out = tmp_path / "b.nc"
    run_sweep(sw, out, scheduler="synchronous", chunk_size=3, keep_parts=True).close()
    parts = sorted((tmp_path / "b.nc.parts").glob("cases-*.nc"))
    assert len(parts) == 3
    out.unlink()
    parts[1].unlink()  # as if interrupted with one chunk missing
    again = run_sweep(sw, out, scheduler="synchronous", chunk_size=3, resume=True)
    run = json.loads(again.attrs["sweep_run"])
    assert run["chunks_reused"] == 2 and run["chunks_computed"] == 1
    for name in ds.data_vars:
        assert np.array_equal(again[name].values, ds[name].values, equal_nan=True), name
    again.close()


def test_a_stronger_retrograde_kick_shortens_the_orbit():
    sw = _sweep('[sweep.parameters]\n"orbit.impulses[0].delta_v[1]" = { values = ["0 m/s", "-2e-3 m/s", '
                '"-4e-3 m/s"] }')
    ds = sw.compute()
    a, p = ds["orbit_a_final"].values, ds["orbit_period_final"].values
    assert a[0] > a[1] > a[2] and p[0] > p[1] > p[2]


def test_libration_angle_and_drift_exact():
    # body axis 1 along the line of centres: 0; rotated 30 deg about axis 3: 30 deg (sign-free)
    c, s = np.cos(np.radians(15)), np.sin(np.radians(15))
    q = np.array([[1.0, 0, 0, 0], [c, 0, 0, s], [c, 0, 0, -s]])
    r = np.array([[2.0, 0, 0], [-3.0, 0, 0], [1.0, 0, 0]])
    assert np.allclose(libration_angle(q, r), np.radians([0.0, 30.0, 30.0]), atol=1e-15)
    assert relative_drift(np.array([5.0, 2.0, 4.0, 3.0]), 1) == 1.0  # from 2: |4 - 2| / 2
    assert relative_drift(np.array([[0.0, 0, 9], [3.0, 0, 0], [3.0, 4.0, 0], [3.0, 0, 0]]), 1) == 4.0 / 3.0


@pytest.mark.parametrize("table, where", [
    ('samples = 2\n[sweep.parameters]\n"body.density" = { distribution = "uniform", low = 1, high = 2 }',
     r'\[sweep.parameters."body.density"\]: .*body.density is not in the scenario'),
    ('samples = 2\n[sweep.parameters]\n"orbit.impulses[3].time" = { distribution = "uniform", low = 1, high = 2 }',
     r'\[sweep.parameters."orbit.impulses\[3\].time"\]: .*past its end'),
    ('samples = 2\n[sweep.parameters]\n"integration.rtol" = { values = [1e-10, 1e-11] }',
     r'\[sweep.parameters."integration.rtol"\]: \[integration\] is shared'),
    ('samples = 2\n[sweep.parameters]\ninertia1 = { distribution = "normal", std = "1e11 kg m2" }',
     r'\[sweep.parameters\] inertia1: .*"body.inertia\[0\]"'),
    ('[sweep.parameters]\n"body.mass" = { values = ["4e9 kg"] }\noutputs = ["tumbling"]',
     r"\[sweep.parameters\] outputs|\[sweep\] outputs"),
    ('pointing_axis = [1, 0, 0]\n[sweep.parameters]\n"body.mass" = { values = ["4e9 kg"] }',
     r"\[sweep\] pointing_axis: not used"),
])
def test_bad_binary_sweeps_are_refused_naming_the_key(table, where):
    with pytest.raises(ScenarioError, match=where):
        _sweep(table)


def test_conservation_needs_the_coupled_potential():
    text = _dd().replace('kind = "coupled"', 'kind = "gravity-gradient"')
    with pytest.raises(ScenarioError, match=r"\[sweep\] outputs: 'conservation': nothing is conserved"):
        _sweep('outputs = ["conservation"]\n[sweep.parameters]\n"body.mass" = { values = ["4e9 kg"] }', text)
    sw = _sweep('outputs = ["max_libration"]\n[sweep.parameters]\n"body.mass" = { values = ["4e9 kg", "5e9 kg"] }',
                text)
    ds = sw.compute()
    assert set(ds.data_vars) == {"max_libration_angle", "integration_failed"}


def test_invalid_case_is_named_or_resampled():
    # a separation below the bodies' contact, or an unbound orbit, is an invalid case
    table = ('samples = 40\n[sweep.parameters]\n'
             '"orbit.velocity[1]" = { distribution = "uniform", low = "1e-4 km/s", high = "3e-4 km/s" }\n')
    with pytest.raises(InputError, match=r"case \d+ \(orbit.velocity\[1\] = .* km/s\) makes the scenario invalid: "
                                         r"\[orbit\] velocity: the relative orbit is not bound"):
        _sweep(table)
    sw = _sweep(table.replace("samples = 40", 'samples = 40\non_invalid = "resample"'))
    assert sw.resampled > 0
    for k in range(sw.cases):
        Scenario(parse(sw.case_text(k), "case.toml"))  # every case's scenario builds


def test_shipped_montecarlo_scenario_from_the_cli(tmp_path):
    text = re.sub(r"^t_end = .*$", 't_end = "1 d"', MC.read_text(), flags=re.M)
    text = text.replace("samples = 100", "samples = 6")
    src = tmp_path / "mc.toml"
    src.write_text(text)
    out = tmp_path / "mc.nc"
    r = subprocess.run([sys.executable, "-m", "orbatt.cli", "sweep", str(src), "-o", str(out), "--scheduler",
                        "synchronous", "--chunk-size", "4"], capture_output=True, text=True, timeout=600,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "6 (body.mass" in r.stdout
    sw = load_sweep(src)
    from orbatt.dataset import open_dataset

    with open_dataset(out, load=True) as ds:
        one = Scenario(parse(sw.case_text(4), "case.toml")).run()
        assert np.array_equal(ds["q_final"].values[4], one["q"].values[-1])
        assert np.array_equal(ds["position_final"].values[4], one["position"].values[-1])
        assert int(ds["integration_failed"].sum()) == 0


def test_a_binary_run_and_sweep_are_bounded_by_their_work():
    """Binary scenarios estimate their steps as rigid ones do (the relative orbit's angle, the
    bodies' turn, or t_end / step): a run of ~1e8 steps is refused naming the key, and a sweep
    of cases times their steps above 1e9 naming ``[sweep] samples`` (binary sweeps had no
    bound)."""
    long = re.sub(r"^output_step = .*$", 'output_step = "1000 yr"', _dd(t_end='"30000 yr"'), flags=re.M)
    with pytest.raises(ScenarioError, match=r"\[primary\] omega: the primary turns .* rad over t_end = .*more "
                                            r"than 1e\+08 \(hours of computing\)"):
        Scenario(parse(long, "long.toml"))  # Didymos turns in 2.26 h, Dimorphos's orbit takes 11.9 h
    slow = long.replace('omega = ["0 rad/s", "0 rad/s", "7.72e-4 rad/s"]', 'omega = ["0 rad/s", "0 rad/s", "0 rad/s"]')
    with pytest.raises(ScenarioError, match=r"\[orbit\]: the orbit \(period .*more than 1e\+08"):
        Scenario(parse(slow, "slow.toml"))
    year = re.sub(r"^output_step = .*$", 'output_step = "10 yr"', _dd(t_end='"300 yr"'), flags=re.M)
    sc = Scenario(parse(year, "year.toml"))
    # the primary's turn over 300 years (7.3e6 rad), pi a step, as the rigid scenarios count
    assert 2e6 < sc.work_steps < 4e6
    with pytest.raises(ScenarioError, match=r"\[sweep\] samples: 2000 cases of at least .* \(days of computing\)"):
        _sweep('samples = 2000\n[sweep.parameters]\n'
               '"body.mass" = { distribution = "uniform", low = "3e9 kg", high = "6e9 kg" }\n', text=year)

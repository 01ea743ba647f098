"""The study outputs of a sweep (issue 23 item 3) against their definitions, computed here
from the single run of each case's scenario: the detumble time on a 30x finer run, the
largest dipole / control torque / wheel speed and the pointing error over the window on the
same outputs, the saturation flags against the wheels' limits; and the schema's refusals."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.sweep import Sweep
from orbatt.sweep.study import crossing_time

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
BDOT = (SCEN / "cubesat-bdot-detumble.toml").read_text()
WHEELS = re.sub(r"^t_end = .*$", 't_end = "1 orbits"', (SCEN / "lvlh-hold-wheels.toml").read_text(), flags=re.M)
BDOT_OMEGA = 'omega = ["4 deg/s", "-3 deg/s", "3 deg/s"]'
WHEELS_OMEGA = 'omega = ["0.5 deg/s", "-0.3 deg/s", "0.2 deg/s"]'


def _last_crossing_fine(t, x, level):
    """The last downward crossing of ``level`` by linear interpolation on a fine grid."""
    k = np.flatnonzero(x >= level)[-1]
    return t[k] + (x[k] - level) / (x[k] - x[k + 1]) * (t[k + 1] - t[k])


def test_crossing_time_locates_between_the_outputs():
    t = np.linspace(0.0, 10.0, 11)
    x = 5.0 - 0.37 * t + 0.01 * t**2  # a smooth decrease: the cubic is exact on a quadratic
    root = (0.37 - np.sqrt(0.37**2 - 4 * 0.01 * 2.0)) / (2 * 0.01)  # x = 3
    assert crossing_time(t, x, 3.0) == pytest.approx(root, abs=1e-12)
    assert crossing_time(t, x, 100.0) == 0.0          # below from the start
    assert np.isnan(crossing_time(t, x, 2.0))          # never below (x(10) = 2.3)
    y = x.copy()
    y[7] = 3.0  # back above: the last crossing counts
    assert t[7] < crossing_time(t, y, 2.9) <= t[8]
    y[3] = np.nan
    assert np.isnan(crossing_time(t, y, 2.9))


def test_bdot_detumble_time_dipole_and_torque_match_the_single_runs():
    table = ('\n[sweep]\noutputs = ["detumble_time", "max_dipole", "max_control_torque"]\ndetumble_rate = "0.5 deg/s"\n'
             '[sweep.parameters]\nomega1 = { values = ["-4 deg/s", "6 deg/s"] }\n')
    text = re.sub(r"^t_end = .*$", 't_end = "1 orbits"', BDOT, flags=re.M)
    sw = Sweep(Scenario(parse(text + table, "mc.toml")), seed=1)
    ds = sw.compute()
    assert ds["max_dipole"].attrs["units"] == "A m^2" and ds["detumble_time"].attrs["units"] == "s"
    for k, w1 in enumerate(("-4 deg/s", "6 deg/s")):
        case = text.replace(BDOT_OMEGA, f'omega = ["{w1}", "-3 deg/s", "3 deg/s"]')
        one = Scenario(parse(case, "case.toml")).run()
        m = np.sqrt((one["dipole_control"].values ** 2).sum(axis=-1))
        tau = np.sqrt((one["torque_control"].values ** 2).sum(axis=-1))
        assert ds["max_dipole"].values[k] == pytest.approx(m.max(), rel=1e-12)
        assert ds["max_control_torque"].values[k] == pytest.approx(tau.max(), rel=1e-12)
        fine = Scenario(parse(re.sub(r"^output_step = .*$", 'output_step = "1 s"', case, flags=re.M), "f.toml")).run()
        rate = np.sqrt((fine["omega"].values ** 2).sum(axis=-1))
        t = fine["time"].values.astype(float) if fine["time"].dtype.kind == "f" else np.arange(rate.size) * 1.0
        expect = _last_crossing_fine(t, rate, np.deg2rad(0.5))
        assert abs(ds["detumble_time"].values[k] - expect) < 1e-3, (ds["detumble_time"].values[k], expect)  # 30 s outputs


def test_wheels_settling_pointing_and_saturation_match_the_single_run():
    table = ('\n[sweep]\noutputs = ["settling_time", "pointing_error", "max_wheel_speed", "wheel_saturated"]\n'
             'settling_angle = "3 deg"\nwindow = "1000 s"\n[sweep.parameters]\n'
             'omega1 = { values = ["0.5 deg/s"] }\n')
    sw = Sweep(Scenario(parse(WHEELS + table, "w.toml")), seed=1)
    ds = sw.compute()
    one = sw.scenario.run()  # the grid's one case is the nominal scenario
    qo = one["q_orbital"].values  # the PD law's target is the orbital frame
    perr = 2 * np.arctan2(np.sqrt((qo[:, 1:] ** 2).sum(axis=-1)), np.abs(qo[:, 0]))
    t = one["time"].values.astype(float)
    w = perr[t >= t[-1] - 1000.0]
    assert ds["pointing_error_max"].values[0] == pytest.approx(w.max(), rel=1e-9)
    assert ds["pointing_error_rms"].values[0] == pytest.approx(np.sqrt(np.mean(w * w)), rel=1e-9)
    settle = ds["settling_time"].values[0]
    k = np.flatnonzero(perr >= np.deg2rad(3.0))[-1]
    assert t[k] < settle <= t[k + 1]
    speed = np.abs(one["wheel_speed"].values).max(axis=0)
    np.testing.assert_allclose(ds["max_wheel_speed"].values[0], speed, rtol=1e-9)
    limits = np.array([w.max_speed_rad_s for w in sw.scenario.body.wheels])
    torque = np.abs(one["wheel_torque"].values).max(axis=0)
    tlim = np.array([w.max_torque_n_m for w in sw.scenario.body.wheels])
    expect = (speed >= limits * (1 - 1e-9)) | (torque >= tlim * (1 - 1e-9))
    np.testing.assert_array_equal(ds["wheel_saturated"].values[0], expect.astype(np.int8))


@pytest.mark.parametrize("base, extra, match", [
    (BDOT, 'outputs = ["detumble_time"]', r"\[sweep\] detumble_rate.*missing"),
    (BDOT, 'outputs = ["max_wheel_speed"]', r"max_wheel_speed.*reaction wheels"),
    (WHEELS, 'outputs = ["max_dipole"]', r"max_dipole.*B-dot"),
    (BDOT, 'outputs = ["max_dipole"]\nsettling_angle = "2 deg"', r"settling_angle.*only used"),
    (BDOT, 'outputs = ["detumble_time"]\ndetumble_rate = "-1 deg/s"', r"detumble_rate.*positive"),
    (BDOT, 'outputs = ["max_dipole"]\nwindow = "10 s"', r"\[sweep\] window.*only used"),
])
def test_study_keys_are_checked(base, extra, match):
    text = base + f'\n[sweep]\n{extra}\n[sweep.parameters]\nomega1 = {{ values = ["0.1 deg/s"] }}\n'
    with pytest.raises(ScenarioError, match=match):
        parse(text, "bad.toml")


def test_info_prints_each_outputs_percentiles_and_nan_count():
    import xarray as xr

    from orbatt.cli import sweep_summary
    from orbatt.sweep.report import percentile_table

    rng = np.random.default_rng(3)
    t = rng.uniform(100.0, 900.0, 400)
    t[:7] = np.nan  # never detumbled
    ds = xr.Dataset({"detumble_time": ("case", t, {"units": "s"}),
                     "pointing_error_max": ("case", np.full(400, np.deg2rad(2.0)), {"units": "rad"}),
                     "integration_failed": ("case", np.zeros(400, dtype=np.int8))},
                    coords={"case": np.arange(400)}, attrs={"sweep_cases": 400})
    lines = percentile_table(ds)
    row = next(x for x in lines if x.strip().startswith("detumble_time")).split()
    expect = np.percentile(t[7:], [0, 50, 95, 99, 100])
    np.testing.assert_allclose([float(v) for v in row[1:6]], expect, rtol=1e-3)
    assert row[6] == "7" and row[7] == "s"
    row = next(x for x in lines if x.strip().startswith("pointing_error_max")).split()
    assert float(row[1]) == pytest.approx(2.0, rel=1e-3) and row[-1] == "deg"  # angles in degrees
    assert "detumble_time" in sweep_summary(ds, title="x")


def test_sweep_figures_draw_every_output_against_every_parameter():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import xarray as xr

    from orbatt.dataset.sweep_figures import draw_sweep

    rng = np.random.default_rng(5)
    ds = xr.Dataset({"detumble_time": ("case", rng.uniform(100, 900, 50), {"units": "s"}),
                     "pointing_error_max": ("case", rng.uniform(0, 0.1, 50), {"units": "rad"}),
                     "integration_failed": ("case", np.zeros(50, dtype=np.int8))},
                    coords={"case": np.arange(50), "control_gain": ("case", rng.normal(4e4, 5e3, 50),
                                                                     {"units": "A m2 s / T", "scenario_key": "control.gain"}),
                            "omega1": ("case", rng.uniform(-0.1, 0.1, 50), {"units": "rad s^-1"})})
    fig = draw_sweep(ds, "distributions")
    axes = fig.axes
    assert len(axes) == 4  # two outputs x (histogram, CDF)
    assert axes[2].get_xlabel() == "pointing_error_max [deg]"  # angles in degrees
    assert len(axes[1].get_lines()) == 4  # the CDF and p50, p95, p99
    plt.close(fig)
    fig = draw_sweep(ds, "scatter")
    assert len(fig.axes) == 4  # 2 outputs x 2 parameters
    assert fig.axes[2].get_xlabel() == "control.gain [A m2 s / T]"
    plt.close(fig)

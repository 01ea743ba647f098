"""The outputs issue 32 adds to sweeps (item 7), each against the single run's Dataset of the
case: ``slew_time`` (settling_time's computation, against the law's target) on the 90 deg
wheel slew, ``max_rate`` (variable ``max_body_rate``) and ``final_wheel_momentum`` from the
run's ``omega`` and ``wheel_momentum``, ``mode_entry_time`` from the run's own; and the
schema's refusals of a scenario without what they need."""
from __future__ import annotations

import re

import numpy as np
import pytest

from orbatt import quaternion as qt
from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.shipped import shipped_file
from orbatt.sweep import Sweep

pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")

SLEW = re.sub(r'^t_end = .*$', 't_end = "150 s"', shipped_file("cubesat-slew-wheels").read_text(), flags=re.M)
MODES = ('[control]\nperiod = "1 s"\n\n[[control.modes]]\nname = "detumble"\nlaw = "bdot"\n'
         'gain = "4e4 A m2 s / T"\nmax_dipole = "0.2 A m2"\nuntil_rate = "7 deg/s"\nhold = "10 s"\n\n'
         '[[control.modes]]\nname = "nadir"\nlaw = "pd"\ntarget = "orbital"\nkp = "2e-5 N m"\n'
         'kd = "5e-4 N m s"\nmax_torque = "1e-4 N m"\nuntil_time = "1 day"\n\n[[control.modes]]\nname = "never"\nlaw = "bdot"\n'
         'gain = "4e4 A m2 s / T"\nmax_dipole = "0.2 A m2"\n\n')


def _modes_text():
    """B-dot until |omega| has stayed below 7 deg/s for 10 s, then the orbital frame held for a
    day (so the third mode is never entered in the 300 s run)."""
    text = shipped_file("cubesat-bdot-detumble").read_text()
    text = re.sub(r'\[control\]\nlaw = "bdot"\n[^\[]*', lambda m: MODES, text)
    return re.sub(r'^t_end = .*$', 't_end = "300 s"', text, flags=re.M)


def _sweep(text, outputs, extra=""):
    table = "\n[sweep]\noutputs = [" + ", ".join(f'"{o}"' for o in outputs) + "]\n" + extra
    nominal = re.search(r'^omega = \["([^"]*)"', text, flags=re.M).group(1)
    table += f'[sweep.parameters]\nomega1 = {{ values = ["{nominal}"] }}\n'  # the one case is the nominal run
    return Sweep(Scenario(parse(text + table, "new.toml")), seed=1)


def _refused(base, outputs, match):
    text = SLEW if base == "slew" else shipped_file("cubesat-bdot-detumble").read_text()
    text += f'\n[sweep]\noutputs = {outputs}\n[sweep.parameters]\nomega1 = {{ values = ["0.1 deg/s"] }}\n'
    with pytest.raises(ScenarioError, match=match):
        parse(text, "bad.toml")


#: the PD law's target on the slew: 90 deg about body axis 3
TARGET = np.array([0.7071067811865476, 0.0, 0.0, 0.7071067811865476])


# --- slew_time
def test_slew_time_is_the_single_runs_attitude_error_to_the_target():
    sw = _sweep(SLEW, ["settling_time", "slew_time"], 'settling_angle = "1 deg"\n')
    ds = sw.compute()
    one = sw.scenario.run()
    e = qt.mul(qt.conj(TARGET)[None], one["q"].values)
    err = 2 * np.arctan2(np.linalg.norm(e[:, 1:], axis=-1), np.abs(e[:, 0]))
    t = one["elapsed"].values
    k = np.flatnonzero(err >= np.deg2rad(1.0))[-1]
    slew = ds["slew_time"].values[0]
    assert t[k] < slew <= t[k + 1] and 85.0 < slew < 110.0  # the slew settles within 1 deg in about 95 s
    assert ds["slew_time"].attrs["units"] == "s" and ds["slew_time"].attrs["settling_angle_rad"] == np.deg2rad(1.0)
    assert slew == ds["settling_time"].values[0]  # the same computation: the law holds a target
    _refused("bdot", '["slew_time"]\nsettling_angle = "1 deg"', r"slew_time.*with a target")
    _refused("slew", '["slew_time"]', r"\[sweep\] settling_angle.*missing; 'slew_time'")
    _refused("bdot", '["max_control_torque"]\nsettling_angle = "1 deg"',
             r"settling_angle.*only used with 'settling_time' or 'slew_time'")


# --- max_rate
def test_max_rate_is_the_single_runs_largest_body_rate():
    sw = _sweep(SLEW, ["max_rate"])
    ds = sw.compute()
    one = sw.scenario.run()
    assert "max_rate" not in ds  # the variable is max_body_rate: [control] max_rate is the PD's limit (1 deg/s)
    rate = np.linalg.norm(one["omega"].values, axis=-1).max()
    assert ds["max_body_rate"].attrs["units"] == one["omega"].attrs["units"] == "rad s^-1"
    assert ds["max_body_rate"].values[0] == pytest.approx(rate, rel=1e-12)
    assert np.deg2rad(0.9) < rate < np.deg2rad(1.0) * 1.05


# --- final_wheel_momentum
def test_final_wheel_momentum_is_the_single_runs():
    sw = _sweep(SLEW, ["final_wheel_momentum"])
    ds = sw.compute()
    one = sw.scenario.run()
    axes = np.array([w.axis for w in sw.scenario.body.wheels])
    h = one["wheel_momentum"].values[-1] @ axes  # sum_k h_k a_k, body axes
    var = ds["final_wheel_momentum"]
    assert var.dims == ("case", "axis") and var.attrs["units"] == one["wheel_momentum"].attrs["units"] == "kg m^2 s^-1"
    np.testing.assert_allclose(var.values[0], h, rtol=1e-12, atol=1e-15 * np.abs(h).max())
    assert np.abs(h).max() > 0
    _refused("bdot", '["final_wheel_momentum"]', r"final_wheel_momentum.*reaction wheels")


# --- mode_entry_time
def test_mode_entry_time_is_the_single_runs():
    sw = _sweep(_modes_text(), ["mode_entry_time"])
    ds = sw.compute()
    one = sw.scenario.run()
    var = ds["mode_entry_time"]
    assert var.dims == ("case", "mode_index") and var.attrs["units"] == "s"
    np.testing.assert_array_equal(var.values[0], one["mode_entry_time"].values)
    assert var.values[0, 0] == 0.0 and 0.0 < var.values[0, 1] < 300.0 and np.isnan(var.values[0, 2])
    assert ds["mode_index"].attrs["mode_names"] == "detumble nadir never"
    _refused("slew", '["mode_entry_time"]', r"mode_entry_time.*mode sequence")

"""Mode sequences of the flight software (issue 32, item 4): ``[[control.modes]]`` run in order,
a transition decided at a tick when the mode's condition has held; the Dataset's ``mode`` (CF
flags naming the modes) and ``mode_entry_time``; the sequence's state carried bitwise through
pause/resume and ensembles like every held command."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt.dataset.control import mode_column, mode_entry_times
from orbatt.dataset.timeaxis import elapsed_values
from orbatt.errors import InputError, ScenarioError
from orbatt.methods.problem import kernel_spec
from orbatt.scenario import parse
from orbatt.shipped import shipped_file
from orbatt.sweep import Sweep

MODES = """[control]
period = "1 s"

[[control.modes]]
name = "detumble"
law = "bdot"
gain = "4e4 A m2 s / T"
max_dipole = "0.2 A m2"
until_rate = "{rate}"
hold = "{hold}"

[[control.modes]]
name = "nadir"
law = "pd"
target = "orbital"
kp = "2e-5 N m"
kd = "5e-4 N m s"
max_torque = "1e-4 N m"
{extra}
"""


def _text(rate="1 deg/s", hold="20 s", extra="", t_end="2400 s", output_step="1 s"):
    text = shipped_file("cubesat-bdot-detumble").read_text()
    text = re.sub(r'\[control\]\nlaw = "bdot"\n[^\[]*', MODES.format(rate=rate, hold=hold, extra=extra) + "\n", text)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end}"', text)
    return re.sub(r'output_step = "[^"]*"', f'output_step = "{output_step}"', text)


def _expected_switch(t, w, rate, hold):
    """The first tick where |omega| < rate has held for ``hold`` (ticks = the outputs here)."""
    since = None
    for ti, wi in zip(t, w):
        if wi < rate:
            since = ti if since is None else since
            if ti - since >= hold:
                return ti
        else:
            since = None
    return None


@pytest.fixture(scope="module")
def detumble_then_nadir():
    return orbatt.Scenario(parse(_text(), "modes.toml")).run()


def test_the_switch_happens_at_the_tick_the_condition_has_held(detumble_then_nadir):
    ds = detumble_then_nadir
    t = elapsed_values(ds)
    w = np.linalg.norm(ds["omega"].values, axis=1)
    t_switch = _expected_switch(t, w, math.radians(1.0), 20.0)
    assert t_switch is not None and 100.0 < t_switch < 2000.0
    mode = ds["mode"].values
    assert mode[0] == 0 and mode[-1] == 1
    np.testing.assert_array_equal(mode, np.where(t >= t_switch, 1, 0))
    assert ds["mode"].attrs["flag_meanings"] == "detumble nadir"
    np.testing.assert_array_equal(ds["mode"].attrs["flag_values"], [0, 1])
    np.testing.assert_array_equal(ds["mode_entry_time"].values, [0.0, t_switch])
    # each mode's law acts only in its mode: the dipole is zero after the switch, the PD torque
    # (an ideal torque) is what acts then
    m = ds["dipole_control"].values
    assert np.abs(m[mode == 0]).max() > 0 and np.abs(m[mode == 1]).max() == 0


def test_the_pd_mode_points_after_the_detumble(detumble_then_nadir):
    ds = detumble_then_nadir
    q_o = ds["q_orbital"].values if "q_orbital" in ds else None
    assert q_o is not None
    err = 2 * np.arccos(np.clip(np.abs(q_o[:, 0]), 0, 1))
    assert err[-1] < math.radians(5.0)


def test_until_time_and_until_settled():
    extra = 'until_settled = "2 deg"\nhold = "30 s"\n\n[[control.modes]]\nname = "coast"\nlaw = "bdot"\n' \
            'gain = "1 A m2 s / T"\nmax_dipole = "0.001 A m2"'
    text = _text(rate="1 deg/s", hold="0 s", extra=extra, t_end="3000 s", output_step="1 s")
    text = text.replace('until_rate = "1 deg/s"\nhold = "0 s"', 'until_time = "300 s"')
    ds = orbatt.Scenario(parse(text, "modes3.toml")).run()
    t = elapsed_values(ds)
    mode = ds["mode"].values
    entry = ds["mode_entry_time"].values
    assert entry[1] == 300.0  # until_time, at the tick
    assert mode[np.searchsorted(t, 299.0)] == 0 and mode[np.searchsorted(t, 300.0)] == 1
    q_o = ds["q_orbital"].values
    err = 2 * np.arccos(np.clip(np.abs(q_o[:, 0]), 0, 1))
    if not np.isnan(entry[2]):  # settled within 2 deg for 30 s (ticks = outputs)
        k = np.searchsorted(t, entry[2])
        assert np.all(err[k - 30:k + 1] < math.radians(2.0) + 1e-9) and mode[k] == 2


@pytest.mark.parametrize("period", ["1 s", None])
def test_a_mode_entered_and_left_between_two_outputs_keeps_its_entry_time(period, monkeypatch):
    """detumble for 3 s, nadir for 2 s, then coast; outputs every 10 s: nadir lies between the
    outputs 0 and 10 s, so no output shows it, yet its entry time (3 s) is in the Dataset, the
    sweep output and the figures' intervals, and the sequence's state (each mode's entry) goes
    through pause/resume and an ensemble bitwise. With a period the switches are ticks, without
    one the located ``until_time`` knots: the same instants."""
    from orbatt.dataset.figure_data import mode_intervals

    extra = 'until_time = "2 s"\n\n[[control.modes]]\nname = "coast"\nlaw = "bdot"\n' \
            'gain = "1 A m2 s / T"\nmax_dipole = "0.001 A m2"'
    text = _text(extra=extra, t_end="60 s", output_step="10 s").replace(
        'until_rate = "1 deg/s"\nhold = "20 s"', 'until_time = "3 s"')
    if period is None:
        text = text.replace('[control]\nperiod = "1 s"\n', "[control]\n")
    sc = orbatt.Scenario(parse(text, "passed.toml"))
    ds = sc.run()
    np.testing.assert_array_equal(ds["mode"].values, [0, 2, 2, 2, 2, 2, 2])
    np.testing.assert_array_equal(ds["mode_entry_time"].values, [0.0, 3.0, 5.0])
    assert [(m.start, m.end, m.name) for m in mode_intervals(ds)] == [
        (0.0, 3.0, "detumble"), (3.0, 5.0, "nadir"), (5.0, 60.0, "coast")]
    sweep = Sweep(orbatt.Scenario(parse(
        text + '\n[sweep]\noutputs = ["mode_entry_time"]\n[sweep.parameters]\nomega1 = { values = ["0.05 deg/s"] }\n',
        "passed-sweep.toml")), seed=1).compute()
    np.testing.assert_array_equal(sweep["mode_entry_time"].values, [[0.0, 3.0, 5.0]])
    once, ens = chunked_and_ensemble_runs(sc, monkeypatch)
    np.testing.assert_array_equal(mode_entry_times(ens.command, mode_column(
        kernel_spec(sc.potential, [sc.body], sc.potential.control), len(sc.body.wheels)), 3), [[0.0, 3.0, 5.0]] * 2)


def chunked_and_ensemble_runs(sc, monkeypatch):
    """``(once, ens)``: scenario ``sc`` run once, checked bitwise against the same run paused
    after every call, and a two-member ensemble (the second member's momentum 0.9 times)
    whose first member is checked bitwise against it."""
    once = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, rtol=1e-9, atol=1e-9)
    import orbatt.propagation as prop

    monkeypatch.setattr(prop, "CHUNK_SECONDS", 1e-9)
    chunked = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, rtol=1e-9, atol=1e-9,
                               progress=lambda info: True)
    np.testing.assert_array_equal(chunked.q, once.q)
    np.testing.assert_array_equal(chunked.command, once.command)
    monkeypatch.undo()
    q = np.stack([sc.state0.q, sc.state0.q])
    Q = np.stack([sc.state0.Q, sc.state0.Q * 0.9])
    ens = orbatt.propagate(sc.body, orbatt.State(sc.body, q, Q), sc.potential, sc.times, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(ens.q[0], once.q)
    np.testing.assert_array_equal(ens.command[0], once.command)
    return once, ens


def test_pause_and_resume_and_an_ensemble_keep_the_sequence_bitwise(monkeypatch):
    chunked_and_ensemble_runs(orbatt.Scenario(parse(_text(t_end="400 s", output_step="10 s", rate="3 deg/s"),
                                                    "m.toml")), monkeypatch)


def test_mode_sequences_are_checked_where_they_enter():
    with pytest.raises(ScenarioError, match=r"\[\[control.modes\]\] 1 until_rate"):
        parse(_text(rate="-1 deg/s"), "m.toml")
    with pytest.raises(ScenarioError, match=r"\[\[control.modes\]\] 2 kp"):
        parse(_text().replace('kp = "2e-5 N m"\n', ""), "m.toml")
    with pytest.raises(ScenarioError, match=r"\[\[control.modes\]\] 1 .*no condition|modes.*no condition"):
        parse(_text().replace('until_rate = "1 deg/s"\nhold = "20 s"\n', ""), "m.toml")
    with pytest.raises(ScenarioError, match=r"\[\[control.modes\]\] 2 bogus"):
        parse(_text(extra='bogus = 1'), "m.toml")
    with pytest.raises(ScenarioError, match=r"\[control\] law"):
        parse(_text().replace('[control]\nperiod = "1 s"\n', '[control]\nperiod = "1 s"\nlaw = "pd"\n'), "m.toml")
    law = orbatt.PDControl("inertial", kp=1 * u.N * u.m, kd=1 * u.N * u.m * u.s, target_q=[1, 0, 0, 0])
    from orbatt.modes import Mode, ModeSequence

    ticking = orbatt.PDControl("inertial", kp=1 * u.N * u.m, kd=1 * u.N * u.m * u.s, target_q=[1, 0, 0, 0],
                               period=1 * u.s)
    with pytest.raises(InputError, match="no period"):  # (a sequence without one is continuous: test_mode_events)
        ModeSequence([Mode("a", ticking)], period=None)
    with pytest.raises(InputError, match="name"):
        Mode("not a name", law)
    with pytest.raises(InputError, match="repeat"):
        ModeSequence([Mode("a", law, until_time=1 * u.s), Mode("a", law)], period=1 * u.s)

"""Mode sequences without a flight-software period (issue 32, item 4;
:mod:`orbatt.core.mode_events`): continuous laws, each transition located on the continuous
solution at the instant its condition is met, checked against the integrated solution itself
(the condition's value at the located instant, from a run that ends there), against the same
switch given as a time (a knot), and against the sequence with a period (at most one period
later)."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import quaternion as qt
from orbatt.dataset.timeaxis import elapsed_values
from orbatt.errors import InputError
from orbatt.scenario import parse

from test_mode_sequences import _text, chunked_and_ensemble_runs

RATE = math.radians(1.0)


def _continuous(text):
    """The sequence of ``text`` without its period: continuous B-dot, then continuous PD."""
    assert '[control]\nperiod = "1 s"\n' in text
    return text.replace('[control]\nperiod = "1 s"\n', "[control]\n")


def _ending_at(text, t):
    """``text`` run to ``t`` (s) with one output there."""
    t = float(t)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t!r} s"', text)
    return re.sub(r'output_step = "[^"]*"', f'output_step = "{t!r} s"', text)


def _angle(qa, qb):
    return 2.0 * np.arcsin(np.minimum(1.0, np.linalg.norm(qt.mul(qt.conj(qa), qb)[..., 1:], axis=-1)))


@pytest.fixture(scope="module")
def located():
    """Detumble until |omega| < 1 deg/s has held for 20 s, then nadir: without a period."""
    text = _continuous(_text())
    return text, orbatt.Scenario(parse(text, "continuous.toml")).run()


def test_the_transition_is_the_crossing_plus_the_hold(located):
    text, ds = located
    t = elapsed_values(ds)
    entry = ds["mode_entry_time"].values
    assert entry[0] == 0.0 and 100.0 < entry[1] < 2000.0
    t_cross = entry[1] - 20.0
    # the condition's value at the located crossing, from a run that ends there (no location):
    # |omega| = until_rate to the integration's tolerance
    end = orbatt.Scenario(parse(_ending_at(text, t_cross), "to_crossing.toml")).run()
    assert elapsed_values(end)[-1] == t_cross
    w = np.linalg.norm(end["omega"].values[-1])
    assert abs(w / RATE - 1.0) < 2e-8  # (the two runs' steps differ: rtol = 1e-9 apart)
    # and |omega| stayed below it from there to the switch (the outputs between), above before
    w_out = np.linalg.norm(ds["omega"].values, axis=1)
    assert np.all(w_out[(t > t_cross) & (t <= entry[1])] < RATE)
    assert w_out[np.searchsorted(t, t_cross) - 1] > RATE
    np.testing.assert_array_equal(ds["mode"].values, np.where(t >= entry[1], 1, 0))


def test_the_same_switch_given_as_a_time_is_the_same_run(located):
    text, ds = located
    t_switch = float(ds["mode_entry_time"].values[1])
    timed = text.replace('until_rate = "1 deg/s"\nhold = "20 s"', f'until_time = "{t_switch!r} s"')
    dt = orbatt.Scenario(parse(timed, "timed.toml")).run()
    assert dt["mode_entry_time"].values[1] == t_switch
    assert _angle(ds["q"].values, dt["q"].values).max() < 1e-12
    np.testing.assert_array_equal(ds["mode"].values, dt["mode"].values)


def test_a_period_switches_at_most_one_period_later(located):
    _, ds = located
    ticked = orbatt.Scenario(parse(_text(), "ticked.toml")).run()
    t_cont = float(ds["mode_entry_time"].values[1])
    t_tick = float(ticked["mode_entry_time"].values[1])
    # the sampled B-dot's detumble differs slightly from the continuous one's: the same switch
    # within a few periods, and the continuous one is no tick
    assert abs(t_tick - t_cont) < 5.0 and t_cont != round(t_cont)


def test_conditions_that_hold_at_the_start_pass_through_the_mode():
    text = _continuous(_text(rate="20 deg/s", hold="0 s"))  # |omega(0)| = 5.8 deg/s
    ds = orbatt.Scenario(parse(text, "through.toml")).run()
    # (mode 0 lasted no time: no output shows it, yet it was entered at 0, as mode 1 was)
    np.testing.assert_array_equal(ds["mode_entry_time"].values, [0.0, 0.0])
    assert np.all(ds["mode"].values == 1)
    np.testing.assert_array_equal(ds["dipole_control"].values, 0.0)


def test_until_settled_is_located_on_the_attitude_error():
    extra = 'until_settled = "2 deg"\nhold = "0 s"\n\n[[control.modes]]\nname = "coast"\nlaw = "bdot"\n' \
            'gain = "1 A m2 s / T"\nmax_dipole = "0.001 A m2"'
    text = _continuous(_text(rate="1 deg/s", hold="0 s", extra=extra, t_end="3000 s", output_step="10 s"))
    text = text.replace('until_rate = "1 deg/s"\nhold = "0 s"', 'until_time = "300 s"')
    ds = orbatt.Scenario(parse(text, "settled.toml")).run()
    entry = ds["mode_entry_time"].values
    assert entry[1] == 300.0 and 300.0 < entry[2] < 3000.0
    end = orbatt.Scenario(parse(_ending_at(text, float(entry[2])), "to_settled.toml")).run()
    q_o = end["q_orbital"].values[-1]
    err = 2.0 * math.atan2(np.linalg.norm(q_o[1:]), abs(q_o[0]))
    assert abs(err / math.radians(2.0) - 1.0) < 2e-8


def test_pause_resume_and_members_one_by_one_are_bitwise(monkeypatch):
    sc = orbatt.Scenario(parse(_continuous(_text(t_end="900 s", output_step="30 s", rate="3 deg/s")), "m.toml"))
    once, ens = chunked_and_ensemble_runs(sc, monkeypatch)
    assert once.command[-1, 0] == 1.0  # the switch happened
    assert ens.command[1, -1, 1] != once.command[-1, 1]  # the other member switched at its own instant
    q = np.stack([sc.state0.q, sc.state0.q])
    Q = np.stack([sc.state0.Q, sc.state0.Q * 0.9])
    with pytest.raises(InputError, match="lockstep.*mode sequence"):
        orbatt.propagate(sc.body, orbatt.State(sc.body, q, Q), sc.potential, sc.times, method="dop853-lanes")


def test_a_continuous_sequence_through_the_api():
    from orbatt.modes import Mode, ModeSequence

    pd = orbatt.PDControl("inertial", kp=2e-5 * u.N * u.m, kd=5e-4 * u.N * u.m * u.s, target_q=[1, 0, 0, 0])
    seq = ModeSequence([Mode("a", pd, until_time=50 * u.s), Mode("b", pd)], period=None)
    assert seq.period is None and "continuous" in repr(seq)


def test_facets_and_a_shadow_switch_beside_the_sequence():
    """The shipped mission (drag and SRP on six facets, a conical shadow: 15 switching functions
    of the terms) without its period: the sequence's function follows the terms' (its index
    offset), the detumble's end is located between the outputs, and |omega| there is the
    threshold to the runs' reproducibility (the facets' edge-on arcs, integrated across their
    kinks while disarmed, make two runs on other output grids differ by ~1e-7)."""
    from orbatt.shipped import shipped_file

    text = shipped_file("cubesat-mission-modes").read_text()
    text = re.sub(r'\nperiod = "1 s"[^\n]*\n', "\n", text, count=1)
    text = re.sub(r't_end = "[^"]*"', 't_end = "4000 s"', text)
    ds = orbatt.Scenario(parse(text, "continuous-mission.toml")).run()
    entry = ds["mode_entry_time"].values
    t_cross = float(entry[1]) - 60.0  # (until_rate = 0.5 deg/s held for 60 s)
    assert 1000.0 < t_cross < 3900.0 and t_cross % 30.0 != 0.0
    end = orbatt.Scenario(parse(_ending_at(text, t_cross), "to_crossing.toml")).run()
    w = np.linalg.norm(end["omega"].values[-1])
    assert abs(w / math.radians(0.5) - 1.0) < 1e-5

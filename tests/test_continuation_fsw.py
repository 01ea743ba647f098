"""Continuing a run with flight software (issue 32 item 2): the controllers' discrete state
``z`` (held commands, a PD law's integral, a mode sequence's state), the wheels' momenta, the
tick grid and the step controller's memory travel with a :class:`orbatt.State`
(:meth:`orbatt.trajectory.Trajectory.state`) and with a NetCDF file (its ``continuation``
attribute, ``orbatt run --append``): a run split at a time ``T`` - on a tick or between ticks -
and continued gives the single run's outputs after ``T`` bit for bit."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

import orbatt
from orbatt.cli import main
from orbatt.dataset import open_dataset
from orbatt.errors import InputError
from orbatt.scenario import parse
from orbatt.shipped import shipped_file

PERIOD = 0.1  # s: ticks at k * 0.1 s
#: a PD law on wheels with an integral gain, at 10 Hz, in a sequence of two modes (the switch at
#: 1 s, before the splits): the shipped LVLH hold on wheels with its [control] replaced
CONTROL = """[control]
period = "0.1 s"

[[control.modes]]
name = "acquire"
law = "pd"
target = "orbital"
kp = "4e-3 N m"
kd = "8e-2 N m s"
ki = "2e-4 N m / s"
max_torque = "4e-3 N m"
actuator = "wheels"
until_time = "1 s"

[[control.modes]]
name = "hold"
law = "pd"
target = "orbital"
target_q = [0.9961946980917455, 0.0, 0.08715574274765817, 0.0]
kp = "4e-3 N m"
kd = "8e-2 N m s"
ki = "4e-4 N m / s"
max_torque = "4e-3 N m"
actuator = "wheels"
"""


def _text(t_end, output_step="0.25 s"):
    text = shipped_file("lvlh-hold-wheels").read_text()
    text = re.sub(r"\[control\]\n(?:[^\[]*\n)", CONTROL + "\n", text, count=1)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end}"', text)
    return re.sub(r'output_step = "[^"]*"', f'output_step = "{output_step}"', text)


def _scenario(t_end):
    return orbatt.Scenario(parse(_text(t_end), "fsw-split.toml"))


@pytest.fixture(scope="module")
def single():
    """The single run over 4 s (outputs every 0.25 s)."""
    sc = _scenario("4 s")
    return sc, orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, **sc.settings)


def _assert_same(a, b):
    for name in ("t", "q", "Q", "wheel_momenta", "command"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.mark.parametrize("split", [2.5, 2.25], ids=["on-a-tick", "between-ticks"])
def test_a_run_continued_from_its_state_is_the_single_run_bitwise(single, split):
    """Run to ``T`` (2.5 s is tick 25; 2.25 s lies between ticks 22 and 23), take
    ``Trajectory.state()``, propagate on: the outputs after ``T`` are the single run's, bit for
    bit (the held command is not issued again at ``T``; the integral and the mode go on)."""
    sc, one = single
    assert (split / PERIOD == round(split / PERIOD)) == (split == 2.5)
    first = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times[sc.times <= split], **sc.settings)
    state = first.state()
    assert state.t == split and state.phase == 0.0 and state.period == PERIOD
    assert state.stepper is not None and state.command.shape == one.command.shape[1:]
    rest = sc.times[sc.times >= split]
    second = orbatt.propagate(sc.body, state, sc.potential, rest, **sc.settings)
    k = np.searchsorted(one.t, split)
    _assert_same(second, _slice(one, k))
    # the run went through both modes, with the integral working: a test that can fail
    col = np.flatnonzero(np.all(one.command == np.round(one.command), axis=0) & (one.command[-1] == 1.0))
    assert col.size and one.command[0, col[0]] == 0.0
    # without the flight software's state (a new run from q, Q and the wheels), not the same run
    fresh = orbatt.State.continuing(sc.body, split, np.concatenate([state.q, state.Q, state.wheel_momenta]))
    fresh.command = None  # the commands issued anew at T, the integral and the mode from 0
    again = orbatt.propagate(sc.body, fresh, sc.potential, rest, **sc.settings)
    assert not np.array_equal(again.q[1:], one.q[k + 1:])


def _slice(tr, k):
    class Part:
        pass

    p = Part()
    for name in ("t", "q", "Q", "wheel_momenta", "command"):
        v = getattr(tr, name)
        setattr(p, name, v[k:])
    return p


def _data(path):
    with open_dataset(path, load=True) as ds:
        return {k: v.values for k, v in ds.variables.items()}, dict(ds.attrs)


@pytest.fixture(scope="module")
def single_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("fsw-single")
    (d / "full.toml").write_text(_text("4 s"))
    assert main(["run", str(d / "full.toml"), "-o", str(d / "single.nc"), "--quiet"]) == 0
    return d


@pytest.mark.parametrize("split", ["2.5 s", "2.25 s"], ids=["on-a-tick", "between-ticks"])
def test_orbatt_run_append_continues_the_file_bitwise(single_file, tmp_path, split, capsys):
    """``orbatt run`` to ``T``, then ``orbatt run --append`` of the same scenario to 4 s: the
    file equals the single run's on every variable (the mode sequence's ``mode`` and
    ``mode_entry_time``, the wheels' torques, the integral's effect), bit for bit."""
    first, full, out = tmp_path / "first.toml", single_file / "full.toml", tmp_path / "split.nc"
    first.write_text(_text(split))
    assert main(["run", str(first), "-o", str(out), "--quiet"]) == 0
    part, attrs = _data(out)
    rec = json.loads(attrs["continuation"])
    assert rec["t"] == float(split.split()[0]) and rec["phase"] == 0.0 and rec["period"] == PERIOD
    assert main(["run", str(full), "-o", str(out), "--append", "--quiet"]) == 0
    got, attrs = _data(out)
    want, attrs_single = _data(single_file / "single.nc")
    assert set(got) == set(want)
    for name in want:
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)
    # the state at the end, to continue from again (the step proposal in it is the first run's
    # initial step, capped by its shorter span and kept by every landing on a tick: not compared)
    end, end_single = json.loads(attrs["continuation"]), json.loads(attrs_single["continuation"])
    assert end["t"] == end_single["t"] == 4.0 and end["y"] == end_single["y"]
    assert attrs["scenario"] == attrs_single["scenario"] and attrs["potential"] == attrs_single["potential"]
    assert set(want["mode"].tolist()) == {0, 1} and part["time"].size < want["time"].size
    # a third --append has nothing left to run: refused, naming the fix
    capsys.readouterr()
    assert main(["run", str(full), "-o", str(out), "--append", "--quiet"]) == 2
    assert re.search(r"already ends at t = 4\.0 s.*later \[integration\] t_end", capsys.readouterr().err)


def test_append_refuses_another_run(single_file, tmp_path, capsys):
    """The file's run and the scenario must differ in ``t_end`` only."""
    other = tmp_path / "other.toml"
    other.write_text(_text("6 s").replace('kp = "4e-3 N m"', 'kp = "5e-3 N m"', 1))
    out = tmp_path / "copy.nc"
    out.write_bytes((single_file / "single.nc").read_bytes())
    assert main(["run", str(other), "-o", str(out), "--append", "--quiet"]) == 2
    assert "holds a run of another scenario" in capsys.readouterr().err


def test_append_refuses_a_state_laid_out_otherwise(single_file, tmp_path, capsys):
    """A file whose ``continuation`` holds a flight-software state of another size (a file of an
    orbatt whose mode sequence kept 4 numbers, not 4 + one entry time per mode) is refused
    before the run, naming the cause, and the file is left as it was."""
    import netCDF4

    out = tmp_path / "old.nc"
    out.write_bytes((single_file / "single.nc").read_bytes())
    with netCDF4.Dataset(out, "a") as f:
        rec = json.loads(f.getncattr("continuation"))
        rec["y"] = rec["y"][:-2]  # the two modes' entry times
        f.setncattr("continuation", json.dumps(rec))
    before = out.read_bytes()
    longer = tmp_path / "longer.toml"
    longer.write_text(_text("6 s"))
    assert main(["run", str(longer), "-o", str(out), "--append", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert re.search(r"components of the flight software's state.*laid out otherwise.*run the scenario whole", err)
    assert out.read_bytes() == before


def test_a_state_continues_from_its_own_time(single):
    sc, one = single
    state = one.state(8)  # t = 2 s: no step memory there (a fresh first step), still at its time
    assert state.t == 2.0 and state.stepper is None
    with pytest.raises(InputError, match=r"^t: the run starts at 1\.5 and state0 is the state at 2\.0"):
        orbatt.propagate(sc.body, state, sc.potential, sc.times[sc.times >= 1.5], **sc.settings)

"""A sweep builds each orbit's environment once (issue 35 item 1): the orbit (a TLE's SGP4
samples) and the field tables along it are shared by every case on that orbit whatever else
varies (a gain, a dipole), and every case still equals the single run of its scenario, bit
for bit."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import orbatt.scenario.load as load
import orbatt.torques as torques
from orbatt.scenario import Scenario, parse
from orbatt.sweep import Sweep
from orbatt.sweep.case_groups import clear_environments

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")


def _short(name, t_end):
    text = (SCEN / f"{name}.toml").read_text()
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    return re.sub(r"\n\[sweep\].*", "\n", text, flags=re.S)  # the file's own [sweep], if any, replaced


def _counted(monkeypatch, module, name):
    calls = []
    original = getattr(module, name)

    def counted(*args, **kwargs):
        calls.append(name)
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, counted)
    return calls


def _each_case_is_its_single_run(sw, ds):
    for k in range(sw.cases):
        one = Scenario(parse(sw.case_text(k), "case.toml")).run()
        assert np.array_equal(ds["q_final"].values[k], one["q"].values[-1]), k
        assert np.array_equal(ds["Q_final"].values[k], one["Q"].values[-1]), k


def test_a_gain_sweep_samples_the_environment_once(monkeypatch):
    """``control.kd`` varies: every case is its own model (its own ensemble call), and the
    density, Sun and magnetic field tables along the orbit are sampled once for all of them."""
    text = _short("nadir-hold-montecarlo", '"300 s"')
    table = ('\n[sweep]\nsamples = 4\noutputs = ["final_state", "max_control_torque"]\n[sweep.parameters]\n'
             '"control.kd" = { distribution = "uniform", low = "6e-2 N m s", high = "1.2e-1 N m s" }\n'
             '"initial.omega[0]" = { distribution = "uniform", low = "0.2 deg/s", high = "0.8 deg/s" }\n')
    sw = Sweep(Scenario(parse(text + table, "kd.toml")), seed=3)
    assert np.unique(sw.values["control.kd"]).size == 4
    clear_environments()
    tables = _counted(monkeypatch, torques, "tabulate_along_orbit")
    ds = sw.compute()
    assert len(tables) == 3  # density, Sun, field: once, not once per case
    again = sw.compute(1, 3)  # a later chunk in the same process samples nothing
    assert len(tables) == 3
    monkeypatch.undo()
    assert np.array_equal(again["q_final"].values, ds["q_final"].values[1:3])
    _each_case_is_its_single_run(sw, ds)


def test_a_tle_orbit_is_propagated_once_whatever_varies(monkeypatch):
    """A TLE scenario varying its residual dipole and a facet's drag coefficient: no SGP4 run
    and one set of tables in the sweep (the nominal scenario's orbit is every case's)."""
    text = _short("iss-tle-disturbances", '"600 s"')
    table = ('\n[sweep]\nsamples = 3\noutputs = ["final_state"]\n[sweep.parameters]\n'
             '"torques.residual_dipole[0]" = { distribution = "normal", std = "0.002 A m2" }\n'
             '"body.facets[0].drag_coefficient" = { distribution = "uniform", low = 2.0, high = 2.4 }\n')
    sw = Sweep(Scenario(parse(text + table, "tle.toml")), seed=5)
    clear_environments()
    orbits = _counted(monkeypatch, load, "build_tle_orbit")
    tables = _counted(monkeypatch, torques, "tabulate_along_orbit")
    ds = sw.compute()
    assert orbits == [] and len(tables) == 3
    monkeypatch.undo()
    _each_case_is_its_single_run(sw, ds)


def test_another_environment_is_built_for_its_own_cases(monkeypatch):
    """A swept ``[environment]`` key (the solar flux) changes the density table: each value gets
    its own environment (and the cases stay their single runs)."""
    text = _short("nadir-hold-montecarlo", '"120 s"')
    table = ('\n[sweep]\noutputs = ["final_state"]\n[sweep.parameters]\n'
             '"environment.f107" = { values = [120.0, 180.0] }\n"control.kd" = { values = ["8e-2 N m s", '
             '"1e-1 N m s"] }\n')
    sw = Sweep(Scenario(parse(text + table, "f107.toml")), seed=1)
    clear_environments()
    tables = _counted(monkeypatch, torques, "tabulate_along_orbit")
    ds = sw.compute()
    assert len(tables) == 6  # two environments of three tables, whatever kd is
    monkeypatch.undo()
    _each_case_is_its_single_run(sw, ds)


def test_the_scheduler_is_chosen_by_the_work_and_progress_counts_cases():
    """Default run_sweep (no scheduler, no workers): a small sweep stays in this process (said
    in the progress line and in sweep_run), and the progress moves case by case."""
    from orbatt.sweep import run_sweep

    text = _short("nadir-hold-montecarlo", '"60 s"')
    table = ('\n[sweep]\nsamples = 6\noutputs = ["final_state"]\n[sweep.parameters]\n'
             '"control.kd" = { distribution = "uniform", low = "6e-2 N m s", high = "1.2e-1 N m s" }\n')
    sw = Sweep(Scenario(parse(text + table, "auto.toml")), seed=2)
    seen = []
    ds = run_sweep(sw, progress=seen.append)
    run = __import__("json").loads(ds.attrs["sweep_run"])
    assert run["scheduler"] == "synchronous" and run["scheduler_choice"].startswith("auto: in-process")
    done = [i.cases_done for i in seen if i.partial]
    assert done == list(range(1, 7))  # one report per case (each its own model)
    last = seen[-1]
    assert last.cases_done == 6 and last.rate > 0 and last.eta_s == 0
    assert "6/6 cases" in last.line() and "cases/s" in last.line() and "in-process" in last.line()
    assert np.array_equal(ds["q_final"].values, sw.compute()["q_final"].values)


def test_choose_scheduler():
    from orbatt.sweep.run import CLUSTER_START_S, choose_scheduler

    # 4 cases, each its own model: 5 s for the first (the environment), then 1 s each
    marks = [(0.0, 0), (5.0, 1), (6.0, 1), (7.0, 1), (8.0, 1)]
    assert not choose_scheduler(marks, 12, 2)[0]  # 12 s here against 8 + 4 + 6 s on two workers
    assert choose_scheduler(marks, 1000, 2)[0]
    assert "1000 cases of 1 s" in choose_scheduler(marks, 1000, 2)[1]
    assert not choose_scheduler(marks, 1000, 1)[0]  # one core: nothing to gain
    assert not choose_scheduler([(0.0, 0), (4.0, 4)], 1000, 2)[0]  # one ensemble: every core already
    assert not choose_scheduler(marks, int(2 * (CLUSTER_START_S + 4)) - 2, 2)[0]

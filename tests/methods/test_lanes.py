"""The one adaptive step loop in lockstep lanes (issue 22, item 3): the group loop is the
single loop with a lane dimension, so a group of one is bitwise the single run, and every
instantiation of the single loop (Verner 9(8), extended models, every step end) reaches
ensembles: each member meets the tolerance it would meet alone and the invariants hold."""
from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from method_cases import GG, PERIOD, angle, random_data

import orbatt
from orbatt import canonical as cn
from orbatt import quaternion as qt


def assert_same(a, b):
    """Two trajectories bit for bit (times, states, wheels, counters)."""
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.Q, b.Q)
    if a.wheel_momenta is not None or b.wheel_momenta is not None:
        np.testing.assert_array_equal(a.wheel_momenta, b.wheel_momenta)
    for key in ("steps", "rejected_steps", "rhs_evaluations"):
        assert a.stats[key] == b.stats[key], key


@pytest.mark.parametrize("method", ["dop853", "vern98"])
def test_a_group_of_one_lane_is_the_single_loop_bitwise(sat, method):
    """lanes = 1: the same operations as the member alone (the single loop is the group loop with
    one lane), on the Keplerian gravity gradient in the eccentric anomaly."""
    body, _ = sat
    q, g = random_data(3, seed=11)
    states = orbatt.State.from_momentum(body, q, g)
    t = np.linspace(0.0, PERIOD, 4)
    alone = orbatt.propagate(body, states, GG, t, method=method, rtol=1e-9, atol=1e-11)
    ens = orbatt.propagate(body, states, GG, t, method=f"{method}-lanes", rtol=1e-9, atol=1e-11, lanes=1)
    assert ens.settings["independent_variable"] == "eccentric-anomaly"
    assert_same(ens, alone)


def test_vern98_lanes_agree_with_one_by_one_to_tolerance(sat):
    """Verner 9(8) in lockstep groups: each member at least as accurate as alone (the group's
    largest error controls the step), not bitwise."""
    body, _ = sat
    q, g = random_data(20, seed=4)
    states = orbatt.State.from_momentum(body, q, g)
    t = np.array([0.0, 0.5 * PERIOD, PERIOD])
    ref = orbatt.propagate(body, states, GG, t, rtol=1e-14, atol=1e-16)
    alone = orbatt.propagate(body, states, GG, t, method="vern98", rtol=1e-9, atol=1e-11)
    ens = orbatt.propagate(body, states, GG, t, method="vern98-lanes", rtol=1e-9, atol=1e-11, lanes=8)
    assert ens.method == "vern98-lanes" and ens.settings["lanes"] == 8
    err_lanes = angle(ens.q, ref.q).max(axis=1)
    err_alone = angle(alone.q, ref.q).max(axis=1)
    assert err_lanes.max() < 2e-8
    assert np.all(err_lanes <= 2.0 * err_alone + 1e-12)
    # fewer group steps than the members' steps together: they share the grid
    assert ens.stats["group_steps"] < alone.stats["steps"]


def wheels_ensemble(n, seed=2):
    """The shipped LVLH hold with PD control and three reaction wheels, ``n`` members: the
    scenario's attitude turned by up to ~6 deg and its rate perturbed by 0.1 deg/s."""
    sc = orbatt.load_scenario("lvlh-hold-wheels")
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    half = rng.uniform(0.0, 0.05, size=(n, 1))
    turn = np.concatenate([np.cos(half), np.sin(half) * axis], axis=1)
    q = qt.mul(np.broadcast_to(sc.state0.q, (n, 4)), turn)
    omega = sc.state0.omega + np.deg2rad(0.1) * rng.normal(size=(n, 3))
    return sc, orbatt.State.from_omega(sc.body, q, omega * u.rad / u.s)


@pytest.mark.parametrize("method", ["dop853", "vern98"])
def test_wheels_and_pd_control_in_lanes_agree_with_one_by_one(method):
    """An extended model (gyrostat + PD law on wheels) in lockstep groups: each member within
    the tolerance of its own run, wheels' momenta too; |q| = 1 and q.Q = 0 hold."""
    sc, states = wheels_ensemble(6)
    t = sc.times[sc.times <= 600.0]
    kw = dict(rtol=1e-10, atol=1e-10)
    alone = orbatt.propagate(sc.body, states, sc.potential, t, method=method, **kw)
    ens = orbatt.propagate(sc.body, states, sc.potential, t, method=f"{method}-lanes", lanes=4, **kw)
    ref = orbatt.propagate(sc.body, states, sc.potential, t, rtol=1e-13, atol=1e-13)
    assert ens.wheel_momenta.shape == alone.wheel_momenta.shape == (6, t.size, 3)
    err_lanes = angle(ens.q, ref.q).max(axis=1)
    err_alone = angle(alone.q, ref.q).max(axis=1)
    assert err_lanes.max() < 1e-9  # measured 6e-11 (dop853), 3e-11 (vern98)
    assert np.all(err_lanes <= 2.0 * err_alone + 1e-12)
    h_scale = np.abs(ref.wheel_momenta).max()
    assert np.abs(ens.wheel_momenta - ref.wheel_momenta).max() < 1e-9 * h_scale  # measured 4e-11
    # a real manoeuvre: every member turned by tens of degrees
    assert angle(ens.q[:, -1], ens.q[:, 0]).min() > 0.5
    np.testing.assert_allclose(qt.norm(ens.q), 1.0, atol=1e-12)
    assert np.abs(qt.dot(ens.q, ens.Q)).max() < 1e-12 * np.abs(ens.Q).max()
    # the members share the grid: fewer group steps than the members' steps together
    assert ens.stats["group_steps"] < alone.stats["steps"]


def test_free_gyrostat_in_lanes_keeps_its_space_momentum():
    """Spinning free wheels on a torque-free body (an extended model with no external torque):
    the space angular momentum ``G = 1/2 Im(Q q~)`` is an invariant in every lane."""
    wheels = [orbatt.ReactionWheel(axis, "0.01 kg m2", speed=f"{s} rpm")
              for axis, s in (((1.0, 0.0, 0.0), 300), ((0.0, 1.0, 0.0), -500), ((0.0, 0.6, 0.8), 800))]
    body = orbatt.RigidBody([12.0, 10.0, 6.0] * u.kg * u.m**2, wheels=wheels)
    rng = np.random.default_rng(3)
    n = 5
    states = orbatt.State.from_omega(body, qt.normalize(rng.normal(size=(n, 4))),
                                     0.05 * rng.normal(size=(n, 3)) * u.rad / u.s)
    t = np.linspace(0.0, 200.0, 5)
    tr = orbatt.propagate(body, states, orbatt.TorqueFree(), t, method="dop853-lanes", lanes=3, rtol=1e-12,
                          atol=1e-12)
    G = cn.space_momentum(tr.q, tr.Q)
    drift = np.abs(G - G[:, :1]).max()
    assert drift < 1e-10 * np.abs(G).max()
    # the body turned and the wheels were not idle: a real gyrostat motion
    assert angle(tr.q[:, -1], tr.q[:, 0]).min() > 0.1
    np.testing.assert_allclose(qt.norm(tr.q), 1.0, atol=1e-10)


def test_every_step_end_in_lanes_is_the_single_loops():
    """record_all reaches the group loop: one member without output times (every step end)
    through dop853-lanes is bitwise the single run."""
    sc, states = wheels_ensemble(1)
    one = orbatt.State(sc.body, states.q[0], states.Q[0])
    kw = dict(t_span=(0.0, 300.0), rtol=1e-9, atol=1e-9)
    alone = orbatt.propagate(sc.body, one, sc.potential, **kw)
    lanes = orbatt.propagate(sc.body, one, sc.potential, method="dop853-lanes", **kw)
    assert alone.t.size > 20
    assert_same(lanes, alone)


def test_lanes_warn_on_a_model_whose_torques_switch():
    """A lockstep group steps every member across every other member's facet and shadow
    switches (0.007x against 0.105x for independent members on the disturbed 3U case): the
    lanes methods say so, naming the method to use; a model without switches runs silently."""
    import re
    import warnings
    from pathlib import Path

    from orbatt.methods.dop853 import LockstepSwitchWarning
    from orbatt.scenario import Scenario, parse

    path = Path(__file__).resolve().parents[2] / "scenarios" / "cubesat-3u-disturbances.toml"
    text = re.sub(r"^t_end = .*$", 't_end = "60 s"', path.read_text(), flags=re.M)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = Scenario(parse(text, path.stem))
    q = qt.normalize(np.array([[1.0, 0.1, 0.2, 0.3], [0.5, -0.5, 0.5, 0.5]]))
    states = orbatt.State.from_omega(sc.body, q, np.full((2, 3), 0.01) * u.rad / u.s)
    with pytest.warns(LockstepSwitchWarning, match=r"'dop853-lanes'.*give method = 'dop853'"):
        orbatt.propagate(sc.body, states, sc.potential, [0.0, 60.0], method="dop853-lanes")
    with warnings.catch_warnings():
        warnings.simplefilter("error", LockstepSwitchWarning)
        orbatt.propagate(sc.body, states, orbatt.GravityGradient(sc.orbit), [0.0, 60.0], method="dop853-lanes")
        orbatt.propagate(sc.body, states, sc.potential, [0.0, 60.0], method="dop853")

"""DOP853 in the eccentric anomaly on a Keplerian orbit (``independent_variable``, issue 15):
the closed-form orbit of the anomaly form against Kepler's equation, the dynamics against the
time form, the mapping of outputs, steps, bounds and failures back to time, ensembles, and the
refusals."""
from __future__ import annotations

import math

import numpy as np
import pytest
from method_cases import GG, I_SAT, ORB, P0_TANGENT, PERIOD, Q0_PAPER, angle

import orbatt
from orbatt import quaternion as qt
from orbatt.core import kepler
from orbatt.core import model as km
from orbatt.core import potentials as kp
from orbatt.errors import InputError, IntegrationError

TIGHT = {"rtol": 1e-13, "atol": 1e-13}


@pytest.fixture(scope="module")
def sat():
    body = orbatt.RigidBody(I_SAT)
    return body, orbatt.State(body, Q0_PAPER, P0_TANGENT)


def test_orbit_in_the_anomaly_equals_the_orbit_in_time():
    """At random anomalies of eccentric orbits (e up to 0.95, several revolutions), the
    closed form gives the time whose Kepler solve returns the anomaly, and the radius, radial
    direction and velocity of the time form at that time; dt/dE = r / (n a)."""
    rng = np.random.default_rng(11)
    for e in (0.0, 0.2, 0.74, 0.95):
        orb = kepler.orbit_vector(7000.0, e, 1.1, 0.3, 2.0, 0.4, math.sqrt(398600.4418 / 7000.0**3))
        E = np.sort(rng.uniform(-20.0, 40.0, 200))
        t = kepler.times_at(E, orb)
        back, increasing = kepler.anomalies_at(t, orb)
        assert increasing
        np.testing.assert_allclose(back, E, rtol=0, atol=4e-15 * 40 / (1 - e))
        for Ei, ti in zip(E[::10], t[::10]):
            ta, dtde, r, xhat, v = kepler.kepler_anomaly(Ei, orb, True, kp.new_work())
            assert ta == ti
            work = kp.new_work()
            r_t, xhat_t, v_t = kepler.kepler_state(ti, orb, work)
            assert r == pytest.approx(r_t, rel=1e-13 / (1 - e))
            np.testing.assert_allclose(xhat, xhat_t, atol=1e-13 / (1 - e))
            np.testing.assert_allclose(v, v_t, rtol=1e-12 / (1 - e))
            assert dtde == pytest.approx(r / (orb[6] * orb[0]), rel=1e-15)
            # dt/dE against a central difference of t(E)
            h = 1e-5
            fd = (kepler.times_at(np.array([Ei + h]), orb)[0] - kepler.times_at(np.array([Ei - h]), orb)[0]) / (2 * h)
            assert dtde == pytest.approx(fd, rel=1e-8)
            # without the velocity: the same numbers, zero velocity
            tb, dtdeb, rb, xb, vb = kepler.kepler_anomaly(Ei, orb, False, kp.new_work())
            assert (tb, dtdeb, rb, xb) == (ta, dtde, r, xhat) and vb == (0.0, 0.0, 0.0)
            # from a base up to 0.125 rad away (sin, cos by angle addition): within 2 ulp of 1
            for d in (-0.125, -0.01, 1e-9, 0.07, 0.125):
                work = kp.new_work()
                kepler.kepler_anomaly(Ei - d, orb, True, work)  # sets the base
                assert work[0] == Ei - d
                tc, dtdec, rc, xc, vc = kepler.kepler_anomaly(Ei, orb, True, work)
                assert work[0] == Ei - d  # still that base
                assert abs(tc - ta) <= 4e-16 * abs(ta) + 1e-15 / orb[6]
                assert rc == pytest.approx(r, rel=4e-16 / (1 - e), abs=0)
                np.testing.assert_allclose(xc, xhat, rtol=0, atol=1e-15 / (1 - e))
                np.testing.assert_allclose(vc, v, rtol=0, atol=2e-15 / (1 - e) * np.linalg.norm(v))


def test_anomaly_and_time_forms_agree(sat):
    """The paper's Keplerian case over 2 orbits: both forms meet the tolerance against a
    tight run of the other, the state stays on the manifold, and the settings say which
    variable was used."""
    body, s0 = sat
    t = np.linspace(0.0, 2 * PERIOD, 41)
    ref_t = orbatt.propagate(body, s0, GG, t, rtol=3e-15, atol=1e-16, independent_variable="time")
    ref_e = orbatt.propagate(body, s0, GG, t, rtol=3e-15, atol=1e-16, independent_variable="eccentric-anomaly")
    assert angle(ref_t.q, ref_e.q).max() < 2e-12
    for iv in ("auto", "eccentric-anomaly"):
        tr = orbatt.propagate(body, s0, GG, t, rtol=1e-10, atol=1e-10, independent_variable=iv)
        assert tr.settings["independent_variable"] == "eccentric-anomaly"
        np.testing.assert_array_equal(tr.t, t)  # the user's times, not mapped ones
        err = angle(tr.q, ref_t.q).max()
        assert 1e-12 < err < 1e-7, err  # a real integration error, at the tolerance's level
        y = np.concatenate([tr.q, tr.Q], axis=-1)
        assert np.abs(np.linalg.norm(tr.q, axis=-1) - 1).max() < 1e-9
        assert np.abs(np.einsum("...i,...i", y[..., :4], y[..., 4:])).max() < 1e-9
    tt = orbatt.propagate(body, s0, GG, t, rtol=1e-10, atol=1e-10, independent_variable="time")
    assert tt.settings["independent_variable"] == "time"


def test_auto_keeps_time_without_a_keplerian_orbit():
    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    tr = orbatt.propagate(body, orbatt.State(body, Q0_PAPER, P0_TANGENT), orbatt.TorqueFree(), [0.0, 5.0])
    assert tr.settings["independent_variable"] == "time"


def test_step_ends_map_back_to_time(sat):
    """``t_span`` mode records every step end: their times come back increasing, in time,
    ending exactly on t_end, and the states there are those of a time-form run at them."""
    body, s0 = sat
    T = 0.7 * PERIOD
    tr = orbatt.propagate(body, s0, GG, t_span=(0.0, T), **TIGHT)
    assert tr.settings["independent_variable"] == "eccentric-anomaly"
    assert tr.t[0] == 0.0 and tr.t[-1] == T and np.all(np.diff(tr.t) > 0)
    assert tr.t.size == tr.stats["steps"] + 1
    check = orbatt.propagate(body, s0, GG, tr.t, **TIGHT, independent_variable="time")
    assert angle(tr.q, check.q).max() < 1e-10


def test_outputs_closer_than_the_anomaly_resolves(sat):
    """Consecutive float times far out (1e9 s: 1e6 rad of anomaly, whose ulp is 20x the
    anomaly of one ulp of time) can map to one anomaly: ``auto`` then integrates in time,
    ``eccentric-anomaly`` refuses."""
    body, s0 = sat
    t = [1e9]
    for _ in range(200):
        t.append(np.nextafter(t[-1], np.inf))
    E, increasing = kepler.anomalies_at(np.array(t), ORB)
    assert not increasing
    tv = np.array([0.0, *t[:40]])
    with pytest.raises(InputError, match="too close together"):
        orbatt.propagate(body, s0, GG, tv, independent_variable="eccentric-anomaly", max_steps=1)
    with pytest.raises(IntegrationError) as err:  # auto: the time form starts (and stops at max_steps)
        orbatt.propagate(body, s0, GG, tv, max_steps=1)
    assert err.value.trajectory.settings["independent_variable"] == "time"
    tr = orbatt.propagate(body, s0, GG, [0.0, 100.0, 200.0])
    assert tr.settings["independent_variable"] == "eccentric-anomaly"


def test_max_step_bounds_the_time_step(sat):
    body, s0 = sat
    tr = orbatt.propagate(body, s0, GG, t_span=(0.0, 0.3 * PERIOD), rtol=1e-6, atol=1e-6, max_step=7.0)
    assert tr.settings["independent_variable"] == "eccentric-anomaly"
    assert np.diff(tr.t).max() <= 7.0 * (1 + 1e-12)
    free = orbatt.propagate(body, s0, GG, t_span=(0.0, 0.3 * PERIOD), rtol=1e-6, atol=1e-6)
    assert np.diff(free.t).max() > 20.0  # the bound is what made the steps short


def test_first_step_is_in_time(sat):
    """A first step given in time is the first step taken, in time (mapped with dt/dE at the start)."""
    body, s0 = sat
    tr = orbatt.propagate(body, s0, GG, t_span=(0.0, 100.0), rtol=1e-3, atol=1e-3, step=0.25)
    assert tr.t[1] == pytest.approx(0.25, rel=1e-6)  # mapped at the start: exact to first order


def test_ensembles_in_the_anomaly(sat):
    """Ensemble members stepped one by one are bitwise the single runs; the lockstep lanes
    agree with them to the tolerance."""
    body, s0 = sat
    rng = np.random.default_rng(5)
    qs = qt.normalize(Q0_PAPER + 0.05 * rng.normal(size=(5, 4)))
    Ps = [2.0 * qt.mul(q, np.concatenate([[0.0], [0.0004, -0.0003, 0.0007]])) for q in qs]
    states = orbatt.State(body, qs, np.array(Ps))
    t = np.linspace(0.0, PERIOD, 5)
    ens = orbatt.propagate(body, states, GG, t, rtol=1e-11, atol=1e-11)
    lanes = orbatt.propagate(body, states, GG, t, method="dop853-lanes", rtol=1e-11, atol=1e-11, lanes=4)
    assert ens.settings["independent_variable"] == lanes.settings["independent_variable"] == "eccentric-anomaly"
    for k in range(5):
        one = orbatt.propagate(body, orbatt.State(body, qs[k], Ps[k]), GG, t, rtol=1e-11, atol=1e-11)
        np.testing.assert_array_equal(ens.q[k], one.q)
        assert angle(lanes.q[k], one.q).max() < 1e-8


def test_failure_is_reported_in_time(sat):
    """A run stopped by max_steps reports the time it reached (not the anomaly), and its
    partial result ends there."""
    body, s0 = sat
    t = np.linspace(0.0, 2 * PERIOD, 9)
    with pytest.raises(IntegrationError) as err:
        orbatt.propagate(body, s0, GG, t, rtol=1e-12, atol=1e-12, max_steps=50)
    part = err.value.trajectory
    reached = err.value.t
    assert 0 < part.t[-1] <= reached < 2 * PERIOD
    assert f"t = {reached!r}" in str(err.value)
    # the time reached is the time of the anomaly reached: a time-form run to it agrees
    # with the anomaly form's own run to it
    a = orbatt.propagate(body, s0, GG, [0.0, reached], rtol=1e-12, atol=1e-12)
    b = orbatt.propagate(body, s0, GG, [0.0, reached], rtol=1e-12, atol=1e-12, independent_variable="time")
    assert angle(a.q[-1], b.q[-1]) < 1e-9


def test_progress_is_in_time(sat):
    body, s0 = sat
    seen = []
    orbatt.propagate(body, s0, GG, [0.0, 2 * PERIOD], rtol=1e-12, atol=1e-12, independent_variable="eccentric-anomaly",
                     progress=lambda info: seen.append(info))
    assert seen and all(0.0 <= info.t <= info.t_end == 2 * PERIOD for info in seen)
    assert all(info.fraction == pytest.approx(info.t / info.t_end) for info in seen)
    assert seen[-1].t == pytest.approx(2 * PERIOD, rel=1e-14)


def test_refusals(sat):
    body, s0 = sat
    with pytest.raises(InputError, match="independent_variable: 'anomaly' is not one of"):
        orbatt.propagate(body, s0, GG, [0.0, 10.0], independent_variable="anomaly")
    free = orbatt.RigidBody([1.25, 1.0, 0.75])
    with pytest.raises(InputError, match="needs a Keplerian orbit"):
        orbatt.propagate(free, orbatt.State(free, Q0_PAPER, P0_TANGENT), orbatt.TorqueFree(), [0.0, 5.0],
                         independent_variable="eccentric-anomaly")


def test_kernel_model_of_the_anomaly_is_only_the_drivers():
    """The evaluation kernels keep the time: the anomaly kind is made by the driver only."""
    terms, params, table = km.from_spec(GG.kind, GG.params, GG.table)
    assert int(terms[0, km.KIND]) == km.ORBIT_KEPLER
    assert ORB.size == kepler.ORB_SIZE


SCEN = __import__("pathlib").Path(__file__).resolve().parents[2] / "scenarios"


@pytest.mark.parametrize("value, used", [(None, "eccentric-anomaly"), ("auto", "eccentric-anomaly"),
                                         ("eccentric-anomaly", "eccentric-anomaly"), ("time", "time")])
def test_scenario_key(tmp_path, value, used):
    """``[integration] independent_variable`` reaches the integrator, and ``"time"`` gives the
    time form's numbers exactly."""
    import json
    import warnings

    src = (SCEN / "paper-keplerian.toml").read_text().replace('t_end = "2 orbits"', 't_end = "0.2 orbits"')
    if value is not None:
        src = src.replace("[integration]", f'[integration]\nindependent_variable = "{value}"')
    p = tmp_path / "a.toml"
    p.write_text(src)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = orbatt.load_scenario(p).run()
        ref = orbatt.load_scenario(p).run(independent_variable=used)
    assert json.loads(ds.attrs["method_settings"])["independent_variable"] == used
    np.testing.assert_array_equal(ds["q"].values, ref["q"].values)


@pytest.mark.parametrize("scenario, value, message", [
    ("paper-keplerian", '"bogus"', "'bogus' is not one of 'auto', 'eccentric-anomaly', 'time'"),
    ("paper-torque-free", '"eccentric-anomaly"', "'eccentric-anomaly' needs a Keplerian orbit .* has no orbit"),
    ("sso-j2-rebound", '"eccentric-anomaly"', "'eccentric-anomaly' needs a Keplerian orbit .* provider = 'rebound'"),
])
def test_scenario_key_refusals(tmp_path, scenario, value, message):
    from orbatt.scenario import ScenarioError

    p = tmp_path / "a.toml"
    p.write_text((SCEN / f"{scenario}.toml").read_text().replace(
        "[integration]", f"[integration]\nindependent_variable = {value}"))
    with pytest.raises(ScenarioError, match=r"\[integration\] independent_variable: " + message):
        orbatt.load_scenario(p)

"""DOP853 lands on the knots of the environment tables and on a sampled orbit's samples
(``orbatt.core.model.next_breakpoint``): both are piecewise polynomials in time whose
derivatives jump at the knots, and a step across a knot loses DOP853's order. Knots are found
in time and in the eccentric anomaly, steps land on them, outputs stay the user's, and the
magnetic torque and the TLE orbit's gravity gradient converge with the tolerance."""
from __future__ import annotations

import math

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time
from method_cases import angle

import orbatt
from orbatt import quaternion as qt
from orbatt.core import kepler
from orbatt.core import model as km
from orbatt.environment.magnetic import DipoleField
from orbatt.orbits import KeplerOrbit
from orbatt.torques import EnvironmentTorques

EPOCH = Time("2025-03-20T00:00:00", scale="utc")


@pytest.fixture(scope="module")
def case():
    orbit = KeplerOrbit(6778.137 * u.km, 0.0005, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, true_anomaly=0 * u.deg,
                        epoch=EPOCH)
    T = orbit.period_value
    body = orbatt.RigidBody([0.0387, 0.0387, 0.0067] * u.kg * u.m**2)
    env = EnvironmentTorques(orbit, T * u.s, residual_dipole=[0.005, 0.0, 0.002] * u.A * u.m**2,
                             magnetic_field=DipoleField(EPOCH))
    rng = np.random.default_rng(7)
    q = qt.normalize(rng.normal(size=(4, 4)))
    w = rng.normal(size=(4, 3)) * math.radians(0.05)  # slow: the tables' knots set the error
    return body, env, orbatt.State.from_omega(body, q, w * u.rad / u.s), T


def _knots(env):
    terms, params, table = env.kernel_model()
    rows = [j for j in range(1, terms.shape[0]) if terms[j, km.R1] - terms[j, km.R0] >= 2]
    assert rows
    return np.unique(np.concatenate([table[terms[j, km.R0]:terms[j, km.R1], 0] for j in rows]))


def test_next_breakpoint_in_time_and_in_the_anomaly(case):
    body, env, _, T = case
    terms, params, table = env.kernel_model()
    knots = _knots(env)
    for t in (-1.0, 0.0, knots[3], 0.5 * (knots[7] + knots[8]), knots[-2]):
        expect = knots[knots > t][0]
        assert km.next_breakpoint(t, terms, params, table) == expect
    assert km.next_breakpoint(knots[-1], terms, params, table) == np.inf
    # the same knots as anomalies in the anomaly form
    an = terms.copy()
    an[0, km.KIND] = km.ORBIT_KEPLER_ANOMALY
    orb = params[terms[0, km.P0]:terms[0, km.P1]]
    E5, _ = kepler.anomalies_at(knots[5:6], orb)
    got = km.next_breakpoint(float(kepler.anomalies_at(knots[4:5], orb)[0][0]), an, params, table)
    assert got == E5[0]
    # a model without tables has none
    gg = orbatt.GravityGradient(env.orbit).kernel_model()
    assert km.next_breakpoint(0.0, *gg) == np.inf


@pytest.mark.parametrize("iv", ["time", "eccentric-anomaly"])
def test_steps_land_on_the_knots_and_outputs_stay_the_users(case, iv):
    body, env, states, T = case
    s0 = orbatt.State(body, states.q[0], states.Q[0])
    tr = orbatt.propagate(body, s0, env, t_span=(0.0, 0.25 * T), rtol=1e-8, atol=1e-8, independent_variable=iv)
    knots = _knots(env)
    inside = knots[(knots > 0) & (knots < 0.25 * T)]
    # every knot is a step end (to the rounding of the anomaly's mapping back to time)
    gap = np.abs(tr.t[None, :] - inside[:, None]).min(axis=1)
    assert gap.max() <= 1e-9 * T
    grid = np.linspace(0.0, 0.25 * T, 7)
    tg = orbatt.propagate(body, s0, env, grid, rtol=1e-8, atol=1e-8, independent_variable=iv)
    np.testing.assert_array_equal(tg.t, grid)


def test_the_magnetic_torque_converges_with_the_tolerance(case):
    """One orbit of four slowly turning cubesats under a residual dipole: the error against a
    tight run falls with the tolerance as it should, 450-1000 rtol (measured 4.5e-6, 7.3e-8, 1.0e-9
    rad at rtol 1e-8, 1e-10, 1e-12), in both forms and in the lockstep lanes: the tables' knots
    (600 s apart, landed on) cost no order. (With the 20 s cubic splines the tables were before
    issue 23, and no landing: 1.8e-7 .. 1.6e-5 rad, and still 6e-8 at rtol 1e-12.)"""
    body, env, states, T = case
    ref = orbatt.propagate(body, states, env, [0.0, T], rtol=3e-15, atol=1e-18).q[:, -1]
    for rtol in (1e-8, 1e-12):
        for iv in ("time", "eccentric-anomaly"):
            q = orbatt.propagate(body, states, env, [0.0, T], rtol=rtol, atol=rtol, independent_variable=iv).q[:, -1]
            assert angle(q, ref).max() < 3e3 * rtol, (iv, rtol)
        lanes = orbatt.propagate(body, states, env, [0.0, T], method="dop853-lanes", rtol=rtol, atol=rtol, lanes=4)
        assert angle(lanes.q[:, -1], ref).max() < 3e3 * rtol, ("lanes", rtol)


def test_a_sampled_orbits_samples_are_breakpoints():
    """A TLE orbit is sampled (SGP4, 128 samples per orbit) and interpolated by quintic Hermite
    pieces, C2 in time: steps land on every sample, and the attitude converges with the
    tolerance (before: 5.6e-7 rad at rtol 1e-8, 1.0e-8 at 1e-12 against a tight run)."""
    sc = orbatt.load_scenario("iss-tle-gravity-gradient")
    terms, params, table = sc.potential.kernel_model()
    assert terms[0, km.KIND] == km.ORBIT_SAMPLED
    samples = table[terms[0, km.R0]:terms[0, km.R1], 0]
    for t in (samples[0], samples[5], 0.5 * (samples[7] + samples[8])):
        assert km.next_breakpoint(t, terms, params, table) == samples[samples > t][0]
    assert km.next_breakpoint(samples[-1], terms, params, table) == np.inf
    span = (0.0, sc.times[sc.times.size // 4])
    ends = orbatt.propagate(sc.body, sc.state0, sc.potential, t_span=span, rtol=1e-8, atol=1e-8)
    inside = samples[(samples > span[0]) & (samples < span[1])]
    assert inside.size > 20 and np.isin(inside, ends.t).all()
    t = sc.times[:: sc.times.size // 12]
    tight = orbatt.propagate(sc.body, sc.state0, sc.potential, t, rtol=1e-13, atol=1e-13)
    for rtol in (1e-6, 1e-8, 1e-10):
        tr = orbatt.propagate(sc.body, sc.state0, sc.potential, t, rtol=rtol, atol=rtol)
        assert angle(tr.q, tight.q).max() < 1e-12, rtol

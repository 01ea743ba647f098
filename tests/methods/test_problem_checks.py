"""orbatt.methods.problem: the checks of propagate's arguments - clear errors, before any
integration - and the times they give."""
from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from method_cases import GG, Spec, angle, random_states

import orbatt
from orbatt import analytic
from orbatt.errors import InputError

def _bad_cases(body, s0):
    return [
        (dict(t=[0, 1], method="rk5"), "method: 'rk5' is not a known method"),
        (dict(t=[0, 1], method="splitting4"), "step: method 'splitting4' has a fixed step"),
        (dict(t=[0, 1], method="splitting4", step=0.0), "step: 0.0 must be a finite positive number"),
        (dict(t=[0, 1], method="rk4", step=-1.0), "step: -1.0 must be"),
        (dict(t=[0, 1], method="rk4", step=float("nan")), "step: nan must be"),
        (dict(t_span=(1.0, 0.0)), "t_span: the end 0.0 is not after the start 1.0"),
        (dict(t_span=(1.0, 1.0)), "t_span: the end 1.0 is not after the start 1.0"),
        (dict(t=[0.0, 2.0, 1.0]), "t: output times must increase strictly; t[2] = 1.0 follows t[1] = 2.0"),
        (dict(t=[0.0, float("inf")]), "t: "),
        (dict(), "t: give the output times t"),
        (dict(t=[0, 5], t_span=(0, 2)), "t: the output times [0.0 .. 5.0] leave t_span"),
        (dict(t=[0, 1], rtol=1e-17), "rtol: 1e-17 is below"),
        (dict(t=[0, 1], rtol=-1.0), "rtol: -1.0 must be"),
        (dict(t=[0, 1], rtol=1e5), "rtol: 100000.0 is above 0.1"),
        (dict(t=[0, 1], rtol=1e308), "rtol: 1e+308 is above 0.1"),
        (dict(t=[0, 1], atol=1e10), "atol: 10000000000.0 is above 1: |q| = 1"),
        (dict(t=[0, 1], method="rk4", step=0.1, rtol=1e5), "rtol: 100000.0 is above 0.1"),
        (dict(t=[0, 1], atol="x"), "atol: 'x' is not a number"),
        (dict(t=[0, 1], max_steps=0), "max_steps: 0 is not a positive integer"),
        (dict(t=[0, 1], progress="yes"), "progress: expected None, True or a callable"),
        (dict(t=[0, 1], kinetic="axes"), "kinetic: method 'dop853' takes no option 'kinetic'"),
        (dict(t=[0, 1], method="splitting2", step=0.1, kinetic="diagonal"), "kinetic: 'diagonal' is not one of"),
        (dict(t=[0, 1e9], method="splitting2", step=1.0, max_steps=1000), "step: 1.0 needs 1000000000 steps"),
        (dict(t=[0, 1] * u.s), "t: "),
    ]


def test_bad_inputs_are_refused_with_clear_messages(free):
    body, s0 = free
    for kw, msg in _bad_cases(body, s0):
        with pytest.raises(InputError) as exc:
            orbatt.propagate(body, s0, orbatt.TorqueFree(), **kw)
        assert msg in str(exc.value), (kw, str(exc.value))


def test_bad_objects_are_refused(free, sat):
    body, s0 = free
    with pytest.raises(InputError, match="state0: expected an orbatt.State"):
        orbatt.propagate(body, (s0.q, s0.Q), orbatt.TorqueFree(), [0, 1])
    with pytest.raises(InputError, match="body: expected a RigidBody"):
        orbatt.propagate("body", s0, orbatt.TorqueFree(), [0, 1])
    with pytest.raises(InputError, match="potential: expected an orbatt Potential"):
        orbatt.propagate(body, s0, None, [0, 1])
    with pytest.raises(InputError, match="different units"):
        orbatt.propagate(sat[0], s0, orbatt.TorqueFree(), [0, 1])
    # non-finite state (State refuses it itself; a tampered one is caught here too)
    with pytest.raises(InputError):
        orbatt.State(body, [np.nan, 0, 0, 1], [0, 0, 0, 0])
    bad = orbatt.State(body, s0.q, s0.Q)
    bad.Q = bad.Q.copy()
    bad.Q[1] = np.inf
    with pytest.raises(InputError, match="state0: contains non-finite values"):
        orbatt.propagate(body, bad, orbatt.TorqueFree(), [0, 1])
    states = random_states(body, 3)
    bodies = [body, body]
    with pytest.raises(InputError, match="do not broadcast"):
        orbatt.propagate(bodies, states, orbatt.TorqueFree(), [0, 1])
    with pytest.raises(InputError, match="an ensemble has no common step grid"):
        orbatt.propagate(body, states, orbatt.TorqueFree(), t_span=(0, 1))


# ---------------------------------------------------------------------------------------
# Times


def test_start_time_and_outputs_inside_t_span(free):
    body, s0 = free
    t = [2.0, 3.0]
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, t_span=(1.0, 4.0), rtol=1e-12)
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, np.array(t) - 1.0)
    assert angle(tr.q, qref).max() < 1e-10
    # the epoch may be any time: a shifted start gives the same motion
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), [100.0, 101.0, 102.0], rtol=1e-12)
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, np.array([0.0, 1.0, 2.0]))
    assert angle(tr.q, qref).max() < 1e-10


def test_quantity_times(sat):
    body, s0 = sat
    a = orbatt.propagate(body, s0, GG, [0.0, 10.0] * u.min, rtol=1e-10)
    b = orbatt.propagate(body, s0, GG, [0.0, 600.0], rtol=1e-10)
    np.testing.assert_array_equal(a.t, [0.0, 600.0])
    np.testing.assert_array_equal(a.q, b.q)
    c = orbatt.propagate(body, s0, GG, [0.0, 600.0], method="splitting4", step=1 * u.min)
    assert c.settings["step"] == 60.0
    assert angle(c.q[-1], b.q[-1]) < 1e-6


def test_propagation_stays_inside_the_potentials_time_span(sat):
    """A potential defined on a limited span (a sampled orbit) says so with ``time_span``;
    propagate refuses to leave it before integrating."""
    body, s0 = sat
    assert orbatt.TorqueFree().time_span is None
    limited = Spec(GG.kind, GG.params)
    limited.time_span = (0.0, 600.0)
    orbatt.propagate(body, s0, limited, [0.0, 600.0], rtol=1e-8)
    for kw in (dict(t=[0.0, 601.0]), dict(t=[-1.0, 600.0]), dict(t_span=(0.0, 700.0))):
        with pytest.raises(InputError, match=r"leaves the span \[0.0, 600.0\] of the sampled orbit"):
            orbatt.propagate(body, s0, limited, **kw)


def test_gravity_gradient_time_span_is_its_orbits(sat):
    pytest.importorskip("rebound")
    from orbatt.orbits import KeplerOrbit, ReboundOrbit

    body, s0 = sat
    kepler = KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg, true_anomaly=0 * u.deg,
                         body_radius=None)
    assert kepler.time_span is None and orbatt.GravityGradient(kepler).time_span is None
    sampled = ReboundOrbit(kepler, 600 * u.s)
    gg = orbatt.GravityGradient(sampled)
    assert gg.time_span == sampled.time_span == (0.0, sampled.t_last) == (0.0, float(gg.params[2]))
    with pytest.raises(InputError, match="leaves the span"):
        orbatt.propagate(body, s0, gg, [0.0, sampled.t_last + 1.0])

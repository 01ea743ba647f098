"""The energy and torque variables of an ensemble's Dataset: one compiled call over the members
(orbatt.potentials.evaluate_members) gives each member the numbers of its own evaluation, as a
Dataset of that member alone; a potential evaluated by other means gets a call per member."""
import warnings

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.potentials import (GravityGradient, Potential, energy_and_torques, evaluate_members, kernel_backed,
                               member_body)
from orbatt.trajectory import Trajectory

ENERGY_AND_TORQUES = ("potential_energy", "energy", "torque")


def _members(sc, n, t, rtol=1e-10, bodies=None, seed=3):
    """An ensemble of ``n`` members around the scenario's state (attitudes turned by up to ~0.2
    rad), propagated over ``t``: the Trajectory and each member's own one."""
    rng = np.random.default_rng(seed)
    q0 = qt.normalize(sc.state0.q + 0.1 * rng.normal(size=(n, 4)))
    g0 = np.broadcast_to(sc.state0.g, (n, 3))  # the body momentum of the scenario's state
    body = sc.body if bodies is None else bodies
    states = orbatt.State.from_momentum(sc.body, q0, g0)
    tr = orbatt.propagate(body, states, sc.potential, t, rtol=rtol, atol=rtol)
    alone = [Trajectory(body=(sc.body if bodies is None else bodies[e]), potential=sc.potential, t=tr.t, q=tr.q[e],
                        Q=tr.Q[e], inertia=None, method=tr.method) for e in range(n)]
    return tr, alone


def _same_member_values(ens, alone, e, names):
    for name in names:
        if name in alone:
            assert np.array_equal(ens[name].values[e], alone[name].values), (name, e)


def test_gravity_gradient_members_with_their_own_inertia():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = orbatt.load_scenario("paper-keplerian")
    inertias = [[400.0, 500.0, 600.0], [410.0, 500.0, 590.0], [380.0, 520.0, 600.0]]
    bodies = [orbatt.RigidBody(I * u.kg * u.km**2) for I in inertias]
    t = np.linspace(0.0, 600.0, 7)
    tr, alone = _members(sc, 3, t, bodies=bodies)
    ens = D.to_dataset(tr)
    for e in range(3):
        _same_member_values(ens, D.to_dataset(alone[e]), e, ENERGY_AND_TORQUES + ("kinetic_energy",))
        U, tau = energy_and_torques(sc.potential, bodies[e], tr.t, tr.q[e], True)
        assert np.array_equal(ens["potential_energy"].values[e], U * 1e6)  # kernel units -> J
    # the potential energy is the gravity gradient's: (3 GM / 2 r^3) x_B . I x_B
    r = ens["r"].values
    xb = qt.rotate_inv(tr.q, qt.rotate(ens["p"].values, [1.0, 0.0, 0.0]))
    I = np.asarray(inertias)[:, None, :]
    U = 1.5 * sc.orbit.gm / r**3 * np.sum(xb * I * xb, axis=-1)  # kg km^2 s^-2
    assert ens["potential_energy"].attrs["units"] == "J"
    assert np.allclose(ens["potential_energy"].values, U * 1e6, rtol=1e-12, atol=0)


def test_environment_torques_members_term_by_term():
    sc = orbatt.load_scenario("cubesat-3u-disturbances")
    t = sc.times[:6]
    tr, alone = _members(sc, 4, t)
    ens = D.to_dataset(tr)
    names = [f"torque_{n}" for n in sc.potential.term_names]
    assert len(names) >= 3 and all(n in ens for n in names)
    for e in range(4):
        _same_member_values(ens, D.to_dataset(alone[e]), e, ENERGY_AND_TORQUES + tuple(names))
    # the total is the sum of the terms
    total = sum(ens[n].values for n in names)
    assert np.allclose(ens["torque"].values, total, rtol=1e-12, atol=1e-20)


class _Doubled(GravityGradient):
    """A gravity gradient evaluated by other means than its kernel model (here: twice its
    energy): ensembles must call it member by member."""

    def evaluate(self, body, t, q):
        U, G, tau = super().evaluate(body, t, q)
        return 2.0 * U, 2.0 * G, 2.0 * tau


def test_a_potential_evaluated_otherwise_is_called_per_member():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = orbatt.load_scenario("paper-keplerian")
    doubled = _Doubled(sc.orbit)
    assert not getattr(type(doubled).evaluate, "kernel_backed", False)
    assert getattr(GravityGradient.evaluate, "kernel_backed", False) and Potential.term_torques.kernel_backed
    t = np.linspace(0.0, 300.0, 4)
    q = qt.normalize(np.random.default_rng(5).normal(size=(3, 4, 4)))
    inertia = np.array([[400.0, 500.0, 600.0], [410.0, 500.0, 590.0], [380.0, 520.0, 600.0]])
    U2, tau2 = evaluate_members(doubled, sc.body, inertia, t, q, True)
    U1, tau1 = evaluate_members(sc.potential, sc.body, inertia, t, q, True)
    assert np.array_equal(U2, 2.0 * U1) and np.array_equal(tau2, 2.0 * tau1)
    for e in range(3):
        assert np.array_equal(U1[e], energy_and_torques(sc.potential, member_body(sc.body, inertia[e]), t, q[e],
                                                        False)[0])


def test_members_are_checked_as_one_evaluation():
    """What evaluate refuses (a body of the other unit system) is refused for the ensemble."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = orbatt.load_scenario("paper-keplerian")
    plain = orbatt.RigidBody([1.0, 2.0, 3.0])
    q = np.tile([1.0, 0.0, 0.0, 0.0], (2, 3, 1))
    with pytest.raises(orbatt.InputError, match="body: plain-number inertia"):
        evaluate_members(sc.potential, plain, np.ones((2, 3)), np.zeros(3), q, False)


def test_kernel_backed_marks_the_method():
    class Mine(Potential):
        @kernel_backed
        def evaluate(self, body, t, q):
            return super().evaluate(body, t, q)

    assert Mine.evaluate.kernel_backed and Mine.term_torques.kernel_backed


def test_a_kernel_specification_without_evaluate_is_refused_by_name():
    """propagate takes any object with a kernel kind, params and table; its Dataset needs the
    potential energy: a clear refusal, not an AttributeError."""
    class Spec:
        kind, params, table = orbatt.TorqueFree.kind, orbatt.TorqueFree.params, orbatt.TorqueFree.table

    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    tr = orbatt.propagate(body, orbatt.State.from_omega(body, [1.0, 0.0, 0.0, 0.0], [0.1, 0.2, 0.3]), Spec(),
                          [0.0, 1.0])
    with pytest.raises(orbatt.InputError, match=r"potential: Spec has no evaluate\(body, t, q\).*orbatt Potential"):
        D.to_dataset(tr)

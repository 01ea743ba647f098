"""The control law as a peer of the potential (issue 22, item 2): ``propagate(..., control=law)``
assembles the same kernel model as a law carried by ``EnvironmentTorques(control=)``, needs no
environment object where the law reads nothing along the orbit, and is refused, naming what is
missing, where it does."""
from __future__ import annotations

import json

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt import quaternion as qt
from orbatt.environment.magnetic import DipoleField
from orbatt.errors import InputError

from control_support import angle, rotation

INERTIA = np.array([12.0, 10.0, 6.0]) * u.kg * u.m**2
EPOCH = Time("2024-03-01T00:00:00", scale="utc")
ORBIT = orbatt.KeplerOrbit(6878.137 * u.km, 0.001, 97.4 * u.deg, 30 * u.deg, 0 * u.deg, epoch=EPOCH)
T_END = 1800.0


def _pd(target="orbital", **kw):
    return orbatt.PDControl(target, kp="5e-4 N m", kd="8e-2 N m s", max_torque="2e-4 N m", **kw)


def _start(body):
    return orbatt.state_from_orbital(body, ORBIT, rotation([1, 0, 0], 0.4), np.deg2rad([0.2, -0.3, 0.1]) * u.rad / u.s)


def test_a_law_beside_the_potential_is_the_law_carried_by_it_bitwise():
    """PD towards the orbital frame under the plain gravity gradient, given beside it, equals
    the same law carried by the environment torques (same model rows, same numbers), and the
    Dataset records the law (``torque_control``, the ``potential`` attribute's ``control``)."""
    body = orbatt.RigidBody(INERTIA)
    t = np.linspace(0.0, T_END, 181)
    pd = _pd()
    peer = orbatt.propagate(body, _start(body), orbatt.GravityGradient(ORBIT), t, rtol=1e-10, atol=1e-12, control=pd)
    env = orbatt.EnvironmentTorques(ORBIT, T_END * u.s, gravity_gradient=True, control=pd)
    carried = orbatt.propagate(body, _start(body), env, t, rtol=1e-10, atol=1e-12)
    assert peer.control is pd and carried.control is pd
    assert np.array_equal(peer.q, carried.q) and np.array_equal(peer.Q, carried.Q)
    # the law acted: the error to the orbital frame fell from 23 deg
    err = np.rad2deg(angle(orbatt.orbital_attitude(ORBIT, peer.t, peer.q), np.array([1.0, 0.0, 0.0, 0.0])))
    assert err[0] > 20.0 and err[-1] < 0.5 * err[0]
    ds = orbatt.to_dataset(peer)
    assert json.loads(ds.attrs["potential"])["control"]["law"] == "pd"
    tau = ds["torque_control"].values
    assert np.abs(tau).max() > 1e-5   # N m: the saturated start
    ds_env = orbatt.to_dataset(carried)
    assert np.array_equal(tau, ds_env["torque_control"].values)


def test_an_inertial_target_needs_no_orbit():
    """PD towards an inertial attitude on a free body (``TorqueFree()``): the body settles on
    the target (the error decays as exp(-kd t / 2I): ~1e-5 rad after 6000 s) and comes to rest;
    |q| = 1 and q.Q = 0 hold along the way."""
    body = orbatt.RigidBody(INERTIA)
    target = rotation([0, 0, 1], 0.6)
    pd = orbatt.PDControl("inertial", kp="2e-3 N m", kd="5e-2 N m s", target_q=target)
    s0 = orbatt.State.from_omega(body, rotation([1, 1, 0], 0.5), np.deg2rad([0.5, -0.2, 0.3]) * u.rad / u.s)
    t = np.linspace(0.0, 6000.0, 301)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, rtol=1e-11, atol=1e-13, control=pd)
    err = angle(tr.q, np.broadcast_to(target, tr.q.shape))
    assert err[0] > 0.3 and err[-1] < 1e-4
    assert np.allclose(np.linalg.norm(tr.q, axis=1), 1.0, atol=1e-10)
    assert np.abs(qt.dot(tr.q, tr.Q)).max() < 1e-12
    w = np.linalg.norm(orbatt.to_dataset(tr)["omega"].values, axis=1)
    assert w[0] > 5e-3 and w[-1] < 1e-6   # rad/s


def test_a_law_given_twice_or_of_the_wrong_type_is_refused():
    body = orbatt.RigidBody(INERTIA)
    pd = _pd()
    env = orbatt.EnvironmentTorques(ORBIT, T_END * u.s, gravity_gradient=True, control=pd)
    with pytest.raises(InputError, match="already carries a control law"):
        orbatt.propagate(body, _start(body), env, [0.0, 10.0], control=_pd())
    with pytest.raises(InputError, match="control: expected one of PDControl, BDotControl, ModeSequence, got str"):
        orbatt.propagate(body, _start(body), orbatt.GravityGradient(ORBIT), [0.0, 10.0], control="pd")


def test_a_law_that_reads_what_the_potential_lacks_is_refused_naming_it():
    body = orbatt.RigidBody(INERTIA)
    bdot = orbatt.BDotControl("2e4 A m2 s / T", "0.2 A m2")
    with pytest.raises(InputError, match="reads the magnetic field along the orbit, which GravityGradient does not "
                                         "sample"):
        orbatt.propagate(body, _start(body), orbatt.GravityGradient(ORBIT), [0.0, 10.0], control=bdot)
    s0 = orbatt.State.from_omega(body, [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0] * u.rad / u.s)
    with pytest.raises(InputError, match="reads the orbit .* and TorqueFree has none"):
        orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, 10.0], control=_pd())
    # with the field sampled by the environment torques, B-dot beside them runs as carried
    env = orbatt.EnvironmentTorques(ORBIT, 600 * u.s, gravity_gradient=False, magnetic_field=DipoleField(EPOCH))
    t = np.linspace(0.0, 600.0, 61)
    peer = orbatt.propagate(body, _start(body), env, t, rtol=1e-10, atol=1e-12, control=bdot)
    env2 = orbatt.EnvironmentTorques(ORBIT, 600 * u.s, gravity_gradient=False, magnetic_field=DipoleField(EPOCH),
                                     control=bdot)
    carried = orbatt.propagate(body, _start(body), env2, t, rtol=1e-10, atol=1e-12)
    assert np.array_equal(peer.q, carried.q) and np.array_equal(peer.Q, carried.Q)
    w = np.linalg.norm(orbatt.to_dataset(peer)["omega"].values, axis=1)
    assert w[-1] < w[0]   # detumbling

"""Bad input at the control API: each raises :class:`orbatt.errors.InputError` with a
one-line message that starts with the argument's name."""
from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt.errors import InputError

ORBIT = orbatt.KeplerOrbit(6878.137 * u.km, 0.0, 97.4 * u.deg, 30 * u.deg, 0 * u.deg)
INERTIA = [12.0, 10.0, 6.0] * u.kg * u.m**2
PD = dict(kp="5e-4 N m", kd="8e-2 N m s")


def wheel(axis=(1.0, 0.0, 0.0), **kw):
    return orbatt.ReactionWheel(axis, "0.01 kg m2", **kw)


def raises(name, fn, *args, **kwargs):
    with pytest.raises(InputError) as info:
        fn(*args, **kwargs)
    message = str(info.value)
    assert message.startswith(f"{name}:") and "\n" not in message, message
    return message


@pytest.mark.parametrize("name, kwargs", [
    ("kp", dict(kp="-5e-4 N m", kd="1e-2 N m s")),
    ("kd", dict(kp="5e-4 N m", kd="-1e-2 N m s")),
    ("max_torque", dict(max_torque="-2e-4 N m", **PD)),
    ("max_torque", dict(max_torque="0 N m", **PD)),
    ("kp", dict(kp="5e-4 N", kd="1e-2 N m s")),                 # wrong dimension
    ("kd", dict(kp="5e-4 N m", kd=0.01)),                        # no unit
    ("target", dict(target="moon", **PD)),
    ("actuator", dict(actuator="thrusters", **PD)),
    ("target_q", dict(target="inertial", **PD)),                # inertial without target_q
    ("target_q", dict(target="inertial", target_q=[1.0, 0.1, 0.0, 0.0], **PD)),   # not unit
    ("target_q", dict(target="orbital", target_q=[0.0, 0.0, 0.0], **PD)),
    ("target_q", dict(target="sun", target_axis=[0, 0, 1], target_q=[1, 0, 0, 0], **PD)),
    ("target_axis", dict(target="sun", **PD)),
    ("target_axis", dict(target="sun", target_axis=[0, 0, 2], **PD)),
    ("target_axis", dict(target="orbital", target_axis=[0, 0, 1], **PD)),
])
def test_pd_control_refuses(name, kwargs):
    raises(name, orbatt.PDControl, **kwargs)


@pytest.mark.parametrize("name, args", [
    ("gain", ("-2e4 A m2 s / T", "0.1 A m2")),
    ("max_dipole", ("2e4 A m2 s / T", "-0.1 A m2")),
    ("max_dipole", ("2e4 A m2 s / T", "0 A m2")),
    ("gain", ("2e4 A m2", "0.1 A m2")),
])
def test_bdot_control_refuses(name, args):
    raises(name, orbatt.BDotControl, *args)


@pytest.mark.parametrize("name, args, kwargs", [
    ("axis", ([1.0, 1.0, 0.0], "0.01 kg m2"), {}),                # not a unit vector
    ("axis", ([1.0, 0.0], "0.01 kg m2"), {}),
    ("inertia", ([1.0, 0.0, 0.0], "-0.01 kg m2"), {}),
    ("max_torque", ([1.0, 0.0, 0.0], "0.01 kg m2"), dict(max_torque="-5e-3 N m")),
    ("max_speed", ([1.0, 0.0, 0.0], "0.01 kg m2"), dict(max_speed="-6000 rpm")),
    ("speed", ([1.0, 0.0, 0.0], "0.01 kg m2"), dict(speed="7000 rpm", max_speed="6000 rpm")),
    ("speed", ([1.0, 0.0, 0.0], "0.01 kg m2"), dict(speed="-7000 rpm", max_speed="6000 rpm")),
])
def test_reaction_wheel_refuses(name, args, kwargs):
    raises(name, orbatt.ReactionWheel, *args, **kwargs)


def test_speed_at_max_speed_is_accepted():
    assert wheel(speed="6000 rpm", max_speed="6000 rpm").speed_rad_s == pytest.approx(200 * np.pi)


def test_wheels_on_a_body():
    raises("wheels", orbatt.RigidBody, INERTIA, wheels=["x"])
    raises("wheels", orbatt.RigidBody, [1.0, 2.0, 2.5], wheels=[wheel()])      # dimensionless body
    # rotors heavier than the body about an axis
    raises("wheels", orbatt.RigidBody, INERTIA, wheels=[orbatt.ReactionWheel([1, 0, 0], "13 kg m2")])


def propagate(body, potential, method="dop853"):
    s0 = orbatt.State.from_omega(body, [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.001] * u.rad / u.s)
    return orbatt.propagate(body, s0, potential, np.linspace(0.0, 10.0, 3), method=method)


def test_actuator_wheels_needs_wheels_spanning_three_axes():
    pd = orbatt.PDControl(actuator="wheels", **PD)
    env = orbatt.EnvironmentTorques(ORBIT, 10 * u.s, control=pd)
    parallel = orbatt.RigidBody(INERTIA, wheels=[wheel(), wheel((-1.0, 0.0, 0.0)), wheel((0.0, 0.0, 1.0))])
    message = raises("[[body.wheels]] axis", propagate, parallel, env)
    assert "uncontrollable" in message
    raises("actuator", propagate, orbatt.RigidBody(INERTIA), env)
    # the same parallel wheels are fine with an ideal actuator (they are free rotors then)
    ideal = orbatt.EnvironmentTorques(ORBIT, 10 * u.s, control=orbatt.PDControl(**PD))
    assert propagate(parallel, ideal).wheel_momenta.shape == (3, 3)


def test_environment_control_needs_its_fields():
    raises("magnetic_field", orbatt.EnvironmentTorques, ORBIT, 10 * u.s,
           control=orbatt.BDotControl("2e4 A m2 s / T", "0.1 A m2"))
    raises("epoch", orbatt.EnvironmentTorques, ORBIT, 10 * u.s,
           control=orbatt.PDControl("sun", target_axis=[0, 0, 1], **PD))
    raises("control", orbatt.EnvironmentTorques, ORBIT, 10 * u.s, control="pd")


@pytest.mark.parametrize("method", ["rk4", "splitting4"])
def test_methods_without_the_extended_state_refuse_wheels_and_control(method):
    body = orbatt.RigidBody(INERTIA, wheels=[wheel()])
    message = raises("method", propagate, body, orbatt.TorqueFree(), method=method)
    assert "dop853" in message
    env = orbatt.EnvironmentTorques(ORBIT, 10 * u.s, control=orbatt.PDControl(**PD))
    raises("method", propagate, orbatt.RigidBody(INERTIA), env, method=method)


def test_pd_params_refuses_a_target_quaternion_that_is_not_unit():
    """The kernel's PD row: an orbital or inertial target needs a unit quaternion (an all-zero
    one would silently turn the proportional term into nonsense)."""
    from orbatt.core import control as kc

    for target in (kc.TARGET_ORBITAL, kc.TARGET_INERTIAL):
        with pytest.raises(ValueError, match="unit quaternion"):
            kc.pd_params(target, 1.0, 1.0, np.inf, (0.0, 0.0, 0.0, 0.0))
    c = slice(kc.PD.c, kc.PD.c + 4)
    assert kc.pd_params(kc.TARGET_ORBITAL, 1.0, 1.0, np.inf)[c].tolist() == [1.0, 0.0, 0.0, 0.0]
    assert kc.pd_params(kc.TARGET_SUN, 1.0, 1.0, np.inf, (0.0, 0.0, 1.0))[c].tolist() == [0.0, 0.0, 1.0, 0.0]


def test_a_law_changed_after_a_run_runs_with_its_new_gains():
    """The PD law's model row is kept between runs, keyed on its settings: a changed gain
    makes a new row (the old row ran silently with the old gains)."""
    law = orbatt.PDControl("inertial", target_q=[1.0, 0.0, 0.0, 0.0], **PD)
    body = orbatt.RigidBody(INERTIA)
    s0 = orbatt.State.from_omega(body, [0.9, 0.1, 0.3, 0.3], [0.0, 0.0, 0.01] * u.rad / u.s)
    t = np.linspace(0.0, 60.0, 3)
    before = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, control=law).q[-1]
    law.kp = 4.0 * law.kp
    after = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, control=law).q[-1]
    fresh = orbatt.propagate(body, s0, orbatt.TorqueFree(), t,
                             control=orbatt.PDControl("inertial", target_q=[1.0, 0.0, 0.0, 0.0], kp="2e-3 N m",
                                                      kd="8e-2 N m s")).q[-1]
    assert not np.array_equal(before, after)
    np.testing.assert_array_equal(after, fresh)

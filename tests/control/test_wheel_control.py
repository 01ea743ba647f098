"""PD feedback made by reaction wheels (``actuator = "wheels"``, ``docs/design.md`` §10): the wheels'
torque is internal, so the total angular momentum G stays without external torque; under the
gravity gradient the wheels store its secular part; the motor torque and speed limits hold."""
from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import canonical as cn
from orbatt import quaternion as qt

from control_support import angle, outputs, rotation

INERTIA = np.array([12.0, 10.0, 6.0])   # kg m^2, rotors locked
ORBIT = orbatt.KeplerOrbit(6878.137 * u.km, 0.0, 97.4 * u.deg, 30 * u.deg, 0 * u.deg)
PERIOD, N = ORBIT.period_value, ORBIT.n_value
#: three orthogonal wheels and a skewed one
AXES = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
AXES = AXES / np.linalg.norm(AXES, axis=1)[:, None]
MOTOR = 8e-5                            # N m
Q_BO = qt.mul(rotation([1, 0, 0], 0.5), rotation([0, 1, 0], -0.4))   # 37 deg off O


def wheeled(rotor, max_speed=None, max_torque=MOTOR):
    """The satellite with four wheels of axial moment ``rotor`` (kg m^2), at rest relative to the
    body, motor limit ``max_torque`` (N m) and speed limit ``max_speed`` (rad/s)."""
    wheels = [orbatt.ReactionWheel(a, rotor * u.kg * u.m**2, 0.0 * u.rad / u.s,
                                   max_torque=None if max_torque is None else max_torque * u.N * u.m,
                                   max_speed=None if max_speed is None else max_speed * u.rad / u.s) for a in AXES]
    return orbatt.RigidBody(INERTIA * u.kg * u.m**2, wheels=wheels)


def run(body, pd, q_bo, w_bo, t_end, gravity_gradient):
    env = orbatt.EnvironmentTorques(ORBIT, t_end * u.s, gravity_gradient=gravity_gradient, control=pd)
    s0 = orbatt.state_from_orbital(body, ORBIT, q_bo, np.asarray(w_bo) * u.rad / u.s)
    t = np.linspace(0.0, t_end, int(t_end / 10.0) + 1)
    return orbatt.propagate(body, s0, env, t, method="dop853", rtol=1e-11, atol=1e-11), env


def wheel_speeds(body, tr, out):
    """The rotors' speeds relative to the body, ``h_k / Iw_k - a_k . omega`` (rad/s)."""
    rotor = np.array([w.inertia for w in body.wheels])
    return tr.wheel_momenta / rotor - out.omega @ AXES.T


@pytest.mark.parametrize("case", ["slew", "saturating"])
def test_wheel_pd_conserves_the_total_momentum_and_respects_the_limits(case):
    """No external torque (gravity gradient off): G (inertial) constant to round-off while the
    wheels slew the body by 37 deg. ``slew``: 0.01 kg m^2 rotors, the body at rest relative to
    O; the pointing settles at 0.63 deg, not 0: the momentum left in the wheels turns in body
    axes once per orbit and takes the steady torque ``n o3 x h``. ``saturating``: 2e-4 kg m^2
    rotors limited to 3000 rpm against 0.54 deg/s of tumbling: every motor reaches its torque
    limit and every rotor its speed limit (the body keeps tumbling).

    The speed limit stops the motor, not the rotor: with ``u_k = 0`` the axial momentum
    ``h_k`` is frozen but the relative speed ``h_k / Iw - a_k . omega`` still follows the body
    rate, so the bound is ``max_speed + max |omega|``. Measured: G 3e-15 and 5e-15 relative;
    speeds up to ``max_speed (1 + 8.9e-6)`` (the bound: 2.2e-5)."""
    pd = orbatt.PDControl("orbital", kp="5e-4 N m", kd="8e-2 N m s", max_torque="2e-4 N m", actuator="wheels")
    if case == "slew":
        body, w_bo, max_speed = wheeled(0.01), np.zeros(3), None
    else:
        max_speed = 3000 * 2 * np.pi / 60
        body, w_bo = wheeled(2e-4, max_speed), np.deg2rad([0.3, -0.4, 0.2])
    tr, env = run(body, pd, Q_BO, w_bo, 2 * PERIOD, gravity_gradient=False)
    G = cn.space_momentum(tr.q, tr.Q)
    drift = np.linalg.norm(G - G[0], axis=1).max() / np.linalg.norm(G[0])
    out = outputs(tr, env)
    speed = wheel_speeds(body, tr, out)
    print(f"{case}: G drift {drift:.3g}, speeds/max_speed {np.abs(speed).max(axis=0) / (max_speed or 1)}")
    assert drift < 1e-12
    # the body feels -A u: the commanded torque, within the motor limits
    np.testing.assert_allclose(out.tau, -out.u @ AXES, rtol=0, atol=1e-15)
    assert np.abs(out.u).max() <= MOTOR * (1 + 1e-12)
    assert np.isclose(np.abs(out.u).max(), MOTOR, rtol=1e-12)
    if case == "slew":
        err = np.rad2deg(angle(orbatt.orbital_attitude(ORBIT, tr.t, tr.q), np.array([1.0, 0.0, 0.0, 0.0])))
        assert err[tr.t >= PERIOD].max() < 1.0 and np.ptp(err[tr.t >= 1.5 * PERIOD]) < 1e-6
    else:
        assert np.all(np.isclose(np.abs(out.u).max(axis=0), MOTOR, rtol=1e-12))
        top = np.abs(speed).max(axis=0)
        assert np.all(top >= max_speed * (1 - 1e-6))
        assert np.all(top <= max_speed + np.abs(out.omega).max())


def test_wheels_store_the_secular_gravity_gradient_momentum():
    """The target pitched by 20 deg about the orbit normal (``target_q`` relative to O): the
    gravity-gradient torque ``3 n^2 r^ x I r^`` is constant along body axis 3, which stays along
    the orbit normal, so the wheels' momentum along it grows linearly at that rate and G grows
    along o3 (inertial); held on O itself (the equilibrium) the wheels store nothing secular.
    Measured: slope of h3 2.3755e-6 N m against the torque at the target 2.3622e-6 (0.56 %; the
    body sits 0.14 deg off the target) and at the actual attitude to 1e-8."""
    pd_args = dict(kp="2e-3 N m", kd="0.16 N m s", max_torque="2e-4 N m", actuator="wheels")
    q_off = rotation([0, 0, 1], np.deg2rad(20.0))
    pd = orbatt.PDControl("orbital", target_q=q_off, **pd_args)
    body = wheeled(0.01)
    tr, env = run(body, pd, q_off, np.zeros(3), 3 * PERIOD, gravity_gradient=True)
    out = outputs(tr, env)
    late = tr.t >= PERIOD
    slope = np.polyfit(tr.t[late], out.h[late], 1)[0]                      # N m, body axes
    r_hat = qt.rotate_inv(q_off, np.array([1.0, 0.0, 0.0]))
    tau_target = 3 * N**2 * np.cross(r_hat, INERTIA * r_hat)
    r_body = qt.rotate_inv(tr.q, ORBIT.radial_direction(tr.t))
    tau_actual = (3 * N**2 * np.cross(r_body, INERTIA * r_body))[late].mean(axis=0)
    print(f"h slope {slope} N m; gravity gradient at the target {tau_target}, at the attitude {tau_actual}")
    assert abs(tau_target[2]) > 1e-6 and np.allclose(tau_target[:2], 0.0, atol=1e-20)
    np.testing.assert_allclose(slope, tau_actual, rtol=0, atol=1e-5 * abs(tau_target[2]))
    np.testing.assert_allclose(slope, tau_target, rtol=0, atol=0.02 * abs(tau_target[2]))
    # a build-up, not an oscillation: h3 grows by the torque times the time
    assert out.h[-1, 2] - out.h[0, 2] > 0.9 * tau_target[2] * tr.t[-1]
    # inertial G grows at the same rate along the orbit normal
    o3 = qt.rotate(ORBIT.orbital_quaternion(0.0), np.array([0.0, 0.0, 1.0]))
    G = cn.space_momentum(tr.q, tr.Q) * 1e6
    np.testing.assert_allclose(np.polyfit(tr.t[late], G[late], 1)[0], slope[2] * o3, rtol=0,
                               atol=1e-5 * abs(slope[2]))
    # the equilibrium target: nothing secular
    tr0, env0 = run(body, orbatt.PDControl("orbital", **pd_args), [1.0, 0.0, 0.0, 0.0], np.zeros(3), 3 * PERIOD,
                    gravity_gradient=True)
    assert np.abs(outputs(tr0, env0).h).max() < 1e-3 * out.h[-1, 2]

"""Per-axis limits with a full inertia tensor (issue 32 item 6): a PD law's ``max_torque`` (ideal,
wheels), the magnetorquers' ``max_dipole``, B-dot's ``max_dipole`` and momentum dumping's
``dump_max_dipole`` clip each axis of the user's body frame B, while orbatt integrates in the
tensor's principal frame P (``orbatt.core.control.clip_in_body_axes``).

Oracles: the ideal-torque PD law is integrated again by scipy's ``solve_ivp`` as Euler's
equations in B with the torque clipped per body axis (``I_B dw/dt = tau - w x I_B w``); the
magnetorquers' dipole is recomputed from the Dataset's state and the field model in B; every
law's command (Dataset, body axes) stays within its limit on each body axis and reaches it,
although its principal components do not (so a clip along P would differ).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time
from scipy.integrate import solve_ivp

import orbatt
from orbatt import quaternion as qt
from orbatt.dataset.timeaxis import elapsed_values
from orbatt.environment.magnetic import DipoleField

I_P = np.array([0.10, 0.12, 0.05])  # kg m^2
R_Q = qt.normalize(np.array([0.95, 0.15, -0.2, 0.18]))  # a rotation of about 37 deg
R_M = qt.to_matrix(R_Q)
TENSOR = R_M @ np.diag(I_P) @ R_M.T
TENSOR = 0.5 * (TENSOR + TENSOR.T)
TARGET = qt.normalize(np.array([0.9, 0.3, -0.2, 0.25]))
Q0 = np.array([1.0, 0.0, 0.0, 0.0])
KP, KD, TMAX = 4e-3, 1.4e-2, 1e-3  # N m, N m s, N m: saturated over the first tens of seconds

EPOCH = Time("2024-06-01T00:00:00", scale="utc")
ORBIT = orbatt.KeplerOrbit(6878.137 * u.km, 0.001, 60 * u.deg, 30 * u.deg, 0 * u.deg, epoch=EPOCH)
FIELD = DipoleField(EPOCH)


def _within_and_reaching(x, limit, what):
    """Each body-axis component of ``x (N, 3)`` within ``limit`` (to round-off) and the limit
    reached; its principal components (a clip along P's axes would hold those) exceed it."""
    assert np.abs(x).max() <= limit * (1 + 1e-12), what
    assert np.abs(x).max() >= limit * (1 - 1e-12), what
    assert np.abs(x @ R_M).max() > 1.05 * limit, what  # x_P = R^T x_B


def _body(wheels=()):
    return orbatt.RigidBody(TENSOR * u.kg * u.m**2, wheels=list(wheels))


def _pd(**kw):
    return orbatt.PDControl("inertial", kp=KP * u.N * u.m, kd=KD * u.N * u.m * u.s, target_q=TARGET,
                            max_torque=TMAX * u.N * u.m, **kw)


def _euler_in_b(t):
    """The PD law with ideal torque clipped per body axis, as Euler's equations in B (scipy)."""
    Ii = np.linalg.inv(TENSOR)

    def rhs(_, y):
        q, w = y[:4] / np.linalg.norm(y[:4]), y[4:]
        e = qt.mul(qt.conj(TARGET), q)
        tau = np.clip(-KP * np.sign(e[0]) * e[1:] - KD * w, -TMAX, TMAX)
        return np.concatenate([0.5 * qt.mul(q, np.concatenate([[0.0], w])), Ii @ (tau - np.cross(w, TENSOR @ w))])

    out = [np.concatenate([Q0, np.zeros(3)])]
    for a, b in zip(t[:-1], t[1:]):  # integrate to each output (no dense output: design.md section 4)
        s = solve_ivp(rhs, (a, b), out[-1], method="DOP853", rtol=1e-12, atol=1e-14)
        out.append(s.y[:, -1])
    return np.array(out)


def test_ideal_torque_clips_each_body_axis_as_euler_equations_in_b():
    """120 s of a 37 deg-rotated tensor slewing 57 deg under max_torque = 1 mN m: the Dataset's
    torque_control (B) stays within the limit on each body axis and reaches it; the attitude and
    rate agree with scipy's integration of Euler's equations in B with the clipped torque (the
    measured difference ~1e-11 rad)."""
    t = np.linspace(0.0, 120.0, 25)
    body = _body()
    st = orbatt.State.from_omega(body, Q0, [0.0, 0.0, 0.0] * u.rad / u.s)
    tr = orbatt.propagate(body, st, orbatt.TorqueFree(), t, control=_pd(), rtol=1e-12, atol=1e-14)
    ds = orbatt.to_dataset(tr)
    _within_and_reaching(ds["torque_control"].values, TMAX, "torque_control")
    ref = _euler_in_b(t)
    assert float(np.max(qt.angle_between(ds["q"].values, ref[:, :4] / np.linalg.norm(ref[:, :4], axis=1,
                                                                                        keepdims=True)))) < 1e-8
    assert np.abs(ds["omega"].values - ref[:, 4:]).max() < 1e-9
    assert float(qt.angle_between(ds["q"].values[-1], TARGET)) < math.radians(5.0)  # the law acts


def test_wheels_and_an_integral_term_clip_each_body_axis():
    """The same slew on four wheels (the body feels -A u = the clipped command) with an integral
    gain and a 0.1 s period: the torque stays within max_torque per body axis and reaches it;
    the integral, held in body components, winds up on no saturated body axis (the attitude
    still converges)."""
    axes = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    wheels = [orbatt.ReactionWheel(a, "2e-4 kg m2") for a in axes]
    body = _body(wheels)
    st = orbatt.State.from_omega(body, Q0, [0.0, 0.0, 0.0] * u.rad / u.s)
    law = _pd(actuator="wheels", ki=2e-5 * u.N * u.m / u.s, period=0.1 * u.s)
    tr = orbatt.propagate(body, st, orbatt.TorqueFree(), np.linspace(0.0, 300.0, 601), control=law, rtol=1e-10,
                          atol=1e-13)
    ds = orbatt.to_dataset(tr)
    _within_and_reaching(ds["torque_control"].values, TMAX, "torque_control")
    assert float(qt.angle_between(ds["q"].values[-1], TARGET)) < math.radians(0.5)
    G = ds["G"].values  # the wheels' torques are internal
    assert np.abs(G - G[0]).max() < 1e-9 * np.abs(G).max() + 1e-15


def _environment(law, t_end):
    return orbatt.EnvironmentTorques(ORBIT, t_end * u.s, gravity_gradient=False, magnetic_field=FIELD, control=law)


@pytest.mark.parametrize("period", [None, 2.0])
def test_magnetorquers_clip_each_body_axis(period):
    """A PD law on magnetorquers (max_dipole = 0.02 A m^2, clipped most of the run): the
    Dataset's dipole_control (B) stays within the limit per body axis and reaches it; without a
    period it is ``clip_B((B_B x tau_B) / |B|^2)`` recomputed from the Dataset's attitude, rate
    and the field model (to 1e-9 of the limit)."""
    mmax, t_end = 0.02, 600.0
    law = orbatt.PDControl("inertial", kp=1e-5 * u.N * u.m, kd=1e-3 * u.N * u.m * u.s, target_q=TARGET,
                           actuator="magnetorquers", max_dipole=mmax * u.A * u.m**2,
                           period=None if period is None else period * u.s)
    body = _body()
    st = orbatt.State.from_omega(body, Q0, [0.0, 0.0, 0.0] * u.rad / u.s)
    t = np.arange(0.0, t_end + 1e-9, 10.0)
    tr = orbatt.propagate(body, st, _environment(law, t_end), t, method="dop853", rtol=1e-10, atol=1e-12)
    ds = orbatt.to_dataset(tr)
    m = ds["dipole_control"].values
    _within_and_reaching(m, mmax, "dipole_control")
    if period is None:
        q, w = ds["q"].values, ds["omega"].values
        b = qt.rotate_inv(q, FIELD.field(EPOCH + elapsed_values(ds) * u.s, ds["position"].values))
        e = qt.mul(qt.conj(np.broadcast_to(TARGET, q.shape)), q)
        tau = -1e-5 * np.sign(e[:, :1]) * e[:, 1:] - 1e-3 * w
        want = np.clip(np.cross(b, tau) / np.sum(b * b, axis=1, keepdims=True), -mmax, mmax)
        assert np.abs(m - want).max() < 1e-9 * mmax


@pytest.mark.parametrize("period", [None, 1.0])
def test_bdot_clips_each_body_axis(period):
    """B-dot detumbling a tensor body from 3 deg/s (max_dipole = 0.05 A m^2): the dipole stays
    within the limit per body axis and reaches it, and the rate falls."""
    mmax, t_end = 0.05, 1200.0
    law = orbatt.BDotControl("2e5 A m2 s / T", mmax * u.A * u.m**2, period=None if period is None else period * u.s)
    body = _body()
    st = orbatt.State.from_omega(body, Q0, np.radians([3.0, -2.0, 1.5]) * u.rad / u.s)
    tr = orbatt.propagate(body, st, _environment(law, t_end), np.arange(0.0, t_end + 1e-9, 5.0), method="dop853",
                          rtol=1e-10, atol=1e-12)
    ds = orbatt.to_dataset(tr)
    _within_and_reaching(ds["dipole_control"].values, mmax, "dipole_control")
    w = np.linalg.norm(ds["omega"].values, axis=1)
    assert w[-1] < 0.7 * w[0]


def test_momentum_dumping_clips_each_body_axis():
    """Wheels holding an inertial attitude under a constant body torque, their momentum dumped
    by magnetorquers (dump_max_dipole = 0.01 A m^2): the dumping dipole stays within the limit
    per body axis and reaches it."""
    mmax, t_end = 0.01, 1800.0
    axes = np.eye(3)
    wheels = [orbatt.ReactionWheel(a, "2e-4 kg m2", "3000 rpm") for a in axes]
    law = orbatt.PDControl("inertial", kp=4e-3 * u.N * u.m, kd=1.4e-2 * u.N * u.m * u.s, target_q=TARGET,
                           actuator="wheels", dump_gain=5e-2 / u.s, dump_max_dipole=mmax * u.A * u.m**2)
    body = _body(wheels)
    st = orbatt.State.from_omega(body, TARGET, [0.0, 0.0, 0.0] * u.rad / u.s)
    env = orbatt.EnvironmentTorques(ORBIT, t_end * u.s, gravity_gradient=False, magnetic_field=FIELD, control=law,
                                    constant_torque=[2e-6, 1e-6, -3e-6] * u.N * u.m)
    tr = orbatt.propagate(body, st, env, np.arange(0.0, t_end + 1e-9, 10.0), method="dop853", rtol=1e-10,
                          atol=1e-12)
    ds = orbatt.to_dataset(tr)
    _within_and_reaching(ds["dipole_control"].values, mmax, "dipole_control")


def test_a_mode_sequence_clips_each_body_axis_in_every_mode():
    """B-dot for 300 s, then the PD law on an ideal torque, at 1 s: each mode's law (a copy
    in the principal frame) clips along the body axes: the dipole of the first mode and the
    torque of the second stay within their limits per body axis and reach them."""
    from orbatt.modes import Mode, ModeSequence

    mmax, t_end = 0.05, 600.0
    seq = ModeSequence([Mode("detumble", orbatt.BDotControl("2e5 A m2 s / T", mmax * u.A * u.m**2, period=1 * u.s),
                             until_time=300 * u.s),
                        Mode("hold", _pd(period=1 * u.s))], period=1 * u.s)
    body = _body()
    st = orbatt.State.from_omega(body, Q0, np.radians([3.0, -2.0, 1.5]) * u.rad / u.s)
    tr = orbatt.propagate(body, st, _environment(seq, t_end), np.arange(0.0, t_end + 1e-9, 5.0), method="dop853",
                          rtol=1e-10, atol=1e-12)
    ds = orbatt.to_dataset(tr)
    mode = ds["mode"].values
    _within_and_reaching(ds["dipole_control"].values[mode == 0], mmax, "dipole_control")
    _within_and_reaching(ds["torque_control"].values[mode == 1], TMAX, "torque_control")

"""The torque-free gyrostat (a rigid body with free reaction wheels, ``docs/design.md`` §10): the
invariants, an independent classical model, and the closed-form axisymmetric solution.

Units are orbatt's internal ones (kg, km, s): inertia kg km^2, momenta kg km^2/s."""
from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from scipy.integrate import solve_ivp

import orbatt
from orbatt import canonical as cn
from orbatt import quaternion as qt

from control_support import angle

#: a small spacecraft (kg m^2, rotors locked) with three orthogonal wheels and a skewed one
INERTIA = np.array([0.05, 0.06, 0.02])
AXES = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
AXES = AXES / np.linalg.norm(AXES, axis=1)[:, None]
ROTOR = np.array([4e-5, 4e-5, 4e-5, 3e-5])                        # kg m^2
SPEED = np.array([100.0, -50.0, 30.0, 200.0]) * 2 * np.pi / 60  # rad/s, relative to the body
Q0 = qt.normalize(np.array([0.8, 0.3, -0.4, 0.331662479035540]))
OMEGA0 = np.array([0.01, -0.005, 0.008])                          # rad/s
T_END = 1e4                                                       # s


def gyrostat(inertia=INERTIA, axes=AXES, rotor=ROTOR, speed=SPEED):
    wheels = [orbatt.ReactionWheel(a, Iw * u.kg * u.m**2, s * u.rad / u.s) for a, Iw, s in zip(axes, rotor, speed)]
    return orbatt.RigidBody(np.asarray(inertia) * u.kg * u.m**2, wheels=wheels)


def locked_out(inertia, axes, rotor):
    """``J = diag(I) - sum Iw a a^T`` (kg km^2)."""
    return np.diag(inertia) * 1e-6 - 1e-6 * np.einsum("k,ki,kj->ij", rotor, axes, axes)


def energy_and_momentum(tr, inertia=INERTIA, axes=AXES, rotor=ROTOR):
    """``T = 1/2 (g - h).J^-1 (g - h)`` and the inertial ``G = q g q~`` of a trajectory."""
    g = cn.body_momentum(tr.q, tr.Q)
    x = g - tr.wheel_momenta @ axes
    T = 0.5 * np.einsum("ni,ni->n", x, np.linalg.solve(locked_out(inertia, axes, rotor), x.T).T)
    return T, cn.space_momentum(tr.q, tr.Q)


@pytest.fixture(scope="module", params=[1.0, 10.0], ids=["wheels-100rpm", "wheels-1000rpm"])
def free_run(request):
    speed = SPEED * request.param
    body = gyrostat(speed=speed)
    s0 = orbatt.State.from_omega(body, Q0, OMEGA0 * u.rad / u.s)
    t = np.linspace(0.0, T_END, 201)
    return speed, orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="dop853", rtol=3e-15, atol=3e-15)


def test_initial_state_holds_the_total_momentum(free_run):
    """g = I omega + sum Iw speed a (rotors locked I), h_k = Iw (a.omega + speed_k)."""
    speed, tr = free_run
    g = cn.body_momentum(tr.q[0], tr.Q[0])
    np.testing.assert_allclose(g, 1e-6 * (INERTIA * OMEGA0 + (ROTOR * speed) @ AXES), rtol=1e-14)
    np.testing.assert_allclose(tr.wheel_momenta[0], 1e-6 * ROTOR * (AXES @ OMEGA0 + speed), rtol=1e-14)


def test_torque_free_gyrostat_conserves_G_T_and_the_wheels(free_run):
    """Free wheels keep their axial momenta; G (inertial) and T stay to round-off over 1e4 s.

    ``Q`` holds the total momentum ``g`` and ``T`` reads the difference ``g - h``: the
    integrator's relative error on ``g`` reaches ``T`` amplified by ``|h| / |g - h|`` (1.5 with
    the wheels at ~100 rpm, 15 at ~1000 rpm). Measured at rtol = atol = 3e-15 over 1e4 s:
    G 4e-15 and 1.2e-14, T 1.3e-13 and 4.5e-12 relative (at rtol 1e-14: T 5e-13 and 1.6e-11;
    the same body with the rotors locked: T 2.7e-14). The bound is 1e-12 times that amplification
    (at least 1)."""
    speed, tr = free_run
    assert np.array_equal(tr.wheel_momenta, np.broadcast_to(tr.wheel_momenta[0], tr.wheel_momenta.shape))
    T, G = energy_and_momentum(tr)
    g = cn.body_momentum(tr.q[0], tr.Q[0])
    h = tr.wheel_momenta[0] @ AXES
    amplification = max(1.0, np.linalg.norm(h) / np.linalg.norm(g - h))
    drift_G = np.max(np.linalg.norm(G - G[0], axis=1)) / np.linalg.norm(G[0])
    drift_T = np.max(np.abs(T / T[0] - 1.0))
    print(f"|h|/|g-h| = {amplification:.3g}: G {drift_G:.3g}, T {drift_T:.3g}")
    assert drift_G < 1e-12
    assert drift_T < 1e-12 * amplification


def classical_gyrostat(t, q0, omega0, inertia, axes, rotor, speed, rtol=1e-13):
    """Euler's equations of a gyrostat in the textbook variables (Hughes, *Spacecraft Attitude
    Dynamics*, ch. 3): body rate ``w``, rotor speeds ``s_k`` relative to the body, free rotors
    (``Iw (a_k.w' + s_k') = 0``)::

        (I - sum Iw a a^T) w' = -w x (I w + sum Iw s_k a_k),   s_k' = -a_k.w',
        q' = 1/2 q (0, w),

    SI units, scipy's DOP853. Returns the quaternions at ``t``."""
    I = np.diag(inertia)
    J = I - np.einsum("k,ki,kj->ij", rotor, axes, axes)
    n = len(rotor)

    def rhs(_, y):
        q, w, s = y[:4], y[4:7], y[7:]
        wd = np.linalg.solve(J, -np.cross(w, I @ w + (rotor * s) @ axes))
        w0, w1, w2, w3 = q
        qd = 0.5 * np.array([-w1 * w[0] - w2 * w[1] - w3 * w[2], w0 * w[0] + w2 * w[2] - w3 * w[1],
                             w0 * w[1] + w3 * w[0] - w1 * w[2], w0 * w[2] + w1 * w[1] - w2 * w[0]])
        return np.concatenate([qd, wd, -axes @ wd])

    y0 = np.concatenate([q0, omega0, speed])
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=rtol, atol=rtol * 1e-3)
    assert sol.success and sol.y.shape[1] == len(t) and n == sol.y.shape[0] - 7
    return sol.y[:4].T


def test_gyrostat_agrees_with_the_classical_model():
    """orbatt's (q, Q, h) against Euler's equations with rotors written above, to 1e-10 rad
    over 1e4 s (~100 rad turned). Measured 1.5e-11 rad (orbatt at rtol 1e-14; at 1e-13:
    5.4e-11); the classical model at rtol 1e-13 differs from itself at 1e-12 by 2.4e-10."""
    body = gyrostat()
    t = np.linspace(0.0, T_END, 101)
    s0 = orbatt.State.from_omega(body, Q0, OMEGA0 * u.rad / u.s)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="dop853", rtol=1e-14, atol=1e-14)
    ref = classical_gyrostat(t, Q0, OMEGA0, INERTIA, AXES, ROTOR, SPEED)
    err = angle(tr.q, ref)
    print(f"orbatt vs classical gyrostat over {T_END:g} s: {err.max():.3g} rad")
    assert err.max() < 1e-10
    # the rotors change the motion: the rigid body (rotors locked) is far from it
    rigid = classical_gyrostat(t, Q0, OMEGA0, INERTIA, AXES, ROTOR, 0.0 * SPEED)
    assert angle(rigid, ref).max() > 1e-2


def test_axisymmetric_gyrostat_closed_form():
    r"""An axisymmetric gyrostat: ``I1 = I2 = I`` (rotors locked), one wheel of axial moment
    ``Iw`` along body axis 3 spinning at ``s`` relative to the body. With ``J = diag(A, A, C)``,
    ``A = I``, ``C = I3 - Iw`` and the rotor's absolute momentum ``h = Iw (w3 + s)`` (constant,
    the rotor is free), the total momentum is ``g = (A w1, A w2, C w3 + h)`` and Euler's
    equation ``g' = g x w`` reads

    * ``A w1' = w2 ((A - C) w3 - h)``, ``A w2' = w1 ((C - A) w3 + h)``, ``w3' = 0``:

    so ``w1 + i w2 = (w1(0) + i w2(0)) exp(i lam t)`` with
    ``lam = ((C - A) w3 + h) / A = ((I3 - I) w3 + Iw s) / I``.

    The attitude: in body axes ``g(t) = Rz(lam t) g(0)``. With ``G`` constant in space,
    ``R(t) = Rot(G^, phi' t) R0 Rz(-lam t)`` keeps ``R g = G``, and its body rate
    ``phi' g/|G| - lam e3`` equals ``w`` when ``phi' = |G| / A`` (components 1, 2:
    ``g_perp / A = w_perp``; component 3: ``g3 / A - lam = w3``). In quaternions
    ``q(t) = q_rot(G^, |G| t / A) q0 q_rot(e3, -lam t)``.

    Measured over 5000 s (rtol 1e-13): attitude 4.9e-12 rad, body rate 1.2e-13 rad/s (of
    0.027 rad/s).
    """
    I, I3, Iw = 0.05, 0.08, 3e-5            # kg m^2
    s = 1000 * 2 * np.pi / 60               # rad/s
    w0 = np.array([0.02, -0.01, 0.015])     # rad/s
    body = gyrostat([I, I, I3], [[0.0, 0.0, 1.0]], [Iw], [s])
    t = np.linspace(0.0, 5000.0, 251)
    s0 = orbatt.State.from_omega(body, Q0, w0 * u.rad / u.s)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="dop853", rtol=1e-13, atol=1e-15)

    lam = ((I3 - I) * w0[2] + Iw * s) / I
    assert abs(lam) > 5 * abs((I3 - I) * w0[2] / I)          # the wheel dominates the nutation rate
    w_ref = np.column_stack([w0[0] * np.cos(lam * t) - w0[1] * np.sin(lam * t),
                             w0[0] * np.sin(lam * t) + w0[1] * np.cos(lam * t), np.full_like(t, w0[2])])
    J = np.array([I, I, I3 - Iw]) * 1e-6
    omega = (cn.body_momentum(tr.q, tr.Q) - tr.wheel_momenta @ np.array([[0.0, 0.0, 1.0]])) / J

    g0 = 1e-6 * np.array([I * w0[0], I * w0[1], (I3 - Iw) * w0[2] + Iw * (w0[2] + s)])
    G = qt.rotate(Q0, g0)
    np.testing.assert_allclose(cn.space_momentum(tr.q, tr.Q), np.broadcast_to(G, (len(t), 3)), rtol=0,
                               atol=1e-13 * np.linalg.norm(G))
    Gn = np.linalg.norm(G)
    q_ref = qt.mul(qt.mul(qt.from_axis_angle(G / Gn, Gn * t / (I * 1e-6)), Q0),
                   qt.from_axis_angle([0.0, 0.0, 1.0], -lam * t))
    err = angle(tr.q, q_ref)
    print(f"axisymmetric gyrostat vs closed form over {t[-1]:g} s: {err.max():.3g} rad, "
          f"omega {np.abs(omega - w_ref).max():.3g} rad/s")
    assert err.max() < 1e-10
    np.testing.assert_allclose(omega, w_ref, rtol=0, atol=3e-11 * np.linalg.norm(w0))


def test_scipy_methods_integrate_the_gyrostat():
    """scipy's DOP853 on the same state (q, Q, h) agrees with orbatt's DOP853 (measured 8.2e-12
    rad over 2000 s at rtol 1e-12)."""
    body = gyrostat()
    t = np.linspace(0.0, 2000.0, 11)
    s0 = orbatt.State.from_omega(body, Q0, OMEGA0 * u.rad / u.s)
    a, b = (orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method=m, rtol=1e-12, atol=1e-14)
            for m in ("dop853", "scipy-DOP853"))
    print(f"dop853 vs scipy-DOP853: {angle(a.q, b.q).max():.3g} rad")
    assert angle(a.q, b.q).max() < 1e-10
    np.testing.assert_array_equal(b.wheel_momenta, a.wheel_momenta)

"""The coupled binary (orbatt.binary, orbatt.core.mutual) against physics: an independent
Newton-Euler model, the one-way Keplerian limit, the sphere-ellipsoid synchronous equilibrium,
and the invariants."""
import math

import astropy.units as u
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import orbatt
from orbatt import quaternion as qt
from orbatt.binary import BinarySystem, Impulse, binary_content, propagate_binary
from orbatt.binary.system import G_KM
from orbatt.core import mutual as km

KGM2 = u.kg * u.m**2
# Didymos-Dimorphos-like (the contract values)
M1, M2 = 5.3e11, 4.3e9
I2 = np.array([8.6e12, 1.17e13, 1.41e13]) * 1e-6   # kg km^2
I1 = np.array([2.93e16, 2.93e16, 3.83e16]) * 1e-6
P_ORBIT = 11.92 * 3600.0


def binary_system(rigid=True, potential="coupled", m2=M2, i2=I2):
    return BinarySystem(m2 * u.kg, i2 * u.kg * u.km**2, M1 * u.kg, I1 * u.kg * u.km**2 if rigid else None,
                        potential=potential)


def tilted_state(s):
    """An excited state: eccentric inclined orbit, the secondary tilted and spinning off-synchronous,
    the primary spinning about a tilted axis (so that every torque and coupling term acts)."""
    q2 = qt.normalize(np.array([0.9, 0.2, -0.1, 0.3]))
    q1 = qt.normalize(np.array([0.98, 0.05, 0.12, 0.0]))
    n = 2 * math.pi / P_ORBIT
    return s.state_from_elements(1.19 * u.km, 0.05, 8 * u.deg, 20 * u.deg, 30 * u.deg, 10 * u.deg, q2,
                                 [0.1 * n, -0.2 * n, 1.3 * n] * u.rad / u.s, q1,
                                 [1e-5, -2e-5, 7.72e-4] * u.rad / u.s)


# ---------------------------------------------------------------------------------------------
# An independent Newton-Euler model: rotation matrices and Euler's equations, written here


def _newton_euler(s):
    G, mu = G_KM, s.reduced_mass
    rigid = s.rigid_primary

    def grad_and_torques(r, R2, R1):
        rn = np.linalg.norm(r)
        force = G * M1 * s.mass * r / rn**3   # dU/dr, point masses
        taus = []
        for R, I, Mo in ((R2, s.inertia, M1), (R1, s.primary_inertia, s.mass)):
            if R is None:
                taus.append(None)
                continue
            IS = R @ np.diag(I) @ R.T
            rIr = r @ IS @ r / rn**2
            force = force + 1.5 * G * Mo / rn**5 * (np.trace(IS) * r + 2 * IS @ r - 5 * rIr * r)
            taus.append(R.T @ (3 * G * Mo / rn**5 * np.cross(r, IS @ r)))   # body axes
        return force, taus

    def f(t, x):
        r, v = x[0:3], x[3:6]
        R2 = x[6:15].reshape(3, 3)
        w2 = x[15:18]
        R1 = x[18:27].reshape(3, 3) if rigid else None
        force, (tau2, tau1) = grad_and_torques(r, R2, R1)
        out = [v, -force / mu, (R2 @ _hat(w2)).ravel(), (np.cross(s.inertia * w2, w2) + tau2) / s.inertia]
        if rigid:
            w1 = x[27:30]
            out += [(R1 @ _hat(w1)).ravel(), (np.cross(s.primary_inertia * w1, w1) + tau1) / s.primary_inertia]
        return np.concatenate(out)

    return f


def _hat(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def _matrix(q):
    return Rotation.from_quat(np.r_[q[1:], q[0]]).as_matrix()


def _to_ne(s, y):
    mu = s.reduced_mass
    g2 = 0.5 * qt.mul(qt.conj(y[6:10]), y[10:14])[1:]
    x = [y[0:3], y[3:6] / mu, _matrix(y[6:10]).ravel(), g2 / s.inertia]
    if s.rigid_primary:
        g1 = 0.5 * qt.mul(qt.conj(y[14:18]), y[18:22])[1:]
        x += [_matrix(y[14:18]).ravel(), g1 / s.primary_inertia]
    return np.concatenate(x)


def _rotation_angle(Ra, Rb):
    c = (np.trace(Ra.T @ Rb) - 1) / 2
    s = np.linalg.norm(Rotation.from_matrix(Ra.T @ Rb).as_rotvec())
    return s if c > 0 else math.acos(max(-1.0, min(1.0, c)))


@pytest.mark.parametrize("rigid", [False, True], ids=["point-primary", "rigid-primary"])
def test_newton_euler_agreement_ten_orbits(rigid):
    """Position 1e-9 relative, both attitudes 1e-9 rad over 10 orbits, against scipy's DOP853 on
    the Newton-Euler equations (rotation matrices, Euler's equations)."""
    s = binary_system(rigid)
    y0 = tilted_state(s)
    t = np.linspace(0.0, 10 * P_ORBIT, 11)
    tr = propagate_binary(s, y0, t, rtol=2e-14, atol=1e-18)   # (at rtol 1e-13: 5e-10 rad, 1429 steps)
    x0 = _to_ne(s, y0)
    scale = np.abs(x0) + np.r_[np.ones(3), 1e-4 * np.ones(3), np.ones(9), 1e-3 * np.ones(3),
                               np.ones(12)][:x0.size]
    # scipy's step-end values at the output times: integrate to each (docs/design.md §4)
    xs = [x0]
    for a, b in zip(t[:-1], t[1:]):
        sol = solve_ivp(_newton_euler(s), (a, b), xs[-1], method="DOP853", rtol=2.5e-14, atol=1e-17 * scale)
        xs.append(sol.y[:, -1])
    xs = np.array(xs)
    pos_err = np.max(np.linalg.norm(tr.y[:, 0:3] - xs[:, 0:3], axis=1) / np.linalg.norm(xs[:, 0:3], axis=1))
    att2 = max(_rotation_angle(_matrix(tr.y[k, 6:10]), xs[k, 6:15].reshape(3, 3)) for k in range(t.size))
    assert pos_err < 1e-9, pos_err
    assert att2 < 1e-9, att2
    if rigid:
        att1 = max(_rotation_angle(_matrix(tr.y[k, 14:18]), xs[k, 18:27].reshape(3, 3)) for k in range(t.size))
        assert att1 < 1e-9, att1
    # the coupling is not negligible here: the orbit differs from a Keplerian one by far more
    kep = orbatt.KeplerOrbit.from_state(tr.y[0, 0:3] * u.km, tr.y[0, 3:6] / s.reduced_mass * u.km / u.s,
                                        gm=s.gm * u.km**3 / u.s**2, body_radius=None)
    rk, _ = kep.state(t)
    assert np.max(np.linalg.norm(rk - tr.y[:, 0:3], axis=1)) > 1e-3   # km


def test_secondary_mass_to_zero_is_the_one_way_kepler_run():
    """potential = 'gravity-gradient', M2 -> 0: the attitude of provider = 'kepler' with gm = G M1
    (1e-10 rad), and the orbit the Keplerian one."""
    m2 = 1e-6   # kg: G (M1 + M2) = G M1 to 2e-18
    s = binary_system(rigid=False, potential="gravity-gradient", m2=m2, i2=I2 * m2 / M2)
    q2 = qt.normalize(np.array([0.9, 0.2, -0.1, 0.3]))
    n = 2 * math.pi / P_ORBIT
    w = [0.1 * n, -0.2 * n, 1.3 * n]
    els = (1.19 * u.km, 0.05, 8 * u.deg, 20 * u.deg, 30 * u.deg)
    y0 = s.state_from_elements(*els, 10 * u.deg, q2, w * u.rad / u.s)
    t = np.linspace(0.0, 3 * P_ORBIT, 7)
    tr = propagate_binary(s, y0, t, rtol=1e-13, atol=1e-17)
    orbit = orbatt.KeplerOrbit(*els, true_anomaly=10 * u.deg, gm=G_KM * M1 * u.km**3 / u.s**2, body_radius=None)
    body = orbatt.RigidBody(s.inertia * u.kg * u.km**2)
    state0 = orbatt.State.from_omega(body, q2, w * u.rad / u.s)
    one_way = orbatt.propagate(body, state0, orbatt.GravityGradient(orbit), t, rtol=1e-13, atol=1e-17)
    ang = qt.angle_between(tr.y[:, 6:10], one_way.q)
    assert np.max(ang) < 1e-10, np.max(ang)
    pos, _ = orbit.state(t)
    assert np.max(np.linalg.norm(pos - tr.y[:, 0:3], axis=1)) / 1.19 < 1e-10


def test_sphere_ellipsoid_synchronous_equilibrium():
    """Long axis radial, spin n about z with n^2 = G (M1 + M2) / r^3 (1 + 3 (Iyy + Izz - 2 Ixx) /
    (2 M2 r^2)): the configuration stays and the period is 2 pi / n to 1e-12."""
    s = binary_system(rigid=False)   # a sphere primary is a point mass at this order
    r = 1.19
    Ixx, Iyy, Izz = s.inertia
    n = math.sqrt(s.gm / r**3 * (1 + 3 * (Iyy + Izz - 2 * Ixx) / (2 * s.mass * r**2)))
    y0 = s.state([r, 0, 0] * u.km, [0, n * r, 0] * u.km / u.s, [1, 0, 0, 0], [0, 0, n] * u.rad / u.s)
    T = 2 * math.pi / n
    t = np.linspace(0.0, T, 9)
    tr = propagate_binary(s, y0, t, rtol=1e-14, atol=1e-18)
    # the orbit angle after one period of 2 pi / n: back to 0 (phase error / 2 pi = period error)
    phase = math.atan2(tr.y[-1, 1], tr.y[-1, 0])
    assert abs(phase) / (2 * math.pi) < 1e-12, phase
    assert abs(np.linalg.norm(tr.y[-1, 0:3]) - r) / r < 1e-12
    # the long axis (body x) stays radial, the spin stays n about z at every output
    xb = qt.rotate(tr.y[:, 6:10], np.array([1.0, 0, 0]))
    rhat = tr.y[:, 0:3] / np.linalg.norm(tr.y[:, 0:3], axis=1)[:, None]
    assert np.max(np.linalg.norm(np.cross(xb, rhat), axis=1)) < 1e-12
    _, _, om, _ = km.evaluate(tr.y, tr.c)
    assert np.max(np.abs(om - [0, 0, n])) < 1e-12 * n
    # the classical Keplerian rate alone is measurably different (the check has teeth)
    assert abs(math.sqrt(s.gm / r**3) / n - 1) > 1e-5


@pytest.mark.parametrize("method", ["dop853", "vern98"])
def test_energy_and_total_angular_momentum_conserved(method):
    """1e-12 relative at rtol 1e-13 (rigid primary, every coupling acting), with an impulse the
    angular momentum changes by exactly r x (mu dv)."""
    s = binary_system(rigid=True)
    y0 = tilted_state(s)
    t = np.linspace(0.0, 5 * P_ORBIT, 51)
    tr = propagate_binary(s, y0, t, method=method, rtol=1e-13, atol=1e-17)
    ds = binary_content(tr)
    E = ds["energy"].values
    L = ds["angular_momentum_total"].values
    assert np.max(np.abs(E - E[0])) / abs(E[0]) < 1e-12
    assert np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0]) < 1e-12
    # orbit energy and spins do exchange (the invariants are not trivially constant)
    orbit_energy = np.sum(ds["velocity"].values ** 2, axis=1)
    assert np.ptp(orbit_energy) / np.mean(orbit_energy) > 1e-3


def test_impulse_changes_the_period_and_angular_momentum():
    s = binary_system(rigid=False)
    n = 2 * math.pi / P_ORBIT
    y0 = s.state_from_elements(1.19 * u.km, 0.0, 0 * u.deg, 0 * u.deg, 0 * u.deg, 0 * u.deg, [1, 0, 0, 0],
                               [0, 0, n] * u.rad / u.s)
    t = np.linspace(0.0, 2 * P_ORBIT, 9)
    dv = (0.0, -2.7e-6, 0.0)   # km/s along-track, against the motion
    tr = propagate_binary(s, y0, t, impulses=[Impulse(P_ORBIT, dv)], rtol=1e-12, atol=1e-16)
    ds = binary_content(tr)
    per = ds["orbit_period"].values
    k = np.searchsorted(t, P_ORBIT)
    assert per[k + 1] < per[k] - 60.0   # the period shrinks (minutes)
    L = ds["angular_momentum_total"].values
    assert np.linalg.norm(L[k + 1] - L[k]) > 1e-6 * np.linalg.norm(L[k])
    assert np.max(np.linalg.norm(L[k + 1:] - L[k + 1], axis=1)) < 1e-11 * np.linalg.norm(L[k])

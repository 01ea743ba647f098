"""Attitude relative to the orbital frame (orbatt.orbital) and the gravity-gradient physics
checks: relative equilibrium, pitch libration frequency, planar spin-orbit equation."""
import math

import astropy.units as u
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from orbatt import RigidBody, State
from orbatt import canonical as cn
from orbatt import orbital as orb
from orbatt import quaternion as qt
from orbatt.core import hamiltonian as ham
from orbatt.core import model as km
from orbatt.core import potentials as kp
from orbatt.errors import InputError
from orbatt.orbits import KeplerOrbit, ReboundOrbit

INERTIA = np.array([400.0, 500.0, 600.0])  # kg km^2: I1 < I2 < I3, the Lagrange-stable order


@pytest.fixture(scope="module")
def body():
    return RigidBody(INERTIA * u.kg * u.km**2)


@pytest.fixture(scope="module")
def circular():
    return KeplerOrbit(7000 * u.km, 0.0, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, true_anomaly=10 * u.deg)


@pytest.fixture(scope="module")
def paper():
    return KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg, body_radius=None)


def integrate(orbit, state, t_eval, rtol=1e-13):
    """Hamilton's equations (compiled RHS) with scipy's DOP853, integrating to each output time."""
    model = km.from_spec(*orbit.kernel())
    work = kp.new_work()
    inertia = state.body.inertia_value

    def f(t, y):
        dy = np.empty(8)
        ham.rhs(t, y, inertia, *model, work, dy)
        return dy

    sol = solve_ivp(f, (t_eval[0], t_eval[-1]), state.y, method="DOP853", rtol=rtol, atol=rtol * 1e-3,
                    t_eval=t_eval)
    assert sol.status == 0
    return sol.y[:4].T, sol.y[4:].T


# ---- the frame helpers ---------------------------------------------------------------------
def test_round_trip_and_identity(paper):
    t = np.linspace(0, paper.period_value, 50)
    p = paper.orbital_quaternion(t)
    assert np.allclose(orb.orbital_attitude(paper, t, p), [1, 0, 0, 0], atol=1e-15)
    rng = np.random.default_rng(1)
    q_BO = qt.normalize(rng.normal(size=(50, 4)))
    q = orb.inertial_attitude(paper, t, q_BO)
    assert np.allclose(orb.orbital_attitude(paper, t, q), q_BO, atol=1e-15)
    # an ensemble (E, N, 4) broadcasts against the N times
    qe = np.stack([q, -q])
    assert np.allclose(orb.orbital_attitude(paper, t, qe)[1], -q_BO, atol=1e-15)


def test_state_from_orbital_defaults(body, paper):
    s = orb.state_from_orbital(body, paper)
    assert isinstance(s, State)
    assert np.allclose(s.q, paper.orbital_quaternion(0.0), atol=1e-16)
    fdot = paper.orbital_rate(0.0)[2]
    assert np.allclose(s.omega, [0, 0, fdot], rtol=0, atol=1e-18)  # turns with O about o3 = b3
    assert abs(s.radial_residual) < 1e-18
    # attitude and rates relative to O come back from (q, Q)
    q_BO, w_BO = orb.to_orbital(paper, 0.0, s.q, s.Q, body)
    assert np.allclose(q_BO, [1, 0, 0, 0], atol=1e-16) and np.allclose(w_BO, 0, atol=1e-18)
    # a relative rate and attitude in body axes; a later time t0
    q_BO = qt.from_axis_angle([0.2, -0.3, 1.0], 0.7)
    w_BO = np.array([1e-4, -2e-4, 3e-4])
    s = orb.state_from_orbital(body, paper, q_BO, w_BO * u.rad / u.s, t0=1000 * u.s)
    q2, w2 = orb.to_orbital(paper, 1000.0, s.q, s.Q, body)
    assert np.allclose(q2, q_BO, atol=1e-15) and np.allclose(w2, w_BO, rtol=0, atol=1e-17)
    # batch of initial attitudes (ensembles)
    sb = orb.state_from_orbital(body, paper, np.stack([q_BO, [1.0, 0, 0, 0]]), w_BO)
    assert sb.q.shape == (2, 4) and sb.Q.shape == (2, 4)


def test_relative_rate_is_the_derivative_of_the_relative_attitude(body, paper):
    """omega_BO_B from to_orbital equals 2 q_BO~ dq_BO/dt along an integrated trajectory in
    the eccentric orbit (checks the frame rate and the composition of rates)."""
    s = orb.state_from_orbital(body, paper, qt.from_axis_angle([1, 2, 3], 0.4), [3e-4, -1e-4, 2e-3])
    dt = 1.0
    centres = np.linspace(100, 2 * paper.period_value, 11)
    t_eval = np.sort(np.concatenate([centres + k * dt for k in (-2, -1, 0, 1, 2)]))
    q, Q = integrate(paper, s, np.concatenate([[0.0], t_eval]))
    q, Q = q[1:].reshape(11, 5, 4), Q[1:].reshape(11, 5, 4)
    tt = t_eval.reshape(11, 5)
    q_BO, w_BO = orb.to_orbital(paper, tt[:, 2], q[:, 2], Q[:, 2], INERTIA)
    qbo = np.stack([orb.orbital_attitude(paper, tt[:, k], q[:, k]) for k in range(5)], axis=1)
    dq = (qbo[:, 0] - 8 * qbo[:, 1] + 8 * qbo[:, 3] - qbo[:, 4]) / (12 * dt)
    w_fd = 2 * qt.mul(qt.conj(q_BO), dq)[:, 1:]
    assert np.allclose(w_fd, w_BO, rtol=0, atol=1e-9 * np.max(np.abs(w_BO)))
    # and the inertial body rate decomposes as omega_BO_B + q_BO~ omega_OS_O q_BO
    w_B = cn.body_rate(q[:, 2], Q[:, 2], INERTIA)
    assert np.allclose(orb.body_rate_from_orbital(paper, tt[:, 2], q_BO, w_BO), w_B, rtol=0, atol=1e-18)
    assert np.allclose(orb.relative_rate(paper, tt[:, 2], q[:, 2], w_B), w_BO, rtol=0, atol=1e-18)


def test_frame_helpers_with_a_rebound_orbit(body, paper):
    ro = ReboundOrbit(paper, 1000 * u.s, perturbations=["j2"])
    s = orb.state_from_orbital(body, ro)
    q_BO, w_BO = orb.to_orbital(ro, 0.0, s.q, s.Q, body)
    assert np.allclose(q_BO, [1, 0, 0, 0], atol=1e-15) and np.allclose(w_BO, 0, atol=1e-18)
    w_O = ro.orbital_rate(0.0)
    assert np.allclose(s.omega, w_O, rtol=1e-13, atol=0)  # includes the J2 term r a_n / h about o1
    assert abs(w_O[0]) > 0


def test_bad_input(body, paper):
    with pytest.raises(InputError, match="body: the body and the orbit must be both dimensional"):
        orb.state_from_orbital(RigidBody([1.0, 2.0, 2.5]), paper)
    with pytest.raises(InputError, match="q_BO: .* is not 1"):
        orb.state_from_orbital(body, paper, [1.0, 0.1, 0, 0])
    with pytest.raises(InputError, match="orbit: expected an orbit provider"):
        orb.state_from_orbital(body, "leo")
    with pytest.raises(InputError, match="omega_BO_B: expected 3"):
        orb.state_from_orbital(body, paper, omega_BO_B=[0.0, 0.0])
    with pytest.raises(InputError, match="omega_BO_B: .* wrong dimension"):
        orb.state_from_orbital(body, paper, omega_BO_B=[0.0, 0.0, 1.0] * u.km)
    with pytest.raises(InputError, match="inertia: needed with Q"):
        orb.to_orbital(paper, 0.0, [1.0, 0, 0, 0], [0.0, 0, 0, 0])


# ---- physics ---------------------------------------------------------------------------------
def test_relative_equilibrium_in_a_circular_orbit(body, circular):
    """Aligned with O and turning at the orbital rate: stays aligned (the gravity-gradient
    torque vanishes on the principal axes)."""
    s = orb.state_from_orbital(body, circular)
    t = np.linspace(0, 3 * circular.period_value, 61)
    q, Q = integrate(circular, s, t)
    q_BO, w_BO = orb.to_orbital(circular, t, q, Q, body)
    assert np.max(qt.angle_between(q_BO, np.array([1.0, 0, 0, 0]))) < 1e-10  # measured ~1e-12
    assert np.max(np.abs(w_BO)) < 1e-12 * circular.n_value


def _pitch(q_BO):
    """Rotation angle about o3 = b3 of a planar relative attitude (0, 0, sin, cos form)."""
    return 2 * np.arctan2(q_BO[..., 3], q_BO[..., 0])


def _crossing_times(t, x):
    """Upward zero crossings, located by cubic interpolation of 4 neighbouring samples."""
    out = []
    for i in np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]:
        if 1 <= i < len(x) - 2:
            c = np.polyfit(t[i - 1:i + 3] - t[i], x[i - 1:i + 3], 3)
            roots = np.roots(c)
            roots = roots[np.isreal(roots)].real
            h = t[i + 1] - t[i]
            out.append(t[i] + roots[(roots >= -1e-9 * h) & (roots <= h * (1 + 1e-9))][0])
    return np.array(out)


def test_small_pitch_libration_frequency(body, circular):
    """Pitch about the orbit normal (axis 3) librates at n sqrt(3 (I2 - I1) / I3)."""
    theta0 = 0.01  # rad: the amplitude correction to the frequency is ~theta0^2 / 4 = 2.5e-5
    s = orb.state_from_orbital(body, circular, qt.from_axis_angle([0, 0, 1.0], theta0))
    wl = circular.n_value * math.sqrt(3 * (INERTIA[1] - INERTIA[0]) / INERTIA[2])
    T_lib = 2 * math.pi / wl
    t = np.linspace(0, 4.5 * T_lib, 1801)
    q, Q = integrate(circular, s, t, rtol=1e-12)
    q_BO = orb.orbital_attitude(circular, t, q)
    # planar: roll and yaw stay zero
    assert np.max(np.abs(q_BO[:, 1:3])) < 1e-12
    theta = _pitch(q_BO)
    assert np.max(np.abs(theta)) == pytest.approx(theta0, rel=1e-3)
    tc = _crossing_times(t, theta)
    assert len(tc) >= 4
    measured = 2 * math.pi * (len(tc) - 1) / (tc[-1] - tc[0])
    assert abs(measured / wl - 1) < 1e-3  # the bound; measured ~2.5e-5 (the amplitude effect)
    assert abs(measured / wl - 1) < 1e-4


def _spin_orbit_rhs(orbit, A, B, C):
    """C theta'' = -(3/2) (GM/r^3) (B - A) sin 2 (theta - lambda), lambda = raan + argp + f
    (equatorial orbit: the true longitude; theta: angle of body axis 1 from s1)."""
    lam0 = orbit.raan + orbit.argp

    def f(t, y):
        r = orbit.radius(t)
        lam = lam0 + orbit.true_anomaly(t)
        return [y[1], -1.5 * orbit.gm / r**3 * (B - A) / C * math.sin(2 * (y[0] - lam))]

    return f


def test_planar_case_reduces_to_the_spin_orbit_equation(body):
    """Orbit normal along body axis 3 (equatorial orbit, rotation about s3): the quaternion
    integration matches the direct integration of the spin-orbit equation."""
    orbit = KeplerOrbit(7000 * u.km, 0.2, 0 * u.deg, 20 * u.deg, 40 * u.deg, true_anomaly=0.3, body_radius=None)
    theta0, thetadot0 = 1.0, 1.7 * orbit.n_value
    q0 = qt.from_axis_angle([0, 0, 1.0], theta0)
    s = State.from_omega(body, q0, [0, 0, thetadot0] * u.rad / u.s)
    t = np.linspace(0, 5 * orbit.period_value, 501)
    q, Q = integrate(orbit, s, t)
    assert np.max(np.abs(q[:, 1:3])) < 1e-13  # stays a rotation about s3 = b3
    theta_q = np.unwrap(2 * np.arctan2(q[:, 3], q[:, 0]))
    A, B, C = INERTIA
    sol = solve_ivp(_spin_orbit_rhs(orbit, A, B, C), (0, t[-1]), [theta0, thetadot0], method="DOP853",
                    rtol=1e-13, atol=1e-15, t_eval=t)
    assert np.max(np.abs(theta_q - sol.y[0])) < 1e-9  # measured ~1e-11
    omega3 = cn.body_rate(q, Q, INERTIA)[:, 2]
    assert np.max(np.abs(omega3 - sol.y[1])) < 1e-9 * orbit.n_value
    # the spin is really driven: theta' changes by a fair fraction over 5 orbits
    assert np.ptp(sol.y[1]) > 0.1 * orbit.n_value


# ------------------------------------------------------------------------------------------
# roll, pitch, yaw about the orbital axes (moved from tests/test_dataset.py)
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("axis,index", [((0, 1, 0), 0), ((0, 0, 1), 1), ((1, 0, 0), 2)])
def test_lvlh_angles_name_the_orbital_axes(axis, index):
    """Roll is about along-track o2, pitch about the orbit normal o3, yaw about radial o1."""
    a = 0.3
    angles = np.array(orb.lvlh_angles(qt.from_axis_angle(axis, a)))
    expected = np.zeros(3)
    expected[index] = a
    assert np.allclose(angles, expected, atol=1e-15)


def test_lvlh_angles_still_reachable_from_dataset():
    from orbatt import dataset as D

    assert D.lvlh_angles is orb.lvlh_angles

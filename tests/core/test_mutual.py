"""The kernels of the coupled binary (orbatt.core.mutual) against the mutual potential written
here with rotation matrices: its value, its gradient (central differences), the torques (minus
the derivative of U along small rotations of each body), Newton's third law for the angular
momentum, and dH/dt = 0 along the right-hand side."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from orbatt import quaternion as qt
from orbatt.core import mutual as km

G, M1, M2 = 6.674e-20, 5.3e11, 4.3e9
I2 = np.array([8.6e12, 1.17e13, 1.41e13]) * 1e-6
I1 = np.array([2.93e16, 2.93e16, 3.83e16]) * 1e-6
Q2 = qt.normalize(np.array([0.9, 0.2, -0.1, 0.3]))
Q1 = qt.normalize(np.array([0.98, 0.05, 0.12, -0.2]))
R0 = np.array([1.1, 0.3, -0.2])
MODEL = np.zeros((1, 6), np.int64), np.zeros(1), np.zeros((1, 1)), np.zeros(1)


def matrix(q):
    return Rotation.from_quat(np.r_[q[1:], q[0]]).as_matrix()


def U_ref(r, q2, q1, rigid=True, point=True):
    """The mutual potential (``point``: with the point masses' term, which no rotation changes)."""
    rn = np.linalg.norm(r)
    rh = r / rn
    A = matrix(q2) @ np.diag(I2) @ matrix(q2).T
    U = -G * M1 * M2 / rn * point - G * M1 / (2 * rn**3) * (np.trace(A) - 3 * rh @ A @ rh)
    if rigid:
        B = matrix(q1) @ np.diag(I1) @ matrix(q1).T
        U -= G * M2 / (2 * rn**3) * (np.trace(B) - 3 * rh @ B @ rh)
    return U


def state(rigid=True):
    y = np.zeros(km.N_RIGID if rigid else km.N_POINT)
    y[0:3] = R0
    y[3:6] = [10.0, 700.0, -30.0]
    y[6:10] = Q2
    y[10:14] = 2 * qt.mul(Q2, np.r_[0.0, I2 * [1e-5, 2e-5, 1.4e-4]])
    if rigid:
        y[14:18] = Q1
        y[18:22] = 2 * qt.mul(Q1, np.r_[0.0, I1 * [1e-5, -2e-5, 7.7e-4]])
    return y


def rot(e, a):
    return np.r_[np.cos(a / 2), np.sin(a / 2) * e]


@pytest.mark.parametrize("rigid", [False, True])
def test_potential_gradient_and_torques(rigid):
    c = km.constants(G, M1, M2, I2, I1 if rigid else None)
    y = state(rigid)
    assert km.potential(y, c) == pytest.approx(U_ref(R0, Q2, Q1, rigid), rel=1e-15)
    d, t2, t1 = km.torques(y, c)
    h = 1e-6
    fd = [(U_ref(R0 + h * e, Q2, Q1, rigid) - U_ref(R0 - h * e, Q2, Q1, rigid)) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(d, fd, rtol=1e-8)
    # the torque (inertial) is minus the derivative of U along a small rotation of the body in space
    h = 1e-5
    fd2 = [-(U_ref(R0, qt.mul(rot(e, h), Q2), Q1, rigid, False) - U_ref(R0, qt.mul(rot(e, -h), Q2), Q1, rigid, False))
           / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(matrix(Q2) @ t2, fd2, rtol=1e-8)
    if rigid:
        fd1 = [-(U_ref(R0, Q2, qt.mul(rot(e, h), Q1), True, False) - U_ref(R0, Q2, qt.mul(rot(e, -h), Q1), True, False))
               / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(matrix(Q1) @ t1, fd1, rtol=1e-7)   # U1 is 400x the torque: round-off
    else:
        assert np.all(t1 == 0)
    # Newton's third law for the angular momentum: d(r x p)/dt = -r x dU/dr = -(tau2 + tau1) (inertial)
    np.testing.assert_allclose(np.cross(R0, d), matrix(Q2) @ t2 + matrix(Q1) @ t1, rtol=1e-12,
                               atol=1e-14 * np.abs(np.cross(R0, d)).max())


@pytest.mark.parametrize("rigid", [False, True])
def test_invariants_are_stationary_along_the_rhs(rigid):
    """dH/dt = grad H . f = 0 and dL/dt = 0 (central differences of the kernels' H and L)."""
    c = km.constants(G, M1, M2, I2, I1 if rigid else None)
    y = state(rigid)
    f = np.zeros_like(y)
    km.rhs_coupled(0.0, y, c, *MODEL, f)
    for h in (10.0, 3.0):   # s; the fastest motion here takes ~1e4 s (central differences: error (h/1e4 s)^2)
        dE = (km.energy(y + h * f, c) - km.energy(y - h * f, c)) / (2 * h)
        dL = (km.angular_momentum(y + h * f, c) - km.angular_momentum(y - h * f, c)) / (2 * h)
        scale_E = abs(f[3:6] @ y[3:6]) / c[km.C_MU]
        assert abs(dE) < 1e-5 * scale_E, (h, dE, scale_E)   # (each power term is ~scale_E)
        assert np.linalg.norm(dL) < 1e-9 * np.linalg.norm(np.cross(y[0:3], f[3:6])), (h, dL)
    # the constraint q.Q = 0 is kept exactly: d(q.Q)/dt = qdot.Q + q.Qdot = 0
    assert abs(f[6:10] @ y[10:14] + y[6:10] @ f[10:14]) < 1e-15 * np.abs(y[10:14]).max()


def test_point_mass_primary_is_the_limit_of_a_vanishing_inertia():
    c0 = km.constants(G, M1, M2, I2)
    c1 = km.constants(G, M1, M2, I2, I1 * 1e-30)
    y0, y1 = state(False), state(True)
    f0, f1 = np.zeros(14), np.zeros(22)
    km.rhs_coupled(0.0, y0, c0, *MODEL, f0)
    km.rhs_coupled(0.0, y1, c1, *MODEL, f1)
    np.testing.assert_allclose(f1[:14], f0, rtol=1e-12, atol=1e-300)

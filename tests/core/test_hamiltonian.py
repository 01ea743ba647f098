"""Hamilton's equations (eq. 7): kernel vs numpy reference, vs the classical model, vs the
Euler-angle Hamiltonian (eq. 10); potentials (eq. 18) and their invariants."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import orbatt
from orbatt import canonical as cn
from orbatt import euler as eu
from orbatt import quaternion as qt
from orbatt.core import hamiltonian as H
from orbatt.core import model as km
from orbatt.core import potentials as kp

I = np.array([1.25, 1.0, 0.75])
q0 = np.array([0.5, -1 / np.sqrt(2), 0.0, 0.5])
Q0 = np.array([0.3, -0.848528, 0.141421, -1.5])
RTOL = 1e-13


def quaternion_rhs(kind=kp.TORQUE_FREE, params=np.zeros(1), inertia=I):
    work = kp.new_work()
    model = km.from_spec(kind, params, kp.EMPTY_TABLE)

    def f(t, y):
        dy = np.empty(8)
        H.rhs(t, y, inertia, *model, work, dy)
        return dy

    return f


def classical_rhs(inertia=I, torque=None):
    """Euler's equations + quaternion kinematics: y = (q, omega_body)."""

    def f(t, y):
        q, w = y[:4], y[4:]
        g = inertia * w
        tau = np.zeros(3) if torque is None else torque(q)
        wd = (np.cross(g, w) + tau) / inertia
        return np.r_[0.5 * qt.mul(q, qt.pure(w)), wd]

    return f


def integrate(f, y0, t_end, n_out=11):
    t = np.linspace(0, t_end, n_out)
    sol = solve_ivp(f, (0, t_end), y0, method="DOP853", rtol=RTOL, atol=RTOL, t_eval=t, dense_output=False)
    assert sol.success
    return sol.y.T


def test_kernel_matches_numpy_reference():
    rng = np.random.default_rng(0)
    hp = orbatt.HeavyTop(0.5, [1.0, 0.2, -0.3])
    body = orbatt.RigidBody(I)
    for _ in range(20):
        q = qt.normalize(rng.normal(size=4))
        Q = cn.momentum_from_body_momentum(q, rng.normal(size=3))
        for pot in (orbatt.TorqueFree(), hp):
            dy = np.empty(8)
            H.rhs(0.0, np.r_[q, Q], I, *pot.kernel_model(), kp.new_work(), dy)
            _, grad, _ = pot.evaluate(body, 0.0, q)
            qd, Qd = cn.hamilton_rhs(q, Q, I, grad[0])
            assert np.allclose(dy, np.r_[qd, Qd], atol=1e-15, rtol=1e-14)
            # dq/dt = 1/2 q omega
            assert np.allclose(dy[:4], 0.5 * qt.mul(q, qt.pure(cn.body_rate(q, Q, I))), atol=1e-15)


@pytest.fixture(scope="module")
def free_run():
    return integrate(quaternion_rhs(), np.r_[q0, Q0], 100.0, 101)


def test_free_body_invariants(free_run):
    y = free_run
    q, Q = y[:, :4], y[:, 4:]
    T = cn.kinetic_energy(q, Q, I)
    G = cn.space_momentum(q, Q)
    assert np.max(np.abs(qt.norm(q) - 1)) < 1e-11
    assert np.max(np.abs(qt.dot(q, Q) - qt.dot(q0, Q0))) < 1e-11  # q.Q is conserved (paper's -9.7e-8)
    assert np.max(np.abs(T - T[0])) < 1e-11
    assert np.max(np.abs(G - G[0])) < 1e-11


def test_quaternion_form_matches_classical_model(free_run):
    w0 = cn.body_rate(q0, Q0, I)
    yc = integrate(classical_rhs(), np.r_[q0, w0], 100.0, 101)
    q, Q = free_run[:, :4], free_run[:, 4:]
    assert np.max(np.abs(q - yc[:, :4])) < 1e-10
    assert np.max(np.abs(cn.body_rate(q, Q, I) - yc[:, 4:])) < 1e-10


def euler_form(t_end, mass_g=0.0, xc=(0.0, 0.0, 0.0), sign=1.0):
    ang, mom = eu.from_canonical(q0, Q0)
    y0 = np.r_[ang, mom]
    f = lambda t, y: eu.equations_of_motion(y, I, mass_g, xc, sign)  # noqa: E731
    y = integrate(f, y0, t_end, 51)
    return y


@pytest.mark.parametrize("mass_g,xc", [(0.0, (0, 0, 0)), (0.5, (1.0, 0.0, 0.0)), (0.5, (0.3, -0.4, 0.6))])
def test_quaternion_form_matches_euler_hamiltonian(mass_g, xc):
    """Eq. (7) vs eq. (10) (+ eq. 18): two independent formulations, same motion. The span
    keeps sin(theta) away from 0 (checked), where the Euler form is regular."""
    t_end = 20.0
    ye = euler_form(t_end, mass_g, xc)
    assert np.min(np.abs(np.sin(ye[:, 1]))) > 0.05
    pot = orbatt.HeavyTop(mass_g, xc) if mass_g else orbatt.TorqueFree()
    yq = integrate(quaternion_rhs(pot.kind, pot.params), np.r_[q0, Q0], t_end, 51)
    qe = qt.from_euler313(ye[:, 0], ye[:, 1], ye[:, 2])
    s = np.sign(qt.dot(qe, yq[:, :4]))[:, None]
    assert np.max(np.abs(s * qe - yq[:, :4])) < 1e-10
    _, mom = eu.from_canonical(yq[:, :4], yq[:, 4:])
    assert np.max(np.abs(mom - ye[:, 3:])) < 1e-9


def test_heavy_top_torque_and_sign():
    """docs/design.md §3 / §3a item 7: physical U = M g z_c with torque x_c x F_B; the paper's
    printed eq. (18) is the opposite sign."""
    body = orbatt.RigidBody(I)
    xc = np.array([1.0, -0.5, 0.25])
    rng = np.random.default_rng(1)
    q = qt.normalize(rng.normal(size=(30, 4)))
    FB = qt.rotate_inv(q, [0.0, 0.0, -0.5])  # gravity -M g s3 in body components
    U, grad, tau = orbatt.HeavyTop(0.5, xc).evaluate(body, 0.0, q)
    assert np.allclose(tau, np.cross(xc, FB), atol=1e-15)
    assert np.allclose(U, 0.5 * qt.rotate(q, xc)[:, 2], atol=1e-15)  # M g z_c
    Up, _, taup = orbatt.HeavyTop(0.5, xc, sign="paper").evaluate(body, 0.0, q)
    assert np.allclose(Up, -U) and np.allclose(taup, -tau)


@pytest.mark.parametrize("potential", [orbatt.HeavyTop(0.7, [0.3, -0.2, 0.9])])
def test_gradient_is_tangential_and_matches_complex_step(potential):
    """Gradient of U(q/|q|): tangent to the sphere (q.dU/dq = 0: docs/design.md §3a item 8) and equal
    to a complex-step derivative of U_raw(q/|q|) (5e-16 level)."""
    rng = np.random.default_rng(2)
    xc = potential.params[1:]
    smg = potential.params[0]

    def cmul(a, b):  # Hamilton product, complex-safe (qt.mul works in float64)
        return np.array([a[0] * b[0] - a[1:] @ b[1:], *(a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:]))])

    def U_ext(q):  # raw formula composed with q/|q|, analytic in q for the complex step
        q = q / np.sqrt(np.sum(q * q))
        w = cmul(cmul(q, np.r_[0, xc]), q * np.array([1, -1, -1, -1]))
        return smg * w[3]

    body = orbatt.RigidBody(I)
    for _ in range(10):
        q = rng.normal(size=4) * 1.3  # off the sphere on purpose
        _, grad, _ = potential.evaluate(body, 0.0, q)
        h = 1e-30
        cs = np.array([U_ext(q + 1j * h * e).imag / h for e in np.eye(4)])
        assert np.allclose(grad[0], cs, atol=1e-15, rtol=1e-14)
        assert abs(qt.dot(q, grad[0])) < 1e-15


def test_heavy_top_conserves_energy_and_vertical_momentum():
    pot = orbatt.HeavyTop(0.5, [1.0, 0.0, 0.0])
    y = integrate(quaternion_rhs(pot.kind, pot.params), np.r_[q0, Q0], 100.0, 201)
    q, Q = y[:, :4], y[:, 4:]
    body = orbatt.RigidBody(I)
    E = cn.kinetic_energy(q, Q, I) + pot.evaluate(body, 0.0, q)[0]
    Gz = cn.space_momentum(q, Q)[:, 2]
    assert np.max(np.abs(E - E[0])) < 1e-11
    assert np.max(np.abs(Gz - Gz[0])) < 1e-11
    assert np.max(np.abs(qt.dot(q, Q) - qt.dot(q0, Q0))) < 1e-11
    assert np.max(np.abs(qt.norm(q) - 1)) < 1e-11
    # a real heavy top: G_x, G_y are not conserved
    assert np.ptp(cn.space_momentum(q, Q)[:, 0]) > 0.1


def test_heavy_top_matches_classical_model():
    xc = np.array([1.0, 0.0, 0.0])
    pot = orbatt.HeavyTop(0.5, xc)
    torque = lambda q: np.cross(xc, qt.rotate_inv(q, [0, 0, -0.5]))  # noqa: E731
    yc = integrate(classical_rhs(torque=torque), np.r_[q0, cn.body_rate(q0, Q0, I)], 50.0, 51)
    yq = integrate(quaternion_rhs(pot.kind, pot.params), np.r_[q0, Q0], 50.0, 51)
    assert np.max(np.abs(yq[:, :4] - yc[:, :4])) < 1e-10
    assert np.max(np.abs(cn.body_rate(yq[:, :4], yq[:, 4:], I) - yc[:, 4:])) < 1e-10


def test_heavy_top_validation():
    with pytest.raises(orbatt.InputError, match="sign"):
        orbatt.HeavyTop(0.5, [1, 0, 0], sign="up")
    with pytest.raises(orbatt.InputError, match="center_of_mass"):
        orbatt.HeavyTop(0.5, [1, 0])
    with pytest.raises(orbatt.InputError, match="mass_g"):
        orbatt.HeavyTop(-0.5, [1, 0, 0])

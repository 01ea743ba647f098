"""The exact torque-free solution (orbatt.analytic) against tight numerical integrations of
eq. (7) (the compiled kernel) and of the classical model (Euler's equations + quaternion
kinematics), in every regime; invariants; input handling.

Integrations use scipy's DOP853 at rtol = atol = 1e-13 and are compared at the integrator's
own step ends, not through its dense output (``docs/design.md`` §4: dense output is much less
accurate than the steps at this tolerance). The analytic solution itself was checked against
a 30-digit mpmath Taylor integration to 4e-15 (see the module docstring); the tolerances
below are those of the integrations (each test notes the error measured when it was written).
"""
import numpy as np
import pytest
from scipy import special as sp
from scipy.integrate import solve_ivp

import orbatt
from orbatt import analytic as an
from orbatt import canonical as cn
from orbatt import quaternion as qt
from orbatt.core import hamiltonian as H
from orbatt.core import model as km
from orbatt.core import potentials as kp
from orbatt.errors import InputError

# the paper's torque-free case (Sect. 6.1, Fig. 1)
I_PAPER = np.array([1.25, 1.0, 0.75])
Q_PAPER = np.array([0.5, -1 / np.sqrt(2), 0.0, 0.5])
P_PAPER = np.array([0.3, -0.848528, 0.141421, -1.5])
Q_UNIT = qt.normalize(np.array([0.3, 0.1, -0.4, 0.8]))
RTOL = 1e-13


def integrate(inertia, q0, Q0, t_end):
    """Eq. (7) with the compiled kernel (torque-free); returns step-end times and states."""
    inertia = np.asarray(inertia, dtype=np.float64)
    work = kp.new_work()
    model = km.build()

    def f(t, y):
        dy = np.empty(8)
        H.rhs(t, y, inertia, *model, work, dy)
        return dy

    sol = solve_ivp(f, (0.0, t_end), np.r_[q0, Q0], method="DOP853", rtol=RTOL, atol=RTOL)
    assert sol.success
    return sol.t, sol.y.T


def errors(inertia, q0, Q0, t_end):
    """``(max |q - q_num|, max |Q - Q_num| / |Q0|)`` of the exact solution at the steps."""
    t, y = integrate(inertia, q0, Q0, t_end)
    q, Q = an.torque_free(inertia, q0, Q0, t)
    return np.abs(q - y[:, :4]).max(), np.abs(Q - y[:, 4:]).max() / np.linalg.norm(Q0)


def state(g, q=Q_UNIT):
    return q, cn.momentum_from_body_momentum(q, np.asarray(g, dtype=np.float64))


def ratio_D(inertia, g):
    """``D = |g|^2 / 2T``."""
    g = np.asarray(g, dtype=np.float64)
    return g @ g / (g @ (g / np.asarray(inertia)))


@pytest.fixture(scope="module")
def paper_run():
    t, y = integrate(I_PAPER, Q_PAPER, P_PAPER, 100.0)
    q, Q = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, t)
    return t, y, q, Q


# ---- the paper's case and the two regimes ------------------------------------------------
def test_paper_case_matches_integration(paper_run):
    # D = 0.936 lies between I3 = 0.75 and I2 = 1: g circulates about body axis 3
    g0 = cn.body_momentum(Q_PAPER, P_PAPER)
    assert 0.75 < ratio_D(I_PAPER, g0) < 1.0
    t, y, q, Q = paper_run
    assert t[-1] == 100.0 and len(t) > 100
    # measured 1.6e-11 (q) and 1.8e-11 (Q): the integrator's error
    assert np.abs(q - y[:, :4]).max() < 1e-10
    assert np.abs(Q - y[:, 4:]).max() / np.linalg.norm(P_PAPER) < 1e-10
    g = cn.body_momentum(q, Q)
    assert np.all(np.sign(g[:, 2]) == np.sign(g0[2]))  # circulation about axis 3


def test_paper_case_negative_times():
    # measured 1.8e-11
    eq, eQ = errors(I_PAPER, Q_PAPER, P_PAPER, -100.0)
    assert eq < 1e-10 and eQ < 1e-10


def test_other_regime_circulation_about_largest_axis():
    g0 = np.array([1.0, 0.2, 0.3])
    assert ratio_D(I_PAPER, g0) > 1.0  # D = 1.18 between I2 = 1 and I1 = 1.25
    q0, Q0 = state(g0)
    eq, eQ = errors(I_PAPER, q0, Q0, 100.0)  # measured 2.9e-11
    assert eq < 1e-10 and eQ < 1e-10
    g = an.torque_free_momentum(I_PAPER, g0, np.linspace(0, 100, 2001))
    assert np.all(g[:, 0] > 0) and g[:, 2].min() < 0 < g[:, 2].max()


@pytest.mark.parametrize("g0", [(0.3, -0.8, 0.2), (-0.3, 0.8, -0.2), (0.2, 0.1, -0.9), (-1.0, -0.2, 0.3)])
def test_regimes_and_signs(g0):
    # both regimes, every sign of the circulating component (D = 1.006, 1.006, 0.77, 1.18)
    q0, Q0 = state(g0)
    eq, eQ = errors(I_PAPER, q0, Q0, 60.0)  # measured <= 1.9e-11
    assert eq < 1e-10 and eQ < 1e-10


# ---- separatrix ------------------------------------------------------------------------------
def test_separatrix_exact():
    # I = (1.5, 1, 0.75): (I1 - I2)/I1 = (I2 - I3)/I3 = 1/3, so g1 = g3 puts D = I2 exactly
    inertia = np.array([1.5, 1.0, 0.75])
    g0 = np.array([0.6, 0.5, 0.6])
    assert ratio_D(inertia, g0) == pytest.approx(1.0, abs=1e-15)
    # the numerical solution leaves the separatrix as exp(lam t) times its error (lam = 0.33):
    # compare over [0, 20], measured 4e-12
    eq, eQ = errors(inertia, *state(g0), 20.0)
    assert eq < 2e-11 and eQ < 2e-11
    # it tends to the unstable equilibria on the middle axis, opposite ones as t -> -+inf
    g = an.torque_free_momentum(inertia, g0, [-200.0, 200.0])
    G = np.linalg.norm(g0)
    np.testing.assert_allclose(np.abs(g), [[0.0, G, 0.0], [0.0, G, 0.0]], atol=1e-14)
    assert g[0, 1] * g[1, 1] < 0


def test_separatrix_paper_inertia():
    g0 = np.array([1.0, 0.3, np.sqrt(0.6)])  # D = I2 to rounding
    assert ratio_D(I_PAPER, g0) == pytest.approx(1.0, abs=1e-15)
    eq, eQ = errors(I_PAPER, *state(g0), 20.0)  # measured 1.6e-11 (1.8e-11 for Q)
    assert eq < 1e-10 and eQ < 1e-10


@pytest.mark.parametrize("eps, t_end", [(1e-3, 50.0), (1e-6, 80.0)])
def test_perturbed_spin_about_the_intermediate_axis(eps, t_end):
    # the tennis-racket (Dzhanibekov) flip: 1 - m ~ eps^2, next to the separatrix, where
    # scipy's ellipj (parameter m) would lose digits. The integration's error is amplified by
    # exp(lam t) near the unstable spin; measured 1.1e-11 and 2.2e-11
    g0 = np.array([eps, 1.0, eps])
    eq, eQ = errors(I_PAPER, *state(g0), t_end)
    assert eq < 1e-10 and eQ < 1e-10
    g = an.torque_free_momentum(I_PAPER, g0, np.linspace(0, t_end, 4001))
    assert g[:, 1].min() < -0.99  # it flips


# ---- steady spins and symmetric bodies --------------------------------------------------
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_pure_spin_about_each_principal_axis(axis):
    g0 = np.zeros(3)
    g0[axis] = -0.7 if axis == 1 else 0.7
    q0, Q0 = state(g0)
    eq, eQ = errors(I_PAPER, q0, Q0, 50.0)  # measured <= 9.4e-13
    assert eq < 1e-11 and eQ < 1e-11
    t = np.linspace(-30, 30, 61)
    q, Q = an.torque_free(I_PAPER, q0, Q0, t)
    w = g0 / I_PAPER
    q_expected = qt.mul(q0, qt.exp(qt.pure(0.5 * w * t[:, None])))
    np.testing.assert_allclose(q, q_expected, atol=1e-15)
    np.testing.assert_allclose(cn.body_momentum(q, Q), np.broadcast_to(g0, (61, 3)), atol=1e-14)


@pytest.mark.parametrize("inertia", [(1.0, 1.0, 0.5), (1.0, 0.5, 1.0), (0.6, 1.0, 1.0), (2.0, 2.0, 2.0)])
@pytest.mark.parametrize("g0", [(0.3, -0.8, 0.2), (1.0, 0.2, 0.3)])
def test_symmetric_bodies(inertia, g0):
    eq, eQ = errors(inertia, *state(g0), 60.0)  # measured <= 5.3e-12
    assert eq < 1e-10 and eQ < 1e-10
    inertia = np.asarray(inertia)
    t = np.linspace(-50, 50, 101)
    g = an.torque_free_momentum(inertia, g0, t)
    for k in range(3):  # the symmetry-axis component is constant
        if np.sum(inertia == inertia[k]) == 1:
            np.testing.assert_allclose(g[:, k], g0[k], rtol=1e-15)


def test_symmetric_body_spin_in_the_equal_moment_plane():
    # g in the plane of the two equal moments is an eigenvector: a steady rotation
    inertia = (1.0, 1.0, 0.5)
    g0 = np.array([0.3, 0.4, 0.0])
    eq, eQ = errors(inertia, *state(g0), 30.0)
    assert eq < 1e-11 and eQ < 1e-11
    np.testing.assert_array_equal(an.torque_free_momentum(inertia, g0, [1.0, 7.0]), [g0, g0])


@pytest.mark.parametrize(
    "inertia", [(0.75, 1.25, 1.0), (1.0, 0.75, 1.25), (1.25, 0.75, 1.0), (1.0, 1.25, 0.75)]
)
@pytest.mark.parametrize("g0", [(0.3, -0.8, 0.2), (1.0, 0.2, 0.3)])
def test_unsorted_inertia(inertia, g0):
    # the relabelling must be a proper (det +1) permutation: an odd one alone would reverse time
    eq, eQ = errors(inertia, *state(g0), 60.0)  # measured <= 2.5e-11
    assert eq < 1e-10 and eQ < 1e-10


@pytest.mark.parametrize(
    "inertia", [(1.0, 1.0 - 1e-12, 0.5), (0.5, 0.5 + 1e-12, 1.0), (1.0, 1.0 + 1e-9, 0.5)]
)
@pytest.mark.parametrize("g0", [(0.2, 0.3, 0.0), (0.6, 0.8, 1e-9), (1.0, 0.2, 0.3)])
def test_nearly_degenerate_moments(inertia, g0):
    # two moments equal to 1e-12: g moves very slowly (lam ~ 1e-6) and the precession angle
    # must not carry the round-off of the whole slow period (measured <= 1.2e-11)
    eq, eQ = errors(inertia, *state(g0), 40.0)
    assert eq < 1e-10 and eQ < 1e-10


def test_relabelling_the_body_axes_gives_the_same_motion():
    # a body with its axes cyclically relabelled (a proper rotation of the body frame by
    # mu, with R(mu) = P^T) moves identically in space
    P = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]], dtype=float)  # new axis k = old axis P[k]
    mu = qt.from_matrix(P.T)
    g0 = np.array([0.3, -0.8, 0.2])
    q0, Q0 = state(g0)
    t = np.linspace(-40, 40, 81)
    q, Q = an.torque_free(I_PAPER, q0, Q0, t)
    qb, Qb = an.torque_free(P @ I_PAPER, qt.mul(q0, mu), qt.mul(Q0, mu), t)
    np.testing.assert_allclose(qt.angle_between(q, qt.mul(qb, qt.conj(mu))), 0.0, atol=1e-13)
    np.testing.assert_allclose(cn.space_momentum(qb, Qb), cn.space_momentum(q, Q), atol=1e-14)


# ---- the classical model ------------------------------------------------------------------------
def test_classical_model(paper_run):
    """Euler's equations + dq/dt = q w / 2, integrated independently of eq. (7)."""
    q0 = Q_PAPER
    g0 = cn.body_momentum(q0, P_PAPER)
    w0 = g0 / I_PAPER
    I = I_PAPER

    def f(t, y):
        q0_, q1, q2, q3, w1, w2, w3 = y
        g1, g2, g3 = I[0] * w1, I[1] * w2, I[2] * w3
        return [
            0.5 * (-q1 * w1 - q2 * w2 - q3 * w3),
            0.5 * (q0_ * w1 + q2 * w3 - q3 * w2),
            0.5 * (q0_ * w2 - q1 * w3 + q3 * w1),
            0.5 * (q0_ * w3 + q1 * w2 - q2 * w1),
            (g2 * w3 - g3 * w2) / I[0],
            (g3 * w1 - g1 * w3) / I[1],
            (g1 * w2 - g2 * w1) / I[2],
        ]

    sol = solve_ivp(f, (0.0, 60.0), np.r_[q0, w0], method="DOP853", rtol=RTOL, atol=RTOL)
    assert sol.success
    q, Q = an.torque_free(I_PAPER, q0, P_PAPER, sol.t)
    # measured 5.6e-13 (q) and 1.9e-14 (g)
    assert np.abs(q - sol.y[:4].T).max() < 1e-10
    assert np.abs(cn.body_momentum(q, Q) - I * sol.y[4:].T).max() < 1e-10
    assert np.abs(an.torque_free_momentum(I, g0, sol.t) - I * sol.y[4:].T).max() < 1e-10


# ---- invariants, radial part, non-unit q ----------------------------------------------------
def test_invariants():
    t = np.linspace(-1000.0, 1000.0, 20001)
    q, Q = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, t)
    G0 = cn.space_momentum(Q_PAPER, P_PAPER)
    T0 = cn.kinetic_energy(Q_PAPER, P_PAPER, I_PAPER)
    assert np.abs(qt.norm(q) - 1.0).max() < 1e-15
    assert np.abs(cn.space_momentum(q, Q) - G0).max() < 1e-14  # measured 1.3e-15
    assert np.abs(cn.kinetic_energy(q, Q, I_PAPER) - T0).max() < 1e-14 * T0
    # the printed Q0's radial part q.Q = -9.7e-8 is carried along unchanged
    radial = qt.dot(Q_PAPER, P_PAPER)
    assert radial == pytest.approx(-9.7e-8, abs=1e-9)
    np.testing.assert_allclose(qt.dot(q, Q), radial, rtol=0, atol=1e-15)
    g = an.torque_free_momentum(I_PAPER, cn.body_momentum(Q_PAPER, P_PAPER), t)
    np.testing.assert_allclose(Q, 2.0 * qt.mul(q, qt.pure(g)) + radial * q, rtol=0, atol=1e-14)


def test_invariants_at_large_times():
    t = np.array([1e4, 1e6, 1e9, -1e12])
    q, Q = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, t)
    G0 = cn.space_momentum(Q_PAPER, P_PAPER)
    assert np.abs(qt.norm(q) - 1.0).max() < 1e-15
    assert np.abs(cn.space_momentum(q, Q) - G0).max() < 1e-14  # measured 6e-16


def test_non_unit_q0_is_the_exact_flow_of_eq7():
    # |q| is an invariant of eq. (7); the attitude q/|q| turns as a body with g = 1/2 Im(q~Q)
    q0 = 1.7 * Q_UNIT
    Q0 = 2.0 * qt.mul(q0, qt.pure(np.array([0.3, -0.8, 0.2]))) / 1.7**2 + 0.05 * q0
    eq, eQ = errors(I_PAPER, q0, Q0, 60.0)  # measured 1.0e-11 (q, |q| = 1.7), 6.3e-12 (Q)
    assert eq < 1e-10 and eQ < 1e-10


# ---- times: zero, negative, unsorted, shapes ----------------------------------------------
def test_initial_value_and_branch(paper_run):
    q, Q = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, [0.0])
    np.testing.assert_allclose(q[0], Q_PAPER, atol=3e-16)  # q0 itself, not -q0
    np.testing.assert_allclose(Q[0], P_PAPER, atol=1e-15)
    # continuous in t: neighbouring samples are close (no sign flips)
    t = np.linspace(-200, 200, 40001)
    q, _ = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, t)
    assert np.abs(np.diff(q, axis=0)).max() < 0.02


def test_unsorted_and_negative_times():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(-300, 300, 501))
    t[250] = 0.0
    perm = rng.permutation(len(t))
    for inertia, q0, Q0 in [(I_PAPER, Q_PAPER, P_PAPER), ((1.0, 0.75, 1.25), *state((1.0, 0.2, 0.3))),
                            ((1.5, 1.0, 0.75), *state((0.6, 0.5, 0.6)))]:
        q, Q = an.torque_free(inertia, q0, Q0, t)
        qp, Qp = an.torque_free(inertia, q0, Q0, t[perm])
        np.testing.assert_allclose(qp, q[perm], rtol=0, atol=1e-15)
        np.testing.assert_allclose(Qp, Q[perm], rtol=0, atol=1e-15)


def test_time_shapes():
    q, Q = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, 2.5)
    assert q.shape == Q.shape == (4,)
    q2, _ = an.torque_free(I_PAPER, Q_PAPER, P_PAPER, [[2.5, 0.0], [1.0, -1.0]])
    assert q2.shape == (2, 2, 4)
    np.testing.assert_allclose(q2[0, 0], q, atol=1e-16)
    assert an.torque_free(I_PAPER, Q_PAPER, P_PAPER, [])[0].shape == (0, 4)
    assert an.torque_free_momentum(I_PAPER, [0.1, 0.2, 0.3], np.zeros((3, 2))).shape == (3, 2, 3)


def test_rigid_body_input_and_scaling():
    # a dimensional body (kg km^2, s): the same motion as the scaled dimensionless one
    body = orbatt.RigidBody([400.0, 500.0, 600.0] * orbatt.units.INERTIA)
    g0 = np.array([0.3, -0.8, 0.2]) * 1e-3
    q0, Q0 = state(g0)
    t = np.linspace(-3e5, 3e5, 31)
    q, Q = an.torque_free(body, q0, Q0, t)
    # I -> I/500, g -> g/1e-3 maps t -> t * 1e-3 / 500
    qs, Qs = an.torque_free([0.8, 1.0, 1.2], q0, Q0 * 1e3, t * 2e-6)
    np.testing.assert_allclose(q, qs, atol=2e-14)
    np.testing.assert_allclose(Q * 1e3, Qs, atol=2e-14)
    eq, eQ = errors(body.inertia_value, q0, Q0, 2e7)  # 40 rad, measured 1.6e-12
    assert eq < 1e-10 and eQ < 1e-10


# ---- the momentum solution and the elliptic functions -------------------------------------
def test_momentum_matches_the_attitude_solution():
    t = np.linspace(-50, 50, 1001)
    for inertia, g0 in [(I_PAPER, (0.3, -0.8, 0.2)), ((0.75, 1.25, 1.0), (1.0, 0.2, 0.3)),
                        ((1.5, 1.0, 0.75), (0.6, 0.5, 0.6)), ((1.0, 1.0, 0.5), (0.3, 0.4, 0.5))]:
        q, Q = an.torque_free(inertia, *state(g0), t)
        np.testing.assert_allclose(cn.body_momentum(q, Q), an.torque_free_momentum(inertia, g0, t),
                                   rtol=0, atol=1e-15)


def test_momentum_satisfies_euler_equations():
    # central differences of the closed form against Euler's right-hand side
    h = 1e-4
    t = np.linspace(-20, 20, 41)
    cases = [(I_PAPER, (0.3, -0.8, 0.2)), (I_PAPER, (1.0, 0.2, 0.3)), ((1.5, 1.0, 0.75), (0.6, 0.5, 0.6))]
    for inertia, g0 in cases:
        inertia = np.asarray(inertia)
        g = an.torque_free_momentum(inertia, g0, t)
        gp = an.torque_free_momentum(inertia, g0, t + h)
        gm = an.torque_free_momentum(inertia, g0, t - h)
        np.testing.assert_allclose((gp - gm) / (2 * h), np.cross(g, g / inertia), atol=1e-8)


@pytest.mark.parametrize("m", [0.0, 0.3, 0.9, 0.999999])
def test_jacobi_matches_scipy(m):
    K = sp.ellipk(m)
    u = np.linspace(-K, K, 201)
    sn, cn_, dn, _ = sp.ellipj(u, m)
    s, c, d = an.jacobi(u, 1.0 - m)
    for a, b in ((s, sn), (c, cn_), (d, dn)):
        np.testing.assert_allclose(a, b, rtol=0, atol=2e-14)


@pytest.mark.parametrize("m1", [1e-6, 1e-14, 1e-40])
def test_jacobi_near_m_equal_1(m1):
    K = float(sp.elliprf(0.0, m1, 1.0))
    u = np.linspace(-K, K, 401)
    sn, cn_, dn = an.jacobi(u, m1)
    np.testing.assert_allclose(sn * sn + cn_ * cn_, 1.0, atol=4e-16)
    np.testing.assert_allclose(dn * dn + (1 - m1) * sn * sn, 1.0, atol=4e-16)
    np.testing.assert_allclose(an.jacobi(K, m1)[1], 0.0, atol=1e-15)  # cn(K) = 0, to the digit
    # dn(K) = sqrt(m1), to the absolute accuracy of cn (about 1e-16)
    np.testing.assert_allclose(an.jacobi(K, m1)[2], np.sqrt(m1), rtol=1e-6, atol=1e-15)
    # near u = 0, sn -> tanh u as m -> 1
    np.testing.assert_allclose(an.jacobi(0.5, m1)[0], np.tanh(0.5), atol=m1)
    with pytest.raises(InputError, match="m1"):
        an.jacobi(u, 0.0)


# ---- input validation --------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(inertia=(1.0, 2.0)), r"inertia: expected .*shape \(2,\)"),
        (dict(inertia=(1.0, 0.0, 2.0)), r"inertia: \[1.0, 0.0, 2.0\] has a moment <= 0"),
        (dict(inertia=(1.0, -1.0, 2.0)), r"inertia: .*must be\s+positive"),
        (dict(inertia=(1.0, np.nan, 2.0)), r"inertia: .*non-finite"),
        (dict(q0=(1.0, 0.0, 0.0)), r"q0: expected shape \(4,\).*got shape \(3,\)"),
        (dict(q0=(0.0, 0.0, 0.0, 0.0)), r"q0: the zero quaternion"),
        (dict(q0=(1.0, np.nan, 0.0, 0.0)), r"q0: .*non-finite"),
        (dict(Q0=np.zeros((2, 4))), r"Q0: expected shape \(4,\).*\(2, 4\)"),
        (dict(Q0=(0.0, np.inf, 0.0, 0.0)), r"Q0: .*non-finite"),
        (dict(t=[0.0, np.inf]), r"t: contains the non-finite time inf; give finite times"),
        (dict(t=["a"]), r"t: .*not an array of times"),
        (dict(t="10 s"), r"t: got '10 s'; .*plain floats"),
    ],
)
def test_bad_input(kwargs, match):
    args = dict(inertia=I_PAPER, q0=Q_PAPER, Q0=P_PAPER, t=[0.0, 1.0])
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        an.torque_free(args["inertia"], args["q0"], args["Q0"], args["t"])


def test_bad_input_momentum_and_quantities():
    with pytest.raises(InputError, match=r"g0: expected shape \(3,\)"):
        an.torque_free_momentum(I_PAPER, [1.0, 2.0, 3.0, 4.0], [0.0])
    with pytest.raises(InputError, match=r"inertia: .*Quantity|inertia: got"):
        an.torque_free_momentum([1.0, 2.0, 3.0] * orbatt.units.INERTIA, [1.0, 2.0, 3.0], [0.0])
    with pytest.raises(ValueError):  # InputError is also a ValueError
        an.torque_free_momentum(I_PAPER, [1.0, np.nan, 3.0], [0.0])

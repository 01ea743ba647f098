"""The gravity-gradient potential (eq. 20, docs/design.md §3) driven by orbit providers:
gradient vs complex step, torque vs the classical formula, the paper's Sect. 6.2 case vs
the classical Euler-equation model, REBOUND-driven vs Kepler-driven attitude."""
import json
import math

import astropy.units as u
import numba as nb
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from orbatt import RigidBody
from orbatt import canonical as cn
from orbatt import quaternion as qt
from orbatt.core import hamiltonian as ham
from orbatt.core import model as km
from orbatt.core import kepler as kk
from orbatt.core import potentials as kp
from orbatt.errors import InputError
from orbatt.orbits import KeplerOrbit, ReboundOrbit
from orbatt.potentials import GravityGradient

INERTIA = np.array([400.0, 500.0, 600.0])  # kg km^2 (paper Sect. 6.2)
Q0_PAPER = np.array([0.5, -1 / math.sqrt(2), 0.0, 0.5])
P0_PAPER = np.array([0.3, -0.848528, 0.141421, -1.5])  # kg km^2 / s, 6 printed digits


@pytest.fixture(scope="module")
def paper():
    return KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg, true_anomaly=0 * u.deg,
                       body_radius=None)


@pytest.fixture(scope="module")
def body():
    return RigidBody(INERTIA * u.kg * u.km**2)


# ---- complex-step reference ----------------------------------------------------------------
def _cmul(a, b):
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return np.array([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0])


def _U_holomorphic(q, inertia, k, xhat):
    """Eq. (20) extended as a function of q/|q|, written with operations that are analytic
    in q (no complex conjugation, |q|^2 = sum q_i^2), so complex step differentiates it."""
    qc = np.array([q[0], -q[1], -q[2], -q[3]])
    xb = _cmul(_cmul(qc, np.array([0.0, *xhat])), q)[1:]
    n2 = np.sum(q * q)
    return 1.5 * k * np.sum(xb * inertia * xb) / (n2 * n2)


def _complex_step_gradient(q, inertia, k, xhat, h=1e-30):
    g = np.empty(4)
    for i in range(4):
        qq = q.astype(complex)
        qq[i] += 1j * h
        g[i] = _U_holomorphic(qq, inertia, k, xhat).imag / h
    return g


@pytest.mark.parametrize("scale", [1.0, 1.3, 0.7])
def test_gradient_matches_complex_step(scale):
    rng = np.random.default_rng(11)
    k = 398600.4418 / 7000.0**3
    worst = 0.0
    for _ in range(200):
        q = rng.normal(size=4)
        q *= scale / np.linalg.norm(q)
        x = rng.normal(size=3)
        x /= np.linalg.norm(x)
        U, grad = kp.gravity_gradient(tuple(q), INERTIA, k, tuple(x))
        ref = _complex_step_gradient(q, INERTIA, k, x)
        # relative to the gradient's natural scale 6 k I3 (the tangential gradient vanishes at the
        # relative equilibria, where a componentwise relative error means nothing)
        worst = max(worst, np.max(np.abs(np.array(grad) - ref)) / (6 * k * INERTIA.max() / scale))
        assert U == pytest.approx(_U_holomorphic(q, INERTIA, k, x).real, rel=1e-14)
        assert abs(np.dot(grad, q)) <= 1e-14 * np.linalg.norm(ref) * scale  # tangential
    assert worst < 1e-9  # the bound
    assert worst < 2e-15  # measured 5e-16


def test_torque_is_the_classical_formula_along_the_orbit(paper, body):
    gg = GravityGradient(paper)
    rng = np.random.default_rng(5)
    t = rng.uniform(0, 3 * paper.period_value, 300)
    q = qt.normalize(rng.normal(size=(300, 4)))
    U, grad, tau = gg.evaluate(body, t, q)
    r = paper.radius(t)
    xb = qt.rotate_inv(q, paper.radial_direction(t))
    c = 3 * paper.gm / r**3
    tau_ref = c[:, None] * np.cross(xb, INERTIA * xb)
    assert np.max(np.linalg.norm(tau - tau_ref, axis=-1)) < 1e-13 * np.max(np.linalg.norm(tau_ref, axis=-1))
    assert np.allclose(U, 0.5 * c * np.sum(xb * INERTIA * xb, axis=-1), rtol=1e-14, atol=0)
    assert np.max(np.abs(np.sum(grad * q, axis=-1))) < 1e-14 * np.max(np.abs(grad))
    # the same from the kernel-level torque: tau = -1/2 Im(q~ dU/dq)
    tq = np.array([kp.torque_from_gradient(tuple(qi), tuple(gi)) for qi, gi in zip(q[:5], grad[:5])])
    assert np.allclose(tq, tau[:5], rtol=1e-15, atol=0)


def test_vectorized_over_an_ensemble(paper, body):
    gg = GravityGradient(paper)
    rng = np.random.default_rng(2)
    q = qt.normalize(rng.normal(size=(64, 4)))
    t = np.full(64, 1234.5)
    U, grad, tau = gg.evaluate(body, t, q)
    for i in (0, 17, 63):  # (the Kepler warm start may change the last bit)
        Ui, gi, ti = gg.evaluate(body, t[i:i + 1], q[i:i + 1])
        assert np.allclose(Ui[0], U[i], rtol=1e-15, atol=0) and np.allclose(gi[0], grad[i], rtol=1e-14, atol=0)
        assert np.allclose(ti[0], tau[i], rtol=1e-14, atol=0)
    U2, _, _ = gg.evaluate(body, 1234.5, q)  # one time for all members
    assert np.allclose(U2, U, rtol=1e-15, atol=0)


def test_potential_object_and_validation(paper):
    gg = GravityGradient(paper)
    assert gg.orbit is paper and gg.kind == kp.GRAVITY_GRADIENT_KEPLER
    assert np.array_equal(gg.params, paper.kernel()[1])
    d = gg.describe()
    json.dumps(d)
    assert d["kind"] == "gravity-gradient" and d["orbit"]["type"] == "kepler"
    with pytest.raises(InputError, match="orbit: expected an orbit provider"):
        GravityGradient("kepler")
    with pytest.raises(InputError, match="body: plain-number inertia with a dimensional orbit"):
        gg.check_body(RigidBody([400.0, 500.0, 600.0]))
    ro = ReboundOrbit(paper, 600 * u.s)
    gr = GravityGradient(ro)
    assert gr.kind == kp.GRAVITY_GRADIENT_SAMPLED and gr.table is ro.samples
    with pytest.raises(InputError, match="outside the sampled span"):
        gr.evaluate(RigidBody(INERTIA * u.kg * u.km**2), [0.0, 601.0], np.tile(Q0_PAPER, (2, 1)))


def test_kernel_model_is_built_once_and_handed_out_as_copies(paper):
    """A potential builds its model once; kernel_model() hands out writeable copies (a caller
    changing them changes no later call or run), and the potential's parameters are
    read-only (the cached model cannot go stale)."""
    gg = GravityGradient(paper)
    first = gg.kernel_model()
    expected = km.from_spec(gg.kind, gg.params, gg.table)
    assert all(np.array_equal(a, b) for a, b in zip(first, expected))
    for a in first:
        assert a.flags.writeable and a.flags.c_contiguous
        a[...] = 0
    again = gg.kernel_model()
    assert all(np.array_equal(a, b) for a, b in zip(again, expected))
    assert all(a is not b for a, b in zip(again, first))
    with pytest.raises(ValueError, match="read-only"):
        gg.params[0] = 1.0


def test_models_of_equal_potentials_are_remembered_but_never_shared(paper):
    """Two potentials with the same kernel specification (a scenario loaded twice) get the
    model from_spec builds, each in arrays of its own: changing one changes no other."""
    first, second = GravityGradient(paper).build_model(), GravityGradient(paper).build_model()
    gg = GravityGradient(paper)
    expected = km.from_spec(gg.kind, gg.params, gg.table)
    for a, b, c in zip(first, second, expected):
        assert a is not b and a.dtype == c.dtype and a.flags.c_contiguous and a.flags.writeable
        assert a.tobytes() == b.tobytes() == c.tobytes()
        a[...] = 0
    again = GravityGradient(paper).build_model()
    assert all(a.tobytes() == c.tobytes() for a, c in zip(again, expected))


# ---- the paper's Sect. 6.2 case against the classical model --------------------------------
@nb.njit(cache=False)
def _classical_rhs(t, y, inertia, gm, orb, work):
    """Euler's equations + q' = 1/2 q (0, w) + the classical gravity-gradient torque."""
    r, x = kk.kepler_radial(t, orb, work)
    q0, q1, q2, q3 = y[0], y[1], y[2], y[3]
    n = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    a0, a1, a2, a3 = q0 / n, q1 / n, q2 / n, q3 / n
    # x_B = R(q)^T x_S with R the matrix of x -> q x q~
    xb0 = (1 - 2 * (a2 * a2 + a3 * a3)) * x[0] + 2 * (a1 * a2 + a0 * a3) * x[1] + 2 * (a1 * a3 - a0 * a2) * x[2]
    xb1 = 2 * (a1 * a2 - a0 * a3) * x[0] + (1 - 2 * (a1 * a1 + a3 * a3)) * x[1] + 2 * (a2 * a3 + a0 * a1) * x[2]
    xb2 = 2 * (a1 * a3 + a0 * a2) * x[0] + 2 * (a2 * a3 - a0 * a1) * x[1] + (1 - 2 * (a1 * a1 + a2 * a2)) * x[2]
    c = 3.0 * gm / (r * r * r)
    I1, I2, I3 = inertia[0], inertia[1], inertia[2]
    t1 = c * (xb1 * I3 * xb2 - xb2 * I2 * xb1)
    t2 = c * (xb2 * I1 * xb0 - xb0 * I3 * xb2)
    t3 = c * (xb0 * I2 * xb1 - xb1 * I1 * xb0)
    w0, w1, w2 = y[4], y[5], y[6]
    dy = np.empty(7)
    dy[0] = 0.5 * (-q1 * w0 - q2 * w1 - q3 * w2)
    dy[1] = 0.5 * (q0 * w0 + q2 * w2 - q3 * w1)
    dy[2] = 0.5 * (q0 * w1 - q1 * w2 + q3 * w0)
    dy[3] = 0.5 * (q0 * w2 + q1 * w1 - q2 * w0)
    dy[4] = (t1 - (I3 - I2) * w1 * w2) / I1
    dy[5] = (t2 - (I1 - I3) * w2 * w0) / I2
    dy[6] = (t3 - (I2 - I1) * w0 * w1) / I3
    return dy


def _hamiltonian_solution(orbit, y0, t_eval, rtol=3e-14):
    terms, params, table = km.from_spec(*orbit.kernel())
    work = kp.new_work()

    def f(t, y):
        dy = np.empty(8)
        ham.rhs(t, y, INERTIA, terms, params, table, work, dy)
        return dy

    sol = solve_ivp(f, (t_eval[0], t_eval[-1]), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2, t_eval=t_eval)
    assert sol.status == 0
    return sol.y[:4].T, sol.y[4:].T


def test_paper_sect_6_2_agrees_with_the_classical_model_over_10_orbits(paper):
    q0 = Q0_PAPER / np.linalg.norm(Q0_PAPER)
    assert abs(np.dot(q0, P0_PAPER)) == pytest.approx(9.7e-8, rel=0.01)  # docs/design.md §3a item 9
    P0 = P0_PAPER - np.dot(q0, P0_PAPER) * q0  # its tangential part (same g, same physics)
    assert np.allclose(cn.body_momentum(q0, P0), cn.body_momentum(q0, P0_PAPER), rtol=0, atol=1e-15)
    t_eval = np.linspace(0, 10 * paper.period_value, 401)
    qH, QH = _hamiltonian_solution(paper, np.concatenate([q0, P0]), t_eval)
    orb = paper.kernel()[1][1:]
    work = np.full(4, np.nan)
    w0 = cn.body_rate(q0, P0, INERTIA)
    sol = solve_ivp(lambda t, y: _classical_rhs(t, y, INERTIA, paper.gm, orb, work), (0, t_eval[-1]),
                    np.concatenate([q0, w0]), method="DOP853", rtol=3e-14, atol=3e-16, t_eval=t_eval)
    qC, wC = sol.y[:4].T, sol.y[4:].T
    # measured: attitude 4e-12 rad, momentum 3e-12 relative (both integrations at rtol 3e-14)
    assert np.max(qt.angle_between(qH, qC)) < 3e-11
    gH = cn.body_momentum(qH, QH)
    assert np.max(np.linalg.norm(gH - INERTIA * wC, axis=-1) / np.linalg.norm(gH, axis=-1)) < 3e-11
    # constraints stay at round-off (measured 1.7e-14 and 3e-14: DOP853 is not structure-preserving)
    assert np.max(np.abs(np.linalg.norm(qH, axis=-1) - 1)) < 1e-13
    assert np.max(np.abs(np.sum(qH * QH, axis=-1)) / np.linalg.norm(QH, axis=-1)) < 1e-13
    # energy is not conserved (time-dependent U) but the motion is bounded and non-trivial
    assert np.max(qt.angle_between(qH, np.tile(q0, (len(t_eval), 1)))) > 1.0


def test_printed_momentum_keeps_its_radial_part(paper):
    """With the paper's printed Q(t0) (q.Q = -9.7e-8), q.Q is an invariant of the exact
    flow with the tangential gradient: it stays at its initial value."""
    q0 = Q0_PAPER / np.linalg.norm(Q0_PAPER)
    t_eval = np.linspace(0, 2 * paper.period_value, 41)
    qH, QH = _hamiltonian_solution(paper, np.concatenate([q0, P0_PAPER]), t_eval)
    qQ = np.sum(qH * QH, axis=-1)
    assert np.allclose(qQ, np.dot(q0, P0_PAPER), rtol=0, atol=1e-13)


def test_rebound_driven_attitude_matches_kepler_driven(paper):
    """Two-body REBOUND samples handed to the kernel (kind 3) drive the same attitude as the
    in-kernel Kepler solve (kind 2)."""
    ro = ReboundOrbit(paper, 3 * paper.period_value * u.s)
    q0 = Q0_PAPER / np.linalg.norm(Q0_PAPER)
    P0 = P0_PAPER - np.dot(q0, P0_PAPER) * q0
    t_eval = np.linspace(0, 3 * paper.period_value, 121)
    y0 = np.concatenate([q0, P0])
    qK, QK = _hamiltonian_solution(paper, y0, t_eval, rtol=1e-13)
    qR, QR = _hamiltonian_solution(ro, y0, t_eval, rtol=1e-13)
    assert np.max(qt.angle_between(qK, qR)) < 1e-10  # measured ~1e-11
    assert np.max(np.abs(QK - QR)) < 1e-10 * np.max(np.abs(QK))

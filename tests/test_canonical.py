"""Canonical variables (q, Q), the paper's initial data, and the Euler-angle form."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import orbatt
from orbatt import canonical as cn
from orbatt import euler as eu
from orbatt import quaternion as qt
from orbatt.errors import InputError

I_PAPER = np.array([1.25, 1.0, 0.75])
Q0_PAPER_Q = np.array([0.5, -1 / np.sqrt(2), 0.0, 0.5])
Q0_PAPER_P = np.array([0.3, -0.848528, 0.141421, -1.5])
EULER0 = np.array([np.pi / 4, 3 * np.pi / 2, np.pi / 4])
EULER_MOMENTA0 = np.array([0.5, 0.6, 0.4])

unit_quats = arrays(np.float64, 4, elements=st.floats(-1, 1)).filter(lambda q: np.linalg.norm(q) > 1e-2).map(
    lambda q: q / np.linalg.norm(q))
vec3 = arrays(np.float64, 3, elements=st.floats(-5, 5))


@given(unit_quats, vec3)
def test_momentum_round_trips(q, w):
    Q = cn.momentum_from_omega(q, w, I_PAPER)
    assert abs(qt.dot(q, Q)) < 1e-13 * max(1, np.linalg.norm(Q))
    assert np.allclose(cn.body_rate(q, Q, I_PAPER), w, atol=1e-13, rtol=0)
    g = I_PAPER * w
    assert np.allclose(cn.body_momentum(q, Q), g, atol=1e-13, rtol=0)
    assert np.allclose(cn.space_momentum(q, Q), qt.rotate(q, g), atol=1e-13, rtol=0)
    # Q = 4 q (I (x) q~ dq/dt) with dq/dt = 1/2 q omega  (paper eq. 5)
    qdot = 0.5 * qt.mul(q, qt.pure(w))
    Q_eq5 = 4 * qt.mul(q, qt.hadamard(np.r_[0, I_PAPER], qt.mul(qt.conj(q), qdot)))
    assert np.allclose(Q_eq5, Q, atol=1e-12)
    assert np.isclose(cn.kinetic_energy(q, Q, I_PAPER), 0.5 * g @ w, rtol=1e-13, atol=1e-13)


@given(unit_quats, vec3)
def test_euler_momenta_round_trip(q, g):
    Q = cn.momentum_from_body_momentum(q, g)
    ang, mom = eu.from_canonical(q, Q)
    if np.sin(ang[1]) < 1e-3:
        return  # Euler momenta are singular there; the quaternion form is not
    q2, Q2 = eu.to_canonical(ang, mom)
    s = np.sign(qt.dot(q, q2))
    assert np.allclose(s * q2, q, atol=1e-11)
    assert np.allclose(s * Q2, Q, atol=1e-9 * max(1, np.linalg.norm(Q)))
    # eq. (10) with the Psi^2 / I3 term equals T (the paper's print drops the 1/I3: §3a item 4)
    assert np.isclose(eu.hamiltonian(ang, mom, I_PAPER), cn.kinetic_energy(q, Q, I_PAPER), rtol=1e-9, atol=1e-12)


def test_eq10_needs_the_inverse_I3_on_psi_squared():
    ang, mom = np.array([0.3, 1.1, -0.4]), np.array([0.2, -0.7, 0.9])
    q, Q = eu.to_canonical(ang, mom)
    T = cn.kinetic_energy(q, Q, I_PAPER)
    printed = eu.hamiltonian(ang, mom, I_PAPER) - 0.5 * mom[2] ** 2 / I_PAPER[2] + 0.5 * mom[2] ** 2
    assert np.isclose(eu.hamiltonian(ang, mom, I_PAPER), T, rtol=1e-14)
    assert not np.isclose(printed, T, rtol=1e-3)


def test_paper_initial_data_both_forms():
    """docs/design.md §3a items 5, 6 and 9: what the paper's two forms of the Sect. 6.1 initial
    state give. Eq. (12) at (pi/4, 3pi/2, pi/4) gives -q(t0); eq. (14) gives +Q(t0) (to the
    6 printed digits): the printed (q, Q) pair has g = (-0.0707107, 0.7778173, -0.4), the
    opposite of the Euler-variable state's g."""
    qe, Qe = eu.to_canonical(EULER0, EULER_MOMENTA0)
    assert np.allclose(qe, -Q0_PAPER_Q, atol=1e-15)
    assert np.allclose(Qe, Q0_PAPER_P, atol=1e-6)
    g_printed = cn.body_momentum(Q0_PAPER_Q, Q0_PAPER_P)
    assert np.allclose(g_printed, [-0.0707107, 0.7778173, -0.4], atol=2e-7)
    assert np.allclose(cn.body_momentum(qe, Qe), [0.0707107, -0.7778175, 0.4], atol=2e-7)
    # eqs. (13), (15) map back into 0 < theta < pi: (5pi/4, pi/2, 5pi/4), Theta of opposite sign
    ang, mom = eu.from_canonical(qe, Qe)
    assert np.allclose(np.mod(ang, 2 * np.pi), [5 * np.pi / 4, np.pi / 2, 5 * np.pi / 4], atol=1e-12)
    assert np.allclose(mom, [0.5, -0.6, 0.4], atol=1e-6)
    # item 9: the printed Q has a radial residual q.Q = -9.7e-8, accepted and reported
    body = orbatt.RigidBody(I_PAPER)
    s = orbatt.State(body, Q0_PAPER_Q, Q0_PAPER_P)
    assert s.radial_residual == pytest.approx(-9.7173e-8, rel=1e-3)


def test_node_vector_and_b1():
    """docs/design.md §3a item 3: b1 = l cos psi + (b3 x l) sin psi (the print has s3 x l)."""
    rng = np.random.default_rng(5)
    for phi, th, ps in rng.uniform([-3, 0.1, -3], [3, 3.0, 3], size=(20, 3)):
        q = qt.from_euler313(phi, th, ps)
        l = np.array([np.cos(phi), np.sin(phi), 0.0])
        b1, b3 = qt.rotate(q, [1, 0, 0]), qt.rotate(q, [0, 0, 1])
        assert np.allclose(b1, l * np.cos(ps) + np.cross(b3, l) * np.sin(ps), atol=1e-14)
        assert not np.allclose(b1, l * np.cos(ps) + np.cross([0, 0, 1], l) * np.sin(ps), atol=1e-3)


def test_paper_matrix_is_the_transpose():
    """docs/design.md §3a item 2: the printed R (rows R(e_i) = p e_i p~ read as rows) is the
    transpose of x -> p x p~."""
    q = qt.normalize([0.3, -0.2, 0.9, 0.1])
    rows = np.array([qt.rotate(q, e) for e in np.eye(3)])
    x = np.array([0.3, -1.2, 2.0])
    assert np.allclose(rows.T @ x, qt.rotate(q, x), atol=1e-14)
    assert np.allclose(rows @ x, qt.rotate_inv(q, x), atol=1e-14)


# ---- validation -----------------------------------------------------------------------

def test_rigid_body_validation():
    with pytest.raises(InputError, match="positive"):
        orbatt.RigidBody([1.0, -1.0, 1.0])
    with pytest.raises(InputError, match="triangle"):
        orbatt.RigidBody([1.0, 1.0, 3.0])
    with pytest.raises(InputError, match="shape"):
        orbatt.RigidBody([1.0, 1.0])
    with pytest.raises(InputError, match="not finite"):
        orbatt.RigidBody([1.0, np.nan, 1.0])
    with pytest.raises(InputError, match="dimension"):
        import astropy.units as u
        orbatt.RigidBody([1, 2, 2] * u.kg)
    orbatt.RigidBody([1.0, 1.0, 2.0])  # a flat lamina: equality allowed


def test_state_validation():
    body = orbatt.RigidBody(I_PAPER)
    with pytest.raises(InputError, match=r"\|q\|"):
        orbatt.State(body, [1, 0, 0, 0.1], [0, 0, 0, 0])
    with pytest.raises(InputError, match="zero quaternion"):
        orbatt.State(body, [0, 0, 0, 0], [0, 0, 0, 0])
    with pytest.raises(InputError, match="non-finite"):
        orbatt.State(body, [np.inf, 0, 0, 0], [0, 0, 0, 0])
    with pytest.raises(InputError, match=r"q\.Q = 0\.5"):
        orbatt.State(body, [1, 0, 0, 0], [0.5, 1, 0, 0])
    with pytest.raises(InputError, match="shape"):
        orbatt.State(body, [1, 0, 0, 0], [0, 1, 0])
    with pytest.raises(InputError, match="singular"):
        orbatt.State.from_euler(body, [0.1, 0.0, 0.2], [1, 1, 1])


def test_state_constructors_agree():
    import astropy.units as u

    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    q = qt.normalize([0.2, 0.4, -0.1, 0.8])
    w = [1e-3, -2e-3, 5e-4] * u.rad / u.s
    s1 = orbatt.State.from_omega(body, q, w)
    s2 = orbatt.State.from_momentum(body, q, (body.inertia * w / u.rad).to(u.kg * u.m**2 / u.s))
    assert np.allclose(s1.Q, s2.Q, rtol=1e-14, atol=1e-15)
    assert np.allclose(s1.omega, w.value, rtol=1e-14)
    with pytest.raises(InputError, match="no unit"):
        orbatt.State.from_omega(body, q, [1e-3, 0, 0])
    ang, mom = s1.euler()
    s3 = orbatt.State.from_euler(body, ang, mom)
    assert np.allclose(np.sign(qt.dot(s3.q, s1.q)) * s3.Q, s1.Q, rtol=1e-10, atol=1e-15)

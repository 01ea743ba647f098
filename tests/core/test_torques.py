"""Flat-plate drag and SRP, and the magnetic torque, at single instants against independent
evaluations written here (docs/design.md §10); drag as a term of the model."""
from __future__ import annotations

import numpy as np
import pytest

from orbatt import quaternion as qt
from orbatt.core import hamiltonian as H
from orbatt.core import kepler
from orbatt.core import evaluation as kev
from orbatt.core import model as km
from orbatt.core import potentials as kp
from orbatt.core import torques as trq
from orbatt.environment.sun import shadow
from orbatt.environment.tables import Pieces, piece_table, piece_times

rng = np.random.default_rng(11)


def _facets(n=6):
    """A box-like body: six plates with random areas, offsets and reflectivities."""
    normals = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)[:n]
    F = np.zeros((n, trq.FACET_SIZE))
    F[:, 0] = rng.uniform(0.01, 0.1, n)
    F[:, 1:4] = normals
    F[:, 4:7] = normals * 0.15 + rng.normal(scale=0.02, size=(n, 3))
    F[:, 7] = rng.uniform(0, 0.5, n)
    F[:, 8] = rng.uniform(0, 0.4, n)
    return F


def _drag_reference(q, k, vhat_s, F):
    v = qt.rotate_inv(q, vhat_s)
    tau = np.zeros(3)
    for f in F:
        c = max(0.0, f[1:4] @ v)
        force = -k * f[0] * c * v
        tau += np.cross(f[4:7], force)
    return tau


def _srp_reference(q, P, shat_s, F):
    s = qt.rotate_inv(q, shat_s)
    tau = np.zeros(3)
    for f in F:
        n = f[1:4]
        c = n @ s
        if c <= 0:
            continue
        force = -P * f[0] * c * ((1 - f[7]) * s + 2 * (f[7] * c + f[8] / 3) * n)
        tau += np.cross(f[4:7], force)
    return tau


@pytest.mark.parametrize("seed", range(5))
def test_facet_torques_match_the_flat_plate_formulas(seed):
    r = np.random.default_rng(seed)
    F = _facets()
    q = qt.normalize(r.normal(size=4))
    d = qt.normalize(np.r_[0.0, r.normal(size=3)])[1:]
    k = 0.5 * 3e-3 * 7.6**2
    tau = np.array(trq.facet_drag(tuple(q), k, tuple(d), F.ravel(), 0, F.shape[0]))
    np.testing.assert_allclose(tau, _drag_reference(q, k, d, F), rtol=1e-13, atol=1e-30)
    tau = np.array(trq.facet_srp(tuple(q), 4.5e-6, tuple(d), F.ravel(), 0, F.shape[0]))
    np.testing.assert_allclose(tau, _srp_reference(q, 4.5e-6, d, F), rtol=1e-13, atol=1e-30)
    m = r.normal(size=3)
    b = r.normal(size=3) * 3e-5
    tau = np.array(trq.dipole_torque(tuple(q), tuple(m), tuple(b)))
    np.testing.assert_allclose(tau, np.cross(m, qt.rotate_inv(q, b)), rtol=1e-13, atol=1e-30)


def test_torque_enters_as_a_tangent_generalized_gradient():
    q = qt.normalize(rng.normal(size=4))
    tau = rng.normal(size=3)
    G = np.array(trq.gradient_of_torque(tuple(q), tuple(tau)))
    assert abs(G @ q) < 1e-15
    np.testing.assert_allclose(kp.torque_from_gradient(tuple(q), tuple(G)), tau, rtol=1e-14, atol=1e-15)


GM = 398600.4418
ORB = kepler.orbit_vector(6778.0, 0.001, 0.9, 0.3, 0.2, 0.1, np.sqrt(GM / 6778.0**3))


PIECES = Pieces(300.0, 10)


def _orbit_samples(t0=-100.0, t1=3100.0):
    t = piece_times(t0, t1, PIECES)
    _, _, r, pos, vel = kepler.kepler_many(t, ORB, GM)
    return t, r, pos, vel


def _table(t, values):
    """The piece table of ``values`` at the :func:`_orbit_samples` times."""
    return piece_table(t, values, PIECES.degree)


RHO0, H0, HS, REQ, WE = 3e-3, 400.0, 60.0, 6378.137, 7.2921159e-5


def _drag_model(F):
    ts, rs, _, _ = _orbit_samples()
    dens = _table(ts, RHO0 * np.exp(-((rs - REQ) - H0) / HS))
    return km.build(orbit=(km.ORBIT_KEPLER, ORB, None), terms=[(km.DRAG, km.drag_params(F, WE), dens)])


def test_drag_term_of_the_model():
    """The model's drag term: the density table along the orbit, the velocity relative to the
    co-rotating atmosphere, the flat-plate torque; Kepler velocity against kepler_many."""
    F = _facets()
    model = _drag_model(F)
    assert model[0][0, km.FLAGS] & km.NEEDS_VELOCITY and model[0][1, km.FLAGS] == km.FIRST_TABLE_SLOT
    t = np.array([0.0, 100.0, 2500.0])
    q = np.array([qt.normalize(rng.normal(size=4)) for _ in t])
    U, tau = kev.evaluate_terms(t, q, np.array([1.0, 2.0, 3.0]), *model, kp.new_work())
    assert np.all(U == 0.0)
    _, _, r, pos, vel = kepler.kepler_many(t, ORB, GM)
    for i in range(t.size):
        vrel = vel[i] - np.cross([0, 0, WE], pos[i])
        rho = RHO0 * np.exp(-((r[i] - REQ) - H0) / HS)
        k = 0.5 * rho * vrel @ vrel
        ref = _drag_reference(q[i], k, vrel / np.linalg.norm(vrel), F)
        np.testing.assert_allclose(tau[i, 0], ref, rtol=1e-9)


def test_drag_term_with_the_exponential_atmosphere_in_closed_form():
    """Issue 25: the exponential density evaluated in the kernel at the orbit's radius (no table,
    no table knots to land on): the torque of the flat-plate formulas to round-off at any time,
    where the table of the same density is off by its interpolation error between its nodes."""
    F = _facets()
    closed = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                      terms=[(km.DRAG, km.drag_params(F, WE, (RHO0, H0, HS, REQ)), None)])
    assert closed[2].shape[0] == 0 and closed[0][1, km.R1] == closed[0][1, km.R0]
    assert closed[1][closed[0][1, km.P0] + 2] == km.DENSITY_EXPONENTIAL
    assert km.next_breakpoint(10.0, *closed) == np.inf         # no knots
    t = np.array([0.0, 15.0, 1234.5, 2500.0])
    q = np.array([qt.normalize(rng.normal(size=4)) for _ in t])
    _, tau = kev.evaluate_terms(t, q, np.array([1.0, 2.0, 3.0]), *closed, kp.new_work())
    _, tau_table = kev.evaluate_terms(t, q, np.array([1.0, 2.0, 3.0]), *_drag_model(F), kp.new_work())
    _, _, r, pos, vel = kepler.kepler_many(t, ORB, GM)
    for i in range(t.size):
        vrel = vel[i] - np.cross([0, 0, WE], pos[i])
        k = 0.5 * RHO0 * np.exp(-((r[i] - REQ) - H0) / HS) * (vrel @ vrel)
        ref = _drag_reference(q[i], k, vrel / np.linalg.norm(vrel), F)
        np.testing.assert_allclose(tau[i, 0], ref, rtol=1e-13, atol=1e-13 * np.linalg.norm(ref))
        np.testing.assert_allclose(tau_table[i, 0], ref, rtol=1e-8)
    with pytest.raises(ValueError, match="needs a table"):     # a tabulated density needs its table
        km.build(orbit=(km.ORBIT_KEPLER, ORB, None), terms=[(km.DRAG, km.drag_params(F, WE), None)])


def test_srp_and_magnetic_terms_of_the_model():
    """SRP with the conical shadow and the pressure scaled by (AU / d)^2; m x B with the field
    from its table; both against the formulas evaluated here."""
    F = _facets()
    ts, _, pos_s, _ = _orbit_samples()
    sun = np.array([1.2e8, -8.0e7, 3.0e7]) + ts[:, None] * np.array([1.0, 2.0, 0.5])
    bfield = 3e-5 * np.stack([np.cos(ts / 900.0), np.sin(ts / 700.0), 0.3 * np.ones_like(ts)], axis=1)
    m = np.array([5e-3, 0.0, 2e-3])
    P1, AU, RB, RS = 4.5e-3, 1.495978707e8, 6378.137, 696000.0
    model = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                     terms=[(km.SRP, km.srp_params(F, P1, AU, km.SHADOW_CONICAL, RB, RS), _table(ts, sun)),
                            (km.MAGNETIC, m, _table(ts, bfield))])
    assert list(model[0][1:, km.FLAGS]) == [km.FIRST_TABLE_SLOT, km.FIRST_TABLE_SLOT + 1]
    t = np.array([0.0, 1000.0, 2000.0, 3000.0])
    q = np.array([qt.normalize(rng.normal(size=4)) for _ in t])
    _, tau = kev.evaluate_terms(t, q, np.array([1.0, 2.0, 3.0]), *model, kp.new_work())
    _, _, _, pos, _ = kepler.kepler_many(t, ORB, GM)
    lit = 0
    for i, ti in enumerate(t):
        s_i = np.array([1.2e8, -8.0e7, 3.0e7]) + ti * np.array([1.0, 2.0, 0.5])
        d = s_i - pos[i]
        nu = shadow(pos[i][None], s_i[None], kind="conical", body_radius=RB, sun_radius=RS)[0]
        lit += nu > 0
        ref = _srp_reference(q[i], nu * P1 * (AU / np.linalg.norm(d)) ** 2, d / np.linalg.norm(d), F)
        np.testing.assert_allclose(tau[i, 0], ref, rtol=1e-9, atol=1e-30)
        b = 3e-5 * np.array([np.cos(ti / 900.0), np.sin(ti / 700.0), 0.3])
        np.testing.assert_allclose(tau[i, 1], np.cross(m, qt.rotate_inv(q[i], b)), rtol=1e-7)
    assert lit >= 2


def test_kepler_and_sampled_state_keep_the_radial_numbers():
    work1, work2 = kp.new_work(), kp.new_work()
    for t in (0.0, 10.0, 3000.0):
        r1, x1 = kepler.kepler_radial(t, ORB, work1)
        r2, x2, v = kepler.kepler_state(t, ORB, work2)
        assert r1 == r2 and x1 == x2
        _, _, _, _, vel = kepler.kepler_many(np.array([t]), ORB, GM)
        np.testing.assert_allclose(v, vel[0], rtol=1e-13)


def test_drag_with_gravity_gradient_in_the_step_loop():
    """A model of two terms through the compiled RHS: q.Q stays 0 and |q| = 1 (tangent)."""
    F = _facets()
    ts, rs, _, _ = _orbit_samples()
    dens = _table(ts, RHO0 * np.exp(-((rs - REQ) - H0) / HS))
    model = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                     terms=[(km.GRAVITY_GRADIENT, [GM], None), (km.DRAG, km.drag_params(F, WE), dens)])
    y = np.r_[qt.normalize(rng.normal(size=4)), np.zeros(4)]
    dy = np.empty(8)
    H.rhs(50.0, y, np.array([1e-5, 2e-5, 3e-5]), *model, kp.new_work(), dy)
    assert np.abs(dy[4:]).max() > 0.0
    assert abs(y[:4] @ dy[4:] + y[4:] @ dy[:4]) < 1e-14 * np.abs(dy[4:]).max()


def test_environment_terms_in_lanes_are_the_single_member_operations():
    """A model of all four terms through rhs_lanes (the per-term loops) equals rhs member by
    member, bitwise, for an odd group."""
    F = _facets()
    ts, rs, _, _ = _orbit_samples()
    dens = _table(ts, RHO0 * np.exp(-((rs - REQ) - H0) / HS))
    sun = _table(ts, np.array([1.2e8, -8.0e7, 3.0e7]) + ts[:, None] * np.array([1.0, 2.0, 0.5]))
    bf = _table(ts, 3e-5 * np.stack([np.cos(ts / 900.0), np.sin(ts / 700.0), 0.3 * np.ones_like(ts)], axis=1))
    model = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                     terms=[(km.GRAVITY_GRADIENT, [GM], None), (km.DRAG, km.drag_params(F, WE), dens),
                            (km.SRP, km.srp_params(F, 4.5e-3, 1.495978707e8, km.SHADOW_CONICAL, REQ, 696000.0), sun),
                            (km.MAGNETIC, [5e-9, 0.0, 2e-9], bf)])
    L = 7
    Y = np.ascontiguousarray(np.array([np.r_[qt.normalize(rng.normal(size=4)), rng.normal(size=4) * 1e-9]
                                       for _ in range(L)]).T)
    I = np.ascontiguousarray(np.tile([[3e-8], [3e-8], [1e-8]], (1, L)))
    dY = np.empty((8, L))
    G = np.empty((4, L))
    for t in (0.0, 1500.0):
        H.rhs_lanes(t, Y, L, I, *model, kp.new_work(), G, dY)
        for l in range(L):
            dy = np.empty(8)
            H.rhs(t, np.ascontiguousarray(Y[:, l]), np.ascontiguousarray(I[:, l]), *model, kp.new_work(), dy)
            np.testing.assert_array_equal(dY[:, l], dy)

"""The term list (orbatt.core.model): layout, the sum over terms, one member vs lanes, and
the conversion of the older kernel specification."""
from __future__ import annotations

import numpy as np
import pytest

from orbatt.core import hamiltonian as H
from orbatt.core import kepler
from orbatt.core import evaluation as kev
from orbatt.core import model as km
from orbatt.core import potentials as kp

I_SAT = np.array([400.0, 500.0, 600.0])
GM = 398600.4418
ORB = kepler.orbit_vector(7000.0, 0.2, np.pi / 6, np.pi / 4, np.pi / 12, 0.0, np.sqrt(GM / 7000.0**3))
TOP = np.array([0.5, 1.0, 0.2, -0.3])


def _states(n, seed=0):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    Q = rng.normal(size=(n, 4)) * 1e-2
    Q -= np.sum(Q * q, axis=1)[:, None] * q
    return np.concatenate([q, Q], axis=1)


def test_build_layout_slices_every_row():
    tab = np.arange(20.0).reshape(2, 10)
    terms, params, table = km.build(orbit=(km.ORBIT_SAMPLED, [0.0, 1.0], tab),
                                    terms=[(km.GRAVITY_GRADIENT, [GM], None), (km.HEAVY_TOP, TOP, None)])
    assert terms.dtype == np.int64 and terms.shape == (3, km.TERM_FIELDS)
    assert list(terms[:, km.KIND]) == [km.ORBIT_SAMPLED, km.GRAVITY_GRADIENT, km.HEAVY_TOP]
    np.testing.assert_array_equal(params[terms[0, 1]:terms[0, 2]], [0.0, 1.0])
    np.testing.assert_array_equal(params[terms[1, 1]:terms[1, 2]], [GM])
    np.testing.assert_array_equal(params[terms[2, 1]:terms[2, 2]], TOP)
    np.testing.assert_array_equal(table[terms[0, 3]:terms[0, 4]], tab)
    assert table.flags.c_contiguous and table.flags.writeable
    empty = km.build()
    assert empty[0].shape == (1, km.TERM_FIELDS) and empty[0][0, 0] == km.ORBIT_NONE


def test_from_spec_refuses_unknown_kinds_and_short_params():
    with pytest.raises(ValueError, match="unknown potential kind"):
        km.from_spec(7, np.zeros(1), kp.EMPTY_TABLE)
    with pytest.raises(ValueError, match="expected 16 params"):
        km.from_spec(kp.GRAVITY_GRADIENT_KEPLER, np.zeros(3), kp.EMPTY_TABLE)
    with pytest.raises(ValueError, match="table of shape"):
        km.from_spec(kp.GRAVITY_GRADIENT_SAMPLED, np.zeros(3), np.zeros((1, 10)))


def test_a_model_of_one_term_is_that_term_exactly():
    """The sum starts from the first term: one term gives the kernel's own numbers."""
    terms, params, table = km.from_spec(kp.GRAVITY_GRADIENT_KEPLER, np.r_[GM, ORB], kp.EMPTY_TABLE)
    y = _states(20)
    for t in (0.0, 1234.5, 5000.0):
        r, xhat = kepler.kepler_radial(t, ORB, kp.new_work())
        for yi in y:
            q = tuple(yi[:4])
            U, G = kev.evaluate_many(np.array([t]), yi[None, :4].copy(), I_SAT, terms, params, table,
                                    kp.new_work())[:2]
            U0, G0 = kp.gravity_gradient(q, tuple(I_SAT), GM / (r * r * r), xhat)
            assert U[0] == U0
            np.testing.assert_array_equal(G[0], G0)


def test_terms_add_up():
    """Gravity gradient + heavy top = the sum of the two models; the same term twice = twice it."""
    gg = km.from_spec(kp.GRAVITY_GRADIENT_KEPLER, np.r_[GM, ORB], kp.EMPTY_TABLE)
    ht = km.from_spec(kp.HEAVY_TOP, TOP, kp.EMPTY_TABLE)
    both = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                    terms=[(km.GRAVITY_GRADIENT, [GM], None), (km.HEAVY_TOP, TOP, None)])
    twice = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                     terms=[(km.GRAVITY_GRADIENT, [GM], None), (km.GRAVITY_GRADIENT, [GM], None)])
    y = _states(30, 1)
    t = np.full(30, 777.0)
    q = np.ascontiguousarray(y[:, :4])
    Ug, Gg, tg = kev.evaluate_many(t, q, I_SAT, *gg, kp.new_work())
    Uh, Gh, th = kev.evaluate_many(t, q, I_SAT, *ht, kp.new_work())
    Ub, Gb, tb = kev.evaluate_many(t, q, I_SAT, *both, kp.new_work())
    U2, G2, _ = kev.evaluate_many(t, q, I_SAT, *twice, kp.new_work())
    np.testing.assert_array_equal(Ub, Ug + Uh)
    np.testing.assert_array_equal(Gb, Gg + Gh)
    np.testing.assert_allclose(tb, tg + th, rtol=1e-13, atol=1e-20)
    np.testing.assert_array_equal(U2, 2.0 * Ug)
    np.testing.assert_array_equal(G2, 2.0 * Gg)


@pytest.mark.parametrize("nterms", [0, 1, 2, 3])
def test_lanes_are_the_single_member_operations(nterms):
    """rhs_lanes (one fused loop for one term, a loop per term otherwise) gives bitwise the
    numbers of rhs member by member, for any number of terms and an odd group size."""
    rows = [(km.GRAVITY_GRADIENT, [GM], None), (km.HEAVY_TOP, TOP, None), (km.GRAVITY_GRADIENT, [0.5 * GM], None)]
    model = km.build(orbit=(km.ORBIT_KEPLER, ORB, None), terms=rows[:nterms])
    L = 13
    Y = np.ascontiguousarray(_states(L, nterms).T)
    I = np.ascontiguousarray(np.tile(I_SAT[:, None], (1, L)) * np.random.default_rng(3).uniform(0.9, 1.1, (3, L)))
    dY = np.empty((8, L))
    G = np.empty((4, L))
    for t in (0.0, 1234.5):
        H.rhs_lanes(t, Y, L, I, *model, kp.new_work(), G, dY)
        for l in range(L):
            dy = np.empty(8)
            H.rhs(t, np.ascontiguousarray(Y[:, l]), np.ascontiguousarray(I[:, l]), *model, kp.new_work(), dy)
            np.testing.assert_array_equal(dY[:, l], dy)


def test_a_torque_free_model_keeps_the_constraints():
    """dq/dt.q = 0 and d(q.Q)/dt = 0 for every model: the generalized gradient is tangent."""
    model = km.build(orbit=(km.ORBIT_KEPLER, ORB, None),
                     terms=[(km.GRAVITY_GRADIENT, [GM], None), (km.HEAVY_TOP, TOP, None)])
    for y in _states(10, 5):
        dy = np.empty(8)
        H.rhs(321.0, y, I_SAT, *model, kp.new_work(), dy)
        q, Q, qd, Qd = y[:4], y[4:], dy[:4], dy[4:]
        assert abs(q @ qd) < 1e-15
        assert abs(qd @ Q + q @ Qd) < 1e-12 * np.abs(Qd).max()

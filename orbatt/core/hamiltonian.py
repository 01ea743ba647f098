"""Hamilton's equations of the rigid body in the canonical pair ``(q, Q)`` (paper eqs. 6-7):
the only compiled implementation of eq. (7), for one member (:func:`rhs`) and for a lockstep
group of members (:func:`rhs_lanes`), both built on :func:`eq7`.

State vector ``y`` (float64, length 8) = ``(q0, q1, q2, q3, Q0, Q1, Q2, Q3)``. ``inertia``
is the float64 vector ``(I1, I2, I3)`` of principal moments; ``I0^-1 = 0``. With
``w = q~ Q`` and ``a = (0, w1/I1, w2/I2, w3/I3)`` (= ``I^-1 (x) q~Q``), eq. (7) reads::

    dq/dt = 1/4 q a,        dQ/dt = 1/4 Q a - G

(``-1/4 Q (I^-1 (x) Q~ q) = +1/4 Q a`` because ``Q~ q = conj(w)``), with ``G`` the summed
generalized gradient of the model's terms (:mod:`orbatt.core.model`; ``G = dU/dq`` for a
potential). ``T = 1/8 a.w`` (eq. 6). ``work`` is the per-trajectory scratch array of
:func:`orbatt.core.potentials.new_work`. The vectorized numpy form written as the paper
prints it, :func:`orbatt.canonical.hamilton_rhs`, is the independent reference the tests
compare with.
"""
from __future__ import annotations

from ._jit import jit, jit_inline
from .model import (GRAVITY_GRADIENT, HEAVY_TOP, gradient_at, orbit_at, term_constants,
                    term_value, terms_lanes)
from .evaluation import gradient_called
from .qalg import qconj, qmul, qmul_pure


@jit_inline
def kinetic_rates(q, Q, inertia):
    """``(w, a)``: ``w = q~ Q`` (``= 2 (0, g)``) and ``a = I^-1 (x) w``."""
    w = qmul(qconj(q), Q)
    return w, (0.0, w[1] / inertia[0], w[2] / inertia[1], w[3] / inertia[2])


@jit_inline
def eq7(q, Q, a):
    """The kinetic part of eq. (7) for the rates ``a`` of :func:`kinetic_rates`:
    ``(4 dq/dt, 4 dQ/dt + 4 G) = (q a, Q a)`` (``a`` pure: :func:`~orbatt.core.qalg.qmul_pure`)."""
    v = (a[1], a[2], a[3])
    return qmul_pure(q, v), qmul_pure(Q, v)


def _rhs(s, y, inertia, terms, params, table, work, dy):
    """Write ``dy/ds`` (eq. 7) into ``dy`` for the model ``terms, params, table`` (a model with
    wheels or a control law, row 0's ``EXTENDED`` flag, takes
    :func:`orbatt.core.gyrostat.rhs_extended` instead: the step loops choose it). ``s`` is the
    time, or the eccentric anomaly for an orbit of kind ``ORBIT_KEPLER_ANOMALY``
    (``dy/ds = dt/ds dy/dt``; :mod:`orbatt.core.model`); ``dt/ds = 1`` leaves the numbers of
    ``dy/dt`` exact."""
    q = (y[0], y[1], y[2], y[3])
    Q = (y[4], y[5], y[6], y[7])
    _, a = kinetic_rates(q, Q, inertia)
    qd, Qd = eq7(q, Q, a)
    dtds, _, G = gradient_at(s, q, inertia, terms, params, table, work)
    for k in range(4):
        dy[k] = dtds * (0.25 * qd[k])
        dy[4 + k] = dtds * (0.25 * Qd[k] - G[k])


@jit_inline
def _lane(Y, I, l):
    """``(q, Q, inertia, a)`` of lane ``l``: its state, principal moments and the rates of
    :func:`kinetic_rates`."""
    q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
    Q = (Y[4, l], Y[5, l], Y[6, l], Y[7, l])
    inertia = (I[0, l], I[1, l], I[2, l])
    _, a = kinetic_rates(q, Q, inertia)
    return q, Q, inertia, a


@jit_inline
def _store_lane(dY, l, q, Q, a, g, dtds):
    """``dY[:, l]``: eq. (7) of lane ``l`` from its rates ``a`` and its summed gradient ``g``.
    The lane loops evaluate ``g`` between :func:`_lane` and this (as 0.1.0's lane loops did):
    with ``q a, Q a`` formed first and held across the term, the vectorized gravity-gradient
    loop spilled registers (32 lanes: 425 instead of ~400 ns a call). ``dtds``: the rate of
    the time in the independent variable (:func:`_rhs`)."""
    qd, Qd = eq7(q, Q, a)
    for k in range(4):
        dY[k, l] = dtds * (0.25 * qd[k])
        dY[4 + k, l] = dtds * (0.25 * Qd[k] - g[k])


@jit_inline
def _lanes_one_term(kind, p0, c, Y, nl, I, params, dY, dtds):
    """Eq. (7) with a single term of ``kind`` (constants ``c``) over the lanes, in one fused
    loop (with a constant ``kind`` the term's dispatch folds away and the loop vectorizes)."""
    for l in range(nl):
        q, Q, inertia, a = _lane(Y, I, l)
        _, g = term_value(kind, p0, c, q, inertia, params)
        _store_lane(dY, l, q, Q, a, g, dtds)


#: :func:`_rhs` compiled once and called (the cold call sites: first derivatives, FSAL)
rhs = jit(_rhs)
#: the same function inlined at numba-IR level into the hot stage loop of the step loops (one
#: site per loop: every inlined site costs its type inference and lowering again)
rhs_inline = jit_inline(_rhs)



@jit
def rhs_lanes(s, Y, nl, I, terms, params, table, work, G, dY):
    """Eq. (7) for lanes ``0..nl-1`` of ``Y (8, L)`` at the common ``s`` (the time, or the
    eccentric anomaly as in :func:`_rhs`; inertia
    ``I (3, L)``), into ``dY (8, L)``; ``G (4, L)`` is scratch. The operations of :func:`rhs`,
    member by member, with the orbit evaluated once for the group, in loops over the lanes
    that LLVM vectorizes. A model of one term runs one fused loop, specialized to the term's
    kind (LLVM does not unswitch a loop on a run-time kind, and the fused loop is 2x faster
    than a loop per term into ``G``: measured 240 vs 520 ns for 32 lanes of the Keplerian
    gravity gradient); a model of several terms sums them into ``G`` first
    (:func:`orbatt.core.model.terms_lanes`). Not inlined: one call serves a whole group
    (inlining it at every stage of the group step loops made them take 20-45 s to compile).
    Pass borrowed arrays (:func:`orbatt.core._jit.borrow`)."""
    n = terms.shape[0]
    if n == 1:
        for l in range(nl):
            q, Q, _, a = _lane(Y, I, l)
            _store_lane(dY, l, q, Q, a, (0.0, 0.0, 0.0, 0.0), 1.0)
        return
    t, dtds, r, xhat, v = orbit_at(s, terms, params, table, work)
    if n == 2:
        kind, p0, c = term_constants(1, t, terms, params, table, work, r, xhat, v)
        # the specializations (the formulas stay in orbatt.core.model.term_value)
        if kind == GRAVITY_GRADIENT:
            _lanes_one_term(GRAVITY_GRADIENT, p0, c, Y, nl, I, params, dY, dtds)
        elif kind == HEAVY_TOP:
            _lanes_one_term(HEAVY_TOP, p0, c, Y, nl, I, params, dY, dtds)
        else:
            _lanes_one_term(kind, p0, c, Y, nl, I, params, dY, dtds)
        return
    terms_lanes(t, Y, nl, I, terms, params, table, work, r, xhat, v, G)
    for l in range(nl):
        q, Q, _, a = _lane(Y, I, l)
        _store_lane(dY, l, q, Q, a, (G[0, l], G[1, l], G[2, l], G[3, l]), dtds)


@jit
def kinetic(y, inertia):
    """Kinetic energy ``T = 1/8 (I^-1 (x) q~Q).(q~Q)`` (eq. 6)."""
    w, a = kinetic_rates((y[0], y[1], y[2], y[3]), (y[4], y[5], y[6], y[7]), inertia)
    return 0.125 * (a[1] * w[1] + a[2] * w[2] + a[3] * w[3])


@jit
def energy(t, y, inertia, terms, params, table, work):
    """Hamiltonian ``H = T + U(q, t)``."""
    # the inertia as a tuple, as evaluate_many passes it (one compiled gradient_called)
    u, _ = gradient_called(t, (y[0], y[1], y[2], y[3]), (inertia[0], inertia[1], inertia[2]), terms, params, table,
                           work)
    return kinetic(y, inertia) + u

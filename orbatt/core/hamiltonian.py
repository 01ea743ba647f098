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
from .model import gradient, gradient_lanes
from .qalg import qconj, qmul


@jit_inline
def kinetic_rates(q, Q, inertia):
    """``(w, a)``: ``w = q~ Q`` (``= 2 (0, g)``) and ``a = I^-1 (x) w``."""
    w = qmul(qconj(q), Q)
    return w, (0.0, w[1] / inertia[0], w[2] / inertia[1], w[3] / inertia[2])


@jit_inline
def eq7(q, Q, inertia):
    """The kinetic part of eq. (7): ``(4 dq/dt, 4 dQ/dt + 4 G) = (q a, Q a)``."""
    _, a = kinetic_rates(q, Q, inertia)
    return qmul(q, a), qmul(Q, a)


@jit_inline
def rhs(t, y, inertia, terms, params, table, work, dy):
    """Write ``dy/dt`` (eq. 7) into ``dy`` for the model ``terms, params, table``."""
    q = (y[0], y[1], y[2], y[3])
    Q = (y[4], y[5], y[6], y[7])
    qd, Qd = eq7(q, Q, inertia)
    _, G = gradient(t, q, inertia, terms, params, table, work)
    for k in range(4):
        dy[k] = 0.25 * qd[k]
        dy[4 + k] = 0.25 * Qd[k] - G[k]


@jit
def rhs_lanes(t, Y, nl, I, terms, params, table, work, G, dY):
    """Eq. (7) for lanes ``0..nl-1`` of ``Y (8, L)`` at the common time ``t`` (inertia
    ``I (3, L)``), into ``dY (8, L)``; ``G (4, L)`` is scratch for the terms' gradients. The
    operations of :func:`rhs`, member by member, with the orbit evaluated once. Not inlined:
    one call serves a whole group (inlining it at every stage of the group step loops made
    them take 20-45 s to compile). Pass borrowed arrays (:func:`orbatt.core._jit.borrow`)."""
    has_terms = gradient_lanes(t, Y, nl, I, terms, params, table, work, G)
    for l in range(nl):
        qd, Qd = eq7((Y[0, l], Y[1, l], Y[2, l], Y[3, l]), (Y[4, l], Y[5, l], Y[6, l], Y[7, l]),
                     (I[0, l], I[1, l], I[2, l]))
        for k in range(4):
            dY[k, l] = 0.25 * qd[k]
        if has_terms:
            for k in range(4):
                dY[4 + k, l] = 0.25 * Qd[k] - G[k, l]
        else:
            for k in range(4):
                dY[4 + k, l] = 0.25 * Qd[k] - 0.0


@jit
def kinetic(y, inertia):
    """Kinetic energy ``T = 1/8 (I^-1 (x) q~Q).(q~Q)`` (eq. 6)."""
    w, a = kinetic_rates((y[0], y[1], y[2], y[3]), (y[4], y[5], y[6], y[7]), inertia)
    return 0.125 * (a[1] * w[1] + a[2] * w[2] + a[3] * w[3])


@jit
def energy(t, y, inertia, terms, params, table, work):
    """Hamiltonian ``H = T + U(q, t)``."""
    u, _ = gradient(t, (y[0], y[1], y[2], y[3]), inertia, terms, params, table, work)
    return kinetic(y, inertia) + u

"""Hamilton's equations of the rigid body in the canonical pair ``(q, Q)`` (paper eqs. 6-7).

State vector ``y`` (float64, length 8) = ``(q0, q1, q2, q3, Q0, Q1, Q2, Q3)``. ``inertia``
is the float64 vector ``(I1, I2, I3)`` of principal moments; ``I0^-1 = 0``. With
``w = q~ Q`` and ``a = (0, w1/I1, w2/I2, w3/I3)`` (= ``I^-1 (x) q~Q``), eq. (7) reads::

    dq/dt = 1/4 q a,        dQ/dt = 1/4 Q a - dU/dq

(``-1/4 Q (I^-1 (x) Q~ q) = +1/4 Q a`` because ``Q~ q = conj(w)``). ``T = 1/8 a.w``
(eq. 6). The potential is chosen by ``kind``/``params``/``table``
(:mod:`orbatt.core.potentials`); ``work`` is the per-trajectory scratch array of that
module.
"""
from __future__ import annotations

import numba as nb

from .potentials import potential
from .qalg import qconj, qmul


@nb.njit(cache=True, inline="always")
def _a(q, Q, inertia):
    w = qmul(qconj(q), Q)
    return w, (0.0, w[1] / inertia[0], w[2] / inertia[1], w[3] / inertia[2])


@nb.njit(cache=True)
def rhs(t, y, inertia, kind, params, table, work, dy):
    """Write ``dy/dt`` (eq. 7) into ``dy``; returns nothing."""
    q = (y[0], y[1], y[2], y[3])
    Q = (y[4], y[5], y[6], y[7])
    _, a = _a(q, Q, inertia)
    qd = qmul(q, a)
    Qd = qmul(Q, a)
    _, grad = potential(t, q, inertia, kind, params, table, work)
    for k in range(4):
        dy[k] = 0.25 * qd[k]
        dy[4 + k] = 0.25 * Qd[k] - grad[k]


@nb.njit(cache=True)
def kinetic(y, inertia):
    """Kinetic energy ``T = 1/8 (I^-1 (x) q~Q).(q~Q)`` (eq. 6)."""
    q = (y[0], y[1], y[2], y[3])
    Q = (y[4], y[5], y[6], y[7])
    w, a = _a(q, Q, inertia)
    return 0.125 * (a[1] * w[1] + a[2] * w[2] + a[3] * w[3])


@nb.njit(cache=True)
def energy(t, y, inertia, kind, params, table, work):
    """Hamiltonian ``H = T + U(q, t)``."""
    q = (y[0], y[1], y[2], y[3])
    u, _ = potential(t, q, inertia, kind, params, table, work)
    return kinetic(y, inertia) + u

"""Symplectic splitting of the coupled binary (``docs/design.md`` §12): ``H = T + U`` with
``T = |p|^2 / (2 mu) + T2(q, Q) + T1(q1, Q1)`` and ``U`` the mutual potential of
:mod:`orbatt.core.mutual`.

The flow of ``T`` is exact: the three parts act on disjoint variables and commute, so it is
the drift ``r <- r + tau p / mu`` with each body's exact torque-free motion
(:func:`orbatt.core.free_body.motion` and :func:`orbatt.core.free_body.evaluate`: Jacobi
elliptic functions, the closed form of :mod:`orbatt.analytic`). The flow of ``U`` is exact too
(``r, q, q1`` fixed): the kick ``p <- p - tau dU/dr``, ``Q <- Q + tau 2 q (0, tau_B)``,
``Q1 <- Q1 + tau 2 q1 (0, tau1_B)``. Every piece is symplectic and conserves the total angular
momentum (the free motions conserve each spin, the drift ``r x p``, the kick the sum:
``r x dU/dr = tau2 + tau1`` in the inertial frame), so the compositions keep ``L`` to
round-off and the energy error bounded.

The basic step is Strang's kick-flow-kick ``S(h) = U(h/2) T(h) U(h/2)`` (order 2); orders 4
and 6 are the symmetric compositions of :data:`orbatt.core.splitting.COMPOSITIONS` (their
coefficients, passed as ``gammas``). Adjacent kicks are merged, so an ``s``-stage step costs
``s`` gradient evaluations (the last kick of a step is carried into the next one, and made
only before an output). The loop is resumable (a step budget per call, for progress reports and
Ctrl-C) and stops at the end of the first step whose path comes within the contact distance.
"""
from __future__ import annotations

import numpy as np

from ._jit import jit, jit_inline
from .free_body import NC, evaluate, motion
from .mutual import C_CONTACT2, C_MU, N_POINT, potential_gradient
from .torques import gradient_of_torque

__all__ = ["kick", "free_flow", "closest_approach2", "advance_split", "DONE", "PAUSED", "CONTACT", "CNT_K", "CNT_J", "CNT_STEPS",
           "CNT_EVALS", "CNT_SIZE", "SP_PENDING", "SP_SIZE"]


@jit_inline
def kick(y, c, tau):
    """The exact flow of ``U`` over ``tau``: ``p -= tau dU/dr``, ``Q -= tau G(tau2)``,
    ``Q1 -= tau G(tau1)`` (``G = -2 q (0, tau_B)``)."""
    _, d, tau2, tau1 = potential_gradient(y, c)
    for j in range(3):
        y[3 + j] -= tau * d[j]
    G = gradient_of_torque((y[6], y[7], y[8], y[9]), tau2)
    for j in range(4):
        y[10 + j] -= tau * G[j]
    if y.shape[0] > N_POINT:
        G = gradient_of_torque((y[14], y[15], y[16], y[17]), tau1)
        for j in range(4):
            y[18 + j] -= tau * G[j]


@jit_inline
def free_flow(y, c, tau, inertia2, inertia1, row, tt, buf):
    """The exact flow of ``T`` over ``tau``: the drift of ``r`` and each body's torque-free
    motion (``row (NC,)``, ``tt (1,)``, ``buf (1, 8)``: scratch)."""
    imu = 1.0 / c[C_MU]
    for j in range(3):
        y[j] += tau * y[3 + j] * imu
    tt[0] = tau
    nb = 2 if y.shape[0] > N_POINT else 1
    for b in range(nb):
        k = 6 + 8 * b
        yb = y[k:k + 8]
        motion(inertia2 if b == 0 else inertia1, yb, row)
        evaluate(row, yb, 0.0, tt, buf)
        for j in range(8):
            y[k + j] = buf[0, j]


#: what :func:`advance_split` returns: every output recorded, the step budget of this call used
#: up (call again to continue), the bodies touched (the separation at a step's end at or below
#: the contact distance, ``c[C_CONTACT2]``)
DONE, PAUSED, CONTACT = 0, 1, 2
#: slots of ``cnt`` (int64): outputs recorded, steps taken towards the next output, steps taken
#: in all, gradient evaluations; ``sp[SP_PENDING]`` (float64): the kick carried into the next step
CNT_K, CNT_J, CNT_STEPS, CNT_EVALS, CNT_SIZE = 0, 1, 2, 3, 4
SP_PENDING, SP_SIZE = 0, 1


@jit_inline
def closest_approach2(r0, r1, r2, d0, d1, d2):
    """The smallest ``|r + s d|^2`` over ``0 <= s <= 1``: the squared distance of the segment
    ``r .. r + d`` (a drift: the path of ``r`` in the flow of ``T`` is a straight line) to the
    origin."""
    dd = d0 * d0 + d1 * d1 + d2 * d2
    s = 0.0
    if dd > 0.0:
        s = min(1.0, max(0.0, -(r0 * d0 + r1 * d1 + r2 * d2) / dd))
    x0, x1, x2 = r0 + s * d0, r1 + s * d1, r2 + s * d2
    return x0 * x0 + x1 * x1 + x2 * x2


@jit
def advance_split(y, c, inertia2, inertia1, gammas, h, n_steps, out, sp, cnt, budget):
    """Take ``n_steps[k]`` steps of size ``h`` and record the state into ``out[k]`` for each
    ``k``; ``y`` (14 | 22,) is advanced in place. ``gammas``: the composition's coefficients
    (``(1.0,)``: Strang).

    Resumable: at most ``budget`` steps are taken in this call; ``cnt`` (:data:`CNT_SIZE`,
    zeros to start) and ``sp`` (:data:`SP_SIZE`, zeros to start) carry where the loop is, so
    that calling it again continues bit for bit as if it had not stopped. Contact is checked on
    every step: where a drift's straight path of ``r`` (:func:`closest_approach2`) comes within
    the contact distance (``c[C_CONTACT2]``, its square), the loop stops at the end of that step
    with :data:`CONTACT` (``cnt[CNT_STEPS]`` counts it; ``y`` there, its last kick not made), so
    that no step size steps through the bodies. Returns :data:`DONE`, :data:`PAUSED` or
    :data:`CONTACT`."""
    row = np.zeros(NC)
    tt = np.zeros(1)
    buf = np.zeros((1, 8))
    contact2 = c[C_CONTACT2]
    pending = sp[SP_PENDING]  # the weight of the kick not yet made (merged with the next one)
    taken = 0
    while cnt[CNT_K] < n_steps.shape[0]:
        k = cnt[CNT_K]
        while cnt[CNT_J] < n_steps[k]:
            if taken >= budget:
                sp[SP_PENDING] = pending
                return PAUSED
            touch = False
            for g in gammas:
                pending += 0.5 * g
                kick(y, c, pending * h)
                cnt[CNT_EVALS] += 1
                r0, r1, r2 = y[0], y[1], y[2]
                free_flow(y, c, g * h, inertia2, inertia1, row, tt, buf)
                pending = 0.5 * g
                if closest_approach2(r0, r1, r2, y[0] - r0, y[1] - r1, y[2] - r2) <= contact2:
                    touch = True
            cnt[CNT_J] += 1
            cnt[CNT_STEPS] += 1
            taken += 1
            if touch:
                sp[SP_PENDING] = pending
                return CONTACT
        if pending != 0.0:  # the step's last kick, before the output
            kick(y, c, pending * h)
            cnt[CNT_EVALS] += 1
            pending = 0.0
        for j in range(y.shape[0]):
            out[k, j] = y[j]
        cnt[CNT_K] += 1
        cnt[CNT_J] = 0
    sp[SP_PENDING] = pending
    return DONE

"""The model's terms evaluated at given times and attitudes, for the outputs of a result
(potential energy, torques per term, ensembles member by member): the cold paths beside the
step loops, on the dispatch of :mod:`orbatt.core.model`. These kernels call the model's
gradient compiled once (:func:`gradient_called`) where they can, instead of inlining the whole
term dispatch again at numba-IR level (each inlined site repeats its type inference and
lowering: the compile time of the package, issue 26).
"""
from __future__ import annotations

import numpy as np

from . import potentials as pot
from ._jit import jit
from .model import N_CONSTANTS, gradient, orbit_radial, term_constants, term_value

__all__ = ["gradient_called", "evaluate_terms", "evaluate_many", "evaluate_members"]


@jit
def gradient_called(t, q, inertia, terms, params, table, work):
    """:func:`orbatt.core.model.gradient`, compiled once and called (not inlined)."""
    return gradient(t, q, inertia, terms, params, table, work)


@jit
def evaluate_terms(t, q, inertia, terms, params, table, work):
    """Each term alone: ``U (N, n)`` and the body torque ``tau (N, n, 3)`` of the ``n`` terms
    at the times ``t (N,)`` and attitudes ``q (N, 4)`` (for the per-term outputs of a
    result; ``tau = -1/2 Im(q~ G)``)."""
    n = q.shape[0]
    nt = terms.shape[0] - 1
    U = np.zeros((n, nt))
    tau = np.zeros((n, nt, 3))
    inertia_t = (inertia[0], inertia[1], inertia[2])
    if nt == 0:
        return U, tau
    for i in range(n):
        qi = (q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        r, xhat, v = orbit_radial(t[i], terms, params, table, work)
        for j in range(1, nt + 1):
            kind, p0, c = term_constants(j, t[i], terms, params, table, work, r, xhat, v)
            u, g = term_value(kind, p0, c, qi, inertia_t, params)
            U[i, j - 1] = u
            tq = pot.torque_from_gradient(qi, g)
            for k in range(3):
                tau[i, j - 1, k] = tq[k]
    return U, tau


@jit
def evaluate_many(t, q, inertia, terms, params, table, work):
    """``U (N,)``, ``G (N, 4)`` and the body torque ``tau (N, 3)`` of the model at the times
    ``t (N,)`` and attitudes ``q (N, 4)``."""
    n = q.shape[0]
    U = np.empty(n)
    grad = np.empty((n, 4))
    tau = np.empty((n, 3))
    inertia_t = (inertia[0], inertia[1], inertia[2])
    for i in range(n):
        qi = (q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        u, g = gradient_called(t[i], qi, inertia_t, terms, params, table, work)
        U[i] = u
        tq = pot.torque_from_gradient(qi, g)
        for k in range(4):
            grad[i, k] = g[k]
        for k in range(3):
            tau[i, k] = tq[k]
    return U, grad, tau


@jit
def evaluate_members(t, q, inertia, terms, params, table, per_term, want_tau):
    """Ensemble members each as alone: ``U (E, N)`` (:func:`evaluate_many`) and (``want_tau``)
    the torques ``tau (E, N, n, 3)`` of the ``n`` terms (``per_term``, :func:`evaluate_terms`)
    or their total (``n = 1``), at the times ``t (N,)`` and attitudes ``q (E, N, 4)`` of members
    of moments ``inertia (E, 3)``. The orbit and the terms' constants are computed once, from
    fresh scratch over the times in order, as the one-member kernels compute them for each
    member: each member gets their numbers (summed as :func:`orbatt.core.model.terms_at` sums)."""
    n_members = q.shape[0]
    n = t.shape[0]
    nt = terms.shape[0] - 1
    U = np.empty((n_members, n))
    tau = np.empty((n_members, n, nt if per_term else 1, 3))
    if nt == 0:  # no term: the one-member kernels' zeros, member by member
        for e in range(n_members):
            u, _, total = evaluate_many(t, q[e], inertia[e], terms, params, table, np.full(pot.WORK_SIZE, np.nan))
            U[e] = u
            if want_tau and not per_term:
                tau[e, :, 0] = total
        return U, tau
    kinds = np.empty(nt, dtype=np.int64)
    starts = np.empty(nt, dtype=np.int64)
    consts = np.empty((n, nt, N_CONSTANTS))
    work = np.full(pot.WORK_SIZE, np.nan)
    for i in range(n):
        r, xhat, v = orbit_radial(t[i], terms, params, table, work)
        for j in range(nt):
            kind, p0, c = term_constants(j + 1, t[i], terms, params, table, work, r, xhat, v)
            kinds[j] = kind
            starts[j] = p0
            for k in range(N_CONSTANTS):
                consts[i, j, k] = c[k]
    for e in range(n_members):
        inertia_t = (inertia[e, 0], inertia[e, 1], inertia[e, 2])
        for i in range(n):
            qi = (q[e, i, 0], q[e, i, 1], q[e, i, 2], q[e, i, 3])
            u_sum = 0.0
            g_sum = (0.0, 0.0, 0.0, 0.0)
            for j in range(nt):
                c = (consts[i, j, 0], consts[i, j, 1], consts[i, j, 2], consts[i, j, 3], consts[i, j, 4], consts[i, j, 5],
                     consts[i, j, 6], consts[i, j, 7])
                u, g = term_value(kinds[j], starts[j], c, qi, inertia_t, params)
                if j == 0:  # as terms_at: the sum starts from the first term's value
                    u_sum = u
                    g_sum = g
                else:
                    u_sum += u
                    g_sum = (g_sum[0] + g[0], g_sum[1] + g[1], g_sum[2] + g[2], g_sum[3] + g[3])
                if want_tau and per_term:
                    tq = pot.torque_from_gradient(qi, g)
                    for k in range(3):
                        tau[e, i, j, k] = tq[k]
            U[e, i] = u_sum
            if want_tau and not per_term:
                tq = pot.torque_from_gradient(qi, g_sum)
                for k in range(3):
                    tau[e, i, 0, k] = tq[k]
    return U, tau

"""Compiled fixed-step integrators: symplectic splitting of ``H = T + U`` (``docs/design.md`` §4)
and, for comparison, the classical Runge-Kutta 4; whole step loop in numba, one trajectory
(:func:`advance`) or an ensemble in parallel (:func:`advance_lanes`).

Splitting
---------
``H = T + U`` with ``T = g.I^-1 g / 2`` split into pieces whose flows are exact:

* the flow of ``c g_i^2 / 2`` (a rotation about body axis ``i``): ``g_i`` is constant along
  it; with ``theta = c g_i tau`` and ``u = (cos theta/2, sin theta/2 e_i)``,
  ``q <- q u``, ``Q <- Q u``;
* the flow of ``c |g|^2 / 2`` (a rotation about ``g`` itself): ``g`` is constant, ``u =
  (cos phi/2, sin phi/2 g/|g|)``, ``phi = c |g| tau``, ``q <- q u``, ``Q <- Q u``;
* the flow of ``U`` (a kick): ``Q <- Q - tau dU/dq(t_kick, q)`` with the tangential gradient
  of :mod:`orbatt.core.potentials`, ``t_kick`` the kick's own sub-step time.

Every piece maps the constraint manifold ``|q| = 1``, ``q.Q = 0`` to itself exactly (rotations
by unit quaternions, kicks tangent to the sphere) and is symplectic, so compositions keep
both constraints to round-off and have bounded energy error for autonomous ``U``.

Two decompositions of ``T`` (the ``kinetic`` choice, :func:`rotation_setup`):

``"axes"``
    ``T = T1 + T2 + T3``, ``Ti = gi^2 / (2 Ii)``; the kinetic block of a step of length
    ``tau`` is ``T1(tau/2) T2(tau/2) T3(tau) T2(tau/2) T1(tau/2)`` (5 rotations).
``"shifted"``
    ``T = |g|^2 / (2 Ir) + sum_{i != r} (1/Ii - 1/Ir) gi^2 / 2`` with ``r`` the axis of the
    middle moment (McLachlan 1993; Fasso 2003). ``|g|^2`` is a Casimir: its flow commutes
    with the other two, so the block ``Ta(tau/2) Tb(tau) Ta(tau/2) G(tau)`` is symmetric, has
    4 rotations, and its splitting error comes only from ``[Ta, Tb]``, whose coefficients
    ``(1/Ia - 1/Ir)(1/Ib - 1/Ir)`` are much smaller than the ``1/(Ii Ij)`` of ``"axes"``.

The basic step is Strang's kick-drift-kick ``S(tau) = U(tau/2) K(tau) U(tau/2)`` (order 2,
symmetric); higher orders are symmetric compositions ``S(g_s h) ... S(g_1 h)`` with the
coefficients of :data:`COMPOSITIONS` (data, not code). Adjacent kicks are merged, and a
gradient is reused while ``q`` and the time have not changed (first kick of a step = last
kick of the previous one), so a step of an ``s``-stage composition costs ``s`` gradient
evaluations.

Output times that fall between grid points are reached by a separate partial step from the
last grid point; the trajectory itself stays on the grid ``t0 + k h`` (outputs never perturb
it), and an output has the accuracy of one step of the same method.

Per-trajectory state (resumable, as :mod:`orbatt.core.dop853`): ``y (8)``, ``st`` (the cached
gradient and its validity), ``cnt`` (grid index, next output, steps, gradient/RHS evaluations).

Ensembles (:func:`advance_lanes`) run groups of members on the common grid: the orbit of an
orbit-driven potential is evaluated once per kick (or RHS) for the group and the gradient
arithmetic runs in loops over members that LLVM vectorizes. Every member performs exactly the
operations of :func:`advance`, so results are identical to one-by-one runs.
"""
from __future__ import annotations

import functools
import math

import numba as nb
import numpy as np

from ._jit import (DONE, EPS, MAX_STEPS, NDIM, NONFINITE, PAUSED, STEP_TOO_SMALL, borrow, borrow_model, jit,
                   jit_inline, jit_parallel, keepalive)
from .hamiltonian import rhs_inline, rhs_lanes
from .model import gradient, gradient_lanes_called
from .qalg import qmul

# ---------------------------------------------------------------------------------------
# Compositions of the symmetric Strang step (palindromic coefficient lists). Each entry:
# (order, coefficients, reference).


def _mclachlan4():
    """McLachlan's (1995) 5-stage order-4 composition: ``g1 = g5 = 0.28``, ``g2 = g4`` the
    root of ``sum g^3 = 0`` near 0.6255 (Newton to round-off), ``g3 = 1 - 2 (g1 + g2)``."""
    g1 = 0.28
    g2 = 0.62546642846767004501
    for _ in range(5):
        g3 = 1.0 - 2.0 * (g1 + g2)
        f = 2.0 * g1 ** 3 + 2.0 * g2 ** 3 + g3 ** 3
        fp = 6.0 * g2 ** 2 - 6.0 * g3 ** 2
        g2 -= f / fp
    return (g1, g2, 1.0 - 2.0 * (g1 + g2), g2, g1)


_Y4 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_S4 = 1.0 / (4.0 - 4.0 ** (1.0 / 3.0))
_Y6 = (0.78451361047755726381949763, 0.23557321335935813368479318, -1.17767998417887100694641568)
_KL6 = (0.39216144400731413927925056, 0.33259913678935943859974864, -0.70624617255763935980996482,
        0.08221359629355080023149045)

COMPOSITIONS = {
    "strang": (2, (1.0,), "Strang (1968): the basic symmetric step"),
    "yoshida4": (4, (_Y4, 1.0 - 2.0 * _Y4, _Y4), "Yoshida (1990) / Forest-Ruth triple jump, 3 stages"),
    "suzuki4": (4, (_S4, _S4, 1.0 - 4.0 * _S4, _S4, _S4), "Suzuki (1990) fractal, 5 stages"),
    "mclachlan4": (4, _mclachlan4(), "McLachlan (1995) optimized, 5 stages"),
    "yoshida6": (6, _Y6 + (1.0 - 2.0 * sum(_Y6),) + _Y6[::-1], "Yoshida (1990) solution A, 7 stages"),
    "kahanli6": (6, _KL6 + (1.0 - 2.0 * sum(_KL6),) + _KL6[::-1], "Kahan & Li (1997) optimized, 9 stages"),
}

# Flow codes of a flattened step sequence
KICK = 0
ROT_A = 1  # rotation about the body axis axes[0] with coefficient coef[0]
ROT_B = 2
ROT_C = 3
ROT_G = 4  # rotation about g with coefficient coef[3]

# Fixed-step methods of the driver
SPLITTING = 0
RK4 = 1

KINETIC = ("shifted", "axes")
#: RK4's stage nodes (and the weights of the previous stage in each): y + a h k_{s-1}
RK4_NODES = np.array([0.0, 0.5, 0.5, 1.0])

# ``st`` layout: cached gradient (4), validity flag (1)
ST_SIZE = 5
# ``cnt`` layout
CNT_K = 0       # grid index: the state is at t0 + k h
CNT_IOUT = 1    # next output index
CNT_STEPS = 2   # steps taken (grid and partial)
CNT_EVALS = 3   # gradient evaluations (splitting) or RHS evaluations (RK4)
CNT_SIZE = 4



def new_state(batch=None):
    """Fresh ``(st, cnt)`` arrays, for one trajectory or a ``batch`` of them."""
    shape = () if batch is None else (batch,)
    return np.zeros(shape + (ST_SIZE,)), np.zeros(shape + (CNT_SIZE,), dtype=np.int64)


def _kinetic_block(kinetic, tau, toff):
    """Rotations of the kinetic block of length ``tau`` (list of (code, weight, toff))."""
    if kinetic == "axes":
        return [(ROT_A, tau / 2, toff), (ROT_B, tau / 2, toff), (ROT_C, tau, toff), (ROT_B, tau / 2, toff),
                (ROT_A, tau / 2, toff)]
    if kinetic == "shifted":
        return [(ROT_A, tau / 2, toff), (ROT_B, tau, toff), (ROT_A, tau / 2, toff), (ROT_G, tau, toff)]
    raise ValueError(f"kinetic: {kinetic!r} is not one of {KINETIC}")


def sequence(gammas, kinetic="shifted"):
    """Flatten the composition ``S(g_s h) ... S(g_1 h)`` of kick-drift-kick Strang steps into
    ``(flow, weight, toff)`` arrays: flow codes, durations and kick time offsets in units of
    ``h``. Adjacent kicks and adjacent rotations of the same kind are merged. (Fresh copies of
    arrays flattened once per composition and ``kinetic``.)"""
    flow, weight, toff = _flatten(tuple(float(g) for g in gammas), kinetic)
    return flow.copy(), weight.copy(), toff.copy()


@functools.lru_cache(maxsize=64)
def _flatten(gammas, kinetic):
    """:func:`sequence` of the tuple ``gammas`` (cached)."""
    ops = []
    t = 0.0
    for g in gammas:
        ops.append((KICK, g / 2, t))
        ops.extend(_kinetic_block(kinetic, g, t))
        t += g
        ops.append((KICK, g / 2, t))
    merged = []
    for code, w, off in ops:
        if merged and merged[-1][0] == code:
            c0, w0, off0 = merged[-1]
            merged[-1] = (code, w0 + w, off0)
        else:
            merged.append((code, w, off))
    flow = np.array([m[0] for m in merged], dtype=np.int64)
    weight = np.array([m[1] for m in merged], dtype=np.float64)
    toff = np.array([m[2] for m in merged], dtype=np.float64)
    return flow, weight, toff


def rotation_setup(inertia, kinetic="shifted"):
    """``(axes, coef)`` for one body or a batch: the body axes (1..3) of the rotation slots A,
    B, C and the coefficients ``c`` of the flows ``c g_i^2/2`` (slots A, B, C) and
    ``c |g|^2/2`` (slot G)."""
    inertia = np.asarray(inertia, dtype=np.float64)
    flat = inertia.reshape(-1, 3)
    axes = np.zeros((flat.shape[0], 3), dtype=np.int64)
    coef = np.zeros((flat.shape[0], 4))
    for n, I in enumerate(flat):
        if kinetic == "axes":
            axes[n] = (1, 2, 3)
            coef[n, :3] = 1.0 / I
        elif kinetic == "shifted":
            order = np.argsort(I, kind="stable")
            r = order[1]  # middle moment
            a, b = order[2], order[0]  # largest moment in the outer half-rotations
            axes[n] = (a + 1, b + 1, r + 1)
            coef[n] = (1.0 / I[a] - 1.0 / I[r], 1.0 / I[b] - 1.0 / I[r], 0.0, 1.0 / I[r])
        else:
            raise ValueError(f"kinetic: {kinetic!r} is not one of {KINETIC}")
    shape = inertia.shape[:-1]
    return axes.reshape(shape + (3,)), coef.reshape(shape + (4,))


# ---------------------------------------------------------------------------------------
# Exact flows


@jit_inline
def _rot_axis(q, Q, axis, ctau):
    """Exact flow of ``c g_axis^2 / 2`` for a time ``tau`` (``ctau = c tau``)."""
    q0, q1, q2, q3 = q
    Q0, Q1, Q2, Q3 = Q
    # w_axis of w = q~ Q (= 2 g_axis)
    if axis == 1:
        w = q0 * Q1 - q1 * Q0 - q2 * Q3 + q3 * Q2
    elif axis == 2:
        w = q0 * Q2 + q1 * Q3 - q2 * Q0 - q3 * Q1
    else:
        w = q0 * Q3 - q1 * Q2 + q2 * Q1 - q3 * Q0
    half = 0.25 * ctau * w  # theta / 2, theta = c g tau
    c = math.cos(half)
    s = math.sin(half)
    # right multiplication by u = (c, s e_axis)
    if axis == 1:
        return ((q0 * c - q1 * s, q1 * c + q0 * s, q2 * c + q3 * s, q3 * c - q2 * s),
                (Q0 * c - Q1 * s, Q1 * c + Q0 * s, Q2 * c + Q3 * s, Q3 * c - Q2 * s))
    elif axis == 2:
        return ((q0 * c - q2 * s, q1 * c - q3 * s, q2 * c + q0 * s, q3 * c + q1 * s),
                (Q0 * c - Q2 * s, Q1 * c - Q3 * s, Q2 * c + Q0 * s, Q3 * c + Q1 * s))
    return ((q0 * c - q3 * s, q1 * c + q2 * s, q2 * c - q1 * s, q3 * c + q0 * s),
            (Q0 * c - Q3 * s, Q1 * c + Q2 * s, Q2 * c - Q1 * s, Q3 * c + Q0 * s))


@jit_inline
def _rot_g(q, Q, ctau):
    """Exact flow of ``c |g|^2 / 2`` for a time ``tau`` (``ctau = c tau``): rotation about
    ``g`` by ``c |g| tau``."""
    q0, q1, q2, q3 = q
    Q0, Q1, Q2, Q3 = Q
    w1 = q0 * Q1 - q1 * Q0 - q2 * Q3 + q3 * Q2
    w2 = q0 * Q2 + q1 * Q3 - q2 * Q0 - q3 * Q1
    w3 = q0 * Q3 - q1 * Q2 + q2 * Q1 - q3 * Q0
    nw = math.sqrt(w1 * w1 + w2 * w2 + w3 * w3)  # 2 |g|
    if nw == 0.0:
        return q, Q
    half = 0.25 * ctau * nw
    c = math.cos(half)
    s = math.sin(half) / nw
    u = (c, s * w1, s * w2, s * w3)
    return qmul(q, u), qmul(Q, u)


@jit_inline
def _rotate(q, Q, f, axes, coef, tau):
    """The exact flow of the rotation ``f`` (:data:`ROT_A` .. :data:`ROT_G`) for a time
    ``tau``, with the body's ``axes (3,)`` and ``coef (4,)`` of :func:`rotation_setup`."""
    if f == ROT_G:
        return _rot_g(q, Q, coef[3] * tau)
    return _rot_axis(q, Q, axes[f - 1], coef[f - 1] * tau)


@jit_inline
def _split_step(q, Q, t, h, flow, weight, toff, axes, coef, inertia, terms, params, table, work, gc, gvalid):
    """One composed splitting step of length ``h`` from time ``t``. ``gc``/``gvalid``: the
    cached gradient at ``(t, q)``. Returns ``(q, Q, gc, gvalid, evaluations)``."""
    nev = 0
    for j in range(flow.shape[0]):
        f = flow[j]
        tau = weight[j] * h
        if f != KICK:
            q, Q = _rotate(q, Q, f, axes, coef, tau)
            gvalid = False
        elif terms.shape[0] > 1:
            if not gvalid:
                _, gc = gradient(t + toff[j] * h, q, inertia, terms, params, table, work)
                nev += 1
                gvalid = True
            Q = (Q[0] - tau * gc[0], Q[1] - tau * gc[1], Q[2] - tau * gc[2], Q[3] - tau * gc[3])
    return q, Q, gc, gvalid, nev


@jit_inline
def _rk4_step(y, t, h, inertia, terms, params, table, work, K, ytmp):
    """Classical RK4 step, in place on ``y`` (4 RHS evaluations into ``K (4, 8)``), with one
    inlined right-hand side (a loop over the stages, one call site: every inlined site costs
    its type inference and lowering again)."""
    for s in range(4):
        ts = t
        if s == 0:
            for i in range(NDIM):
                ytmp[i] = y[i]
        else:
            a = RK4_NODES[s]
            ts = t + a * h
            for i in range(NDIM):
                ytmp[i] = y[i] + a * h * K[s - 1, i]
        rhs_inline(ts, ytmp, inertia, terms, params, table, work, K[s])
    for i in range(NDIM):
        y[i] += h / 6.0 * (K[0, i] + 2.0 * (K[1, i] + K[2, i]) + K[3, i])


@jit_inline
def plan_grid_step(t_out, i_out, t0, k, h, max_steps, done_here, budget):
    """``(at_output, status, full, tk, step)`` at the grid point ``tk = t0 + k h`` for the
    next output time ``tt = t_out[i_out]``: ``at_output`` when ``tk`` is ``tt`` (to
    rounding); else the next step towards ``tt``, a full grid step or the partial step to
    ``tt`` when ``tt`` falls before the next grid point, with status :data:`DONE` to take it,
    else why to stop."""
    tt = t_out[i_out]
    tk = t0 + k * h
    tol = 4.0 * EPS * max(abs(tt), abs(tk))
    if abs(tt - tk) <= tol:
        return True, DONE, False, tk, 0.0
    if done_here >= budget:
        return False, PAUSED, False, tk, 0.0
    full = t0 + (k + 1) * h <= tt + tol
    if full and k >= max_steps:
        return False, MAX_STEPS, full, tk, 0.0
    step = h if full else tt - tk
    if step <= 0.0:
        return False, STEP_TOO_SMALL, full, tk, step
    return False, DONE, full, tk, step


@jit_inline
def load_counters(cnt):
    """``(k, i_out, steps, evaluations)`` from the counters ``cnt``."""
    return cnt[CNT_K], cnt[CNT_IOUT], cnt[CNT_STEPS], cnt[CNT_EVALS]


@jit_inline
def save_counters(cnt, k, i_out, steps, nev):
    """Store the counters of :func:`load_counters` back into ``cnt``."""
    cnt[CNT_K] = k
    cnt[CNT_IOUT] = i_out
    cnt[CNT_STEPS] = steps
    cnt[CNT_EVALS] = nev


@jit_inline
def _finite(q, Q):
    s = q[0] + q[1] + q[2] + q[3] + Q[0] + Q[1] + Q[2] + Q[3]
    return abs(s) < np.inf


@jit
def advance(y, st, cnt, t_out, out_y, t0, h, method, flow, weight, toff, axes, coef, inertia, terms,
            params, table, work, max_steps, budget):
    """Advance one trajectory on the grid ``t0 + k h`` through the output times
    ``t_out[cnt[CNT_IOUT]:]`` (increasing, ``>= t0 + cnt[CNT_K] h``); ``out_y[i]`` receives
    ``y(t_out[i])``.

    ``method``: :data:`SPLITTING` (``flow, weight, toff`` from :func:`sequence`, ``axes,
    coef`` from :func:`rotation_setup`) or :data:`RK4`. ``max_steps``: limit on grid steps;
    ``budget``: steps allowed in this call. Returns a status code of
    :mod:`orbatt.core.dop853` (on :data:`NONFINITE`, ``y`` is the last finite state, at
    ``t0 + cnt[CNT_K] h``).
    """
    nout = t_out.shape[0]
    k, i_out, steps, nev = load_counters(cnt)
    if i_out >= nout:
        return DONE
    y = borrow(y)
    inertia = borrow(inertia)
    terms, params, table, work = borrow_model(terms, params, table, work)
    flow, weight, toff = borrow(flow), borrow(weight), borrow(toff)
    axes = borrow(axes)
    coef = borrow(coef)
    scratch_own = np.empty((6, NDIM))
    scratch = borrow(scratch_own)
    q = (y[0], y[1], y[2], y[3])
    Q = (y[4], y[5], y[6], y[7])
    gc = (st[0], st[1], st[2], st[3])
    gvalid = st[4] != 0.0
    status = DONE
    done_here = 0
    while i_out < nout:
        at_output, status, full, tk, step = plan_grid_step(t_out, i_out, t0, k, h, max_steps, done_here, budget)
        if at_output:
            out_y[i_out, 0], out_y[i_out, 1], out_y[i_out, 2], out_y[i_out, 3] = q
            out_y[i_out, 4], out_y[i_out, 5], out_y[i_out, 6], out_y[i_out, 7] = Q
            i_out += 1
            continue
        if status != DONE:
            break
        if method == SPLITTING:
            qn, Qn, gcn, gvn, ne = _split_step(q, Q, tk, step, flow, weight, toff, axes, coef, inertia, terms,
                                               params, table, work, gc, gvalid)
            nev += ne
        else:
            ytmp = scratch[0]
            ytmp[0], ytmp[1], ytmp[2], ytmp[3] = q
            ytmp[4], ytmp[5], ytmp[6], ytmp[7] = Q
            _rk4_step(ytmp, tk, step, inertia, terms, params, table, work, scratch[1:5], scratch[5])
            nev += 4
            qn = (ytmp[0], ytmp[1], ytmp[2], ytmp[3])
            Qn = (ytmp[4], ytmp[5], ytmp[6], ytmp[7])
            gcn = gc
            gvn = False
        steps += 1
        done_here += 1
        if not _finite(qn, Qn):
            status = NONFINITE
            break
        if full:
            q, Q, gc, gvalid = qn, Qn, gcn, gvn
            k += 1
        else:
            out_y[i_out, 0], out_y[i_out, 1], out_y[i_out, 2], out_y[i_out, 3] = qn
            out_y[i_out, 4], out_y[i_out, 5], out_y[i_out, 6], out_y[i_out, 7] = Qn
            i_out += 1
    y[0], y[1], y[2], y[3] = q
    y[4], y[5], y[6], y[7] = Q
    st[0], st[1], st[2], st[3] = gc
    st[4] = 1.0 if gvalid else 0.0
    save_counters(cnt, k, i_out, steps, nev)
    keepalive(scratch_own)
    return status


# ---------------------------------------------------------------------------------------
# Groups of members on the common grid (ensembles)


@jit_inline
def _split_step_lanes(yg, nl, t, h, flow, weight, toff, AX, CF, I, terms, params, table, work, G, gvalid):
    """:func:`_split_step` for the lanes of ``yg (8, L)``, in place; ``G (4, L)`` the cached
    gradients. Returns ``(gvalid, evaluations)``."""
    nev = 0
    for j in range(flow.shape[0]):
        f = flow[j]
        tau = weight[j] * h
        if f != KICK:
            for l in range(nl):
                q, Q = _rotate((yg[0, l], yg[1, l], yg[2, l], yg[3, l]), (yg[4, l], yg[5, l], yg[6, l], yg[7, l]), f,
                               AX[:, l], CF[:, l], tau)
                yg[0, l], yg[1, l], yg[2, l], yg[3, l] = q
                yg[4, l], yg[5, l], yg[6, l], yg[7, l] = Q
            gvalid = False
        elif terms.shape[0] > 1:
            if not gvalid:
                gradient_lanes_called(t + toff[j] * h, yg, nl, I, terms, params, table, work, G)
                nev += 1
                gvalid = True
            for i in range(4):
                for l in range(nl):
                    yg[4 + i, l] = yg[4 + i, l] - tau * G[i, l]
    return gvalid, nev


@jit_inline
def _rk4_step_lanes(yg, nl, t, h, I, terms, params, table, work, K, ytmp, G):
    """:func:`_rk4_step` for the lanes of ``yg (8, L)`` (``K (4, 8, L)``), in place."""
    rhs_lanes(t, yg, nl, I, terms, params, table, work, G, K[0])
    for i in range(NDIM):
        for l in range(nl):
            ytmp[i, l] = yg[i, l] + 0.5 * h * K[0, i, l]
    rhs_lanes(t + 0.5 * h, ytmp, nl, I, terms, params, table, work, G, K[1])
    for i in range(NDIM):
        for l in range(nl):
            ytmp[i, l] = yg[i, l] + 0.5 * h * K[1, i, l]
    rhs_lanes(t + 0.5 * h, ytmp, nl, I, terms, params, table, work, G, K[2])
    for i in range(NDIM):
        for l in range(nl):
            ytmp[i, l] = yg[i, l] + h * K[2, i, l]
    rhs_lanes(t + h, ytmp, nl, I, terms, params, table, work, G, K[3])
    for i in range(NDIM):
        for l in range(nl):
            yg[i, l] += h / 6.0 * (K[0, i, l] + 2.0 * (K[1, i, l] + K[2, i, l]) + K[3, i, l])


@jit_inline
def _copy_rows(dst, src, rows, nl):
    """``dst[:rows, :nl] = src[:rows, :nl]`` (lanes last)."""
    for i in range(rows):
        for l in range(nl):
            dst[i, l] = src[i, l]


@jit_inline
def _store_output(out_y, i_out, yg, nl):
    """Output ``i_out`` of every lane: ``out_y[l, i_out] = yg[:, l]``."""
    for l in range(nl):
        for i in range(NDIM):
            out_y[l, i_out, i] = yg[i, l]


@jit
def advance_group(Y, ST, cnt, t_out, out_y, t0, h, method, flow, weight, toff, axes, coef, inertia, terms, params,
                  table, work, max_steps, budget):
    """:func:`advance` for a group of ``nl = Y.shape[0]`` members on the common grid.

    ``Y (nl, 8)``, ``ST (nl, ST_SIZE)``, ``axes (nl, 3)``, ``coef (nl, 4)``, ``inertia (nl, 3)``,
    ``out_y (nl, N, 8)`` per member; ``cnt`` and ``work`` the group's (the counters count
    group steps). On :data:`NONFINITE` every member keeps its last finite state.
    """
    nl = Y.shape[0]
    nout = t_out.shape[0]
    k, i_out, steps, nev = load_counters(cnt)
    if i_out >= nout:
        return DONE
    terms, params, table, work = borrow_model(terms, params, table, work)
    flow, weight, toff = borrow(flow), borrow(weight), borrow(toff)
    own = np.empty((2, NDIM, nl))
    yg = borrow(own[0])
    yn = borrow(own[1])
    Gown = np.empty((2, 4, nl))
    G = borrow(Gown[0])
    Gn = borrow(Gown[1])
    Kown = np.empty((4, NDIM, nl))
    K = borrow(Kown)
    tmpown = np.empty((NDIM, nl))
    ytmp = borrow(tmpown)
    Iown = np.empty((3, nl))
    I = borrow(Iown)
    AXown = np.empty((3, nl), dtype=np.int64)
    AX = borrow(AXown)
    CFown = np.empty((4, nl))
    CF = borrow(CFown)
    for l in range(nl):
        for i in range(NDIM):
            yg[i, l] = Y[l, i]
        for i in range(4):
            G[i, l] = ST[l, i]
            CF[i, l] = coef[l, i]
        for i in range(3):
            I[i, l] = inertia[l, i]
            AX[i, l] = axes[l, i]
    gvalid = ST[0, 4] != 0.0
    status = DONE
    done_here = 0
    while i_out < nout:
        at_output, status, full, tk, step = plan_grid_step(t_out, i_out, t0, k, h, max_steps, done_here, budget)
        if at_output:
            _store_output(out_y, i_out, yg, nl)
            i_out += 1
            continue
        if status != DONE:
            break
        _copy_rows(yn, yg, NDIM, nl)
        if method == SPLITTING:
            _copy_rows(Gn, G, 4, nl)
            gvn, ne = _split_step_lanes(yn, nl, tk, step, flow, weight, toff, AX, CF, I, terms, params, table, work,
                                        Gn, gvalid)
            nev += ne
        else:
            _rk4_step_lanes(yn, nl, tk, step, I, terms, params, table, work, K, ytmp, Gn)
            nev += 4
            gvn = False
        steps += 1
        done_here += 1
        ok = True
        for l in range(nl):
            sm = 0.0
            for i in range(NDIM):
                sm += yn[i, l]
            if not (abs(sm) < np.inf):
                ok = False
        if not ok:
            status = NONFINITE
            break
        if full:
            _copy_rows(yg, yn, NDIM, nl)
            if method == SPLITTING:
                _copy_rows(G, Gn, 4, nl)
            gvalid = gvn
            k += 1
        else:
            _store_output(out_y, i_out, yn, nl)
            i_out += 1
    for l in range(nl):
        for i in range(NDIM):
            Y[l, i] = yg[i, l]
        for i in range(4):
            ST[l, i] = G[i, l]
        ST[l, 4] = 1.0 if gvalid else 0.0
    save_counters(cnt, k, i_out, steps, nev)
    keepalive(own)
    keepalive(Gown)
    keepalive(Kown)
    keepalive(tmpown)
    keepalive(Iown)
    keepalive(AXown)
    keepalive(CFown)
    return status


@jit_parallel
def advance_lanes(Y, ST, GCNT, t_out, out_y, status, t0, h, method, flow, weight, toff, AXES, COEF, inertia, terms,
                  params, table, GWORK, lanes, max_steps, budget):
    """:func:`advance_group` over the groups ``[g lanes, (g + 1) lanes)`` of an ensemble, in
    parallel over groups; ``GCNT, GWORK, status`` have one row per group."""
    E = Y.shape[0]
    for gi in nb.prange((E + lanes - 1) // lanes):  # (a group that is done returns DONE at once)
        a = gi * lanes
        b = min(E, a + lanes)
        status[gi] = advance_group(Y[a:b], ST[a:b], GCNT[gi], t_out, out_y[a:b], t0, h, method, flow, weight, toff,
                                   AXES[a:b], COEF[a:b], inertia[a:b], terms, params, table, GWORK[gi], max_steps,
                                   budget)

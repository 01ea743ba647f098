"""The exact torque-free rigid body, compiled: the closed form of :mod:`orbatt.analytic`
(Jacobi elliptic functions for the body momentum, 3-1-3 angles about the constant angular
momentum for the attitude, Carlson's ``R_J`` for the precession angle) as scalar kernels,
for the method ``"exact"`` (:mod:`orbatt.methods.exact`).

The formulas, the branches (steady rotation, the two elliptic regimes with the W or Y form of
the precession integral, the separatrix) and their accuracy are those of
:mod:`orbatt.analytic` (its module docstring); :mod:`orbatt.analytic` stays the documented
reference and the test oracle. Two changes of evaluation, not of formula: the attitude takes
the half-angle cosines and sines of ``theta`` and ``psi`` straight from ``g'`` (no ``atan2``
then ``sin``/``cos``), and the precession integral is evaluated from ``K`` backwards only
where ``dn^2 < min(sqrt(m1), FAR)`` (:data:`FAR`). The two agree to round-off (a few
``1e-15``, and ``eps |lambda t|`` in the phase: ``1e-14`` at ``t = 100``;
``tests/methods/test_exact_method.py``). This module only moves the work into compiled code:
the constants of a member's motion once (:func:`motion`, into a row of ``NC`` floats, about
2 us), then one scalar evaluation per output time (:func:`evaluate`, 0.6-1 us; about twice
that next to the separatrix, where the backward form is needed).

Units: plain float64 in the body's consistent internal units (moments, momenta, time);
``y = (q, Q)`` scalar-first quaternions, ``q`` body -> inertial, ``Q = 2 q g`` (``docs/design.md`` §1-2).
"""
from __future__ import annotations

import math

import numpy as np
from numba import prange

from ._jit import jit, jit_inline, jit_parallel
from .carlson import AGM_MAX, agm, jacobi, rf, rj

__all__ = ["permutation_parity", "NC", "STEADY", "ELLIPTIC", "SEPARATRIX", "motion", "evaluate", "evaluate_batch", "motion_batch"]

STEADY, ELLIPTIC, SEPARATRIX = 0, 1, 2
# slots of a motion row
(KIND, GABS, LAM, U0, M, M1, K, N, C, ZK, YFORM, S1, RHO, RHO2, RADIAL, A1, A2, A3, SJ1, SJ3, AGM_N) = range(21)
OMEGA = 21   # 3: steady body rate
QHAT0 = 24   # 4: q0 / |q0|
QG = 28      # 4: the constant q_G of q(t) = q_G qe(t) mu~
MU = 32      # 4: the quaternion of M^T
MAT = 36     # 9: g' = M g, row-major
G0 = 45      # 3: the body momentum g0 (steady)
AGM_SEQ = 48  # 3 * AGM_MAX: the AGM sequence of m1 (rows a, b, c)
#: length of a motion row
NC = AGM_SEQ + 3 * AGM_MAX
#: the precession integral is evaluated from ``K`` backwards where ``dn^2 < min(sqrt(m1), FAR)``
#: (:mod:`orbatt.analytic` switches at ``sqrt(m1)``; below ``dn^2 = FAR`` the forward form
#: loses at most ``eps / sqrt(FAR)``, and for ``m1 > FAR`` the second ``sn, cn, dn`` and
#: ``R_J`` of the backward form are never needed)
FAR = 1e-2


@jit_inline
def _qmul(a0, a1, a2, a3, b0, b1, b2, b3):
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


@jit_inline
def _sech(u):
    e = math.exp(-abs(u))
    return 2.0 * e / (1.0 + e * e)


@jit_inline
def _z_reduced(c, ur, sn, cn, dn, seq, nagm):
    """The precession integral ``Z(u_r)``, ``|u_r| <= K`` (:func:`orbatt.analytic._z_reduced`)."""
    n, m, m1 = c[N], c[M], c[M1]
    sn3 = sn * sn * sn
    if dn * dn < min(math.sqrt(m1), FAR):  # next to u_r = +-K: from K backwards
        v = c[K] - abs(ur)
        s, cc, d = jacobi(v, m1, seq, nagm)
        c2, d2 = cc * cc, d * d
        r = s * s * s * rj(c2, d2, 1.0, (d2 + n * c2) / (1.0 + n))
        if c[YFORM] != 0.0:
            V = (v + (n * m1 / (3.0 * (1.0 + n))) * r) / (1.0 + n)
        else:
            V = (v - (m1 / (3.0 * (1.0 + n))) * r) / (1.0 + n)
        return math.copysign(1.0, ur) * (c[ZK] - V) if ur != 0.0 else 0.0
    if c[YFORM] != 0.0:
        P = math.sqrt((n + 1.0) * ((n + m) / n))
        return ((m / (3.0 * n)) * sn3 * rj(cn * cn, dn * dn, 1.0, 1.0 + (m / n) * sn * sn)
                + math.atan2(P * sn, cn * dn) / P)
    return (sn3 / 3.0) * rj(cn * cn, dn * dn, 1.0, 1.0 + n * sn * sn)


@jit_inline
def permutation_parity(perm):
    """``+1.0`` or ``-1.0``: the parity of the permutation ``perm`` of ``0 .. n-1`` (an int
    array, not changed), by counting the swaps that sort it."""
    p = perm.copy()
    sign = 1.0
    for i in range(p.shape[0]):
        while p[i] != i:
            j = p[i]
            p[i], p[j] = p[j], p[i]
            sign = -sign
    return sign


@jit_inline
def _half(y, x):
    """``(cos(a/2), sin(a/2))`` of ``a = atan2(y, x)`` without the angle (well conditioned
    for every direction: the half-angle formula on the side where it does not cancel)."""
    r = math.sqrt(x * x + y * y)
    if r == 0.0:
        return 1.0, 0.0
    if x >= 0.0:
        ch = math.sqrt(0.5 * (r + x) / r)
        return ch, y / (2.0 * r * ch)
    sh = math.copysign(math.sqrt(0.5 * (r - x) / r), y)
    return y / (2.0 * r * sh), sh


@jit_inline
def _angles(c, t):
    """Relabelled momentum ``g'``, the precession angle ``phi`` and the half-angle cosines and
    sines ``ct, st, cp, sp`` of the nutation ``theta`` and the spin ``psi`` at ``t``
    (:func:`orbatt.analytic._evaluate`, which returns the angles themselves)."""
    u = c[LAM] * t + c[U0]
    a1, a2, a3 = c[A1], c[A2], c[A3]
    if c[KIND] == SEPARATRIX:
        sech = _sech(u)
        th = math.tanh(u)
        g1, g2, g3 = c[S1] * a1 * sech, a2 * th, a3 * sech
        phi = (c[GABS] / c[SJ3] + c[C] / (1.0 + c[N])) * t
        if c[N] > 0.0:
            rn = math.sqrt(c[N])
            phi = phi + (c[C] * rn / (c[LAM] * (1.0 + c[N]))) * math.atan(rn * th)
        cp, sp = _half(g1, g2)
    else:
        seq = c[AGM_SEQ:].reshape((3, AGM_MAX))
        nagm = int(c[AGM_N])
        K2 = 2.0 * c[K]
        k = np.rint(u / K2)
        ur = u - k * K2
        sn, cn, dn = jacobi(ur, c[M1], seq, nagm)
        flip = 1.0 if np.fmod(k, 2.0) == 0.0 else -1.0
        g1, g2, g3 = a1 * cn * flip, a2 * sn * flip, a3 * dn
        if c[YFORM] != 0.0:
            rate, coef = c[GABS] / c[SJ3], c[C] / c[LAM]
        else:
            rate, coef = c[GABS] / c[SJ1], -c[C] * c[N] / c[LAM]
        phi = rate * t
        if coef != 0.0:
            phi = phi + coef * (k * (2.0 * c[ZK]) + _z_reduced(c, ur, sn, cn, dn, seq, nagm))
        # psi = atan2(a1 |cn|, a2 sn) - pi k: its half angle turned by -pi k / 2 (k mod 4)
        cp, sp = _half(a1 * abs(cn), a2 * sn)
        j = np.fmod(k, 4.0)
        if j < 0.0:
            j += 4.0
        if j == 1.0:
            cp, sp = sp, -cp
        elif j == 2.0:
            cp, sp = -cp, -sp
        elif j == 3.0:
            cp, sp = -sp, cp
    ct, st = _half(math.sqrt(g1 * g1 + g2 * g2), g3)
    return g1, g2, g3, phi, ct, st, cp, sp


@jit_inline
def _euler(phi, ct, st, cp, sp):
    """``q_z(phi) (q_x(theta) q_z(psi))`` from ``phi`` and the half-angle cosines and sines of
    ``theta`` and ``psi``, formed factor by factor (as :mod:`orbatt.analytic`)."""
    h = 0.5 * phi
    return _qmul(math.cos(h), 0.0, 0.0, math.sin(h), ct * cp, st * cp, -st * sp, ct * sp)


@jit
def motion(inertia, y0, c):
    """Fill the motion row ``c (NC,)`` of a member: principal moments ``inertia (3,)``,
    initial ``y0 = (q0, Q0)`` (8,; ``q0 != 0``) (:func:`orbatt.analytic._motion` and the
    constants of :func:`orbatt.analytic.torque_free`)."""
    c[:] = 0.0
    q0 = y0[:4]
    rho2 = q0[0] * q0[0] + q0[1] * q0[1] + q0[2] * q0[2] + q0[3] * q0[3]
    rho = math.sqrt(rho2)
    c[RHO], c[RHO2] = rho, rho2
    for i in range(4):
        c[QHAT0 + i] = q0[i] / rho
    # w0 = q0~ Q0 = (q0.Q0, 2 g0)
    w = _qmul(q0[0], -q0[1], -q0[2], -q0[3], y0[4], y0[5], y0[6], y0[7])
    c[RADIAL] = w[0]
    g0 = np.array([0.5 * w[1], 0.5 * w[2], 0.5 * w[3]])
    I = inertia
    gabs = math.sqrt(g0[0] * g0[0] + g0[1] * g0[1] + g0[2] * g0[2])
    c[GABS] = gabs
    for i in range(3):
        c[OMEGA + i] = g0[i] / I[i]
        c[G0 + i] = g0[i]
    # steady: g an eigenvector of the inertia tensor (or zero)
    ref = -1.0
    steady = True
    for i in range(3):
        if g0[i] != 0.0:
            if ref < 0.0:
                ref = I[i]
            elif I[i] != ref:
                steady = False
    if steady:
        c[KIND] = STEADY
        return
    e = g0 / gabs
    order = np.argsort(I, kind="mergesort")
    imin, imid, imax = order[0], order[1], order[2]
    Imin, Imid, Imax = I[imin], I[imid], I[imax]
    s = (e[imax] * e[imax]) * ((Imax - Imid) / Imax) - (e[imin] * e[imin]) * ((Imid - Imin) / Imin)
    perm = np.array([imin, imid, imax]) if s >= 0.0 else np.array([imax, imid, imin])
    parity = permutation_parity(perm)
    eps3 = 1.0 if e[perm[2]] >= 0.0 else -1.0
    signs = np.array([1.0, parity * eps3, eps3])
    Mx = np.zeros((3, 3))
    for i in range(3):
        Mx[i, perm[i]] = signs[i]
    J1, J2, J3 = I[perm[0]], I[perm[1]], I[perm[2]]
    h = Mx @ e
    r12 = (J1 / J2) * ((J3 - J2) / (J3 - J1))
    r32 = (J3 / J2) * ((J2 - J1) / (J3 - J1))
    a1 = math.sqrt((h[0] * h[0]) + r12 * (h[1] * h[1]))
    a3 = math.sqrt((h[2] * h[2]) + r32 * (h[1] * h[1]))
    a2 = a1 / math.sqrt(r12)
    n = (J3 / J1) * ((J2 - J1) / (J3 - J2))
    m1 = min(max(s * (J3 / (J3 - J2)) / (a3 * a3), 0.0), 1.0)
    m = 1.0 - m1
    lam = gabs * a3 * math.sqrt(((J3 - J2) / J1) * ((J3 - J1) / J2)) / J3
    sigma = 1.0 if J3 > J1 else -1.0
    c[C] = gabs * ((J3 - J1) / J1) / J3
    c[A1], c[A2], c[A3] = gabs * a1, gabs * a2, gabs * a3
    c[SJ1], c[SJ3] = J1, J3
    c[N], c[M], c[M1] = n, m, m1
    for i in range(3):
        for j in range(3):
            c[MAT + 3 * i + j] = Mx[i, j]
    if m1 == 0.0:
        c[KIND] = SEPARATRIX
        s1 = 1.0 if h[0] >= 0.0 else -1.0
        sech0 = math.sqrt(((h[0] * h[0]) + (h[2] * h[2])) / ((a1 * a1) + (a3 * a3)))
        c[S1] = s1
        c[U0] = math.asinh((h[1] / a2) / sech0)
        c[LAM] = sigma * s1 * lam
        c[M], c[K] = 1.0, np.inf
    else:
        c[KIND] = ELLIPTIC
        c[S1] = 1.0
        x, y = h[0], h[1] * math.sqrt(r12)
        rr = math.sqrt(x * x + y * y)
        cs, sn = x / rr, y / rr
        Kv = rf(0.0, m1, 1.0)
        F = sn * rf(cs * cs, m1 + m * cs * cs, 1.0)
        c[U0] = F if cs >= 0.0 else (1.0 if sn >= 0.0 else -1.0) * 2.0 * Kv - F
        c[K] = Kv
        c[LAM] = sigma * lam
        if n > 1.0:
            c[YFORM] = 1.0
            P = math.sqrt((n + 1.0) * ((n + m) / n))
            c[ZK] = (m / (3.0 * n)) * rj(0.0, m1, 1.0, 1.0 + m / n) + 0.5 * math.pi / P
        elif n > 0.0:
            c[ZK] = rj(0.0, m1, 1.0, 1.0 + n) / 3.0
        c[AGM_N] = agm(m1, c[AGM_SEQ:].reshape((3, AGM_MAX)))
    # mu: the quaternion of M^T (a proper signed permutation; Shepperd's method)
    R = Mx.T
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr >= 0.0:
        r = math.sqrt(1.0 + tr)
        mu = (0.5 * r, (R[2, 1] - R[1, 2]) / (2 * r), (R[0, 2] - R[2, 0]) / (2 * r), (R[1, 0] - R[0, 1]) / (2 * r))
    else:
        i = 0
        if R[1, 1] > R[i, i]:
            i = 1
        if R[2, 2] > R[i, i]:
            i = 2
        j, k = (i + 1) % 3, (i + 2) % 3
        r = math.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        v = np.zeros(4)
        v[0] = (R[k, j] - R[j, k]) / (2 * r)
        v[1 + i] = 0.5 * r
        v[1 + j] = (R[j, i] + R[i, j]) / (2 * r)
        v[1 + k] = (R[k, i] + R[i, k]) / (2 * r)
        mu = (v[0], v[1], v[2], v[3])
    c[MU], c[MU + 1], c[MU + 2], c[MU + 3] = mu
    # q_G = qhat0 mu qe(0)~
    _, _, _, phi0, ct0, st0, cp0, sp0 = _angles(c, 0.0)
    e0 = _euler(phi0, ct0, st0, cp0, sp0)
    a = _qmul(c[QHAT0], c[QHAT0 + 1], c[QHAT0 + 2], c[QHAT0 + 3], mu[0], mu[1], mu[2], mu[3])
    qg = _qmul(a[0], a[1], a[2], a[3], e0[0], -e0[1], -e0[2], -e0[3])
    c[QG], c[QG + 1], c[QG + 2], c[QG + 3] = qg


@jit_inline
def _state(c, t, out):
    """``(q, Q)`` at ``t`` (relative to the epoch of ``y0``) into ``out (8,)``."""
    if c[KIND] == STEADY:
        vx, vy, vz = 0.5 * c[OMEGA] * t, 0.5 * c[OMEGA + 1] * t, 0.5 * c[OMEGA + 2] * t
        nv = math.sqrt(vx * vx + vy * vy + vz * vz)
        sc = math.sin(nv) / nv if nv > 0.0 else 1.0
        qh = _qmul(c[QHAT0], c[QHAT0 + 1], c[QHAT0 + 2], c[QHAT0 + 3], math.cos(nv), sc * vx, sc * vy, sc * vz)
        gx, gy, gz = 2.0 * c[G0], 2.0 * c[G0 + 1], 2.0 * c[G0 + 2]
    else:
        g1, g2, g3, phi, ct, st, cp, sp = _angles(c, t)
        e = _euler(phi, ct, st, cp, sp)
        a = _qmul(c[QG], c[QG + 1], c[QG + 2], c[QG + 3], e[0], e[1], e[2], e[3])
        qh = _qmul(a[0], a[1], a[2], a[3], c[MU], -c[MU + 1], -c[MU + 2], -c[MU + 3])
        # g = M^T g'
        gx = c[MAT] * g1 + c[MAT + 3] * g2 + c[MAT + 6] * g3
        gy = c[MAT + 1] * g1 + c[MAT + 4] * g2 + c[MAT + 7] * g3
        gz = c[MAT + 2] * g1 + c[MAT + 5] * g2 + c[MAT + 8] * g3
        gx, gy, gz = 2.0 * gx, 2.0 * gy, 2.0 * gz
    rho = c[RHO]
    q0, q1, q2, q3 = rho * qh[0], rho * qh[1], rho * qh[2], rho * qh[3]
    Qv = _qmul(q0, q1, q2, q3, c[RADIAL], gx, gy, gz)
    r2 = c[RHO2]
    out[0], out[1], out[2], out[3] = q0, q1, q2, q3
    out[4], out[5], out[6], out[7] = Qv[0] / r2, Qv[1] / r2, Qv[2] / r2, Qv[3] / r2


@jit
def evaluate(c, y0, t0, t, out):
    """``(q, Q)`` of the member with motion row ``c`` and initial state ``y0`` at the times
    ``t (N,)`` (absolute; the epoch of ``y0`` is ``t0``) into ``out (N, 8)``; ``t == t0``
    gives ``y0`` itself."""
    for i in range(t.shape[0]):
        if t[i] == t0:
            out[i, :] = y0
        else:
            _state(c, t[i] - t0, out[i])


@jit_parallel
def motion_batch(inertia, y0, c):
    """:func:`motion` of every member (rows of ``inertia``, ``y0``, ``c``), in parallel."""
    for e in prange(c.shape[0]):
        motion(inertia[e], y0[e], c[e])


@jit_parallel
def evaluate_batch(c, y0, t0, t, out):
    """:func:`evaluate` of every member (``out (E, N, 8)``), in parallel over members."""
    for e in prange(c.shape[0]):
        evaluate(c[e], y0[e], t0, t, out[e])

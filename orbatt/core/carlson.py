"""Compiled scalar elliptic functions for the closed-form free rigid body
(:mod:`orbatt.core.free_body`): Carlson's symmetric integrals ``R_F``, ``R_C``, ``R_J`` and the
Jacobi elliptic functions ``sn, cn, dn`` parametrized by ``m1 = 1 - m``.

Carlson's integrals follow B. C. Carlson, "Numerical computation of real or complex elliptic
integrals", Numer. Algorithms 10 (1995) 13-26 (duplication until the arguments agree to the
truncation error of the fifth-order series, relative error about ``eps``); the same algorithm
as :func:`scipy.special.elliprf`, :func:`~scipy.special.elliprc`,
:func:`~scipy.special.elliprj` (real arguments only: ``x, y, z >= 0`` with at most one zero,
``p > 0``). The Jacobi functions are those of :func:`orbatt.analytic.jacobi` (AGM started from
``sqrt(m1)``), with the AGM sequence computed once per parameter (:func:`agm`) and kept.
Plain floats, dimensionless.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline

__all__ = ["rf", "rc", "rc1", "rj", "agm", "jacobi", "AGM_MAX"]

_R = 0.5 * float(np.finfo(np.float64).eps)
#: Carlson's convergence factors: (3r)^(-1/6) for R_F, (3r)^(-1/8) for R_C, (r/4)^(-1/6) for R_J
_QF = (3.0 * _R) ** (-1.0 / 6.0)
_QC = (3.0 * _R) ** (-1.0 / 8.0)
_QJ = (0.25 * _R) ** (-1.0 / 6.0)
#: longest AGM sequence kept (:func:`agm`)
AGM_MAX = 64


@jit_inline
def rf(x, y, z):
    """Carlson's ``R_F(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z))``."""
    a0 = (x + y + z) / 3.0
    q = _QF * max(abs(a0 - x), abs(a0 - y), abs(a0 - z))
    a, f = a0, 1.0
    xm, ym, zm = x, y, z
    for _ in range(200):
        if f * q < abs(a):
            break
        sx, sy, sz = math.sqrt(xm), math.sqrt(ym), math.sqrt(zm)
        lam = sx * sy + sx * sz + sy * sz
        xm, ym, zm = 0.25 * (xm + lam), 0.25 * (ym + lam), 0.25 * (zm + lam)
        a = 0.25 * (a + lam)
        f *= 0.25
    X = (a0 - x) * f / a
    Y = (a0 - y) * f / a
    Z = -(X + Y)
    e2 = X * Y - Z * Z
    e3 = X * Y * Z
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / math.sqrt(a)


@jit_inline
def rc(x, y):
    """Carlson's ``R_C(x, y) = R_F(x, y, y)`` for ``x >= 0``, ``y > 0``."""
    a0 = (x + 2.0 * y) / 3.0
    q = _QC * abs(a0 - x)
    a, f = a0, 1.0
    xm, ym = x, y
    for _ in range(200):
        if f * q < abs(a):
            break
        lam = 2.0 * math.sqrt(xm) * math.sqrt(ym) + ym
        xm, ym = 0.25 * (xm + lam), 0.25 * (ym + lam)
        a = 0.25 * (a + lam)
        f *= 0.25
    s = (y - a0) * f / a
    poly = 0.3 + s * (1.0 / 7.0 + s * (0.375 + s * (9.0 / 22.0 + s * (159.0 / 208.0 + s * 1.125))))
    return (1.0 + s * s * poly) / math.sqrt(a)


@jit_inline
def rc1(e):
    """``R_C(1, 1 + e)`` for ``e > -1``: ``atan(sqrt(e)) / sqrt(e)`` (``e > 0``),
    ``atanh(sqrt(-e)) / sqrt(-e)`` (``e < 0``), and its series ``sum (-e)^k / (2k + 1)`` for
    ``|e| < 1e-3`` (truncation below ``1e-18``)."""
    if abs(e) < 1e-3:
        return 1.0 - e * (1.0 / 3.0 - e * (0.2 - e * (1.0 / 7.0 - e * (1.0 / 9.0 - e * (1.0 / 11.0 - e / 13.0)))))
    if e > 0.0:
        r = math.sqrt(e)
        return math.atan(r) / r
    r = math.sqrt(-e)
    return math.atanh(r) / r


@jit
def rj(x, y, z, p):
    """Carlson's ``R_J(x, y, z, p) = 3/2 int_0^inf dt / ((t+p) sqrt((t+x)(t+y)(t+z)))`` for
    ``p > 0``."""
    a0 = (x + y + z + 2.0 * p) / 5.0
    delta = (p - x) * (p - y) * (p - z)
    q = _QJ * max(abs(a0 - x), abs(a0 - y), abs(a0 - z), abs(a0 - p))
    a, f, fe, s = a0, 1.0, 1.0, 0.0
    xm, ym, zm, pm = x, y, z, p
    for _ in range(200):
        if f * q < abs(a):
            break
        sx, sy, sz, sp = math.sqrt(xm), math.sqrt(ym), math.sqrt(zm), math.sqrt(pm)
        lam = sx * sy + sx * sz + sy * sz
        d = (sp + sx) * (sp + sy) * (sp + sz)
        e = fe * delta / (d * d)
        s += f * rc1(e) / d
        xm, ym, zm, pm = 0.25 * (xm + lam), 0.25 * (ym + lam), 0.25 * (zm + lam), 0.25 * (pm + lam)
        a = 0.25 * (a + lam)
        f *= 0.25
        fe *= 1.0 / 64.0
    X = (a0 - x) * f / a
    Y = (a0 - y) * f / a
    Z = (a0 - z) * f / a
    P = -0.5 * (X + Y + Z)
    xyz = X * Y * Z
    e2 = X * Y + X * Z + Y * Z - 3.0 * P * P
    e3 = xyz + 2.0 * e2 * P + 4.0 * P * P * P
    e4 = (2.0 * xyz + e2 * P + 3.0 * P * P * P) * P
    e5 = xyz * P * P
    series = (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0 - 9.0 * e2 * e3 / 52.0
              + 3.0 * e5 / 26.0)
    return f * series / (a * math.sqrt(a)) + 6.0 * s


@jit
def agm(m1, seq):
    """The AGM sequence of :func:`orbatt.analytic.jacobi` for ``0 < m1 <= 1``, into
    ``seq (3, AGM_MAX)`` (rows ``a``, ``b``, ``c``); returns its last index ``N``."""
    eps = 2.0 * _R
    seq[0, 0], seq[1, 0], seq[2, 0] = 1.0, math.sqrt(m1), math.sqrt(1.0 - m1)
    n = 0
    while seq[2, n] > 0.5 * eps * seq[0, n] and n + 1 < AGM_MAX:
        a, b, c = seq[0, n], seq[1, n], seq[2, n]
        an = 0.5 * (a + b)
        seq[2, n + 1] = c * c / (4.0 * an)
        seq[1, n + 1] = math.sqrt(a * b)
        seq[0, n + 1] = an
        n += 1
    return n


@jit_inline
def jacobi(u, m1, seq, n):
    """``(sn, cn, dn)`` of ``(u | 1 - m1)`` for ``|u| <= K``, from the AGM sequence ``seq``,
    ``n`` of :func:`agm` (descending Landen, as :func:`orbatt.analytic.jacobi`)."""
    phi = (2.0 ** n * seq[0, n]) * u
    for i in range(n, 0, -1):
        c, b = seq[2, i], seq[1, i]
        cp = c * math.cos(phi)
        beta = math.atan2(c * math.sin(phi), math.sqrt(b * b + cp * cp))
        phi = 0.5 * (phi + beta)
    sn, cn = math.sin(phi), math.cos(phi)
    return sn, cn, math.sqrt(m1 + (1.0 - m1) * cn * cn)

"""Scalar quaternion kernels for compiled hot paths (numba ``njit``).

Quaternions here are 4-tuples of floats ``(q0, q1, q2, q3)``, scalar first; 3-vectors are
3-tuples. Tuples live in registers inside numba, so these kernels allocate nothing. The
conventions are those of :mod:`orbatt.quaternion` (and ``DESIGN.md`` §1); the vectorized,
public, numpy versions are in that module and are tested against these.
"""
from __future__ import annotations

import math

import numba as nb

_jit = nb.njit(cache=True, inline="always")


@_jit
def qmul(a, b):
    """Quaternion product ``a b = (a0 b0 - a.b, a0 b + b0 a + a x b)``."""
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    )


@_jit
def qconj(a):
    """Conjugate ``(a0, -a1, -a2, -a3)``."""
    return (a[0], -a[1], -a[2], -a[3])


@_jit
def qdot(a, b):
    """R^4 dot product ``a.b = Re(a b~)``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]


@_jit
def qscale(s, a):
    """``s a`` for a float ``s``."""
    return (s * a[0], s * a[1], s * a[2], s * a[3])


@_jit
def qadd(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3])


@_jit
def rotate(q, v):
    """``q (0, v) q~`` for a unit ``q`` (body -> space when ``q`` is the attitude)."""
    w = qmul(qmul(q, (0.0, v[0], v[1], v[2])), qconj(q))
    return (w[1], w[2], w[3])


@_jit
def rotate_inv(q, v):
    """``q~ (0, v) q`` for a unit ``q`` (space -> body when ``q`` is the attitude)."""
    w = qmul(qmul(qconj(q), (0.0, v[0], v[1], v[2])), q)
    return (w[1], w[2], w[3])


@_jit
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@_jit
def exp_pure(v0, v1, v2):
    """``exp((0, v))`` = ``(cos|v|, sin|v| v/|v|)``, exact at ``v = 0``."""
    n = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    # sin(n)/n = 1 - n^2/6 + O(n^4): exact in float64 below 1e-8
    s = 1.0 - n * n / 6.0 if n < 1e-8 else math.sin(n) / n
    return (math.cos(n), s * v0, s * v1, s * v2)

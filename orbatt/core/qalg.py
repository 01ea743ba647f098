"""Scalar quaternion kernels for compiled hot paths (numba ``njit``).

Quaternions here are 4-tuples of floats ``(q0, q1, q2, q3)``, scalar first; 3-vectors are
3-tuples. Tuples live in registers inside numba, so these kernels allocate nothing. The
conventions are those of :mod:`orbatt.quaternion` (and ``docs/design.md`` §1); the vectorized,
public, numpy versions are in that module and are tested against these.
"""
from __future__ import annotations


from ._jit import jit_inline


@jit_inline
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


@jit_inline
def qmul_pure(a, v):
    """``a (0, v)`` for a 3-vector ``v``: :func:`qmul` with the products of the zero scalar
    part left out, the remaining terms summed in :func:`qmul`'s order, hence the same numbers
    (``x + 0 = x``; at most the sign of an exact zero differs) for 8 fewer operations."""
    a0, a1, a2, a3 = a
    v1, v2, v3 = v
    return (
        -(a1 * v1) - a2 * v2 - a3 * v3,
        a0 * v1 + a2 * v3 - a3 * v2,
        a0 * v2 - a1 * v3 + a3 * v1,
        a0 * v3 + a1 * v2 - a2 * v1,
    )


@jit_inline
def pure_qmul(v, b):
    """``(0, v) b`` for a 3-vector ``v``: :func:`qmul` without the zero scalar part's products,
    as :func:`qmul_pure` (the same numbers)."""
    v1, v2, v3 = v
    b0, b1, b2, b3 = b
    return (
        -(v1 * b1) - v2 * b2 - v3 * b3,
        v1 * b0 + v2 * b3 - v3 * b2,
        -(v1 * b3) + v2 * b0 + v3 * b1,
        v1 * b2 - v2 * b1 + v3 * b0,
    )


@jit_inline
def qconj(a):
    """Conjugate ``(a0, -a1, -a2, -a3)``."""
    return (a[0], -a[1], -a[2], -a[3])


@jit_inline
def qdot(a, b):
    """R^4 dot product ``a.b = Re(a b~)``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]


@jit_inline
def qscale(s, a):
    """``s a`` for a float ``s``."""
    return (s * a[0], s * a[1], s * a[2], s * a[3])


@jit_inline
def rotate(q, v):
    """``q (0, v) q~`` for a unit ``q`` (body -> space when ``q`` is the attitude)."""
    w = qmul(qmul(q, (0.0, v[0], v[1], v[2])), qconj(q))
    return (w[1], w[2], w[3])


@jit_inline
def rotate_inv(q, v):
    """``q~ (0, v) q`` for a unit ``q`` (space -> body when ``q`` is the attitude)."""
    w = qmul(qmul(qconj(q), (0.0, v[0], v[1], v[2])), q)
    return (w[1], w[2], w[3])


@jit_inline
def vadd(a, b):
    """``a + b`` of 3-tuples."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@jit_inline
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@jit_inline
def mat_vec(m, a, v):
    """``M v`` for the 3x3 matrix ``M`` stored row-major at ``m[a:a + 9]`` (a row's parameters)."""
    return (m[a] * v[0] + m[a + 1] * v[1] + m[a + 2] * v[2],
            m[a + 3] * v[0] + m[a + 4] * v[1] + m[a + 5] * v[2],
            m[a + 6] * v[0] + m[a + 7] * v[1] + m[a + 8] * v[2])


@jit_inline
def mat_t_vec(m, a, v):
    """``M^T v`` for the 3x3 matrix ``M`` stored row-major at ``m[a:a + 9]``."""
    return (m[a] * v[0] + m[a + 3] * v[1] + m[a + 6] * v[2],
            m[a + 1] * v[0] + m[a + 4] * v[1] + m[a + 7] * v[2],
            m[a + 2] * v[0] + m[a + 5] * v[1] + m[a + 8] * v[2])

"""Orbits given by samples: quintic Hermite interpolation (compiled kernels, no units).

A sampled orbit is a float64 ``table`` of shape ``(N, 10)``, one row per sample, times
strictly increasing::

    table[i] = [t, x, y, z, vx, vy, vz, ax, ay, az]

position, velocity and acceleration of the satellite relative to the central body in
inertial ``S`` components, in the caller's consistent units (orbatt: km, km/s, km/s^2,
seconds since the orbit epoch).

On ``[t_i, t_{i+1}]`` (``h = t_{i+1} - t_i``, ``s = (t - t_i) / h``) the position is the
quintic Hermite polynomial matching ``x, v, a`` at both ends::

    x(s) = H0 x_i + H1 h v_i + H2 h^2 a_i + H3 h^2 a_{i+1} + H4 h v_{i+1} + H5 x_{i+1}

Its error is ``h^6 max|x^(6)| / 46080`` at most (the largest value of
``s^3 (1 - s)^3 / 6!``). With samples spaced by ``h = (2 pi / N) sqrt(r^3 / GM)``
(what :class:`orbatt.orbits.ReboundOrbit` does, ``N`` samples per orbit at the local
dynamical time scale) the relative position error is about ``(2 pi / N)^6 / 46080``-ish
times an order-one factor; ``tests/test_rebound_orbit.py`` measures it.

Kernels keep the index of the last interval used in ``work[3]`` (NaN: none), so the
search is O(1) for the integrators' nearby times; a far jump falls back to bisection.
Times outside ``[t_0, t_{N-1}]`` raise ``ValueError`` (no extrapolation).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline
from .environment import find_row

TABLE_COLUMNS = 10
#: index in ``work`` of the last interval used
WORK_SLOT = 3



@jit
def find_interval(table, t, work):
    """Index ``i`` with ``table[i, 0] <= t <= table[i + 1, 0]``; warm-started from
    ``work[3]``. Raises ``ValueError`` for ``t`` outside the sampled span."""
    n = table.shape[0]
    if not (t >= table[0, 0] and t <= table[n - 1, 0]):
        raise ValueError("sampled orbit: time outside the sampled span; build the orbit "
                         "(ReboundOrbit) over a longer span")
    return find_row(table, t, work, WORK_SLOT)


@jit_inline
def _basis(s):
    """Quintic Hermite basis ``(H0..H5)`` and its first and second derivatives in ``s``."""
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    s5 = s4 * s
    H = (1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5,
         s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5,
         0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5,
         0.5 * s3 - s4 + 0.5 * s5,
         -4.0 * s3 + 7.0 * s4 - 3.0 * s5,
         10.0 * s3 - 15.0 * s4 + 6.0 * s5)
    return H


@jit_inline
def _dbasis(s):
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    return (-30.0 * s2 + 60.0 * s3 - 30.0 * s4,
            1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4,
            s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4,
            1.5 * s2 - 4.0 * s3 + 2.5 * s4,
            -12.0 * s2 + 28.0 * s3 - 15.0 * s4,
            30.0 * s2 - 60.0 * s3 + 30.0 * s4)


@jit_inline
def _ddbasis(s):
    s2 = s * s
    s3 = s2 * s
    return (-60.0 * s + 180.0 * s2 - 120.0 * s3,
            -36.0 * s + 96.0 * s2 - 60.0 * s3,
            1.0 - 9.0 * s + 18.0 * s2 - 10.0 * s3,
            3.0 * s - 12.0 * s2 + 10.0 * s3,
            -24.0 * s + 84.0 * s2 - 60.0 * s3,
            60.0 * s - 180.0 * s2 + 120.0 * s3)


@jit_inline
def _combine(table, i, B, h, j):
    """Component ``j`` (0..2) of ``sum B_k c_k`` with the Hermite data of interval ``i``."""
    r0 = table[i]
    r1 = table[i + 1]
    return (B[0] * r0[1 + j] + B[5] * r1[1 + j]
            + h * (B[1] * r0[4 + j] + B[4] * r1[4 + j])
            + h * h * (B[2] * r0[7 + j] + B[3] * r1[7 + j]))


@jit
def sampled_radial(t, table, work):
    """Radius and radial unit vector (inertial components) of a sampled orbit at ``t``.

    Returns ``(r, (x, y, z))`` like :func:`orbatt.core.kepler.kepler_radial`."""
    i = find_interval(table, t, work)
    h = table[i + 1, 0] - table[i, 0]
    B = _basis((t - table[i, 0]) / h)
    x = _combine(table, i, B, h, 0)
    y = _combine(table, i, B, h, 1)
    z = _combine(table, i, B, h, 2)
    r = math.sqrt(x * x + y * y + z * z)
    return r, (x / r, y / r, z / r)


@jit
def sampled_state(t, table, work):
    """Radius, radial unit vector and velocity (inertial components) of a sampled orbit at
    ``t``: ``(r, xhat, v)``, ``r`` and ``xhat`` exactly as :func:`sampled_radial`."""
    i = find_interval(table, t, work)
    h = table[i + 1, 0] - table[i, 0]
    s = (t - table[i, 0]) / h
    B = _basis(s)
    x = _combine(table, i, B, h, 0)
    y = _combine(table, i, B, h, 1)
    z = _combine(table, i, B, h, 2)
    r = math.sqrt(x * x + y * y + z * z)
    D = _dbasis(s)
    return (r, (x / r, y / r, z / r),
            (_combine(table, i, D, h, 0) / h, _combine(table, i, D, h, 1) / h, _combine(table, i, D, h, 2) / h))


@jit
def sampled_many(t, table):
    """Position, velocity and acceleration ``(N, 3)`` each, interpolated at the times
    ``t`` (array; derivatives of the quintic Hermite polynomial)."""
    n = t.shape[0]
    pos = np.empty((n, 3))
    vel = np.empty((n, 3))
    acc = np.empty((n, 3))
    work = np.full(4, np.nan)
    for k in range(n):
        i = find_interval(table, t[k], work)
        h = table[i + 1, 0] - table[i, 0]
        s = (t[k] - table[i, 0]) / h
        B = _basis(s)
        D = _dbasis(s)
        DD = _ddbasis(s)
        for j in range(3):
            pos[k, j] = _combine(table, i, B, h, j)
            vel[k, j] = _combine(table, i, D, h, j) / h
            acc[k, j] = _combine(table, i, DD, h, j) / (h * h)
    return pos, vel, acc

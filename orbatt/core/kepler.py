"""Kepler's equation and the Keplerian orbital frame (compiled kernels, no units).

Orbit parameter vector ``orb`` (float64 array) used by the kernels::

    orb = [a, e, inc, raan, argp, M0, n]

with ``a`` the semi-major axis (length unit of the caller), angles in radians, ``M0`` the
mean anomaly at ``t = 0`` and ``n`` the mean motion (rad per time unit). Frames follow
``DESIGN.md`` §1: the orbital frame ``O`` has ``o1`` radial, ``o3`` along ``r x v``, and the
orbital quaternion ``p`` (3-1-3 Euler parameters of ``(raan, inc, u = argp + f)``) maps ``O``
components to inertial ``S`` components.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

ORB_SIZE = 7
_TWO_PI = 2.0 * math.pi


@nb.njit(cache=True)
def solve_kepler(M, e):
    """Eccentric anomaly ``E`` with ``E - e sin E = M`` for ``0 <= e < 1`` (radians).

    ``M`` is reduced to ``[-pi, pi)``; the result is shifted back by the same multiple of
    ``2 pi``. Danby's starter ``E0 = M + 0.85 e sign(sin M)`` and Halley iterations converge
    for every ``e < 1``; the loop stops when the correction no longer changes ``E``
    (residual at the ulp level).
    """
    k = math.floor((M + math.pi) / _TWO_PI)
    m = M - k * _TWO_PI
    if e == 0.0:
        return M
    s = math.sin(m)
    E = m + 0.85 * e * (1.0 if s >= 0.0 else -1.0)
    for _ in range(64):
        se = e * math.sin(E)
        ce = e * math.cos(E)
        f = E - se - m
        fp = 1.0 - ce
        # Halley: dE = -f / (f' - f f'' / (2 f'))
        d = -f / (fp - 0.5 * f * se / fp)
        E += d
        if abs(d) <= 4e-16 * max(1.0, abs(E)):
            break
    return E + k * _TWO_PI


@nb.njit(cache=True)
def solve_kepler_warm(M, e, work):
    """:func:`solve_kepler` warm-started from the previous call's ``(M, E)`` kept in
    ``work[0], work[1]`` (NaN in ``work[0]`` means no previous call). Integrators call the
    orbit at nearby times, so one or two Halley steps from the linear prediction
    ``E_prev + (M - M_prev) / (1 - e cos E_prev)`` reach the ulp level; a far jump falls
    back to the cold solve."""
    Mp = work[0]
    if Mp == Mp and abs(M - Mp) < 0.3:
        Ep = work[1]
        E = Ep + (M - Mp) / (1.0 - e * math.cos(Ep))
        for _ in range(8):
            se = e * math.sin(E)
            ce = e * math.cos(E)
            f = E - se - M
            fp = 1.0 - ce
            d = -f / (fp - 0.5 * f * se / fp)
            E += d
            if abs(d) <= 4e-16 * max(1.0, abs(E)):
                work[0] = M
                work[1] = E
                return E
    E = solve_kepler(M, e)
    work[0] = M
    work[1] = E
    return E


@nb.njit(cache=True)
def true_anomaly(E, e):
    """True anomaly from the eccentric anomaly (same branch as ``E``)."""
    half = 0.5 * E
    f = 2.0 * math.atan2(math.sqrt(1.0 + e) * math.sin(half), math.sqrt(1.0 - e) * math.cos(half))
    # atan2 returns (-pi, pi]: put f on the same revolution as E (f and E share a half-plane)
    return f + _TWO_PI * round((E - f) / _TWO_PI)


@nb.njit(cache=True)
def kepler_radial(t, orb, work):
    """Radius and radial unit vector in ``S`` at time ``t``.

    Returns ``(r, (x, y, z))``: the orbit radius and ``r_vec / r`` in inertial components.
    ``work`` is the caller's scratch array (see :func:`solve_kepler_warm`).
    """
    a = orb[0]
    e = orb[1]
    inc = orb[2]
    raan = orb[3]
    argp = orb[4]
    M = orb[5] + orb[6] * t
    E = solve_kepler_warm(M, e, work)
    r = a * (1.0 - e * math.cos(E))
    f = true_anomaly(E, e)
    u = argp + f
    cu = math.cos(u)
    su = math.sin(u)
    cO = math.cos(raan)
    sO = math.sin(raan)
    ci = math.cos(inc)
    si = math.sin(inc)
    return r, (cO * cu - sO * su * ci, sO * cu + cO * su * ci, su * si)


@nb.njit(cache=True)
def orbital_quaternion(raan, inc, u):
    """3-1-3 Euler-parameter quaternion ``p`` of ``(raan, inc, u)``: maps ``O`` to ``S``."""
    ci = math.cos(0.5 * inc)
    si = math.sin(0.5 * inc)
    sp = 0.5 * (raan + u)
    sm = 0.5 * (raan - u)
    return (ci * math.cos(sp), si * math.cos(sm), si * math.sin(sm), ci * math.sin(sp))


def orbit_vector(a, e, inc, raan, argp, M0, n):
    """Pack the kernel orbit parameters (floats, caller's units) into ``orb``."""
    return np.array([a, e, inc, raan, argp, M0, n], dtype=np.float64)

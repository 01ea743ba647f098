"""Kepler's equation and the Keplerian orbital frame (compiled kernels, no units).

Orbit parameter vector ``orb`` (float64 array) used by the kernels::

    orb = [a, e, inc, raan, argp, M0, n,            # the elements (ORB_ELEMENTS = 7)
           P1, P2, P3, Q1, Q2, Q3, sqrt(1-e^2), 1-e] # derived (ORB_SIZE = 15)

with ``a`` the semi-major axis (length unit of the caller), angles in radians, ``M0`` the
mean anomaly at ``t = 0`` and ``n`` the mean motion (rad per time unit). ``P`` and ``Q`` are
the perifocal unit vectors (towards periapsis, and 90 degrees ahead in the orbit plane) in
inertial ``S`` components. Build ``orb`` with :func:`orbit_vector`, which fills the derived
entries; a 7-entry vector is still accepted by the kernels (they then recompute ``P, Q``
at every call, which costs six more trigonometric calls).

Frames follow ``docs/design.md`` §1: the orbital frame ``O`` has ``o1`` radial, ``o3`` along
``r x v``, and the orbital quaternion ``p`` (3-1-3 Euler parameters of
``(raan, inc, u = argp + f)``) maps ``O`` components to inertial ``S`` components.

Kepler's equation ``E - e sin E = M`` (``0 <= e < 1``)
-----------------------------------------------------
* ``M`` is reduced to ``m`` in ``[-pi, pi)`` (Cody-Waite three-part ``2 pi``: exact up to
  one rounding of ``m``); ``E`` is solved on that revolution and shifted back by the same
  multiple of ``2 pi``.
* Halley's method from Danby's starter ``E0 = m + 0.85 e sign(sin m)`` (cold), or from the
  previous call's solution (warm, :func:`solve_kepler_warm`). Once a correction is below
  ``1e-2`` rad, ``sin E`` and ``cos E`` are carried by exact angle-addition with Taylor
  polynomials of the correction, so a converged solve costs one ``sin``/``cos`` pair.
* The residual is evaluated without cancellation near periapsis of very eccentric orbits:
  for ``|E| < 1``, ``E - e sin E - m = (1 - e) E + e (E - sin E) - m`` with ``E - sin E``
  from its series, and ``1 - e cos E = (1 - e) + e sin^2 E / (1 + cos E)``. The loop stops
  after a Halley correction ``d`` with ``|d|^3 <= 1e-18 (1 - e) |E|``: Halley's error
  constant is below ``0.3 / (1 - e)``, so the error left is below ``1e-19 |E|``.
* Measured against a long-double reference for ``0 <= e <= 0.999``
  (``tests/test_kepler.py``, ``|M|`` up to 300 rad): residual ``|E - e sin E - M|`` at
  most 1.9 ulp of ``max(|M|, |E|)``; ``E`` itself within 2.5 ulp of the exact root
  (4.9 ulp at ``e = 0.9999``).
* Cost (compiled, warm start, one integrator step apart): ~55 ns per call; cold ~100 ns.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline

ORB_ELEMENTS = 7
ORB_SIZE = 15
_TWO_PI = 2.0 * math.pi
# Cody-Waite three-part 2 pi = C1 + C2 + C3 (C1, C2 with 30 significant bits, so k C1 and
# k C2 are exact for |k| < 2^23): the reduction of M is exact up to one rounding of m
_TWO_PI_C1 = 6.283185303211212
_TWO_PI_C2 = 3.9683743166540886e-09
_TWO_PI_C3 = 2.068073192717642e-18

# reciprocals for the Taylor/series polynomials (multiplications, not divisions)
_R6, _R12, _R20, _R30, _R42, _R56, _R72, _R90 = (1.0 / 6, 1.0 / 12, 1.0 / 20, 1.0 / 30, 1.0 / 42, 1.0 / 56,
                                                 1.0 / 72, 1.0 / 90)
_R110, _R132, _R156, _R210, _R272, _R342 = 1.0 / 110, 1.0 / 132, 1.0 / 156, 1.0 / 210, 1.0 / 272, 1.0 / 342



@jit_inline
def _e_minus_sin(E):
    """``E - sin E`` for ``|E| <= 1`` from its series (no cancellation; 9 terms, rel. 5e-17)."""
    x2 = E * E
    # Horner form of x2/6 (1 - x2/20 (1 - x2/42 (...))); constants are reciprocals
    return (E * x2 * _R6) * (1.0 - x2 * _R20 * (1.0 - x2 * _R42 * (1.0 - x2 * _R72 * (
        1.0 - x2 * _R110 * (1.0 - x2 * _R156 * (1.0 - x2 * _R210 * (1.0 - x2 * _R272 * (
            1.0 - x2 * _R342))))))))


@jit_inline
def _one_minus_cos(s, c):
    """``1 - cos E`` from ``sin E, cos E`` without cancellation."""
    if c > 0.0:
        return s * s / (1.0 + c)
    return 1.0 - c


@jit
def _halley(m, e, E, s, c):
    """Halley iterations on ``E - e sin E = m`` from ``E`` with ``s, c = sin E, cos E``.

    Returns ``(E, sin E, cos E)``."""
    ome = 1.0 - e
    for _ in range(64):
        if abs(E) < 1.0:
            f = ome * E + e * _e_minus_sin(E) - m
        else:
            f = (E - e * s) - m
        fp = ome + e * _one_minus_cos(s, c)  # 1 - e cos E > 0
        d = -f / (fp - 0.5 * f * e * s / fp)
        if d > 1.0:  # guard against a wild step far from the root
            d = 1.0
        elif d < -1.0:
            d = -1.0
        E += d
        ad = abs(d)
        if ad < 1e-2:
            # sin, cos of E + d by angle addition; Taylor errors < d^11/11! ~ 3e-30
            d2 = d * d
            sd = d * (1.0 - d2 * _R6 * (1.0 - d2 * _R20 * (1.0 - d2 * _R42 * (1.0 - d2 * _R72))))
            cd = 1.0 - d2 * 0.5 * (1.0 - d2 * _R12 * (1.0 - d2 * _R30 * (1.0 - d2 * _R56 * (1.0 - d2 * _R90))))
            s, c = s * cd + c * sd, c * cd - s * sd
        else:
            s = math.sin(E)
            c = math.cos(E)
        # Halley's error after this step is K d^3 with K <= 0.3 / (1 - e): stop when that is
        # below 1e-19 |E| (far under one ulp); E = 0 stops only on d = 0
        if ad * ad * ad <= 1e-18 * ome * abs(E):
            break
    return E, s, c


@jit_inline
def _reduce(M):
    """``(m, k)`` with ``M = m + 2 pi k`` and ``m`` in ``[-pi, pi)`` (to rounding; the
    subtraction of ``2 pi k`` is exact up to one rounding of ``m``)."""
    k = math.floor((M + math.pi) / _TWO_PI)
    return ((M - k * _TWO_PI_C1) - k * _TWO_PI_C2) - k * _TWO_PI_C3, k


@jit_inline
def _unreduce(Em, k):
    """``E_m + 2 pi k`` with the three-part ``2 pi``."""
    return k * _TWO_PI_C1 + ((Em + k * _TWO_PI_C3) + k * _TWO_PI_C2)


@jit
def _solve_cold(M, e):
    """``(E_m, sin E, cos E, k)``: ``E_m`` solves Kepler's equation for the reduced
    ``m = M - 2 pi k`` (so ``E = E_m + 2 pi k``)."""
    m, k = _reduce(M)
    if e == 0.0:
        return m, math.sin(m), math.cos(m), k
    # Danby's sign(sin m) from m itself (no sin call): sin m >= 0 on [0, pi] (the double pi lies
    # below pi) and below -pi, where the reduction's rounding may leave m
    E = m + 0.85 * e * (1.0 if (0.0 <= m <= math.pi) or m < -math.pi else -1.0)
    E, s, c = _halley(m, e, E, math.sin(E), math.cos(E))
    return E, s, c, k


@jit
def _solve(M, e, work):
    """Warm-started solve. ``work[0], work[1], work[2]`` hold the previous call's ``M``,
    ``E`` (unreduced) and ``1 / (1 - e cos E)``; NaN in ``work[0]`` means no previous call.

    Returns ``(E_m, sin E, cos E, k)`` as :func:`_solve_cold`. From the linear prediction
    ``E_prev + (M - M_prev) / (1 - e cos E_prev)``, one ``sin``/``cos`` pair and one or two
    Halley corrections (polynomial updates of ``sin``/``cos``) reach the ulp level; a
    predicted jump over 0.5 rad falls back to the cold solve."""
    Mp = work[0]
    done = False
    if Mp == Mp:
        dE = (M - Mp) * work[2]
        if abs(dE) < 0.5:
            m, k = _reduce(M)
            if e == 0.0:
                E, s, c = m, math.sin(m), math.cos(m)
            else:
                E0 = (work[1] - k * _TWO_PI) + dE
                E, s, c = _halley(m, e, E0, math.sin(E0), math.cos(E0))
            done = True
    if not done:
        E, s, c, k = _solve_cold(M, e)
    work[0] = M
    work[1] = _unreduce(E, k)
    work[2] = 1.0 / ((1.0 - e) + e * _one_minus_cos(s, c))
    return E, s, c, k


@jit
def solve_kepler(M, e):
    """Eccentric anomaly ``E`` (rad, unreduced: same revolution as ``M``) with
    ``E - e sin E = M`` for ``0 <= e < 1``. Cold start (see the module docstring)."""
    E, _, _, k = _solve_cold(M, e)
    return _unreduce(E, k)


@jit
def solve_kepler_warm(M, e, work):
    """:func:`solve_kepler` warm-started from the previous call kept in ``work[0:3]``
    (``M``, ``E``, ``1 / (1 - e cos E)``; NaN in ``work[0]`` means no previous call).
    Integrators call the orbit at nearby times; a far jump falls back to the cold solve,
    so the result never depends on the history beyond rounding."""
    E, _, _, k = _solve(M, e, work)
    return _unreduce(E, k)


@jit
def true_anomaly(E, e):
    """True anomaly (rad) from the eccentric anomaly, on the same revolution as ``E``."""
    half = 0.5 * E
    f = 2.0 * math.atan2(math.sqrt(1.0 + e) * math.sin(half), math.sqrt(1.0 - e) * math.cos(half))
    # atan2 returns (-pi, pi]: put f on the same revolution as E (f and E share a half-plane)
    return f + _TWO_PI * round((E - f) / _TWO_PI)


@jit_inline
def _perifocal(orb):
    """``(P, Q, sqrt(1 - e^2), 1 - e)`` from a full ``orb``, or computed from the angles
    for a 7-entry one."""
    if orb.shape[0] >= ORB_SIZE:
        return ((orb[7], orb[8], orb[9]), (orb[10], orb[11], orb[12]), orb[13], orb[14])
    e = orb[1]
    ci = math.cos(orb[2])
    si = math.sin(orb[2])
    cO = math.cos(orb[3])
    sO = math.sin(orb[3])
    cw = math.cos(orb[4])
    sw = math.sin(orb[4])
    P = (cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si)
    Q = (-cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si)
    return P, Q, math.sqrt((1.0 - e) * (1.0 + e)), 1.0 - e


@jit_inline
def _radial(t, orb, work):
    """``(r, xhat, sin E, cos E, P, Q, sqrt(1 - e^2))`` at time ``t`` (Kepler's equation
    warm-started from ``work``); shared by :func:`kepler_radial` and :func:`kepler_state`."""
    a = orb[0]
    e = orb[1]
    P, Q, sq, ome = _perifocal(orb)
    _, s, c, _ = _solve(orb[5] + orb[6] * t, e, work)
    omc = _one_minus_cos(s, c)
    rr = ome + e * omc  # 1 - e cos E
    cf = (ome - omc) / rr  # cos f
    sf = sq * s / rr  # sin f
    return a * rr, (cf * P[0] + sf * Q[0], cf * P[1] + sf * Q[1], cf * P[2] + sf * Q[2]), s, c, P, Q, sq


@jit
def kepler_radial(t, orb, work):
    """Radius and radial unit vector in ``S`` at time ``t``.

    Returns ``(r, (x, y, z))``: the orbit radius (length unit of ``a``) and ``r_vec / r``
    in inertial components. ``work`` is the caller's scratch array (see
    :func:`solve_kepler_warm`). ``cos f = (cos E - e) / (1 - e cos E)`` and
    ``sin f = sqrt(1 - e^2) sin E / (1 - e cos E)`` are formed without cancellation.
    """
    r, xhat, _, _, _, _, _ = _radial(t, orb, work)
    return r, xhat


@jit
def kepler_state(t, orb, work):
    """Radius, radial unit vector and velocity (inertial components) at time ``t``.

    Returns ``(r, xhat, v)``: ``r`` and ``xhat`` exactly as :func:`kepler_radial` (the same
    operations), and ``v = n a^2 / r (-sin E P + sqrt(1 - e^2) cos E Q)`` (length unit of
    ``a`` per time unit; ``n a^2 = sqrt(GM a)``).
    """
    r, xhat, s, c, P, Q, sq = _radial(t, orb, work)
    a = orb[0]
    vfac = orb[6] * a * a
    vs = -vfac * s / r
    vc = vfac * sq * c / r
    return r, xhat, (vs * P[0] + vc * Q[0], vs * P[1] + vc * Q[1], vs * P[2] + vc * Q[2])


@jit_inline
def time_of_anomaly(E, sin_E, orb):
    """The time ``t = (E - e sin E - M0) / n`` of the eccentric anomaly ``E`` (with its
    ``sin E`` given)."""
    return (E - orb[1] * sin_E - orb[5]) / orb[6]


@jit_inline
def anomaly_of_time(t, orb):
    """The eccentric anomaly (rad, unreduced) of the time ``t``: :func:`solve_kepler` of its
    mean anomaly (a cold solve)."""
    return solve_kepler(orb[5] + orb[6] * t, orb[1])


@jit_inline
def kepler_anomaly(E, orb, velocity, work):
    """The orbit at the eccentric anomaly ``E`` (rad, unreduced), in closed form: no Kepler
    solve (the integrators' eccentric-anomaly form, ``orbatt.core.model``'s
    ``ORBIT_KEPLER_ANOMALY``).

    Returns ``(t, dt/dE, r, xhat, v)``: the time ``t = (E - e sin E - M0) / n``, its rate
    ``dt/dE = (1 - e cos E) / n = r / (n a)``, the radius and radial unit vector as
    :func:`kepler_radial` (the same operations from ``sin E, cos E``), and the velocity of
    :func:`kepler_state` when ``velocity`` (else zero). ``orb`` must be the full vector of
    :func:`orbit_vector`.

    ``sin E`` and ``cos E`` come from a base kept in ``work[0:3]`` (``E_b``, ``sin E_b``,
    ``cos E_b``; NaN: none), the slots of Kepler's warm start, unused in this form: within
    0.125 rad of it by angle addition with the Taylor polynomials of ``d = E - E_b`` (errors
    below ``d^11 / 11! ~ 3e-18``; measured at most 1 ulp of 1 against 0.5 for libm's ``sin``
    and ``cos``), else by libm, which sets a new base. The stages of a step lie within a step
    of its start, so most evaluations take no ``sin``/``cos`` call: 98 -> 86-91 ns per
    right-hand side on the paper's Keplerian case. The numbers depend on the base, that is
    on the sequence of calls, which is the same for a member alone and in an ensemble.
    """
    a = orb[0]
    e = orb[1]
    n = orb[6]
    sq = orb[13]
    ome = orb[14]
    d = E - work[0]
    if abs(d) <= 0.125:
        d2 = d * d
        sd = d * (1.0 - d2 * _R6 * (1.0 - d2 * _R20 * (1.0 - d2 * _R42 * (1.0 - d2 * _R72 * (1.0 - d2 * _R110)))))
        cd = 1.0 - d2 * 0.5 * (1.0 - d2 * _R12 * (1.0 - d2 * _R30 * (1.0 - d2 * _R56 * (1.0 - d2 * _R90 * (
            1.0 - d2 * _R132)))))
        sb = work[1]
        cb = work[2]
        s = sb * cd + cb * sd
        c = cb * cd - sb * sd
    else:
        s = math.sin(E)
        c = math.cos(E)
        work[0] = E
        work[1] = s
        work[2] = c
    omc = _one_minus_cos(s, c)
    rr = ome + e * omc  # 1 - e cos E
    cf = (ome - omc) / rr  # cos f
    sf = sq * s / rr  # sin f
    r = a * rr
    xhat = (cf * orb[7] + sf * orb[10], cf * orb[8] + sf * orb[11], cf * orb[9] + sf * orb[12])
    v = (0.0, 0.0, 0.0)
    if velocity:
        vfac = n * a * a
        vs = -vfac * s / r
        vc = vfac * sq * c / r
        v = (vs * orb[7] + vc * orb[10], vs * orb[8] + vc * orb[11], vs * orb[9] + vc * orb[12])
    return time_of_anomaly(E, s, orb), rr / n, r, xhat, v


@jit
def anomalies_at(t, orb):
    """The eccentric anomalies ``E (N,)`` (rad, unreduced: continuous in time) of the times
    ``t (N,)``, each by a cold solve (so each is independent of the others), and whether
    they strictly increase."""
    out = np.empty(t.shape[0])
    increasing = True
    for i in range(t.shape[0]):
        out[i] = anomaly_of_time(t[i], orb)
        if i > 0 and not out[i] > out[i - 1]:
            increasing = False
    return out, increasing


@jit
def times_at(E, orb):
    """The times ``t (N,)`` of the eccentric anomalies ``E (N,)`` (:func:`kepler_anomaly`'s
    ``t``)."""
    out = np.empty(E.shape[0])
    for i in range(E.shape[0]):
        out[i] = time_of_anomaly(E[i], math.sin(E[i]), orb)
    return out


@jit
def kepler_many(t, orb, gm):
    """The Keplerian orbit at the times ``t`` (array, any order; warm-started in sequence).

    Returns ``(E, f, r, pos, vel)``: eccentric and true anomalies (rad, continuous in time:
    on the revolution of the mean anomaly), radius, position ``(N, 3)`` and velocity
    ``(N, 3)`` in inertial ``S`` components (length unit of ``a``; ``gm`` in
    length^3 / time^2).
    """
    n = t.shape[0]
    Eo = np.empty(n)
    fo = np.empty(n)
    ro = np.empty(n)
    pos = np.empty((n, 3))
    vel = np.empty((n, 3))
    a = orb[0]
    e = orb[1]
    P, Q, sq, ome = _perifocal(orb)
    vfac = math.sqrt(gm * a)
    work = np.full(3, np.nan)
    for i in range(n):
        E, s, c, k = _solve(orb[5] + orb[6] * t[i], e, work)
        omc = _one_minus_cos(s, c)
        rr = ome + e * omc
        cf = (ome - omc) / rr
        sf = sq * s / rr
        f = math.atan2(sf, cf)
        f += _TWO_PI * round((E - f) / _TWO_PI)
        Eo[i] = _unreduce(E, k)
        fo[i] = _unreduce(f, k)
        r = a * rr
        ro[i] = r
        # v = sqrt(GM a) / r (-sin E P + sqrt(1 - e^2) cos E Q)
        vs = -vfac * s / r
        vc = vfac * sq * c / r
        for j in range(3):
            pos[i, j] = r * (cf * P[j] + sf * Q[j])
            vel[i, j] = vs * P[j] + vc * Q[j]
    return Eo, fo, ro, pos, vel


@jit
def orbital_quaternion(raan, inc, u):
    """3-1-3 Euler-parameter quaternion ``p`` of ``(raan, inc, u)``: maps ``O`` to ``S``."""
    ci = math.cos(0.5 * inc)
    si = math.sin(0.5 * inc)
    sp = 0.5 * (raan + u)
    sm = 0.5 * (raan - u)
    return (ci * math.cos(sp), si * math.cos(sm), si * math.sin(sm), ci * math.sin(sp))


def orbit_vector(a, e, inc, raan, argp, M0, n):
    """Pack the kernel orbit parameters (floats, caller's units) into ``orb`` (length
    :data:`ORB_SIZE`, derived entries filled; see the module docstring)."""
    ci, si = math.cos(inc), math.sin(inc)
    cO, sO = math.cos(raan), math.sin(raan)
    cw, sw = math.cos(argp), math.sin(argp)
    P = (cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si)
    Q = (-cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si)
    return np.array([a, e, inc, raan, argp, M0, n, *P, *Q, math.sqrt((1.0 - e) * (1.0 + e)), 1.0 - e],
                    dtype=np.float64)

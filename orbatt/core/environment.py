"""Environment kernels on plain floats: exponential densities, the shadow function and the
piece tables of the fields sampled along the orbit (``docs/design.md`` §10).

Units: km for lengths, s for times, kg/m^3 for densities (the table's units for anything
else). Vectors are 3-sequences of floats (tuples or 1-D arrays). The API counterparts, which
build the parameter arrays and tables, are in :mod:`orbatt.environment`.

Parameter layouts
-----------------
* exponential density: ``params = [rho0 (kg/m^3), h0 (km), H (km), R (km)]``,
  ``rho = rho0 exp(-(|r| - R - h0) / H)``.
* piecewise exponential: ``table = [R, h0_0, rho0_0, H_0, h0_1, rho0_1, H_1, ...]`` (km,
  kg/m^3, km), layers by increasing base altitude ``h0_k``; layer ``k`` serves
  ``h0_k <= h < h0_{k+1}`` (the first layer also below ``h0_0``, the last above).
* piece table (the environment fields along the orbit, :func:`piece_eval`):
  ``table[i] = [t_i, w_i, d, a_0 .. a_d (component 0), a_0 .. a_d (component 1), ...]``,
  shape ``(N, PIECE_HEADER + ncomp (d + 1))``; on ``[t_i, t_{i+1}]`` component ``k`` is the
  polynomial ``sum_j a_j x^j`` of degree ``d`` in ``x = (t - t_i) w_i - 1``,
  ``w_i = 2 / (t_{i+1} - t_i)`` (``x`` runs over ``[-1, 1]``). The last row holds ``t_{N-1}``
  and the end values in ``a_0`` (other coefficients 0); it is never an interval.
  :func:`orbatt.environment.tables.piece_table` builds them (Chebyshev interpolation).
* spline table (:func:`not_a_knot_table`, the Earth-orientation nodes of
  :mod:`orbatt.environment.frames`): ``table[i] = [t_i, c0, c1, c2, c3 (component 0), ...]``,
  on ``[t_i, t_{i+1}]`` component ``k`` is ``c0 + c1 s + c2 s^2 + c3 s^3``, ``s = t - t_i``.

Interval search (:func:`find_row`) keeps the last row used in ``work[slot]`` (NaN: none),
as :func:`orbatt.core.sampled.find_interval` does, so consecutive nearby times cost O(1).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline


# ---- densities ---------------------------------------------------------------------------
@jit_inline
def exponential_density(r_km, params):
    """Density (kg/m^3) of an exponential atmosphere at position ``r_km`` (km, any frame
    centred on the body): ``rho0 exp(-(h - h0) / H)``, ``h = |r| - R``;
    ``params = [rho0, h0, H, R]``."""
    h = math.sqrt(r_km[0] * r_km[0] + r_km[1] * r_km[1] + r_km[2] * r_km[2]) - params[3]
    return params[0] * math.exp(-(h - params[1]) / params[2])


@jit_inline
def piecewise_density(r_km, table):
    """Density (kg/m^3) of a piecewise exponential atmosphere at ``r_km`` (km);
    ``table = [R, h0_0, rho0_0, H_0, ...]`` (layers by increasing ``h0``)."""
    h = math.sqrt(r_km[0] * r_km[0] + r_km[1] * r_km[1] + r_km[2] * r_km[2]) - table[0]
    n = (table.shape[0] - 1) // 3
    lo = 0
    hi = n
    while hi - lo > 1:          # largest k with h0_k <= h (0 below the first layer)
        mid = (lo + hi) // 2
        if table[1 + 3 * mid] <= h:
            lo = mid
        else:
            hi = mid
    b = 1 + 3 * lo
    return table[b + 1] * math.exp(-(h - table[b]) / table[b + 2])


# ---- shadow function ------------------------------------------------------------------------
@jit_inline
def shadow_conical(r_sat, r_sun, R_body, R_sun):
    """Fraction of the Sun's disc seen from ``r_sat`` (0 umbra ... 1 full Sun), conical
    model with the apparent-disc overlap (Montenbruck & Gill 2000, §3.4.2).

    ``r_sat``, ``r_sun``: positions relative to the occulting body's centre (km);
    ``R_body``, ``R_sun``: radii (km)."""
    dx = r_sun[0] - r_sat[0]
    dy = r_sun[1] - r_sat[1]
    dz = r_sun[2] - r_sat[2]
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    rs = math.sqrt(r_sat[0] * r_sat[0] + r_sat[1] * r_sat[1] + r_sat[2] * r_sat[2])
    dot = -(r_sat[0] * dx + r_sat[1] * dy + r_sat[2] * dz)
    if dot <= 0.0 and R_body < 0.99 * rs and R_sun < 0.1 * d:
        # the Sun at 90 deg or more from the body's centre (c >= pi/2) while the two apparent
        # radii add up to less than asin(0.99) + asin(0.1) < pi/2: fully lit, the answer of the
        # full test below, without its asin and atan2 (the sunlit half of a low orbit)
        return 1.0
    a, b, c = conical_geometry(r_sat, r_sun, R_body, R_sun)
    if c >= a + b:
        return 1.0
    if c <= b - a:
        return 0.0
    if c <= a - b:              # the body's disc inside the Sun's (annular)
        return 1.0 - (b * b) / (a * a)
    # overlap of the discs = two circular segments, r^2 (phi - sin phi) / 2 with phi twice the
    # half-angle of the common chord (half-length y) seen from each centre; y from the four
    # side differences (no cancellation), phi - sin phi by its series for small phi
    y = 0.5 * math.sqrt(max((a + b - c) * (b + c - a) * (c + a - b) * (a + b + c), 0.0)) / c
    ta = 2.0 * math.atan2(y, (c * c + a * a - b * b) / (2.0 * c))
    tb = 2.0 * math.atan2(y, (c * c + b * b - a * a) / (2.0 * c))
    area = 0.5 * (a * a * phi_minus_sin(ta) + b * b * phi_minus_sin(tb))
    return 1.0 - area / (math.pi * a * a)


@jit_inline
def conical_geometry(r_sat, r_sun, R_body, R_sun):
    """``(a, b, c)`` (rad) of the conical shadow model seen from ``r_sat``: the apparent radii
    of the Sun and of the occulting body and the apparent separation of their centres (the
    shadow's edges: penumbra ``c = a + b``, umbra ``c = b - a``, annular ``c = a - b``).
    Arguments as :func:`shadow_conical`."""
    dx = r_sun[0] - r_sat[0]
    dy = r_sun[1] - r_sat[1]
    dz = r_sun[2] - r_sat[2]
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    rs = math.sqrt(r_sat[0] * r_sat[0] + r_sat[1] * r_sat[1] + r_sat[2] * r_sat[2])
    a = math.asin(min(R_sun / d, 1.0))      # apparent radius of the Sun
    b = math.asin(min(R_body / rs, 1.0))    # apparent radius of the body
    # apparent separation of the centres: angle between -r_sat and r_sun - r_sat
    cx = -(r_sat[1] * dz - r_sat[2] * dy)
    cy = -(r_sat[2] * dx - r_sat[0] * dz)
    cz = -(r_sat[0] * dy - r_sat[1] * dx)
    dot = -(r_sat[0] * dx + r_sat[1] * dy + r_sat[2] * dz)
    c = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), dot)
    return a, b, c


@jit_inline
def phi_minus_sin(phi):
    """``phi - sin(phi)`` without cancellation for small ``phi`` (Taylor series below 0.25,
    relative error < 1e-15)."""
    if phi >= 0.25:
        return phi - math.sin(phi)
    p2 = phi * phi
    return phi * p2 * (1.0 / 6.0 - p2 * (1.0 / 120.0 - p2 * (1.0 / 5040.0 - p2 * (1.0 / 362880.0
                                                                                 - p2 / 39916800.0))))


@jit_inline
def shadow_cylindrical(r_sat, r_sun, R_body, R_sun):
    """Cylindrical shadow: 0 behind the body inside the cylinder of radius ``R_body`` along
    the Sun direction, else 1 (``R_sun`` unused; the same signature as
    :func:`shadow_conical`)."""
    along, perp2 = cylindrical_geometry(r_sat, r_sun)
    if along >= 0.0:
        return 1.0
    if perp2 < R_body * R_body:
        return 0.0
    return 1.0


@jit_inline
def cylindrical_geometry(r_sat, r_sun):
    """``(along, perp2)`` of the cylindrical shadow model: the position's component along the
    Sun direction and the square of its distance from the shadow's axis (the shadow's edge:
    ``along < 0`` and ``perp2 = R_body^2``). Arguments as :func:`shadow_cylindrical`."""
    n = math.sqrt(r_sun[0] * r_sun[0] + r_sun[1] * r_sun[1] + r_sun[2] * r_sun[2])
    along = (r_sat[0] * r_sun[0] + r_sat[1] * r_sun[1] + r_sat[2] * r_sun[2]) / n
    r2 = r_sat[0] * r_sat[0] + r_sat[1] * r_sat[1] + r_sat[2] * r_sat[2]
    return along, r2 - along * along


# ---- sampled tables ------------------------------------------------------------------------
@jit_inline
def bisect_row(table, t):
    """The index ``i`` with ``table[i, 0] <= t < table[i + 1, 0]`` by bisection over the first
    column (increasing times), for ``table[0, 0] <= t < table[-1, 0]``; ``t == table[-1, 0]``
    gives the last interval."""
    lo = 0
    hi = table.shape[0] - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if table[mid, 0] <= t:
            lo = mid
        else:
            hi = mid
    return lo


@jit_inline
def find_row(table, t, work, slot):
    """Index ``i`` with ``table[i, 0] <= t <= table[i + 1, 0]`` (the first column holds
    increasing times), warm-started from ``work[slot]`` and stored there. Raises
    ``ValueError`` for ``t`` outside ``[table[0, 0], table[-1, 0]]``."""
    n = table.shape[0]
    if not (t >= table[0, 0] and t <= table[n - 1, 0]):
        raise ValueError("environment table: time outside the sampled span; sample the "
                         "environment over the whole integration span")
    w = work[slot]
    if w == w:
        i = int(w)
        if 0 <= i < n - 1:
            if table[i, 0] <= t:
                if t <= table[i + 1, 0]:
                    return i
                if i + 2 < n and t <= table[i + 2, 0]:
                    work[slot] = i + 1
                    return i + 1
            elif i >= 1 and table[i - 1, 0] <= t:
                work[slot] = i - 1
                return i - 1
    lo = bisect_row(table, t)
    work[slot] = lo
    return lo


#: columns of a piece-table row before its coefficients: ``[t_i, 2 / (t_{i+1} - t_i), degree]``
PIECE_HEADER = 3


@jit_inline
def piece_eval(table, t, ncomp, slot, work):
    """Values at ``t`` of the first ``ncomp`` (1..4) components of a piece table: a tuple of 4
    floats, the unused ones 0. Each component is the polynomial ``sum a_k x^k`` (Horner) in
    ``x = (t - t_i) 2 / (t_{i+1} - t_i) - 1`` of the row's interval. ``work[slot]`` keeps the
    interval (:func:`find_row`)."""
    i = find_row(table, t, work, slot)
    x = (t - table[i, 0]) * table[i, 1] - 1.0
    d = int(table[i, 2])
    b0 = PIECE_HEADER
    b1 = b0 + d + 1
    b2 = b1 + d + 1
    b3 = b2 + d + 1
    v0 = table[i, b0 + d]
    v1 = table[i, b1 + d] if ncomp > 1 else 0.0
    v2 = table[i, b2 + d] if ncomp > 2 else 0.0
    v3 = table[i, b3 + d] if ncomp > 3 else 0.0
    for k in range(d - 1, -1, -1):
        v0 = v0 * x + table[i, b0 + k]
        if ncomp > 1:
            v1 = v1 * x + table[i, b1 + k]
        if ncomp > 2:
            v2 = v2 * x + table[i, b2 + k]
        if ncomp > 3:
            v3 = v3 * x + table[i, b3 + k]
    return v0, v1, v2, v3


@jit_inline
def piece_eval_rate(table, t, slot, work):
    """``(value, rate)``: the first three components of a piece table at ``t`` and their time
    derivatives (3-tuples; each polynomial's derivative, continuous across the knots to the
    table's interpolation error). ``work[slot]`` keeps the interval (:func:`find_row`)."""
    i = find_row(table, t, work, slot)
    w = table[i, 1]
    x = (t - table[i, 0]) * w - 1.0
    d = int(table[i, 2])
    b0 = PIECE_HEADER
    b1 = b0 + d + 1
    b2 = b1 + d + 1
    v0 = table[i, b0 + d]
    v1 = table[i, b1 + d]
    v2 = table[i, b2 + d]
    d0 = 0.0
    d1 = 0.0
    d2 = 0.0
    for k in range(d - 1, -1, -1):
        d0 = d0 * x + v0
        d1 = d1 * x + v1
        d2 = d2 * x + v2
        v0 = v0 * x + table[i, b0 + k]
        v1 = v1 * x + table[i, b1 + k]
        v2 = v2 * x + table[i, b2 + k]
    return (v0, v1, v2), (w * d0, w * d1, w * d2)


@jit
def piece_eval_many(table, t, ncomp):
    """:func:`piece_eval` at each time of ``t`` (for outputs and tests): ``(len(t), ncomp)``."""
    work = np.full(1, np.nan)
    out = np.empty((t.shape[0], ncomp))
    for j in range(t.shape[0]):
        v = piece_eval(table, t[j], ncomp, 0, work)
        for k in range(ncomp):
            out[j, k] = v[k]
    return out


@jit
def not_a_knot_table(t, v):
    """The spline table (layout above) of the not-a-knot cubic spline through ``v`` at ``t``.

    The first derivatives ``s_i`` at the knots solve the tridiagonal system of scipy's
    ``CubicSpline(t, v, bc_type="not-a-knot")`` (the same rows, the same right-hand sides),
    eliminated without pivoting; each interval is then the cubic Hermite polynomial of its end
    values and slopes, with scipy's formulas. On even steps (the environment tables) the banded
    LU that scipy calls pivots on no row and the table is scipy's bit for bit; on uneven steps
    the values and slopes agree to round-off (``tests/environment/test_environment_tables.py``).

    Parameters
    ----------
    t : ndarray (N,)
        Strictly increasing times, ``N >= 4`` (checked by the caller).
    v : ndarray (N, ncomp)
        Samples, ``ncomp <= 4``.

    Returns
    -------
    ndarray (N, 1 + 4 ncomp)
    """
    n = t.shape[0]
    ncomp = v.shape[1]
    table = np.zeros((n, 1 + 4 * ncomp))
    dx = np.empty(n - 1)
    for i in range(n - 1):
        dx[i] = t[i + 1] - t[i]
    lower = np.empty(n)         # row i: lower[i] s[i-1] + diag[i] s[i] + upper[i] s[i+1] = b[i]
    diag = np.empty(n)
    upper = np.empty(n)
    d0 = t[2] - t[0]
    d1 = t[n - 1] - t[n - 3]
    lower[0] = 0.0
    diag[0] = dx[1]
    upper[0] = d0
    for i in range(1, n - 1):
        lower[i] = dx[i]
        diag[i] = 2.0 * (dx[i - 1] + dx[i])
        upper[i] = dx[i - 1]
    lower[n - 1] = d1
    diag[n - 1] = dx[n - 3]
    upper[n - 1] = 0.0
    for i in range(1, n):       # forward elimination, shared by every component
        f = lower[i] / diag[i - 1]
        lower[i] = f
        diag[i] = diag[i] - f * upper[i - 1]
    slope = np.empty(n - 1)
    b = np.empty(n)
    for k in range(ncomp):
        for i in range(n - 1):
            slope[i] = (v[i + 1, k] - v[i, k]) / dx[i]
        b[0] = ((dx[0] + 2.0 * d0) * dx[1] * slope[0] + dx[0] * dx[0] * slope[1]) / d0
        for i in range(1, n - 1):
            b[i] = 3.0 * (dx[i] * slope[i - 1] + dx[i - 1] * slope[i])
        b[n - 1] = (dx[n - 2] * dx[n - 2] * slope[n - 3] + (2.0 * d1 + dx[n - 2]) * dx[n - 3] * slope[n - 2]) / d1
        for i in range(1, n):
            b[i] = b[i] - lower[i] * b[i - 1]
        b[n - 1] = b[n - 1] / diag[n - 1]
        for i in range(n - 2, -1, -1):      # back substitution: b holds the slopes s
            b[i] = (b[i] - upper[i] * b[i + 1]) / diag[i]
        c = 1 + 4 * k
        for i in range(n - 1):
            w = (b[i] + b[i + 1] - 2.0 * slope[i]) / dx[i]
            table[i, c] = v[i, k]
            table[i, c + 1] = b[i]
            table[i, c + 2] = (slope[i] - b[i]) / dx[i] - w
            table[i, c + 3] = w / dx[i]
        table[n - 1, c] = v[n - 1, k]
    for i in range(n):
        table[i, 0] = t[i]
    return table

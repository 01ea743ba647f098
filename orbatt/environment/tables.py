"""Environment tables: fields sampled along the prescribed orbit and interpolated for the kernel.

The orbit is prescribed, so density, magnetic field and Sun position depend on time alone
along it (``docs/design.md`` §10). They are evaluated by their libraries at the Chebyshev
(Lobatto) nodes of equal pieces of the run (:func:`piece_times`, :func:`sample_pieces`) and
turned into one polynomial per piece (:func:`piece_table`: Chebyshev interpolation, stored as
monomials in the piece's ``x`` in ``[-1, 1]``) that
:func:`orbatt.core.environment.piece_eval` evaluates in the compiled right-hand side. Adjacent
pieces share their end node, so the table is continuous; its derivatives jump at the knots
by the interpolation error, and the step loops land on the knots
(:func:`orbatt.core.model.next_breakpoint`). Long pieces of high degree keep the knots rare
(a few per orbit; the cubic splines of 20-30 s before them put a knot, hence a step, every
20-30 s: issue 23) at a better accuracy than those splines.
Along a sampled orbit (TLE, REBOUND: quintic Hermite pieces between its samples, C2 across)
the field is smooth only between the samples, so they are knots of the tables too (the step
loops land on them anyway): IGRF along the TLE orbit of ``tests/test_tle_torques.py`` is then
1.9e-14 off the library, against 5.7e-8 with 600 s pieces across the samples.

Default pieces (:class:`Pieces`: the longest piece, the degree) and the interpolation error
they give: the largest difference between the table and the library at 39 points inside
every piece, relative to the largest magnitude along the orbit, over two orbits of a 400 km,
51.6 deg orbit from 2024-03-20 (the Sun over one day); ``tests/environment/test_environment_tables.py``
measures and bounds it. The cubic splines before them (20-30 s), on the same points: IGRF 1.1e-7,
NRLMSIS 1.8e-5, piecewise exponential 1.9e-5; Sun 4.4e-14.

* magnetic field, :data:`MAGNETIC_FIELD_PIECES` = 600 s, degree 12: IGRF 1.1e-9, dipole
  1.1e-14 (694 s pieces: degree 10 2.8e-7, 12 9.8e-9, 14 3e-10, 16 7e-12).
* Sun position, :data:`SUN_PIECES` = 21600 s, degree 5: 4.1e-14 in direction.
* NRLMSIS density, :data:`DENSITY_PIECES` = 600 s, degree 12: 1.7e-5 (degree 10: 2.1e-5, 8:
  2.0e-5), the noise of the model itself: NRLMSIS 2.1 as pymsis runs it is single precision
  (float32 densities; its inputs are float32 and the time of day is truncated to whole
  seconds), and the third differences of ``log rho`` along a smooth path are ~1e-5 whatever
  the spacing.
* a layered (piecewise exponential) density jumps at its layers' bases: a long polynomial
  would ring across the whole piece, so it keeps short cubic pieces,
  :data:`LAYERED_DENSITY_PIECES` = 30 s, degree 3: 1.3e-5 (the jump smeared over one piece,
  as the 30 s spline did).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from astropy import units as u

from .. import units as U
from ..errors import InputError

__all__ = ["OrbitSamples", "Pieces", "sample_along_orbit", "sample_pieces", "piece_times", "piece_table",
           "tabulate", "tabulate_along_orbit", "BREAK_LEAD", "MAGNETIC_FIELD_PIECES", "SUN_PIECES", "DENSITY_PIECES", "LAYERED_DENSITY_PIECES",
           "TABLE_MARGIN"]


class Pieces(NamedTuple):
    """How a field is tabulated: equal pieces of at most ``length`` (s), each a polynomial of
    ``degree`` through the field at its ``degree + 1`` Chebyshev-Lobatto nodes."""

    length: float
    degree: int


#: the magnetic-field table (relative error 1.1e-9 for IGRF at 400 km; the 20 s splines: 1.1e-7)
MAGNETIC_FIELD_PIECES = Pieces(600.0, 12)
#: the Sun-position table (relative error 4e-14)
SUN_PIECES = Pieces(21600.0, 5)
#: the NRLMSIS density table (relative error 1.7e-5, NRLMSIS's own single-precision noise)
DENSITY_PIECES = Pieces(600.0, 12)
#: a layered density's table (piecewise exponential: jumps at the layers' bases)
LAYERED_DENSITY_PIECES = Pieces(30.0, 3)
#: how long (s) before and after a break (:func:`tabulate_along_orbit`) the pieces ending and
#: starting there sample their end values
BREAK_LEAD = 1e-3
#: the tables reach this far (s) beyond each end of the run (a stage at the run's end,
#: rounded past it, stays inside)
TABLE_MARGIN = 60.0


class OrbitSamples(NamedTuple):
    """Samples of an orbit: ``t`` (s since the orbit's epoch, ``(N,)``), ``time`` (the same
    instants as an astropy ``Time``, None for an orbit without an epoch), ``position`` (km) and ``velocity`` (km/s) in the
    inertial frame ``S`` = GCRS, each ``(N, 3)``."""

    t: np.ndarray
    time: object
    position: np.ndarray
    velocity: np.ndarray


def _seconds(value, name):
    out = U.strip(value, U.TIME, name, allow_plain=True)
    if out.shape != ():
        raise InputError(f"{name}: expected one time, got {value!r}")
    return float(out)


def _checked_span(orbit, t0, t1):
    t0, t1 = _seconds(t0, "t0"), _seconds(t1, "t1")
    if not t1 > t0:
        raise InputError(f"t1: {t1} s must be after t0 = {t0} s")
    span = orbit.time_span
    if span is not None and (t0 < span[0] or t1 > span[1]):
        raise InputError(f"t0, t1: [{t0}, {t1}] s is outside the orbit's sampled span [{span[0]}, {span[1]}] s; "
                         "build the orbit over the whole run")
    return t0, t1


def _samples_at(orbit, t):
    pos, vel = orbit.state(t)
    return OrbitSamples(t, None if orbit.epoch is None else orbit.epoch + t * u.s, np.asarray(pos, dtype=np.float64),
                        np.asarray(vel, dtype=np.float64))


def sample_along_orbit(orbit, t0, t1, step):
    """Evenly spaced samples of ``orbit`` on ``[t0, t1]``, both ends included.

    Parameters
    ----------
    orbit : orbatt.orbits.OrbitProvider
        The orbit (its inertial frame is GCRS when it has an epoch). Without an epoch the
        samples carry no dates (``time`` None): only the models that need none (the
        exponential atmospheres: altitude over the sphere) can be evaluated on them.
    t0, t1 : float (s since the orbit's epoch) or time Quantity
        The span, ``t0 < t1``; inside ``orbit.time_span`` for a sampled orbit.
    step : float (s) or time Quantity
        Largest spacing; the span is cut into ``ceil((t1 - t0) / step)`` equal intervals.

    Returns
    -------
    OrbitSamples
    """
    t0, t1 = _checked_span(orbit, t0, t1)
    step = _seconds(step, "step")
    if not step > 0.0:
        raise InputError(f"step: {step} s must be positive")
    n = max(int(math.ceil((t1 - t0) / step - 1e-9)), 1)
    return _samples_at(orbit, np.linspace(t0, t1, n + 1))


def piece_times(t0, t1, pieces, knots=()):
    """The sampling times of a piece table on ``[t0, t1]``.

    Parameters
    ----------
    t0, t1 : float
        The span (s), ``t0 < t1``.
    pieces : Pieces
        Each gap between ``t0``, the ``knots`` and ``t1`` is cut into
        ``ceil(gap / length)`` equal pieces, ``degree + 1`` nodes each.
    knots : sequence of float
        Times (s) that must be knots of the table (a sampled orbit's samples: the orbit
        itself is a polynomial between them, C2 across); those outside ``(t0, t1)`` are
        ignored.

    Returns
    -------
    ndarray (n degree + 1,)
        The Chebyshev-Lobatto nodes ``t_i + (1 - cos(pi j / degree)) h_i / 2`` of every piece,
        increasing; piece ``i`` owns ``t[i degree : (i + 1) degree + 1]`` (adjacent pieces
        share their end node, the knot).
    """
    length, degree = float(pieces.length), int(pieces.degree)
    if not (t1 > t0 and length > 0.0 and degree >= 1):
        raise InputError(f"pieces: need t1 > t0, a positive length and a degree >= 1, got t0 = {t0}, t1 = {t1}, "
                         f"{pieces}")
    cuts = np.unique(np.concatenate([[t0], np.asarray(knots, dtype=np.float64).ravel(), [t1]]))
    cuts = cuts[(cuts >= t0) & (cuts <= t1)]
    parts = [np.linspace(a, b, max(int(math.ceil((b - a) / length - 1e-9)), 1) + 1)[:-1]
             for a, b in zip(cuts[:-1], cuts[1:])]
    edges = np.concatenate([*parts, [t1]])
    x = 0.5 * (1.0 - np.cos(np.pi * np.arange(degree) / degree))  # in [0, 1), the end node belongs to the next
    t = edges[:-1, None] + x[None, :] * np.diff(edges)[:, None]
    return np.concatenate([t.ravel(), edges[-1:]])


def sample_pieces(orbit, t0, t1, pieces):
    """Samples of ``orbit`` at the :func:`piece_times` of ``[t0, t1]``.

    Parameters
    ----------
    orbit : orbatt.orbits.OrbitProvider
        As for :func:`sample_along_orbit`.
    t0, t1 : float (s since the orbit's epoch) or time Quantity
        The span, ``t0 < t1``; inside ``orbit.time_span`` for a sampled orbit.
    pieces : Pieces
        The pieces and their degree.

    Returns
    -------
    OrbitSamples
    """
    t0, t1 = _checked_span(orbit, t0, t1)
    return _samples_at(orbit, piece_times(t0, t1, pieces))


def tabulate_along_orbit(orbit, t0, t1, pieces, evaluate, breaks=(), knots=()):
    """The piece table of a field along ``orbit`` on ``[t0, t1]``, with knots at ``breaks``.

    Parameters
    ----------
    orbit : orbatt.orbits.OrbitProvider
        As for :func:`sample_along_orbit`.
    t0, t1 : float
        The span (s since the orbit's epoch), ``t0 < t1``; inside ``orbit.time_span``.
    pieces : Pieces
        The pieces and their degree.
    evaluate : callable
        As for :func:`tabulate`.
    breaks : sequence of float
        Times (s) where the field jumps (NRLMSIS at each UTC midnight: its day of the year is
        an integer input). The span is cut there and each part into its own pieces; the pieces
        ending and starting at a break are sampled there :data:`BREAK_LEAD` before and after it
        (the field's values either side of the jump, whatever the rounding of the time), so no
        piece straddles the jump (a polynomial through one would ring across the piece).
        Breaks outside ``(t0, t1)`` are ignored.
    knots : sequence of float
        Times (s) where the field is continuous but the orbit's interpolant is not smooth (a
        sampled orbit's samples): knots of the table too (:func:`piece_times`).

    Returns
    -------
    ndarray
        The :func:`piece_table` of the whole span (the parts' rows, in order).
    """
    t0, t1 = _checked_span(orbit, t0, t1)
    edges = [t0, *sorted(float(b) for b in breaks if t0 < b < t1), t1]
    parts = []
    for k in range(len(edges) - 1):
        t = piece_times(edges[k], edges[k + 1], pieces, knots)
        at = t.copy()
        lead = min(BREAK_LEAD, 0.01 * (edges[k + 1] - edges[k]))
        if k > 0:
            at[0] = edges[k] + lead
        if k < len(edges) - 2:
            at[-1] = edges[k + 1] - lead
        s = _samples_at(orbit, at)
        parts.append(piece_table(t, evaluate(s.time, s.position), pieces.degree))
    return np.concatenate([p[:-1] for p in parts[:-1]] + [parts[-1]])


def _chebyshev_to_monomial(degree):
    """``P (degree + 1, degree + 1)``: the monomial coefficients of ``T_k`` in column ``k``
    (integers, exact)."""
    P = np.zeros((degree + 1, degree + 1))
    P[0, 0] = 1.0
    if degree >= 1:
        P[1, 1] = 1.0
    for k in range(2, degree + 1):   # T_k = 2 x T_{k-1} - T_{k-2}
        P[1:, k] = 2.0 * P[:-1, k - 1]
        P[:, k] -= P[:, k - 2]
    return P


def piece_table(t, values, degree):
    """The piece table (layout of :mod:`orbatt.core.environment`) interpolating ``values``.

    Each piece's polynomial is the Chebyshev interpolant through its ``degree + 1`` nodes:
    the Chebyshev coefficients by the discrete cosine sums at the Lobatto nodes, then the
    monomial coefficients in ``x`` (exact integer combinations). Plain elementwise arithmetic,
    in a fixed order (no BLAS): the same samples give the same table, bit for bit.

    Parameters
    ----------
    t : array_like (n degree + 1,)
        The :func:`piece_times` of the table.
    values : array_like (N,) or (N, ncomp)
        The field at ``t``, ``ncomp <= 4`` components.
    degree : int
        The pieces' degree (that of :func:`piece_times`).

    Returns
    -------
    ndarray (n + 1, PIECE_HEADER + ncomp (degree + 1))
        Row ``i``: ``[t_i, 2 / (t_{i+1} - t_i), degree, a_0 .. a_degree (component 0), ...]``;
        the last row ``[t_n, 0, degree, end values in a_0]``.
    """
    from ..core.environment import PIECE_HEADER

    t = np.asarray(t, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        v = v[:, None]
    degree = int(degree)
    if t.ndim != 1 or v.ndim != 2 or v.shape[0] != t.shape[0] or not 1 <= v.shape[1] <= 4:
        raise InputError(f"values: expected shape ({t.shape[0]},) or ({t.shape[0]}, ncomp <= 4) for "
                         f"{t.shape[0]} times, got {np.shape(values)}")
    if degree < 1 or t.shape[0] < degree + 1 or (t.shape[0] - 1) % degree or not np.all(np.diff(t) > 0.0):
        raise InputError(f"t: expected the increasing piece_times of degree {degree} (n * {degree} + 1 times), "
                         f"got {t.shape[0]} times")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise InputError("values: contains non-finite samples")
    n, ncomp, d = (t.shape[0] - 1) // degree, v.shape[1], degree
    knots = t[::d]
    # node j of a piece is x_j = -cos(pi j / d): T_k(x_j) = (-1)^k cos(pi j k / d)
    jk = np.arange(d + 1)
    T = np.cos(np.pi * ((jk[:, None] * jk[None, :]) % (2 * d)) / d) * np.where(jk % 2, -1.0, 1.0)[None, :]
    wj = np.where((jk == 0) | (jk == d), 0.5, 1.0)
    nodes = np.stack([v[i * d:i * d + d + 1] for i in range(n)])     # (n, d + 1, ncomp)
    c = np.zeros((n, d + 1, ncomp))
    for j in range(d + 1):                                           # Chebyshev coefficients
        c += (wj[j] * T[j])[None, :, None] * nodes[:, j:j + 1, :]
    c *= (2.0 / d) * wj[None, :, None]
    P = _chebyshev_to_monomial(d)
    a = np.zeros_like(c)
    for k in range(d + 1):                                           # monomials in x
        a += P[None, :, k, None] * c[:, k:k + 1, :]
    table = np.zeros((n + 1, PIECE_HEADER + ncomp * (d + 1)))
    table[:, 0] = knots
    table[:-1, 1] = 2.0 / np.diff(knots)
    table[:, 2] = d
    for k in range(ncomp):
        b = PIECE_HEADER + k * (d + 1)
        table[:-1, b:b + d + 1] = a[:, :, k]
        table[-1, b] = v[-1, k]
    return table


def tabulate(samples, evaluate, degree):
    """A piece table of ``evaluate(samples.time, samples.position)`` at the samples.

    Parameters
    ----------
    samples : OrbitSamples
        From :func:`sample_pieces` (with ``degree``).
    evaluate : callable
        ``(Time (N,), positions (N, 3) km GCRS) -> (N,) or (N, ncomp)``, e.g.
        ``NRLMSIS(...).density``, ``IGRFField().field``, or
        ``lambda t, r: sun_position(t)``.
    degree : int
        The pieces' degree.

    Returns
    -------
    ndarray
        :func:`piece_table` of the values against ``samples.t``.
    """
    return piece_table(samples.t, evaluate(samples.time, samples.position), degree)

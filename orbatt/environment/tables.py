"""Environment tables: fields sampled along the prescribed orbit and splined for the kernel.

The orbit is prescribed, so density, magnetic field and Sun position depend on time alone
along it (``docs/design.md`` §10). They are evaluated by their libraries at evenly spaced
samples (:func:`sample_along_orbit`) and turned into per-interval cubic polynomials
(:func:`spline_table`, the not-a-knot cubic spline of scipy's ``CubicSpline``, computed by
:func:`orbatt.core.environment.not_a_knot_table` without importing scipy) that
:func:`orbatt.core.environment.spline_eval` evaluates in the compiled right-hand side.

Default sampling steps and the interpolation error they give: the largest difference
between the table and the library at the quarter and mid points of every interval, relative
to the largest magnitude along the orbit, over two orbits of a 400 km, 51.6 deg orbit from
2024-03-20 (the Sun over one day); ``tests/environment/test_environment_tables.py`` measures
and bounds it. The error of a cubic spline scales as ``step^4`` (halving the step divides it
by 16) until the library's own noise is reached.

* magnetic field, :data:`MAGNETIC_FIELD_STEP` = 20 s: IGRF 1.8e-7, dipole 7.0e-8 (required
  < 1e-6; 10 s: 1.1e-8, 30 s: 9.4e-7, 60 s: 1.6e-5).
* Sun position, :data:`SUN_STEP` = 3600 s: 4.4e-14 in position, 4.8e-14 in direction
  (required < 1e-6; 14400 s: 1e-12).
* NRLMSIS density, :data:`DENSITY_STEP` = 30 s: 1.2e-5 (required < 1e-4). This is the noise
  of the model itself: NRLMSIS 2.1 as pymsis runs it is single precision (float32 densities; its
  inputs are float32 and the time of day is truncated to whole seconds), and the third
  differences of ``log rho`` along a smooth path are ~1e-5 whatever the spacing. The
  interpolation part is below it up to 60 s (1.35e-5 in all); 120 s gives 1.3e-4.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from astropy import units as u

from .. import units as U
from ..errors import InputError

__all__ = ["OrbitSamples", "sample_along_orbit", "spline_table", "tabulate", "MAGNETIC_FIELD_STEP",
           "SUN_STEP", "DENSITY_STEP"]

#: default sampling step (s) of the magnetic-field table (relative error 1.8e-7 at 400 km)
MAGNETIC_FIELD_STEP = 20.0
#: default sampling step (s) of the Sun-position table (relative error 5e-14)
SUN_STEP = 3600.0
#: default sampling step (s) of the NRLMSIS density table (relative error 1.2e-5, NRLMSIS's
#: own single-precision noise)
DENSITY_STEP = 30.0


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
    t0, t1, step = _seconds(t0, "t0"), _seconds(t1, "t1"), _seconds(step, "step")
    if not t1 > t0:
        raise InputError(f"t1: {t1} s must be after t0 = {t0} s")
    if not step > 0.0:
        raise InputError(f"step: {step} s must be positive")
    span = orbit.time_span
    if span is not None and (t0 < span[0] or t1 > span[1]):
        raise InputError(f"t0, t1: [{t0}, {t1}] s is outside the orbit's sampled span [{span[0]}, {span[1]}] s; "
                         "build the orbit over the whole run")
    n = max(int(math.ceil((t1 - t0) / step - 1e-9)), 1)
    t = np.linspace(t0, t1, n + 1)
    pos, vel = orbit.state(t)
    return OrbitSamples(t, None if orbit.epoch is None else orbit.epoch + t * u.s, np.asarray(pos, dtype=np.float64),
                        np.asarray(vel, dtype=np.float64))


def spline_table(t, values):
    """Per-interval cubic coefficients of the not-a-knot cubic spline through ``values``.

    Parameters
    ----------
    t : array_like (N,)
        Strictly increasing times (s), ``N >= 4``.
    values : array_like (N,) or (N, ncomp)
        Samples, ``ncomp <= 4`` components.

    Returns
    -------
    ndarray (N, 1 + 4 ncomp)
        ``table[i] = [t_i, c0, c1, c2, c3 (component 0), ...]``: on ``[t_i, t_{i+1}]``
        component ``k`` is ``c0 + c1 s + c2 s^2 + c3 s^3``, ``s = t - t_i``; the last row
        holds ``t_{N-1}`` and the end values in ``c0`` (layout of
        :mod:`orbatt.core.environment`).
    """
    from ..core.environment import not_a_knot_table

    t = np.asarray(t, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        v = v[:, None]
    if t.ndim != 1 or v.ndim != 2 or v.shape[0] != t.shape[0] or not 1 <= v.shape[1] <= 4:
        raise InputError(f"values: expected shape ({t.shape[0]},) or ({t.shape[0]}, ncomp <= 4) for "
                         f"{t.shape[0]} times, got {np.shape(values)}")
    if t.shape[0] < 4 or not np.all(np.diff(t) > 0.0):
        raise InputError("t: need at least 4 strictly increasing times for a cubic spline table")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise InputError("values: contains non-finite samples")
    return not_a_knot_table(np.ascontiguousarray(t), np.ascontiguousarray(v))


def tabulate(samples, evaluate):
    """A spline table of ``evaluate(samples.time, samples.position)`` at the samples.

    Parameters
    ----------
    samples : OrbitSamples
        From :func:`sample_along_orbit`.
    evaluate : callable
        ``(Time (N,), positions (N, 3) km GCRS) -> (N,) or (N, ncomp)``, e.g.
        ``NRLMSIS(...).density``, ``IGRFField().field``, or
        ``lambda t, r: sun_position(t)``.

    Returns
    -------
    ndarray
        :func:`spline_table` of the values against ``samples.t``.
    """
    return spline_table(samples.t, evaluate(samples.time, samples.position))

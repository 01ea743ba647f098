"""Pointing error indices of ECSS-E-ST-60-10C (2008, §4-5 and Annex; ESA Pointing Error
Engineering Handbook ESSB-HB-E-003, 2011) on plain arrays (``docs/pointing-budgets.md``).

An **error series** is ``e (N,)`` (angles, rad: the rotation angle from the target, or a
pointing axis' direction angle) or ``e (N, 3)`` (rotation vectors, rad, e.g. the knowledge
error from the estimate to the truth in body axes) at the output times ``t (N,)`` (s, or the
normalized time unit; increasing, possibly non-uniform). The same functions give the
performance indices (APE, MPE, RPE, PDE of the performance error ``e_P``) and the knowledge
indices (AKE, MKE, RKE, KDE of the knowledge error ``e_K``): only the series differs.

**Windows.** The stability window ``Δt`` cuts the time axis into consecutive, non-overlapping,
half-open windows from the first output: window ``k`` is ``[t0 + k Δt, t0 + (k+1) Δt)``. A
window is *complete* when the run reaches its end (``t0 + (k+1) Δt <= t[-1]``); the outputs of
the trailing partial window (after the last complete window, the last output included when it
falls exactly on a window's start) have no window mean: their MPE, RPE and PDE are NaN and they
enter no quantile. A window shorter than two outputs (in any complete window) or longer than
the run is refused (:class:`~orbatt.errors.InputError`). The **mean over a window** is the
arithmetic mean of the outputs in it (each output counts once; equal to the time average for
uniform outputs).

**Indices** (series of the same length as ``e``, rad, one value per output):
``APE(t) = |e(t)|``; ``MPE(t) = |mean_W e|`` with ``W`` the window containing ``t`` (the same
value at every output of a window); ``RPE(t) = |e(t) - mean_W e|``; ``PDE(t) = |mean_W e -
mean_W' e|`` with ``W'`` the window ``s`` windows before ``W`` (``separation = s Δt``). For a
vector series the mean and difference are taken componentwise and ``|.|`` is the Euclidean norm
of the resulting vector; for an angle series ``|.|`` is the absolute value.

**Quantile.** The index value at confidence ``P_C`` of samples ``x_1..x_n`` (NaN left out) is
the smallest sample ``v`` such that a fraction ``>= P_C`` of the samples have ``|x| <= v``: the
``k``-th smallest ``|x|`` with ``k = ceil(n P_C)``, computed exactly with ``P_C`` read as the
decimal it prints as (``0.9973`` is 9973/10000, not its binary neighbour). This is numpy's
``method="inverted_cdf"``. NaN when no sample is left.

**Statistical interpretations** of an ensemble ``x (cases, time)``: *temporal* (per case, over
its times: ``(cases,)``), *ensemble* (per time, over the cases; the worst time's value),
*mixed* (all times of all cases pooled).
"""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from .errors import InputError

__all__ = ["INTERPRETATIONS", "window_index", "window_means", "ape", "mpe", "rpe", "pde", "index_series",
           "INDEX_KINDS", "check_confidence", "quantile", "temporal_quantile", "ensemble_quantiles",
           "ensemble_quantile", "mixed_quantile", "interpreted_quantile", "mixed_bounds", "index_value", "index_attrs"]

#: the statistical interpretations (ECSS-E-ST-60-10C §4.2.4)
INTERPRETATIONS = ("temporal", "ensemble", "mixed")


def _times(t):
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1 or t.size < 2:
        raise InputError(f"t: expected at least two output times (N,), got shape {t.shape}")
    if not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0):
        raise InputError("t: the output times must be finite and strictly increasing")
    return t


def _series(e, n):
    e = np.asarray(e, dtype=np.float64)
    if e.ndim not in (1, 2) or e.shape[0] != n or (e.ndim == 2 and e.shape[1] != 3):
        raise InputError(f"e: expected an error series of angles (N,) or rotation vectors (N, 3) with N = {n} "
                         f"(the output times), got shape {e.shape}")
    return e


def window_index(t, window):
    """The stability window of each output (module docstring: Windows).

    Parameters
    ----------
    t : array_like (N,)
        Output times, strictly increasing (s, or the normalized time unit).
    window : float
        The stability window ``Δt``, in the unit of ``t``.

    Returns
    -------
    ndarray of int (N,)
        ``k`` of the window ``[t0 + k Δt, t0 + (k+1) Δt)`` holding each output; -1 for the
        outputs of the trailing partial window.

    Raises
    ------
    InputError
        ``window`` not finite and positive, longer than the run ``t[-1] - t[0]``, or a complete
        window holding fewer than two outputs.
    """
    t = _times(t)
    span = float(t[-1] - t[0])
    if not (isinstance(window, (int, float, np.floating)) and math.isfinite(window) and window > 0):
        raise InputError(f"stability_window: {window!r} must be a positive time; give the stability time of the "
                         "requirement")
    if window > span:
        raise InputError(f"stability_window: {window:g} is longer than the run ({span:g}, from the first output to "
                         "the last); give a shorter window or a longer run")
    k = np.floor((t - t[0]) / window).astype(np.int64)
    complete = int(math.floor(span / window))  # windows 0 .. complete-1 end inside the run
    while complete > 0 and t[0] + complete * window > t[-1]:  # rounding of span / window
        complete -= 1
    k[k >= complete] = -1
    counts = np.bincount(k[k >= 0], minlength=complete)
    if counts.size and counts.min() < 2:
        j = int(np.argmin(counts))
        raise InputError(f"stability_window: {window:g} leaves {int(counts[j])} output(s) in window {j} "
                         f"(from {t[0] + j * window:g}); each window needs at least two outputs: give a longer window "
                         "or a smaller output_step")
    return k


def window_means(t, e, window):
    """The mean of ``e`` over each complete stability window.

    Parameters
    ----------
    t : array_like (N,)
        Output times, strictly increasing.
    e : array_like (N,) or (N, 3)
        Error angles or rotation vectors (rad).
    window : float
        The stability window, in the unit of ``t``.

    Returns
    -------
    means : ndarray (K,) or (K, 3)
        The arithmetic mean of the outputs of each of the ``K`` complete windows (rad).
    k : ndarray of int (N,)
        :func:`window_index` (-1: the trailing partial window).
    """
    k = window_index(t, window)
    e = _series(e, k.size)
    K = int(k.max()) + 1
    counts = np.bincount(k[k >= 0], minlength=K).astype(np.float64)
    if e.ndim == 1:
        return np.bincount(k[k >= 0], weights=e[k >= 0], minlength=K) / counts, k
    sums = np.stack([np.bincount(k[k >= 0], weights=e[k >= 0, j], minlength=K) for j in range(3)], axis=1)
    return sums / counts[:, None], k


def _magnitude(x):
    """``|x|``: the absolute value of angles (N,), the Euclidean norm of vectors (N, 3)."""
    if x.ndim == 1:
        return np.abs(x)
    return np.sqrt(x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1] + x[:, 2] * x[:, 2])


def _per_output(means, k):
    """The mean of each output's window at that output (NaN in the trailing partial window)."""
    out = np.full((k.size,) + means.shape[1:], np.nan)
    out[k >= 0] = means[k[k >= 0]]
    return out


def ape(e):
    """Absolute error ``|e(t)|`` (APE of ``e_P``, AKE of ``e_K``), rad, per output.

    Parameters
    ----------
    e : array_like (N,) or (N, 3)
        Error angles or rotation vectors (rad).

    Returns
    -------
    ndarray (N,)
    """
    e = np.asarray(e, dtype=np.float64)
    return _magnitude(_series(e, e.shape[0] if e.ndim else -1))


def mpe(t, e, window):
    """Mean error ``|mean_W e|`` of the window ``W`` holding each output (MPE of ``e_P``, MKE
    of ``e_K``), rad, per output; NaN in the trailing partial window.

    Parameters
    ----------
    t : array_like (N,)
        Output times, strictly increasing.
    e : array_like (N,) or (N, 3)
        Error angles or rotation vectors (rad).
    window : float
        The stability window, in the unit of ``t``.

    Returns
    -------
    ndarray (N,)
    """
    means, k = window_means(t, e, window)
    return _magnitude(_per_output(means, k))


def rpe(t, e, window):
    """Relative error ``|e(t) - mean_W e|`` about the mean of the window ``W`` holding ``t``
    (RPE of ``e_P``, RKE of ``e_K``), rad, per output; NaN in the trailing partial window.

    Parameters
    ----------
    t : array_like (N,)
        Output times, strictly increasing.
    e : array_like (N,) or (N, 3)
        Error angles or rotation vectors (rad).
    window : float
        The stability window, in the unit of ``t``.

    Returns
    -------
    ndarray (N,)
    """
    means, k = window_means(t, e, window)
    e = np.asarray(e, dtype=np.float64)
    return _magnitude(e - _per_output(means, k))


def pde(t, e, window, separation):
    """Performance drift ``|mean_W e - mean_W' e|`` between the window ``W`` holding each
    output and the window ``W'`` ``separation`` before it (PDE of ``e_P``, KDE of ``e_K``),
    rad, per output; NaN in the first ``separation / window`` windows and the trailing partial
    one.

    Parameters
    ----------
    t : array_like (N,)
        Output times, strictly increasing.
    e : array_like (N,) or (N, 3)
        Error angles or rotation vectors (rad).
    window : float
        The stability window, in the unit of ``t``.
    separation : float
        ``Δt_s``, the time between the starts of the two windows: a whole number ``s >= 1`` of
        windows (within 1e-9 relative), in the unit of ``t``.

    Returns
    -------
    ndarray (N,)
    """
    s = separation / window if window > 0 else math.nan
    if not (math.isfinite(s) and s >= 1.0 - 1e-9 and abs(s - round(s)) <= 1e-9 * s):
        raise InputError(f"separation: {separation!r} is not a whole number (>= 1) of stability windows "
                         f"({window!r}); give a multiple of the window")
    s = int(round(s))
    means, k = window_means(t, e, window)
    if s >= means.shape[0]:
        raise InputError(f"separation: {separation!r} is {s} windows, but the run holds {means.shape[0]} complete "
                         "windows; give a shorter separation or a longer run")
    drift = np.full(means.shape, np.nan)
    drift[s:] = means[s:] - means[:-s]
    return _magnitude(_per_output(drift, k))


#: the indices of an error series by name: ``name -> (function, needs the window)``;
#: ake, mke, rke are the same functions applied to the knowledge error
INDEX_KINDS = {"ape": (lambda t, e, w: ape(e), False), "mpe": (mpe, True), "rpe": (rpe, True),
               "ake": (lambda t, e, w: ape(e), False), "mke": (mpe, True), "rke": (rpe, True)}


def index_series(name, t, e, window=None):
    """The index ``name`` (a key of :data:`INDEX_KINDS`) of the error series ``e`` at the
    outputs ``t``: ``(N,)``, rad (``window`` in the unit of ``t``; needed by the mean and
    relative indices)."""
    fn, windowed = INDEX_KINDS[name]
    if windowed and window is None:
        raise InputError(f"stability_window: {name} needs the stability window; give it")
    return fn(t, e, window)


def check_confidence(confidence):
    """``confidence`` as a float in (0, 1); :class:`~orbatt.errors.InputError` otherwise."""
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float, np.floating)) \
            or not 0.0 < float(confidence) < 1.0:
        raise InputError(f"confidence: {confidence!r} is outside (0, 1); give a probability such as 0.9973 (3 sigma)")
    return float(confidence)


def _rank(n, confidence):
    """``ceil(n P_C)``, exact, with ``P_C`` the decimal it prints as; at least 1."""
    return max(1, math.ceil(Fraction(repr(float(confidence))) * n))


def quantile(x, confidence):
    """The index value at ``confidence`` of the samples ``x`` (module docstring: Quantile).

    Parameters
    ----------
    x : array_like
        Samples of an index (rad; any shape, pooled); NaN left out.
    confidence : float
        ``P_C`` in (0, 1).

    Returns
    -------
    float
        The smallest ``v`` among the ``|x|`` with a fraction ``>= P_C`` of them ``<= v``; NaN
        without samples.
    """
    p = check_confidence(confidence)
    a = np.abs(np.asarray(x, dtype=np.float64).ravel())
    a = a[~np.isnan(a)]
    if not a.size:
        return math.nan
    k = _rank(a.size, p)
    return float(np.partition(a, k - 1)[k - 1])


def _ensemble(x):
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2:
        raise InputError(f"x: expected an index of an ensemble (cases, time), got shape {x.shape}")
    return x


def temporal_quantile(x, confidence):
    """Temporal interpretation: each case's :func:`quantile` over its times.

    Parameters
    ----------
    x : array_like (cases, time)
        An index (rad) of each case at each output.
    confidence : float

    Returns
    -------
    ndarray (cases,)
    """
    x = _ensemble(x)
    return np.array([quantile(row, confidence) for row in x])


def ensemble_quantiles(x, confidence):
    """The :func:`quantile` over the cases at each time (NaN where no case has a value).

    Parameters
    ----------
    x : array_like (cases, time)
    confidence : float

    Returns
    -------
    ndarray (time,)
    """
    x = _ensemble(x)
    return np.array([quantile(col, confidence) for col in x.T])


def ensemble_quantile(x, confidence):
    """Ensemble interpretation: the worst time's :func:`ensemble_quantiles` (float, rad; NaN
    when no time has a value)."""
    q = ensemble_quantiles(x, confidence)
    return float(np.nanmax(q)) if np.any(~np.isnan(q)) else math.nan


def mixed_quantile(x, confidence):
    """Mixed interpretation: the :func:`quantile` of every time of every case pooled (float)."""
    return quantile(_ensemble(x), confidence)


def interpreted_quantile(x, confidence, interpretation):
    """The index value of ``x (cases, time)`` at ``confidence`` under ``interpretation`` (one
    of :data:`INTERPRETATIONS`): temporal ``(cases,)``, ensemble and mixed a float."""
    fn = {"temporal": temporal_quantile, "ensemble": ensemble_quantile, "mixed": mixed_quantile}.get(interpretation)
    if fn is None:
        raise InputError(f"interpretation: {interpretation!r} is not one of {', '.join(INTERPRETATIONS)}")
    return fn(x, confidence)


def mixed_bounds(temporal):
    """``(low, high)`` bounds of the mixed value from the cases' temporal values alone, for
    cases that share their sample count (a sweep's cases share the output times): every case
    has a fraction ``>= P_C`` of its samples at or below its own value, so the pool has one at
    or below the largest (``high``); below the smallest, every case has less than ``P_C``, so
    the pool has too (``low``). The ensemble value (worst time) is at least the mixed one.
    NaN cases are left out; ``(nan, nan)`` when none is left."""
    v = np.asarray(temporal, dtype=np.float64)
    v = v[~np.isnan(v)]
    return (float(v.min()), float(v.max())) if v.size else (math.nan, math.nan)


def index_value(name, t, e, confidence, window=None, where=""):
    """One case's value of the index ``name`` (:data:`INDEX_KINDS`) under the temporal
    interpretation: :func:`quantile` at ``confidence`` of :func:`index_series` (rad). An
    :class:`~orbatt.errors.InputError` names its field after ``where`` (``"[sweep] "``)."""
    try:
        return quantile(index_series(name, t, e, window), confidence)
    except InputError as exc:
        raise InputError(f"{where}{exc}") from None


def index_attrs(name, confidence, window=None, requirement=None):
    """The attributes a sweep's index variable carries: ``confidence``, ``interpretation``,
    ``quantile`` (the definition), ``stability_window`` (the unit of the output times) where the
    index is windowed, ``requirement_rad`` where one is given."""
    d = dict(confidence=confidence, interpretation="temporal",
             quantile="smallest v with a fraction >= confidence of the output times at |index| <= v")
    if INDEX_KINDS[name][1]:
        d["stability_window"] = window
    if requirement is not None:
        d["requirement_rad"] = requirement
    return d

"""The pointing budget of a sweep result (``docs/pointing-budgets.md``): the ECSS indices it
holds (``ape``, ``rpe``, ``mpe``, ...: variables along ``case`` whose attributes give their
``confidence`` and ``interpretation = "temporal"``, :func:`orbatt.pointing.index_attrs`), read
under the three statistical interpretations as far as the file allows. ``orbatt info`` prints
:func:`budget_lines`; ``orbatt plot`` draws the budget figure from :func:`pointing_budget`
(:mod:`orbatt.dataset.sweep_figures`).

A sweep result holds one value per case (its temporal quantile), not each case's error at each
output time. So the temporal interpretation is exact (the distribution over the cases: median
and maximum); the mixed one is bracketed exactly by the smallest and largest case values (the
cases share their output times: :func:`orbatt.pointing.mixed_bounds`); the ensemble one (the
worst time's quantile over the cases) is at least the mixed one and is not computed: it needs
every case's error at every time (:func:`orbatt.pointing.ensemble_quantile` computes it from
such an array, e.g. an ensemble run's).
"""
from __future__ import annotations

import math

import numpy as np

from ..pointing import ensemble_quantile, index_series, mixed_bounds, mixed_quantile
from .timeaxis import elapsed_values

__all__ = ["index_variables", "pointing_budget", "angle_display", "budget_lines", "WHY_NO_ENSEMBLE"]

#: why ``orbatt info`` prints no ensemble value (and brackets the mixed one), a line each
WHY_NO_ENSEMBLE = ("temporal: each case's quantile over its output times (exact). The file holds that value per case,",
                   "not each case's error at each time: the ensemble value (worst time, over the cases) is not computed;",
                   "it is at least the mixed value (all times of all cases pooled), which lies between the smallest",
                   "and the largest case value (the cases share their output times).")


def index_variables(ds):
    """The pointing indices of a sweep Dataset: float variables along ``case`` only with a
    ``confidence`` attribute and ``interpretation = "temporal"``, in the Dataset's order."""
    return [k for k, v in ds.data_vars.items() if v.dims == ("case",) and v.dtype.kind == "f"
            and "confidence" in v.attrs and v.attrs.get("interpretation") == "temporal"]


def pointing_budget(ds):
    """Each index of :func:`index_variables`: a dict of ``name``, ``confidence``, ``values``
    (the cases' values, rad, NaN left out), ``missing`` (cases without one), ``median`` and
    ``max`` over the cases (temporal), ``mixed`` (``(low, high)`` bounds), ``requirement``
    (rad, or None) and ``meeting`` (cases at or below it, or None)."""
    out = []
    for name in index_variables(ds):
        v = ds[name]
        x = np.asarray(v.values, dtype=np.float64)
        ok = x[np.isfinite(x)]
        req = v.attrs.get("requirement_rad")
        req = None if req is None else float(req)
        out.append(dict(name=name, confidence=float(v.attrs["confidence"]), values=ok, missing=int(x.size - ok.size),
                        median=float(np.median(ok)) if ok.size else math.nan,
                        max=float(np.max(ok)) if ok.size else math.nan, mixed=mixed_bounds(ok), requirement=req,
                        meeting=None if req is None else int(np.count_nonzero(ok <= req)),
                        window=v.attrs.get("stability_window")))
        out[-1].update(_from_series(ds, name, out[-1]))
    return out


#: the error series a sweep result may hold per case and time (its ``trajectory`` output), by
#: the indices computed from it: the knowledge error (the attitude filter's, rad, body axes)
SERIES = {"ake": "knowledge_error", "mke": "knowledge_error", "rke": "knowledge_error"}


def _from_series(ds, name, row):
    """``{"ensemble", "mixed_exact"}`` of the index ``name`` from the cases' error series when
    the result holds them (:data:`SERIES`; a sweep with the ``trajectory`` output), else ``{}``."""
    var = SERIES.get(name)
    if var is None or var not in ds or ds[var].dims[:2] != ("case", "time"):
        return {}
    t = elapsed_values(ds)
    e = np.asarray(ds[var].values, dtype=np.float64)
    x = np.stack([index_series(name, t, e[k], row["window"]) for k in range(e.shape[0])])
    return {"ensemble": ensemble_quantile(x, row["confidence"]), "mixed_exact": mixed_quantile(x, row["confidence"])}


def angle_display(values_rad):
    """``(factor, label)`` showing angles (rad) in deg, or in arcsec where the largest is below
    0.1 deg."""
    x = np.abs(np.asarray(values_rad, dtype=np.float64))
    x = x[np.isfinite(x)]
    top = float(np.max(x)) if x.size else 0.0
    return (np.degrees(1.0) * 3600.0, "arcsec") if top < math.radians(0.1) else (np.degrees(1.0), "deg")


def budget_lines(ds):
    """Lines of ``orbatt info``'s pointing budget (empty without indices)."""
    rows = pointing_budget(ds)
    if not rows:
        return []
    conf = sorted({r["confidence"] for r in rows})
    everything = np.concatenate([[r["max"], r["requirement"] or math.nan] for r in rows])
    factor, unit = angle_display(everything)
    out = [f"  pointing budget (ECSS-E-ST-60-10C) at confidence {', '.join(f'{c:g}' for c in conf)}, {unit}:",
           f"  {'index':<8} {'temporal: median':>17} {'max':>10}   {'mixed: from':>11} {'to':>10}   {'ensemble':>9}   "
           f"{'requirement':>11}  cases meeting it"]
    for r in rows:
        lo, hi = r["mixed"]
        req = "-" if r["requirement"] is None else f"{r['requirement'] * factor:.4g}"
        meet = "" if r["meeting"] is None else f"{r['meeting']} of {r['values'].size}"
        if r["missing"]:
            meet += f" ({r['missing']} cases without a value)"
        if "ensemble" in r:  # computed from the cases' series: exact
            mix, ens = f"{r['mixed_exact'] * factor:>11.4g} {'(exact)':>10}", f"{r['ensemble'] * factor:>9.4g}"
        else:
            mix, ens = f"{lo * factor:>11.4g} {hi * factor:>10.4g}", f"{'>= ' + format(lo * factor, '.4g'):>9}"
        out.append(f"  {r['name']:<8} {r['median'] * factor:>17.4g} {r['max'] * factor:>10.4g}   {mix}   {ens}   "
                   f"{req:>11}  {meet}".rstrip())
    if not all("ensemble" in r for r in rows):
        out += [f"  {line}" for line in WHY_NO_ENSEMBLE]
    return out

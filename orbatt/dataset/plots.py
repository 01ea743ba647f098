"""The quick plots of an orbatt Dataset (also as ``ds.orbatt.plot_state()`` etc.): the paper's
figure layout, Euler angles, and the drift of the invariants. matplotlib is imported only
when a plot is drawn.

Every axis is labelled with its quantity and unit. Time is drawn as UTC dates for a run with
an epoch spanning more than :data:`UTC_SPAN_S`, in orbits for a run with an orbit and no epoch,
else as the time since the start in s, min, h or d by the run's length, the epoch named where
there is one (``time=`` chooses). Angles are unwrapped (no jumps of 360 degrees). Log axes
leave gaps at exact zeros (there is no value to draw on them) and say so in the panel's title.
The impulses of a scenario (``[[orbit.impulses]]``) are marked on every time axis.
"""
from __future__ import annotations

import json
import math

import numpy as np
from astropy import units as u

from .. import quaternion as qt
from ..units import parse_unit, unit_string
from .build import EULER_313_LABELS, EULER_321_LABELS
from .timeaxis import elapsed_unit, elapsed_values

__all__ = ["plot_state", "plot_attitude", "plot_drift", "time_axis", "time_values", "elapsed_scale", "drift_series",
           "mark_impulses", "impulse_times", "log_values", "stored_scenario", "value_in"]

#: choices of the ``time`` argument of the plots
TIME_AXES = ("auto", "utc", "orbits", "time", "elapsed")
#: ``"auto"`` draws UTC dates for a run with an epoch longer than this (s); a shorter one in
#: the time since its start
UTC_SPAN_S = 3 * 86400.0
#: the units of the time since the start: ``(unit, seconds, longest span drawn in it)``
ELAPSED_UNITS = (("s", 1.0, 1200.0), ("min", 60.0, 3 * 3600.0), ("h", 3600.0, 3 * 86400.0), ("d", 86400.0, np.inf))


def member(ds, case=None):
    """One member of an ensemble (``case``; default the first), or ``ds`` itself."""
    if "case" in ds.dims:
        ds = ds.isel(case=0) if case is None else ds.sel(case=case)
    return ds


def _orbit(ds):
    """The orbit description stored in the Dataset (``orbit`` attribute), or None."""
    text = ds.attrs.get("orbit")
    return json.loads(text) if text else None


def orbit_period(ds):
    """The orbital period in the Dataset's time unit (``period_s``, or ``period`` in
    normalized units, of the stored orbit), or None."""
    orb = _orbit(ds)
    if not orb:
        return None
    p = orb.get("period_s", orb.get("period"))
    return float(p) if p else None


def elapsed_scale(span_s):
    """``(unit, seconds)``: the unit a span of ``span_s`` seconds is drawn in
    (:data:`ELAPSED_UNITS`: s up to 20 min, min up to 3 h, h up to 3 d, else d)."""
    for unit, seconds, longest in ELAPSED_UNITS:
        if span_s <= longest:
            return unit, seconds
    return ELAPSED_UNITS[-1][:2]


def _time_mode(ds, time):
    if time not in TIME_AXES:
        raise ValueError(f"time: {time!r} is not one of {TIME_AXES}")
    epoch = ds.orbatt.epoch
    period = orbit_period(ds)
    if time == "auto":
        t = elapsed_values(ds)
        span = float(np.nanmax(t) - np.nanmin(t)) if t.size else 0.0
        dimensionless = elapsed_unit(ds) == "1"
        time = ("utc" if epoch is not None and span > UTC_SPAN_S else "orbits" if epoch is None and period else
                "time" if dimensionless else "elapsed")
    if time == "utc" and epoch is None:
        raise ValueError("time: 'utc' needs an epoch; this Dataset has none")
    if time == "orbits" and not period:
        raise ValueError("time: 'orbits' needs an orbit; this Dataset has none")
    return time, epoch, period


def time_values(ds, t, time="auto"):
    """Times ``t`` (in the Dataset's ``elapsed`` unit: s, or the dimensionless time) on the
    axis :func:`time_axis` draws with ``time``."""
    mode, epoch, period = _time_mode(ds, time)
    t = np.asarray(t, dtype=np.float64)
    if mode == "utc":
        base = np.datetime64(ds.orbatt.times().utc.datetime64[0], "ns")
        t0 = float(elapsed_values(ds)[0])
        return base + np.round((t - t0) * 1e9).astype("timedelta64[ns]")
    if mode == "orbits":
        return t / period
    if mode == "elapsed" and elapsed_unit(ds) != "1":
        all_t = elapsed_values(ds)
        unit, seconds = elapsed_scale(float(np.nanmax(all_t) - np.nanmin(all_t)) if all_t.size else 0.0)
        return t / seconds
    return t


def time_axis(ds, time="auto"):
    """``(values, label)`` of the time axis of a plot.

    Parameters
    ----------
    ds : xarray.Dataset
    time : {"auto", "utc", "orbits", "time", "elapsed"}
        ``"utc"``: dates (numpy datetime64, UTC) from the epoch; ``"orbits"``: time over the
        orbital period; ``"time"``: the ``elapsed`` coordinate in its unit (s, or
        dimensionless); ``"elapsed"``: the same in s, min, h or d by the run's length
        (:func:`elapsed_scale`), labelled with the epoch where there is one. ``"auto"``: UTC for
        a run with an epoch longer than :data:`UTC_SPAN_S`, orbits for a run with an orbit and
        no epoch, else ``"elapsed"``.
    """
    mode, epoch, period = _time_mode(ds, time)
    t = elapsed_values(ds)
    if mode == "utc":
        return ds.orbatt.times().utc.datetime64, f"UTC (from {epoch.utc.isot[:19]})"
    if mode == "orbits":
        return t / period, "time [orbits]"
    units = elapsed_unit(ds)
    if units == "1":
        return t, "time (dimensionless)"
    if mode == "elapsed":
        unit, seconds = elapsed_scale(float(np.nanmax(t) - np.nanmin(t)) if t.size else 0.0)
        since = f"time since {epoch.utc.isot[:19]} UTC" if epoch is not None else "elapsed time"
        return t / seconds, f"{since} [{unit}]"
    return t, f"elapsed time [{unit_string(parse_unit(units))}]"


def stored_scenario(ds):
    """The stored scenario's TOML tables (``scenario`` attribute), read as plain TOML: the run
    validated them; ``{}`` without one or where it does not read."""
    text = ds.attrs.get("scenario")
    if not text:
        return {}
    try:
        import tomllib

        return tomllib.loads(str(text))
    except (ImportError, ValueError):
        return {}


def value_in(value, unit):
    """A scenario value (``"6000 rpm"``, or a plain number: already in ``unit``, the
    normalized scenarios' form) in ``unit``, or None where it is not one."""
    if isinstance(value, bool) or value is None:
        return None
    try:
        if isinstance(value, (int, float)):
            return float(value)
        return float(u.Quantity(str(value)).to_value(unit))
    except (TypeError, ValueError, u.UnitsError):
        return None


def log_values(y):
    """``(y, zeros)``: ``y`` for a log axis - values at or below 0 (SRP in eclipse, an error of
    exactly 0 at an aligned start) replaced by NaN, so that they are gaps, not points at a floor
    no data has - and how many were (the figures say so in the line's label)."""
    y = np.array(y, dtype=np.float64)
    bad = np.isfinite(y) & (y <= 0.0)
    y[bad] = np.nan
    return y, int(np.count_nonzero(bad))


def impulse_times(ds):
    """The times (in the Dataset's ``elapsed`` unit) of the stored scenario's impulses
    (``[[orbit.impulses]] time``: the deliberate Delta v of a binary), sorted; empty without."""
    impulses = ((stored_scenario(ds).get("orbit") or {}).get("impulses")) or []
    unit = u.s if str(ds["elapsed"].attrs.get("units", "s")).strip() not in ("1", "") else None
    out = []
    for imp in impulses if isinstance(impulses, list) else []:
        if isinstance(imp, dict):
            value = imp.get("time")
            t = (float(value) if isinstance(value, (int, float)) and not isinstance(value, bool)
                 else value_in(value, unit) if unit is not None else None)
            if t is not None:
                out.append(t)
    return sorted(out)


def mark_impulses(axes, ds, time="auto"):
    """Mark the scenario's impulses (``[[orbit.impulses]]``: a binary's deliberate Delta v) on
    each of ``axes`` (a time axis of :func:`time_axis` with ``time``) as a labelled vertical
    line; returns how many."""
    times = impulse_times(ds)
    if not times:
        return 0
    xs = time_values(ds, times, time)
    for ax in axes:
        for k, xv in enumerate(np.atleast_1d(xs)):
            ax.axvline(xv, color="tab:red", ls=":", lw=1.4,
                       label="impulse (Delta v, [[orbit.impulses]])" if k == 0 else None)
    return len(times)


def _unit_label(quantity, units):
    return f"{quantity} (dimensionless)" if units in ("1", "") else f"{quantity} [{units}]"


def _finish(fig, x):
    """Slanted date labels on a UTC axis, then a tight layout."""
    if np.issubdtype(np.asarray(x).dtype, np.datetime64):
        fig.autofmt_xdate()
    fig.tight_layout()
    return fig


def plot_state(ds, case=None, fig=None, time="auto"):
    """The paper's figure layout: the four components of ``q`` (left) and of ``Q``
    (right) against time (``time``: see :func:`time_axis`). Returns the matplotlib Figure."""
    import matplotlib.pyplot as plt

    ds = member(ds, case)
    if fig is None:
        fig = plt.figure(figsize=(11, 4))
    axl, axr = fig.subplots(1, 2, sharex=True)
    x, label = time_axis(ds, time)
    for k in range(4):
        axl.plot(x, ds["q"].values[:, k], label=f"q{k}")
        axr.plot(x, ds["Q"].values[:, k], label=f"Q{k}")
    qu = ds["Q"].attrs.get("units", "")
    axl.set_title("attitude quaternion q (B relative to S)")
    axr.set_title("conjugate momentum Q")
    axl.set_ylabel(_unit_label("q", "1"))
    axr.set_ylabel(_unit_label("Q", qu))
    for ax in (axl, axr):
        ax.set_xlabel(label)
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
    return _finish(fig, x)


def plot_attitude(ds, case=None, unit="degree", fig=None, time="auto"):
    """Euler angles against time, unwrapped (continuous through +-180 degrees): the 3-1-3
    angles of ``q`` and, with an orbit, roll, pitch and yaw relative to the orbital frame.
    Returns the Figure."""
    import matplotlib.pyplot as plt

    ds = member(ds, case)
    acc = ds.orbatt
    panels = [("euler_313", EULER_313_LABELS, "3-1-3 Euler angles (B relative to S)")]
    if "euler_321" in ds:
        panels.append(("euler_321", EULER_321_LABELS, "roll, pitch, yaw (B relative to O)"))
    if fig is None:
        fig = plt.figure(figsize=(6 * len(panels), 4))
    axes = np.atleast_1d(fig.subplots(1, len(panels), sharex=True))
    x, label = time_axis(ds, time)
    target = parse_unit(unit)
    for ax, (name, labels, title) in zip(axes, panels):
        rad = acc.to(name, "rad").values
        vals = np.unwrap(rad, axis=0) * float((1.0 * parse_unit("rad")).to_value(target))
        for k, lab in enumerate(labels):
            ax.plot(x, vals[:, k], label=lab)
        ax.set_title(title + ", unwrapped")
        ax.set_xlabel(label)
        ax.set_ylabel(f"angle [{unit_string(target)}]")
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
    return _finish(fig, x)


def _potential(ds):
    """The stored potential kind (``potential`` attribute, JSON), or ""."""
    try:
        return json.loads(ds.attrs.get("potential", "{}")).get("kind", "")
    except (TypeError, ValueError):
        return ""


def drift_series(ds):
    """``(values, title, ylabel)`` of the invariant a drift plot shows.

    - a potential that does not depend on time (torque-free, heavy top): the energy ``H``,
      conserved: ``|H - H0| / |H0|``;
    - a gravity gradient on a circular Keplerian orbit: the Jacobi integral
      ``J = H - n h.G`` (``n`` the mean motion, ``h`` the orbit normal, ``G`` the space
      angular momentum), conserved in the frame turning with the orbit;
    - any other orbit: the energy is not conserved (the potential depends on time), and
      the panel says so: "energy change (not conserved)".

    Relative to the initial value where it is not 0, absolute (in the energy unit) where it is.
    """
    H = np.asarray(ds["energy"].values, dtype=np.float64)
    eu = ds["energy"].attrs.get("units", "1")
    kind = _potential(ds)
    orb = _orbit(ds)
    if kind in ("torque-free", "heavy-top") or orb is None:
        X, name, sym = H, "energy H", "H"
    elif orb.get("type") == "kepler" and float(orb.get("e", 1.0)) == 0.0:
        gm = float(orb.get("gm_km3_s2", orb.get("gm")))
        a = float(orb.get("a_km", orb.get("a")))
        n = math.sqrt(gm / a**3)
        h = qt.rotate(np.asarray(ds["p"].values[0]), np.array([0.0, 0.0, 1.0]))
        G = qt.rotate(np.asarray(ds["q"].values), np.asarray(ds["g"].values))
        X, name, sym = H - n * (G @ h), "Jacobi integral J = H - n h.G", "J"
    else:
        X, name, sym = H, "energy change (not conserved)", "H"
    dX = np.abs(X - X[0])
    if abs(X[0]) > 0:
        return dX / abs(X[0]), f"{name}: |{sym} - {sym}0| / |{sym}0|", "relative change (dimensionless)"
    return dX, f"{name}: |{sym} - {sym}0|", _unit_label("absolute change", eu)


def plot_drift(ds, case=None, fig=None, time="auto"):
    """Drift of the invariants on log axes: the energy or the Jacobi integral, or the energy
    change where nothing is conserved (:func:`drift_series`), ``| |q| - 1 |`` and the drift
    of ``q.Q`` from its initial value (the paper's printed data start at -9.7e-8). Exact
    zeros are gaps (the first sample of a drift is one), counted in the panel's title; the
    scenario's impulses are marked (they change the energy on purpose). Returns the Figure."""
    import matplotlib.pyplot as plt

    ds = member(ds, case)
    if fig is None:
        fig = plt.figure(figsize=(13, 3.6))
    axes = fig.subplots(1, 3, sharex=True)
    x, label = time_axis(ds, time)
    qQ = ds["qQ"].values
    series = [drift_series(ds),
              (np.abs(ds["q_norm_error"].values), "norm constraint | |q| - 1 |", _unit_label("| |q| - 1 |", "1")),
              (np.abs(qQ - qQ[0]), "constraint q.Q: |q.Q - (q.Q)0|",
               _unit_label("|q.Q - (q.Q)0|", ds["qQ"].attrs.get("units", "1")))]
    for ax, (y, title, ylabel) in zip(axes, series):
        y, zeros = log_values(y)
        ax.semilogy(x, y, color="tab:blue")
        ax.set_title(title + (f"\n(exactly 0 at {zeros} of {y.size} samples: gaps)" if zeros else ""),
                     fontsize="medium")
        ax.set_xlabel(label)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3, which="both")
    if mark_impulses(axes, ds, time):  # said in the title: a legend would cover the data
        axes[0].set_title(axes[0].get_title() + "\nred dotted: impulse (Delta v, [[orbit.impulses]])",
                          fontsize="medium")
    return _finish(fig, x)

"""The quick plots of an orbatt Dataset (also as ``ds.orbatt.plot_state()`` etc.): the paper's
figure layout, Euler angles, and the drift of the invariants. matplotlib is imported only
when a plot is drawn.

Every axis is labelled with its quantity and unit. Time is drawn as UTC dates when the
Dataset has an epoch, in orbits when it has an orbit (and no epoch), else in its own unit
(``time=`` chooses). Angles are unwrapped (no jumps of 360 degrees). Log axes draw exact
zeros at the axis floor rather than leaving gaps.
"""
from __future__ import annotations

import json
import math

import numpy as np

from .. import quaternion as qt
from ..units import parse_unit, unit_string
from .build import EULER_313_LABELS, EULER_321_LABELS
from .timeaxis import elapsed_unit, elapsed_values

__all__ = ["plot_state", "plot_attitude", "plot_drift", "time_axis", "drift_series"]

#: choices of the ``time`` argument of the plots
TIME_AXES = ("auto", "utc", "orbits", "time")


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


def time_axis(ds, time="auto"):
    """``(values, label)`` of the time axis of a plot.

    Parameters
    ----------
    ds : xarray.Dataset
    time : {"auto", "utc", "orbits", "time"}
        ``"utc"``: dates (numpy datetime64, UTC) from the epoch; ``"orbits"``: time over the
        orbital period; ``"time"``: the ``elapsed`` coordinate in its unit (s, or dimensionless). ``"auto"``: UTC
        with an epoch, else orbits with an orbit, else time.
    """
    if time not in TIME_AXES:
        raise ValueError(f"time: {time!r} is not one of {TIME_AXES}")
    t = elapsed_values(ds)
    epoch = ds.orbatt.epoch
    period = orbit_period(ds)
    if time == "auto":
        time = "utc" if epoch is not None else "orbits" if period else "time"
    if time == "utc":
        if epoch is None:
            raise ValueError("time: 'utc' needs an epoch; this Dataset has none")
        return ds.orbatt.times().utc.datetime64, f"UTC (from {epoch.utc.isot[:19]})"
    if time == "orbits":
        if not period:
            raise ValueError("time: 'orbits' needs an orbit; this Dataset has none")
        return t / period, "time [orbits]"
    units = elapsed_unit(ds)
    return t, ("time (dimensionless)" if units == "1" else f"elapsed time [{unit_string(parse_unit(units))}]")


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


def _log_floor(y):
    """``y`` with exact zeros raised to the axis floor (a tenth of the smallest positive
    value, or 1e-18), so that a log axis has no gaps; non-finite values kept."""
    y = np.asarray(y, dtype=np.float64)
    pos = y[np.isfinite(y) & (y > 0)]
    floor = pos.min() / 10.0 if pos.size else 1e-18
    return np.where(y == 0.0, floor, y)


def plot_drift(ds, case=None, fig=None, time="auto"):
    """Drift of the invariants on log axes: the energy or the Jacobi integral, or the energy
    change where nothing is conserved (:func:`drift_series`), ``| |q| - 1 |`` and the drift
    of ``q.Q`` from its initial value (the paper's printed data start at -9.7e-8). Exact
    zeros are drawn at the axis floor. Returns the Figure."""
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
        ax.semilogy(x, _log_floor(y))
        ax.set_title(title, fontsize="medium")
        ax.set_xlabel(label)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3, which="both")
    return _finish(fig, x)

"""The engineering figures of a result (issue 26 §4), one matplotlib Figure each:
``pointing``, ``rates``, ``wheels``, ``torques`` and ``drift``; which of them a Dataset calls
for is :func:`orbatt.dataset.figure_data.choose_figures`, and :func:`draw` draws one by name.
matplotlib is imported only when a figure is drawn.

Conventions: angles in degrees, rates in deg/s, wheel speeds in rpm, momenta in N m s,
torques in N m, dipoles in A m^2 (a dimensionless problem keeps its own units); the pointing
error and the torque magnitudes on log axes; eclipses (``shadow`` < 1) shaded grey on every
time axis; every axis labelled with its quantity and unit and every line in a legend. An
ensemble (a ``case`` dimension) draws every case - up to :data:`ENSEMBLE_LINES` cases as
thin lines, more as the median and the band between the 5 % and 95 % quantiles and the
envelope, which the axis title says - and leaves out the per-axis panels.
"""
from __future__ import annotations

import numpy as np

from .figure_data import (FIGURES, eclipse_intervals, log_floor, pointing_error, rate_to_orbital_frame,
                          reference_rates, thresholds, torque_terms, unit_factor, values_in,
                          wheel_limits)
from .plots import plot_drift, time_axis

__all__ = ["ENSEMBLE_LINES", "LOG_DECADES", "EULER_PANEL_MAX_DEG", "draw", "plot_pointing", "plot_rates",
           "plot_wheels", "plot_torques"]

#: an ensemble with more cases than this is drawn as a median and bands instead of a line per case
ENSEMBLE_LINES = 200

#: a log axis (pointing error, torques) shows this fraction of its largest value and above
LOG_DECADES = 1e-8
#: the pointing figure draws roll, pitch and yaw of the error only while the error stays below this (deg)
EULER_PANEL_MAX_DEG = 90.0

_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive")
_AXES = ("x", "y", "z")
_TORQUE_LABELS = {"torque": "total external", "torque_control": "control"}
_TORQUE_STYLES = {"torque": ("black", 1.6), "torque_control": ("tab:red", 1.2)}


def _new(fig, rows, figsize):
    import matplotlib.pyplot as plt

    if fig is None:
        fig = plt.figure(figsize=figsize)
    axes = np.atleast_1d(fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0])
    return fig, list(axes)


def _cases(ds):
    return ds.sizes["case"] if "case" in ds.dims else 0


def _series(ax, x, y, *, label, color=None, lw=1.2, log=False):
    """Draw ``y`` (``(time,)``, or ``(case, time)`` for an ensemble) against ``x``: one line, a
    thin line per case, or (more than :data:`ENSEMBLE_LINES` cases) the median, the 5-95 %
    band and the envelope. Returns a note for the axis title ("" for one run)."""
    y = np.asarray(y, dtype=np.float64)
    if log:
        y = log_floor(y)
    if y.ndim == 1:
        ax.plot(x, y, label=label, color=color, lw=lw)
        return ""
    n = y.shape[0]
    if n <= ENSEMBLE_LINES:
        lines = ax.plot(x, y.T, color=color, lw=0.6, alpha=max(0.15, min(0.8, 8.0 / n)))
        lines[0].set_label(f"{label} ({n} cases)")
        return f"{n} cases, one line each"
    lo, p5, med, p95, hi = np.nanquantile(y, [0.0, 0.05, 0.5, 0.95, 1.0], axis=0)
    ax.fill_between(x, lo, hi, color=color, alpha=0.12, lw=0, label=f"{label}: envelope")
    ax.fill_between(x, p5, p95, color=color, alpha=0.3, lw=0, label=f"{label}: 5-95 %")
    ax.plot(x, med, color=color, lw=lw, label=f"{label}: median")
    return f"{n} cases (over {ENSEMBLE_LINES}: median and bands)"


def _shade_eclipses(axes, ds, x):
    spans = eclipse_intervals(ds, x)
    for ax in axes:
        for k, (a, b, umbra) in enumerate(spans):
            ax.axvspan(a, b, color="0.35" if umbra else "0.6", alpha=0.18, lw=0,
                       label="eclipse (shadow < 1)" if k == 0 else None)
    return bool(spans)


def _finish(fig, axes, ds, x, xlabel, title):
    shaded = _shade_eclipses(axes, ds, x)
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        handles, labels = ax.get_legend_handles_labels()
        if labels:
            ax.legend(loc="best", fontsize="small", framealpha=0.8)
    axes[-1].set_xlabel(xlabel)
    name = str(ds.attrs.get("title", "")).removeprefix("orbatt: ")
    fig.suptitle((f"{name}: {title}" if name else title) + (" (grey: eclipse)" if shaded else ""))
    if np.issubdtype(np.asarray(x).dtype, np.datetime64):
        fig.autofmt_xdate()
    fig.tight_layout()
    return fig


def _log_view(ax):
    """Keep a log axis to :data:`LOG_DECADES` below its largest value: round-off (a torque of
    1e-35 N m, an error of 1e-14 deg at an exactly aligned start) stays below the view."""
    top = max((np.nanmax(np.asarray(line.get_ydata(), dtype=float)) for line in ax.get_lines()), default=np.nan)
    if np.isfinite(top) and top > 0:
        ax.set_ylim(bottom=max(ax.get_ylim()[0], top * LOG_DECADES))


def plot_pointing(ds, fig=None, time="auto"):
    """The pointing error (:func:`orbatt.dataset.figure_data.pointing_error`) on a log axis in
    degrees, with the scenario's ``[sweep] settling_angle`` where it has one; below it (one
    run, not Sun pointing, an error within :data:`EULER_PANEL_MAX_DEG`) the roll, pitch and yaw
    of the error.

    Parameters
    ----------
    ds : xarray.Dataset
        A run or an ensemble with a pointing reference.
    fig : matplotlib.figure.Figure, optional
    time : {"auto", "utc", "orbits", "time"}
        The time axis (:func:`orbatt.dataset.plots.time_axis`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    err = pointing_error(ds)
    if err is None:
        raise ValueError("pointing: this Dataset has no pointing reference (no PD target, no orbital frame)")
    angle, title, rpy = err
    small = bool(np.nanmax(angle, initial=0.0) <= np.radians(EULER_PANEL_MAX_DEG))
    panels = 2 if rpy is not None and small and not _cases(ds) else 1
    fig, axes = _new(fig, panels, (10, 3.2 + 2.6 * (panels - 1)))
    x, xlabel = time_axis(ds, time)
    note = _series(axes[0], x, np.degrees(angle), label="pointing error", color="tab:blue", log=True)
    settle = thresholds(ds)["settling_angle"]
    if settle is not None:
        axes[0].axhline(np.degrees(settle), color="tab:red", ls="--", lw=1.0,
                        label=f"settling threshold ([sweep] settling_angle) = {np.degrees(settle):.3g} deg")
    axes[0].set_yscale("log")
    _log_view(axes[0])
    axes[0].set_ylabel("pointing error [deg]")
    if rpy is not None and not small and not _cases(ds):
        note = f"above {EULER_PANEL_MAX_DEG:g} deg: no roll/pitch/yaw panel"
    axes[0].set_title(title + (f"; {note}" if note else ""), fontsize="medium")
    if panels == 2:
        for k, lab in enumerate(("roll", "pitch", "yaw")):
            axes[1].plot(x, np.degrees(rpy[..., k]), label=lab, color=_COLORS[k], lw=1.0)
        axes[1].set_ylabel("error angle [deg]")
        axes[1].set_title("3-2-1 error angles (roll, pitch, yaw)", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "pointing")


def plot_rates(ds, fig=None, time="auto", threshold=None):
    """The body rate: ``|omega|`` (log axis where it spans more than two decades), the rate
    relative to the orbital frame (runs held on it) and, for one run, the body components, in
    deg/s; dashed: the detumble threshold (``[sweep] detumble_rate`` or ``threshold``) and, for
    B-dot, twice the mean motion (its steady state).

    Parameters
    ----------
    ds : xarray.Dataset
    fig : matplotlib.figure.Figure, optional
    time : {"auto", "utc", "orbits", "time"}
    threshold : astropy.units.Quantity, optional
        A detumble threshold (an angular velocity) drawn as a dashed line; the scenario's
        ``[sweep] detumble_rate`` is drawn without it.

    Returns
    -------
    matplotlib.figure.Figure
    """
    w, unit = values_in(ds, "omega", "degree s^-1")
    unit_label = "deg/s" if unit == "degree s^-1" else unit
    mag = np.linalg.norm(w, axis=-1)
    panels = 1 if _cases(ds) else 2
    fig, axes = _new(fig, panels, (10, 3.2 + 2.6 * (panels - 1)))
    x, xlabel = time_axis(ds, time)
    note = _series(axes[0], x, mag, label="|omega|", color="black", lw=1.4)
    rel = rate_to_orbital_frame(ds)
    if rel is not None:
        rel = np.linalg.norm(rel, axis=-1) * unit_factor(ds, "omega", "degree s^-1")[0]
        _series(axes[0], x, rel, label="|omega| relative to the orbital frame", color="tab:purple", lw=1.0)
        mag = np.concatenate([np.ravel(mag), np.ravel(rel)])
    pos = mag[np.isfinite(mag) & (mag > 0)]
    log = pos.size > 0 and pos.max() > 100.0 * pos.min()
    refs = reference_rates(ds)
    if threshold is not None:
        refs.insert(0, (float(threshold.to_value("rad/s")), "detumble threshold"))
    for k, (r, lab) in enumerate(refs):
        value = np.degrees(r) if unit_label == "deg/s" else r
        axes[0].axhline(value, color=_COLORS[3 + k], ls="--", lw=1.0, label=f"{lab} = {value:.3g} {unit_label}")
    if log:
        axes[0].set_yscale("log")
    axes[0].set_ylabel(f"|omega| [{unit_label}]")
    axes[0].set_title("magnitude of the body rate" + (f"; {note}" if note else ""), fontsize="medium")
    if panels == 2:
        for k in range(3):
            axes[1].plot(x, w[..., k], label=f"omega_{_AXES[k]}", color=_COLORS[k], lw=1.0)
        axes[1].set_ylabel(f"omega [{unit_label}]")
        axes[1].set_title("body components", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "rates")


def plot_wheels(ds, fig=None, time="auto"):
    """The reaction wheels: speed relative to the body (rpm) with ``+-max_speed``, axial
    momentum (N m s) and motor torque (N m) with ``+-max_torque``, a colour per wheel (limits
    from the stored scenario, :func:`orbatt.dataset.figure_data.wheel_limits`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    panels = [("wheel_speed", "rpm", "speed"), ("wheel_momentum", "N m s", "momentum"),
              ("wheel_torque", "N m", "motor torque")]
    panels = [p for p in panels if p[0] in ds]
    fig, axes = _new(fig, len(panels), (10, 2.6 * len(panels) + 0.8))
    x, xlabel = time_axis(ds, time)
    limits = wheel_limits(ds)
    labels = [f"wheel {k + 1}" + (f" {ax}" if ax else "") for k, ax in enumerate(_wheel_axes(ds))]
    notes = []
    for ax, (name, unit, what) in zip(axes, panels):
        v, shown = values_in(ds, name, unit)
        for k in range(v.shape[-1]):
            notes.append(_series(ax, x, v[..., k], label=labels[k], color=_COLORS[k % len(_COLORS)], lw=1.0))
        ax.set_ylabel(f"{what} [{shown}]")
        ax.set_title(f"{ds[name].attrs.get('long_name', name)}", fontsize="medium")
        if limits is not None and name != "wheel_momentum":
            lim = limits[0] * 60.0 / (2.0 * np.pi) if name == "wheel_speed" else limits[1]
            if shown == unit:
                for value in sorted(set(np.round(lim[np.isfinite(lim)], 12))):
                    ax.axhline(value, color="0.2", ls="--", lw=1.0,
                               label=f"max_{what.split()[-1]} = +-{value:.4g} {unit}")
                    ax.axhline(-value, color="0.2", ls="--", lw=1.0)
    if notes and notes[0]:
        axes[0].set_title(axes[0].get_title() + f"; {notes[0]}", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "wheels")


def _wheel_axes(ds):
    if "wheel_axis" not in ds:
        return [""] * ds.sizes["wheel"]
    out = []
    for a in np.asarray(ds["wheel_axis"].values):
        k = int(np.argmax(np.abs(a)))
        out.append(f"(body {'-' if a[k] < 0 else '+'}{_AXES[k]})" if abs(abs(a[k]) - 1.0) < 1e-9 else
                   f"({np.round(a, 3).tolist()})")
    return out


def plot_torques(ds, fig=None, time="auto"):
    """The torque budget: the magnitude (N m, log axis) of each external torque term, of their
    sum and of the control torque; below it the B-dot dipole (A m^2) with ``+-max_dipole``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .figure_data import control_law

    terms = torque_terms(ds)
    if "torque" in terms and len([n for n in terms if n not in ("torque", "torque_control")]) < 2:
        terms.remove("torque")  # one external term: the total is that term
    dipole = "dipole_control" in ds and not _cases(ds)
    fig, axes = _new(fig, 2 if dipole else 1, (10, 3.6 + (2.6 if dipole else 0)))
    x, xlabel = time_axis(ds, time)
    notes = []
    for k, name in enumerate(terms):
        v, unit = values_in(ds, name, "N m")
        label = _TORQUE_LABELS.get(name, name[len("torque_"):].replace("_", " "))
        color, lw = _TORQUE_STYLES.get(name, (_COLORS[k % len(_COLORS)], 1.0))
        notes.append(_series(axes[0], x, np.linalg.norm(v, axis=-1), label=label, color=color, lw=lw, log=True))
    axes[0].set_yscale("log")
    _log_view(axes[0])
    axes[0].set_ylabel(f"|torque| [{unit}]" if terms else "|torque|")
    note = f"; {notes[0]}" if notes and notes[0] else ""
    axes[0].set_title(f"torque budget: magnitude of each term (body frame){note}", fontsize="medium")
    if dipole:
        m, unit = values_in(ds, "dipole_control", "A m^2")
        for k in range(3):
            axes[1].plot(x, m[..., k], label=f"m_{_AXES[k]}", color=_COLORS[k], lw=0.8)
        ctrl = control_law(ds) or {}
        if ctrl.get("max_dipole_A_m2"):
            lim = float(ctrl["max_dipole_A_m2"])
            axes[1].axhline(lim, color="0.2", ls="--", lw=1.0, label=f"max_dipole = +-{lim:.3g} A m^2")
            axes[1].axhline(-lim, color="0.2", ls="--", lw=1.0)
        axes[1].set_ylabel(f"dipole [{unit}]")
        axes[1].set_title("B-dot magnetic dipole (body components)", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "torques")


def _plot_drift(ds, fig=None, time="auto"):
    if _cases(ds):
        raise ValueError("drift: an ensemble's cases each have their own invariant; draw one case: "
                         "ds.isel(case=k).orbatt.plot_drift()")
    return plot_drift(ds, fig=fig, time=time)


_DRAW = {"pointing": plot_pointing, "rates": plot_rates, "wheels": plot_wheels, "torques": plot_torques,
         "drift": _plot_drift}


def draw(ds, figure, fig=None, time="auto"):
    """Draw ``figure`` (one of :data:`orbatt.dataset.figure_data.FIGURES`) of ``ds``.

    Every figure but ``drift`` draws every case of an ensemble; ``drift`` refuses one (each case
    has its own invariant: draw ``ds.isel(case=k)``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if figure not in _DRAW:
        raise ValueError(f"figure: {figure!r} is not one of {FIGURES}")
    return _DRAW[figure](ds, fig=fig, time=time)

"""The engineering figures of a result (issue 26 §4, issue 35 §2), one matplotlib Figure each:
``pointing``, ``orbit`` (a binary), ``rates``, ``wheels``, ``torques`` and ``drift``; which of
them a Dataset calls for is :func:`orbatt.dataset.figure_data.choose_figures`, and :func:`draw`
draws one by name. matplotlib is imported only when a figure is drawn.

Conventions: angles in degrees, rates in deg/s, wheel speeds in rpm, momenta in N m s,
torques in N m, dipoles in A m^2 (a dimensionless problem keeps its own units); roll, pitch
and yaw as the Dataset's ``euler_321`` defines them, each line named with its axis; the
torque magnitudes (and a pointing error or a rate spanning over two decades) on log axes,
where a zero is a gap, said in the line's label; a pointing error never above 180 deg; each
torque term in its own colour in every figure (:data:`TORQUE_COLORS`); limits drawn only where
the data come near them; eclipses (``shadow`` < 1) shaded grey and impulses marked on every
time axis; every axis labelled with its quantity and unit, every line in a legend beside the
axis (never over the data). An ensemble (a ``case`` dimension) draws every case - up to
:data:`ENSEMBLE_LINES` cases as thin lines, more as the median and the band between the 5 %
and 95 % quantiles and the envelope, which the axis title says - and leaves out the per-axis
panels.
"""
from __future__ import annotations

import numpy as np

from .figure_data import (FIGURES, eclipse_intervals, log_values, mode_intervals, pointing_error,
                          rate_to_orbital_frame, reference_rates, thresholds, torque_terms, unit_factor, values_in,
                          wheel_gyroscopic, wheel_limits)
from .plots import mark_impulses, plot_drift, time_axis, time_values

__all__ = ["ENSEMBLE_LINES", "LOG_DECADES", "EULER_PANEL_MAX_DEG", "LIMIT_SHOWN", "TORQUE_COLORS", "draw", "plot_knowledge",
           "plot_pointing", "plot_rates", "plot_wheels", "plot_torques", "plot_orbit", "shade_modes", "MODE_SHADES"]

#: an ensemble with more cases than this is drawn as a median and bands instead of a line per case
ENSEMBLE_LINES = 200

#: a log axis (pointing error, torques) shows this fraction of its largest value and above
LOG_DECADES = 1e-8
#: the pointing figure draws roll, pitch and yaw of the error only while the error stays below this (deg)
EULER_PANEL_MAX_DEG = 90.0
#: a wheel limit (+-max_speed, +-max_torque) is drawn where the wheels reach this fraction of it;
#: below, the panel's title states it and the axis keeps to the data
LIMIT_SHOWN = 0.5
#: a wheel panel whose largest value is this many times its median magnitude (a transient over a
#: steady state) gets a symmetric log axis, linear about the steady state
SYMLOG_SPREAD = 30.0

#: the colours of the data series, one per wheel or component
_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan")
#: the reference lines (thresholds, limits): colours no series takes
_REFERENCE_COLORS = ("tab:red", "0.25", "goldenrod")
_AXES = ("x", "y", "z")
#: each torque term's colour, the same in every figure (others take the colours left)
TORQUE_COLORS = {"torque": "black", "torque_control": "tab:red", "torque_gravity_gradient": "tab:blue",
                 "torque_drag": "tab:orange", "torque_srp": "goldenrod", "torque_magnetic": "tab:green",
                 "torque_constant": "tab:brown", "wheel_gyroscopic": "tab:purple"}
_TORQUE_LABELS = {"torque": "total external", "torque_control": "control",
                  "wheel_gyroscopic": "wheels' gyroscopic omega x h"}


def _new(fig, rows, figsize):
    import matplotlib.pyplot as plt

    if fig is None:
        fig = plt.figure(figsize=figsize)
    axes = np.atleast_1d(fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0])
    return fig, list(axes)


def _cases(ds):
    return ds.sizes["case"] if "case" in ds.dims else 0


def _series(ax, x, y, *, label, color=None, lw=1.2, log=False, **style):
    """Draw ``y`` (``(time,)``, or ``(case, time)`` for an ensemble) against ``x``: one line, a
    thin line per case, or (more than :data:`ENSEMBLE_LINES` cases) the median, the 5-95 %
    band and the envelope. On a log axis values at or below 0 are gaps, and the label says how
    many (:func:`orbatt.dataset.figure_data.log_values`). Returns a note for the axis title
    ("" for one run)."""
    y = np.asarray(y, dtype=np.float64)
    alpha = style.pop("alpha", None)
    if log:
        y, zeros = log_values(y)
        if zeros:
            label = f"{label} (0 at {zeros} of {y.size} samples: gaps)"
    if y.ndim == 1:
        ax.plot(x, y, label=label, color=color, lw=lw, alpha=alpha, **style)
        return ""
    n = y.shape[0]
    if n <= ENSEMBLE_LINES:
        lines = ax.plot(x, y.T, color=color, lw=0.6 * lw / 1.2, alpha=max(0.15, min(0.8, 8.0 / n)) * (alpha or 1.0),
                        **style)
        lines[0].set_label(f"{label} ({n} cases)")
        return f"{n} cases, one line each"
    lo, p5, med, p95, hi = np.nanquantile(y, [0.0, 0.05, 0.5, 0.95, 1.0], axis=0)
    ax.fill_between(x, lo, hi, color=color, alpha=0.12, lw=0, label=f"{label}: envelope")
    ax.fill_between(x, p5, p95, color=color, alpha=0.3, lw=0, label=f"{label}: 5-95 %")
    ax.plot(x, med, color=color, lw=lw, label=f"{label}: median", **style)
    return f"{n} cases (over {ENSEMBLE_LINES}: median and bands)"


def _shade_eclipses(axes, ds, x):
    spans = eclipse_intervals(ds, x)
    for ax in axes:
        for k, (a, b, umbra) in enumerate(spans):
            ax.axvspan(a, b, color="0.35" if umbra else "0.6", alpha=0.18, lw=0,
                       label="eclipse (shadow < 1)" if k == 0 else None)
    return bool(spans)


#: the shades of the modes of a sequence (flag value k: colour k, cycling), light enough for the
#: curves on them
MODE_SHADES = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#bcbd22", "#17becf")


def shade_modes(axes, ds, time="auto"):
    """Shade each interval of the flight software's modes (:func:`mode_intervals`: from the
    Dataset's ``mode`` and its CF ``flag_meanings``) on every axis, one colour per mode, the
    legend naming them (``mode: NAME``); each span's ``gid`` is ``"mode k"``. Returns the
    intervals shaded."""
    spans = mode_intervals(ds)
    for ax in axes:
        named = set()
        for iv in spans:
            a, b = time_values(ds, np.array([iv.start, iv.end]), time)
            ax.axvspan(a, b, color=MODE_SHADES[iv.mode % len(MODE_SHADES)], alpha=0.10, lw=0, zorder=0,
                       gid=f"mode {iv.mode}", label=f"mode: {iv.name}" if iv.mode not in named else None)
            named.add(iv.mode)
    return spans


def legend_outside(ax):
    """The axis' legend to the right of it, where it covers no data (none without labels)."""
    handles, labels = ax.get_legend_handles_labels()
    if labels:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize="small",
                  framealpha=0.9)


def _finish(fig, axes, ds, x, xlabel, title, time="auto"):
    modes = shade_modes(axes, ds, time)
    shaded = _shade_eclipses(axes, ds, x)
    mark_impulses(axes, ds, time)
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        legend_outside(ax)
    axes[-1].set_xlabel(xlabel)
    name = str(ds.attrs.get("title", "")).removeprefix("orbatt: ")
    fig.suptitle((f"{name}: {title}" if name else title) + (" (grey: eclipse)" if shaded else "")
                 + (" (shaded: modes)" if modes else ""))
    if np.issubdtype(np.asarray(x).dtype, np.datetime64):
        fig.autofmt_xdate()
    fig.tight_layout()
    return fig


def _log_view(ax, top=None):
    """Keep a log axis to :data:`LOG_DECADES` below its largest value: round-off (a torque of
    1e-35 N m, an error of 1e-14 deg at an exactly aligned start) stays below the view; and
    below ``top`` where given (a rotation angle is at most 180 deg)."""
    high = max((np.nanmax(np.asarray(line.get_ydata(), dtype=float), initial=-np.inf) for line in ax.get_lines()
                if np.isfinite(np.asarray(line.get_ydata(), dtype=float)).any()), default=np.nan)
    if np.isfinite(high) and high > 0:
        ax.set_ylim(bottom=max(ax.get_ylim()[0], high * LOG_DECADES))
    if top is not None and ax.get_ylim()[1] > top:
        ax.set_ylim(top=top)


def plot_pointing(ds, fig=None, time="auto"):
    """The pointing error (:func:`orbatt.dataset.figure_data.pointing_error`) in degrees - on a
    log axis where it spans more than two decades, else a linear one, and never above 180 deg
    (a rotation angle) - with the scenario's ``[sweep] settling_angle`` where it has one; below
    it (one run, not Sun pointing, an error within :data:`EULER_PANEL_MAX_DEG`) the three angles
    of the error, each labelled with the axis it turns about and the sequence stated on the
    panel: roll, pitch, yaw as the Dataset's ``euler_321`` defines them.

    Parameters
    ----------
    ds : xarray.Dataset
        A run or an ensemble with a pointing reference.
    fig : matplotlib.figure.Figure, optional
    time : {"auto", "utc", "orbits", "time", "elapsed"}
        The time axis (:func:`orbatt.dataset.plots.time_axis`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    err = pointing_error(ds)
    if err is None:
        raise ValueError("pointing: this Dataset has no pointing reference (no PD target, no orbital frame)")
    angle, title, rpy = err.angle, err.title, err.components
    small = bool(np.nanmax(angle, initial=0.0) <= np.radians(EULER_PANEL_MAX_DEG))
    panels = 2 if rpy is not None and small and not _cases(ds) else 1
    fig, axes = _new(fig, panels, (11, 3.4 + 2.8 * (panels - 1)))
    x, xlabel = time_axis(ds, time)
    deg = np.degrees(angle)
    pos = deg[np.isfinite(deg) & (deg > 0)]
    log = pos.size > 0 and pos.max() > 100.0 * np.percentile(pos, 5)
    note = _series(axes[0], x, deg, label="pointing error", color="tab:blue", log=log)
    settle = thresholds(ds)["settling_angle"]
    if settle is not None:
        axes[0].axhline(np.degrees(settle), color="tab:red", ls="--", lw=1.0,
                        label=f"settling threshold ([sweep] settling_angle) = {np.degrees(settle):.3g} deg")
    if log:
        axes[0].set_yscale("log")
        _log_view(axes[0], top=180.0)
    else:
        axes[0].set_ylim(0.0, min(180.0, max(axes[0].get_ylim()[1], 1e-300)))
    axes[0].set_ylabel("pointing error [deg]")
    if rpy is not None and not small and not _cases(ds):
        note = f"above {EULER_PANEL_MAX_DEG:g} deg: no roll/pitch/yaw panel"
    axes[0].set_title(title + (f"; {note}" if note else ""), fontsize="medium")
    if panels == 2:
        for k, lab in enumerate(err.labels):
            axes[1].plot(x, np.degrees(rpy[..., k]), label=lab, color=_COLORS[k], lw=1.0)
        axes[1].set_ylabel("error angle [deg]")
        axes[1].set_title(err.definition, fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "pointing", time)


def plot_rates(ds, fig=None, time="auto", threshold=None):
    """The body rate: ``|omega|`` (log axis where it spans more than two decades), the rate
    relative to the orbital frame (runs held on it) and, for one run, the body components, in
    deg/s; dashed: the detumble threshold (``[sweep] detumble_rate`` or ``threshold``) and, for
    B-dot, twice the mean motion (its steady state).

    Parameters
    ----------
    ds : xarray.Dataset
    fig : matplotlib.figure.Figure, optional
    time : {"auto", "utc", "orbits", "time", "elapsed"}
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
    rel = rate_to_orbital_frame(ds)
    if rel is not None:
        rel = np.linalg.norm(rel, axis=-1) * unit_factor(ds, "omega", "degree s^-1")[0]
    both = mag if rel is None else np.concatenate([np.ravel(mag), np.ravel(rel)])
    pos = both[np.isfinite(both) & (both > 0)]
    log = pos.size > 0 and pos.max() > 100.0 * pos.min()
    panels = 1 if _cases(ds) else 2
    fig, axes = _new(fig, panels, (11, 3.4 + 2.8 * (panels - 1)))
    x, xlabel = time_axis(ds, time)
    note = _series(axes[0], x, mag, label="|omega|", color="black", lw=1.4, log=log)
    if rel is not None:
        _series(axes[0], x, rel, label="|omega| relative to the orbital frame", color="tab:purple", lw=1.0, log=log)
    refs = reference_rates(ds)
    if threshold is not None:
        refs.insert(0, (float(threshold.to_value("rad/s")), "detumble threshold"))
    for k, (r, lab) in enumerate(refs):
        value = np.degrees(r) if unit_label == "deg/s" else r
        axes[0].axhline(value, color=_REFERENCE_COLORS[k % len(_REFERENCE_COLORS)], ls="--", lw=1.0,
                        label=f"{lab} = {value:.3g} {unit_label}")
    if log:
        axes[0].set_yscale("log")
    axes[0].set_ylabel(f"|omega| [{unit_label}]")
    axes[0].set_title("magnitude of the body rate" + (f"; {note}" if note else ""), fontsize="medium")
    if panels == 2:
        for k in range(3):
            axes[1].plot(x, w[..., k], label=f"omega_{_AXES[k]}", color=_COLORS[k], lw=1.0)
        axes[1].set_ylabel(f"omega [{unit_label}]")
        axes[1].set_title("body components", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "rates", time)


def plot_wheels(ds, fig=None, time="auto"):
    """The reaction wheels: speed relative to the body (rpm), axial momentum (N m s) and motor
    torque (N m), a colour per wheel. The limits ``+-max_speed`` and ``+-max_torque``
    (:func:`orbatt.dataset.figure_data.wheel_limits`) are drawn where the wheels reach
    :data:`LIMIT_SHOWN` of them, else stated in the panel's title, so that they do not flatten
    the data; a panel whose transient is :data:`SYMLOG_SPREAD` times its typical value has a
    symmetric log axis (linear about the steady state, said in the title).

    Returns
    -------
    matplotlib.figure.Figure
    """
    panels = [("wheel_speed", "rpm", "speed"), ("wheel_momentum", "N m s", "momentum"),
              ("wheel_torque", "N m", "motor torque")]
    panels = [p for p in panels if p[0] in ds]
    fig, axes = _new(fig, len(panels), (11, 2.8 * len(panels) + 0.8))
    x, xlabel = time_axis(ds, time)
    limits = wheel_limits(ds)
    labels = [f"wheel {k + 1}" + (f" {ax}" if ax else "") for k, ax in enumerate(_wheel_axes(ds))]
    notes = []
    for ax, (name, unit, what) in zip(axes, panels):
        v, shown = values_in(ds, name, unit)
        for k in range(v.shape[-1]):
            notes.append(_series(ax, x, v[..., k], label=labels[k], color=_COLORS[k % len(_COLORS)], lw=1.0))
        ax.set_ylabel(f"{what} [{shown}]")
        title = f"{ds[name].attrs.get('long_name', name)}"
        lim = ()
        if limits is not None and name != "wheel_momentum" and shown == unit:
            lim = limits[0] * 60.0 / (2.0 * np.pi) if name == "wheel_speed" else limits[1]
        ax.set_title(_limits_and_scale(ax, v, lim, f"max_{what.split()[-1]}", unit, title), fontsize="medium")
    if notes and notes[0]:
        axes[0].set_title(axes[0].get_title() + f"; {notes[0]}", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "wheels", time)


def _limits_and_scale(ax, v, limits, key, unit, title):
    """Draw each of ``limits`` (``key = +-value unit``) the data ``v`` reach :data:`LIMIT_SHOWN`
    of, state the others in the returned title (off scale: they would flatten the data), and
    give the axis a symmetric log scale where a transient is :data:`SYMLOG_SPREAD` times the
    typical value (said in the title)."""
    mag = np.abs(np.asarray(v, dtype=np.float64))
    mag = mag[np.isfinite(mag)]
    largest = float(mag.max()) if mag.size else 0.0
    limits = np.asarray(limits, dtype=np.float64)
    for value in sorted(set(np.round(limits[np.isfinite(limits)], 12))):
        if largest >= LIMIT_SHOWN * value:
            ax.axhline(value, color="0.2", ls="--", lw=1.0, label=f"{key} = +-{value:.4g} {unit}")
            ax.axhline(-value, color="0.2", ls="--", lw=1.0)
        else:
            title += f"; {key} +-{value:.4g} {unit} (largest here {largest:.2g}: off scale)"
    typical = float(np.median(mag)) if mag.size else 0.0
    if typical > 0 and largest > SYMLOG_SPREAD * typical:
        thresh = 10.0 ** np.ceil(np.log10(2.0 * typical))
        ax.set_yscale("symlog", linthresh=thresh, linscale=1.0)
        title += f"; symmetric log axis, linear within +-{thresh:.2g}"
    return title


def _wheel_axes(ds):
    if "wheel_axis" not in ds:
        return [""] * ds.sizes["wheel"]
    out = []
    for a in np.asarray(ds["wheel_axis"].values):
        k = int(np.argmax(np.abs(a)))
        out.append(f"(body {'-' if a[k] < 0 else '+'}{_AXES[k]})" if abs(abs(a[k]) - 1.0) < 1e-9 else
                   f"({np.round(a, 3).tolist()})")
    return out


def _torque_colors(names):
    """``{name: colour}``: :data:`TORQUE_COLORS`, and for terms without one the colours left."""
    free = [c for c in _COLORS if c not in TORQUE_COLORS.values()]
    out = {}
    for n in names:
        out[n] = TORQUE_COLORS.get(n) or (free.pop(0) if free else "0.5")
    return out


def plot_torques(ds, fig=None, time="auto"):
    """The torque budget: the magnitude (N m, log axis) of each external torque term, of their
    sum (drawn beneath, wide and pale, so that no term hides under it), of the control torque
    and, with reaction wheels, of their gyroscopic term ``omega x h``
    (:func:`orbatt.dataset.figure_data.wheel_gyroscopic`: what the control balances while the
    body turns with the wheels spun up), each in its own colour (:data:`TORQUE_COLORS`); a term
    that is 0 (SRP in eclipse) leaves gaps, said in its label. Below it the B-dot dipole
    (A m^2) with ``+-max_dipole``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .figure_data import control_law

    terms = torque_terms(ds)
    if "torque" in terms and len([n for n in terms if n not in ("torque", "torque_control")]) < 2:
        terms.remove("torque")  # one external term: the total is that term
    gyro = wheel_gyroscopic(ds)
    dipole = "dipole_control" in ds and not _cases(ds)
    fig, axes = _new(fig, 2 if dipole else 1, (11, 3.8 + (2.8 if dipole else 0)))
    x, xlabel = time_axis(ds, time)
    colors = _torque_colors(terms + ["wheel_gyroscopic"])
    series = [(n, values_in(ds, n, "N m")) for n in terms]
    if gyro is not None:  # after the control: dashed over it, where it balances it
        series.append(("wheel_gyroscopic", (gyro, "N m")))
    notes = []
    unit = "N m"
    for name, (v, unit) in sorted(series, key=lambda s: s[0] != "torque"):  # the total first: beneath
        label = _TORQUE_LABELS.get(name, name[len("torque_"):].replace("_", " "))
        style = ({"lw": 3.2, "alpha": 0.35} if name == "torque" else
                 {"lw": 1.2, "ls": "--"} if name == "wheel_gyroscopic" else
                 {"lw": 1.2 if name == "torque_control" else 1.0})
        notes.append(_series(axes[0], x, np.linalg.norm(v, axis=-1), label=label, color=colors[name], log=True,
                             **style))
    axes[0].set_yscale("log")
    _log_view(axes[0])
    axes[0].set_ylabel(f"|torque| [{unit}]" if series else "|torque|")
    note = next((n for n in notes if n), "")
    balance = ""
    if gyro is not None and "torque_control" in terms:  # tau_control = omega x h in the steady state
        ctrl = dict(series)["torque_control"][0]
        size = np.nanmedian(np.linalg.norm(ctrl, axis=-1))
        if size > 0 and np.nanmedian(np.linalg.norm(ctrl - gyro, axis=-1)) < 0.1 * size:
            balance = "; the control balances omega x h"
    axes[0].set_title("torque budget: magnitude of each term (body frame)" + balance + (f";\n{note}" if note else ""),
                      fontsize="medium")
    if dipole:
        m, unit = values_in(ds, "dipole_control", "A m^2")
        for k in range(3):
            axes[1].plot(x, m[..., k], label=f"m_{_AXES[k]}", color=_COLORS[k], lw=0.8)
        ctrl = control_law(ds) or {}
        lim = [float(ctrl["max_dipole_A_m2"])] if ctrl.get("max_dipole_A_m2") and unit == "A m^2" else []
        axes[1].set_ylabel(f"dipole [{unit}]")
        axes[1].set_title(_limits_and_scale(axes[1], m, lim, "max_dipole", "A m^2",
                                            "B-dot magnetic dipole (body components)"), fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "torques", time)


def _change_if_flat(v, name, unit):
    """``(values, label)``: ``v`` itself, or - where it changes by less than 1e-6 of its size, so
    that the ticks would need an offset like "1e-12+1.19" - its change from the first value,
    the label saying from what."""
    v = np.asarray(v, dtype=np.float64)
    ok = v[np.isfinite(v)]
    if ok.size < 2 or np.ptp(ok) >= 1e-6 * np.max(np.abs(ok)):
        return v, name
    return v - v[..., :1], f"{name} - {v.ravel()[0]:.10g} {unit}".strip()


def plot_orbit(ds, fig=None, time="auto"):
    """A binary's mutual orbit and the secondary's libration: the separation (km), the
    osculating period (h; and the mean period where the Dataset has one), and the in-plane
    libration angle (deg, :func:`orbatt.dataset.figure_data.libration_angle`), the impulses
    (``[[orbit.impulses]]``) marked on every panel.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .figure_data import libration_angle

    if "separation" not in ds:
        raise ValueError("orbit: this Dataset is not a binary's (no separation)")
    lib = libration_angle(ds)
    periods = [n for n in ("orbit_mean_period", "mean_period", "orbit_period") if n in ds]
    rows = 1 + bool(periods) + (lib is not None)
    fig, axes = _new(fig, rows, (11, 2.8 * rows + 0.8))
    x, xlabel = time_axis(ds, time)
    sep, unit = values_in(ds, "separation", "km")
    sep, shown = _change_if_flat(sep, "separation", unit)
    note = _series(axes[0], x, sep, label="separation", color="tab:blue")
    axes[0].set_ylabel(f"{shown} [{unit}]")
    axes[0].set_title("distance between the centres of mass" + (f"; {note}" if note else ""), fontsize="medium")
    k = 1
    if periods:
        flat = all(_change_if_flat(values_in(ds, n, "h")[0], "", "")[1] for n in periods)
        for j, name in enumerate(periods):
            v, punit = values_in(ds, name, "h")
            if flat:  # the period's change from its start (an equilibrium: round-off)
                v = v - v[..., :1]
            _series(axes[k], x, v, label=name.replace("_", " ") + (" (osculating)" if name == "orbit_period" else ""),
                    color=_COLORS[1 + j], lw=1.0)
        axes[k].set_ylabel(f"period change from the start [{punit}]" if flat else f"period [{punit}]")
        axes[k].set_title("period of the mutual orbit" + ("; the osculating Keplerian period about G (M1 + M2) "
                          "differs from the mean period by the bodies' oblateness" if "orbit_period" in periods
                          else ""), fontsize="medium")
        k += 1
    if lib is not None:
        _series(axes[k], x, np.degrees(lib), label="libration", color=_COLORS[2], lw=1.0)
        axes[k].set_ylabel("libration [deg]")
        axes[k].set_title("libration: body axis 1 from the line of centres, about the orbit normal "
                          "(the axis' sign not counted)", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "mutual orbit and libration", time)


def plot_knowledge(ds, fig=None, time="auto"):
    """The attitude filter's knowledge (issue 33): the knowledge error's magnitude (the rotation
    from the estimate to the truth) with three times the filter's 1-sigma (the root sum square
    of its attitude sigmas), and, for one run, each body component with its +-3 sigma band, in
    arcsec. The star tracker's outages (``star_tracker_valid`` 0) are drawn as marks.

    Parameters
    ----------
    ds : xarray.Dataset
        With ``knowledge_error`` and ``knowledge_sigma`` (a run with ``[estimator]``).
    fig : matplotlib.figure.Figure, optional
    time : {"auto", "utc", "orbits", "time", "elapsed"}

    Returns
    -------
    matplotlib.figure.Figure
    """
    if "knowledge_error" not in ds:
        raise ValueError("knowledge: the Dataset has no knowledge_error (a run with an [estimator] has)")
    e, unit = values_in(ds, "knowledge_error", "arcsec")
    sig, _ = values_in(ds, "knowledge_sigma", "arcsec")
    panels = 1 if _cases(ds) else 2
    fig, axes = _new(fig, panels, (11, 3.4 + 2.8 * (panels - 1)))
    x, xlabel = time_axis(ds, time)
    mag = np.linalg.norm(e, axis=-1)
    _series(axes[0], x, mag, label="|knowledge error|", color="black", lw=1.0)
    _series(axes[0], x, 3.0 * np.linalg.norm(sig, axis=-1), label="3 sigma (filter: root sum square of the axes)", color="tab:red", lw=1.0, ls="--")
    if "star_tracker_valid" in ds and not _cases(ds):
        out = np.asarray(ds["star_tracker_valid"].values) == 0
        if out.any():
            axes[0].plot(np.asarray(x)[out], np.zeros(int(out.sum())), "|", color="tab:orange",
                         label="star tracker outage")
    axes[0].set_ylabel(f"[{unit}]")
    axes[0].set_title("knowledge error: the rotation from the filter's estimate to the truth", fontsize="medium")
    if panels == 2:
        for k in range(3):
            axes[1].plot(x, e[..., k], label=f"error_{_AXES[k]}", color=_COLORS[k], lw=0.8)
            axes[1].fill_between(x, -3.0 * sig[..., k], 3.0 * sig[..., k], color=_COLORS[k], alpha=0.12, lw=0)
        axes[1].set_ylabel(f"[{unit}]")
        axes[1].set_title("body components, shaded: +-3 sigma of each", fontsize="medium")
    return _finish(fig, axes, ds, x, xlabel, "knowledge", time)


def _plot_drift(ds, fig=None, time="auto"):
    if _cases(ds):
        raise ValueError("drift: an ensemble's cases each have their own invariant; draw one case: "
                         "ds.isel(case=k).orbatt.plot_drift()")
    return plot_drift(ds, fig=fig, time=time)


_DRAW = {"pointing": plot_pointing, "knowledge": plot_knowledge, "rates": plot_rates, "wheels": plot_wheels, "torques": plot_torques,
         "orbit": plot_orbit, "drift": _plot_drift}


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

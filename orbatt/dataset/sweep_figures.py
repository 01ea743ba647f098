"""The figures of a sweep's per-case outputs (issue 23): each output's distribution (histogram
and empirical CDF, with its median and 95th and 99th percentiles) and the scatter of each
output against each swept parameter. ``orbatt plot SWEEP.nc -o DIR`` writes them as
``DIR/<name>-distributions.png`` and ``DIR/<name>-scatter.png`` (atomically, as every figure:
:mod:`orbatt.dataset.figure_files`).

What a review reads (issue 35 §2): per-wheel outputs (``case, wheel``: ``max_wheel_speed``) get
a distribution per wheel; the cases of each value of a grid parameter (``values = [...]`` in
``[sweep.parameters]``, e.g. two ``control.kd``) are drawn apart - a colour each, their own
percentiles, a column of their own in the scatter; values are shown in a unit that keeps the
tick labels short (deg/s, mm/s, or a power of ten in the axis label); a dimensionless output
carries no unit ``1``; legends stand beside the axes, not on the data.

A sweep with ECSS pointing indices (``ape``, ``rpe``, ``mpe``: ``docs/pointing-budgets.md``)
also gets ``DIR/<name>-budget.png``: each index's CDF over the cases with its requirement line
(``[sweep] requirement``) and the share of cases meeting it, and a bar chart of the budget
(:func:`orbatt.dataset.pointing_budget.pointing_budget`: temporal median and maximum over the
cases, the bounds of the mixed value, the requirement).
"""
from __future__ import annotations

import itertools
import json

import numpy as np

__all__ = ["SWEEP_FIGURES", "sweep_figures_of", "sweep_outputs", "sweep_wheel_outputs", "sweep_parameters", "grid_parameters",
           "display", "draw_sweep"]

#: the figures of a sweep of per-case outputs ("budget": only with pointing indices, :func:`sweep_figures_of`)
SWEEP_FIGURES = ("distributions", "scatter", "budget")
#: flags and bookkeeping, not outputs to draw or summarize
FLAGS = ("integration_failed", "tumbling", "wheel_saturated")
#: display units: a factor and a label
_DISPLAY = {"rad": (np.degrees(1.0), "deg"), "rad s^-1": (np.degrees(1.0), "deg/s"),
            "m s^-1": (1e3, "mm/s"), "m/s": (1e3, "mm/s"),
            "1": (1.0, ""), "": (1.0, "")}
#: per-wheel outputs in these units are shown in rpm
_WHEEL_DISPLAY = {"rad s^-1": (60.0 / (2.0 * np.pi), "rpm")}
#: a float parameter with at most this many distinct values and no ``sweep_parameters`` entry is a grid
GRID_MAX_VALUES = 4
_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan")
_STYLES = ("-", "--", ":", "-.")


def sweep_figures_of(ds):
    """The figures of :data:`SWEEP_FIGURES` that ``ds`` has data for (``budget``: with pointing
    indices)."""
    from .pointing_budget import index_variables

    return tuple(f for f in SWEEP_FIGURES if f != "budget" or index_variables(ds))


def sweep_outputs(ds):
    """The per-case scalar outputs of a sweep Dataset (float variables along ``case`` only,
    flags left out), in the Dataset's order."""
    return [k for k, v in ds.data_vars.items() if v.dims == ("case",) and v.dtype.kind == "f" and k not in FLAGS]


def sweep_wheel_outputs(ds):
    """The per-wheel outputs of a sweep Dataset (float variables along ``(case, wheel)``, e.g.
    ``max_wheel_speed``), in the Dataset's order."""
    return [k for k, v in ds.data_vars.items() if v.dims == ("case", "wheel") and v.dtype.kind == "f"
            and k not in FLAGS]


def sweep_parameters(ds):
    """The swept parameters: float coordinates along ``case`` only (``case`` itself left out)."""
    return [k for k, v in ds.coords.items() if v.dims == ("case",) and k != "case" and v.dtype.kind == "f"]


def _key(ds, name):
    return ds[name].attrs.get("scenario_key", name)


def grid_parameters(ds):
    """The swept parameters that take a few set values (``kind = "grid"`` in the
    ``sweep_parameters`` attribute; without it, at most :data:`GRID_MAX_VALUES` distinct
    values): their cases are drawn apart."""
    try:
        spec = json.loads(ds.attrs.get("sweep_parameters") or "{}")
    except (TypeError, ValueError):
        spec = {}
    out = []
    for name in sweep_parameters(ds):
        entry = spec.get(_key(ds, name), spec.get(name))
        values = np.unique(np.asarray(ds[name].values, dtype=float)[np.isfinite(ds[name].values)])
        if isinstance(entry, dict):
            if entry.get("kind") == "grid":
                out.append(name)
        elif 1 < values.size <= GRID_MAX_VALUES:
            out.append(name)
    return out


def _scale(x, factor, label):
    """``(factor, label)`` with a power of ten (a multiple of 3) folded into the unit where the
    values are below 0.01 or from 1e6 up (tick labels of a few digits)."""
    ok = np.abs(np.asarray(x, dtype=float) * factor)
    ok = ok[np.isfinite(ok) & (ok > 0)]
    if not ok.size:
        return factor, label
    top = float(np.max(ok))
    if 1e-2 <= top < 1e6:
        return factor, label
    exp = int(np.floor(np.log10(top) / 3.0) * 3)
    return factor * 10.0 ** -exp, f"1e{exp} {label}".strip()


def display(v, wheel=False):
    """``(values, unit label)`` of an output or parameter as drawn: angles in deg, rates in
    deg/s (wheel speeds in rpm), speeds in mm/s, times from 1e4 s in h (from 3e5 s in d), a
    power of ten folded into the unit where the values are far from 1 (:func:`_scale`); ``""``
    for a dimensionless quantity."""
    units = str(v.attrs.get("units", "")).strip()
    factor, label = (_WHEEL_DISPLAY.get(units) if wheel else None) or _DISPLAY.get(units, (1.0, units))
    x = np.asarray(v.values, dtype=float)
    if units == "s":  # long times in hours or days
        top = np.nanmax(np.abs(x), initial=0.0)
        factor, label = (1.0 / 86400.0, "d") if top >= 3e5 else (1.0 / 3600.0, "h") if top >= 1e4 else (1.0, "s")
    factor, label = _scale(x, factor, label)
    return x * factor, label


_display = display


def _axis_label(name, label):
    return f"{name} [{label}]" if label else f"{name} (dimensionless)"


def _with_unit(value, label):
    return f"{value:.4g} {label}".strip()


def _groups(ds):
    """``[(label, mask)]``: the cases of each combination of grid values (one group of every
    case without a grid parameter)."""
    n = int(ds.sizes.get("case", 0))
    grid = grid_parameters(ds)
    if not grid:
        return [("", np.ones(n, dtype=bool))]
    out = []
    values = [np.unique(np.asarray(ds[g].values, dtype=float)) for g in grid]
    for combo in itertools.product(*values):
        mask = np.ones(n, dtype=bool)
        parts = []
        for g, val in zip(grid, combo):
            mask &= np.asarray(ds[g].values, dtype=float) == val
            x, label = display(ds[g])
            shown = x[np.asarray(ds[g].values, dtype=float) == val][0]
            parts.append(f"{_key(ds, g)} = {_with_unit(shown, label)}")
        if mask.any():
            out.append((", ".join(parts), mask))
    return out


def _columns(ds, name):
    """``[(label, values over the cases)]``: one column of an output, or one per wheel."""
    v = ds[name]
    if v.dims == ("case",):
        x, label = display(v)
        return [("", x)], label
    x, label = display(v, wheel=True)
    return [(f"wheel {k + 1}", x[:, k]) for k in range(x.shape[1])], label


def _legend(ax):
    handles, labels = ax.get_legend_handles_labels()
    if labels:
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=7)


def _ticks(ax, axis="x"):
    """At most 5 ticks of plain numbers (no offset: the unit's power of ten is in the label)."""
    from matplotlib.ticker import MaxNLocator

    getattr(ax, f"{axis}axis").set_major_locator(MaxNLocator(nbins=5))
    try:
        ax.ticklabel_format(axis=axis, style="plain", useOffset=False)
    except AttributeError:  # not a ScalarFormatter
        pass
    ax.tick_params(labelsize=7)


def _distributions(ds, fig_rows):
    import matplotlib.pyplot as plt

    n = int(ds.sizes.get("case", 0))
    groups = _groups(ds)
    fig, axes = plt.subplots(max(len(fig_rows), 1), 2, figsize=(12, 2.9 * max(len(fig_rows), 1) + 0.6),
                             squeeze=False, layout="constrained")
    for r, name in enumerate(fig_rows):
        columns, label = _columns(ds, name)
        ax_h, ax_c = axes[r]
        series = [(c, g, x[mask]) for c, x in columns for g, mask in groups]
        allvals = np.concatenate([np.ravel(x[np.isfinite(x)]) for _, _, x in series]) if series else np.array([])
        bins = np.histogram_bin_edges(allvals, bins=min(50, max(5, int(np.sqrt(max(allvals.size, 1)))))) \
            if allvals.size else 10
        missing = sum(int(np.count_nonzero(~np.isfinite(x))) for _, _, x in series)
        nan_note = f"; {missing} NaN" if missing else ""
        ax_h.set_title(f"{name}: {n} cases" + (f", {len(columns)} wheels" if len(columns) > 1 else "") + nan_note,
                       fontsize=9)
        single = len(series) == 1
        for col, grp, x in series:
            ok = np.sort(x[np.isfinite(x)])
            if not ok.size:
                continue
            c, g = [cc for cc, _ in columns].index(col), [gg for gg, _ in groups].index(grp)
            # a colour per wheel and a line style per grid value, or a colour per grid value
            color, style = ((_COLORS[c % len(_COLORS)], _STYLES[g % len(_STYLES)]) if len(columns) > 1 else
                            (_COLORS[g % len(_COLORS)], "-"))
            who = ", ".join(s for s in (col, grp) if s)
            if single:
                ax_h.hist(ok, bins=bins, color=color, alpha=0.8)
            else:
                ax_h.hist(ok, bins=bins, color=color, histtype="step", lw=1.4, ls=style)
            ax_c.step(ok, np.arange(1, ok.size + 1) / ok.size, where="post", color=color, ls=style,
                      label=None if single else f"{who} ({ok.size} cases)")
            p = np.percentile(ok, [50, 95, 99])
            if single:
                for v, q, ls in zip(p, (50, 95, 99), (":", "--", "-")):
                    ax_c.axvline(v, color="tab:red", linestyle=ls, label=f"p{q} = {_with_unit(v, label)}")
            else:
                ax_c.plot(p, [0.5, 0.95, 0.99], "o", color=color, ms=4,
                          label=f"  p50, p95, p99: {p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g} {label}".rstrip())
        ax_h.set_xlabel(_axis_label(name, label), fontsize=8)
        ax_h.set_ylabel("cases", fontsize=8)
        ax_c.set_xlabel(_axis_label(name, label), fontsize=8)
        ax_c.set_ylabel("fraction of cases", fontsize=8)
        ax_c.set_ylim(0.0, 1.0)
        for ax in (ax_h, ax_c):
            _ticks(ax)
        _legend(ax_c)
    fig.suptitle(f"{ds.attrs.get('title', 'sweep')}: distributions over the cases", fontsize=10)
    return fig


def _scatter(ds, rows):
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    params = sweep_parameters(ds)
    grid = grid_parameters(ds)
    groups = _groups(ds)
    nr, nc = max(len(rows), 1), max(len(params), 1)
    fig, axes = plt.subplots(nr, nc, figsize=(2.9 * nc + 2.6, 2.5 * nr + 0.8), squeeze=False, layout="constrained")
    legend = {}
    markers = (".", "x", "+", "1")
    for r, name in enumerate(rows):
        columns, ylab = _columns(ds, name)
        for c, par in enumerate(params):
            x, xlab = display(ds[par])
            values = np.unique(x[np.isfinite(x)])
            ax = axes[r][c]
            for k, (col, y) in enumerate(columns):
                for j, (grp, mask) in enumerate(groups):
                    xs = x[mask]
                    if par in grid:  # a grid value: a column of its own, the cases spread across it
                        xs = np.searchsorted(values, xs) + np.random.default_rng(k).uniform(-0.3, 0.3, xs.size)
                    ax.plot(xs, y[mask], markers[k % len(markers)], markersize=3 if k == 0 else 4, alpha=0.6,
                            color=_COLORS[j % len(_COLORS)])
                    if grp:  # the legend: a colour per grid value, a marker per wheel
                        legend.setdefault(grp, Line2D([], [], ls="", marker=".", color=_COLORS[j % len(_COLORS)]))
                    if col:
                        legend.setdefault(col, Line2D([], [], ls="", marker=markers[k % len(markers)], color="0.3"))
            if par in grid:
                ax.set_xticks(np.arange(values.size), [f"{v:.4g}" for v in values])
                ax.set_xlim(-0.5, values.size - 0.5)
                ax.tick_params(labelsize=7)
            else:
                _ticks(ax)
            _ticks(ax, "y")
            if r == nr - 1:
                ax.set_xlabel(_axis_label(_key(ds, par), xlab), fontsize=8)
            if c == 0:
                ax.set_ylabel(_axis_label(name, ylab), fontsize=8)
    if legend:
        fig.legend(list(legend.values()), list(legend), loc="outside right upper", fontsize=7, markerscale=2)
    fig.suptitle(f"{ds.attrs.get('title', 'sweep')}: outputs against the swept parameters"
                 + (f" (a colour per {', '.join(_key(ds, g) for g in grid)})" if grid else ""), fontsize=10)
    return fig


def _budget(ds):
    """Each pointing index's CDF over the cases with its requirement, and the budget's bars."""
    import matplotlib.pyplot as plt

    from .pointing_budget import angle_display, pointing_budget

    rows = pointing_budget(ds)
    n = max(len(rows), 1)
    factor, unit = angle_display(np.concatenate([[r["max"], r["requirement"] or np.nan] for r in rows]
                                                if rows else [[]]))
    fig = plt.figure(figsize=(max(3.2 * n, 6.5) + 2.0, 6.6), layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=(1.0, 1.1))
    axes = np.atleast_1d(top.subplots(1, n, squeeze=False)[0])
    for ax, r in zip(axes, rows):
        x = np.sort(r["values"]) * factor
        if x.size:
            ax.step(x, np.arange(1, x.size + 1) / x.size, where="post", color="tab:blue")
        if r["requirement"] is not None:
            req = r["requirement"] * factor
            ax.axvline(req, color="tab:red", lw=1.4,
                       label=f"requirement {req:.4g} {unit}: {r['meeting']} of {x.size} cases")
        ax.set_title(f"{r['name']} at {r['confidence']:g}: {x.size} cases" +
                     (f"; {r['missing']} NaN" if r["missing"] else ""), fontsize=9)
        ax.set_xlabel(f"{r['name']} [{unit}]", fontsize=8)
        ax.set_ylabel("fraction of cases", fontsize=8)
        ax.set_ylim(0.0, 1.0)
        _ticks(ax)
        if r["requirement"] is not None:
            ax.legend(loc="lower right", fontsize=7)
    ax = bottom.subplots()
    names = [r["name"] for r in rows]
    pos = np.arange(len(rows))
    w = 0.35
    ax.bar(pos - w / 2, [r["median"] * factor for r in rows], w, color="tab:blue", label="temporal: median over cases")
    ax.bar(pos + w / 2, [r["max"] * factor for r in rows], w, color="tab:orange", label="temporal: worst case")
    for k, r in enumerate(rows):
        lo, hi = r["mixed"]
        ax.plot([k + w + 0.08] * 2, [lo * factor, hi * factor], color="0.2", lw=3, solid_capstyle="butt",
                label="mixed: bounds (series not stored)" if k == 0 else None)
        if r["requirement"] is not None:
            ax.hlines(r["requirement"] * factor, k - 0.45, k + 0.45, color="tab:red", lw=2,
                      label="requirement" if all(q["requirement"] is None for q in rows[:k]) else None)
    ax.set_xticks(pos, names)
    ax.set_xlim(-0.6, len(rows) - 0.2)
    ax.set_ylabel(f"index [{unit}]", fontsize=8)
    ax.set_title("budget (ensemble: worst time over the cases, not computed: each case's series is not stored)",
                 fontsize=9)
    _ticks(ax, "y")
    _legend(ax)
    fig.suptitle(f"{ds.attrs.get('title', 'sweep')}: pointing budget (ECSS-E-ST-60-10C)", fontsize=10)
    return fig


def draw_sweep(ds, figure):
    """The matplotlib figure ``figure`` (one of :data:`SWEEP_FIGURES`) of a sweep Dataset."""
    rows = sweep_outputs(ds) + sweep_wheel_outputs(ds)
    if figure == "distributions":
        return _distributions(ds, rows)
    if figure == "scatter":
        return _scatter(ds, rows)
    if figure == "budget":
        return _budget(ds)
    raise ValueError(f"figure: {figure!r} is not one of {SWEEP_FIGURES}")

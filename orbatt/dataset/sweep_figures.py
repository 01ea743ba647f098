"""The figures of a sweep's per-case outputs (issue 23): each output's distribution (histogram
and empirical CDF, with its median and 95th and 99th percentiles marked) and the scatter of
each output against each swept parameter. ``orbatt plot SWEEP.nc -o DIR`` writes them as
``DIR/<name>-distributions.png`` and ``DIR/<name>-scatter.png`` (atomically, as every figure:
:mod:`orbatt.dataset.figure_files`)."""
from __future__ import annotations

import numpy as np

__all__ = ["SWEEP_FIGURES", "sweep_outputs", "sweep_parameters", "draw_sweep"]

#: the figures of a sweep of per-case outputs
SWEEP_FIGURES = ("distributions", "scatter")
#: flags and bookkeeping, not outputs to draw or summarize
FLAGS = ("integration_failed", "tumbling", "wheel_saturated")
#: display units: a factor and a label
_DISPLAY = {"rad": (np.degrees(1.0), "deg"), "rad s^-1": (np.degrees(1.0), "deg/s")}


def sweep_outputs(ds):
    """The per-case scalar outputs of a sweep Dataset (float variables along ``case`` only,
    flags left out), in the Dataset's order."""
    return [k for k, v in ds.data_vars.items() if v.dims == ("case",) and v.dtype.kind == "f" and k not in FLAGS]


def sweep_parameters(ds):
    """The swept parameters: float coordinates along ``case`` only (``case`` itself left out)."""
    return [k for k, v in ds.coords.items() if v.dims == ("case",) and k != "case" and v.dtype.kind == "f"]


def _display(v):
    units = v.attrs.get("units", "")
    factor, label = _DISPLAY.get(units, (1.0, units))
    return np.asarray(v.values, dtype=float) * factor, label


def draw_sweep(ds, figure):
    """The matplotlib figure ``figure`` (one of :data:`SWEEP_FIGURES`) of a sweep Dataset."""
    import matplotlib.pyplot as plt

    outs = sweep_outputs(ds)
    n = int(ds.sizes.get("case", 0))
    if figure == "distributions":
        rows = max(len(outs), 1)
        fig, axes = plt.subplots(rows, 2, figsize=(10, 2.6 * rows), squeeze=False)
        for r, name in enumerate(outs):
            x, label = _display(ds[name])
            ok = np.sort(x[np.isfinite(x)])
            ax_h, ax_c = axes[r]
            title = f"{name} ({ok.size} of {n} cases; {n - ok.size} NaN)"
            if ok.size:
                ax_h.hist(ok, bins=min(50, max(5, int(np.sqrt(ok.size)))), color="tab:blue", alpha=0.8)
                ax_c.step(ok, np.arange(1, ok.size + 1) / ok.size, where="post", color="tab:blue")
                for q, style in ((50, ":"), (95, "--"), (99, "-")):
                    v = np.percentile(ok, q)
                    ax_c.axvline(v, color="tab:red", linestyle=style, label=f"p{q} = {v:.4g} {label}")
                ax_c.legend(fontsize=7, loc="lower right")
            ax_h.set_title(title, fontsize=9)
            ax_h.set_xlabel(f"{name} [{label}]")
            ax_h.set_ylabel("cases")
            ax_c.set_xlabel(f"{name} [{label}]")
            ax_c.set_ylabel("fraction of cases")
            ax_c.set_ylim(0.0, 1.0)
        fig.suptitle(f"{ds.attrs.get('title', 'sweep')}: distributions over the cases", fontsize=10)
    elif figure == "scatter":
        params = sweep_parameters(ds)
        rows, cols = max(len(outs), 1), max(len(params), 1)
        fig, axes = plt.subplots(rows, cols, figsize=(2.8 * cols + 1, 2.4 * rows + 0.6), squeeze=False)
        for r, name in enumerate(outs):
            y, ylab = _display(ds[name])
            for c, par in enumerate(params):
                x, xlab = _display(ds[par])
                ax = axes[r][c]
                ax.plot(x, y, ".", markersize=3, alpha=0.6)
                if r == rows - 1:
                    ax.set_xlabel(f"{ds[par].attrs.get('scenario_key', par)} [{xlab}]", fontsize=8)
                if c == 0:
                    ax.set_ylabel(f"{name} [{ylab}]", fontsize=8)
                ax.tick_params(labelsize=7)
        fig.suptitle(f"{ds.attrs.get('title', 'sweep')}: outputs against the swept parameters", fontsize=10)
    else:
        raise ValueError(f"figure: {figure!r} is not one of {SWEEP_FIGURES}")
    fig.tight_layout()
    return fig

"""The quick plots of an orbatt Dataset (also as ``ds.orbatt.plot_state()`` etc.): the paper's
figure layout, Euler angles, and energy and constraint drift. matplotlib is imported only
when a plot is drawn.
"""
from __future__ import annotations

import numpy as np

from ..units import parse_unit, unit_string
from .build import EULER_313_LABELS, EULER_321_LABELS

__all__ = ["plot_state", "plot_attitude", "plot_drift"]


def member(ds, case=None):
    """One member of an ensemble (``case``; default the first), or ``ds`` itself."""
    if "case" in ds.dims:
        ds = ds.isel(case=0) if case is None else ds.sel(case=case)
    return ds


def time_label(ds):
    """Axis label of ``time`` with its units (``"t"`` for dimensionless time)."""
    units = ds["time"].attrs.get("units", "")
    return "t" if units == "1" else f"t [{units}]"


def plot_state(ds, case=None, fig=None):
    """The paper's figure layout: the four components of ``q`` (left) and of ``Q``
    (right) against time. Returns the matplotlib Figure."""
    import matplotlib.pyplot as plt

    ds = member(ds, case)
    if fig is None:
        fig = plt.figure(figsize=(11, 4))
    axl, axr = fig.subplots(1, 2, sharex=True)
    t = ds["time"].values
    for k in range(4):
        axl.plot(t, ds["q"].values[:, k], label=f"q{k}")
        axr.plot(t, ds["Q"].values[:, k], label=f"Q{k}")
    qu = ds["Q"].attrs.get("units", "")
    axl.set_title("q (B relative to S)")
    axr.set_title("Q" + ("" if qu == "1" else f" [{qu}]"))
    for ax in (axl, axr):
        ax.set_xlabel(time_label(ds))
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def plot_attitude(ds, case=None, unit="degree", fig=None):
    """Euler angles against time: the 3-1-3 angles of ``q`` and, with an orbit, roll,
    pitch and yaw relative to the orbital frame. Returns the Figure."""
    import matplotlib.pyplot as plt

    ds = member(ds, case)
    acc = ds.orbatt
    panels = [("euler_313", EULER_313_LABELS, "3-1-3 angles (B relative to S)")]
    if "euler_321" in ds:
        panels.append(("euler_321", EULER_321_LABELS, "roll, pitch, yaw (B relative to O)"))
    if fig is None:
        fig = plt.figure(figsize=(6 * len(panels), 4))
    axes = np.atleast_1d(fig.subplots(1, len(panels), sharex=True))
    t = ds["time"].values
    for ax, (name, labels, title) in zip(axes, panels):
        vals = acc.to(name, unit).values
        for k, lab in enumerate(labels):
            ax.plot(t, vals[:, k], label=lab)
        ax.set_title(title)
        ax.set_xlabel(time_label(ds))
        ax.set_ylabel(f"[{unit_string(parse_unit(unit))}]")
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def plot_drift(ds, case=None, fig=None):
    """Energy and constraint drift on log axes: ``|H - H0| / |H0|`` (or ``|H - H0|`` when
    ``H0 = 0``), ``| |q| - 1 |`` and the drift of ``q.Q`` from its initial value (the paper's
    printed data start at -9.7e-8; exact zeros are not drawn). For a time-dependent
    potential ``H`` is not an invariant. Returns the Figure."""
    import matplotlib.pyplot as plt

    ds = member(ds, case)
    if fig is None:
        fig = plt.figure(figsize=(13, 3.6))
    axes = fig.subplots(1, 3, sharex=True)
    t = ds["time"].values
    H = ds["energy"].values
    dH = np.abs(H - H[0])
    rel = abs(H[0]) > 0
    series = [(dH / abs(H[0]) if rel else dH, "|H - H0| / |H0|" if rel else "|H - H0|"),
              (np.abs(ds["q_norm_error"].values), "| |q| - 1 |"),
              (np.abs(ds["qQ"].values - ds["qQ"].values[0]), "|q.Q - (q.Q)0|")]
    for ax, (y, title) in zip(axes, series):
        ax.semilogy(t, np.where(y > 0, y, np.nan))  # exact zeros left out of the log axis
        ax.set_title(title)
        ax.set_xlabel(time_label(ds))
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    return fig

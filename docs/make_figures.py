"""Make the figures of ``docs/figures/``: the paper's Figs. 1-3 from the shipped scenarios.

Arribas, Elipe & Palacios (2006), Sect. 6: each figure shows the four components of the
attitude quaternion ``q`` (left panel) and of its conjugate momentum ``Q`` (right panel)
against time. This script runs the shipped scenarios ``paper-torque-free``,
``paper-heavy-top`` and ``paper-keplerian`` exactly as shipped (``orbatt.load_scenario(name).run()``)
and draws them with ``ds.orbatt.plot_state()`` (the paper's layout), then prints the checks
that ``docs/paper-figures.md`` quotes.

Usage (from anywhere; a second or two, plus numba's compilation on a first run)::

    python docs/make_figures.py                 # writes docs/figures/paper-fig{1,2,3}-*.png
    python docs/make_figures.py --outdir /tmp/figs
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import orbatt  # noqa: E402
from orbatt.analytic import torque_free  # noqa: E402

HERE = Path(__file__).resolve().parent

#: (scenario, output file, figure title)
FIGURES = [
    ("paper-torque-free", "paper-fig1-torque-free.png",
     "Fig. 1 - torque-free body, I = (1.25, 1, 0.75), t in [0, 20] (dimensionless)"),
    ("paper-heavy-top", "paper-fig2-heavy-top.png",
     "Fig. 2 - heavy top, x_c = (1, 0, 0), Mg = 0.5, eq. (18) as printed, t in [0, 20]"),
    ("paper-keplerian", "paper-fig3-keplerian.png",
     "Fig. 3 - gravity gradient on a Keplerian orbit (a = 7000 km, e = 0.2), 2 orbits"),
]

#: figure size (inches) and resolution: about 1000 x 380 pixels, well under 200 kB
FIGSIZE = (10.0, 3.8)
DPI = 100


def run(name):
    """The Dataset of shipped scenario ``name`` (its periapsis warning silenced: the paper's
    orbit has a (1 - e) = 5600 km, inside the Earth, and we reproduce it as printed)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="periapsis")
        sc = orbatt.load_scenario(name)
        return sc, sc.run()


def checks(name, sc, ds):
    """Lines of text: the numbers ``docs/paper-figures.md`` quotes."""
    q, Q, t = ds["q"].values, ds["Q"].values, ds["time"].values
    H = ds["energy"].values
    out = [f"{name}: t in [{t[0]:g}, {t[-1]:g}] {ds['time'].attrs['units']}, {t.size} outputs, "
           f"method {ds.attrs['method']}",
           f"  q(t0) = {np.array2string(q[0], precision=7)}",
           f"  Q(t0) = {np.array2string(Q[0], precision=7)}",
           f"  max | |q| - 1 |       = {np.abs(ds['q_norm_error'].values).max():.1e}",
           f"  q.Q from {ds['qQ'].values[0]:.3e} to {ds['qQ'].values[-1]:.3e} "
           f"(change {np.ptp(ds['qQ'].values):.1e})",
           f"  min/max of q: {q.min(0).round(3).tolist()} / {q.max(0).round(3).tolist()}",
           f"  min/max of Q: {Q.min(0).round(3).tolist()} / {Q.max(0).round(3).tolist()}"]
    if name == "paper-torque-free":
        qe, Qe = torque_free(sc.body, q[0], Q[0], t)
        G = ds["G"].values
        out += [f"  max |H - H0| / H0    = {np.abs(H - H[0]).max() / abs(H[0]):.1e}",
                f"  max |G - G0|         = {np.abs(G - G[0]).max():.1e}",
                f"  vs exact solution: max |q - q_exact| = {np.abs(q - qe).max():.1e}, "
                f"max |Q - Q_exact| = {np.abs(Q - Qe).max():.1e}"]
    elif name == "paper-heavy-top":
        G3 = ds["G"].values[:, 2]
        out += [f"  max |H - H0| / |H0|  = {np.abs(H - H[0]).max() / abs(H[0]):.1e}",
                f"  max |G3 - G3(t0)|    = {np.abs(G3 - G3[0]).max():.1e}  (vertical momentum)"]
    else:
        ref = sc.run(method="scipy-DOP853")
        out += [f"  orbital period {sc.orbit.period_value:.1f} s; r from {ds['r'].values.min():.1f} "
                f"to {ds['r'].values.max():.1f} km",
                f"  vs scipy DOP853 (same tolerances): max |dq| = "
                f"{np.abs(q - ref['q'].values).max():.1e}, max |dQ| = {np.abs(Q - ref['Q'].values).max():.1e}"]
    return out


def make(outdir, verbose=True):
    """Write the three PNGs to ``outdir``; return their paths."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fname, title in FIGURES:
        sc, ds = run(name)
        fig = plt.figure(figsize=FIGSIZE)
        ds.orbatt.plot_state(fig=fig)
        fig.suptitle(title, fontsize="medium")
        fig.tight_layout()
        path = outdir / fname
        fig.savefig(path, dpi=DPI)
        plt.close(fig)
        paths.append(path)
        if verbose:
            print("\n".join(checks(name, sc, ds)))
            print(f"  -> {path} ({path.stat().st_size / 1024:.0f} kB)")
    return paths


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--outdir", default=str(HERE / "figures"), help="output folder (default: docs/figures)")
    p.add_argument("--quiet", action="store_true", help="do not print the checks")
    args = p.parse_args(argv)
    make(args.outdir, verbose=not args.quiet)


if __name__ == "__main__":
    main()

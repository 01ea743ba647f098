"""The ``orbatt`` command.

Contract (other tools call these; keep the names)::

    orbatt run SCENARIO.toml [-o OUT.nc] [--plot DIR] [--method M] [--quiet]
    orbatt info OUT.nc
    orbatt plot OUT.nc -o DIR
    orbatt scenarios
    orbatt --version

Bad input exits with code 2 and a one-line error on stderr naming the field, the value and
the fix; ``--debug`` shows the traceback instead.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

EXIT_INPUT = 2


def _version():
    from . import __version__

    return __version__


def _parser():
    p = argparse.ArgumentParser(prog="orbatt", description="Satellite attitude coupled to the orbit "
                                "(Arribas, Elipe & Palacios 2006 quaternion Hamiltonian).")
    p.add_argument("--version", action="version", version=f"orbatt {_version()}")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run a scenario file and write its Dataset to NetCDF")
    r.add_argument("scenario", help="scenario TOML file (or the name of a shipped scenario)")
    r.add_argument("-o", "--output", help="output NetCDF file (default: SCENARIO.nc in the current folder)")
    r.add_argument("--plot", metavar="DIR", help="also write PNG figures to DIR")
    r.add_argument("--method", help="override [integration] method")
    r.add_argument("--quiet", action="store_true", help="no progress bar or summary")

    i = sub.add_parser("info", help="summarize a result file")
    i.add_argument("file")

    pl = sub.add_parser("plot", help="write PNG figures of a result file")
    pl.add_argument("file")
    pl.add_argument("-o", "--output", required=True, metavar="DIR")

    sub.add_parser("scenarios", help="list the shipped scenarios")
    return p


def _cmd_run(args):
    from .dataset import write_netcdf
    from .scenario import load_scenario

    sc = load_scenario(args.scenario)
    out = Path(args.output) if args.output else Path(f"{sc.name}.nc")
    t0 = time.perf_counter()
    ds = sc.run(method=args.method, progress=not args.quiet)
    wall = time.perf_counter() - t0
    write_netcdf(ds, out)
    if not args.quiet:
        print(summary(ds, title=f"{sc.name} -> {out}", wall=wall))
    if args.plot:
        for f in write_plots(ds, args.plot, stem=sc.name):
            if not args.quiet:
                print(f"figure: {f}")
    if not ds.attrs.get("complete", 1):
        print("orbatt: run interrupted; the file holds what was computed", file=sys.stderr)
        return 130
    return 0


def _cmd_info(args):
    from .dataset import open_dataset

    ds = open_dataset(_existing(args.file))
    print(summary(ds, title=str(args.file)))
    return 0


def _cmd_plot(args):
    from .dataset import open_dataset

    ds = open_dataset(_existing(args.file), load=True)
    for f in write_plots(ds, args.output, stem=Path(args.file).stem):
        print(f)
    return 0


def _cmd_scenarios(args):
    from .scenario import shipped_scenarios

    rows = shipped_scenarios()
    width = max(len(n) for n, _, _ in rows)
    for name, desc, _ in rows:
        print(f"{name:<{width}}  {desc}")
    return 0


def _existing(path):
    from .errors import InputError

    p = Path(path)
    if not p.is_file():
        raise InputError(f"file: {path!r} does not exist; give the path of a NetCDF file written by 'orbatt run'")
    return p


def summary(ds, title="", wall=None) -> str:
    """A short text table: span, method, stats, invariant drift, energy error."""
    import json

    import numpy as np

    t = ds["time"].values
    tu = ds["time"].attrs.get("units", "")
    lines = [title] if title else []
    settings = ds.attrs.get("settings", "{}")
    stats = ds.attrs.get("stats", "{}")
    try:
        settings = json.loads(settings) if isinstance(settings, str) else settings
        stats = json.loads(stats) if isinstance(stats, str) else stats
    except ValueError:
        pass
    lines.append(f"  span        {t[0]:.6g} .. {t[-1]:.6g} {tu} ({t.size} outputs)")
    lines.append(f"  method      {ds.attrs.get('method', '?')}  {settings}")
    if stats:
        lines.append("  stats       " + ", ".join(f"{k}={v}" for k, v in stats.items()))
    E = ds["energy"].values
    dE = np.max(np.abs(E - E[..., :1]))
    rel = dE / max(np.max(np.abs(E)), np.finfo(float).tiny)
    lines.append(f"  energy      max |E - E0| = {dE:.3e} {ds['energy'].attrs.get('units', '')} "
                 f"(relative {rel:.3e})")
    lines.append(f"  |q| - 1     max {np.max(np.abs(ds['q_norm_error'].values)):.3e}")
    qQ = ds["qQ"].values
    lines.append(f"  q.Q         max drift {np.max(np.abs(qQ - qQ[..., :1])):.3e} (initial {qQ.ravel()[0]:.3e})")
    if wall is not None:
        lines.append(f"  wall time   {wall:.3f} s")
    if not ds.attrs.get("complete", 1):
        lines.append("  INCOMPLETE  the run was interrupted")
    return "\n".join(lines)


def write_plots(ds, folder, stem="orbatt"):
    """Write the standard figures (state, attitude, drift) as PNG files; return their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for kind in ("state", "attitude", "drift"):
        fig = getattr(ds.orbatt, f"plot_{kind}")()
        path = folder / f"{stem}-{kind}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths


def main(argv=None) -> int:
    from .errors import InputError

    args = _parser().parse_args(argv)
    try:
        return {"run": _cmd_run, "info": _cmd_info, "plot": _cmd_plot, "scenarios": _cmd_scenarios}[args.command](args)
    except InputError as exc:
        if args.debug:
            raise
        print(f"orbatt: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("orbatt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

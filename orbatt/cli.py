"""The ``orbatt`` command.

Contract (other tools call these; keep the names)::

    orbatt run SCENARIO.toml [-o OUT.nc] [--plot DIR] [--aem FILE] [--method M] [--append] [--quiet]
    orbatt sweep SCENARIO.toml [-o OUT.nc] [--scheduler ADDRESS] [--workers N] [--chunk-size N]
                 [--worker-timeout SECONDS] [--resume] [--seed S] [--quiet]
    orbatt info OUT.nc
    orbatt export OUT.nc --aem FILE [--attitude q|q_orbital] [--case N] [--time-system S] [--ref-frame NAME]
    orbatt plot OUT.nc -o DIR       (DIR/OUT-pointing.png, -rates, -wheels, -torques, -drift: what OUT holds)
    orbatt scenarios
    orbatt --version

Bad input exits with code 2 and a one-line error on stderr naming the field, the value and
the fix; a run that fails (e.g. a non-finite state mid-run) exits with 1 and a one-line error
naming the time; ``--debug`` shows the traceback instead.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

EXIT_INPUT = 2
EXIT_FAILURE = 1


def _version():
    from .version import __version__

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
    r.add_argument("--plot", metavar="DIR", help="also write PNG figures to DIR (NAME-pointing.png, -rates, -wheels, "
                                                 "-torques, -drift: those the result's content calls for)")
    r.add_argument("--aem", metavar="FILE", help="also write the attitude q as a CCSDS AEM (needs an epoch; "
                                                 "as 'orbatt export' with its defaults)")
    r.add_argument("--method", help="override [integration] method")
    r.add_argument("--append", action="store_true", help="continue the run in OUTPUT from its last sample to this "
                   "scenario's t_end and append the new samples (the flight software's state and the step loop's "
                   "memory come from the file: bitwise the single run)")
    r.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    r.add_argument("--yes", action="store_true", help="agree to a run the work estimate finds long (minutes)")

    s = sub.add_parser("sweep", help="run a sweep scenario ([sweep] table) on Dask; one Dataset with a case dimension")
    s.add_argument("scenario", help="scenario TOML file with a [sweep] table (or the name of a shipped one)")
    s.add_argument("-o", "--output", help="output file: NetCDF, or Zarr if it ends with .zarr (default: NAME.nc in "
                                          "the current folder); chunks go to OUTPUT.parts/ as they finish")
    s.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler (tcp://host:port); "
                                                          "default: chosen by the work (this process, or a local "
                                                          "cluster when it pays); 'synchronous': no Dask")
    s.add_argument("--workers", type=int, metavar="N", help="a local cluster of N worker processes; "
                                                            "with --scheduler: wait for N workers")
    s.add_argument("--worker-timeout", type=float, default=120.0, metavar="SECONDS",
                   help="with --scheduler and --workers: how long to wait for the workers (default 120)")
    s.add_argument("--chunk-size", type=int, metavar="N", help="cases per task (default: [sweep] chunk_size, else "
                                                               "about 4 tasks per worker); results do not depend on it")
    s.add_argument("--resume", action="store_true", help="finish an interrupted sweep: compute only the chunks "
                                                         "missing from OUTPUT.parts/")
    s.add_argument("--seed", type=int, help="override [sweep] seed")
    s.add_argument("--quiet", action="store_true", help="no progress or summary")
    s.add_argument("--yes", action="store_true", help="agree to a nominal case the work estimate finds long")

    i = sub.add_parser("info", help="summarize a result file")
    i.add_argument("file")

    e = sub.add_parser("export", help="write a result file's attitude as a CCSDS AEM (KVN)")
    e.add_argument("file", help="a NetCDF file written by 'orbatt run' (or 'orbatt sweep' with trajectories)")
    e.add_argument("--aem", metavar="FILE", required=True, help="the AEM file to write")
    e.add_argument("--attitude", choices=("q", "q_orbital"), default="q",
                   help="q: body relative to the inertial frame (default); q_orbital: relative to RTN")
    e.add_argument("--case", type=int, metavar="N", help="the member of an ensemble or sweep to write")
    e.add_argument("--time-system", default="UTC", metavar="S", help="UTC (default), TAI, TT, TDB, TCB or TCG; "
                   "TDB/TCB epochs differ between astropy and Orekit by tens of microseconds")
    e.add_argument("--ref-frame", metavar="NAME", help="REF_FRAME_A: the inertial frame of your orbit elements "
                   "(default GCRF, orbatt's inertial frame; RTN for q_orbital)")

    pl = sub.add_parser("plot", help="write PNG figures of a result file (an ensemble: every case)")
    pl.add_argument("file")
    pl.add_argument("-o", "--output", required=True, metavar="DIR", help="folder of the figures FILE-FIGURE.png")

    sub.add_parser("scenarios", help="list the shipped scenarios")
    return p


def _cmd_run(args):
    from . import coldstart
    from .errors import InputError

    cold = coldstart.plan(args.scenario, args.method)
    if cold is None:
        code = _run(args, None)
        if code == 0:  # every kernel of this kind is compiled and cached now: no interpreted next run
            coldstart.mark_warm(args.scenario, args.method)
        return code
    os.environ["NUMBA_DISABLE_JIT"] = "1"  # a first run of this kind: interpreted kernels (before numba's import)
    try:
        return _run(args, cold)
    except InputError:  # bad input, refused before any kernel ran
        raise
    except Exception:  # noqa: BLE001 - raised where compiled code gives inf/NaN, or any failure:
        return cold.rerun_compiled(args.argv)  # the compiled run decides


def _run(args, cold):
    from .dataset import write_aem, write_netcdf
    from .errors import IntegrationError
    from .scenario import load_scenario

    sc = load_scenario(args.scenario, yes=args.yes)
    out = _output_path(args, sc)
    if getattr(args, "append", False) and out.exists():  # continue the file's run (its last sample's state)
        from .dataset.file_checks import continued_scenario

        sc = continued_scenario(out, sc)
    aem = _aem_path(args, sc, out)
    stem = _plot_stem(args, sc, {"-o": out, "--aem": aem})
    t0 = time.perf_counter()
    progress = not args.quiet
    if cold is not None:  # the input is good: start compiling in the background, go on interpreted
        from .coldstart import ENV_MODE
        from .progress import progress_callback

        if not cold.start_warm_up():  # no warm-up could start: compile now, in a process of its own
            return cold.rerun_compiled(args.argv)
        if not args.quiet:
            print("orbatt: first run of this kind of scenario: the kernels run interpreted while they compile in "
                  f"the background for the next runs (same results; {ENV_MODE}=compile waits for the compiler "
                  "instead)", file=sys.stderr)
        progress = cold.progress(progress_callback(progress))
    import contextlib

    import numpy as np

    # interpreted kernels: numpy scalars warn where compiled code silently gives inf/NaN
    quiet_numpy = np.errstate(all="ignore") if cold is not None else contextlib.nullcontext()
    try:  # the result's content: written and summarized without building the xarray Dataset
        with quiet_numpy:
            content = sc.run_content(method=args.method, progress=progress)
    except IntegrationError as exc:  # keep what was computed, marked incomplete, as Ctrl-C does
        if cold is not None:
            raise  # rerun compiled (_cmd_run)
        _write_partial(exc, out)
        raise
    if cold is not None and cold.switched:  # the kernels compiled meanwhile (or the run is long): finish compiled
        if cold.projected is not None and not args.quiet:
            print(f"orbatt: this run would take ~{cold.projected:.0f} s interpreted; waiting for the compiler instead",
                  file=sys.stderr)
        return cold.rerun_compiled(args.argv, stream=None if args.quiet or cold.projected is None else sys.stderr)
    wall = time.perf_counter() - t0
    appended = getattr(args, "append", False) and out.exists()
    write_netcdf(content, out, append=appended)
    if not args.quiet:
        print(summary(content, title=f"{sc.name} -> {out}" + (" (appended)" if appended else ""), wall=wall))
    if appended and (aem is not None or args.plot):  # the figures and the AEM of the whole run
        from .dataset import open_dataset

        content = open_dataset(out, load=True)
    ds = content.to_dataset() if (aem is not None or args.plot) and hasattr(content, "to_dataset") else content
    if aem is not None:
        write_aem(ds, aem)
        if not args.quiet:
            print(f"AEM: {aem}")
    if args.plot:
        for f in write_plots(ds, args.plot, stem=stem, what="--plot"):
            if not args.quiet:
                print(f"figure: {f}")
    if not int(ds.attrs.get("integration_complete", 1)):
        print("orbatt: run interrupted; the file holds what was computed", file=sys.stderr)
        return 130
    return 0


def _write_partial(exc, out):
    """Write the Dataset of a failed run (``exc.dataset``, :meth:`Scenario.run`) to ``out``,
    marked incomplete, and say so in the error's one-line message."""
    from .dataset import write_netcdf

    ds = getattr(exc, "dataset", None)
    if ds is None:
        return
    write_netcdf(ds, out)
    exc.args = (f"{exc.args[0] if exc.args else exc}; the {ds.sizes['time']} outputs computed until then are in "
                f"{out} (integration_complete = 0)",) + tuple(exc.args[1:])


def _output_path(args, sc, *, zarr=False):
    """The output file of ``run``/``sweep``, checked before anything is computed: ``-o``, or
    ``NAME.nc`` in the current folder (``name`` must then be a plain file name); never the
    scenario file; only a writable folder; only over an earlier orbatt result
    (:func:`orbatt.dataset.check_output_path`)."""
    from .dataset import check_output_path, file_name
    from .errors import InputError

    if args.output is not None and not args.output.strip():
        raise InputError(f"-o: {args.output!r} is an empty path; give an output file such as -o result.nc (or leave "
                         "-o out for NAME.nc)")
    what = "-o" if args.output else "name"
    out = Path(args.output) if args.output else Path(file_name(sc.name, ".nc"))
    src = Path(sc.path) if getattr(sc, "path", None) is not None else None
    if src is not None and src.is_file() and out.exists() and os.path.samefile(src, out):
        raise InputError(f"{what}: {str(out)!r} is the scenario file itself; give another output path "
                         "such as -o result.nc")
    return check_output_path(out, what=what, zarr=zarr)


def _plot_stem(args, sc, outputs=None):
    """The stem of the ``--plot`` figure names (``NAME-pointing.png`` ...), checked before the
    run (:func:`orbatt.dataset.figure_files.check_figure_folder`, for every figure the run may
    draw): ``name`` a plain file name, ``--plot`` a writable folder (or a path to create in
    one), no link or foreign file where a figure goes, and no figure where the run's other
    ``outputs`` (``{option: path or None}``: ``-o``, ``--aem``) go."""
    if not args.plot:
        return None
    from .dataset.figure_files import check_figure_folder
    from .errors import InputError

    paths = check_figure_folder(args.plot, sc.name, what="--plot")
    for option, path in (outputs or {}).items():
        if path is None:
            continue
        for figure, fig in paths.items():
            if os.path.abspath(fig) == os.path.abspath(path):
                raise InputError(f"{option}: {str(path)!r} is also where --plot writes the {figure} figure; give "
                                 f"{option} another name (or --plot another folder)")
    return sc.name


def _aem_path(args, sc, out):
    """The ``--aem`` file of ``run``, checked before the run: the scenario needs an epoch, and
    the path the checks of ``-o`` (:func:`_checked_aem`), other than the NetCDF output."""
    if args.aem is None:
        return None
    from .errors import InputError

    if not args.aem.strip():
        raise InputError(f"--aem: {args.aem!r} is an empty path; give a file such as --aem attitude.aem")
    if getattr(sc, "system", None) is not None:  # a binary asteroid (BinaryScenario): no orbit provider
        raise InputError("--aem: an AEM needs absolute times and a binary asteroid scenario ([orbit] provider = "
                         "\"coupled\") has no epoch; leave --aem out")
    orbit = getattr(sc, "orbit", None)
    if sc.spec.dimensionless or orbit is None or getattr(orbit, "epoch", None) is None:
        raise InputError("--aem: an AEM needs absolute times and this scenario has no epoch (no [orbit] with "
                         "epoch); add one or leave --aem out")
    if os.path.abspath(args.aem) == os.path.abspath(out):
        raise InputError(f"--aem: {args.aem!r} is also the NetCDF output; give the AEM another name such as "
                         f"{Path(out).stem + '.aem'!r}")
    return _checked_aem(args.aem, getattr(sc, "path", None))


def _checked_aem(path, source=None):
    """``--aem``: a writable path that is not ``source`` (the scenario or result read) and
    holds nothing but an earlier orbatt AEM (:func:`orbatt.dataset.check_output_path`)."""
    from .dataset import check_output_path
    from .dataset.aem import is_orbatt_aem
    from .errors import InputError

    if not path.strip():
        raise InputError(f"--aem: {path!r} is an empty path; give a file such as --aem attitude.aem")
    p = Path(path)
    if source is not None and Path(source).is_file() and p.exists() and os.path.samefile(source, p):
        raise InputError(f"--aem: {path!r} is the file being read; give another path such as 'attitude.aem'")
    return check_output_path(p, what="--aem", ours=is_orbatt_aem)


def _cmd_export(args):
    from .dataset import open_dataset, write_aem
    from .errors import InputError

    src = _existing(args.file)
    aem = _checked_aem(args.aem, src)
    if args.ref_frame is not None:
        bad = next((c for c in args.ref_frame if ord(c) < 32 or 127 <= ord(c) < 160), None)
        if bad is not None or not args.ref_frame.strip():
            raise InputError(f"--ref-frame: {args.ref_frame!r} " + (f"holds the control character {bad!r}" if bad else
                                                                     "is empty") + "; give a frame name such as ICRF")
    ds = open_dataset(src, load=True)
    options = {"attitude": args.attitude, "case": args.case, "time_system": args.time_system}
    if args.ref_frame:
        options["ref_frame_a"] = args.ref_frame
    write_aem(ds, aem, **options)
    print(aem)
    return 0


def _cmd_sweep(args):
    from .scenario import load_scenario
    from .sweep import Sweep, run_sweep

    t0 = time.perf_counter()
    sc = load_scenario(args.scenario, yes=args.yes)
    out = _output_path(args, sc, zarr=True)
    sw = Sweep(sc, seed=args.seed)
    sw.setup_seconds = time.perf_counter() - t0  # what each worker of a cluster would pay again

    def report(info):
        if not args.quiet:
            print(f"\r{info.line()}   ", end="", file=sys.stderr, flush=True)  # cases, cases/s, ETA, where

    if not args.quiet and sw.seed_source == "default" and not args.resume:
        print(f"orbatt sweep: [sweep] gives no seed; drew seed = {sw.seed} (recorded in the output as sweep_seed)",
              file=sys.stderr)
    try:
        with _sweep_lock(out):
            ds = run_sweep(sw, out, scheduler=args.scheduler, workers=args.workers, chunk_size=args.chunk_size,
                           resume=args.resume, progress=report, worker_timeout=args.worker_timeout)
    except KeyboardInterrupt:
        if Path(f"{out}.parts").is_dir():
            print(f"\norbatt: interrupted; the finished chunks are in {out.name}.parts/: rerun with --resume to "
                  "compute only the missing ones", file=sys.stderr)
        else:
            print("\norbatt: interrupted before any chunk finished; nothing was written", file=sys.stderr)
        return 130
    if not args.quiet:
        import json

        run = json.loads(ds.attrs["sweep_run"])
        print(file=sys.stderr)
        print(sweep_summary(ds, title=f"{sc.name} -> {out}", run=run))
    ds.close()
    return 0


@contextlib.contextmanager
def _sweep_lock(out):
    """Hold ``.OUTPUT.lock`` beside the sweep's ``OUTPUT`` (an exclusive ``flock``, released when
    the process ends however it ends) while the sweep computes, merges and removes
    ``OUTPUT.parts/``: a second ``orbatt sweep`` of the same output (a concurrent ``--resume``)
    is refused at once instead of racing for the parts."""
    try:
        import fcntl
    except ImportError:  # no flock (Windows): unlocked, as before
        yield
        return
    from .errors import InputError

    lock = Path(out).parent / f".{Path(out).name}.lock"
    fd = os.open(lock, os.O_CREAT | os.O_RDWR, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise InputError(f"-o: another orbatt sweep is writing {str(out)!r} (and its {Path(out).name}.parts/) "
                             "now; wait for it to end (then --resume if it was interrupted)") from None
        try:
            yield
        finally:
            try:
                os.unlink(lock)
            except OSError:
                pass
    finally:
        os.close(fd)


def sweep_summary(ds, title="", run=None) -> str:
    """A short text summary of a sweep Dataset."""
    import json

    import numpy as np

    lines = [title] if title else []
    n = int(ds.attrs.get("sweep_cases", ds.sizes.get("case", 0)))
    params = json.loads(ds.attrs.get("sweep_parameters", "{}"))
    lines.append(f"  cases       {n} ({', '.join(params)}); seed {ds.attrs.get('sweep_seed')} "
                 f"({ds.attrs.get('sweep_seed_source', '?')})")
    if int(ds.attrs.get("sweep_resampled_cases", 0)):
        lines.append(f"  resampled   {int(ds.attrs['sweep_resampled_cases'])} cases (outside physical limits)")
    if run:
        rate = run["cases_computed"] / run["wall_time_s"] if run["wall_time_s"] > 0 else float("nan")
        lines.append(f"  run         {run['chunks_computed']} chunks computed, {run['chunks_reused']} reused, "
                     f"{run['wall_time_s']:.1f} s on {run['scheduler']} ({run['workers']} workers), {rate:.1f} cases/s")
    failed = int(np.asarray(ds["integration_failed"].values).sum())
    if failed:
        lines.append(f"  FAILED      {failed} cases stopped (integration_failed = 1, values NaN)")
    if "max_pointing_error" in ds:
        pe = np.degrees(np.asarray(ds["max_pointing_error"].values))
        lines.append(f"  pointing    max error: median {np.nanmedian(pe):.3g} deg, max {np.nanmax(pe):.3g} deg")
    if "tumbling" in ds:
        lines.append(f"  tumbling    {int((np.asarray(ds['tumbling'].values) == 1).sum())} of {n} cases")
    if "final_energy_error" in ds:
        lines.append(f"  energy      max |relative error| {np.nanmax(np.abs(ds['final_energy_error'].values)):.3e}")
    from .sweep.report import percentile_table

    table = percentile_table(ds)
    if table:
        lines.append("  outputs over the cases (NaN: no value - never reached, or failed):")
        lines.extend(table)
    from .dataset.pointing_budget import budget_lines

    lines.extend(budget_lines(ds))  # the ECSS indices under the interpretations the file allows
    return "\n".join(lines)


#: the variables ``info`` and ``plot`` read from a run result
RUN_VARIABLES = ("q", "Q", "energy", "q_norm_error", "qQ")


def _cmd_info(args):
    from .dataset import open_dataset

    ds = open_dataset(_existing(args.file), load=True)  # every value read: a damaged chunk fails here
    if "sweep_format" in ds.attrs and "energy" not in ds:  # a sweep of reductions (orbatt sweep)
        _check_variables(ds, args.file, ("integration_failed",), "a sweep result")
        print(sweep_summary(ds, title=str(args.file)))
        return 0
    _check_variables(ds, args.file, RUN_VARIABLES, "a run result")
    print(summary(ds, title=str(args.file)))
    return 0


def _cmd_plot(args):
    from .dataset import open_dataset
    from .dataset.figure_files import check_figure_folder, figure_notes
    from .errors import InputError

    src = _existing(args.file)
    check_figure_folder(args.output, Path(args.file).stem, what="-o", figures=())  # the folder, before reading
    ds = open_dataset(src, load=True)
    if "time" not in ds.dims or "omega" not in ds.variables:
        if "sweep_format" not in ds.attrs or "case" not in ds.dims:
            raise InputError(f"file: {args.file!r} has neither time histories nor per-case outputs; give the "
                             "output of 'orbatt run' or 'orbatt sweep'")
        from .dataset.figure_files import write_figures
        from .dataset.sweep_figures import draw_sweep, sweep_figures_of, sweep_outputs

        if not sweep_outputs(ds):
            raise InputError(f"file: {args.file!r} is a sweep result without time histories or per-case outputs to "
                             "draw; add outputs (e.g. \"max_pointing_error\", \"trajectory\") to [sweep] outputs")

        # a sweep's per-case outputs: their distributions and their scatter against the parameters
        for f in write_figures(ds, args.output, Path(args.file).stem, what="-o", figures=sweep_figures_of(ds),
                               draw_figure=draw_sweep):
            print(f)
        return 0
    _check_variables(ds, args.file, RUN_VARIABLES, "a run result")
    for note in figure_notes(ds):
        print(f"orbatt: note: {note}", file=sys.stderr)
    for f in write_plots(ds, args.output, stem=Path(args.file).stem, what="-o"):
        print(f)
    return 0


def _check_variables(ds, path, names, what):
    """Refuse an orbatt file that lacks a variable (a damaged or edited file) or has no times."""
    from .errors import InputError

    missing = [n for n in names if n not in ds.variables]
    if missing or ("time" in ds.dims and ds.sizes["time"] == 0):
        detail = f"no variable {missing[0]!r}" if missing else "no output times"
        raise InputError(f"file: {str(path)!r} is not {what} orbatt can read ({detail}); give the output of "
                         "'orbatt run' or 'orbatt sweep'")


def _cmd_scenarios(args):
    from .scenario import shipped_scenarios

    import shutil
    import textwrap

    rows = shipped_scenarios()
    width = max(len(n) for n, _, _ in rows)
    columns = max(shutil.get_terminal_size((100, 24)).columns, width + 40)
    for name, desc, _ in rows:  # the description re-wrapped, its lines indented under the first
        print(textwrap.fill(" ".join(desc.split()), width=columns - 1, initial_indent=f"{name:<{width}}  ",
                            subsequent_indent=" " * (width + 2), break_on_hyphens=False))
    return 0


def _existing(path):
    from .errors import InputError, not_a_file

    p = Path(path)
    why = not_a_file(p)
    if why is not None:
        raise InputError(f"file: {path!r} {why}; give the path of a NetCDF file written by 'orbatt run'")
    return p


def summary(ds, title="", wall=None) -> str:
    """A short text table: span, method, stats, invariant drift, energy error (of a Dataset or
    its :class:`~orbatt.dataset.content.Content`)."""
    import json

    import numpy as np

    settings = json.loads(ds.attrs.get("method_settings", "{}"))  # as ds.orbatt.settings, .stats
    stats = json.loads(ds.attrs.get("integration_stats", "{}"))
    from .dataset.timeaxis import elapsed_unit, elapsed_values

    t = elapsed_values(ds)
    lines = [title] if title else []
    tu = elapsed_unit(ds)
    tu = "(dimensionless)" if tu == "1" else tu
    lines.append(f"  span        {t[0]:.6g} .. {t[-1]:.6g} {tu} ({t.size} outputs)"
                 + (f", epoch {ds.attrs['epoch']}" if "epoch" in ds.attrs else ""))
    lines.append(f"  method      {ds.attrs.get('method', '?')}  {settings}")
    if stats:
        lines.append("  stats       " + ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                                                for k, v in stats.items()))
    E = ds["energy"].values
    dE = np.max(np.abs(E - E[..., :1]))
    rel = dE / max(np.max(np.abs(E)), np.finfo(float).tiny)
    note = "  (not an invariant: the potential depends on time)" if "orbit" in ds.attrs else ""
    eu = ds["energy"].attrs.get("units", "")
    lines.append(f"  energy      max |E - E0| = {dE:.3e} {'' if eu == '1' else eu} "
                 f"(relative {rel:.3e}){note}")
    lines.append(f"  |q| - 1     max {np.max(np.abs(ds['q_norm_error'].values)):.3e}")
    qQ = ds["qQ"].values
    qu = ds["qQ"].attrs.get("units", "")
    qu = "" if qu in ("1", "") else f" {qu}"
    lines.append(f"  q.Q         max drift {np.max(np.abs(qQ - qQ[..., :1])):.3e}{qu} (initial {qQ.ravel()[0]:.3e})")
    if wall is not None:
        lines.append(f"  wall time   {wall:.3f} s (total, including setup and Dataset)")
    if not int(ds.attrs.get("integration_complete", 1)):
        lines.append("  INCOMPLETE  the run was interrupted; the data end at the last time reached")
    return "\n".join(lines)


def write_plots(ds, folder, stem="orbatt", what="--plot"):
    """Write the figures the content of ``ds`` calls for (pointing, rates, wheels, torques,
    drift: :func:`orbatt.dataset.figure_data.choose_figures`) as ``folder/STEM-FIGURE.png``,
    atomically and never over a link or a file that is not an orbatt figure
    (:func:`orbatt.dataset.figure_files.write_figures`; errors name ``what``); return their
    paths. ``stem`` must be a plain file name (:func:`orbatt.dataset.file_name`)."""
    from .dataset.figure_files import write_figures

    return write_figures(ds, folder, stem, what=what)


def main(argv=None) -> int:
    from .errors import InputError, OrbattError

    args = _parser().parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    if not args.debug:
        import warnings

        def one_line(message, category, filename, lineno, file=None, line=None):
            print(f"orbatt: warning: {' '.join(str(message).split())}", file=sys.stderr)

        warnings.showwarning = one_line
    try:
        return {"run": _cmd_run, "sweep": _cmd_sweep, "info": _cmd_info, "plot": _cmd_plot,
                "export": _cmd_export, "scenarios": _cmd_scenarios}[args.command](args)
    except OrbattError as exc:
        if args.debug:
            raise
        print(f"orbatt: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_INPUT if isinstance(exc, InputError) else EXIT_FAILURE
    except KeyboardInterrupt:
        print("orbatt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (`orbatt scenarios | head`): stop quietly
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit's flush
        except (OSError, ValueError):
            pass
        return EXIT_FAILURE
    except (Exception, RecursionError) as exc:  # noqa: BLE001 - a bug or a resource failure: still one line
        if args.debug:
            raise
        print(f"orbatt: error: {type(exc).__name__}: {' '.join(str(exc).split())[:300]} (an unexpected failure; "
              "rerun with --debug for the traceback and report it)", file=sys.stderr)
        return EXIT_FAILURE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""Running a sweep: chunks in this process or on Dask (chosen by the work), parts written as they finish,
the merge into one Dataset, and its global attributes (``docs/sweeps.md``: Storage and
resumption, Execution)."""
from __future__ import annotations

import json
import math
import os
import secrets
import shutil
import signal
import sys
import threading
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..dataset import check_output_path, global_attrs, open_dataset
from ..dataset.atomic import replacing
from ..errors import InputError, SweepError
from .cases import Sweep, load_sweep
from .chunk import concat_cases, run_chunk
from .stats import add_stats
from .parts import (chunk_ranges, done_parts, parse_part, parts_dir, read_manifest, read_parts, write_manifest,
                    write_part, write_reductions)

__all__ = ["run_sweep", "ChunkInfo", "open_client", "sweep_global_attrs", "choose_scheduler", "MAX_AUTO_CHUNK",
           "PROBE_CASES", "CLUSTER_START_S", "TASK_SECONDS"]

#: largest chunk chosen automatically (cases per task)
MAX_AUTO_CHUNK = 1000


#: cases computed in this process first when the scheduler is chosen by the work (``scheduler``
#: None without ``workers``): their time per case decides (:func:`choose_scheduler`)
PROBE_CASES = 4
#: seconds a local cluster costs besides its tasks: its scheduler and worker processes started,
#: their imports, and closing it; measured on the 2-core sandbox at a load of 6: 2.2 s start,
#: 4.2 s imports, 2.2 s close
CLUSTER_START_S = 8.0
#: a task's work (s) when the chunk size is chosen from the measured time per case: progress
#: every few seconds, each task's ~20-40 ms of Dask, netCDF and merge overhead ~1 %
TASK_SECONDS = 3.0


@dataclass
class ChunkInfo:
    """What a :func:`run_sweep` progress callback receives: after each chunk, and in this
    process after each group of cases (``partial``: within a chunk)."""

    start: int             #: first case of the chunk (of the cases just done, when partial)
    stop: int              #: one past its last case
    chunks_done: int       #: chunks complete (this run and earlier ones)
    chunks_total: int
    cases_done: int        #: cases complete (this run and earlier ones)
    cases_total: int
    wall_time_s: float     #: since the start of this run
    path: Path | None = None   #: the part file written (None without an output)
    extra: dict = field(default_factory=dict)
    cases_computed: int = 0    #: cases computed by this run
    scheduler: str = ""        #: where the cases run: "in-process", "local cluster", an address
    workers: int = 1           #: processes (threads) computing at once
    partial: bool = False      #: reported within a chunk (in this process)

    @property
    def rate(self) -> float:
        """Cases per second of this run (NaN before the first case)."""
        return self.cases_computed / self.wall_time_s if self.cases_computed and self.wall_time_s > 0 else math.nan

    @property
    def eta_s(self) -> float:
        """Seconds left at this run's rate (NaN before the first case)."""
        r = self.rate
        return (self.cases_total - self.cases_done) / r if r > 0 else math.nan

    def line(self) -> str:
        """The progress line ``orbatt sweep`` prints: cases done, cases/s, ETA, chunks and
        where the cases run."""
        r, eta = self.rate, self.eta_s
        speed = f", {r:.3g} cases/s, ETA {_duration(eta)}" if r == r else ""
        where = self.scheduler + (f", {self.workers} workers" if self.workers > 1 else "")
        return (f"orbatt sweep: {self.cases_done}/{self.cases_total} cases{speed} ({self.chunks_done}/"
                f"{self.chunks_total} chunks, {self.wall_time_s:.0f} s; {where})")


def _duration(s):
    if not s == s:
        return "?"
    s = int(round(s))
    return f"{s // 3600} h {s % 3600 // 60:02d} min" if s >= 3600 else f"{s // 60} min {s % 60:02d} s" \
        if s >= 60 else f"{s} s"


def run_sweep(sweep, output=None, *, scheduler=None, workers=None, chunk_size=None, resume=False,
              progress=None, client=None, keep_parts=False, worker_timeout=120.0, notify=None):
    """Run a sweep on Dask, chunk by chunk, and return its Dataset.

    Parameters
    ----------
    sweep : Sweep or str or Path
        A :class:`Sweep`, or a scenario file with ``[sweep]`` (:func:`load_sweep`).
    output : str or Path, optional
        The result file: netCDF, or Zarr if the name ends with ``.zarr``. Chunks are written
        to ``OUTPUT.parts/`` as they finish and merged at the end (``docs/sweeps.md``). Without
        it nothing is written and the chunks are gathered in memory.
    scheduler : str, optional
        ``None`` (default, also ``"auto"``): chosen by the work (:func:`choose_scheduler`):
        the first :data:`PROBE_CASES` cases run in this process, and the rest stay here unless
        a local cluster of one worker per core, its start included, would finish them sooner
        (on 2 cores: a few tens of seconds of work or more, with cases that do not share one
        model); with ``workers``, a local cluster of that many processes on 127.0.0.1, started
        and stopped here (also ``"local"``); ``"tcp://host:port"``: a running dask.distributed
        scheduler; ``"synchronous"``: no Dask, the chunks one after the other in this process.
        The progress (:class:`ChunkInfo`) and the ``sweep_run`` record say which ran.
    workers : int, optional
        Local cluster: its number of worker processes (default: the CPU count); giving it asks
        for the cluster. With a scheduler address: wait until that many workers are connected.
    chunk_size : int, optional
        Cases per task. Default: the ``[sweep] chunk_size``, else a multiple of four tasks
        per worker, at most 1000 cases each (a cluster chosen by the work: about
        :data:`TASK_SECONDS` of work per task, from the measured time per case). The results
        do not depend on it. Keep a task above ~0.1 s of work: each costs ~20-40 ms of Dask,
        netCDF and merge overhead.
    resume : bool
        Keep the complete parts of an interrupted run of the same sweep (same scenario text,
        seed and number of cases; the seed is read back when the file gives none) and
        compute only the missing cases. Without it, an existing ``OUTPUT.parts/`` is refused.
    progress : callable, optional
        Called with a :class:`ChunkInfo` after every chunk, after every group of cases
        computed in this process (``partial``), and once at the start with the chunks found on
        resume; :meth:`ChunkInfo.line` is ``orbatt sweep``'s progress line.
    client : dask.distributed.Client, optional
        Use this client (its cluster is left running); overrides ``scheduler``/``workers``.
    keep_parts : bool
        Keep ``OUTPUT.parts/`` after merging.
    worker_timeout : float
        With a scheduler address and ``workers``: seconds to wait for them (default 120).
    notify : callable, optional
        Receives one-line messages about waits (``"waiting up to 120 s for 4 workers at
        tcp://...: 1 connected"``); default: printed on stderr.

    Returns
    -------
    xarray.Dataset
        Dimension ``case`` (and ``time``, ``quat``, ``axis`` as the outputs need); the swept
        parameters as coordinates along ``case``; global attributes ``sweep_seed``,
        ``sweep_parameters``, ... and ``sweep_run`` (JSON: chunks computed and reused this
        run, wall time, scheduler, and ``scheduler_choice``: "asked", or why it was chosen). Opened from ``output`` when one is given (lazily for
        netCDF; load it or close it when done).

    Raises
    ------
    InputError
        Bad arguments, a parts folder without ``resume``, a parts folder (or a part) of
        another sweep, an unreachable scheduler, workers that did not connect in time.

    Notes
    -----
    A run that fails before writing any part (e.g. the scheduler cannot be reached) removes
    the ``OUTPUT.parts/`` folder it created, so the next run starts afresh.
    """
    if not isinstance(sweep, Sweep):
        sweep = load_sweep(sweep)
    _check_arguments(workers, chunk_size, scheduler)
    if isinstance(worker_timeout, bool) or not isinstance(worker_timeout, (int, float)) or \
            not 0 < worker_timeout < math.inf:
        raise InputError(f"worker_timeout: {worker_timeout!r} must be a positive number of seconds")
    out_path, parts, zarr_out = _output(output, resume)
    covered = np.zeros(sweep.cases, dtype=bool)
    reused = []
    created = parts is not None and not parts.exists()
    if parts is not None:
        sweep, reused, covered, complete = _open_parts(sweep, parts, out_path, zarr_out, resume)
        if complete:
            return open_dataset(out_path)
    try:
        results, run = _execute(sweep, parts, reused, covered, scheduler=scheduler, workers=workers,
                                chunk_size=chunk_size, progress=progress, client=client,
                                connect=dict(timeout=worker_timeout, notify=notify))
    except BaseException:
        if created and not any(parse_part(p.name) for p in parts.iterdir()):
            shutil.rmtree(parts, ignore_errors=True)  # nothing of this run to resume: as if never started
        raise
    import dask

    with dask.config.set(scheduler="synchronous"):
        if parts is None:
            stats = {}
            for ds in results:
                add_stats(stats, ds.attrs.get("integration_stats"), skip=("members",))
            ds = concat_cases(sorted(results, key=lambda d: int(d["case"].values[0])))
            return sweep_global_attrs(ds, sweep, stats, run)
        _merge_parts(sweep, parts, out_path, zarr_out, run)
    if not keep_parts:
        shutil.rmtree(parts)
    if zarr_out:
        import xarray as xr

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return xr.open_zarr(out_path)
    return open_dataset(out_path)


def _check_arguments(workers, chunk_size, scheduler):
    for name, v in (("workers", workers), ("chunk_size", chunk_size)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1):
            raise InputError(f"{name}: {v!r} must be a positive integer")
    if scheduler is not None and not isinstance(scheduler, str):
        raise InputError(f"scheduler: expected an address such as 'tcp://127.0.0.1:8786', 'synchronous' or None, "
                         f"got {scheduler!r}")


def _output(output, resume):
    """``(out_path, parts, zarr_out)`` of the ``output`` argument (all None/False without one)."""
    if output is None:
        if resume:
            raise InputError("resume: needs an output file (the parts of the interrupted run are beside it)")
        return None, None, False
    out_path = Path(output)
    zarr_out = out_path.suffix == ".zarr"
    if zarr_out:
        try:
            import zarr  # noqa: F401
        except ImportError:
            raise InputError(f"output: {output!s} is a Zarr store but zarr is not installed; pip install zarr, "
                             "or give a .nc file") from None
    if not out_path.parent.is_dir():
        raise InputError(f"output: the folder {str(out_path.parent)!r} does not exist")
    check_output_path(out_path, what="output", zarr=True)  # as -o: no link, only an earlier orbatt result
    return out_path, parts_dir(out_path), zarr_out


def _with_seed(sweep, seed):
    """The sweep again with the seed of an interrupted run (a file without a seed)."""
    if sweep.seed_source != "default" or seed is None:
        return sweep
    again = Sweep(sweep.scenario, seed=int(seed))
    again.seed_source = "default"
    return again


def _open_parts(sweep, parts, out_path, zarr_out, resume):
    """Resume from (or create) the parts folder: ``(sweep, reused, covered, complete)``;
    ``complete``: ``out_path`` already holds this sweep's result."""
    if parts.exists():
        if not resume:
            raise InputError(f"output: {str(parts)!r} holds the chunks of an interrupted sweep; pass --resume "
                             "(resume=True) to finish it, or delete that folder to start again")
        man = read_manifest(parts)
        sweep = _with_seed(sweep, man.get("seed", sweep.seed))
        if man.get("fingerprint") != sweep.fingerprint:
            raise InputError(f"resume: {str(parts)!r} belongs to another sweep (the scenario text, seed or number "
                             f"of cases changed: fingerprint {man.get('fingerprint')} != {sweep.fingerprint}); "
                             "delete it or rerun without changes")
        reused, covered = done_parts(parts, sweep.cases, sweep.fingerprint)
        return sweep, reused, covered, False
    if resume and out_path.exists() and not zarr_out:
        try:
            with open_dataset(out_path) as old:
                fp = old.attrs.get("sweep_fingerprint")
                old_seed = old.attrs.get("sweep_seed")
        except Exception:  # noqa: BLE001 - an unreadable file is simply recomputed
            fp = old_seed = None
        sweep = _with_seed(sweep, old_seed)
        if fp == sweep.fingerprint:
            return sweep, [], None, True
    write_manifest(parts, sweep)
    return sweep, [], np.zeros(sweep.cases, dtype=bool), False


def _execute(sweep, parts, reused, covered, *, scheduler, workers, chunk_size, progress, client, connect):
    """Compute the missing chunks; ``(results, run)``: the chunk Datasets kept in memory
    (without ``parts``) and the ``sweep_run`` record."""
    n_cases = sweep.cases
    covered = covered.copy()
    auto = scheduler in (None, "auto") and workers is None and client is None and not covered.all()
    synchronous = (scheduler == "synchronous" and client is None) or covered.all()  # all on disk: only the merge
    t_start = time.perf_counter()
    own = None
    owned_client = False
    results = []
    state = {"compute_s": 0.0, "k_done": len(reused), "cases_done": int(covered.sum()), "computed": 0,
             "chunks_total": len(reused), "scheduler": "in-process", "workers": 1, "computed_chunks": 0}
    choice = "asked"

    def report(a, b, path=None, partial=False):
        if progress is not None:
            progress(ChunkInfo(a, b, state["k_done"], state["chunks_total"], cases_done=state["cases_done"],
                               cases_total=n_cases, wall_time_s=time.perf_counter() - t_start, path=path,
                               cases_computed=state["computed"], scheduler=state["scheduler"],
                               workers=state["workers"], partial=partial))

    def handle(a, b, ds, counted=False):
        state["compute_s"] += float(ds.attrs.pop("sweep_chunk_seconds", 0.0))
        path = None
        if parts is not None:
            path = write_part(ds, parts, a, b, sweep.fingerprint)
        else:
            results.append(ds)
        state["k_done"] += 1
        state["computed_chunks"] += 1
        if not counted:
            state["cases_done"] += b - a
            state["computed"] += b - a
        report(a, b, path)

    def here(a, b, marks=None):
        """The chunk ``(a, b)`` in this process, reported case by case."""
        pos = [a]

        def on_cases(k):
            state["cases_done"] += k
            state["computed"] += k
            if marks is not None:
                marks.append((time.perf_counter(), k))
            report(pos[0], pos[0] + k, partial=True)
            pos[0] += k

        handle(a, b, run_chunk(sweep.job(a, b), on_cases, sweep.scenario), counted=True)

    try:
        if auto:
            marks = [(time.perf_counter(), 0)]
            size = min(PROBE_CASES, int(chunk_size or sweep.spec.chunk_size or PROBE_CASES))
            probe = chunk_ranges(~covered, size)[:1]
            state["chunks_total"] += 1  # the probe; the others once the scheduler is chosen
            report(0, 0)
            for a, b in probe:
                here(a, b, marks)
                covered[a:b] = True
            cluster, choice = choose_scheduler(marks, int((~covered).sum()), os.cpu_count() or 1,
                                               getattr(sweep, "setup_seconds", 0.0))
            synchronous = not cluster
        if not synchronous:
            if client is None:
                client, own = open_client(None if auto else scheduler, workers, **connect)
                owned_client = True
            state["workers"] = max(1, sum(client.nthreads().values()))  # worker threads: tasks that run at once
            if not owned_client:
                state["scheduler"] = str(getattr(client, "scheduler", None) and client.scheduler.address)
            else:
                state["scheduler"] = "local cluster" if auto else (scheduler or "local cluster")
        if chunk_size is None:
            chunk_size = sweep.spec.chunk_size
        if chunk_size is None:
            n_left = int((~covered).sum())
            w = state["workers"]
            rounds = math.ceil(max(n_left, 1) / (4 * w * MAX_AUTO_CHUNK))
            chunk_size = max(1, math.ceil(n_left / (4 * w * rounds)))  # a multiple of 4 tasks per worker
            if auto and not synchronous:  # a few seconds of work per task (the measured time per case)
                chunk_size = max(1, min(chunk_size, math.ceil(TASK_SECONDS / max(_per_case(marks), 1e-3))))
        todo = chunk_ranges(~covered, int(chunk_size))
        state["chunks_total"] = state["k_done"] + len(todo)
        report(0, 0)  # (again after the probe: where the rest runs)
        if synchronous:
            for a, b in todo:
                here(a, b)
        elif todo:
            _run_on_dask(client, sweep, todo, parts, handle)
    except BaseException:
        if owned_client:
            _quiet_dask_logs()
        raise
    finally:
        if owned_client:
            client.close()
            if own is not None:
                own.close()
    name = state["scheduler"] if state["scheduler"] != "in-process" else "synchronous"
    run = {"chunks": state["chunks_total"], "chunks_computed": state["computed_chunks"], "chunks_reused": len(reused),
           "cases_computed": state["computed"], "chunk_size": int(chunk_size),
           "wall_time_s": time.perf_counter() - t_start, "compute_time_s": state["compute_s"],
           "scheduler": name, "workers": int(state["workers"]), "scheduler_choice": choice}
    return results, run


def _per_case(marks):
    """Seconds per case after the first group of the probe (the environment and the kernels
    of this process are set up by then), else over the whole probe."""
    if len(marks) > 2:
        k = sum(m[1] for m in marks[2:])
        return (marks[-1][0] - marks[1][0]) / k
    k = sum(m[1] for m in marks[1:])
    return (marks[-1][0] - marks[0][0]) / max(k, 1)


def choose_scheduler(marks, left, cores, setup_s=0.0):
    """``(cluster, why)``: whether the ``left`` cases of a sweep run on a local cluster of
    ``cores`` workers rather than in this process, from the probe's ``marks`` (``[(time,
    cases)]``: its start, then each group of cases as it was done).

    In this process each case costs the measured time per case (:func:`_per_case`); a cluster
    divides that by ``cores`` but first costs :data:`CLUSTER_START_S` plus, in every worker,
    what the probe's first group cost beyond a case (the environment, loading the kernels) and
    the nominal scenario's build (``setup_s``). Cases that share a model run as one ensemble
    here, on every core already: they stay in this process."""
    per_case = _per_case(marks)
    here = per_case * left
    first = marks[1][0] - marks[0][0] - per_case * marks[1][1] if len(marks) > 1 else 0.0
    probe_cases = sum(m[1] for m in marks[1:])
    if cores < 2:
        return False, f"auto: in-process (1 core; {per_case:.3g} s per case)"
    if len(marks) - 1 < probe_cases:
        return False, f"auto: in-process (the cases share models: ensembles on every core; {per_case:.3g} s per case)"
    cluster = CLUSTER_START_S + max(first, 0.0) + setup_s + here / cores
    if cluster < here:
        return True, (f"auto: local cluster ({left} cases of {per_case:.3g} s: ~{here:.0f} s here, ~{cluster:.0f} s "
                      f"on {cores} workers)")
    return False, (f"auto: in-process ({left} cases of {per_case:.3g} s: ~{here:.0f} s here, ~{cluster:.0f} s on a "
                   f"{cores}-worker cluster)")


def _run_on_dask(client, sweep, todo, parts, handle):
    """Submit every chunk ``(a, b)`` of ``todo`` (numba single-threaded in each task) and
    ``handle(a, b, ds)`` each as it finishes; a task that failed for good raises
    :class:`SweepError` (the unfinished ones are cancelled)."""
    from dask.distributed import as_completed

    futures = {}
    for a, b in todo:
        fut = client.submit(run_chunk, sweep.job(a, b, 1), pure=False,
                            key=f"orbatt-sweep-{sweep.fingerprint[:12]}-{a}-{b}-{secrets.token_hex(4)}")
        futures[fut.key] = (fut, a, b)
    pending = iter(as_completed([f for f, _, _ in futures.values()], with_results=True))
    try:
        while True:
            try:
                fut, ds = next(pending)
            except StopIteration:
                break
            except Exception as exc:  # a task failed for good (raised, or its workers kept dying)
                left = sorted((a, b) for _, a, b in futures.values())
                keep = f"; the finished chunks are kept in {str(parts)!r}: rerun with --resume" if parts else ""
                raise SweepError(f"sweep: a task failed ({len(left)} chunks not finished, the first from case "
                                 f"{left[0][0]}): {type(exc).__name__}: {exc}{keep}") from exc
            _, a, b = futures.pop(fut.key)
            del fut  # let the scheduler forget the result
            handle(a, b, ds)
    except BaseException:
        client.cancel([f for f, _, _ in futures.values()])
        raise


def _merge_parts(sweep, parts, out_path, zarr_out, run):
    """Merge every part into ``out_path`` (netCDF or Zarr), written under a temporary name
    and renamed; the parts stay if anything fails (``--resume`` merges again)."""
    opened = read_parts(parts, sweep.cases, lazy="trajectory" in sweep.spec.outputs,
                        fingerprint=sweep.fingerprint)
    try:
        stats = {}
        for d in opened:
            add_stats(stats, d.attrs.get("integration_stats"), skip=("members",))
        ds = sweep_global_attrs(concat_cases(opened), sweep, stats, run)
        if zarr_out:
            with replacing(out_path, folder=True) as tmp, warnings.catch_warnings():
                warnings.simplefilter("ignore")  # zarr 3 on the 1-character label coordinates
                ds.drop_encoding().to_zarr(tmp, mode="w")
        else:
            write_reductions(ds, out_path)
    finally:
        for d in opened:
            d.close()


def sweep_global_attrs(ds, sweep, stats, run):
    """``ds`` with the global attributes of a sweep's result: the run's (CF conventions,
    method, potential, orbit, scenario text, epoch; as :func:`orbatt.to_dataset` writes
    them), the sweep's (:meth:`Sweep.attrs`), the summed ``stats`` and ``run`` (JSON).
    With trajectories, the pieces' own attributes are kept underneath."""
    sc = sweep.scenario
    attrs = {}
    if "trajectory" in sweep.spec.outputs:
        attrs = {k: v for k, v in ds.attrs.items() if k not in ("sweep_chunk_seconds", "epoch")}
    binary = getattr(sc, "system", None)  # a binary asteroid (BinaryScenario): no orbit provider, no epoch
    orbit = None if binary is not None else sc.orbit
    if binary is not None:
        from ..binary.dataset import describe, potential_attr

        attrs["binary"] = json.dumps(describe(binary))
    attrs.update(global_attrs(
        method=sc.method, settings={"method": sc.method, **sc.settings}, stats=json.dumps(stats, sort_keys=True),
        potential=potential_attr(binary) if binary is not None else sc.potential,
        dimensionless=sc.spec.dimensionless, orbit=orbit,
        epoch=None if orbit is None else orbit.epoch, scenario_text=sc.text,
        title=f"orbatt sweep: {sc.name} ({sweep.cases} cases)",
        action=f"sweep of {sweep.cases} cases ({run.get('scheduler')})",
        sweep_output_times=np.int64(sc.times.size), sweep_t_end=float(sc.times[-1]), **sweep.attrs(),
        sweep_run=json.dumps(run, sort_keys=True)))
    ds.attrs = attrs
    return ds


@contextmanager
def _workers_ignore_sigint():
    """Start worker processes with SIGINT ignored (inherited through exec): Ctrl-C in a
    terminal signals the whole process group, and each worker would print its own
    KeyboardInterrupt traceback; this process alone handles it and closes the cluster.
    The cost: a Ctrl-C in the seconds the cluster takes to start is ignored (press it
    again). (Blocking SIGINT instead does not reach the workers: they are spawned with it
    unblocked.) The workers log only CRITICAL messages (``silence_logs``): a failed task
    reaches this process as an exception, and a worker whose scheduler closed on Ctrl-C
    would log tracebacks."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _quiet_dask_logs():
    """Silence dask.distributed's loggers: a cluster closed on Ctrl-C (or after a failure)
    logs the tasks it cancels as errors, tracebacks included."""
    import logging

    for name in ("distributed", "tornado", "asyncio"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def open_client(scheduler, workers, *, timeout=120.0, notify=None):
    """A Dask client: ``(client, cluster_or_None)``. ``scheduler`` None: a local cluster of
    ``workers`` single-threaded processes on 127.0.0.1 (returned, to close); an address: a
    running scheduler; with ``workers``, wait up to ``timeout`` seconds until that many of
    its workers are connected, saying so once through ``notify`` (default: a line on stderr)
    when fewer are."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - dask is a dependency
        raise InputError("scheduler: dask.distributed is not installed; pip install 'dask[distributed]'") from None
    if scheduler in (None, "local"):
        import logging

        n = workers or os.cpu_count() or 1
        with _workers_ignore_sigint():
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None, silence_logs=logging.CRITICAL)
        return Client(cluster), cluster
    try:
        client = Client(scheduler)  # waits up to dask's distributed.comm.timeouts.connect
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"scheduler: cannot connect to {scheduler!r} ({exc}); start one with 'dask scheduler' "
                         "and workers with 'dask worker ADDRESS', or leave --scheduler out for a local cluster") from None
    if workers:
        have = len(client.nthreads())
        if have < workers:
            if notify is None:
                def notify(line):
                    print(line, file=sys.stderr, flush=True)
            notify(f"orbatt sweep: waiting up to {timeout:g} s for {workers} workers at {scheduler}: {have} connected "
                   "(start them with 'dask worker ADDRESS')")
            try:
                client.wait_for_workers(workers, timeout=timeout)
            except TimeoutError:
                have = len(client.nthreads())
                client.close()
                raise InputError(f"workers: {workers} workers did not connect to {scheduler!r} within {timeout:g} s "
                                 f"({have} connected); start more with 'dask worker {scheduler}', ask for fewer, "
                                 "or wait longer (--worker-timeout)") from None
    return client, None

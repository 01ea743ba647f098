"""Running a sweep: chunks on Dask (or in this process), parts written as they finish,
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

__all__ = ["run_sweep", "ChunkInfo", "open_client", "sweep_global_attrs", "MAX_AUTO_CHUNK"]

#: largest chunk chosen automatically (cases per task)
MAX_AUTO_CHUNK = 1000


@dataclass
class ChunkInfo:
    """What a :func:`run_sweep` progress callback receives after each chunk."""

    start: int             #: first case of the chunk
    stop: int              #: one past its last case
    chunks_done: int       #: chunks complete (this run and earlier ones)
    chunks_total: int
    cases_done: int
    cases_total: int
    wall_time_s: float     #: since the start of this run
    path: Path | None = None   #: the part file written (None without an output)
    extra: dict = field(default_factory=dict)

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
        ``None`` (default): a local cluster of ``workers`` processes on 127.0.0.1, started
        and stopped here; ``"tcp://host:port"``: a running dask.distributed scheduler;
        ``"synchronous"``: no Dask, the chunks one after the other in this process.
    workers : int, optional
        Local cluster: its number of worker processes (default: the CPU count). With a
        scheduler address: wait until that many workers are connected.
    chunk_size : int, optional
        Cases per task. Default: the ``[sweep] chunk_size``, else a multiple of four tasks
        per worker, at most 1000 cases each. The results do not depend on it. Keep a task
        above ~0.1 s of work: each costs ~20-40 ms of Dask, netCDF and merge overhead.
    resume : bool
        Keep the complete parts of an interrupted run of the same sweep (same scenario text,
        seed and number of cases; the seed is read back when the file gives none) and
        compute only the missing cases. Without it, an existing ``OUTPUT.parts/`` is refused.
    progress : callable, optional
        Called with a :class:`ChunkInfo` after every chunk (and once at the start, with the
        chunks found on resume).
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
        run, wall time, scheduler). Opened from ``output`` when one is given (lazily for
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
    synchronous = (scheduler == "synchronous" and client is None) or covered.all()  # all on disk: only the merge
    scheduler_name = "synchronous" if scheduler == "synchronous" and client is None else \
        (scheduler or "local cluster") if client is None else \
        str(getattr(client, "scheduler", None) and client.scheduler.address)
    t_start = time.perf_counter()
    own = None
    owned_client = False
    n_workers = 1
    if not synchronous:
        if client is None:
            client, own = open_client(scheduler, workers, **connect)
            owned_client = True
        n_workers = max(1, sum(client.nthreads().values()))  # worker threads: tasks that run at once
    results = []
    state = {"compute_s": 0.0, "k_done": len(reused), "cases_done": int(covered.sum())}
    try:
        if chunk_size is None:  # a multiple of 4 tasks per worker, at most MAX_AUTO_CHUNK cases each
            rounds = math.ceil(n_cases / (4 * n_workers * MAX_AUTO_CHUNK))
            chunk_size = sweep.spec.chunk_size or max(1, math.ceil(n_cases / (4 * n_workers * rounds)))
        todo = chunk_ranges(~covered, int(chunk_size))
        info = dict(chunks_total=len(reused) + len(todo), cases_total=n_cases)
        if progress is not None:
            progress(ChunkInfo(0, 0, len(reused), cases_done=state["cases_done"], wall_time_s=0.0, **info))

        def handle(a, b, ds):
            state["compute_s"] += float(ds.attrs.pop("sweep_chunk_seconds", 0.0))
            path = None
            if parts is not None:
                path = write_part(ds, parts, a, b, sweep.fingerprint)
            else:
                results.append(ds)
            state["k_done"] += 1
            state["cases_done"] += b - a
            if progress is not None:
                progress(ChunkInfo(a, b, state["k_done"], cases_done=state["cases_done"],
                                   wall_time_s=time.perf_counter() - t_start, path=path, **info))

        if synchronous:
            for a, b in todo:
                handle(a, b, run_chunk(sweep.job(a, b)))
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
    run = {"chunks": info["chunks_total"], "chunks_computed": len(todo), "chunks_reused": len(reused),
           "cases_computed": int(sum(b - a for a, b in todo)), "chunk_size": int(chunk_size),
           "wall_time_s": time.perf_counter() - t_start, "compute_time_s": state["compute_s"],
           "scheduler": scheduler_name, "workers": int(n_workers)}
    return results, run


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

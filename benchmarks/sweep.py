"""Sweep benchmark (issue 7): cases per second of the paper's Keplerian scenario (1 orbit)
on a local Dask cluster vs the serial ensemble call, and the overhead per task.

    python benchmarks/sweep.py [--cases N] [--workers W] [--tasks-cases M]

The sweep: ``scenarios/paper-keplerian.toml`` over one orbit (5828.5 s, dop853 at
rtol = atol = 1e-12 as the file says, outputs every 60 s), N cases with normal dispersions on
the three moments (1 %) and the three initial rates (1e-4 rad/s); outputs the final state and
the maximum pointing error.

Lines printed:

* ``serial``: one ensemble call over all N cases in this process (``Sweep.compute()``; numba
  uses every core) - the propagation alone (``propagate``) and with the reductions;
* ``cluster``: ``run_sweep`` on a ``LocalCluster`` of W processes x 1 thread (numba 1 thread
  per task), default chunking (4 tasks per worker), results gathered in memory and written
  to netCDF parts + merge; the cluster's start-up is reported apart;
* ``overhead``: per task, from a run of M one-case tasks:
  ``(wall x W - sum of in-task time) / tasks`` - scheduling, (de)serialisation, the driver's
  bookkeeping - besides the in-task time of a one-case chunk (integration, reductions, its
  Dataset), and the round trip of a no-op Dask task.

Timings are the best of ``--repeat`` runs (the machine may be shared). Results equal bit for
bit in every mode (checked).

Measured (2 CPU cores shared with other jobs, load ~1; numbers vary by up to 40 % from run
to run there)::

    serial   one ensemble call:   8744.5 cases/s propagate (0.94 s),   6926.7 cases/s with reductions (1.18 s)
    cluster  2 workers x 1 thread, 16 tasks of 512 cases:   6910.3 cases/s in memory (1.19 s),
             3960.2 cases/s to netCDF (2.07 s); start-up 0.4 s + first tasks 1.0 s; ratio to serial 1.00
    overhead 256 one-case tasks: 6.0 ms per task (wall x workers - in-task compute, in-task 1.8 ms each);
             Dask no-op round trip 10.5 ms, 637 no-op tasks/s

On two cores the cluster matches the serial ensemble call (numba's prange already uses both
cores); writing the parts and the merge run in the driver and take cores from the workers here.
"""
from __future__ import annotations

import argparse
import json
import logging
import os
import re
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def keplerian_sweep(cases, seed=1):
    from orbatt.scenario import Scenario, parse
    from orbatt.sweep import Sweep

    text = (ROOT / "scenarios" / "paper-keplerian.toml").read_text()
    text = re.sub(r"^t_end = .*$", 't_end = "1 orbit"', text, flags=re.M)
    text = re.sub(r"^output_step = .*$", 'output_step = "60 s"', text, flags=re.M)
    text += f"""
[sweep]
samples = {cases}
seed = {seed}
outputs = ["final_state", "max_pointing_error"]
[sweep.parameters]
inertia1 = {{ distribution = "normal", std = "4 kg km2" }}
inertia2 = {{ distribution = "normal", std = "5 kg km2" }}
inertia3 = {{ distribution = "normal", std = "6 kg km2" }}
omega1 = {{ distribution = "normal", std = "1e-4 rad/s" }}
omega2 = {{ distribution = "normal", std = "1e-4 rad/s" }}
omega3 = {{ distribution = "normal", std = "1e-4 rad/s" }}
"""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the paper's periapsis is inside the Earth (docs/design.md §9)
        return Sweep(Scenario(parse(text, "paper-keplerian-sweep.toml")))


def _noop():
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=8192)
    ap.add_argument("--workers", type=int, default=os.cpu_count())
    ap.add_argument("--tasks-cases", type=int, default=256, help="one-case tasks for the overhead measurement")
    ap.add_argument("--repeat", type=int, default=3, help="best of this many timings")
    args = ap.parse_args()

    import numba
    import xarray as xr
    from dask.distributed import Client, LocalCluster

    from orbatt.sweep import run_sweep

    W = args.workers
    sw = keplerian_sweep(args.cases)
    sw.compute(0, 2)  # compile / load the numba cache
    N = sw.cases
    print(f"# paper-keplerian, 1 orbit, {N} cases, dop853 rtol=atol=1e-12, outputs every 60 s; "
          f"{os.cpu_count()} CPUs, numba {numba.get_num_threads()} threads")

    t_serial = t_prop = np.inf
    for _ in range(args.repeat):  # best of: the machine may be shared
        t = time.perf_counter()
        serial = sw.compute()
        t_serial = min(t_serial, time.perf_counter() - t)
        t_prop = min(t_prop, json.loads(serial.attrs["integration_stats"])["wall_time_s"])
    print(f"serial   one ensemble call: {N / t_prop:8.1f} cases/s propagate ({t_prop:.2f} s), "
          f"{N / t_serial:8.1f} cases/s with reductions ({t_serial:.2f} s)")

    t = time.perf_counter()
    cluster = LocalCluster(n_workers=W, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address=None, silence_logs=logging.ERROR)
    client = Client(cluster)
    t_start = time.perf_counter() - t
    try:
        t = time.perf_counter()
        run_sweep(keplerian_sweep(4 * W), client=client, chunk_size=1)  # warm the workers (numba cache)
        t_warm = time.perf_counter() - t
        t_mem = t_file = np.inf
        for _ in range(args.repeat):
            t = time.perf_counter()
            mem = run_sweep(sw, client=client)
            t_mem = min(t_mem, time.perf_counter() - t)
            run = json.loads(mem.attrs["sweep_run"])
            xr.testing.assert_equal(mem.drop_attrs(deep=False), serial.drop_attrs(deep=False))
            with tempfile.TemporaryDirectory() as d:
                t = time.perf_counter()
                f = run_sweep(sw, Path(d) / "k.nc", client=client)
                t_file = min(t_file, time.perf_counter() - t)
                with f:
                    xr.testing.assert_equal(f.load().drop_attrs(deep=False), serial.drop_attrs(deep=False))
        print(f"cluster  {W} workers x 1 thread, {run['chunks']} tasks of {run['chunk_size']} cases: "
              f"{N / t_mem:8.1f} cases/s in memory ({t_mem:.2f} s), {N / t_file:8.1f} cases/s to netCDF "
              f"({t_file:.2f} s); start-up {t_start:.1f} s + first tasks {t_warm:.1f} s; "
              f"ratio to serial {t_serial / t_mem:.2f}")

        M = args.tasks_cases
        small = keplerian_sweep(M, seed=2)
        t = time.perf_counter()
        ds = run_sweep(small, client=client, chunk_size=1)
        wall = time.perf_counter() - t
        r = json.loads(ds.attrs["sweep_run"])
        per_task = (wall * W - r["compute_time_s"]) / M
        lat = []
        for _ in range(50):
            t = time.perf_counter()
            client.submit(_noop, pure=False).result()
            lat.append(time.perf_counter() - t)
        t = time.perf_counter()
        client.gather(client.map(lambda i: i, range(1000), pure=False))
        thr = 1000 / (time.perf_counter() - t)
        print(f"overhead {M} one-case tasks: {1e3 * per_task:.1f} ms per task (wall x workers - in-task compute, "
              f"in-task {1e3 * r['compute_time_s'] / M:.1f} ms each); Dask no-op round trip "
              f"{1e3 * float(np.median(lat)):.1f} ms, {thr:.0f} no-op tasks/s")
    finally:
        client.close()
        cluster.close()


if __name__ == "__main__":
    main()

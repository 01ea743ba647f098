"""Stress numba's disk cache of the kernels: several processes compile every kernel family
at once into one empty cache, and every result is checked bit for bit (issue 34, item 1).

Each trial gets an empty, isolated cache (``NUMBA_CACHE_DIR`` set to a fresh temporary folder:
the package's own cache is never touched). It starts ``--procs`` worker processes at once
(a barrier of files: their compiles fall within milliseconds of each other), each running
the same list of short jobs (single runs, ensembles, lockstep lanes, fixed-step methods, a
sweep, on the torque-free body and the shipped wheel, disturbance and B-dot scenarios) from
its own offset in the list: worker k compiles job k first, so different variants of one
closure (the DOP853 and Verner loops, the rigid and extended loops, ...) compile at the same
moment in different processes. Then two fresh processes load everything from that cache,
in the list's order and reversed. Every job's result (its arrays' bytes) is compared with
the reference computed once, by one process alone on its own empty cache.

A mismatch prints the trial, the process, the job and what the cache holds: every symbol
name that two different closure variants were compiled under (numba names a function's
machine code ``<qualname>`` + a per-process counter, :func:`symbol_clashes`).

    python benchmarks/cache_stress.py [--trials 3] [--procs 3] [--jobs tf-dop853,...]

Bounded: one trial compiles every job's kernels once per worker (~1-3 min on 2 busy cores).
"""
from __future__ import annotations

import argparse
import collections
import hashlib
import io
import json
import os
import pickle
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCEN = ROOT / "scenarios"


# ---------------------------------------------------------------------------------------
# the jobs (run in the worker processes)

def _content_arrays(name, t_end, method=None):
    import numpy as np
    from orbatt.scenario import Scenario, parse

    text = re.sub(r"^t_end = .*$", f't_end = "{t_end}"', (SCEN / f"{name}.toml").read_text(), flags=re.M)
    ds = Scenario(parse(text, f"{name}.toml")).run(method=method)
    return [np.ascontiguousarray(ds["q"].values), np.ascontiguousarray(ds["Q"].values)]


def _torque_free(method, ensemble=False, **kw):
    import numpy as np
    import orbatt

    st_q, st_Q = [0.5, -0.5 ** 0.5, 0.0, 0.5], [0.3, -0.848528, 0.141421, -1.5]
    t = np.linspace(0.0, 5.0, 4)
    if ensemble:
        bodies = [orbatt.RigidBody([1.25, 1.0, 0.75 + 0.01 * k]) for k in range(5)]
        st = orbatt.State(bodies[0], st_q, st_Q)
        tr = orbatt.propagate(bodies, st, orbatt.TorqueFree(), t, method=method, **kw)
    else:
        body = orbatt.RigidBody([1.25, 1.0, 0.75])
        st = orbatt.State(body, st_q, st_Q)
        tr = orbatt.propagate(body, st, orbatt.TorqueFree(), t, method=method, **kw)
    return [np.ascontiguousarray(tr.q), np.ascontiguousarray(tr.Q)]


def _sweep(name, t_end, method=None):
    import numpy as np
    from orbatt.scenario import Scenario, parse
    from orbatt.sweep import Sweep, run_sweep

    text = re.sub(r"^t_end = .*$", f't_end = "{t_end}"', (SCEN / f"{name}.toml").read_text(), flags=re.M)
    if method:
        text = re.sub(r'^method = .*$', f'method = "{method}"', text, count=1, flags=re.M)
    text += ('\n[sweep]\noutputs = ["final_state"]\n[sweep.parameters]\n'
             'omega1 = { values = ["-0.7 deg/s", "0.2 deg/s", "0.4 deg/s"] }\n')
    ds = run_sweep(Sweep(Scenario(parse(text, f"{name}-sweep.toml")), seed=1), scheduler="synchronous")
    return [np.ascontiguousarray(ds["q_final"].values), np.ascontiguousarray(ds["integration_failed"].values)]


#: name -> a function of no argument returning a list of arrays; neighbours in the list are
#: variants of one closure (the worker k starts at job k)
JOBS = {
    "tf-dop853": lambda: _torque_free("dop853", atol=1e-12),
    "tf-vern98": lambda: _torque_free("vern98", atol=1e-12),
    "wheels-dop853": lambda: _content_arrays("lvlh-hold-wheels", "300 s", "dop853"),
    "wheels-vern98": lambda: _content_arrays("lvlh-hold-wheels", "300 s", "vern98"),
    "tf-ens-dop853": lambda: _torque_free("dop853", ensemble=True, atol=1e-12),
    "tf-ens-vern98": lambda: _torque_free("vern98", ensemble=True, atol=1e-12),
    "wheels-sweep-dop853": lambda: _sweep("lvlh-hold-wheels", "300 s"),
    "wheels-sweep-vern98": lambda: _sweep("lvlh-hold-wheels", "300 s", "vern98"),
    "tf-lanes-dop853": lambda: _torque_free("dop853-lanes", ensemble=True, atol=1e-12),
    "tf-lanes-vern98": lambda: _torque_free("vern98-lanes", ensemble=True, atol=1e-12),
    "tf-splitting4": lambda: _torque_free("splitting4", step=0.01),
    "tf-rk4": lambda: _torque_free("rk4", step=0.01),
    "disturbances-dop853": lambda: _content_arrays("cubesat-3u-disturbances", "120 s", "dop853"),
    "bdot-dop853": lambda: _content_arrays("cubesat-bdot-detumble", "120 s", "dop853"),
}


def _digest(arrays):
    import numpy as np

    h = hashlib.sha1()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype}{a.shape};".encode())
        h.update(a.tobytes())
    return h.hexdigest()[:16]


def worker(names, barrier=None, n=0):
    """Run the jobs ``names`` in order (after the barrier of ``n`` processes); print
    ``{job: digest or "error: ..."}`` as JSON."""
    import warnings

    warnings.simplefilter("ignore")
    import orbatt  # noqa: F401 - imported before the barrier: the compiles start together
    import orbatt.scenario  # noqa: F401
    import orbatt.sweep  # noqa: F401

    if barrier is not None:
        barrier = Path(barrier)
        (barrier / f"ready-{os.getpid()}").touch()
        while len(list(barrier.glob("ready-*"))) < n:
            time.sleep(0.002)
    out = {}
    for name in names:
        try:
            out[name] = _digest(JOBS[name]())
        except Exception as exc:  # noqa: BLE001 - reported as the job's result
            out[name] = f"error: {type(exc).__name__}: {str(exc)[:200]}"
    print(json.dumps(out))


# ---------------------------------------------------------------------------------------
# the driver

#: the folder whose ``orbatt`` the workers import (``--source``; default: this checkout)
SOURCE = ROOT


def _start(cache, names, barrier=None, n=0):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "ORBATT_COLD_START": "compile", "PYTHONSAFEPATH": "1",
           "PYTHONPATH": os.pathsep.join([str(SOURCE), *filter(None, [os.environ.get("PYTHONPATH")])])}
    cmd = [sys.executable, "-P", str(Path(__file__).resolve()), "--worker", ",".join(names)]
    if barrier is not None:
        cmd += ["--barrier", str(barrier), "--n", str(n)]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)


def _result(proc, timeout=1800):
    out, err = proc.communicate(timeout=timeout)
    if proc.returncode != 0:
        return {"(process)": f"error: exit {proc.returncode}: {err.strip()[-400:]}"}
    return json.loads(out.strip().splitlines()[-1])


def symbol_clashes(cache) -> list[str]:
    """Each machine-code symbol in the numba cache folder ``cache`` that two closure variants
    (two different closure digests in the index keys) were compiled under: a process loading
    both binds the second's calls to the first's code."""
    import numba  # noqa: F401 - unpickling the entries needs it

    names = collections.defaultdict(set)
    for nbi in Path(cache).rglob("*.nbi"):
        try:
            f = io.BytesIO(nbi.read_bytes())
            pickle.load(f)
            _, overloads = pickle.loads(f.read())
        except Exception:  # noqa: BLE001 - another numba, or being written
            continue
        for key, data_name in overloads.items():
            try:
                fndesc = pickle.loads((nbi.parent / data_name).read_bytes())[1]
            except Exception:  # noqa: BLE001
                continue
            names[fndesc.mangled_name].add((key[2][1][:10], data_name))
    return [f"{name[:90]}...: {sorted(v)}" for name, v in names.items() if len({c for c, _ in v}) > 1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--procs", type=int, default=3)
    ap.add_argument("--jobs", default=",".join(JOBS), help="comma-separated job names (default: all)")
    ap.add_argument("--reference", help="a JSON file of reference digests (written if missing)")
    ap.add_argument("--source", help="the folder holding the orbatt to test (default: this checkout)")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--barrier", help=argparse.SUPPRESS)
    ap.add_argument("--n", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker is not None:
        worker(args.worker.split(","), args.barrier, args.n)
        return 0

    global SOURCE
    if args.source:
        SOURCE = Path(args.source).resolve()
    names = args.jobs.split(",")
    root = Path(tempfile.mkdtemp(prefix="orbatt-cache-stress-"))
    print(f"cache stress: {args.trials} trials x {args.procs} processes, {len(names)} jobs, orbatt from {SOURCE}; "
          f"caches under {root}")
    ref_file = Path(args.reference) if args.reference else None
    if ref_file is not None and ref_file.is_file():
        ref = json.loads(ref_file.read_text())
    else:
        t0 = time.monotonic()
        ref = _result(_start(root / "reference", names))
        print(f"reference: one process on an empty cache, {time.monotonic() - t0:.0f} s")
        if ref_file is not None:
            ref_file.write_text(json.dumps(ref, indent=1))
    bad_ref = {k: v for k, v in ref.items() if v.startswith("error")}
    if bad_ref:
        print("the reference run failed:", bad_ref)
        return 2
    failures = 0
    for trial in range(args.trials):
        cache = root / f"trial-{trial}"
        barrier = root / f"barrier-{trial}"
        barrier.mkdir()
        t0 = time.monotonic()
        procs = [_start(cache, names[k % len(names):] + names[:k % len(names)], barrier, args.procs)
                 for k in range(args.procs)]
        results = {f"worker {k}": _result(p) for k, p in enumerate(procs)}
        t1 = time.monotonic()
        results["loader (in order)"] = _result(_start(cache, names))
        results["loader (reversed)"] = _result(_start(cache, names[::-1]))
        bad = [(who, job, got) for who, res in results.items() for job, got in res.items() if got != ref.get(job)]
        failures += len(bad)
        print(f"trial {trial}: compile {t1 - t0:.0f} s, loads {time.monotonic() - t1:.0f} s, "
              f"{sum(len(r) for r in results.values())} results, {len(bad)} wrong")
        for who, job, got in bad:
            print(f"    {who}: {job}: {got} (reference {ref.get(job)})")
        clashes = symbol_clashes(cache)
        if clashes:
            print(f"    {len(clashes)} symbol(s) compiled for two closure variants:")
            for c in clashes:
                print(f"      {c}")
    print(f"total: {failures} wrong results in {args.trials} trials x ({args.procs} workers + 2 loaders)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

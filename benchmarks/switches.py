"""Steps that land on switches (issue 25, item 2): rejected steps, right-hand-side evaluations,
wall time and accuracy of every shipped single-trajectory scenario, with the switch location on
and off in the same run.

For each scenario (a sweep's nominal case; not the binaries): ``orbatt.propagate`` on the scenario's body, state, potential and output
times at its own tolerance, with ``switches=True`` (the default: steps land on the zeros of the
switching functions, :mod:`orbatt.core.switches`) and ``switches=False``; the error is the
largest rotation angle between the run's attitudes and a reference run at ``rtol / 1000``
(switches on), over the output times of the first tenth of the span (``--horizon``: the tumbling
cubesat's attitude over a day is chaotic enough that runs at different tolerances part
completely). ``ref`` is the same angle between the references with and without switches
(how far the reference can be trusted). Attempts count accepted, rejected and retaken steps
(``rej %``: rejected for their error; ``retake %``: retaken to end on a switch). Usage::

    python benchmarks/switches.py [--only NAME ...] [--repeat N] [--horizon F] [--work-precision]

``--work-precision``: then, for each scenario with switches, the error and the right-hand-side
evaluations at rtol = atol 1e-7 .. 1e-12, with and without location (accuracy per RHS).
"""
from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import orbatt
from orbatt.scenario.load import shipped_scenarios

#: the binaries run another driver (a sweep scenario runs its nominal case here)
SKIP = ("didymos", "sphere-ellipsoid")


def angle(q1, q2):
    """Largest rotation angle (rad) between the unit attitudes ``q1``, ``q2`` (N, 4)."""
    d = np.minimum(np.linalg.norm(q1 - q2, axis=-1), np.linalg.norm(q1 + q2, axis=-1))
    return float(np.max(4.0 * np.arcsin(np.minimum(1.0, 0.5 * d))))


def run(sc, switches, rtol=None, repeat=1):
    kw = dict(sc.settings)
    if rtol is not None:
        kw["rtol"] = rtol
        kw["atol"] = rtol
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        tr = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method=sc.method, switches=switches, **kw)
        w = time.perf_counter() - t0
        best = w if best is None else min(best, w)
    return tr, best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--horizon", type=float, default=0.1)
    ap.add_argument("--work-precision", action="store_true")
    a = ap.parse_args(argv)
    print(f"{'scenario':28s} {'loc':>3s} {'attempts':>9s} {'rej %':>6s} {'retake %':>8s} {'RHS':>9s} "
          f"{'wall s':>8s} {'err rad':>9s} {'ref rad':>9s}")
    switched = []
    for name, _, path in shipped_scenarios():
        if any(s in name for s in SKIP) or (a.only and name not in a.only):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sc = orbatt.load_scenario(path)
            if sc.method != "dop853":
                continue
            rtol = sc.settings.get("rtol", 1e-10)
            ref, _ = run(sc, True, rtol=max(rtol / 1000, 2.5e-15))
            ref_off, _ = run(sc, False, rtol=max(rtol / 1000, 2.5e-15))
            t = np.asarray(ref.t, dtype=np.float64)
            m = t <= t[0] + a.horizon * (t[-1] - t[0])
            qref = np.asarray(ref.q)[m]
            dref = angle(np.asarray(ref_off.q)[m], qref)
            rows = []
            for loc in (False, True):
                tr, w = run(sc, loc, repeat=a.repeat)
                rows.append((loc, tr, w))
        if rows[1][1].stats["switch_retakes"]:
            switched.append((name, sc, ref, m))
        for loc, tr, w in rows:
            s = tr.stats
            att = s["steps"] + s["rejected_steps"] + s["switch_retakes"]
            print(f"{name:28s} {'on' if loc else 'off':>3s} {att:9d} {100 * s['rejected_steps'] / att:6.2f} "
                  f"{100 * s['switch_retakes'] / att:8.2f} {s['rhs_evaluations']:9d} {w:8.3f} "
                  f"{angle(np.asarray(tr.q)[m], qref):9.2e} {dref:9.2e}")

    if a.work_precision:
        work_precision(switched)


def work_precision(switched):
    """Error (against the scenario's reference) and RHS evaluations over a range of tolerances,
    location off and on."""
    print(f"\n{'scenario':28s} {'rtol':>7s} {'RHS off':>9s} {'err off':>9s} {'RHS on':>9s} {'err on':>9s}")
    for name, sc, ref, m in switched:
        qref = np.asarray(ref.q)[m]
        for rtol in (1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = [run(sc, loc, rtol=rtol)[0] for loc in (False, True)]
            cols = " ".join(f"{r.stats['rhs_evaluations']:9d} {angle(np.asarray(r.q)[m], qref):9.2e}" for r in res)
            print(f"{name:28s} {rtol:7.0e} {cols}")


if __name__ == "__main__":
    main()

"""Verner's 9(8) pair (``method="vern98"``) against DOP853 (``"dop853"``) at tight tolerances
(issue 15): the work-precision of both on the benchmark cases of ``run.py``.

    python benchmarks/verner98.py [--repeats N]

For the Keplerian gravity-gradient case (10 orbits) in the eccentric anomaly (default form)
and in time, and for the torque-free case: for every grid rtol (= atol) from 1e-7 to 1e-14
(4 per decade, ``run.RTOLS``) the steps, RHS evaluations, final attitude error against the
case's reference, and the step loop's wall time (``stats['wall_time_s']``, best of
``repeats``, the two methods alternated A, B, A, B ... so that a busy machine slows both).
Then, per target (1e-6 and 1e-9 rad), the loosest grid rtol reaching it per method and the
ratio of loop times vern98 / dop853.
"""
from __future__ import annotations

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import orbatt  # noqa: E402
from run import RTOLS, angle, free_case, kepler_case  # noqa: E402

METHODS = ("dop853", "vern98")
GRID = [r for r in RTOLS if 0.99e-14 <= r <= 1.01e-7]


def measure(case, form, repeats):
    """``{(method, rtol): (steps, nfev, err, best loop s)}``."""
    kw = {} if form is None else {"independent_variable": form}
    res = {}
    for rtol in GRID:
        best = {m: float("inf") for m in METHODS}
        last = {}
        for _ in range(repeats):
            for m in METHODS:
                tr = orbatt.propagate(case.body, case.state, case.potential, [0.0, case.T], method=m,
                                      rtol=rtol, atol=rtol, **kw)
                best[m] = min(best[m], tr.stats["wall_time_s"])
                last[m] = tr
        for m in METHODS:
            s = last[m].stats
            res[m, rtol] = (s["steps"], s["rhs_evaluations"], angle(last[m].q[-1], case.qref), best[m])
    return res


def report(title, res, targets):
    print(f"\n## {title}")
    print(f"{'rtol':>9} | " + " | ".join(f"{m:>7} steps  nfev    error     loop ms" for m in METHODS))
    for rtol in GRID:
        cells = []
        for m in METHODS:
            st, nf, err, w = res[m, rtol]
            cells.append(f"{'':>7} {st:5d} {nf:6d}  {err:8.1e}  {w * 1e3:8.3f}")
        print(f"{rtol:9.2e} | " + " | ".join(cells))
    for target in targets:
        found = {}
        for m in METHODS:
            for rtol in GRID:
                if res[m, rtol][2] <= target:
                    found[m] = (rtol, *res[m, rtol])
                    break
        line = [f"target {target:.0e} rad:"]
        for m in METHODS:
            if m in found:
                rtol, st, nf, err, w = found[m]
                line.append(f"{m} rtol {rtol:.2e} ({st} steps, {nf} f, {err:.1e} rad, {w * 1e3:.3f} ms)")
            else:
                line.append(f"{m}: not reached on the grid")
        if len(found) == 2:
            line.append(f"ratio vern98/dop853 loop time {found['vern98'][4] / found['dop853'][4]:.2f}, "
                        f"steps {found['vern98'][1] / found['dop853'][1]:.2f}, "
                        f"f {found['vern98'][2] / found['dop853'][2]:.2f}")
        print("  ".join(line))
        interp = {m: at_error(res, m, target) for m in METHODS}
        if all(v is not None for v in interp.values()):
            d, v = interp["dop853"], interp["vern98"]
            print(f"  at exactly {target:.0e} rad (log-log interpolation between grid points): dop853 {d[0]:.0f} f, "
                  f"{d[1] * 1e3:.3f} ms; vern98 {v[0]:.0f} f, {v[1] * 1e3:.3f} ms; ratio f {v[0] / d[0]:.2f}, "
                  f"loop time {v[1] / d[1]:.2f}")


def at_error(res, m, target):
    """``(nfev, loop s)`` of ``m`` at the error ``target``, log-log interpolated between the
    two neighbouring grid points (None if the grid does not bracket it)."""
    pts = [(res[m, r][2], res[m, r][1], res[m, r][3]) for r in GRID]
    for (e0, f0, w0), (e1, f1, w1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > e1:
            x = math.log(target / e0) / math.log(e1 / e0)
            return f0 * (f1 / f0) ** x, w0 * (w1 / w0) ** x
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    kc = kepler_case()
    fc = free_case()
    for c in (kc, fc):  # compile / warm up
        for m in METHODS:
            orbatt.propagate(c.body, c.state, c.potential, [0.0, c.T], method=m, rtol=1e-10, atol=1e-10)
            orbatt.propagate(c.body, c.state, c.potential, [0.0, c.T], method=m, rtol=1e-10, atol=1e-10,
                             independent_variable="time")
    print(kc.ref_note)
    report(f"{kc.name}, eccentric anomaly (default)", measure(kc, None, args.repeats), (1e-6, 1e-9))
    report(f"{kc.name}, time", measure(kc, "time", args.repeats), (1e-6, 1e-9))
    report(fc.name, measure(fc, None, args.repeats), (1e-6, 1e-9))


if __name__ == "__main__":
    main()

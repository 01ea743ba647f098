"""Stepping between the flight software's ticks (issue 32, item 8): Dormand-Prince 5(4)
(``method="dopri5"``) against DOP853 (``"dop853"``) on a 10 Hz loop, measured in one run.

    python benchmarks/tick_stepping.py [--orbits X] [--repeats N]

The loop: the 6U fine-pointing loop of ``benchmarks/basilisk_fine_pointing.py``
(``scenarios/cubesat-fine-pointing.toml`` when it exists, else ``scenarios/cubesat-slew-
wheels.toml`` with a gyro at 10 Hz, a star tracker at 1 Hz and the MEKF, the law on the
estimate, starting on the target: an inertial hold), 10 Hz PD on three wheels, the gravity
gradient on a 550 km SSO, ``X`` orbits (default 1, ~57,000 ticks), outputs every second.
Every step lands on a tick (no step crosses one; docs/design.md §4).

Tables (ratios against ``dop853`` at the scenario's rtol = atol = 1e-10, measured in the same
run, the methods alternated A, B, A, B ... so that a busy machine slows both):

1. per method and rtol: accepted and rejected steps, steps per tick, RHS evaluations (per
   step and per orbit), the step loop's wall time per orbit (``stats['wall_time_s']``, best of
   ``N``), the largest attitude difference from ``dop853`` at rtol = atol = 1e-12 over the
   outputs, and the ratios.
2. the same without sensors (the shipped slew: a 90 deg rate-limited slew at 1 deg/s, then the
   hold; the command changes fastest there) and on ``lvlh-hold-wheels`` at 10 Hz.
3. whether the derivative after a tick must be evaluated again: over 200 s sampled at every
   tick, the fraction of ticks at which the held motor torques (``wheel_torque``) changed.
4. without ticks, for contrast: the paper's Keplerian gravity-gradient case of ``run.py`` (10
   orbits, the eccentric anomaly), the final attitude error against its reference, per rtol.
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import orbatt  # noqa: E402
from orbatt import quaternion as qt  # noqa: E402
from orbatt.scenario import Scenario, parse  # noqa: E402
from run import kepler_case  # noqa: E402
from basilisk_fine_pointing import SENSORS  # noqa: E402  (the fine-pointing loop's sensors and MEKF)

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "scenarios" / "cubesat-fine-pointing.toml"
SLEW = ROOT / "scenarios" / "cubesat-slew-wheels.toml"
LVLH = ROOT / "scenarios" / "lvlh-hold-wheels.toml"
PERIOD = 0.1  # s, the flight software's tick
#: (method, rtol): the runs of table 1 (the reference: dop853 at 1e-12)
RUNS = (("dop853", 1e-10), ("dopri5", 1e-10), ("vern98", 1e-10), ("dopri5", 1e-8), ("dopri5", 1e-12))
REFERENCE = ("dop853", 1e-12)


def fine_pointing_text(t_end, output_step="1 s"):
    """The fine-pointing loop (module docstring), ``t_end`` seconds."""
    if SHIPPED.exists():
        text = SHIPPED.read_text()
    else:
        text = SLEW.read_text().replace('period = "0.1 s"\n', 'period = "0.1 s"\n' + SENSORS, 1)
        target = re.search(r"target_q = (\[[^\]]*\])", text).group(1)
        text = re.sub(r'(\[initial\][^\[]*?)q = \[[^\]]*\]', lambda m: f"{m.group(1)}q = {target}", text, count=1)
    return _span(text, t_end, output_step)


def _span(text, t_end, output_step):
    text = re.sub(r'^t_end = "[^"]*"', f't_end = "{t_end:.10g} s"', text, flags=re.M)
    return re.sub(r'^output_step = "[^"]*"', f'output_step = "{output_step}"', text, flags=re.M)


def slew_text(t_end):
    """The shipped slew on wheels (no sensors), ``t_end`` seconds."""
    return _span(SLEW.read_text(), t_end, "1 s")


def lvlh_text(t_end):
    """``lvlh-hold-wheels`` with its law at 10 Hz, ``t_end`` seconds."""
    text = LVLH.read_text().replace("[control]\n", f'[control]\nperiod = "{PERIOD} s"\n', 1)
    return _span(text, t_end, "20 s")


def angle(q, qref):
    """Rotation angle between attitudes (rad), sign-insensitive."""
    w = qt.mul(qt.conj(np.asarray(qref)), np.asarray(q))
    return 2 * np.arctan2(np.linalg.norm(w[..., 1:], axis=-1), np.abs(w[..., 0]))


def measure(sc, runs, repeats):
    """``{(method, rtol): (stats, best loop s, q)}`` of the scenario ``sc`` (rtol = atol)."""
    best = {r: np.inf for r in runs}
    last = {}
    for _ in range(repeats):
        for m, rtol in runs:
            ds = sc.run(method=m, rtol=rtol, atol=rtol)
            best[m, rtol] = min(best[m, rtol], ds.orbatt.stats["wall_time_s"])
            last[m, rtol] = (ds.orbatt.stats, ds["q"].values)
    return {r: (last[r][0], best[r], last[r][1]) for r in runs}


def table(title, res, ticks, per, base=("dop853", 1e-10), ref=REFERENCE):
    """Print one table: ``ticks`` in the span, ``per`` the span in orbits."""
    print(f"\n### {title}")
    print("| method | rtol | steps | rejected | steps/tick | RHS/step | RHS per orbit | loop s per orbit | "
          "max attitude diff vs dop853 1e-12 (rad) | RHS ratio | time ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    s0, w0, _ = res[base]
    qref = res[ref][2]
    for (m, rtol), (s, w, q) in res.items():
        if (m, rtol) == ref:
            continue
        err = angle(q, qref).max()
        print(f"| {m} | {rtol:.0e} | {s['steps']} | {s['rejected_steps']} | {s['steps'] / ticks:.3f} | "
              f"{s['rhs_evaluations'] / s['steps']:.2f} | {s['rhs_evaluations'] / per:,.0f} | {w / per:.4f} | "
              f"{err:.1e} | {s['rhs_evaluations'] / s0['rhs_evaluations']:.3f} | {w / w0:.3f} |")


def command_changes(text_of, t_end=200.0):
    """The fraction of ticks at which the held motor torques changed (outputs at every tick:
    an output at a tick shows the command issued there), and the number of ticks."""
    sc = Scenario(parse(text_of(t_end), "changes.toml"))
    sc.times = np.arange(round(t_end / PERIOD) + 1) * PERIOD
    ds = sc.run(method="dop853")
    u = ds["wheel_torque"].values
    changed = np.any(u[1:] != u[:-1], axis=-1)
    return changed.mean(), changed.size


def without_ticks(repeats):
    """Table 4: dop853 and dopri5 on the Keplerian case (no ticks), per rtol."""
    case = kepler_case()
    print(f"\n### Without ticks: {case.name} ({case.ref_note})")
    print("| rtol | dop853 steps | dop853 RHS | dop853 error (rad) | dop853 loop s | dopri5 steps | dopri5 RHS | "
          "dopri5 error (rad) | dopri5 loop s | RHS ratio | time ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for m in ("dop853", "dopri5"):  # compile, once
        orbatt.propagate(case.body, case.state, case.potential, [0.0, 1.0], method=m)
    for rtol in (1e-8, 1e-10, 1e-12):
        best, last = {}, {}
        for _ in range(repeats):
            for m in ("dop853", "dopri5"):
                tr = orbatt.propagate(case.body, case.state, case.potential, [0.0, case.T], method=m, rtol=rtol,
                                      atol=rtol)
                best[m] = min(best.get(m, np.inf), tr.stats["wall_time_s"])
                last[m] = tr
        cells = [f"{last[m].stats['steps']} | {last[m].stats['rhs_evaluations']} | "
                 f"{angle(last[m].q[-1], case.qref):.1e} | {best[m]:.4f}" for m in ("dop853", "dopri5")]
        r = last["dopri5"].stats["rhs_evaluations"] / last["dop853"].stats["rhs_evaluations"]
        print(f"| {rtol:.0e} | {cells[0]} | {cells[1]} | {r:.2f} | {best['dopri5'] / best['dop853']:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--orbits", type=float, default=1.0, help="orbits of the fine-pointing loop (default 1)")
    ap.add_argument("--repeats", type=int, default=3, help="best of N for the wall times (default 3)")
    args = ap.parse_args()
    load = os.getloadavg()
    print(f"# tick stepping: dopri5 against dop853 at 10 Hz (load average {load[0]:.2f} {load[1]:.2f})")
    probe = Scenario(parse(fine_pointing_text(10.0), "fp.toml"))
    T = probe.orbit.period_value
    t_end = args.orbits * T
    fp = Scenario(parse(fine_pointing_text(t_end), "fp.toml"))
    runs = RUNS + (REFERENCE,)
    for m, rtol in runs:  # compile, once
        Scenario(parse(fine_pointing_text(1.0), "warm.toml")).run(method=m, rtol=rtol, atol=rtol)
    t0 = time.perf_counter()
    res = measure(fp, runs, args.repeats)
    ticks = round(t_end / PERIOD)
    table(f"Fine pointing (gyro, star tracker, MEKF, PD on wheels at 10 Hz), {args.orbits:g} orbit "
          f"({t_end:.0f} s, {ticks} ticks)", res, ticks, args.orbits)
    print(f"\n(measured in {time.perf_counter() - t0:.0f} s)")
    span = 600.0
    short = (("dop853", 1e-10), ("dopri5", 1e-10), REFERENCE)
    res = measure(Scenario(parse(slew_text(span), "slew.toml")), short, args.repeats)
    table(f"The shipped slew (90 deg at 1 deg/s, then hold; no sensors), {span:.0f} s", res, round(span / PERIOD),
          span / T)
    lvlh = Scenario(parse(lvlh_text(3000.0), "lvlh.toml"))
    res = measure(lvlh, short, args.repeats)
    table("lvlh-hold-wheels with its law at 10 Hz, 3000 s", res, round(3000.0 / PERIOD),
          3000.0 / lvlh.orbit.period_value)
    print("\n### Ticks at which the held command changed (200 s, every tick sampled)")
    for name, text_of in (("fine pointing", fine_pointing_text), ("slew", slew_text)):
        frac, n = command_changes(text_of)
        print(f"- {name}: {frac:.4f} of {n} ticks")
    without_ticks(args.repeats)


if __name__ == "__main__":
    main()

"""The environment-torque ensemble against the gravity-gradient-only one (issue 23, item 5):
part B of ``benchmarks/montecarlo.py``, also run alone.

    python benchmarks/env_ensemble.py            # N = 200 members, 3 repeats
    python benchmarks/env_ensemble.py --quick    # N = 50, 2 repeats (about 1 minute)
    NUMBA_NUM_THREADS=1 python benchmarks/env_ensemble.py --quick --cpu-time   # a loaded machine

``scenarios/cubesat-3u-disturbances.toml`` (3U, six facets, NRLMSIS drag with co-rotation, SRP
with a conical shadow, a residual dipole in IGRF, gravity gradient) over one orbit, as an
ensemble of N members (random attitudes, rates 0.5 deg/s rms) through ``orbatt.propagate``
with a batch ``State``, against the same members under the gravity gradient alone on the same
orbit and under each environment torque alone, at the scenario's tolerances (rtol 1e-10, atol
1e-12); ``dop853`` (members independent) and ``dop853-lanes``. Printed beside the throughput
(body-orbits per second, ratios against the gravity gradient alone measured in the same run):
the error of the first members' final attitudes against a tight run of the same model (rtol
3e-15), steps and right-hand sides per member, ns per right-hand side, and the time to sample
the environment along the orbit (building the tables, once per orbit, shared by the members)
with its largest items (cProfile). Results: ``benchmarks/README.md``, section "Monte Carlo".
"""
from __future__ import annotations

import argparse
import cProfile
import io
import math
import pstats
import re
import shutil
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
ENV_SCENARIO = ROOT / "scenarios" / "cubesat-3u-disturbances.toml"

warnings.simplefilter("ignore")


def stats(xs):
    """``(best, median)`` of the timings ``xs``."""
    return min(xs), statistics.median(xs)


#: the environment-torque variants of the scenario: (label, regex substitutions)
_DIPOLE, _FIELD = r"^residual_dipole = .*\n", r"^magnetic_field = .*\n"
_ATMOSPHERE, _SHADOW = r"^(atmosphere|f107|f107a|ap|corotation) = .*\n", r"^shadow = .*\n"
_FACETS = r"^\[\[body\.facets\]\].*\n(?:[^\[\n].*\n|\n)*"
ENV_VARIANTS = [
    ("GG + magnetic (residual dipole, IGRF)", [(r"^drag = true", "drag = false"), (r"^srp = true", "srp = false"),
                                               (_ATMOSPHERE, ""), (_SHADOW, ""), (_FACETS, "")]),
    ("GG + drag (NRLMSIS, 6 facets)", [(r"^srp = true", "srp = false"), (_DIPOLE, ""), (_FIELD, ""), (_SHADOW, "")]),
    ("GG + SRP (conical shadow, 6 facets)", [(r"^drag = true", "drag = false"), (_DIPOLE, ""), (_FIELD, ""),
                                             (_ATMOSPHERE, "")]),
    ("GG + drag + SRP + magnetic", []),
]


def env_scenarios(folder):
    """``cubesat-3u-disturbances`` shortened to one orbit, and its variants with one
    environment torque each: ``[(label, path)]`` (:data:`ENV_VARIANTS`)."""
    text = ENV_SCENARIO.read_text()
    text = re.sub(r'^t_end = .*$', 't_end = "1 orbits"', text, flags=re.M)
    text = re.sub(r'^output_step = .*$', 'output_step = "600 s"', text, flags=re.M)
    out = []
    for k, (label, subs) in enumerate(ENV_VARIANTS):
        t = text
        for pattern, repl in subs:
            t, n = re.subn(pattern, repl, t, flags=re.M)
            assert n, pattern
        path = Path(folder) / f"cubesat-3u-disturbances-{k}.toml"
        path.write_text(t)
        out.append((label, path))
    return out


#: members whose final attitude is compared with a tight run (table B's error column)
ERROR_MEMBERS = 8


def part_b(n_members, repeats, cpu_time=False):
    """Measure and print part B, the environment-torque ensemble against the gravity gradient.

    Parameters
    ----------
    n_members : int
        Ensemble members.
    repeats : int
        Alternated repeats (``dop853-lanes``: at most 2).
    cpu_time : bool
        Time the loops by the process's CPU time around ``propagate`` (with
        ``NUMBA_NUM_THREADS=1``: the loop's own cost, whatever else the machine runs) instead
        of their wall time.
    """
    import orbatt
    from astropy import units as u

    from orbatt import quaternion as qt
    from orbatt.scenario import load_scenario
    from orbatt.scenario.build import build_potential
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from run import angle

    folder = Path(tempfile.mkdtemp(prefix="orbatt-env-"))
    variants = [(label, load_scenario(path)) for label, path in env_scenarios(folder)]
    sc = variants[-1][1]
    t_end = float(sc.t_end)
    rtol, atol = sc.settings["rtol"], sc.settings["atol"]
    print(f"\n## B. Environment-torque ensemble: cubesat-3u-disturbances over one orbit ({t_end:.0f} s), "
          f"N = {n_members}, rtol {rtol:g}, atol {atol:g}\n")
    rng = np.random.default_rng(7)
    q = qt.normalize(rng.normal(size=(n_members, 4)))
    w = rng.normal(size=(n_members, 3)) * math.radians(0.5)
    states = orbatt.State.from_omega(sc.body, q, w * u.rad / u.s)
    firsts = orbatt.State.from_omega(sc.body, q[:ERROR_MEMBERS], w[:ERROR_MEMBERS] * u.rad / u.s)
    models = [("gravity gradient alone", orbatt.GravityGradient(sc.orbit), 0.0)]
    for label, v in variants:   # sampling the environment along the orbit (tables shared by all members)
        samp = []
        for _ in range(2):
            t0 = time.perf_counter()
            pot = build_potential(v.spec, v.orbit, t_end)
            pot.kernel_model()
            samp.append(time.perf_counter() - t0)
        models.append((label, pot, min(samp)))
    prof = cProfile.Profile()
    prof.enable()
    build_potential(sc.spec, sc.orbit, t_end).kernel_model()
    prof.disable()
    refs = {}   # the final attitudes of the first ERROR_MEMBERS members from a tight run, per model
    for label, pot, _ in models:
        refs[label] = orbatt.propagate(sc.body, firsts, pot, [0.0, t_end], rtol=3e-15,
                                       atol=1e-18).q[:, -1]
    rows = []
    for method in ("dop853", "dop853-lanes"):
        chosen = models if method == "dop853" else [models[0], models[-1]]
        loops, last, errors, refused = {}, {}, {}, {}
        for label, pot, _ in chosen:   # compile, or learn that the method refuses the model
            try:
                orbatt.propagate(sc.body, states, pot, [0.0, t_end], method=method, rtol=rtol, atol=atol)
                loops[label] = []
            except Exception as exc:  # noqa: BLE001 - a method that refuses the model: say so
                refused[label] = str(exc).splitlines()[0]
        for _ in range(repeats if method == "dop853" else min(repeats, 2)):   # alternate the models
            for label, pot, _ in chosen:
                if label in loops:
                    c0 = time.process_time()
                    tr = orbatt.propagate(sc.body, states, pot, [0.0, t_end], method=method, rtol=rtol, atol=atol)
                    cpu = time.process_time() - c0
                    loops[label].append(cpu if cpu_time else tr.stats["wall_time_s"])
                    last[label] = tr.stats
                    errors[label] = max(angle(tr.q[e, -1], refs[label][e]) for e in range(ERROR_MEMBERS))
        for label, _, samp in chosen:
            rows.append((method, label, (stats(loops[label]), last[label], errors[label]) if label in loops else None,
                         refused.get(label), samp))
    orbits = t_end / sc.orbit.period_value
    print(f"{'method':<13} {'model':<38} {'loop best':>9} {'median':>9} {'body-orbits/s':>13} {'vs GG':>7} "
          f"{'steps/m':>8} {'RHS/m':>7} {'ns/RHS':>7} {'error':>8} {'tables':>7}")
    base = {}
    for method, label, res, err, samp in rows:
        if res is None:
            print(f"{method:<13} {label:<38} refused: {err}")
            continue
        (lb, lm), st, error = res
        rate = n_members * orbits / lb
        base.setdefault(method, rate)
        print(f"{method:<13} {label:<38} {lb * 1e3:7.1f}ms {lm * 1e3:7.1f}ms {rate:13.0f} {rate / base[method]:6.3f}x "
              f"{st['steps'] / n_members:8.0f} {st['rhs_evaluations'] / n_members:7.0f} "
              f"{lb / st['rhs_evaluations'] * 1e9:7.0f} {error:8.1e} {samp:6.2f}s")
    print(f"(loop = the compiled ensemble call, {'CPU time of propagate' if cpu_time else 'its wall_time_s'}; "
          "steps and RHS per member, "
          "dop853-lanes counts every lane of a group; error = the largest angle (rad) between the final attitude "
          f"and a tight run's (rtol 3e-15) over the first {ERROR_MEMBERS} members; tables = sampling the environment "
          "along the orbit, build_potential + kernel_model, once per orbit for all members)")
    print("\nSampling the full environment, largest items (cProfile, cumulative):")
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("cumulative").print_stats(14)
    for line in s.getvalue().splitlines():
        if re.match(r"\s+\d", line) and "{built-in method builtins.exec}" not in line:
            print("   ", line.strip()[:150])
    shutil.rmtree(folder, ignore_errors=True)


def main(argv=None):
    """The command line (``--help``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 50 members, 2 repeats")
    ap.add_argument("--cpu-time", action="store_true",
                    help="time the loops by CPU time (run with NUMBA_NUM_THREADS=1 on a loaded machine)")
    args = ap.parse_args(argv)
    print(f"orbatt environment-ensemble benchmark ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{'--quick' if args.quick else 'default'})")
    part_b(50 if args.quick else 200, 2 if args.quick else 3, cpu_time=args.cpu_time)


if __name__ == "__main__":
    main()

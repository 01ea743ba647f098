"""Where a right-hand side of the environment-torque ensemble goes (issue 23, item 5): the cost
of each part of one evaluation, and the throughput ratio against the gravity gradient alone
that each part allows.

    NUMBA_NUM_THREADS=1 python benchmarks/rhs_breakdown.py            # 200,000 evaluations
    NUMBA_NUM_THREADS=1 python benchmarks/rhs_breakdown.py --quick    # 50,000

The models of ``benchmarks/env_ensemble.py`` (``cubesat-3u-disturbances`` over one orbit, the
gravity gradient alone and with each environment torque, then all four), in the form the DOP853
loops run them (the eccentric anomaly as the independent variable, ``orbatt.methods.dop853``).
Each part runs in its own compiled loop over the same points (anomalies in increasing order
over the orbit, as a step loop visits them; random attitudes), by CPU time, best of 5; every
result is summed into the loop's return value, so that no part is optimized away:

* ``rhs``: :func:`orbatt.core.hamiltonian.rhs` (called), the whole evaluation;
* ``orbit``: :func:`orbatt.core.model.orbit_at` (closed form in the anomaly);
* ``constants``: what each term reads from the orbit and the environment tables
  (:func:`orbatt.core.model.term_constants`), net of ``orbit``;
* ``values``: each term's torque and generalized gradient at the attitude
  (:func:`orbatt.core.model.term_value`), the constants given;
* ``rest``: ``rhs`` minus the three (the kinetic part, eq. 7, and the sums).

Then the ratio to the gravity gradient's throughput, from the right-hand sides per member of a
short run (rtol 1e-10, atol 1e-12, as in ``env_ensemble.py``) times the ns per right-hand side:
as measured; with the environment's sampling free (``constants`` = the gravity gradient's);
and with that and the gravity gradient's number of right-hand sides (no switches, no knots).
"""
from __future__ import annotations

import argparse
import math
import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

warnings.simplefilter("ignore")
sys.path.insert(0, str(Path(__file__).resolve().parent))


def loops():
    """The compiled timing loops (compiled on first use, after numba is imported)."""
    import numba as nb

    from orbatt.core import hamiltonian as H
    from orbatt.core import model as km

    @nb.njit
    def rhs(s, ys, inertia, terms, params, table, work, dy):
        acc = 0.0
        for i in range(s.shape[0]):
            H.rhs(s[i], ys[i], inertia, terms, params, table, work, dy)
            acc += dy[0] + dy[5]
        return acc

    @nb.njit
    def constants(s, terms, params, table, work, with_terms):
        """The orbit at each point, and (``with_terms``) every term's constants there."""
        acc = 0.0
        for i in range(s.shape[0]):
            t, dtds, r, x, v = km.orbit_at(s[i], terms, params, table, work)
            acc += t + dtds + r + x[0] + x[1] + x[2] + v[0] + v[1] + v[2]
            if with_terms:
                for j in range(1, terms.shape[0]):
                    kind, p0, c = km.term_constants(j, t, terms, params, table, work, r, x, v)
                    acc += c[0] + c[1] + c[2] + c[3] + c[4] + c[5] + c[6] + c[7]
        return acc

    @nb.njit
    def values(s, ys, inertia, terms, params, table, work):
        n = terms.shape[0]
        kinds = np.zeros(n, np.int64)
        p0s = np.zeros(n, np.int64)
        C = np.zeros((n, 8))
        t, dtds, r, x, v = km.orbit_at(s[s.shape[0] // 2], terms, params, table, work)
        for j in range(1, n):
            kind, p0, c = km.term_constants(j, t, terms, params, table, work, r, x, v)
            kinds[j] = kind
            p0s[j] = p0
            for k in range(8):
                C[j, k] = c[k]
        I = (inertia[0], inertia[1], inertia[2])
        acc = 0.0
        for i in range(s.shape[0]):
            q = (ys[i, 0], ys[i, 1], ys[i, 2], ys[i, 3])
            for j in range(1, n):
                c = (C[j, 0], C[j, 1], C[j, 2], C[j, 3], C[j, 4], C[j, 5], C[j, 6], C[j, 7])
                u, g = km.term_value(kinds[j], p0s[j], c, q, I, params)
                acc += u + g[0] + g[1] + g[2] + g[3]
        return acc

    return rhs, constants, values


def best_ns(f, n, *args, repeats=5):
    """Best CPU time of ``f(*args)`` over ``repeats``, in ns per point (``n`` points)."""
    f(*args)
    best = math.inf
    for _ in range(repeats):
        c0 = time.process_time()
        f(*args)
        best = min(best, time.process_time() - c0)
    return best / n * 1e9


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="50,000 evaluations instead of 200,000")
    args = ap.parse_args(argv)
    import orbatt
    from astropy import units as u

    from env_ensemble import env_scenarios
    from orbatt import quaternion as qt
    from orbatt.core import potentials as kp
    from orbatt.methods.dop853 import EccentricAnomaly
    from orbatt.model_assembly import assemble
    from orbatt.scenario import load_scenario
    from orbatt.scenario.build import build_potential

    n = 50_000 if args.quick else 200_000
    print(f"orbatt right-hand-side breakdown ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{n} evaluations, CPU time, best of 5)\n")
    folder = Path(tempfile.mkdtemp(prefix="orbatt-rhs-"))
    variants = [(label, load_scenario(path)) for label, path in env_scenarios(folder)]
    sc = variants[-1][1]
    t_end = float(sc.t_end)
    models = [("gravity gradient alone", orbatt.GravityGradient(sc.orbit))]
    models += [(label, build_potential(v.spec, v.orbit, t_end)) for label, v in variants]
    rng = np.random.default_rng(3)
    ys = rng.normal(size=(n, 8))
    ys[:, :4] = qt.normalize(ys[:, :4])
    inertia = np.ascontiguousarray(sc.body.inertia_value)
    ys[:, 4:] *= float(inertia.max()) * 1e-2
    # the members of the RHS count (as env_ensemble.py's, fewer)
    members = 8
    q0 = qt.normalize(rng.normal(size=(members, 4)))
    states = orbatt.State.from_omega(sc.body, q0, rng.normal(size=(members, 3)) * math.radians(0.5) * u.rad / u.s)
    rtol, atol = sc.settings["rtol"], sc.settings["atol"]
    f_rhs, f_constants, f_values = loops()
    rows = []
    for label, pot in models:
        an = EccentricAnomaly(assemble(pot, [sc.body]), 0.0, np.array([t_end]))
        terms, params, table = an.kernel.terms, an.kernel.params, an.kernel.table
        s = np.sort(rng.uniform(an.s0, an.s_out[-1], n))
        work = kp.new_work()
        dy = np.empty(8)
        t_rhs = best_ns(f_rhs, n, s, ys, inertia, terms, params, table, work, dy)
        t_orbit = best_ns(f_constants, n, s, terms, params, table, work, False)
        t_const = best_ns(f_constants, n, s, terms, params, table, work, True) - t_orbit
        t_values = best_ns(f_values, n, s, ys, inertia, terms, params, table, work)
        tr = orbatt.propagate(sc.body, states, pot, [0.0, t_end], rtol=rtol, atol=atol)
        rows.append((label, t_rhs, t_orbit, t_const, t_values, tr.stats["rhs_evaluations"] / members))
    shutil.rmtree(folder, ignore_errors=True)
    g = rows[0]
    print(f"{'model':<40} {'rhs ns':>7} {'orbit':>6} {'constants':>9} {'values':>7} {'rest':>6} {'RHS/member':>10} "
          f"{'vs GG now':>9} {'sampling free':>13} {'and GG RHS':>10}")
    for label, t_rhs, t_orbit, t_const, t_values, nrhs in rows:
        free = t_rhs - (t_const - g[3])     # the environment's sampling at the gravity gradient's cost
        print(f"{label:<40} {t_rhs:7.1f} {t_orbit:6.1f} {t_const:9.1f} {t_values:7.1f} "
              f"{t_rhs - t_orbit - t_const - t_values:6.1f} {nrhs:10.0f} "
              f"{(g[5] * g[1]) / (nrhs * t_rhs):8.3f}x {(g[5] * g[1]) / (nrhs * free):12.3f}x "
              f"{g[1] / free:9.3f}x")
    print("(vs GG: the gravity gradient's RHS per member x ns per RHS over the model's; 'sampling free': "
          "the model's constants at the gravity gradient's cost; 'and GG RHS': also the gravity gradient's "
          "number of right-hand sides)")


if __name__ == "__main__":
    main()

"""The coupled binary over many orbits with the symplectic splitting: total angular momentum to
round-off and the energy error bounded, no drift (issue 24's long-run check; a benchmark, not a
test).

Run: ``python benchmarks/binary_long_run.py [N_ORBITS] [STEPS_PER_ORBIT] [COMPOSITION]`` (default
100000 orbits, 100 steps per orbit, Strang). The case is ``benchmarks/binary_heyoka.py``'s
(Didymos-Dimorphos-like, rigid primary, e = 0.02, i = 3 deg, the secondary librating). Prints the
largest relative energy and angular momentum errors over each tenth of the run and the wall time.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from binary_heyoka import P_ORBIT, case  # noqa: E402

from orbatt.binary import binary_content, propagate_binary  # noqa: E402


def main(n_orbits=100_000, per_orbit=100, composition="strang"):
    s, y0 = case()
    outputs = 1000
    step = P_ORBIT / per_orbit
    k = round(n_orbits * per_orbit / outputs)
    t = np.arange(outputs + 1) * k * step
    propagate_binary(s, y0, [0.0, step], method="splitting", step=step, composition=composition)  # load the kernels
    w = time.perf_counter()
    tr = propagate_binary(s, y0, t, method="splitting", step=step, composition=composition)
    w = time.perf_counter() - w
    ds = binary_content(tr)
    E = ds["energy"].values
    L = ds["angular_momentum_total"].values
    dE = np.abs(E - E[0]) / abs(E[0])
    dL = np.linalg.norm(L - L[0], axis=1) / np.linalg.norm(L[0])
    print(f"{n_orbits} orbits, {per_orbit} steps per orbit, {composition}: {tr.stats['steps']} steps, "
          f"{tr.stats['gradient_evaluations']} kicks, {w:.1f} s ({w / tr.stats['steps'] * 1e6:.2f} us a step)")
    print(f"{'orbits':>16}{'max |dE|/|E0|':>16}{'max |dL|/|L0|':>16}")
    for j in range(10):
        sl = slice(j * outputs // 10 + (j > 0), (j + 1) * outputs // 10 + 1)
        print(f"{t[sl][0] / P_ORBIT:>7.0f}..{t[sl][-1] / P_ORBIT:<7.0f}{dE[sl].max():>16.2e}{dL[sl].max():>16.2e}")


if __name__ == "__main__":
    args = sys.argv[1:]
    main(int(args[0]) if args else 100_000, int(args[1]) if len(args) > 1 else 100, args[2] if len(args) > 2 else "strang")

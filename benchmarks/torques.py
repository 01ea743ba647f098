"""Cost of the right-hand side with environment torques (issue 11): ns per RHS evaluation of
the compiled DOP853 loop for the gravity gradient alone and with drag, SRP and a residual
dipole on six facets, on the same orbit, measured in the same run.

    python benchmarks/torques.py

The RHS cost is the loop's wall time over its RHS evaluations (``Trajectory.stats``), the
median of several runs; the environment tables are built once, before the timing.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt.environment.atmosphere import ExponentialAtmosphere
from orbatt.environment.magnetic import DipoleField
from orbatt.orbits import KeplerOrbit
from orbatt.torques import EnvironmentTorques, Facet

warnings.simplefilter("ignore")


def facets():
    rows = [(0.034, [1, 0, 0], [0.05, 0, 0.02]), (0.034, [-1, 0, 0], [-0.05, 0, 0.02]),
            (0.034, [0, 1, 0], [0, 0.05, 0.02]), (0.034, [0, -1, 0], [0, -0.05, 0.02]),
            (0.01, [0, 0, 1], [0, 0, 0.19]), (0.01, [0, 0, -1], [0, 0, -0.15])]
    return [Facet(a * u.m**2, n, p * u.m, 2.2, 0.1, 0.3) for a, n, p in rows]


def rhs_ns(body, state, potential, t_end, repeats=7):
    t = np.array([0.0, t_end])
    orbatt.propagate(body, state, potential, t, rtol=1e-12, atol=1e-12)  # compile
    per = []
    for _ in range(repeats):
        tr = orbatt.propagate(body, state, potential, t, rtol=1e-12, atol=1e-12)
        per.append(tr.stats["wall_time_s"] / tr.stats["rhs_evaluations"])
    return 1e9 * float(np.median(per)), tr.stats["rhs_evaluations"]


def main():
    epoch = Time("2025-03-20T00:00:00", scale="utc")
    orbit = KeplerOrbit(6778.137 * u.km, 0.0005, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, true_anomaly=0 * u.deg,
                        epoch=epoch)
    T = 2 * np.pi * np.sqrt(6778.137**3 / 398600.4418)
    body = orbatt.RigidBody([0.0387, 0.0387, 0.0067] * u.kg * u.m**2)
    state = orbatt.State.from_omega(body, [1.0, 0, 0, 0], [0.05, -0.03, 0.1] * u.deg / u.s)
    t0 = time.perf_counter()
    full = EnvironmentTorques(orbit, T * u.s, facets=facets(), drag=True, srp=True,
                              residual_dipole=[0.005, 0.0, 0.002] * u.A * u.m**2,
                              atmosphere=ExponentialAtmosphere(3e-12 * u.kg / u.m**3, 400 * u.km, 60 * u.km),
                              magnetic_field=DipoleField(epoch))
    full.kernel_model()
    setup = time.perf_counter() - t0
    rows = [("gravity gradient alone", orbatt.GravityGradient(orbit)),
            ("+ drag, SRP, magnetic, 6 facets", full)]
    print(f"environment tables for one orbit: {setup:.2f} s (sampling the models; once per run)")
    print(f"{'model':34s} {'ns/RHS':>8s} {'RHS evals':>10s} {'ratio':>7s}")
    base = None
    for name, pot in rows:
        ns, n = rhs_ns(body, state, pot, T)
        base = base or ns
        print(f"{name:34s} {ns:8.0f} {n:10d} {ns / base:7.2f}")


if __name__ == "__main__":
    main()

"""The benchmark's problems as heyoka Taylor integrators (baseline (c) of ``run.py``).

Eq. (7) of the paper with the tangential gradient of the gravity-gradient potential (and
heyoka's ``kepE`` for the Keplerian orbit). Imports numpy and heyoka only, so that a fresh
process can time heyoka's first result (import + JIT compilation + integration) beside a
first ``orbatt run``: ``python benchmarks/heyoka_model.py TOL`` prints that time.
"""
from __future__ import annotations

import math
import sys
import time

import numpy as np

GM = 398600.4418
A, ECC, INC, RAAN, ARGP = 7000.0, 0.2, math.pi / 6, math.pi / 4, math.pi / 12
N_MEAN = math.sqrt(GM / A**3)
PERIOD = 2 * math.pi / N_MEAN
Q0 = np.array([0.5, -1 / math.sqrt(2), 0.0, 0.5])
P0 = np.array([0.3, -0.848528, 0.141421, -1.5])
P0 = P0 - (Q0 @ P0) * Q0
KEPLER_INERTIA = np.array([400.0, 500.0, 600.0])  # kg km^2
FREE_INERTIA = np.array([1.25, 1.0, 0.75])


def perifocal_axes(inc=INC, raan=RAAN, argp=ARGP):
    """The unit vectors P (to periapsis) and Q (90 deg ahead) in inertial components
    (as :func:`orbatt.core.kepler.orbit_vector` packs them)."""
    ci, si = math.cos(inc), math.sin(inc)
    cO, sO = math.cos(raan), math.sin(raan)
    cw, sw = math.cos(argp), math.sin(argp)
    return ((cO * cw - sO * sw * ci, sO * cw + cO * sw * ci, sw * si),
            (-cO * sw - sO * cw * ci, -sO * sw + cO * cw * ci, cw * si))


def integrator(inertia, gravity_gradient, tol):
    """``(system, heyoka.taylor_adaptive)`` of eq. (7) for the body ``inertia`` (I1, I2, I3),
    torque-free or with the Keplerian gravity gradient, at tolerance ``tol``."""
    import heyoka as hy

    qs = hy.make_vars("q0", "q1", "q2", "q3")
    ps = hy.make_vars("p0", "p1", "p2", "p3")
    I = inertia

    def mul(a, b):
        a0, a1, a2, a3 = a
        b0, b1, b2, b3 = b
        return [a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0]

    def conj(a):
        return [a[0], -a[1], -a[2], -a[3]]

    w = mul(conj(qs), ps)
    a = [0.0, w[1] / I[0], w[2] / I[1], w[3] / I[2]]
    qd, pd = mul(qs, a), mul(ps, a)
    grad = [0.0] * 4
    if gravity_gradient:
        E = hy.kepE(ECC, N_MEAN * hy.time)
        cE, sE = hy.cos(E), hy.sin(E)
        rr = 1.0 - ECC * cE
        cf, sf = (cE - ECC) / rr, math.sqrt(1 - ECC**2) * sE / rr
        P, Qv = perifocal_axes()
        X = [0.0] + [cf * P[k] + sf * Qv[k] for k in range(3)]
        k3 = GM / (A * rr) ** 3
        xb = mul(mul(conj(qs), X), qs)
        Y = [0.0, I[0] * xb[1], I[1] * xb[2], I[2] * xb[3]]
        graw = [-6.0 * k3 * c for c in mul(mul(X, qs), Y)]
        n2 = sum(c * c for c in qs)
        cdot = sum(qs[i] * graw[i] for i in range(4)) / n2
        grad = [(graw[i] - cdot * qs[i]) / (n2 * n2) for i in range(4)]
    sys_ = [(qs[i], 0.25 * qd[i]) for i in range(4)] + [(ps[i], 0.25 * pd[i] - grad[i]) for i in range(4)]
    return sys_, hy.taylor_adaptive(sys_, list(Q0) + list(P0), tol=tol)


def propagate(ta, t_end):
    """The final attitude of ``ta`` from the paper's state over ``[0, t_end]``."""
    ta.time = 0.0
    ta.state[:] = list(Q0) + list(P0)
    ta.propagate_until(t_end)
    return np.array(ta.state[:4])


if __name__ == "__main__":  # heyoka's first result in a fresh process (the Keplerian case)
    start = time.perf_counter()
    _, ta = integrator(KEPLER_INERTIA, True, float(sys.argv[1]))
    propagate(ta, 10 * PERIOD)
    print(f"{time.perf_counter() - start:.6f}")

"""The coupled binary (Didymos-Dimorphos-like, rigid primary, every coupling acting) in orbatt and
in heyoka, side by side: agreement and time over 100 orbits.

heyoka writes the same equations (``docs/design.md`` §12: ``(r, p)``, ``(q, Q)``, ``(q1, Q1)``, the
second-order mutual potential's gradient and torques, eq. 7 for each body) with its expression
system, in scaled variables (lengths in the initial separation, time in ``1 / n``, momenta in
their natural scales), since its error control takes the infinity norm of the whole state.

Run: ``python benchmarks/binary_heyoka.py`` (needs ``pip install heyoka``). It prints, for each
tool and tolerance, the largest position error (relative to the separation) and attitude errors
(rad) at the end against a tight orbatt reference (DOP853, rtol 1e-14), and the wall times
(orbatt: ``propagate_binary`` on a warm compile cache; heyoka: building the integrator, JIT
included, and integrating).
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import astropy.units as u  # noqa: E402

from orbatt import quaternion as qt  # noqa: E402
from orbatt.binary import BinarySystem, propagate_binary  # noqa: E402
from orbatt.binary.system import G_KM  # noqa: E402

M1, M2 = 5.3e11, 4.3e9
I2 = np.array([8.6e12, 1.17e13, 1.41e13]) * 1e-6   # kg km^2
I1 = np.array([2.93e16, 2.93e16, 3.83e16]) * 1e-6
P_ORBIT = 11.92 * 3600.0
N_ORBITS = 100


def case():
    """The system and its initial state: the issue's contract values, e = 0.02, i = 3 deg, the
    secondary near synchronous (long axis 5 deg off the radial direction, rate the mean motion),
    the primary spinning about its short axis with a small nutation: a regular (librating) motion,
    so that tools can agree over 100 orbits (an off-synchronous tumbling secondary is chaotic)."""
    s = BinarySystem(M2 * u.kg, I2 * u.kg * u.km**2, M1 * u.kg, I1 * u.kg * u.km**2)
    n = 2 * math.pi / P_ORBIT
    p = qt.from_axis_angle(np.array([1.0, 0.0, 0.0]), math.radians(3.0))   # the orbital frame at f = 0
    q2 = qt.mul(p, qt.from_axis_angle(np.array([0.0, 0.0, 1.0]), math.radians(5.0)))
    w2 = qt.rotate_inv(q2, qt.rotate(p, np.array([0.0, 0.0, n])))
    y0 = s.state_from_elements(1.19 * u.km, 0.02, 3 * u.deg, 0 * u.deg, 0 * u.deg, 0 * u.deg, q2, w2 * u.rad / u.s,
                               [1.0, 0.0, 0.0, 0.0], [1e-6, 0.0, 7.72e-4] * u.rad / u.s)
    return s, y0


def heyoka_integrator(s, y0, tol):
    """``(taylor_adaptive, scales, n)``: the coupled equations in heyoka, state scaled by ``scales``
    (``y = scales * x``), time in units of ``1 / n``."""
    import heyoka as hy

    n = 2 * math.pi / P_ORBIT
    L = float(np.linalg.norm(y0[0:3]))
    mu = s.reduced_mass
    scales = np.concatenate([np.full(3, L), np.full(3, mu * L * n), np.ones(4), np.full(4, max(I2) * n), np.ones(4),
                             np.full(4, max(I1) * n)])
    x = hy.make_vars(*[f"x{k}" for k in range(22)])
    y = [scales[k] * x[k] for k in range(22)]

    def mul(a, b):
        a0, a1, a2, a3 = a
        b0, b1, b2, b3 = b
        return [a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0]

    def conj(a):
        return [a[0], -a[1], -a[2], -a[3]]

    r = y[0:3]
    r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    rn = hy.sqrt(r2)
    ir3 = 1.0 / (r2 * rn)
    ir5 = ir3 / r2
    grad = [G_KM * M1 * M2 * ir3 * r[k] for k in range(3)]
    rates = []
    for k0, I, Mo in ((6, I2, M1), (14, I1, M2)):
        q, Q = y[k0:k0 + 4], y[k0 + 4:k0 + 8]
        rb = mul(mul(conj(q), [0.0] + r), q)[1:]
        Ir = [I[j] * rb[j] for j in range(3)]
        IrS = mul(mul(q, [0.0] + Ir), conj(q))[1:]
        rIr = rb[0] * Ir[0] + rb[1] * Ir[1] + rb[2] * Ir[2]
        a = 1.5 * G_KM * Mo * ir5
        b = float(sum(I)) - 5.0 * rIr / r2
        grad = [grad[j] + a * (b * r[j] + 2.0 * IrS[j]) for j in range(3)]
        sc = 3.0 * G_KM * Mo * ir5
        tau = [sc * (rb[1] * Ir[2] - rb[2] * Ir[1]), sc * (rb[2] * Ir[0] - rb[0] * Ir[2]),
               sc * (rb[0] * Ir[1] - rb[1] * Ir[0])]
        w = mul(conj(q), Q)
        om = [0.0, w[1] / I[0], w[2] / I[1], w[3] / I[2]]   # (0, 2 omega)
        qd, Qd = mul(q, om), mul(Q, om)
        tq = mul(q, [0.0] + tau)
        rates.append(([0.25 * qd[j] for j in range(4)], [0.25 * Qd[j] + 2.0 * tq[j] for j in range(4)]))
    f = [y[3 + j] / mu for j in range(3)] + [-grad[j] for j in range(3)]
    for qd, Qd in rates:
        f += qd + Qd
    sys_ = [(x[k], f[k] / (scales[k] * n)) for k in range(22)]
    ta = hy.taylor_adaptive(sys_, list(y0 / scales), tol=tol)
    return ta, scales, n


def errors(y, ref):
    """(position / separation, secondary attitude rad, primary attitude rad) at the end."""
    return (float(np.linalg.norm(y[0:3] - ref[0:3]) / np.linalg.norm(ref[0:3])),
            float(qt.angle_between(y[6:10], ref[6:10])), float(qt.angle_between(y[14:18], ref[14:18])))


def main():
    s, y0 = case()
    T = N_ORBITS * P_ORBIT
    t = np.array([0.0, T])
    propagate_binary(s, y0, [0.0, 1.0])   # load the compiled loop
    ref = propagate_binary(s, y0, t, rtol=1e-14, atol=1e-18).y[-1]
    print(f"{N_ORBITS} orbits ({T / 86400:.1f} d); errors at the end against orbatt DOP853 rtol 1e-14")
    print(f"{'tool':<28}{'pos/sep':>10}{'att2 rad':>10}{'att1 rad':>10}{'wall s':>10}")
    for method, rtol in (("dop853", 1e-11), ("dop853", 1e-12), ("vern98", 1e-12), ("vern98", 1e-13)):
        w = time.perf_counter()
        tr = propagate_binary(s, y0, t, method=method, rtol=rtol, atol=rtol * 1e-4)
        w = time.perf_counter() - w
        e = errors(tr.y[-1], ref)
        print(f"{f'orbatt {method} {rtol:g}':<28}{e[0]:>10.2e}{e[1]:>10.2e}{e[2]:>10.2e}{w:>10.4f}")
    for comp, m in (("yoshida6", 200), ("yoshida6", 400)):
        w = time.perf_counter()
        tr = propagate_binary(s, y0, t, method="splitting", step=P_ORBIT / m, composition=comp)
        w = time.perf_counter() - w
        e = errors(tr.y[-1], ref)
        print(f"{f'orbatt {comp} T/{m}':<28}{e[0]:>10.2e}{e[1]:>10.2e}{e[2]:>10.2e}{w:>10.4f}")
    try:
        import heyoka  # noqa: F401
    except ImportError:
        print("heyoka not installed: pip install heyoka")
        return
    for tol in (1e-9, 1e-12, 1e-15):
        w0 = time.perf_counter()
        ta, scales, n = heyoka_integrator(s, y0, tol)
        w1 = time.perf_counter()
        ta.propagate_until(n * T)
        w2 = time.perf_counter()
        e = errors(np.array(ta.state) * scales, ref)
        print(f"{f'heyoka {tol:g}':<28}{e[0]:>10.2e}{e[1]:>10.2e}{e[2]:>10.2e}{w2 - w1:>10.4f}"
              f"   (+ {w1 - w0:.2f} s building the integrator, JIT included)")


if __name__ == "__main__":
    main()

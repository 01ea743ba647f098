"""What evaluating the environment torques of many members at once (SIMD across members) would
save (issue 23, item 5): the torques at the attitude of ``cubesat-3u-disturbances`` (drag and
SRP on six facets each, the residual dipole) for 32 members, each with its own constants (its
own time, as members with their own step sizes have), evaluated

* one member at a time, through orbatt's kernels (``facets_scalar``: what the step loops do);
* lanes innermost, branch-free (``max(cos, 0)``), so that LLVM vectorizes across members
  (``facets_lanes``: a prototype, not used by the library);
* and today's lanes form (``model.term_value`` per lane and term, ``values_lanes``) against one
  at a time (``values_scalar``): the environment terms are called there, not vectorized.

    NUMBA_NUM_THREADS=1 python benchmarks/simd_torques.py

CPU time, best of 5, per member evaluation. Results: ``benchmarks/README.md``.
"""
import sys, time, warnings, tempfile
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent))
warnings.simplefilter("ignore")
import numpy as np, numba as nb
from orbatt.core import model as km, potentials as kp
from orbatt.methods.dop853 import EccentricAnomaly
from orbatt.model_assembly import assemble
from orbatt.scenario import load_scenario
from orbatt.scenario.build import build_potential
from env_ensemble import env_scenarios
from orbatt.core.torques import FACET_SIZE

@nb.njit
def consts(s, terms, params, table, work):
    NB, L = s.shape
    n = terms.shape[0]
    C = np.zeros((NB, n, 8, L))
    for b in range(NB):
        for l in range(L):
            t, dtds, r, x, v = km.orbit_at(s[b, l], terms, params, table, work)
            for j in range(1, n):
                kind, p0, c = km.term_constants(j, t, terms, params, table, work, r, x, v)
                for k in range(8):
                    C[b, j, k, l] = c[k]
    return C

@nb.njit
def values_scalar(C, Y, I, terms, params):
    NB, n, _, L = C.shape
    acc = 0.0
    for b in range(NB):
        for l in range(L):
            q = (Y[b, 0, l], Y[b, 1, l], Y[b, 2, l], Y[b, 3, l])
            inertia = (I[0, l], I[1, l], I[2, l])
            for j in range(1, n):
                c = (C[b, j, 0, l], C[b, j, 1, l], C[b, j, 2, l], C[b, j, 3, l], 0.0, 0.0, 0.0, 0.0)
                u, g = km.term_value(terms[j, 0], terms[j, 1], c, q, inertia, params)
                acc += g[0] + g[1] + g[2] + g[3]
    return acc

@nb.njit(inline="always")
def lanes_kind(kind, j, p0, C, b, Y, I, params, G, L):
    for l in range(L):
        q = (Y[b, 0, l], Y[b, 1, l], Y[b, 2, l], Y[b, 3, l])
        c = (C[b, j, 0, l], C[b, j, 1, l], C[b, j, 2, l], C[b, j, 3, l], 0.0, 0.0, 0.0, 0.0)
        u, g = km.term_value(kind, p0, c, q, (I[0, l], I[1, l], I[2, l]), params)
        G[0, l] += g[0]; G[1, l] += g[1]; G[2, l] += g[2]; G[3, l] += g[3]

@nb.njit
def values_lanes(C, Y, I, terms, params):
    NB, n, _, L = C.shape
    G = np.zeros((4, L))
    for b in range(NB):
        for j in range(1, n):
            kind = terms[j, 0]
            p0 = terms[j, 1]
            if kind == km.GRAVITY_GRADIENT:
                lanes_kind(km.GRAVITY_GRADIENT, j, p0, C, b, Y, I, params, G, L)
            elif kind == km.DRAG:
                lanes_kind(km.DRAG, j, p0, C, b, Y, I, params, G, L)
            elif kind == km.SRP:
                lanes_kind(km.SRP, j, p0, C, b, Y, I, params, G, L)
            elif kind == km.MAGNETIC:
                lanes_kind(km.MAGNETIC, j, p0, C, b, Y, I, params, G, L)
    return G.sum()


@nb.njit(fastmath=False)
def facets_lanes(C, Y, params, terms):
    """drag + SRP facets and the dipole, branch-free, lanes innermost (SIMD across members)."""
    NB, n, _, L = C.shape
    acc = 0.0
    ux = np.empty(L); uy = np.empty(L); uz = np.empty(L)
    tx = np.empty(L); ty = np.empty(L); tz = np.empty(L)
    for b in range(NB):
        for l in range(L):
            tx[l] = 0.0; ty[l] = 0.0; tz[l] = 0.0
        for j in range(1, n):
            kind = terms[j, 0]
            p0 = terms[j, 1]
            if kind == km.GRAVITY_GRADIENT:
                continue
            # the direction (or field) in body axes, every lane: u = q~ v q
            for l in range(L):
                q0 = Y[b, 0, l]; q1 = Y[b, 1, l]; q2 = Y[b, 2, l]; q3 = Y[b, 3, l]
                vx = C[b, j, 1, l] if kind != km.MAGNETIC else C[b, j, 0, l]
                vy = C[b, j, 2, l] if kind != km.MAGNETIC else C[b, j, 1, l]
                vz = C[b, j, 3, l] if kind != km.MAGNETIC else C[b, j, 2, l]
                # R^T v with R from q (scalar first)
                r00 = 1 - 2 * (q2 * q2 + q3 * q3); r01 = 2 * (q1 * q2 - q0 * q3); r02 = 2 * (q1 * q3 + q0 * q2)
                r10 = 2 * (q1 * q2 + q0 * q3); r11 = 1 - 2 * (q1 * q1 + q3 * q3); r12 = 2 * (q2 * q3 - q0 * q1)
                r20 = 2 * (q1 * q3 - q0 * q2); r21 = 2 * (q2 * q3 + q0 * q1); r22 = 1 - 2 * (q1 * q1 + q2 * q2)
                ux[l] = r00 * vx + r10 * vy + r20 * vz
                uy[l] = r01 * vx + r11 * vy + r21 * vz
                uz[l] = r02 * vx + r12 * vy + r22 * vz
            if kind == km.MAGNETIC:
                mx = params[p0]; my = params[p0 + 1]; mz = params[p0 + 2]
                for l in range(L):
                    tx[l] += my * uz[l] - mz * uy[l]
                    ty[l] += mz * ux[l] - mx * uz[l]
                    tz[l] += mx * uy[l] - my * ux[l]
                continue
            srp = kind == km.SRP
            nf = int(params[p0 + 1]) if not srp else int(params[p0 + 5])
            base = p0 + (km.DRAG_HEADER if not srp else km.SRP_HEADER)
            for f in range(nf):
                fb = base + f * FACET_SIZE
                a0 = params[fb]; nx = params[fb + 1]; ny = params[fb + 2]; nz = params[fb + 3]
                rx = params[fb + 4]; ry = params[fb + 5]; rz = params[fb + 6]
                cs = params[fb + 7]; cd = params[fb + 8]
                for l in range(L):
                    cos = nx * ux[l] + ny * uy[l] + nz * uz[l]
                    w = max(cos, 0.0)
                    a = -C[b, j, 0, l] * a0 * w
                    if srp:
                        ks = a * (1.0 - cs)
                        kn = a * 2.0 * (cs * w + cd / 3.0)
                        fx = ks * ux[l] + kn * nx; fy = ks * uy[l] + kn * ny; fz = ks * uz[l] + kn * nz
                    else:
                        fx = a * ux[l]; fy = a * uy[l]; fz = a * uz[l]
                    tx[l] += ry * fz - rz * fy
                    ty[l] += rz * fx - rx * fz
                    tz[l] += rx * fy - ry * fx
        for l in range(L):
            acc += tx[l] + ty[l] + tz[l]
    return acc

@nb.njit
def facets_scalar(C, Y, params, terms):
    """the same torques, one member at a time, through orbatt's own kernels"""
    NB, n, _, L = C.shape
    acc = 0.0
    for b in range(NB):
        for l in range(L):
            q = (Y[b, 0, l], Y[b, 1, l], Y[b, 2, l], Y[b, 3, l])
            for j in range(1, n):
                kind = terms[j, 0]; p0 = terms[j, 1]
                if kind == km.DRAG:
                    t = km.trq.facet_drag(q, C[b, j, 0, l], (C[b, j, 1, l], C[b, j, 2, l], C[b, j, 3, l]), params,
                                          p0 + km.DRAG_HEADER, int(params[p0 + 1]))
                elif kind == km.SRP:
                    t = km.trq.facet_srp(q, C[b, j, 0, l], (C[b, j, 1, l], C[b, j, 2, l], C[b, j, 3, l]), params,
                                         p0 + km.SRP_HEADER, int(params[p0 + 5]))
                elif kind == km.MAGNETIC:
                    t = km.trq.dipole_torque(q, (params[p0], params[p0 + 1], params[p0 + 2]),
                                             (C[b, j, 0, l], C[b, j, 1, l], C[b, j, 2, l]))
                else:
                    continue
                acc += t[0] + t[1] + t[2]
    return acc

def main():
    folder = tempfile.mkdtemp()
    variants = [(l, load_scenario(p)) for l, p in env_scenarios(folder)]
    sc = variants[-1][1]; t_end = float(sc.t_end)
    pot = build_potential(sc.spec, sc.orbit, t_end)
    an = EccentricAnomaly(assemble(pot, [sc.body]), 0.0, np.array([t_end]))
    terms, params, table = an.kernel.terms, an.kernel.params, an.kernel.table
    L = 32
    NB = 4000
    rng = np.random.default_rng(0)
    s = np.sort(rng.uniform(an.s0, an.s_out[-1], NB * L)).reshape(NB, L)
    Y = rng.normal(size=(NB, 4, L)); Y /= np.sqrt((Y ** 2).sum(axis=1))[:, None, :]
    I = np.ascontiguousarray(np.repeat(sc.body.inertia_value[:, None], L, axis=1))
    C = consts(s, terms, params, table, kp.new_work())
    for f in (values_scalar, values_lanes, values_scalar, values_lanes):
        f(C, Y, I, terms, params)
        best = 1e9
        for _ in range(5):
            c0 = time.process_time(); f(C, Y, I, terms, params); best = min(best, time.process_time() - c0)
        print(f.__name__, f"{best / (NB * L) * 1e9:.1f} ns per member evaluation")
    print("torques only (drag 6 facets + SRP 6 facets + dipole):")
    for f in (facets_scalar, facets_lanes, facets_scalar, facets_lanes):
        f(C, Y, params, terms)
        best = 1e9
        for _ in range(5):
            c0 = time.process_time(); f(C, Y, params, terms); best = min(best, time.process_time() - c0)
        print(f.__name__, f"{best / (NB * L) * 1e9:.1f} ns per member")
    print("agree:", facets_scalar(C, Y, params, terms), facets_lanes(C, Y, params, terms))


if __name__ == "__main__":
    main()

"""Shared data and helpers of the tests of orbatt.methods and orbatt.propagation: the
paper's problems (docs/design.md §9), attitude errors, the exact free body, and direct calls of
the compiled kernels."""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

import orbatt
from orbatt import analytic
from orbatt import quaternion as qt
from orbatt.core import dop853 as kd
from orbatt.core import model as km
from orbatt.core import kepler
from orbatt.core import potentials as kp
from orbatt.core import splitting as ks
from orbatt.core.hamiltonian import rhs

# ---------------------------------------------------------------------------------------
# Problems: the paper's data (docs/design.md §9)

Q0_PAPER = np.array([0.5, -1 / math.sqrt(2), 0.0, 0.5])
#: Q(t0) as printed (radial residual -9.7e-8, docs/design.md §3a item 9)
P0_PAPER = np.array([0.3, -0.848528, 0.141421, -1.5])
#: the printed Q(t0) without its radial residual, so that the exact solution and the
#: kernels start from the same point of the manifold
P0_TANGENT = P0_PAPER - (Q0_PAPER @ P0_PAPER) * Q0_PAPER
Y0 = np.concatenate([Q0_PAPER, P0_TANGENT])
I_FREE = np.array([1.25, 1.0, 0.75])
I_SAT = np.array([400.0, 500.0, 600.0])
GM = 398600.4418
A_ORB = 7000.0
N_ORB = math.sqrt(GM / A_ORB**3)
PERIOD = 2 * math.pi / N_ORB
ORB = kepler.orbit_vector(A_ORB, 0.2, math.pi / 6, math.pi / 4, math.pi / 12, 0.0, N_ORB)
PARAMS_GG = np.concatenate([[GM], ORB])
PARAMS_TOP = np.array([0.5, 1.0, 0.0, 0.0])
EMPTY = np.zeros((0, 0))
NO_PARAMS = np.zeros(1)


class Spec:
    """A potential given by its kernel specification only (docs/design.md §3, core.potentials)."""

    def __init__(self, kind, params, table=None):
        self.kind = kind
        self.params = np.asarray(params, dtype=float)
        self.table = np.zeros((0, 0)) if table is None else table


#: the paper's Keplerian gravity gradient (Sect. 6.2)
GG = Spec(kp.GRAVITY_GRADIENT_KEPLER, PARAMS_GG)


def angle(q, qref):
    """Rotation angle between attitudes (rad), sign-insensitive."""
    w = qt.mul(qt.conj(np.asarray(qref)), np.asarray(q))
    return 2 * np.arctan2(np.linalg.norm(w[..., 1:], axis=-1), np.abs(w[..., 0]))


def observed_orders(errors):
    """log2 of the ratios of errors at successively halved steps."""
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


def exact_free(t):
    """The exact free body (Jacobi elliptic functions) from ``Y0`` with ``I_FREE``."""
    q, Q = analytic.torque_free(I_FREE, Q0_PAPER, P0_TANGENT, np.asarray(t, dtype=float))
    return q, Q


def random_data(n, seed=0):
    """``n`` random attitudes and body momenta."""
    rng = np.random.default_rng(seed)
    return qt.normalize(rng.normal(size=(n, 4))), rng.normal(size=(n, 3)) * 0.8


def random_states(body, n, seed=0):
    return orbatt.State.from_momentum(body, *random_data(n, seed))


# ---------------------------------------------------------------------------------------
# The classical model: Euler's equations + quaternion kinematics


def classical_reference(body, state, kind, params, t, rtol=1e-13):
    """Euler's equations I dw/dt = I w x w + tau and dq/dt = 1/2 q (0, w), solved by scipy
    at a tight tolerance; torques written the classical way (docs/design.md §3)."""
    I = body.inertia_value
    w0 = state.omega

    def f(tt, x):
        q = x[:4]
        w = x[4:]
        if kind == kp.GRAVITY_GRADIENT_KEPLER:
            r, xs = kepler.kepler_radial(tt, params[1:], kp.new_work())
            xb = qt.rotate_inv(q / np.linalg.norm(q), np.array(xs))
            tau = 3 * params[0] / r**3 * np.cross(xb, I * xb)
        elif kind == kp.HEAVY_TOP:
            FB = qt.rotate_inv(q / np.linalg.norm(q), np.array([0.0, 0.0, -params[0]]))
            tau = np.cross(params[1:], FB)
        else:
            tau = np.zeros(3)
        dw = (np.cross(I * w, w) + tau) / I
        return np.concatenate([0.5 * qt.mul(q, qt.pure(w)), dw])

    sol = solve_ivp(f, (t[0], t[-1]), np.concatenate([state.q, w0]), method="DOP853", t_eval=None, rtol=rtol,
                    atol=1e-16, dense_output=False)
    assert sol.success
    # integrate to each output (docs/design.md §4: no dense output at this accuracy)
    out = [np.concatenate([state.q, w0])]
    for a, b in zip(t[:-1], t[1:]):
        s = solve_ivp(f, (a, b), out[-1], method="DOP853", rtol=rtol, atol=1e-16)
        out.append(s.y[:, -1])
    return np.array(out)[:, :4]


# ---------------------------------------------------------------------------------------
# Direct kernel calls


def run_dop853(t_out, inertia=I_FREE, kind=0, params=NO_PARAMS, rtol=1e-10, atol=1e-12, max_step=np.inf, y0=Y0,
               budget=10**9, h0=0.0, advance=kd.advance):
    """The compiled DOP853 kernel (or another pair's loop, ``advance``: ``kd.advance_dopri5``
    ...) from ``y0`` at ``t = 0`` to the times ``t_out``."""
    y = y0.copy()
    st, cnt, f0 = kd.new_state()
    st[kd.ST_H] = h0
    out = np.zeros((len(t_out), 8))
    work = kp.new_work()
    status = kd.PAUSED
    while status == kd.PAUSED:
        status = advance(y, st, cnt, f0, np.asarray(t_out, dtype=float), np.empty(0), out, False, inertia,
                         *km.from_spec(kind, params, EMPTY), work, rtol, atol, max_step, 10**9, budget)
    assert status == kd.DONE
    return out, cnt


def free_rhs(inertia=I_FREE):
    """``f(t, y)``: the compiled right-hand side of the torque-free body (a fresh array)."""
    model = km.from_spec(0, NO_PARAMS, EMPTY)
    work = kp.new_work()

    def f(t, y):
        out = np.empty(8)
        rhs(t, y, inertia, *model, work, out)
        return out
    return f


def tableau_steps(f, h, n, tab, stages=None, y0=Y0):
    """``y`` after ``n`` steps ``h`` from ``y0`` at ``t = 0`` of the explicit tableau of the
    coefficients module ``tab`` (``C``, ``A``, ``B``), evaluated in numpy: its first ``stages``
    stages (default all; a pair whose last stage is the next step's first leaves it out)."""
    stages = tab.N_STAGES if stages is None else stages
    y = y0.copy()
    K = np.zeros((tab.N_STAGES, y.shape[0]))
    for k in range(n):
        for s in range(stages):
            K[s] = f(k * h + tab.C[s] * h, y + h * (tab.A[s, :s] @ K[:s]))
        y = y + h * (tab.B @ K)
    return y


def run_fixed(t_out, h, comp="strang", kinetic="axes", inertia=I_FREE, kind=0, params=NO_PARAMS, method=ks.SPLITTING,
              y0=Y0, budget=10**12, work=None):
    """The compiled fixed-step kernel (splitting composition ``comp``, or RK4) with step ``h``."""
    flow, weight, toff = ks.sequence(ks.COMPOSITIONS[comp][1], kinetic)
    axes, coef = ks.rotation_setup(inertia, kinetic)
    y = y0.copy()
    st, cnt = ks.new_state()
    out = np.zeros((len(t_out), 8))
    work = kp.new_work() if work is None else work
    status = kd.PAUSED
    while status == kd.PAUSED:
        status = ks.advance(y, st, cnt, np.asarray(t_out, dtype=float), out, 0.0, h, method, flow, weight, toff, axes,
                            coef, inertia, *km.from_spec(kind, params, EMPTY), work, 10**12, budget)
    assert status == kd.DONE
    return out, cnt

"""orbatt.methods.fixed_step and the compiled fixed-step kernels (orbatt.core.splitting):
splitting coefficients and exact flows, orders, invariants, energy, the output grid, groups
of ensemble members."""
from __future__ import annotations

import math

import numpy as np
import pytest
from method_cases import (EMPTY, GG, I_FREE, I_SAT, PARAMS_GG, PARAMS_TOP, PERIOD, Y0, angle, exact_free,
                          observed_orders, random_data, run_fixed)

import orbatt
from orbatt import analytic
from orbatt import quaternion as qt
from orbatt.core import dop853 as kd
from orbatt.core import model as km
from orbatt.core import potentials as kp
from orbatt.core import splitting as ks
from orbatt.core.hamiltonian import energy
from orbatt.methods import METHODS

# ---------------------------------------------------------------------------------------
# Coefficient data


@pytest.mark.parametrize("name", sorted(ks.COMPOSITIONS))
def test_compositions_satisfy_their_order_conditions(name):
    order, g, _ = ks.COMPOSITIONS[name]
    g = np.array(g)
    np.testing.assert_allclose(g, g[::-1], rtol=0, atol=0)  # palindromic (symmetric method)
    assert g.sum() == pytest.approx(1.0, abs=1e-15)
    if order >= 4:
        assert abs((g**3).sum()) < 1e-14
    if order >= 6:
        assert abs((g**5).sum()) < 1e-14


@pytest.mark.parametrize("kinetic", ks.KINETIC)
@pytest.mark.parametrize("comp", ["strang", "yoshida4", "kahanli6"])
def test_flattened_sequence_adds_up(comp, kinetic):
    flow, weight, toff = ks.sequence(ks.COMPOSITIONS[comp][1], kinetic)
    # every flow acts for one step in total; kicks are merged and sit at their sub-step times
    assert weight[flow == ks.KICK].sum() == pytest.approx(1.0, abs=1e-14)
    slots = (ks.ROT_A, ks.ROT_B, ks.ROT_C) if kinetic == "axes" else (ks.ROT_A, ks.ROT_B, ks.ROT_G)
    for code in slots:
        assert weight[flow == code].sum() == pytest.approx(1.0, abs=1e-14)
    assert np.all(np.diff(flow) != 0) or len(flow) == 1  # adjacent equal flows merged
    assert flow[0] == ks.KICK and flow[-1] == ks.KICK
    assert toff[0] == 0.0 and toff[-1] == pytest.approx(1.0, abs=1e-15)
    n_stages = len(ks.COMPOSITIONS[comp][1])
    assert (flow == ks.KICK).sum() == n_stages + 1


def test_rotation_setup_shifted_uses_middle_moment():
    axes, coef = ks.rotation_setup(np.array([500.0, 400.0, 600.0]), "shifted")
    # middle moment 500 on axis 1 -> the |g|^2 flow has c = 1/500; the other axes are shifted
    assert list(axes) == [3, 2, 1]
    np.testing.assert_allclose(coef, [1 / 600 - 1 / 500, 1 / 400 - 1 / 500, 0.0, 1 / 500])
    axes, coef = ks.rotation_setup(I_SAT, "axes")
    assert list(axes) == [1, 2, 3]
    np.testing.assert_allclose(coef[:3], 1 / I_SAT)


# ---------------------------------------------------------------------------------------
# Exact flows


@pytest.mark.parametrize("axis", [1, 2, 3])
def test_axis_rotation_is_right_multiplication(axis):
    rng = np.random.default_rng(axis)
    q = qt.normalize(rng.normal(size=4))
    g = rng.normal(size=3)
    Q = 2 * qt.mul(q, qt.pure(g))
    c, tau = 0.7, 0.9
    qn, Qn = ks._rot_axis(tuple(q), tuple(Q), axis, c * tau)
    theta = c * g[axis - 1] * tau
    e = np.zeros(3)
    e[axis - 1] = 1.0
    u = np.concatenate([[math.cos(theta / 2)], math.sin(theta / 2) * e])
    np.testing.assert_allclose(qn, qt.mul(q, u), atol=1e-15)
    np.testing.assert_allclose(Qn, qt.mul(Q, u), atol=1e-15)


def test_rotations_are_the_exact_flows_of_their_hamiltonians():
    """Flow of c g_i^2/2 and of c |g|^2/2 against a tight numerical solution of eq. (7)-type
    equations dq/dt = 1/2 q (0, dF/dg), dQ/dt = 1/2 Q (0, dF/dg)."""
    from scipy.integrate import solve_ivp

    rng = np.random.default_rng(7)
    q = qt.normalize(rng.normal(size=4))
    g = rng.normal(size=3)
    Q = 2 * qt.mul(q, qt.pure(g))
    c, tau = 0.8, 2.5

    def flow(grad):
        def f(t, y):
            qq, QQ = y[:4], y[4:]
            gg = 0.5 * qt.vector(qt.mul(qt.conj(qq), QQ))
            w = qt.pure(grad(gg))
            return np.concatenate([0.5 * qt.mul(qq, w), 0.5 * qt.mul(QQ, w)])
        return solve_ivp(f, (0, tau), np.concatenate([q, Q]), method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]

    for axis in (1, 2, 3):
        ref = flow(lambda gg: c * gg * (np.arange(1, 4) == axis))
        qn, Qn = ks._rot_axis(tuple(q), tuple(Q), axis, c * tau)
        np.testing.assert_allclose(np.concatenate([qn, Qn]), ref, atol=1e-11)
    ref = flow(lambda gg: c * gg)
    qn, Qn = ks._rot_g(tuple(q), tuple(Q), c * tau)
    np.testing.assert_allclose(np.concatenate([qn, Qn]), ref, atol=1e-11)


# ---------------------------------------------------------------------------------------
# Convergence orders against the exact free rigid body


@pytest.mark.parametrize("comp,kinetic,steps", [
    ("strang", "axes", (100, 200, 400)),
    ("strang", "shifted", (100, 200, 400)),
    ("yoshida4", "axes", (100, 200, 400)),
    ("suzuki4", "axes", (100, 200, 400)),
    ("mclachlan4", "axes", (100, 200, 400)),
    ("mclachlan4", "shifted", (50, 100, 200)),
    ("yoshida6", "axes", (50, 100, 200)),
    ("kahanli6", "axes", (25, 50, 100)),
])
def test_splitting_order_on_free_body(comp, kinetic, steps):
    T = 20.0
    qref, _ = exact_free([T])
    errs = []
    for n in steps:
        out, _ = run_fixed([0.0, T], T / n, comp, kinetic)
        errs.append(angle(out[-1, :4], qref[0]))
    order = ks.COMPOSITIONS[comp][0]
    assert errs[-1] > 1e-12, "errors too small to measure the order"
    np.testing.assert_allclose(observed_orders(errs), order, atol=0.15)


def test_rk4_order_on_free_body():
    T = 20.0
    qref, _ = exact_free([T])
    errs = [angle(run_fixed([0.0, T], T / n, method=ks.RK4)[0][-1, :4], qref[0]) for n in (100, 200, 400)]
    np.testing.assert_allclose(observed_orders(errs), 4.0, atol=0.15)


def test_registered_splitting4_converges_at_order_4(free):
    """``method="splitting4"`` (the registered class: McLachlan's composition, order 4)
    through orbatt.propagate, against the exact free body."""
    cls = METHODS["splitting4"]
    assert cls.order == 4 and cls.composition == "mclachlan4" and cls.symplectic
    body, s0 = free
    T = 20.0
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, np.array([0.0, T]))
    errs = []
    for n in (50, 100, 200):
        tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, T], method="splitting4", step=T / n)
        assert tr.settings["order"] == 4 and tr.stats["steps"] == n
        errs.append(angle(tr.q[-1], qref[-1]))
    assert errs[-1] > 1e-12, "errors too small to measure the order"
    np.testing.assert_allclose(observed_orders(errs), 4.0, atol=0.15)


# ---------------------------------------------------------------------------------------
# Invariants, energy, resumability, the output grid


def test_splitting_keeps_constraints_to_roundoff():
    T = 10 * PERIOD
    n = 200_000
    out, cnt = run_fixed(np.linspace(0, T, 11), T / n, "strang", "axes", I_SAT, kp.GRAVITY_GRADIENT_KEPLER,
                         PARAMS_GG)
    q, Q = out[:, :4], out[:, 4:]
    assert np.abs(np.linalg.norm(q, axis=1) - 1).max() < 1e-13
    assert np.abs(np.einsum("ij,ij->i", q, Q)).max() < 1e-13 * np.linalg.norm(Q, axis=1).max()
    assert cnt[ks.CNT_EVALS] == n + 1  # one gradient per Strang step (kicks merged/reused)


@pytest.mark.slow
def test_splitting_keeps_constraints_over_1e7_steps():
    n = 10_000_000
    T = 100 * PERIOD
    out, _ = run_fixed(np.linspace(0, T, 101), T / n, "strang", "axes", I_SAT, kp.GRAVITY_GRADIENT_KEPLER, PARAMS_GG)
    q, Q = out[:, :4], out[:, 4:]
    dn = np.abs(np.linalg.norm(q, axis=1) - 1).max()
    dqQ = np.abs(np.einsum("ij,ij->i", q, Q)).max() / np.linalg.norm(Q, axis=1).max()
    assert dn < 1e-12 and dqQ < 1e-12, (dn, dqQ)


def _energy_error(out, inertia, kind, params):
    model = km.from_spec(kind, params, EMPTY)
    H = np.array([energy(0.0, y, inertia, *model, kp.new_work()) for y in out])
    return np.abs(H - H[0]) / abs(H[0])


@pytest.mark.parametrize("comp", ["strang", "mclachlan4"])
def test_splitting_energy_error_is_bounded_heavy_top(comp):
    """Autonomous potential: the energy error oscillates, it does not drift; RK4 at the same
    step drifts."""
    T, n = 4000.0, 200_000
    t = np.linspace(0, T, 401)
    out, _ = run_fixed(t, T / n, comp, "axes", I_FREE, kp.HEAVY_TOP, PARAMS_TOP)
    dH = _energy_error(out, I_FREE, kp.HEAVY_TOP, PARAMS_TOP)
    early, late = dH[:41].max(), dH[200:].max()
    assert late < 2.0 * early + 1e-15, (early, late)
    assert np.abs(np.linalg.norm(out[:, :4], axis=1) - 1).max() < 1e-13
    if comp == "strang":
        rk, _ = run_fixed(t, 10 * T / n, method=ks.RK4, inertia=I_FREE, kind=kp.HEAVY_TOP, params=PARAMS_TOP)
        dHr = _energy_error(rk, I_FREE, kp.HEAVY_TOP, PARAMS_TOP)
        assert dHr[-1] > 5 * dHr[40]  # RK4 drifts (secular growth)


@pytest.mark.slow
def test_splitting_energy_bounded_over_long_run():
    T, n = 2.0e5, 4_000_000
    t = np.linspace(0, T, 201)
    out, _ = run_fixed(t, T / n, "strang", "axes", I_FREE, kp.HEAVY_TOP, PARAMS_TOP)
    dH = _energy_error(out, I_FREE, kp.HEAVY_TOP, PARAMS_TOP)
    assert dH[100:].max() < 2.0 * dH[:21].max()


@pytest.mark.parametrize("budget", [1, 7, 1000])
def test_fixed_step_kernel_resumes_exactly(budget):
    """Stopping every `budget` steps and calling again changes nothing (progress reports and
    KeyboardInterrupt rely on it)."""
    t = np.array([0.0, 0.3 * PERIOD, 0.5 * PERIOD])
    ref, _ = run_fixed(t, 7.3, "mclachlan4", "axes", I_SAT, 2, PARAMS_GG)
    got, _ = run_fixed(t, 7.3, "mclachlan4", "axes", I_SAT, 2, PARAMS_GG, budget=budget)
    np.testing.assert_array_equal(got, ref)


def test_splitting_outputs_do_not_perturb_the_grid():
    """Off-grid output times are reached by partial steps; the grid trajectory is unchanged
    and off-grid outputs are as accurate as grid ones."""
    h, T = 0.05, 20.0
    plain, _ = run_fixed([0.0, T], h, "mclachlan4")
    extra_t = [0.0, 3.01234, 7.777, 12.5, T]  # 12.5 is a grid point
    extra, cnt = run_fixed(extra_t, h, "mclachlan4")
    np.testing.assert_array_equal(extra[-1], plain[-1])
    qref, _ = exact_free(extra_t)
    err = angle(extra[:, :4], qref)
    assert err.max() < 3 * angle(plain[-1, :4], qref[-1]) + 1e-12
    assert cnt[ks.CNT_STEPS] == round(T / h) + 2  # the grid plus one partial step per off-grid output


def test_splitting_kernel_reports_a_nonfinite_state():
    """A non-finite derivative: the kernel stops with NONFINITE and keeps the last finite state."""
    bad = np.array([np.inf, 1.0, 0.0, 0.0])  # heavy top with an infinite weight
    flow, weight, toff = ks.sequence((1.0,), "axes")
    axes, coef = ks.rotation_setup(I_FREE, "axes")
    y = Y0.copy()
    st, cnt = ks.new_state()
    status = ks.advance(y, st, cnt, np.array([0.0, 10.0]), np.zeros((2, 8)), 0.0, 0.1, ks.SPLITTING, flow, weight,
                        toff, axes, coef, I_FREE, *km.from_spec(kp.HEAVY_TOP, bad, EMPTY), kp.new_work(), 10**6, 10**6)
    assert status == kd.NONFINITE
    np.testing.assert_array_equal(y, Y0)


# ---------------------------------------------------------------------------------------
# Ensembles in groups


def test_fixed_step_ensembles_in_several_groups_are_identical(sat):
    """70 members = groups of 32, 32, 6 on the common grid: identical to one-by-one."""
    body, _ = sat
    q, g = random_data(70, seed=3)
    t = np.array([0.0, 100.0, 250.3])
    ens = orbatt.propagate(body, orbatt.State.from_momentum(body, q, g), GG, t, method="splitting2", step=7.0)
    for e in (0, 31, 32, 69):
        one = orbatt.propagate(body, orbatt.State.from_momentum(body, q[e], g[e]), GG, t, method="splitting2",
                               step=7.0)
        np.testing.assert_array_equal(ens.q[e], one.q)
    assert ens.stats["steps"] == 70 * one.stats["steps"]
    assert ens.stats["kicks"] == 70 * one.stats["kicks"]

"""orbatt.methods.dop853 and the compiled DOP853 kernels (orbatt.core.dop853): coefficients,
order, tolerance, landing on output times, failures, lockstep lanes."""
from __future__ import annotations

import math

import numpy as np
import pytest
from method_cases import (EMPTY, GG, I_FREE, I_SAT, NO_PARAMS, PARAMS_GG, PARAMS_TOP, PERIOD, Q0_PAPER, Y0, angle,
                          exact_free, observed_orders, random_data, run_dop853)

import orbatt
from orbatt import analytic
from orbatt.core import dop853 as kd
from orbatt.core import dop853_coefficients as dc
from orbatt.core import model as km
from orbatt.core import potentials as kp

def test_dop853_tableau_is_consistent():
    # rows of A sum to the nodes, weights to 1, error estimators to 0
    np.testing.assert_allclose(dc.A.sum(axis=1), dc.C, atol=1e-14)
    assert dc.B.sum() == pytest.approx(1.0, abs=1e-14)
    assert abs(dc.E5.sum()) < 1e-14 and abs(dc.E3.sum()) < 1e-14
    # quadrature conditions of order 8: sum b_i c_i^k = 1 / (k + 1)
    for k in range(8):
        assert (dc.B * dc.C**k).sum() == pytest.approx(1.0 / (k + 1), abs=1e-13)
    # the sparse copy of A used by the stage loop
    for s in range(dc.N_STAGES):
        row = np.zeros(dc.N_STAGES)
        row[dc.A_COL[dc.A_PTR[s]:dc.A_PTR[s + 1]]] = dc.A_VAL[dc.A_PTR[s]:dc.A_PTR[s + 1]]
        np.testing.assert_array_equal(row, dc.A[s])


# ---------------------------------------------------------------------------------------
# Convergence and accuracy against the exact free rigid body


def test_dop853_order_on_free_body():
    """With loose tolerances the step is max_step everywhere: a fixed-step DOP853."""
    T = 12.0
    qref, _ = exact_free([T])
    errs = []
    for n in (12, 48):
        out, cnt = run_dop853([T], rtol=1.0, atol=1.0, max_step=T / n, h0=T / n)
        assert cnt[kd.CNT_STEPS] == n and cnt[kd.CNT_REJECTED] == 0
        errs.append(angle(out[-1, :4], qref[0]))
    assert errs[-1] > 1e-13
    # over h -> h/4 (before the error reaches round-off): measured 8.35; h -> h/2 gives 9.8
    # then 6.9 (pre-asymptotic), identical to scipy's DOP853 with the same steps
    assert observed_orders(errs)[0] / 2 == pytest.approx(8.0, abs=0.5)


def test_dop853_meets_tolerance_on_free_body():
    t = np.linspace(0.0, 50.0, 26)[1:]
    qref, Qref = exact_free(t)
    for rtol in (1e-8, 1e-12):
        out, cnt = run_dop853(t, rtol=rtol, atol=rtol * 1e-2)
        err = angle(out[:, :4], qref).max()
        assert err < 200 * rtol
        assert np.abs(out[:, 4:] - Qref).max() < 200 * rtol
        assert cnt[kd.CNT_REJECTED] < 0.25 * cnt[kd.CNT_STEPS]


def test_dop853_other_regime_and_separatrix():
    """g circulating about the smallest-moment axis (D < I2), and on the separatrix."""
    from orbatt import canonical as cn

    # D < I2; a steady spin about axis 1; on the separatrix (g1^2 (1 - I2/I1) = g3^2 (I2/I3 - 1)),
    # where errors grow exponentially (the motion approaches the unstable axis 2): shorter run
    for g, T in (([0.2, 0.1, 1.0], 30.0), ([1.0, 0.0, 0.0], 30.0), ([math.sqrt(5 / 3), 0.0, 1.0], 7.0)):
        q0 = Q0_PAPER
        Q0 = cn.momentum_from_body_momentum(q0, np.array(g))
        y0 = np.concatenate([q0, Q0])
        t = np.array([T / 4, T])
        qref, _ = analytic.torque_free(I_FREE, q0, Q0, t)
        out, _ = run_dop853(t, rtol=1e-12, atol=1e-14, y0=y0)
        assert angle(out[:, :4], qref).max() < 1e-11


def test_dop853_lands_on_output_times():
    t = np.sort(np.random.default_rng(3).uniform(0, 30, 40))
    qref, _ = exact_free(t)
    out, _ = run_dop853(t, rtol=1e-12, atol=1e-14)
    assert angle(out[:, :4], qref).max() < 1e-10


# ---------------------------------------------------------------------------------------
# Resumability and failures


@pytest.mark.parametrize("budget", [1, 7, 1000])
def test_dop853_kernel_resumes_exactly(budget):
    """Stopping every `budget` steps and calling again changes nothing (progress reports and
    KeyboardInterrupt rely on it)."""
    t = np.array([0.0, 0.3 * PERIOD, 0.5 * PERIOD])
    ref, _ = run_dop853(t[1:], I_SAT, 2, PARAMS_GG, rtol=1e-9, atol=1e-11)
    got, _ = run_dop853(t[1:], I_SAT, 2, PARAMS_GG, rtol=1e-9, atol=1e-11, budget=budget)
    np.testing.assert_array_equal(got, ref)


def test_dop853_kernel_reports_a_nonfinite_state():
    """A non-finite derivative: the kernel stops with NONFINITE and keeps the last finite state."""
    bad = np.array([np.inf, 1.0, 0.0, 0.0])  # heavy top with an infinite weight
    y = Y0.copy()
    st, cnt, f0 = kd.new_state()
    out = np.zeros((1, 8))
    status = kd.advance(y, st, cnt, f0, np.array([10.0]), np.empty(0), out, False, I_FREE, *km.from_spec(kp.HEAVY_TOP, bad, EMPTY),
                        kp.new_work(), 1e-8, 1e-10, np.inf, 10**6, 10**6)
    assert status == kd.NONFINITE
    np.testing.assert_array_equal(y, Y0)


def test_dop853_refuses_to_crawl():
    """A derivative of 1e300: no NaN, but steps of 1e-300; the step-size floor (relative to the
    time span) stops it instead of crawling for ever."""
    y = Y0.copy()
    st, cnt, f0 = kd.new_state()
    status = kd.advance(y, st, cnt, f0, np.array([10.0]), np.empty(0), np.zeros((1, 8)), False, I_FREE,
                        *km.from_spec(kp.HEAVY_TOP, np.array([1e300, 1.0, 0.0, 0.0]), EMPTY), kp.new_work(), 1e-8, 1e-10, np.inf,
                        10**6, 10**6)
    assert status in (kd.NONFINITE, kd.STEP_TOO_SMALL)
    assert cnt[kd.CNT_STEPS] + cnt[kd.CNT_REJECTED] < 10_000


# ---------------------------------------------------------------------------------------
# Lockstep lanes


@pytest.mark.parametrize("kind,inertia,params", [(kp.TORQUE_FREE, I_FREE, NO_PARAMS),
                                                 (kp.HEAVY_TOP, I_FREE, PARAMS_TOP),
                                                 (kp.GRAVITY_GRADIENT_KEPLER, I_SAT, PARAMS_GG)])
def test_lane_rhs_equals_rhs(kind, inertia, params):
    """The vectorized group right-hand side performs the operations of hamiltonian.rhs."""
    from orbatt.core.hamiltonian import rhs, rhs_lanes

    rng = np.random.default_rng(kind)
    L = 13
    Y = rng.normal(size=(8, L))
    I = np.tile(inertia[:, None], (1, L)) * rng.uniform(0.9, 1.1, size=(3, L))
    dY = np.empty((8, L))
    G = np.empty((4, L))
    work = kp.new_work()
    model = km.from_spec(kind, params, EMPTY)
    for t in (0.0, 1234.5, 1300.0):
        rhs_lanes(t, Y, L, I, *model, work, G, dY)
        for l in range(L):
            dy = np.empty(8)
            rhs(t, np.ascontiguousarray(Y[:, l]), np.ascontiguousarray(I[:, l]), *model, kp.new_work(), dy)
            # the same operations member by member: bitwise
            np.testing.assert_array_equal(dY[:, l], dy)


def test_dop853_lanes_agrees_with_one_by_one_to_tolerance(sat):
    """Lockstep groups share the step size (the largest error of the group controls it):
    each member is at least as accurate as alone, not bitwise identical."""
    body, _ = sat
    q, g = random_data(40, seed=4)
    states = orbatt.State.from_momentum(body, q, g)
    t = np.array([0.0, 0.5 * PERIOD, PERIOD])
    ref = orbatt.propagate(body, states, GG, t, rtol=1e-14, atol=1e-16)
    for lanes in (1, 16, 64):
        ens = orbatt.propagate(body, states, GG, t, method="dop853-lanes", rtol=1e-9, atol=1e-11, lanes=lanes)
        assert ens.q.shape == (40, 3, 4) and ens.settings["lanes"] == lanes
        alone = orbatt.propagate(body, states, GG, t, rtol=1e-9, atol=1e-11)
        err_lanes = angle(ens.q, ref.q).max(axis=1)
        err_alone = angle(alone.q, ref.q).max(axis=1)
        assert err_lanes.max() < 2e-8
        assert np.all(err_lanes <= 2.0 * err_alone + 1e-12)
        if lanes == 1:  # a group of one lane runs the single loop's operations
            assert ens.stats["steps"] == alone.stats["steps"]
            np.testing.assert_array_equal(ens.q, alone.q)

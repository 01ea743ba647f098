"""method="bs32": the Bogacki-Shampine 3(2) pair (orbatt.core.bs32_coefficients) in the one
compiled step loop (issue 32 item 8). The coefficients against the published rationals and the
order conditions; the loop equal to the tableau with fixed steps and its global error of order 3
against the exact free body; the embedded estimate of order 2 (local error h^3); on the 10 Hz
LVLH hold on wheels one step per tick and agreement with DOP853; continuation bit for bit,
ensembles and lanes; the method listed."""
from __future__ import annotations

import re
from fractions import Fraction as F

import numpy as np
import pytest
from method_cases import I_FREE, Y0, angle, exact_free, free_rhs, run_dop853, tableau_steps

import orbatt
from orbatt.core import bs32_coefficients as bc
from orbatt.core import dop853 as kd
from orbatt.methods import METHODS, Bs32, Bs32Lanes, methods
from orbatt.methods.base import resolve_method
from orbatt.scenario import parse
from orbatt.shipped import shipped_file

#: Bogacki & Shampine (1989)
C_EXACT = [F(0), F(1, 2), F(3, 4), F(1)]
A_EXACT = {(1, 0): F(1, 2), (2, 1): F(3, 4), (3, 0): F(2, 9), (3, 1): F(1, 3), (3, 2): F(4, 9)}
B_EXACT = [F(2, 9), F(1, 3), F(4, 9), F(0)]
BHAT_EXACT = [F(7, 24), F(1, 4), F(1, 3), F(1, 8)]


def _conditions(b, A, c):
    """The residuals of the order conditions up to order 4 of the weights ``b`` on ``(A, c)``."""
    Ac = A @ c
    return {1: [b.sum() - 1], 2: [b @ c - F(1, 2)], 3: [b @ (c * c) - F(1, 3), b @ Ac - F(1, 6)],
            4: [b @ (c * c * c) - F(1, 4), b @ (c * Ac) - F(1, 8), b @ (A @ (c * c)) - F(1, 12),
                b @ (A @ Ac) - F(1, 24)]}


def test_coefficients_are_the_published_rationals_and_have_orders_3_and_2():
    """Every float is the nearest float64 to the rational; ``b`` meets the conditions up to
    order 3 and not 4, ``bhat = b - e`` up to 2 and not 3; the nodes are the rows' sums and the
    last row of ``A`` is ``b`` (stage 4 is ``f(t + h, y_new)``)."""
    n = bc.N_STAGES
    assert n == 4 and bc.LAST_STAGE_IS_NEW and bc.ORDER == 3 and bc.ORDER_EMBEDDED == 2
    for i in range(n):
        assert bc.C[i] == float(C_EXACT[i]) and bc.B[i] == float(B_EXACT[i])
        assert bc.E[i] == float(B_EXACT[i] - BHAT_EXACT[i])
        for j in range(n):
            assert bc.A[i, j] == float(A_EXACT.get((i, j), 0)), (i, j)
    A = np.array([[A_EXACT.get((i, j), F(0)) for j in range(n)] for i in range(n)], dtype=object)
    c = np.array(C_EXACT, dtype=object)
    b = np.array(B_EXACT, dtype=object)
    bhat = np.array(BHAT_EXACT, dtype=object)
    assert all(sum(A[i]) == c[i] for i in range(n)) and list(A[n - 1]) == list(b)
    res, res_hat = _conditions(b, A, c), _conditions(bhat, A, c)
    assert all(r == 0 for order in (1, 2, 3) for r in res[order]) and any(r != 0 for r in res[4])
    assert all(r == 0 for order in (1, 2) for r in res_hat[order]) and any(r != 0 for r in res_hat[3])
    assert kd.TABLEAUS["bs32"][0] == 4 and kd.TABLEAUS["dopri5"][0] == 7


def test_loop_is_the_tableau_with_fixed_steps_and_converges_with_order_3():
    """Loose tolerances and ``max_step = T / n``: ``n`` steps of 3 evaluations (the fourth
    stage is the next step's first), equal to round-off to a numpy evaluation of the tableau;
    the global error at ``T`` against the exact free body falls as ``h^3`` (slopes in 2.9-3.1
    over n = 256 -> 2048)."""
    T = 12.0
    f = free_rhs()
    q, _ = exact_free([T])
    ns = (256, 512, 1024, 2048)
    errs = []
    for n in ns:
        out, cnt = run_dop853([T], rtol=1.0, atol=1.0, max_step=T / n, h0=T / n, advance=kd.advance_bs32)
        assert cnt[kd.CNT_REJECTED] == 0 and cnt[kd.CNT_STEPS] == n and cnt[kd.CNT_NFEV] == 3 * n + 1
        if n == 256:
            y = tableau_steps(f, T / n, n, bc, stages=bc.N_STAGES - 1)
            np.testing.assert_allclose(out[-1], y, rtol=0, atol=1e-13)
        errs.append(angle(out[-1, :4], q[0]))
    slopes = np.diff(np.log2(errs)) / -np.diff(np.log2(ns))
    assert np.all((slopes > 2.9) & (slopes < 3.1)), (errs, slopes)


def test_embedded_estimate_has_order_2():
    """One step of size ``h`` from ``Y0``: the local error of ``y_new`` (order 3) falls as
    ``h^4``, the estimate ``h E . K`` and the local error of ``y_hat = y_new - h E . K`` (order 2)
    as ``h^3``, and the estimate tracks the embedded solution's error (ratio -> 1)."""
    f = free_rhs()
    hs = 0.2 / 2.0 ** np.arange(4)
    err_new, err_hat, est = [], [], []
    for h in hs:
        K = np.zeros((bc.N_STAGES, 8))
        for s in range(bc.N_STAGES):
            K[s] = f(bc.C[s] * h, Y0 + h * (bc.A[s, :s] @ K[:s]))
        y_new = Y0 + h * (bc.B @ K)
        e = h * (bc.E @ K)
        q, Q = exact_free([h])
        exact = np.concatenate([q[0], Q[0]])
        err_new.append(np.linalg.norm(y_new - exact))
        err_hat.append(np.linalg.norm(y_new - e - exact))
        est.append(np.linalg.norm(e))
    for errs, order in ((err_new, 4), (err_hat, 3), (est, 3)):
        slopes = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
        assert np.all(np.abs(slopes - order) < 0.25), (order, errs, slopes)
    assert abs(est[-1] / err_hat[-1] - 1.0) < 0.1


def test_adaptive_error_falls_with_rtol_on_the_free_body():
    """Adaptive, against ``method="exact"``: over 20 time units the global error is proportional
    to rtol (1000x smaller for 1000x in rtol; measured ~1600 rtol over ~240-2400 steps) and the
    steps grow as rtol^(-1/3) (order 3: 10x for 1000x)."""
    body = orbatt.RigidBody(list(I_FREE))
    s0 = orbatt.State(body, Y0[:4], Y0[4:])
    t = np.linspace(0.0, 20.0, 9)
    ref = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact")
    errs, steps = [], []
    for rtol in (1e-6, 1e-9):
        tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="bs32", rtol=rtol, atol=rtol)
        assert tr.method == "bs32" and tr.settings["order"] == 3
        errs.append(angle(tr.q, ref.q).max())
        steps.append(tr.stats["steps"])
        assert errs[-1] < 3000 * rtol
    assert 0.5e-3 < errs[1] / errs[0] < 2e-3, errs
    # steps ~ rtol^(-1/3): 10x for 1000x
    assert 7 < steps[1] / steps[0] < 13, steps


def _lvlh(t_end):
    """The 10 Hz LVLH hold on three wheels with gravity gradient (benchmarks/basilisk_fsw.py)."""
    text = shipped_file("lvlh-hold-wheels").read_text()
    text = text.replace('actuator = "wheels"\n', 'actuator = "wheels"\nperiod = "0.1 s"\n', 1)
    return re.sub(r'^t_end = "[^"]*"', f't_end = "{t_end}"', text, flags=re.M)


@pytest.mark.parametrize("iv", ["auto", "time"])
def test_one_step_per_tick_and_agrees_with_dop853_on_the_ticked_lvlh_hold(iv):
    """bs32 at rtol 1e-10 against dop853 at rtol 1e-12, ticks at 10 Hz, in the eccentric anomaly
    (``auto``) and in time, over the 30 deg transient (200 s): attitude, momentum and wheels'
    momenta agree to 1e-9 (relative; measured 7.2e-10 rad, 3e-10, 6e-10); one step per tick (a
    few ticks of the transient take two: 2123 steps for 2000 ticks), each of 3 evaluations; the
    derivative after a tick is the last stage's with its wheels' rows rewritten for the new
    command (orbatt.core.held_commands: no evaluation)."""
    sc = orbatt.Scenario(parse(_lvlh("200 s"), "lvlh.toml"))
    b3 = sc.run(method="bs32", rtol=1e-10, atol=1e-10, independent_variable=iv)
    ref = sc.run(method="dop853", rtol=1e-12, atol=1e-12, independent_variable=iv)
    assert b3.attrs["method"] == "bs32"
    assert angle(b3["q"].values, ref["q"].values).max() < 1e-9
    for v in ("Q", "wheel_momentum"):
        scale = np.abs(ref[v].values).max()
        np.testing.assert_allclose(b3[v].values, ref[v].values, rtol=0, atol=1e-9 * scale, err_msg=v)
    s = b3.orbatt.stats
    ticks = round(float(sc.times[-1] - sc.times[0]) / 0.1)
    assert s["rejected_steps"] == 0 and ticks <= s["steps"] <= 1.07 * ticks
    # (+ 2: the derivative at the start and Hairer's initial-step probe)
    assert s["rhs_evaluations"] == 3 * s["steps"] + 2


def test_continuation_is_bitwise_and_lanes_agree():
    """On the LVLH hold (60 s): a run continued from its state at 25 s (on a tick) and at 25.05 s
    (between ticks) equals the single run bit for bit; each member of an ensemble equals it bit
    for bit; ``bs32-lanes`` agrees to the tolerance."""
    text = re.sub(r'^output_step = "[^"]*"', 'output_step = "0.05 s"', _lvlh("60 s"), flags=re.M)
    sc = orbatt.Scenario(parse(text, "lvlh.toml"))
    kw = dict(rtol=1e-10, atol=1e-10)
    one = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method="bs32", **kw)
    for split in (25.0, 25.05):
        first = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times[sc.times <= split], method="bs32", **kw)
        state = first.state()
        assert state.stepper is not None and state.stepper["method"] == "bs32"
        rest = orbatt.propagate(sc.body, state, sc.potential, sc.times[sc.times >= split], method="bs32", **kw)
        k = int(np.searchsorted(one.t, split))
        for v in ("q", "Q", "wheel_momenta", "command"):
            np.testing.assert_array_equal(getattr(rest, v), getattr(one, v)[k:], err_msg=f"{v} {split}")
    twice = orbatt.State(sc.body, np.stack([sc.state0.q] * 2), np.stack([sc.state0.Q] * 2))
    ens = orbatt.propagate(sc.body, twice, sc.potential, sc.times, method="bs32", **kw)
    lanes = orbatt.propagate(sc.body, twice, sc.potential, sc.times, method="bs32-lanes", **kw)
    assert lanes.method == "bs32-lanes"
    for e in range(2):
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.wheel_momenta[e], one.wheel_momenta)
        assert angle(lanes.q[e], one.q).max() < 1e-10


def test_registered_listed_and_named_in_scenarios():
    """``"bs32"`` and ``"bs32-lanes"`` resolve and are listed (:func:`orbatt.methods.methods`,
    the methods' docstring); ``[integration] method = "bs32"`` runs it, in the eccentric anomaly."""
    assert resolve_method("bs32") is METHODS["bs32"] is Bs32 and METHODS["bs32-lanes"] is Bs32Lanes
    assert Bs32Lanes.order == 3 and Bs32.ticks and Bs32.extended and "independent_variable" in Bs32.options
    assert {"bs32", "bs32-lanes"} <= set(methods())
    assert '``"bs32"``' in orbatt.methods.__doc__ and '``"bs32-lanes"``' in orbatt.methods.__doc__
    text = _lvlh("20 s").replace('method = "dop853"', 'method = "bs32"')
    if 'method = "bs32"' not in text:
        text = text.replace("[integration]\n", '[integration]\nmethod = "bs32"\n', 1)
    ds = orbatt.Scenario(parse(text, "lvlh.toml")).run()
    assert ds.attrs["method"] == "bs32" and "eccentric-anomaly" in ds.attrs["method_settings"]

"""method="dopri5": the Dormand-Prince 5(4) pair (orbatt.core.dopri5_coefficients) in the one
compiled step loop (issue 32 item 8). The coefficients against the published rationals and
the order conditions; the loop equal to the tableau with fixed steps and its global error of
order 5; agreement with DOP853 on the ticked shipped scenarios in time and in the eccentric
anomaly; pause/resume, continuation and ensembles bit for bit; the scenario key."""
from __future__ import annotations

import re
from fractions import Fraction as F

import numpy as np
import pytest
from method_cases import angle, exact_free, free_rhs, run_dop853, tableau_steps

import orbatt
from orbatt.core import dop853 as kd
from orbatt.core import dopri5_coefficients as dc
from orbatt.core.held_commands import wheel_ticks_only
from orbatt.methods import METHODS, Dopri5
from orbatt.methods.base import resolve_method
from orbatt.methods.problem import kernel_spec
from orbatt.scenario import parse
from orbatt.shipped import shipped_file

#: Dormand & Prince (1980), RK5(4)7M (Hairer's dopri5.f)
C_EXACT = [F(0), F(1, 5), F(3, 10), F(4, 5), F(8, 9), F(1), F(1)]
A_EXACT = {(1, 0): F(1, 5), (2, 0): F(3, 40), (2, 1): F(9, 40), (3, 0): F(44, 45), (3, 1): F(-56, 15),
           (3, 2): F(32, 9), (4, 0): F(19372, 6561), (4, 1): F(-25360, 2187), (4, 2): F(64448, 6561),
           (4, 3): F(-212, 729), (5, 0): F(9017, 3168), (5, 1): F(-355, 33), (5, 2): F(46732, 5247),
           (5, 3): F(49, 176), (5, 4): F(-5103, 18656), (6, 0): F(35, 384), (6, 2): F(500, 1113),
           (6, 3): F(125, 192), (6, 4): F(-2187, 6784), (6, 5): F(11, 84)}
B_EXACT = [F(35, 384), F(0), F(500, 1113), F(125, 192), F(-2187, 6784), F(11, 84), F(0)]
E_EXACT = [F(71, 57600), F(0), F(-71, 16695), F(71, 1920), F(-17253, 339200), F(22, 525), F(-1, 40)]


def _conditions(b, A, c):
    """The residuals of the order conditions of the weights ``b`` on ``(A, c)`` (Butcher's
    rooted trees), by order: ``{order: [sum - 1/gamma, ...]}``."""
    Ac, c2, c3 = A @ c, c * c, c * c * c
    AAc = A @ Ac
    return {1: [b.sum() - 1], 2: [b @ c - F(1, 2)],
            3: [b @ c2 - F(1, 3), b @ Ac - F(1, 6)],
            4: [b @ c3 - F(1, 4), b @ (c * Ac) - F(1, 8), b @ (A @ c2) - F(1, 12), b @ AAc - F(1, 24)],
            5: [b @ (c3 * c) - F(1, 5), b @ (c2 * Ac) - F(1, 10), b @ (c * (A @ c2)) - F(1, 15),
                b @ (c * AAc) - F(1, 30), b @ (Ac * Ac) - F(1, 20), b @ (A @ c3) - F(1, 20),
                b @ (A @ (c * Ac)) - F(1, 40), b @ (A @ (A @ c2)) - F(1, 60), b @ (A @ AAc) - F(1, 120)]}


def test_coefficients_are_the_published_rationals_and_have_orders_5_and_4():
    """Every float of the table is the nearest float64 to Dormand & Prince's rational; with the
    rationals, ``b`` meets every order condition up to 5, ``bhat = b - e`` up to 4 and not 5,
    the nodes are the rows' sums and the last row of ``A`` is ``b`` (the seventh stage is
    ``f(t + h, y_new)``)."""
    n = dc.N_STAGES
    assert n == 7 and dc.LAST_STAGE_IS_NEW
    for i in range(n):
        assert dc.C[i] == float(C_EXACT[i]) and dc.B[i] == float(B_EXACT[i]) and dc.E[i] == float(E_EXACT[i])
        for j in range(n):
            assert dc.A[i, j] == float(A_EXACT.get((i, j), 0)), (i, j)
    A = np.array([[A_EXACT.get((i, j), F(0)) for j in range(n)] for i in range(n)], dtype=object)
    c = np.array(C_EXACT, dtype=object)
    b = np.array(B_EXACT, dtype=object)
    bhat = b - np.array(E_EXACT, dtype=object)
    assert all(sum(A[i]) == c[i] for i in range(n)) and list(A[n - 1]) == list(b)
    for order, res in _conditions(b, A, c).items():
        assert all(r == 0 for r in res), order
    res = _conditions(bhat, A, c)
    assert all(r == 0 for order in (1, 2, 3, 4) for r in res[order])
    assert any(r != 0 for r in res[5])
    # the step loop runs the pair with its own controller (exponent 1/5) and the FSAL stage
    assert kd.TABLEAUS["dopri5"][0] == 7 and kd.TABLEAUS["dop853"][0] == 12 and kd.TABLEAUS["verner98"][0] == 16



def test_loop_is_the_tableau_with_fixed_steps_and_converges_with_order_5():
    """Loose tolerances and ``max_step = T / n``: the loop takes ``n`` steps of 6 evaluations
    (the seventh stage is the next step's first), equal to round-off to a plain numpy
    evaluation of the tableau; the global error at ``T`` against the exact free body falls as
    ``h^5`` (slope between 4.8 and 5.2 over n = 128 -> 1024; pre-asymptotic below)."""
    T = 12.0
    f = free_rhs()

    q, _ = exact_free([T])
    ns = (128, 256, 512, 1024)
    errs = []
    for n in ns:
        out, cnt = run_dop853([T], rtol=1.0, atol=1.0, max_step=T / n, h0=T / n, advance=kd.advance_dopri5)
        assert cnt[kd.CNT_REJECTED] == 0 and cnt[kd.CNT_STEPS] == n and cnt[kd.CNT_NFEV] == 6 * n + 1
        if n == 128:
            y = tableau_steps(f, T / n, n, dc, stages=dc.N_STAGES - 1)
            np.testing.assert_allclose(out[-1], y, rtol=0, atol=1e-13)
        errs.append(angle(out[-1, :4], q[0]))
    slopes = np.diff(np.log2(errs)) / -np.diff(np.log2(ns))
    assert np.all((slopes > 4.8) & (slopes < 5.2)), (errs, slopes)


def test_meets_the_tolerance_on_the_free_body(free):
    """Adaptive: the attitude error against the exact free body over 20 time units stays within
    a few times rtol, and falls with it."""
    body, s0 = free
    t = np.linspace(0.0, 20.0, 9)
    errs = []
    for rtol in (1e-7, 1e-10):
        tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="dopri5", rtol=rtol, atol=rtol)
        assert tr.method == "dopri5" and tr.settings["order"] == 5
        qref, _ = exact_free(t)
        errs.append(angle(tr.q, qref).max())
        assert errs[-1] < 50 * rtol
    assert errs[1] < 1e-2 * errs[0]


def _short(name, t_end, period=None):
    text = shipped_file(name).read_text()
    if period is not None:
        text = text.replace("[control]\n", f'[control]\nperiod = "{period}"\n', 1)
    return re.sub(r'^t_end = "[^"]*"', f't_end = "{t_end}"', text, flags=re.M)


#: the shipped scenarios with ticks at 10 Hz: the rate-limited slew on wheels, and the LVLH hold
#: on wheels with its law at 10 Hz
TICKED = {"slew": lambda: _short("cubesat-slew-wheels", "120 s"),
          "lvlh": lambda: _short("lvlh-hold-wheels", "300 s", period="0.1 s")}


@pytest.mark.parametrize("name", sorted(TICKED))
@pytest.mark.parametrize("iv", ["auto", "time"])
def test_agrees_with_dop853_on_the_ticked_scenarios(name, iv):
    """dopri5 at rtol 1e-10 against dop853 at rtol 1e-12, with ticks at 10 Hz, in the eccentric
    anomaly (``auto`` on these Keplerian orbits) and in time: the attitude, the momentum and the
    wheels' momenta agree to 1e-10 (relative); one step per tick, each of 6 evaluations plus the
    derivative again after the tick (the held command changed), except where the only laws are PD
    laws on the wheels: then the last stage's derivative with its wheels' rows rewritten
    (orbatt.core.held_commands: no evaluation)."""
    sc = orbatt.Scenario(parse(TICKED[name](), f"{name}.toml"))
    d5 = sc.run(method="dopri5", rtol=1e-10, atol=1e-10, independent_variable=iv)
    ref = sc.run(method="dop853", rtol=1e-12, atol=1e-12, independent_variable=iv)
    assert d5.attrs["method"] == "dopri5"
    assert angle(d5["q"].values, ref["q"].values).max() < 1e-10
    for v in ("Q", "wheel_momentum"):
        scale = np.abs(ref[v].values).max()
        np.testing.assert_allclose(d5[v].values, ref[v].values, rtol=0, atol=1e-10 * scale, err_msg=v)
    s = d5.orbatt.stats
    ticks = round(float(sc.times[-1] - sc.times[0]) / 0.1)
    # (the first tick interval may take 2 or 3 steps from Hairer's initial step, in time)
    assert s["rejected_steps"] == 0 and ticks <= s["steps"] <= ticks + 2
    # (+ 2: the derivative at the start and Hairer's initial-step probe)
    k = kernel_spec(sc.potential, [sc.body])
    after_tick = 0 if wheel_ticks_only(k.terms, k.params) else ticks
    assert after_tick == 0   # (both scenarios' laws are PD laws on the wheels)
    assert s["rhs_evaluations"] == 6 * s["steps"] + after_tick + 2


class _Pausing(Dopri5):
    """dopri5 returning to Python every 3 step attempts (not registered)."""

    def advance(self, budget):
        return super().advance(3)


def test_pause_resume_continuation_and_ensembles_are_bitwise():
    """With ticks (the slew, 60 s): a run paused every 3 attempts, a run continued from its state
    at 25 s (on a tick) and at 25.05 s (between ticks; outputs every 0.05 s), and each member of
    an ensemble equal the single run bit for bit; ``dopri5-lanes`` agrees to the tolerance."""
    text = re.sub(r'^output_step = "[^"]*"', 'output_step = "0.05 s"', _short("cubesat-slew-wheels", "60 s"),
                  flags=re.M)
    sc = orbatt.Scenario(parse(text, "slew.toml"))
    kw = dict(rtol=1e-10, atol=1e-10)
    one = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method="dopri5", **kw)
    paused = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method=_Pausing, **kw)
    for v in ("q", "Q", "wheel_momenta", "command"):
        np.testing.assert_array_equal(getattr(paused, v), getattr(one, v), err_msg=v)
    for split in (25.0, 25.05):
        first = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times[sc.times <= split], method="dopri5",
                                 **kw)
        state = first.state()
        assert state.stepper is not None and state.stepper["method"] == "dopri5"
        rest = orbatt.propagate(sc.body, state, sc.potential, sc.times[sc.times >= split], method="dopri5", **kw)
        k = int(np.searchsorted(one.t, split))
        for v in ("q", "Q", "wheel_momenta", "command"):
            np.testing.assert_array_equal(getattr(rest, v), getattr(one, v)[k:], err_msg=f"{v} {split}")
    twice = orbatt.State(sc.body, np.stack([sc.state0.q] * 2), np.stack([sc.state0.Q] * 2))
    ens = orbatt.propagate(sc.body, twice, sc.potential, sc.times, method="dopri5", **kw)
    lanes = orbatt.propagate(sc.body, twice, sc.potential, sc.times, method="dopri5-lanes", **kw)
    for e in range(2):
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.wheel_momenta[e], one.wheel_momenta)
        assert angle(lanes.q[e], one.q).max() < 1e-10


def test_registered_and_named_in_scenarios():
    """``method="dopri5"`` and ``"dopri5-lanes"`` resolve; ``[integration] method = "dopri5"``
    runs it; the eccentric anomaly option is the DOP853 driver's."""
    assert resolve_method("dopri5") is METHODS["dopri5"] is Dopri5 and METHODS["dopri5-lanes"].order == 5
    assert Dopri5.ticks and Dopri5.extended and "independent_variable" in Dopri5.options
    text = _short("cubesat-slew-wheels", "5 s").replace('method = "dop853"', 'method = "dopri5"')
    sc = orbatt.Scenario(parse(text, "slew.toml"))
    ds = sc.run()
    assert ds.attrs["method"] == "dopri5" and "eccentric-anomaly" in ds.attrs["method_settings"]

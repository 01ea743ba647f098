"""method="vern98": Verner's 9(8) pair in the compiled step loop of orbatt.core.dop853
(coefficients: tests/core/test_verner98.py). Agreement with the exact free body and with
DOP853 on the Keplerian gravity gradient, invariants, ensembles, DOP853 unchanged."""
from __future__ import annotations

import numpy as np
import pytest
from method_cases import GG, PERIOD, angle, exact_free, free_rhs, random_data, run_dop853, tableau_steps

import orbatt
from orbatt import canonical
from orbatt.core import dop853 as kd
from orbatt.core import verner98_coefficients as vc



def test_vern98_loop_is_the_tableau_with_fixed_steps():
    """Loose tolerances, the step bounded by max_step = 12 / n: a fixed-step pair, equal to
    round-off to the same steps taken by a plain numpy evaluation of the tableau
    (orbatt.core.verner98_coefficients) on the same right-hand side; the error at t = 12
    against the exact solution falls with n (the order itself is checked on the coefficients,
    tests/core/test_verner98.py: the free body is pre-asymptotic here, ~8.4 over n = 8 -> 32)."""
    T = 12.0
    f = free_rhs()

    q, _ = exact_free([T])
    errs = []
    for n in (8, 16, 32):
        out, cnt = run_dop853([T], rtol=1.0, atol=1.0, max_step=T / n, h0=T / n, advance=kd.advance_verner98)
        assert cnt[kd.CNT_REJECTED] == 0 and cnt[kd.CNT_STEPS] == n and cnt[kd.CNT_NFEV] == 16 * n + 1
        np.testing.assert_allclose(out[-1], tableau_steps(f, T / n, n, vc), rtol=0, atol=1e-13)
        errs.append(angle(out[-1, :4], q[0]))
    assert np.log2(errs[0] / errs[-1]) / 2 > 7.5, errs


def test_vern98_meets_tolerance_and_keeps_invariants(free):
    body, s0 = free
    t = np.linspace(0.0, 50.0, 11)
    qx, Qx = exact_free(t)
    for rtol, bound in ((1e-8, 1e-6), (1e-11, 1e-9), (1e-13, 1e-11)):
        tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="vern98", rtol=rtol, atol=rtol)
        assert tr.method == "vern98" and tr.settings["order"] == 9
        np.testing.assert_array_equal(tr.t, t)
        assert angle(tr.q, qx).max() < bound
        # |q| = 1, q.Q = 0 and the energy T, to the tolerance
        assert np.abs(np.linalg.norm(tr.q, axis=-1) - 1.0).max() < 10 * bound
        qQ = np.einsum("...i,...i", tr.q, tr.Q)  # (the printed Q(t0) has q.Q = -9.7e-8: docs/design.md §3a item 9)
        assert np.abs(qQ - qQ[0]).max() < 10 * bound
        T = canonical.kinetic_energy(tr.q, tr.Q, body.inertia_value)
        assert np.abs(T / T[0] - 1.0).max() < 10 * bound


@pytest.mark.parametrize("iv", ["auto", "time"])
def test_vern98_agrees_with_dop853_on_keplerian_gravity_gradient(sat, iv):
    """The paper's Keplerian case over 2 orbits: vern98 at rtol 1e-11 and dop853 at 1e-11
    both within 1e-8 rad of dop853 at 1e-14; |q| = 1 and q.Q = 0 kept."""
    body, s0 = sat
    t = np.linspace(0.0, 2 * PERIOD, 5)
    ref = orbatt.propagate(body, s0, GG, t, rtol=1e-14, atol=1e-14, independent_variable=iv)
    v = orbatt.propagate(body, s0, GG, t, method="vern98", rtol=1e-11, atol=1e-11, independent_variable=iv)
    d = orbatt.propagate(body, s0, GG, t, rtol=1e-11, atol=1e-11, independent_variable=iv)
    assert v.settings["independent_variable"] == d.settings["independent_variable"]
    assert angle(v.q, ref.q).max() < 1e-8 and angle(d.q, ref.q).max() < 1e-8
    assert np.abs(v.Q - ref.Q).max() < 1e-8 * np.abs(ref.Q).max()
    assert np.abs(np.linalg.norm(v.q, axis=-1) - 1.0).max() < 1e-10
    qQ = np.einsum("...i,...i", v.q, v.Q)
    assert np.abs(qQ - qQ[0]).max() < 1e-10 * np.abs(ref.Q).max()
    # the same work-precision class: no more right-hand-side evaluations than dop853 here
    assert v.stats["steps"] < d.stats["steps"]


def test_vern98_ensemble_is_bitwise_one_by_one(sat):
    body, _ = sat
    q, g = random_data(6, seed=7)
    states = orbatt.State.from_momentum(body, q, g)
    t = np.array([0.0, 0.5 * PERIOD, PERIOD])
    ens = orbatt.propagate(body, states, GG, t, method="vern98", rtol=1e-10, atol=1e-10)
    assert ens.q.shape == (6, 3, 4)
    for e in range(6):
        one = orbatt.propagate(body, orbatt.State.from_momentum(body, q[e], g[e]), GG, t, method="vern98", rtol=1e-10, atol=1e-10)
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.Q[e], one.Q)


def test_vern98_dop853_tableau_unchanged():
    """The DOP853 loop runs the DOP853 tableau; the pairs differ."""
    assert kd.TABLEAUS["dop853"][0] == 12 and kd.TABLEAUS["verner98"][0] == 16
    a, _ = run_dop853([5.0], rtol=1e-10, atol=1e-10)
    b, _ = run_dop853([5.0], rtol=1e-10, atol=1e-10, advance=kd.advance_verner98)
    assert 0.0 < angle(a[-1, :4], b[-1, :4]) < 1e-8


@pytest.mark.parametrize("name", ["lvlh-hold-wheels", "cubesat-bdot-detumble"])
def test_vern98_integrates_wheels_and_control_laws(name):
    """Extended models (reaction wheels with a PD law; a B-dot law on magnetorquers) over a
    tenth of the shipped scenario: vern98 at rtol 1e-11 and dop853 at rtol 1e-13 agree on the
    attitude, the momentum and the wheels' momenta; an ensemble of the scenario's state twice
    is bitwise the single run."""
    sc = orbatt.load_scenario(name)
    sc.times = sc.times[: max(3, sc.times.size // 10)]
    v = sc.run(method="vern98", rtol=1e-11, atol=1e-11)
    d = sc.run(method="dop853", rtol=1e-13, atol=1e-13)
    assert v.attrs["method"] == "vern98" and v.orbatt.stats["steps"] > 0
    assert angle(v["q"].values, d["q"].values).max() < 1e-8
    np.testing.assert_allclose(v["Q"].values, d["Q"].values, rtol=0, atol=1e-8 * np.abs(d["Q"].values).max())
    if "wheel_momentum" in d:  # (the B-dot cubesat has no wheels)
        h = d["wheel_momentum"].values
        np.testing.assert_allclose(v["wheel_momentum"].values, h, rtol=0, atol=1e-8 * np.abs(h).max())
    t = sc.times
    one = orbatt.propagate(sc.body, sc.state0, sc.potential, t, method="vern98", rtol=1e-11, atol=1e-11)
    twice = orbatt.State(sc.body, np.stack([sc.state0.q] * 2), np.stack([sc.state0.Q] * 2))
    ens = orbatt.propagate(sc.body, twice, sc.potential, t, method="vern98", rtol=1e-11, atol=1e-11)
    for e in range(2):
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.Q[e], one.Q)

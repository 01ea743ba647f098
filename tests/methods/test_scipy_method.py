"""orbatt.methods.scipy_ivp: scipy's solvers on the compiled right-hand side."""
from __future__ import annotations

import orbatt
from method_cases import GG, PERIOD, angle, random_states

def test_scipy_reference_path_agrees_with_compiled(sat):
    body, s0 = sat
    t = [0.0, 0.5 * PERIOD, PERIOD]
    a = orbatt.propagate(body, s0, GG, t, rtol=1e-12, atol=1e-14)
    b = orbatt.propagate(body, s0, GG, t, method="scipy-DOP853", rtol=1e-12, atol=1e-14)
    assert angle(a.q, b.q).max() < 1e-10
    # same algorithm, same step-size control: similar work
    assert 0.7 < a.stats["rhs_evaluations"] / b.stats["rhs_evaluations"] < 1.3


def test_ensemble_scipy_reference(free):
    body, _ = free
    states = random_states(body, 2, seed=9)
    t = [0.0, 1.0, 2.0]
    a = orbatt.propagate(body, states, orbatt.TorqueFree(), t, method="scipy-DOP853", rtol=1e-12, atol=1e-14)
    b = orbatt.propagate(body, states, orbatt.TorqueFree(), t, rtol=1e-12, atol=1e-14)
    assert a.q.shape == b.q.shape == (2, 3, 4)
    assert angle(a.q, b.q).max() < 1e-10

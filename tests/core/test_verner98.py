"""Verner's 9(8) pair (orbatt.core.verner98_coefficients), checked independently of its
source: the tableau's consistency, every Butcher order condition (rooted trees) up to order 9
for the propagated solution and up to 8 for the embedded one (and that the embedded one is not
of order 9), and the observed convergence orders of both with fixed steps."""
from __future__ import annotations

import math

import numpy as np
import pytest

from orbatt.core import verner98_coefficients as vc


def test_verner98_tableau_is_consistent():
    np.testing.assert_allclose(vc.A.sum(axis=1), vc.C, atol=1e-14)
    assert np.all(np.triu(vc.A) == 0.0)
    assert vc.B.sum() == pytest.approx(1.0, abs=1e-14)
    assert vc.BHAT.sum() == pytest.approx(1.0, abs=1e-14)
    assert abs(vc.E.sum()) < 1e-14
    assert vc.C[0] == 0.0 and vc.C[1] == 0.03462 and vc.C[14] == vc.C[15] == 1.0
    assert vc.B[15] == 0.0 and vc.BHAT[14] == 0.0 and vc.BHAT[13] == 0.0  # stage 16: embedded only
    # the quadrature conditions: sum b_i c_i^(k-1) = 1/k, k = 1..9 (the embedded weights to 8)
    for k in range(1, 10):
        assert (vc.B * vc.C ** (k - 1)).sum() == pytest.approx(1.0 / k, abs=1e-14)
    for k in range(1, 9):
        assert (vc.BHAT * vc.C ** (k - 1)).sum() == pytest.approx(1.0 / k, abs=1e-14)
    assert abs((vc.BHAT * vc.C ** 8).sum() - 1.0 / 9) > 1e-6
    # the sparse copy of A used by the stage loop
    for s in range(vc.N_STAGES):
        row = np.zeros(vc.N_STAGES)
        row[vc.A_COL[vc.A_PTR[s]:vc.A_PTR[s + 1]]] = vc.A_VAL[vc.A_PTR[s]:vc.A_PTR[s + 1]]
        np.testing.assert_array_equal(row, vc.A[s])


def _trees(order):
    """The rooted trees of each order 1..``order``: a tree is the sorted tuple of its root's
    subtrees (the leaf is ``()``)."""
    by_order = {1: {()}}
    for n in range(2, order + 1):
        grown = set()
        for t in by_order[n - 1]:
            grown |= _grow(t)
        by_order[n] = grown
    return by_order


def _grow(t):
    """The trees made by adding one leaf to any vertex of ``t``."""
    out = {tuple(sorted(t + ((),)))}
    for i, child in enumerate(t):
        for g in _grow(child):
            out.add(tuple(sorted(t[:i] + (g,) + t[i + 1:])))
    return out


def _weights(t, A):
    """The stage vector of tree ``t``: ``prod_children (A . weights(child))`` (ones for a
    leaf), and its density gamma(t)."""
    g = np.ones(A.shape[0])
    gamma = 1
    size = 1
    for child in t:
        gc, gamc, sc = _weights(child, A)
        g = g * (A @ gc)
        gamma *= gamc
        size += sc
    return g, gamma * size, size


def test_verner98_order_conditions():
    """``b . Phi(t) = 1 / gamma(t)`` for all 486 rooted trees of order <= 9 (the embedded
    weights: the 200 trees of order <= 8, and not all of order 9)."""
    trees = _trees(9)
    assert [len(trees[n]) for n in range(1, 10)] == [1, 1, 2, 4, 9, 20, 48, 115, 286]
    worst = {"b": 0.0, "bhat": 0.0, "bhat9": 0.0}
    for n in range(1, 10):
        for t in trees[n]:
            g, gamma, size = _weights(t, vc.A)
            assert size == n
            worst["b"] = max(worst["b"], abs(vc.B @ g - 1.0 / gamma) * gamma)
            r = abs(vc.BHAT @ g - 1.0 / gamma) * gamma
            if n <= 8:
                worst["bhat"] = max(worst["bhat"], r)
            else:
                worst["bhat9"] = max(worst["bhat9"], r)
    assert worst["b"] < 1e-11, worst
    assert worst["bhat"] < 1e-11, worst
    assert worst["bhat9"] > 1e-4, worst


def _rk_fixed(f, y0, T, n, w):
    """``n`` fixed steps of the pair with weights ``w`` (plain numpy)."""
    h = T / n
    y = np.array(y0, dtype=float)
    t = 0.0
    K = np.zeros((vc.N_STAGES, y.shape[0]))
    for _ in range(n):
        for s in range(vc.N_STAGES):
            K[s] = f(t + vc.C[s] * h, y + h * (vc.A[s, :s] @ K[:s]))
        y = y + h * (w @ K)
        t += h
    return y


def test_verner98_convergence_orders():
    """On y1' = 1 + y1^2, y2' = cos(t) y2, y3' = y1 y3 (exact: tan t, exp(sin t), 1/cos t),
    to t = 1: the observed orders over a range of step counts are ~9 (propagated solution) and
    ~8 (embedded), from a least-squares slope of log(error) against log(n)."""
    def f(t, y):
        return np.array([1.0 + y[0] ** 2, math.cos(t) * y[1], y[0] * y[2]])

    def exact(t):
        return np.array([math.tan(t), math.exp(math.sin(t)), 1.0 / math.cos(t)])

    T = 1.45
    ns = np.array([12, 16, 20, 24, 32, 40])
    slopes = {}
    for name, w in (("b", vc.B), ("bhat", vc.BHAT)):
        err = [np.abs(_rk_fixed(f, exact(0.0), T, n, w) / exact(T) - 1.0).max() for n in ns]
        slopes[name] = -np.polyfit(np.log(ns), np.log(err), 1)[0]
    assert 8.3 < slopes["b"] < 10.5, slopes
    assert 7.3 < slopes["bhat"] < 9.5, slopes

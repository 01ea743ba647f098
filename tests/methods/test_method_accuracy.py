"""Every registered method against the exact free rigid body and the classical model
(Euler's equations + quaternion kinematics), through orbatt.propagate."""
from __future__ import annotations

import numpy as np
import pytest
from method_cases import GG, PERIOD, angle, classical_reference

import orbatt
from orbatt import analytic
from orbatt.core import potentials as kp
from orbatt.methods import METHODS

FREE_SETTINGS = {
    "dop853": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "dop853-lanes": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "vern98": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "vern98-lanes": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "dopri5": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "dopri5-lanes": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "bs32": ({"rtol": 1e-10, "atol": 1e-12}, 1e-6),
    "bs32-lanes": ({"rtol": 1e-10, "atol": 1e-12}, 1e-6),
    "scipy-DOP853": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "scipy-RK45": ({"rtol": 1e-9, "atol": 1e-11}, 1e-7),
    "scipy-RK23": ({"rtol": 1e-8, "atol": 1e-10}, 1e-5),
    "scipy-Radau": ({"rtol": 1e-9, "atol": 1e-11}, 1e-7),
    "scipy-BDF": ({"rtol": 1e-7, "atol": 1e-9}, 1e-4),
    "scipy-LSODA": ({"rtol": 1e-10, "atol": 1e-12}, 1e-7),
    "rk4": ({"step": 0.005}, 1e-9),
    "splitting2": ({"step": 0.002}, 1e-6),
    "splitting4": ({"step": 0.05}, 1e-9),
    "splitting4-yoshida": ({"step": 0.02}, 1e-9),
    "splitting4-suzuki": ({"step": 0.05}, 1e-9),
    "splitting6": ({"step": 0.2}, 1e-9),
    "splitting6-yoshida": ({"step": 0.1}, 1e-9),
}


def test_every_method_has_settings_here():
    names = {c.name for c in METHODS.values() if not c.closed_form}  # "exact": test_exact_method.py
    assert names == set(FREE_SETTINGS)


@pytest.mark.parametrize("method", sorted(FREE_SETTINGS))
def test_every_method_matches_exact_free_body(free, method):
    body, s0 = free
    kw, bound = FREE_SETTINGS[method]
    t = np.linspace(0.0, 20.0, 9)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method=method, **kw)
    qref, Qref = analytic.torque_free(body.inertia_value, s0.q, s0.Q, t)
    assert tr.complete and tr.method == METHODS[method].name
    np.testing.assert_array_equal(tr.t, t)
    assert angle(tr.q, qref).max() < bound
    assert np.abs(tr.Q - Qref).max() < 10 * bound
    assert tr.stats["steps"] > 0 and tr.stats["wall_time_s"] > 0
    assert ("kicks" in tr.stats) == METHODS[method].symplectic


@pytest.mark.parametrize("method,kw,bound", [
    ("dop853", {"rtol": 1e-11, "atol": 1e-13}, 1e-9),
    ("scipy-DOP853", {"rtol": 1e-11, "atol": 1e-13}, 1e-9),
    ("rk4", {"step": 2.0}, 1e-9),
    ("splitting2", {"step": 0.25}, 1e-6),
    ("splitting4", {"step": 2.0}, 1e-9),
    ("splitting6", {"step": 5.0}, 1e-9),
])
def test_methods_match_classical_model_gravity_gradient(sat, method, kw, bound):
    """The paper's Keplerian case (Sect. 6.2), one orbit, against Euler's equations with the
    classical torque (3 GM / r^3) x_B x (I x_B)."""
    body, s0 = sat
    t = np.linspace(0.0, PERIOD, 5)
    ref = _classical_gg(body, s0)
    tr = orbatt.propagate(body, s0, GG, t, method=method, **kw)
    assert angle(tr.q, ref).max() < bound


_CACHE = {}


def _classical_gg(body, s0):
    if "gg" not in _CACHE:
        _CACHE["gg"] = classical_reference(body, s0, kp.GRAVITY_GRADIENT_KEPLER, GG.params,
                                           np.linspace(0.0, PERIOD, 5))
    return _CACHE["gg"]


def test_heavy_top_matches_classical_model(free):
    body, s0 = free
    top = orbatt.HeavyTop(0.5, [1.0, 0.0, 0.0])
    t = np.linspace(0.0, 20.0, 5)
    ref = classical_reference(body, s0, kp.HEAVY_TOP, top.params, t)
    for method, kw in (("dop853", {"rtol": 1e-12}), ("splitting4", {"step": 0.02}), ("splitting6", {"step": 0.1})):
        tr = orbatt.propagate(body, s0, top, t, method=method, **kw)
        assert angle(tr.q, ref).max() < 1e-9, method

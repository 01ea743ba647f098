"""The constant body torque (``[torques] constant``, :data:`orbatt.core.model.CONSTANT_TORQUE`;
issue 22's proof of one term added through the kind descriptors): exact solutions, an
independent Newton-Euler model, the Dataset's ``torque_constant``, scenario keys."""
from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from scipy.integrate import solve_ivp

import orbatt
from orbatt.core import kinds
from orbatt.core import model as km
from orbatt.errors import ScenarioError
from orbatt.torques import EnvironmentTorques

INERTIA = [0.03, 0.04, 0.05]  # kg m2


def _body():
    return orbatt.RigidBody(INERTIA * u.kg * u.m**2)


def test_the_kind_is_described_once():
    k = kinds.BY_CODE[km.CONSTANT_TORQUE]
    assert k.name == "constant" and not (k.orbit or k.velocity or k.table or k.extended or k.conservative)
    assert km.KIND_DESCRIPTIONS[km.CONSTANT_TORQUE] == k.description
    assert km.CONSTANT_TORQUE not in km.ORBIT_TERMS | km.TABLE_TERMS | km.EXTENDED_KINDS
    # the sets the builder and the loops read, as they were written by hand before the descriptors
    assert km.ORBIT_TERMS == {km.GRAVITY_GRADIENT, km.DRAG, km.SRP, km.MAGNETIC, km.BDOT_CONTROL, km.MOMENTUM_DUMP,
                              km.MAGNETORQUERS, km.VECTOR_SENSOR}
    assert km.VELOCITY_TERMS == {km.DRAG, km.PD_CONTROL}
    assert km.TABLE_TERMS == {km.DRAG, km.SRP, km.MAGNETIC, km.BDOT_CONTROL, km.MOMENTUM_DUMP, km.MAGNETORQUERS,
                              km.VECTOR_SENSOR}
    assert km.EXTENDED_KINDS == {km.WHEELS, km.PD_CONTROL, km.BDOT_CONTROL, km.MOMENTUM_DUMP, km.MODES, km.MAGNETORQUERS,
                                 km.NAVIGATION, km.VECTOR_SENSOR}
    assert orbatt.torques.TERM_NAMES[km.CONSTANT_TORQUE] == "constant"


def test_spin_up_about_a_principal_axis_is_exact():
    """From rest, a torque along principal axis 3 turns the body about it by
    ``theta = tau t^2 / (2 I3)``."""
    tau = 1e-6  # N m
    pot = EnvironmentTorques(None, None, gravity_gradient=False, constant_torque=[0.0, 0.0, tau] * u.N * u.m)
    body = _body()
    st = orbatt.State.from_omega(body, [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0] * u.rad / u.s)
    t = np.linspace(0.0, 600.0, 61)
    tr = orbatt.propagate(body, st, pot, t, rtol=1e-12, atol=1e-12)
    theta = tau * t**2 / (2 * INERTIA[2])
    exact = np.stack([np.cos(theta / 2), 0 * t, 0 * t, np.sin(theta / 2)], axis=-1)
    assert np.abs(tr.q - exact).max() < 1e-10
    assert tr.stats["steps"] < 2000


def test_agrees_with_an_independent_newton_euler_model():
    """A tumbling body under a constant torque on all axes: Euler's equations with the
    quaternion kinematics (scipy, written here), against the canonical (q, Q) run."""
    tau = np.array([2e-7, -1e-7, 3e-7])  # N m
    w0 = np.array([0.05, -0.03, 0.08])    # rad/s
    q0 = np.array([0.9, 0.1, -0.3, 0.2])
    q0 /= np.linalg.norm(q0)
    body = _body()
    I = np.array(INERTIA)

    def f(t, y):
        q, w = y[:4], y[4:]
        qd = 0.5 * np.r_[-q[1:] @ w, q[0] * w + np.cross(q[1:], w)]  # q (0, w), written out
        wd = (tau - np.cross(w, I * w)) / I
        return np.r_[qd, wd]

    t = np.linspace(0.0, 300.0, 31)
    ref = solve_ivp(f, (0, 300.0), np.r_[q0, w0], method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t)
    pot = EnvironmentTorques(None, None, gravity_gradient=False, constant_torque=tau * u.N * u.m)
    tr = orbatt.propagate(body, orbatt.State.from_omega(body, q0, w0 * u.rad / u.s), pot, t, rtol=1e-12,
                          atol=1e-12)
    qref = ref.y[:4].T
    sign = np.sign(np.sum(qref * tr.q, axis=1))[:, None]
    assert np.abs(tr.q - sign * qref).max() < 1e-9
    q, Q = tr.q, tr.Q  # omega = I^-1 g, g = 1/2 Im(q~ Q) (docs/design.md §2), written out
    g = 0.5 * (q[:, :1] * Q[:, 1:] - Q[:, :1] * q[:, 1:] - np.cross(q[:, 1:], Q[:, 1:]))
    assert np.abs(g / body.inertia_value - ref.y[4:].T).max() < 1e-10
    assert np.abs(np.linalg.norm(tr.q, axis=1) - 1).max() < 1e-11  # DOP853 at rtol 1e-12: integration error only
    assert np.abs(np.sum(tr.q * tr.Q, axis=1)).max() < 1e-11 * np.abs(tr.Q).max()


SCENARIO = """
name = "constant-torque"
[body]
inertia = ["0.03 kg m2", "0.04 kg m2", "0.05 kg m2"]
[initial]
q = [1.0, 0.0, 0.0, 0.0]
omega = ["0.01 rad/s", "0 rad/s", "0.02 rad/s"]
[potential]
kind = "{kind}"
{orbit}
[torques]
constant = ["1e-7 N m", "0 N m", "-2e-7 N m"]
[integration]
rtol = 1e-11
atol = 1e-11
t_end = "600 s"
output_step = "60 s"
"""
ORBIT = """[orbit]
provider = "kepler"
central_body = "earth"
a = "7000 km"
e = 0.001
i = "50 deg"
raan = "0 deg"
argp = "0 deg"
true_anomaly = "0 deg"
"""


@pytest.mark.parametrize("kind", ["torque-free", "gravity-gradient"])
def test_scenario_key_and_dataset_variable(kind, tmp_path):
    f = tmp_path / "ct.toml"
    f.write_text(SCENARIO.format(kind=kind, orbit=ORBIT if kind == "gravity-gradient" else ""))
    ds = orbatt.load_scenario(f).run()
    tc = ds["torque_constant"]
    assert tc.attrs["units"] == "N m"
    np.testing.assert_allclose(tc.values, np.broadcast_to([1e-7, 0.0, -2e-7], tc.shape), rtol=0, atol=1e-17)  # -1/2 Im(q~ G) of G = -2 q (0, tau)
    names = ["constant"] if kind == "torque-free" else ["gravity_gradient", "constant"]
    total = sum(ds[f"torque_{n}"].values for n in names)
    np.testing.assert_allclose(ds["torque"].values, total, rtol=0, atol=1e-20)
    # the same body without the torque follows another path: the term acts
    f2 = tmp_path / "free.toml"
    f2.write_text(SCENARIO.format(kind=kind, orbit=ORBIT if kind == "gravity-gradient" else "")
                  .replace('constant = ["1e-7 N m", "0 N m", "-2e-7 N m"]', 'constant = ["0 N m", "0 N m", "0 N m"]'))
    ds0 = orbatt.load_scenario(f2).run()
    assert np.abs(ds["q"].values[-1] - ds0["q"].values[-1]).max() > 1e-4


@pytest.mark.parametrize("text, key", [
    ('constant = ["1 N m", "0 N m"]', "[torques] constant"),
    ('constant = ["1 kg", "0 N m", "0 N m"]', "[torques] constant"),
    ('constant = ["1 N m", "0 N m", "0 N m"]\ndrag = true', "[torques]"),
])
def test_bad_constant_torque_names_the_key(text, key, tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(SCENARIO.format(kind="torque-free", orbit="").replace(
        'constant = ["1e-7 N m", "0 N m", "-2e-7 N m"]', text))
    with pytest.raises(ScenarioError, match=key.replace("[", r"\[").replace("]", r"\]")):
        orbatt.load_scenario(f)


def test_heavy_top_refuses_it(tmp_path):
    f = tmp_path / "ht.toml"
    f.write_text(SCENARIO.format(kind="heavy-top", orbit="").replace("[torques]", "[potential.extra]\n[torques]"))
    with pytest.raises(ScenarioError):
        orbatt.load_scenario(f)

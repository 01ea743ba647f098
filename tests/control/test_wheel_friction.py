"""Reaction-wheel friction (issue 32, item 5): Coulomb (smoothed over ``friction_width``) and
viscous friction between rotor and body, an internal torque: the total angular momentum is
conserved, the kinetic energy falls, and a rotor's relative speed decays as the model says."""
from __future__ import annotations

import math

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import canonical as cn
from orbatt.errors import InputError, ScenarioError
from orbatt.scenario import parse
from orbatt.shipped import shipped_file


def _free(coulomb=None, viscous=None, speed_rpm=3000.0, t_end=600.0):
    wheel = orbatt.ReactionWheel([0.0, 0.0, 1.0], 4e-4 * u.kg * u.m**2, speed_rpm * orbatt.rpm,
                                 friction_coulomb=None if coulomb is None else coulomb * u.N * u.m,
                                 friction_viscous=None if viscous is None else viscous * u.N * u.m * u.s)
    body = orbatt.RigidBody([1.8, 2.2, 1.2] * u.kg * u.m**2, wheels=[wheel])
    state = orbatt.State.from_omega(body, [1.0, 0.0, 0.0, 0.0], np.radians([0.5, -0.3, 0.2]) * u.rad / u.s)
    t = np.linspace(0.0, t_end, 121)
    tr = orbatt.propagate(body, state, orbatt.TorqueFree(), t, rtol=1e-11, atol=1e-12)
    return orbatt.to_dataset(tr), tr


def test_friction_conserves_the_total_momentum_and_dissipates():
    ds, tr = _free(coulomb=2e-4, viscous=1e-6)
    G = np.asarray(ds["G"].values)
    assert np.abs(G - G[0]).max() < 1e-11 * np.linalg.norm(G[0])  # internal: the space momentum stays
    T = np.asarray(ds["kinetic_energy"].values)
    assert np.all(np.diff(T) <= 1e-12 * T[0]) and T[-1] < 0.9 * T[0]
    speed = np.asarray(ds["wheel_speed"].values)[:, 0]
    assert abs(speed[-1]) < 0.6 * abs(speed[0])


def test_viscous_decay_rate():
    """Viscous friction alone, the body nearly inertial against the light rotor: the relative
    speed decays as exp(-b t / I_eff), I_eff = Iw (1 - Iw / J3) for the spin axis."""
    b, iw, j3 = 2e-6, 4e-4, 1.2
    ds, _ = _free(viscous=b, t_end=600.0)
    speed = np.asarray(ds["wheel_speed"].values)[:, 0]
    t = np.linspace(0.0, 600.0, 121)
    rate = -np.polyfit(t, np.log(speed), 1)[0]
    expected = b * (1.0 / iw + 1.0 / (j3 - iw))  # the rotor and the body (less the rotor) share the torque
    assert rate == pytest.approx(expected, rel=2e-3)


def test_without_friction_nothing_changes():
    a, tra = _free()
    wheel = orbatt.ReactionWheel([0.0, 0.0, 1.0], 4e-4 * u.kg * u.m**2, 3000.0 * orbatt.rpm)
    assert wheel.friction_coulomb is None and "friction_coulomb_N_m" not in wheel.describe()
    speed = np.asarray(a["wheel_speed"].values)[:, 0]
    G = np.asarray(a["G"].values)
    assert np.abs(G - G[0]).max() < 1e-11 * np.linalg.norm(G[0])
    assert np.ptp(speed) < 1e-3 * abs(speed[0])  # no dissipation: only the body's nutation moves it


def test_friction_keys_are_checked():
    with pytest.raises(InputError, match="friction_coulomb"):
        orbatt.ReactionWheel([0, 0, 1], 4e-4 * u.kg * u.m**2, friction_coulomb=-1 * u.N * u.m)
    with pytest.raises(InputError, match="friction_width"):
        orbatt.ReactionWheel([0, 0, 1], 4e-4 * u.kg * u.m**2, friction_width=1 * u.rad / u.s)
    text = shipped_file("lvlh-hold-wheels").read_text()
    good = text.replace('max_speed = "6000 rpm"\n', 'max_speed = "6000 rpm"\nfriction_coulomb = "1e-5 N m"\n'
                        'friction_viscous = "1e-8 N m s"\n', 1)
    spec = parse(good, "f.toml")
    assert spec.control["wheels"][0]["friction_coulomb"] == pytest.approx(1e-5)
    assert spec.control["wheels"][1]["friction_coulomb"] is None
    with pytest.raises(ScenarioError, match=r"\[\[body.wheels\]\] 1 friction_viscous"):
        parse(good.replace('"1e-8 N m s"', '"1e-8 N m"'), "f.toml")

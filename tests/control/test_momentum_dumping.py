"""Momentum management (issue 32, item 5): magnetorquers dump the wheels' momentum with the
cross-product law ``m = k (h x B) / |B|^2`` (``[control] dump_gain``, ``dump_max_dipole`` on the
PD law with ``actuator = "wheels"``). Under a constant body torque that saturates the wheels of
``lvlh-hold-wheels`` within two orbits, dumping keeps their momentum bounded (IGRF and the dipole
field); the dipole is normal to B and ``m x B = -k h_perp`` where it is not clipped; with a
``period`` the dipole is held between ticks while the torque follows the field."""
from __future__ import annotations

import re

import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import quaternion as qt
from orbatt.core import control as kc
from orbatt.dataset.timeaxis import elapsed_values
from orbatt.errors import InputError, ScenarioError
from orbatt.scenario import parse
from orbatt.shipped import shipped_file

GAIN, MMAX = 5e-3, 3.0  # 1/s, A m^2
MAX_SPEED = 6000 * 2 * np.pi / 60  # rad/s, the wheels' limit in lvlh-hold-wheels
#: a constant body torque (N m): the body holds LVLH, so its orbit-normal part piles up in the wheels
CONSTANT = '["2e-5 N m", "1e-5 N m", "-3e-5 N m"]'


def _scenario(dump=True, field="igrf", extra="", t_end="3 orbits", output_step="60 s", torques=""):
    """``lvlh-hold-wheels`` with an epoch, the constant torque (and ``torques``), dumping (or
    not) with ``field``, ``extra`` [control] keys."""
    text = shipped_file("lvlh-hold-wheels").read_text()
    keys = (f'dump_gain = "{GAIN} / s"\ndump_max_dipole = "{MMAX} A m2"\n' if dump else "") + extra + "\n"
    text = text.replace("[control]\n", "[control]\n" + keys, 1)
    text = text.replace('true_anomaly = "0 deg"\n', 'true_anomaly = "0 deg"\nepoch = "2025-06-01T00:00:00"\n')
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end}"', text)
    text = re.sub(r'output_step = "[^"]*"', f'output_step = "{output_step}"', text)
    text += f"\n[torques]\nconstant = {CONSTANT}\n{torques}\n"
    if field is not None:
        text += f'\n[environment]\nmagnetic_field = "{field}"\n'
    return text


def _run(text):
    return orbatt.Scenario(parse(text, "dumping.toml")).run()


@pytest.fixture(scope="module")
def undumped():
    return _run(_scenario(dump=False, field=None))


@pytest.mark.parametrize("field", ["igrf", "dipole"])
def test_dumping_bounds_the_wheel_momentum(undumped, field):
    """Three orbits under 3e-5 N m about the orbit normal: without dumping the wheels reach
    max_speed (the first after 1.9 orbits); with dumping (5e-3 /s, 3 A m^2) every wheel stays
    below 1500 rpm and the wheels' total momentum over the last orbit below 0.04 N m s
    (measured 0.030 with IGRF, 0.031 with the dipole field; 0.42 without)."""
    sp0 = np.abs(undumped["wheel_speed"].values)
    assert sp0.max() >= MAX_SPEED * (1 - 1e-9)
    h0 = undumped["wheel_momentum"].values
    ds = _run(_scenario(field=field))
    sp = np.abs(ds["wheel_speed"].values)
    h = ds["wheel_momentum"].values
    last = slice(2 * len(h) // 3, None)
    assert sp[:, :2].max() < 1500 * 2 * np.pi / 60  # the z wheel starts at its 2000 rpm bias, dumped too
    assert sp[last].max() < 1000 * 2 * np.pi / 60
    assert np.linalg.norm(h[last], axis=1).max() < 0.04 < 0.3 < np.linalg.norm(h0[last], axis=1).max()
    m = ds["dipole_control"].values
    assert np.abs(m).max() <= MMAX * (1 + 1e-12)
    assert "dipole_control" not in undumped


def test_the_torque_is_minus_k_h_perp_normal_to_b():
    """A small residual dipole makes the Dataset carry the field the kernel read: in body axes,
    m . B = 0 and m x B = -k h_perp (h_perp the wheels' momentum normal to B) at every output
    where no axis of m is clipped (to 1e-9 of k |h|), and m x B is normal to B at all of them."""
    ds = _run(_scenario(t_end="1 orbits", output_step="20 s",
                        torques='residual_dipole = ["0.01 A m2", "0 A m2", "0 A m2"]'))
    q = ds["q"].values
    b_s = ds["magnetic_field"].values  # T, inertial
    b = qt.rotate_inv(q, b_s)
    m = ds["dipole_control"].values  # A m^2
    h = ds["wheel_momentum"].values @ ds["wheel_axis"].values  # N m s, body axes
    tau = np.cross(m, b)
    bn = np.linalg.norm(b, axis=1)
    hn = np.linalg.norm(h, axis=1)
    np.testing.assert_array_less(np.abs(np.sum(tau * b, axis=1)), 1e-12 * np.linalg.norm(tau, axis=1) * bn + 1e-300)
    free = np.all(np.abs(m) < MMAX * (1 - 1e-12), axis=1)
    assert 10 < free.sum() < free.size  # clipped at first (the 2000 rpm bias), free later
    h_perp = h - b * (np.sum(h * b, axis=1) / bn**2)[:, None]
    np.testing.assert_array_less(np.abs(np.sum(m * b, axis=1))[free], 1e-9 * (np.linalg.norm(m, axis=1) * bn)[free])
    err = np.linalg.norm(tau + GAIN * h_perp, axis=1)
    np.testing.assert_array_less(err[free], 1e-9 * GAIN * hn[free])


def test_the_kernel_law():
    """The kernel's dipole for random h, B: m x B = -k h_perp and m . B = 0 unclipped; each axis
    within the limit clipped; none in a zero field."""
    rng = np.random.default_rng(3)
    p = kc.dump_params(0.02, 1e9)
    pc = kc.dump_params(0.02, 1e-3)
    for _ in range(20):
        h, b = rng.normal(size=3), rng.normal(size=3) * 3e-5
        m = np.array(kc.dump_dipole(tuple(h), tuple(b), p, 0))
        h_perp = h - b * (h @ b) / (b @ b)
        np.testing.assert_allclose(np.cross(m, b), -0.02 * h_perp, rtol=0, atol=1e-12 * np.linalg.norm(h))
        assert abs(m @ b) <= 1e-12 * np.linalg.norm(m) * np.linalg.norm(b)
        mc = np.array(kc.dump_dipole(tuple(h), tuple(b), pc, 0))
        np.testing.assert_array_equal(mc, np.clip(m, -1e-3, 1e-3))
    assert kc.dump_dipole((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), p, 0) == (0.0, 0.0, 0.0)


def test_the_held_dipole_is_constant_between_ticks():
    """At 0.1 Hz the dipole changes only at the ticks (outputs every 2.5 s: four per interval
    share it), while the torque m x B(t) turns with the field between them."""
    ds = _run(_scenario(extra='period = "10 s"', t_end="600 s", output_step="2.5 s"))
    m = ds["dipole_control"].values
    t = elapsed_values(ds)
    k = np.floor(t / 10.0 + 1e-9)
    for kk in np.unique(k)[:-1]:
        block = m[k == kk]
        np.testing.assert_array_equal(block, np.broadcast_to(block[0], block.shape))
    assert np.abs(np.diff(m, axis=0)).max() > 0
    u_w = ds["wheel_torque"].values
    tau_mag = ds["torque_control"].values + u_w @ ds["wheel_axis"].values  # less the wheels' reaction -A u
    block = tau_mag[k == 3]
    assert np.abs(np.diff(block, axis=0)).max() > 0


def test_keys_are_checked():
    with pytest.raises(ScenarioError, match=r"\[control\] dump_max_dipole: .*needs the magnetorquers"):
        parse(_scenario(dump=False, extra='dump_gain = "1e-3 / s"'), "bad.toml")
    with pytest.raises(ScenarioError, match=r"\[control\] dump_gain"):
        parse(_scenario(dump=False, extra='dump_gain = "-1e-3 / s"\ndump_max_dipole = "1 A m2"'), "bad.toml")
    with pytest.raises(ScenarioError, match=r"\[environment\] magnetic_field: missing"):
        parse(_scenario(field=None), "bad.toml")
    ideal = _scenario().replace('actuator = "wheels"', 'actuator = "ideal"')
    with pytest.raises(ScenarioError, match=r"\[control\] dump_gain: .*actuator = 'wheels'"):
        parse(ideal, "bad.toml")
    with pytest.raises(InputError, match="dump_max_dipole: only read with dump_gain"):
        orbatt.PDControl(kp=1 * u.N * u.m, kd=1 * u.N * u.m * u.s, actuator="wheels", dump_max_dipole=1 * u.A * u.m**2)
    sc = parse(_scenario(), "ok.toml")
    assert sc.control["control"]["dump_gain"] == GAIN and sc.control["magnetic_field"] == "igrf"

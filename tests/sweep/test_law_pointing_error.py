"""The sweep's pointing error for a PD law that points an axis (issue 32 item 3): its own error,
computed by the kernel along the orbit and the law's table (the Sun's position, a ground
target), checked against the angle recomputed from the single run's Dataset (the Sun's direction
in body axes; a ground point placed by astropy)."""
from __future__ import annotations

import re

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import GCRS, ITRS, EarthLocation
from astropy.time import Time

import orbatt
from orbatt.pointing import index_value
from orbatt.shipped import shipped_file

pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")

EPOCH = "2026-03-20T12:00:00Z"


def _text(target):
    text = shipped_file("cubesat-slew-wheels").read_text()
    text = re.sub(r'target = "inertial"\ntarget_q = \[[^\]]*\][^\n]*\n', target, text)
    text = text.replace("[orbit]\n", f'[orbit]\nepoch = "{EPOCH}"\n', 1)
    text = re.sub(r't_end = "[^"]*"', 't_end = "200 s"', text)
    text = re.sub(r'output_step = "[^"]*"', 'output_step = "5 s"', text)
    return text + '''
[sweep]
outputs = ["trajectory", "ape", "settling_time", "slew_time"]
settling_angle = "2 deg"

[sweep.parameters]
omega1 = { values = ["0.2 deg/s", "-0.1 deg/s"] }
'''


def _angle(a, b):
    c = np.sum(a * b, axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    s = np.linalg.norm(np.cross(a, b), axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.arctan2(s, c)


def _run(tmp_path, target):
    p = tmp_path / "point.toml"
    p.write_text(_text(target))
    sw = orbatt.load_sweep(p)
    return sw, sw.compute()


def test_sun_pointing_error_is_the_angle_to_the_sun(tmp_path):
    """Body axis 3 pointed at the Sun: the sweep's ape is the quantile of the angle between the
    axis and the Dataset's Sun direction (inertial, turned into body axes), and the law settles (settling_time and
    slew_time finite and equal)."""
    sw, ds = _run(tmp_path, 'target = "sun"\ntarget_axis = [0.0, 0.0, 1.0]\n')
    t = np.arange(0.0, 201.0, 5.0)
    for k in range(2):
        (tmp_path / "case.toml").write_text(sw.case_text(k))
        one = orbatt.load_scenario(tmp_path / "case.toml").run()
        s = orbatt.quaternion.rotate_inv(one["q"].values, one["sun_direction"].values)  # (inertial) to body axes
        err = _angle(s, np.array([0.0, 0.0, 1.0]))
        assert ds["ape"].values[k] == pytest.approx(index_value("ape", t, err, 0.9973), rel=1e-9, abs=1e-12)
        assert np.isfinite(ds["settling_time"].values[k])
        assert ds["slew_time"].values[k] == ds["settling_time"].values[k]
        assert err[-1] < np.radians(2.0)


def test_ground_target_error_is_the_angle_to_the_line_of_sight(tmp_path):
    """Body axis 3 on a ground point: the error recomputed from the Dataset's attitude and
    position with astropy's GCRS position of the site (within 1e-4 deg of the kernel's)."""
    target = 'target = "ground"\ntarget_location = ["10 deg", "20 deg", "0 m"]\ntarget_axis = [0.0, 0.0, 1.0]\n'
    sw, ds = _run(tmp_path, target)
    (tmp_path / "case.toml").write_text(sw.case_text(0))
    one = orbatt.load_scenario(tmp_path / "case.toml").run()
    t = np.arange(0.0, 201.0, 5.0)
    times = Time(EPOCH) + t * u.s
    site = EarthLocation.from_geodetic(20 * u.deg, 10 * u.deg, 0 * u.m)
    g = ITRS(site.get_itrs(obstime=times).cartesian, obstime=times).transform_to(GCRS(obstime=times))
    los = g.cartesian.xyz.to_value(u.km).T - one["position"].values / 1e3 ** (one["position"].attrs["units"] == "m")
    q = one["q"].values
    axis = orbatt.quaternion.rotate(q, np.array([0.0, 0.0, 1.0]))
    err = _angle(los, axis)
    want = index_value("ape", t, err, 0.9973)
    assert abs(ds["ape"].values[0] - want) < np.radians(1e-4)
    assert np.isfinite(ds["settling_time"].values[0])

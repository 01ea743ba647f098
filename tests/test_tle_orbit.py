"""Orbits from a TLE (docs/design.md §11): SGP4 + astropy TEME -> GCRS, sampled and interpolated;
checked against sgp4 and astropy called directly, the orbital frame of the SGP4 state, the
gravity-gradient kernel, and bad TLEs refused naming ``tle``."""
import subprocess
import sys

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import GCRS, TEME, CartesianDifferential, CartesianRepresentation
from astropy.time import Time
from sgp4.api import Satrec

import orbatt
from orbatt import RigidBody
from orbatt import quaternion as qt
from orbatt.core import potentials as kp
from orbatt.errors import InputError
from orbatt.orbits import GM_EARTH, TleOrbit, frame_quaternion
from orbatt.orbits.tle import parse_tle, tle_checksum
from orbatt.potentials import GravityGradient

L1 = "1 25544U 98067A   19343.69339541  .00001764  00000-0  38792-4 0  9991"
L2 = "2 25544  51.6439 211.2001 0007417  17.6667  85.6398 15.50103472202482"
#: a fictitious low, high-drag orbit (bstar 0.39, 16.1 rev/day): SGP4 reports it decayed
#: (error 6) 0.306 days after its epoch
DECAY = ("1 25544U 98067A   19343.69339541  .00001764  00000-0  38792-1 0  9998",
         "2 25544  51.6439 211.2001 0007417  17.6667  85.6398 16.10103472202489")


def direct_gcrs(line1, line2, epoch, t):
    """sgp4 and astropy called directly: GCRS position (km) and velocity (km/s) at ``t`` s
    after ``epoch``."""
    sat = Satrec.twoline2rv(line1, line2)
    tle_epoch = Time(sat.jdsatepoch, sat.jdsatepochF, format="jd", scale="utc")
    tsince = (epoch - tle_epoch).to_value(u.s) + t
    err, r, v = sat.sgp4_array(np.full(t.shape, sat.jdsatepoch), sat.jdsatepochF + tsince / 86400.0)
    assert not err.any()
    obstime = epoch + t * u.s
    teme = TEME(CartesianRepresentation(r.T * u.km, differentials=CartesianDifferential(v.T * u.km / u.s)),
                obstime=obstime)
    g = teme.transform_to(GCRS(obstime=obstime)).cartesian
    return g.xyz.to_value(u.km).T, g.differentials["s"].d_xyz.to_value(u.km / u.s).T


@pytest.fixture(scope="module")
def iss():
    return TleOrbit([L1, L2], 2 * u.d)


def test_positions_match_sgp4_and_astropy_directly(iss):
    rng = np.random.default_rng(13)
    t = np.sort(rng.uniform(0.0, iss.t_end, 150))  # between samples, in general
    pos, vel = iss.state(t)
    ref_pos, ref_vel = direct_gcrs(L1, L2, iss.epoch, t)
    assert np.abs(pos - ref_pos).max() < 1e-3  # km: < 1 m (the docstring states 13 cm at N = 128)
    assert np.abs(vel - ref_vel).max() < 1e-4  # km/s
    # at the samples the interpolant is the SGP4 state itself
    ts = iss.samples[5:40, 0]
    p_s, v_s = direct_gcrs(L1, L2, iss.epoch, ts)
    assert np.abs(iss.state(ts)[0] - p_s).max() < 1e-9


def test_interpolation_error_as_stated(iss):
    tab = iss.samples
    quarter = (0.75 * tab[:-1, 0] + 0.25 * tab[1:, 0])[:300]  # (the error vanishes at midpoints)
    err = np.abs(iss.state(quarter)[0] - iss.sgp4_gcrs(quarter)[0]).max()
    assert 1e-5 < err < 2e-4, err  # km; TleOrbit's docstring: 1.3e-4 km at N = 128
    coarse = TleOrbit([L1, L2], 3 * u.h, samples_per_orbit=32)
    tc = coarse.samples
    qc = 0.75 * tc[:-1, 0] + 0.25 * tc[1:, 0]
    err32 = np.abs(coarse.state(qc)[0] - coarse.sgp4_gcrs(qc)[0]).max()
    assert 2 * err < err32 < 1e-3  # sparser samples, larger error (~ h), still below 1 m


def test_orbital_frame_is_that_of_the_sgp4_state(iss):
    t = np.linspace(0.0, iss.t_end, 120)
    ref_pos, ref_vel = direct_gcrs(L1, L2, iss.epoch, t)
    p = iss.orbital_quaternion(t)
    p_ref = frame_quaternion(ref_pos, ref_vel)
    ang = 2 * np.arccos(np.clip(np.abs(np.sum(p * p_ref, axis=-1)), 0, 1))
    assert ang.max() < 1e-5  # rad (SGP4's velocity is not exactly d/dt of its position: ~1e-5 km/s)
    # o1 radial outwards, o3 along r x v
    o1 = qt.rotate(p, np.array([1.0, 0, 0]))
    assert np.allclose(o1, ref_pos / np.linalg.norm(ref_pos, axis=-1)[:, None], atol=1e-9)


def test_epoch_defaults_to_the_tle_and_may_start_later(iss):
    assert abs((iss.epoch - iss.tle_epoch).to_value(u.s)) == 0
    assert iss.tle_epoch.isot.startswith("2019-12-09T16:38:29")
    later = TleOrbit([L1, L2], 3 * u.h, epoch="2019-12-09T17:38:29.363")
    t = np.linspace(0, 7200, 50)
    assert np.abs(later.state(t)[0] - iss.state(t + later.offset)[0]).max() < 5e-4  # two interpolants
    assert abs(later.offset - 3600.0) < 1e-3
    assert abs(iss.period_value - 86400 / 15.50103472) < 1e-3


def test_sampled_before_the_epoch_with_t_start(iss):
    """``t_start < 0`` samples before the epoch (SGP4 propagates backwards too): the states
    there match SGP4 + astropy; t = 0 stays a sample and the samples inside [0, t_end) are
    those of the orbit without a margin; a positive t_start is refused naming it."""
    wide = TleOrbit([L1, L2], 3 * u.h, t_start=-1 * u.h)
    assert wide.time_span == (-3600.0, 10800.0) and wide.describe()["t_start_s"] == -3600.0
    t = np.linspace(-3600.0, 10800.0, 97)
    pos, vel = wide.state(t)
    ref_pos, ref_vel = direct_gcrs(L1, L2, wide.epoch, t)
    assert np.abs(pos - ref_pos).max() < 1e-3 and np.abs(vel - ref_vel).max() < 1e-4
    ts = wide.samples[:, 0]
    assert np.all(np.diff(ts) > 0) and 0.0 in ts
    h = np.diff(ts)
    assert h.max() < 1.6 * h.min()  # no sliver at either end (steps equal in E, N = 128)
    inner = iss.samples[:, 0][iss.samples[:, 0] < 10000.0]
    np.testing.assert_array_equal(ts[(ts >= 0.0) & (ts < 10000.0)], inner)
    with pytest.raises(InputError, match="t_start: .* must be one time <= 0"):
        TleOrbit([L1, L2], 3 * u.h, t_start=1 * u.s)


def test_plugs_into_the_gravity_gradient_kernel(iss):
    gg = GravityGradient(iss)
    assert gg.kind == kp.GRAVITY_GRADIENT_SAMPLED and gg.table is iss.samples
    body = RigidBody([12, 110, 115] * u.kg * u.m**2)
    rng = np.random.default_rng(3)
    q = qt.normalize(rng.normal(size=(20, 4)))
    t = rng.uniform(0, iss.t_end, 20)
    _, _, tau = gg.evaluate(body, t, q)
    pos, _ = direct_gcrs(L1, L2, iss.epoch, t)
    r = np.linalg.norm(pos, axis=-1)
    xb = qt.rotate(qt.conj(q), pos / r[:, None])
    inertia = body.inertia_value
    classical = 3 * GM_EARTH / r[:, None] ** 3 * np.cross(xb, inertia * xb)
    assert np.allclose(tau, classical, rtol=1e-6, atol=1e-6 * np.abs(classical).max())


def test_parse_tle_accepts_a_name_line_and_text():
    title, a, b = parse_tle(["ISS (ZARYA)", L1, L2])
    assert (title, a, b) == ("ISS (ZARYA)", L1, L2)
    assert parse_tle(f"{L1}\n{L2}\n")[1:] == (L1, L2)
    assert tle_checksum(L1) == 1 and tle_checksum(L2) == 2


@pytest.mark.parametrize("lines, match", [
    ([L1[:-1] + "5", L2], "line 1 checksum"),
    ([L1, L2[:-2] + "2"], "line 2 has 68 characters"),
    ([L2, L1], "line 1 must start with '1 '"),
    ([L1], "expected 2 lines"),
    ([L1, "2 25545" + L2[7:-1] + "3"], "catalogue numbers differ"),
])
def test_bad_tles_are_refused_naming_tle(lines, match):
    with pytest.raises(InputError, match=f"tle: .*{match}"):
        TleOrbit(lines, 1 * u.h)


def test_decayed_orbit_is_refused_naming_tle():
    TleOrbit(list(DECAY), 6 * u.h)  # fine before it decays
    with pytest.raises(InputError, match="tle: SGP4 fails .* decayed"):
        TleOrbit(list(DECAY), 1 * u.d)


SCEN = """
name = "tle-test"
[body]
inertia = ["12 kg m2", "110 kg m2", "115 kg m2"]
[initial]
frame = "orbital"
euler_313 = ["0 deg", "3 deg", "5 deg"]
omega = ["0 rad/s", "0 rad/s", "0 rad/s"]
[potential]
kind = "gravity-gradient"
[orbit]
provider = "tle"
{orbit}
[integration]
t_end = "{t_end}"
output_step = "60 s"
"""


def _run_cli(tmp_path, orbit, t_end="0.2 orbits"):
    path = tmp_path / "s.toml"
    path.write_text(SCEN.format(orbit=orbit, t_end=t_end))
    return subprocess.run([sys.executable, "-m", "orbatt.cli", "run", str(path), "-o", str(tmp_path / "o.nc")],
                          capture_output=True, text=True)


@pytest.mark.parametrize("orbit, t_end, match", [
    (f'tle = ["{L1[:-1]}0", "{L2}"]', "0.2 orbits", "checksum"),
    (f'tle = ["{L1}", "{L2[:-3]}"]', "0.2 orbits", "66 characters"),
    (f'tle = ["{L2}", "{L1}"]', "0.2 orbits", "must start with"),
    (f'tle = ["{DECAY[0]}", "{DECAY[1]}"]', "1 d", "decayed"),
])
def test_cli_exits_2_naming_tle(tmp_path, orbit, t_end, match):
    res = _run_cli(tmp_path, orbit, t_end)
    assert res.returncode == 2, res.stderr
    assert "tle" in res.stderr and match in res.stderr


def test_scenario_with_a_tle_file_relative_to_the_scenario(tmp_path):
    (tmp_path / "iss.tle").write_text(f"ISS (ZARYA)\n{L1}\n{L2}\n")
    path = tmp_path / "s.toml"
    path.write_text(SCEN.format(orbit='tle_file = "iss.tle"\nepoch = "2019-12-09T17:00:00"', t_end="0.1 orbits"))
    sc = orbatt.load_scenario(path)
    assert isinstance(sc.orbit, TleOrbit) and sc.orbit.title == "ISS (ZARYA)"
    ds = sc.run()
    assert ds.attrs["epoch"].startswith("2019-12-09T17:00:00")
    ref_pos, _ = direct_gcrs(L1, L2, Time("2019-12-09T17:00:00", scale="utc"), ds["elapsed"].values)
    assert np.abs(ds["position"].values - ref_pos).max() < 1e-3
    path.write_text(SCEN.format(orbit='tle_file = "missing.tle"', t_end="0.1 orbits"))
    with pytest.raises(InputError, match="tle_file: cannot read"):
        orbatt.load_scenario(path)
    path.write_text(SCEN.format(orbit=f'tle = ["{L1}", "{L2}"]\na = "7000 km"', t_end="0.1 orbits"))
    with pytest.raises(InputError, match=r"\[orbit\] a: not used by provider = 'tle'"):
        orbatt.load_scenario(path)

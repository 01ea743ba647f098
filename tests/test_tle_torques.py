"""TLE orbits with the environment torques and control laws (issue 26, item 2): scenario
files with drag, SRP, a residual dipole or B-dot on a TLE run without ``[orbit] epoch`` (the
TLE's own dates the environment); each torque of the Dataset is recomputed here from the
Dataset's own density, field, Sun direction, velocity and attitude, and against the same
environment built in Python on a TLE orbit sampled over the run only (the margin cut)."""
import astropy.units as u
import numpy as np
import pytest

import orbatt
from orbatt import quaternion as qt
from orbatt.control import BDotControl
from orbatt.environment import sun as esun
from orbatt.environment.atmosphere import PiecewiseExponentialAtmosphere
from orbatt.environment.frames import EARTH_ROTATION_RATE
from orbatt.environment.magnetic import DipoleField, IGRFField
from orbatt.errors import InputError
from orbatt.orbits import TleOrbit
from orbatt.torques import EnvironmentTorques, Facet, sample_margin

L1 = "1 25544U 98067A   19343.69339541  .00001764  00000-0  38792-4 0  9991"
L2 = "2 25544  51.6439 211.2001 0007417  17.6667  85.6398 15.50103472202482"
TLE_EPOCH = "2019-12-09T16:38:29.363"
#: the facets of the scenario below: area (m^2), normal, position (m), C_D, specular, diffuse
FACETS = [(0.034, [1.0, 0.0, 0.0], [0.05, 0.0, 0.02], 2.2, 0.1, 0.3),
          (0.034, [0.0, -1.0, 0.0], [0.0, -0.05, 0.02], 2.2, 0.1, 0.3),
          (0.01, [0.0, 0.0, 1.0], [0.0, 0.0, 0.19], 2.2, 0.0, 0.2)]
DIPOLE = np.array([0.005, 0.0, 0.002])  # A m^2

FACET_TOML = "".join(f"""
[[body.facets]]
area = "{a} m2"
normal = {n}
position = ["{p[0]} m", "{p[1]} m", "{p[2]} m"]
drag_coefficient = {cd}
specular = {s}
diffuse = {d}
""" for a, n, p, cd, s, d in FACETS)

HEAD = f"""
name = "{{name}}"
[body]
inertia = ["0.0387 kg m2", "0.0387 kg m2", "0.0067 kg m2"]
{{facets}}
[potential]
kind = "gravity-gradient"
[orbit]
provider = "tle"
tle = ["ISS (ZARYA)", "{L1}", "{L2}"]
[integration]
rtol = 1e-10
atol = 1e-12
t_end = "{{t_end}}"
output_step = "60 s"
"""

DISTURBED = HEAD.format(name="iss-tle-torques", facets=FACET_TOML, t_end="0.5 orbits") + """
[torques]
drag = true
srp = true
residual_dipole = ["0.005 A m2", "0 A m2", "0.002 A m2"]
[environment]
atmosphere = "exponential"
magnetic_field = "dipole"
shadow = "conical"
[initial]
frame = "orbital"
euler_313 = ["10 deg", "20 deg", "30 deg"]
omega = ["0.5 deg/s", "-0.3 deg/s", "0.2 deg/s"]
"""

BDOT = HEAD.format(name="iss-tle-bdot", facets="", t_end="0.5 orbits") + """
[control]
law = "bdot"
gain = "4e4 A m2 s / T"
max_dipole = "0.2 A m2"
[environment]
magnetic_field = "igrf"
[initial]
frame = "inertial"
q = [1.0, 0.0, 0.0, 0.0]
omega = ["4 deg/s", "-3 deg/s", "3 deg/s"]
"""


def _load(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text)
    return orbatt.load_scenario(path)


def _body_vectors(q, v_inertial):
    return np.array([qt.rotate_inv(qi, vi) for qi, vi in zip(q, v_inertial)])


def _check_constraints(ds):
    """|q| = 1 and q.Q = 0 held to the integration's tolerance (rtol 1e-10; measured 1.6e-12
    and 1.5e-12 |Q|)."""
    assert np.abs(ds["q_norm_error"].values).max() < 1e-10
    Q = ds["Q"].values
    assert np.abs(ds["qQ"].values).max() < 1e-10 * np.abs(Q).max()


@pytest.fixture(scope="module")
def disturbed(tmp_path_factory):
    sc = _load(tmp_path_factory.mktemp("tle"), DISTURBED)
    return sc, sc.run()


def test_tle_epoch_dates_the_environment_and_the_orbit_covers_the_margin(disturbed):
    sc, ds = disturbed
    assert ds.attrs["epoch"].startswith(TLE_EPOCH)           # no [orbit] epoch: the TLE's
    margin = sample_margin(drag=True, srp=True, magnetic=True)
    assert margin == 60.0                                    # orbatt.environment.tables.TABLE_MARGIN
    t_end = float(ds["elapsed"].values[-1])
    assert sc.orbit.time_span == (-margin, t_end + margin)
    assert sc.potential.time_span == (0.0, t_end)
    _check_constraints(ds)


def test_drag_torque_is_r_cross_f_from_the_datasets_density_velocity_and_attitude(disturbed):
    _, ds = disturbed
    q, rho = ds["q"].values, ds["density"].values                      # kg m^-3
    r, v = ds["position"].values * 1e3, ds["velocity"].values * 1e3    # m, m/s (GCRS)
    v_rel = v - np.cross([0.0, 0.0, EARTH_ROTATION_RATE], r)           # co-rotating atmosphere
    speed = np.linalg.norm(v_rel, axis=1)
    vb = _body_vectors(q, v_rel / speed[:, None])
    ref = np.zeros_like(vb)
    for area, n, p, cd, _, _ in FACETS:
        c = np.maximum(vb @ np.array(n), 0.0)
        force = -(0.5 * rho * speed**2 * cd * area * c)[:, None] * vb  # N
        ref += np.cross(p, force)
    got = ds["torque_drag"].values                                     # N m
    assert np.abs(ref).max() > 1e-9                                    # ISS altitude: ~1e-8 N m
    # the kernel reads the density from its spline table (at the outputs, multiples of its 30 s
    # step, the samples themselves): measured 4e-12
    assert np.abs(got - ref).max() < 1e-9 * np.abs(ref).max()


def test_srp_and_magnetic_torques_from_the_datasets_fields(disturbed):
    sc, ds = disturbed
    q, t = ds["q"].values, ds["elapsed"].values
    pos = ds["position"].values
    sun = np.asarray(esun.sun_position(sc.orbit.epoch + t * u.s))      # km, GCRS
    scale = (esun.AU / np.linalg.norm(sun - pos, axis=1)) ** 2
    pressure = esun.SRP_FLUX / esun.SPEED_OF_LIGHT * scale * ds["shadow"].values
    sb = _body_vectors(q, ds["sun_direction"].values)
    ref = np.zeros_like(sb)
    for area, n, p, _, spec, diff in FACETS:
        n = np.array(n)
        c = sb @ n
        lit = c > 0
        force = -(pressure * area * c)[:, None] * ((1 - spec) * sb + 2 * (spec * c + diff / 3)[:, None] * n)
        ref += np.where(lit[:, None], np.cross(p, force), 0.0)
    got = ds["torque_srp"].values
    assert np.abs(ref).max() > 1e-9 and (ds["shadow"].values == 0).any()  # sunlit and eclipsed
    assert np.abs(got - ref).max() < 1e-9 * np.abs(ref).max()
    B = _body_vectors(q, ds["magnetic_field"].values)                  # T, body axes
    ref = np.cross(DIPOLE, B)
    assert np.abs(ds["torque_magnetic"].values - ref).max() < 1e-9 * np.abs(ref).max()  # measured 3.5e-12
    terms = sum(ds[f"torque_{k}"].values for k in ("gravity_gradient", "drag", "srp", "magnetic"))
    np.testing.assert_allclose(ds["torque"].values, terms, rtol=0, atol=1e-12 * np.abs(terms).max())


def test_python_tle_sampled_over_the_run_only_gives_the_same_torques(disturbed):
    """A TLE orbit over [0, t_end] alone (the tables' margin cut to it) against the
    scenario's, sampled an hour either side: the torques at the Dataset's (t, q) agree to
    the orbit's interpolation (the two sample grids differ near the ends: positions 7.9e-5
    km apart) and the tables' end intervals. Measured, relative to each term's largest:
    gravity gradient 1.9e-8, drag 5.9e-6 (the density's altitude gradient, 1 / 60 km),
    SRP 1.0e-12, magnetic 1.9e-8."""
    sc, ds = disturbed
    t, q = ds["elapsed"].values, ds["q"].values
    orbit = TleOrbit([L1, L2], t[-1] * u.s)
    assert orbit.time_span == (0.0, t[-1])
    env = EnvironmentTorques(orbit, t[-1] * u.s, facets=[Facet(a * u.m**2, n, p * u.m, cd, s, d)
                                                       for a, n, p, cd, s, d in FACETS],
                             drag=True, srp=True, residual_dipole=DIPOLE * u.A * u.m**2,
                             atmosphere=PiecewiseExponentialAtmosphere(), magnetic_field=DipoleField(orbit.epoch))
    tau = env.term_torques(sc.body, t, q) * 1e6                        # N m
    for k, name in enumerate(env.term_names):
        ref = ds[f"torque_{name}"].values
        assert np.abs(tau[:, k] - ref).max() < 1e-5 * np.abs(ref).max(), name
    with pytest.raises(InputError, match=r"t_end: .* outside the span .* build it with a larger t_end"):
        EnvironmentTorques(orbit, (t[-1] + 1.0) * u.s, magnetic_field=DipoleField(orbit.epoch),
                           residual_dipole=DIPOLE * u.A * u.m**2)


def test_bdot_on_a_tle_detumbles_with_m_cross_b(tmp_path):
    sc = _load(tmp_path, BDOT)
    ds = sc.run()
    _check_constraints(ds)
    assert ds.attrs["epoch"].startswith(TLE_EPOCH)
    assert sc.orbit.time_span[0] == -sample_margin(magnetic=True)
    q, t = ds["q"].values, ds["elapsed"].values
    pos = ds["position"].values
    B = _body_vectors(q, IGRFField().field(sc.orbit.epoch + t * u.s, pos))   # T, body axes
    m = ds["dipole_control"].values
    assert np.abs(m).max() <= 0.2 * (1 + 1e-12)
    ref = np.cross(m, B)
    assert np.abs(ds["torque_control"].values - ref).max() < 1e-9 * np.abs(ref).max()   # measured 2.9e-12
    # m = -gain dB_B/dt, clipped per axis: dB_B/dt = R^T dB/dt - omega x B_B, dB/dt by a
    # central difference of IGRF along the orbit (the kernel differentiates its table, pieces
    # between the orbit's samples): measured 2.4e-8 A m^2 (unsaturated here: -gain dB_B/dt < 0.13 A m^2)
    h = 1.0
    Bdot = (IGRFField().field(sc.orbit.epoch + (t + h) * u.s, sc.orbit.state(t + h)[0])
            - IGRFField().field(sc.orbit.epoch + (t - h) * u.s, sc.orbit.state(t - h)[0])) / (2 * h)
    dBb = _body_vectors(q, Bdot) - np.cross(ds["omega"].values, B)
    law = np.clip(-4e4 * dBb, -0.2, 0.2)
    assert np.abs(m - law).max() < 1e-6 * 0.2
    rate = np.degrees(np.linalg.norm(ds["omega"].values, axis=1))
    assert rate[0] > 5.0 and rate[-1] < 0.5                            # 5.8 -> 0.39 deg/s in half an orbit
    assert isinstance(sc.potential.control, BDotControl)

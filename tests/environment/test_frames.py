"""orbatt.environment.frames: GCRS <-> ITRS rotation and WGS84 geodetic coordinates, checked
against astropy's own position transforms and known Earth-fixed points."""
import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import GCRS, ITRS, CartesianRepresentation, EarthLocation
from astropy.time import Time

from orbatt.environment import frames
from orbatt.errors import InputError

T = Time("2024-03-20T12:00:00", scale="utc") + np.linspace(0.0, 86400.0, 7) * u.s


def _positions(n, radius=6778.0, seed=3):
    r = np.random.default_rng(seed).normal(size=(n, 3))
    return radius * r / np.linalg.norm(r, axis=1)[:, None]


def test_gcrs_to_itrs_equals_astropy_position_transform():
    r = _positions(7)
    with frames.offline_iers():
        ref = GCRS(CartesianRepresentation(r.T * u.km), obstime=T).transform_to(ITRS(obstime=T))
    ref = ref.cartesian.xyz.to_value(u.km).T
    np.testing.assert_allclose(frames.gcrs_to_itrs(T, r), ref, rtol=0, atol=1e-9)


def test_rotation_is_orthogonal_and_inverse_round_trips():
    R = frames.rotation_gcrs_to_itrs(T)
    np.testing.assert_allclose(R @ R.transpose(0, 2, 1), np.broadcast_to(np.eye(3), R.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)
    v = _positions(7, radius=3e-5)   # a free vector (a field in T)
    np.testing.assert_allclose(frames.itrs_to_gcrs(T, frames.gcrs_to_itrs(T, v)), v, atol=1e-19)


def test_earth_turns_once_per_sidereal_day_about_the_pole():
    """The ITRS longitude of a fixed GCRS point on the equator advances by -360 deg per
    sidereal day (86164.0905 s)."""
    t = Time("2024-03-20T00:00:00") + np.array([0.0, 86164.0905 / 4]) * u.s
    x = frames.gcrs_to_itrs(t, np.array([[7000.0, 0.0, 0.0]] * 2))
    lon = np.degrees(np.arctan2(x[:, 1], x[:, 0]))
    assert ((lon[1] - lon[0] + 180.0) % 360.0 - 180.0) == pytest.approx(-90.0, abs=0.02)


def test_geodetic_recovers_a_known_place():
    loc = EarthLocation.from_geodetic(lon=5.32415 * u.deg, lat=60.39299 * u.deg, height=400 * u.km,
                                      ellipsoid="WGS84")
    x_itrs = np.array([loc.x.to_value(u.km), loc.y.to_value(u.km), loc.z.to_value(u.km)])
    r_gcrs = frames.itrs_to_gcrs(T[2], x_itrs)
    lat, lon, alt = frames.geodetic(T[2], r_gcrs)
    assert lat[0] == pytest.approx(60.39299, abs=1e-9)
    assert lon[0] == pytest.approx(5.32415, abs=1e-9)
    assert alt[0] == pytest.approx(400.0, abs=1e-8)


def test_bad_inputs_name_the_argument():
    with pytest.raises(InputError, match="r_gcrs_km"):
        frames.gcrs_to_itrs(T, np.zeros((7, 2)))
    with pytest.raises(InputError, match="t: expected a Time array of shape"):
        frames.gcrs_to_itrs(T, np.zeros((3, 3)))
    with pytest.raises(InputError, match="t: expected an astropy Time"):
        frames.gcrs_to_itrs(0.0, np.zeros((1, 3)))


def test_erfa_rotation_is_astropys_transform():
    """The fast GCRS -> ITRS matrix (ERFA's c2t06a with the IERS table's UT1 and polar motion)
    against astropy's own frame transform of the basis vectors, over a day."""
    import astropy.units as u
    from astropy.time import Time

    from orbatt.environment import frames

    t = Time("2025-03-20T00:00:00", scale="utc") + np.linspace(0.0, 86400.0, 97) * u.s
    fast = frames.rotation_gcrs_to_itrs(t)
    slow = frames.rotation_gcrs_to_itrs_astropy(t)
    assert np.abs(fast - slow).max() < 1e-14
    np.testing.assert_allclose(np.einsum("nij,nkj->nik", fast, fast), np.broadcast_to(np.eye(3), fast.shape),
                               atol=1e-15)


def test_geodetic_is_astropys_to_geodetic_bit_for_bit():
    """frames.geodetic calls ERFA directly (no astropy.coordinates import, issue 25) with the
    operations of EarthLocation.to_geodetic("WGS84") and Longitude.wrap_at(180 deg)."""
    rng = np.random.default_rng(5)
    r = rng.normal(size=(3000, 3))
    r *= rng.uniform(6300.0, 42000.0, (3000, 1)) / np.linalg.norm(r, axis=1)[:, None]
    r[:4, 1] = 0.0                  # on the 0 / 180 deg meridians
    r[:2, 0] = -7000.0
    t = Time("2025-03-20T00:00:00", scale="utc") + np.linspace(0.0, 86400.0, 3000) * u.s
    lat, lon, alt = frames.geodetic(t, r)
    x = frames.gcrs_to_itrs(t, r)
    loc = EarthLocation.from_geocentric(x[:, 0], x[:, 1], x[:, 2], unit=u.km)
    lon_ref, lat_ref, h_ref = loc.to_geodetic("WGS84")
    np.testing.assert_array_equal(lat, lat_ref.to_value(u.deg))
    np.testing.assert_array_equal(lon, lon_ref.wrap_at(180 * u.deg).to_value(u.deg))
    np.testing.assert_array_equal(alt, h_ref.to_value(u.km))
    assert np.all((lon >= -180.0) & (lon < 180.0))


@pytest.mark.parametrize("span_days, n", [(1.0, 4321), (30.0, 20000), (0.01, 200)])
def test_interpolated_precession_nutation_is_erfas(span_days, n):
    """Many instants: the bias-precession-nutation matrix from nodes every 10 minutes agrees
    with ERFA's c2i06a at each instant to round-off, and the whole rotation with c2t06a
    (issue 25: c2i06a was ~0.2 s of each day-long environment table)."""
    import astropy.units as u
    import erfa
    from astropy.time import Time

    from orbatt.environment import frames

    t = Time("2025-03-20T00:00:00", scale="utc") + np.linspace(0.0, span_days * 86400.0, n) * u.s
    tt = t.tt
    c2i = frames.celestial_to_intermediate(tt.jd1, tt.jd2)
    assert np.abs(c2i - erfa.c2i06a(tt.jd1, tt.jd2)).max() <= 1e-15
    R = frames.rotation_gcrs_to_itrs(t)
    with frames.offline_iers():
        from astropy.utils import iers

        xp, yp = iers.earth_orientation_table.get().pm_xy(t)
    ut1 = t.ut1
    direct = erfa.c2t06a(tt.jd1, tt.jd2, ut1.jd1, ut1.jd2, xp.to_value(u.rad), yp.to_value(u.rad))
    assert np.abs(R - direct).max() <= 1e-15
    few = t[:50]    # few instants: c2i06a at each, c2t06a's bits
    np.testing.assert_array_equal(frames.rotation_gcrs_to_itrs(few), direct[:50])


EOP_CHILD = """
import sys, numpy as np, astropy.units as u
from astropy.time import Time
from orbatt.environment import frames
R = frames.rotation_gcrs_to_itrs(Time('2025-03-20T00:00:00') + np.linspace(0.0, 86400.0, 25) * u.s)
print(frames.EOP_SOURCE, R.tobytes().hex())
"""


def test_the_earth_orientation_table_is_parsed_once_per_installation(tmp_path):
    """Issue 25: astropy parses its bundled IERS table (1-2.5 s) in every process; orbatt keeps
    the parsed table beside numba's cache: the next process reads it, with the same bits, and a
    corrupted file is parsed again and rewritten."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}

    def run():
        r = subprocess.run([sys.executable, "-c", EOP_CHILD], capture_output=True, text=True, env=env, timeout=300)
        assert r.returncode == 0, r.stderr
        return r.stdout.split()

    source, first = run()
    assert source == "astropy"
    cached = list((tmp_path / "orbatt").glob("iers-*.pickle"))
    assert len(cached) == 1
    source, again = run()
    assert source == "cache" and again == first
    cached[0].write_bytes(cached[0].read_bytes()[:100])  # truncated
    source, third = run()
    assert source == "astropy" and third == first
    assert run()[0] == "cache"

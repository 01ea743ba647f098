"""orbatt.environment.magnetic: IGRF along an orbit against ppigrf called directly (geodetic
and geocentric forms, frames through astropy), the dipole against IGRF's degree-1 terms."""
import numpy as np
import ppigrf
import pytest
from astropy import units as u
from astropy.time import Time

from orbatt.environment import frames
from orbatt.environment.magnetic import DipoleField, IGRFField
from orbatt.errors import InputError
from orbatt.orbits import KeplerOrbit

EPOCH = Time("2024-03-20T06:00:00", scale="utc")


def _orbit_points(n=6):
    orbit = KeplerOrbit(6778.137 * u.km, 0.001, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, epoch=EPOCH)
    s = np.linspace(0.0, 20000.0, n)
    return EPOCH + s * u.s, orbit.state(s)[0]


def _enu_to_itrs(lat_deg, lon_deg, east, north, up):
    la, lo = np.radians(lat_deg), np.radians(lon_deg)
    e = np.array([-np.sin(lo), np.cos(lo), 0.0])
    n = np.array([-np.sin(la) * np.cos(lo), -np.sin(la) * np.sin(lo), np.cos(la)])
    z = np.array([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)])
    return east * e + north * n + up * z


def test_igrf_equals_ppigrf_geodetic_along_an_orbit():
    t, r = _orbit_points()
    B = IGRFField().field(t, r)
    lat, lon, alt = frames.geodetic(t, r)
    for k in range(len(t)):
        be, bn, bu = ppigrf.igrf(lon[k], lat[k], alt[k], t[k].utc.datetime)
        ref = frames.itrs_to_gcrs(t[k], _enu_to_itrs(lat[k], lon[k], be.item(), bn.item(), bu.item()) * 1e-9)[0]
        # ppigrf's geodetic <-> geocentric series (Olsen's) vs astropy's exact WGS84: ~1e-9
        np.testing.assert_allclose(B[k], ref, rtol=0, atol=1e-8 * np.linalg.norm(ref))
    assert np.all((np.linalg.norm(B, axis=1) > 1.5e-5) & (np.linalg.norm(B, axis=1) < 6e-5))


def test_igrf_equals_ppigrf_geocentric_to_round_off():
    t, r = _orbit_points()
    x = frames.gcrs_to_itrs(t, r)
    B = IGRFField().field_itrs(t, x)
    rr = np.linalg.norm(x, axis=1)
    th = np.degrees(np.arccos(x[:, 2] / rr))
    ph = np.degrees(np.arctan2(x[:, 1], x[:, 0]))
    for k in range(len(t)):
        br, bt, bp = (c.item() for c in ppigrf.igrf_gc(rr[k], th[k], ph[k], t[k].utc.datetime))
        e_r = x[k] / rr[k]
        e_p = np.array([-np.sin(np.radians(ph[k])), np.cos(np.radians(ph[k])), 0.0])
        e_t = np.cross(e_p, e_r)
        ref = (br * e_r + bt * e_t + bp * e_p) * 1e-9
        np.testing.assert_allclose(B[k], ref, rtol=0, atol=1e-13 * np.linalg.norm(ref))


def test_igrf_secular_variation_follows_each_instant():
    """Between two instants a year apart the field at a fixed Earth-fixed point changes by
    tens of nT, as ppigrf says."""
    x = np.array([[6778.0, 0.0, 0.0]])
    f = IGRFField()
    t0, t1 = Time("2024-01-01"), Time("2025-01-01")
    d = f.field_itrs(t1, x) - f.field_itrs(t0, x)
    ref = [np.array([c.item() for c in ppigrf.igrf_gc(6778.0, 90.0, 0.0, t.utc.datetime)]) for t in (t0, t1)]
    assert np.linalg.norm(d) * 1e9 == pytest.approx(np.linalg.norm(ref[1] - ref[0]), rel=1e-9)
    assert 5.0 < np.linalg.norm(d) * 1e9 < 200.0


def test_dipole_equals_igrf_degree_one_at_its_epoch():
    t, r = _orbit_points()
    d = DipoleField(EPOCH)
    x = frames.gcrs_to_itrs(t, r)
    Bd = d.field_itrs(None, x)
    # IGRF truncated to n = 1, with the coefficients of the dipole's epoch
    B1 = IGRFField(max_degree=1).field_itrs(EPOCH, x)
    np.testing.assert_allclose(Bd, B1, rtol=0, atol=1e-14 * np.abs(Bd).max())
    # ... and ppigrf's own n = 1 evaluation at one point
    rr = np.linalg.norm(x[0])
    th, ph = np.degrees(np.arccos(x[0, 2] / rr)), np.degrees(np.arctan2(x[0, 1], x[0, 0]))
    br, _, _ = ppigrf.igrf_gc(rr, th, ph, EPOCH.utc.datetime, max_degree=1)
    assert np.dot(Bd[0], x[0] / rr) * 1e9 == pytest.approx(br.item(), rel=1e-12)
    # g10 of IGRF-14 in 2024: about -29350 nT
    assert d.coefficients[0] == pytest.approx(-29350.0, abs=30.0)
    # in GCRS: the same field rotated
    np.testing.assert_allclose(frames.gcrs_to_itrs(t, d.field(t, r)), Bd, atol=1e-18)


def test_dipole_magnitude_at_the_equator():
    """On the geomagnetic equator at the surface |B| = sqrt(g10^2 + g11^2 + h11^2) ~ 3e-5 T."""
    d = DipoleField("2020-01-01T00:00:00")
    m = d.moment_itrs / np.linalg.norm(d.moment_itrs)
    eq = np.cross(m, [0.0, 0.0, 1.0])
    eq *= 6371.2 / np.linalg.norm(eq)
    b = np.linalg.norm(d.field_itrs(None, eq[None, :]))
    assert b == pytest.approx(np.linalg.norm(d.coefficients) * 1e-9, rel=1e-12)
    assert 2.9e-5 < b < 3.1e-5


def test_out_of_span_and_bad_arguments():
    with pytest.raises(InputError, match="epoch"):
        DipoleField("1850-01-01T00:00:00")
    with pytest.raises(InputError, match="outside IGRF-14"):
        IGRFField().field(Time("2031-01-01") + [0.0] * u.s, np.array([[7000.0, 0.0, 0.0]]))
    with pytest.raises(InputError, match="max_degree"):
        IGRFField(max_degree=14)

"""orbatt.environment.sun: the Sun's position (astropy, offline) and the shadow function,
with umbra/penumbra entry and exit times against a direct geometric computation."""
import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time
from astropy.utils.data import conf as data_conf

from orbatt.environment import sun
from orbatt.environment.frames import R_EARTH_WGS84
from orbatt.errors import InputError
from orbatt.orbits import KeplerOrbit

EPOCH = Time("2024-06-01T00:00:00", scale="utc")


def test_sun_position_offline_and_physical():
    t = Time(["2024-03-20T03:06:00", "2024-06-20T20:51:00", "2024-01-03T00:00:00", "2024-07-05T00:00:00"])
    with data_conf.set_temp("allow_internet", False):
        r = sun.sun_position(t)
    d = np.linalg.norm(r, axis=1) / sun.AU
    assert d[2] == pytest.approx(0.9833, abs=2e-4)     # perihelion
    assert d[3] == pytest.approx(1.0167, abs=2e-4)     # aphelion
    ra = np.degrees(np.arctan2(r[:, 1], r[:, 0]))
    dec = np.degrees(np.arcsin(r[:, 2] / np.linalg.norm(r, axis=1)))
    # March equinox: RA = Dec = 0 of date, which in GCRS (J2000 axes) is moved by the general
    # precession over 24.2 years, m = 46.12"/yr in RA and n = 20.04"/yr in Dec (nutation < 0.01 deg)
    years = (t[0].jyear - 2000.0)
    assert ra[0] == pytest.approx(-46.12 * years / 3600.0, abs=0.01)
    assert dec[0] == pytest.approx(-20.04 * years / 3600.0, abs=0.01)
    assert ra[1] == pytest.approx(90.0 - 0.31, abs=0.1) and dec[1] == pytest.approx(23.44, abs=0.01)  # solstice


def test_constants():
    assert sun.SRP_FLUX == 1361.0
    assert sun.AU == pytest.approx(149597870.7)
    assert sun.SRP_FLUX / sun.SPEED_OF_LIGHT == pytest.approx(4.54e-6, rel=1e-3)


# ---- shadow along a LEO orbit --------------------------------------------------------------
ORBIT = KeplerOrbit(6778.137 * u.km, 0.0005, 28.5 * u.deg, 10 * u.deg, 0 * u.deg, epoch=EPOCH)
T_SPAN = 6000.0
_SUN_NODES = sun.sun_position(EPOCH + np.array([0.0, T_SPAN]) * u.s)


def _r_sun(s):
    """The Sun along the span, linear between its astropy positions at both ends (the Sun
    moves by 0.07 deg in 6000 s; the same function feeds both computations)."""
    w = np.atleast_1d(s)[:, None] / T_SPAN
    return (1.0 - w) * _SUN_NODES[0] + w * _SUN_NODES[1]


def _geometry(s):
    """``(c - (a + b), c - (b - a))``: penumbra and umbra boundary functions written from
    the apparent radii and the separation (arccos of the dot product)."""
    r = ORBIT.state(np.atleast_1d(s))[0]
    d = _r_sun(s) - r
    rn, dn = np.linalg.norm(r, axis=1), np.linalg.norm(d, axis=1)
    a = np.arcsin(sun.R_SUN / dn)
    b = np.arcsin(R_EARTH_WGS84 / rn)
    c = np.arccos(np.sum(-r * d, axis=1) / (rn * dn))
    return c - (a + b), c - (b - a)


def _nu(s):
    return sun.shadow(ORBIT.state(np.atleast_1d(s))[0], _r_sun(s))


def _bisect(f, lo, hi, n=60):
    flo = f(lo)
    for _ in range(n):
        mid = 0.5 * (lo + hi)
        if (f(mid) > 0) == (flo > 0):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def test_umbra_penumbra_times_against_direct_geometry():
    s = np.arange(0.0, T_SPAN, 1.0)
    nu = _nu(s)
    assert nu.max() == 1.0 and nu.min() == 0.0
    events = {}
    for name, test in (("penumbra", lambda x: 0.5 - (_nu(x) < 1.0)), ("umbra", lambda x: (_nu(x) > 0.0) - 0.5)):
        v = test(s)
        idx = np.nonzero(np.diff(np.sign(v)))[0]
        assert len(idx) == 2, name            # one entry and one exit in the span
        events[name] = [_bisect(test, s[i], s[i + 1]) for i in idx]
    for k, name in ((0, "penumbra"), (1, "umbra")):
        g = lambda x, k=k: _geometry(x)[k][0]
        v = np.array([g(x) for x in s[::10]])
        idx = np.nonzero(np.diff(np.sign(v)))[0]
        ref = [_bisect(g, s[::10][i], s[::10][i + 1]) for i in idx]
        np.testing.assert_allclose(events[name], ref, atol=1e-6)
    # penumbra entry < umbra entry < umbra exit < penumbra exit; penumbra ~ 8-10 s at 400 km
    p_in, p_out = events["penumbra"]
    u_in, u_out = events["umbra"]
    assert p_in < u_in < u_out < p_out
    assert 5.0 < u_in - p_in < 15.0 and 5.0 < p_out - u_out < 15.0
    assert 1500.0 < u_out - u_in < 2400.0
    # full Sun outside, umbra inside, partial and monotonic in the penumbra
    assert _nu(p_in - 1.0)[0] == 1.0 and _nu(0.5 * (u_in + u_out))[0] == 0.0
    pen = _nu(np.linspace(p_in + 1e-3, u_in - 1e-3, 50))
    assert np.all((pen > 0.0) & (pen < 1.0)) and np.all(np.diff(pen) < 0.0)


def test_cylindrical_shadow_is_conical_without_penumbra():
    """The cylindrical shadow starts between the conical penumbra and umbra boundaries."""
    s = np.arange(0.0, T_SPAN, 0.5)
    r = ORBIT.state(s)[0]
    cyl = sun.shadow(r, _r_sun(s), kind="cylindrical")
    con = sun.shadow(r, _r_sun(s))
    assert set(np.unique(cyl)) == {0.0, 1.0}
    assert np.all(cyl[con == 0.0] == 0.0) and np.all(cyl[con == 1.0] == 1.0)


def test_annular_and_validation():
    # far behind a small body: the body's disc inside the Sun's
    r_sun = np.array([sun.AU, 0.0, 0.0])
    nu = sun.shadow(np.array([-1e6, 0.0, 0.0]), r_sun, body_radius=1000.0)
    a, b = np.arcsin(sun.R_SUN / (sun.AU + 1e6)), np.arcsin(1000.0 / 1e6)
    assert nu[0] == pytest.approx(1.0 - b**2 / a**2, rel=1e-12)
    with pytest.raises(InputError, match="kind"):
        sun.shadow(np.ones(3), r_sun, kind="conic")


@pytest.mark.parametrize("frac", [0.01, 0.2, 0.5, 0.8, 0.99])
def test_penumbra_fraction_against_quadrature(frac):
    """nu in the penumbra = 1 - (overlap of the two apparent discs) / (pi a^2), the overlap
    integrated numerically: chord of the body's disc across the Sun's disc."""
    from scipy.integrate import quad

    rn = R_EARTH_WGS84 + 400.0
    b = np.arcsin(R_EARTH_WGS84 / rn)
    d = sun.AU
    a = np.arcsin(sun.R_SUN / d)
    c = (b - a) + frac * 2.0 * a           # from umbra contact to penumbra contact
    # satellite at -x * rn; the Sun seen at angle c from the body's centre direction (+x)
    r_sat = np.array([-rn, 0.0, 0.0])
    r_sun = r_sat + d * np.array([np.cos(c), np.sin(c), 0.0])
    nu = sun.shadow(r_sat, r_sun, body_radius=R_EARTH_WGS84, sun_radius=sun.R_SUN)[0]

    def inside(u):   # chord at abscissa u common to the Sun disc |p| <= a and the body disc |p - (c, 0)| <= b
        half_sun = np.sqrt(max(a * a - u * u, 0.0))
        half_body = np.sqrt(max(b * b - (u - c) ** 2, 0.0))
        return 2.0 * min(half_sun, half_body)

    overlap = quad(inside, -a, a, epsabs=1e-16, epsrel=1e-12, limit=200)[0]
    assert nu == pytest.approx(1.0 - overlap / (np.pi * a * a), abs=1e-9)

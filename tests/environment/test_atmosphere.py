"""orbatt.environment.atmosphere: the exponential models (formula, Vallado's table) and
NRLMSIS 2.1 against pymsis called directly with astropy's geodetic coordinates."""
import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import GCRS, ITRS, CartesianRepresentation
from astropy.time import Time

from orbatt.environment import atmosphere as atm
from orbatt.environment.frames import offline_iers
from orbatt.errors import InputError

R = atm.R_EARTH_WGS84


def _along_x(alt_km):
    alt = np.atleast_1d(np.asarray(alt_km, dtype=float))
    return np.stack([R + alt, np.zeros_like(alt), np.zeros_like(alt)], axis=1)


def test_exponential_formula():
    m = atm.ExponentialAtmosphere("3e-12 kg/m3", "400 km", "60 km")
    rho = m.density(None, _along_x([400.0, 460.0, 340.0]))
    np.testing.assert_allclose(rho, 3e-12 * np.exp([0.0, -1.0, 1.0]), rtol=1e-14)
    # units at the boundary: g/cm3 and m are converted
    m2 = atm.ExponentialAtmosphere(3e-15 * u.g / u.cm**3, 400e3 * u.m, 60 * u.km, body_radius=6378.137 * u.km)
    np.testing.assert_allclose(m2.kernel_params(), m.kernel_params(), rtol=1e-15)


@pytest.mark.parametrize("alt, rho", [
    (0.0, 1.225), (400.0, 3.725e-12), (1000.0, 3.019e-15), (150.0, 2.070e-9),
    # inside a layer: rho0 exp(-(h - h0) / H)
    (425.0, 3.725e-12 * np.exp(-25.0 / 58.515)), (720.0, 3.614e-14 * np.exp(-20.0 / 88.667)),
    (1500.0, 3.019e-15 * np.exp(-500.0 / 268.0)), (449.999, 3.725e-12 * np.exp(-49.999 / 58.515)),
])
def test_vallado_table_values(alt, rho):
    assert atm.PiecewiseExponentialAtmosphere().density(None, _along_x(alt))[0] == pytest.approx(rho, rel=1e-13)


def test_vallado_table_is_nearly_continuous():
    """Vallado's layers join to within 6 %: each layer's top density is close to the next
    layer's base density (a typo in the table would break this)."""
    m = atm.PiecewiseExponentialAtmosphere()
    h0 = atm.VALLADO_TABLE[1:, 0]
    below = m.density(None, _along_x(h0 - 1e-9))
    above = m.density(None, _along_x(h0))
    np.testing.assert_allclose(below / above, 1.0, atol=0.06)


def test_nrlmsis_equals_pymsis_called_directly():
    import pymsis

    t = Time("2024-03-20T06:00:00", scale="utc") + np.array([0.0, 1000.0, 2000.0, 30000.0]) * u.s
    rng = np.random.default_rng(5)
    r = rng.normal(size=(4, 3))
    r = (R + 400.0) * r / np.linalg.norm(r, axis=1)[:, None]
    rho = atm.NRLMSIS(150.0, 140.0, 4.0).density(t, r)
    with offline_iers():
        itrs = GCRS(CartesianRepresentation(r.T * u.km), obstime=t).transform_to(ITRS(obstime=t))
    lon, lat, h = itrs.earth_location.to_geodetic("WGS84")
    for k in range(4):
        ref = pymsis.calculate(np.datetime64(t[k].utc.isot), lon[k].to_value(u.deg), lat[k].to_value(u.deg),
                               h[k].to_value(u.km), [150.0], [140.0], [[4.0] * 7], version=2.1)
        assert rho[k] == pytest.approx(float(ref[0, pymsis.Variable.MASS_DENSITY]), rel=1e-6)
    # space weather matters: a storm raises the density at 400 km
    assert np.all(atm.NRLMSIS(150.0, 140.0, 200.0).density(t, r) > 1.2 * rho)
    assert 1e-13 < rho.min() and rho.max() < 1e-10


def test_bad_inputs_name_the_key():
    with pytest.raises(InputError, match="density0"):
        atm.ExponentialAtmosphere("-1 kg/m3", "400 km", "60 km")
    with pytest.raises(InputError, match="scale_height"):
        atm.ExponentialAtmosphere("1e-12 kg/m3", "400 km", "0 km")
    with pytest.raises(InputError, match="altitude0"):
        atm.ExponentialAtmosphere("1e-12 kg/m3", "400 s", "60 km")
    with pytest.raises(InputError, match="ap"):
        atm.NRLMSIS(150, 150, "quiet")
    with pytest.raises(InputError, match="f107"):
        atm.NRLMSIS(-1, 150, 4)

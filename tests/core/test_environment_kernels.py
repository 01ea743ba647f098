"""orbatt.core.environment: the compiled kernels equal the numpy models of
orbatt.environment (densities, shadow function, spline tables)."""
import numba as nb
import numpy as np
import pytest

from orbatt.core import environment as ke
from orbatt.environment import atmosphere as atm


@nb.njit(cache=False)
def _exp_many(r, params):
    out = np.empty(r.shape[0])
    for i in range(r.shape[0]):
        out[i] = ke.exponential_density(r[i], params)
    return out


@nb.njit(cache=False)
def _piecewise_many(r, table):
    out = np.empty(r.shape[0])
    for i in range(r.shape[0]):
        out[i] = ke.piecewise_density((r[i, 0], r[i, 1], r[i, 2]), table)
    return out


def _radial(alts, seed=0):
    d = np.random.default_rng(seed).normal(size=(len(alts), 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return (atm.R_EARTH_WGS84 + np.asarray(alts))[:, None] * d


def test_exponential_kernel_equals_class():
    m = atm.ExponentialAtmosphere("3e-12 kg/m3", "400 km", "60 km")
    r = _radial(np.linspace(150.0, 900.0, 101))
    np.testing.assert_allclose(_exp_many(r, m.kernel_params()), m.density(None, r), rtol=1e-14)


def test_piecewise_kernel_equals_class_in_every_layer():
    m = atm.PiecewiseExponentialAtmosphere()
    h0 = atm.VALLADO_TABLE[:, 0]
    alts = np.concatenate([np.linspace(-5.0, 1500.0, 3011), h0, h0 - 1e-7, h0 + 1e-7])
    r = _radial(alts, seed=1)
    np.testing.assert_allclose(_piecewise_many(r, m.kernel_params()), m.density(None, r), rtol=1e-13)


@nb.njit(cache=False)
def _shadow_many(r_sat, r_sun, R_body, R_sun, conical):
    out = np.empty(r_sat.shape[0])
    for i in range(r_sat.shape[0]):
        a = (r_sat[i, 0], r_sat[i, 1], r_sat[i, 2])
        b = (r_sun[i, 0], r_sun[i, 1], r_sun[i, 2])
        out[i] = ke.shadow_conical(a, b, R_body, R_sun) if conical else ke.shadow_cylindrical(a, b, R_body, R_sun)
    return out


@pytest.mark.parametrize("kind", ["conical", "cylindrical"])
def test_shadow_kernels_equal_numpy(kind):
    from orbatt.environment import sun

    # satellites on a 400 km sphere, densest near the shadow boundary of a Sun along +x
    rng = np.random.default_rng(2)
    n = 20000
    ang = rng.uniform(0.0, 2.0 * np.pi, n)
    off = np.concatenate([rng.uniform(-1.0, 1.0, n // 2), rng.uniform(-0.02, 0.02, n // 2)])
    rho = atm.R_EARTH_WGS84 * (1.0 + off * 0.1)     # distance from the Sun line
    r = atm.R_EARTH_WGS84 + 400.0
    x = -np.sqrt(np.maximum(r**2 - rho**2, 0.0))
    r_sat = np.stack([x, rho * np.cos(ang), rho * np.sin(ang)], axis=1)
    r_sun = np.tile([sun.AU, 1e5, -2e5], (n, 1))
    nu_np = sun.shadow(r_sat, r_sun, kind=kind)
    nu_k = _shadow_many(r_sat, r_sun, atm.R_EARTH_WGS84, sun.R_SUN, kind == "conical")
    # nu's sensitivity to the separation is ~1/a (a = 0.0047 rad): round-off ~1e-14
    np.testing.assert_allclose(nu_k, nu_np, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(nu_k == 0.0, nu_np == 0.0)
    np.testing.assert_array_equal(nu_k == 1.0, nu_np == 1.0)
    assert np.any(nu_np == 0.0) and np.any(nu_np == 1.0)
    if kind == "conical":
        assert np.sum((nu_np > 0.0) & (nu_np < 1.0)) > 100     # the penumbra is sampled


def test_conical_shadow_shortcut_on_the_sunlit_side():
    """The sunlit half (the Sun 90 deg or more from the body's centre) returns 1 without the
    full test: the same answers as numpy's full test on a sphere of satellites, the terminator
    plane and a satellite inside the body (where the shortcut does not apply) included."""
    from orbatt.environment import sun

    rng = np.random.default_rng(5)
    n = 20000
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    d[: n // 4, 0] = rng.uniform(-1e-6, 1e-6, n // 4)          # near the terminator plane
    r_sat = d * rng.choice([atm.R_EARTH_WGS84 + 400.0, atm.R_EARTH_WGS84 * 1.005, 0.5 * atm.R_EARTH_WGS84],
                           size=n)[:, None]
    r_sun = np.tile([sun.AU, 1e5, -2e5], (n, 1))
    nu_np = sun.shadow(r_sat, r_sun, kind="conical")
    nu_k = _shadow_many(r_sat, r_sun, atm.R_EARTH_WGS84, sun.R_SUN, True)
    np.testing.assert_allclose(nu_k, nu_np, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(nu_k == 1.0, nu_np == 1.0)
    assert np.sum(nu_np == 1.0) > n // 3 and np.any(nu_np == 0.0)

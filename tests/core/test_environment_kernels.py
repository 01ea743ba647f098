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

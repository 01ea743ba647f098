"""orbatt.environment.tables and the compiled spline evaluator: exactness on cubics, the
warm-started interval search, orbit sampling, and the interpolation error of each
environment table at its default step along a 400 km orbit (the numbers the module states)."""
import numba as nb
import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

from orbatt.core import environment as ke
from orbatt.environment import tables
from orbatt.environment.atmosphere import NRLMSIS
from orbatt.environment.magnetic import DipoleField, IGRFField
from orbatt.environment.sun import sun_position
from orbatt.errors import InputError
from orbatt.orbits import KeplerOrbit

EPOCH = Time("2024-03-20T00:00:00", scale="utc")
ORBIT = KeplerOrbit(6778.137 * u.km, 0.0005, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, epoch=EPOCH)


@nb.njit(cache=False)
def _eval_in_order(table, t, ncomp, order):
    work = np.full(3, np.nan)
    out = np.zeros((t.shape[0], 4))
    for j in order:
        v = ke.spline_eval(table, t[j], ncomp, 2, work)
        out[j, 0], out[j, 1], out[j, 2], out[j, 3] = v
    return out, work


@pytest.mark.parametrize("ncomp", [1, 2, 3, 4])
def test_spline_table_is_exact_on_cubics(ncomp):
    rng = np.random.default_rng(ncomp)
    t = np.sort(rng.uniform(0.0, 100.0, 30))
    coef = rng.normal(size=(4, ncomp))
    f = lambda x: sum(coef[p] * (x[:, None] - 50.0) ** p for p in range(4))  # noqa: E731
    table = tables.spline_table(t, f(t) if ncomp > 1 else f(t)[:, 0])
    assert table.shape == (30, 1 + 4 * ncomp)
    x = np.concatenate([rng.uniform(t[0], t[-1], 500), t])
    order = rng.permutation(len(x))        # jumps back and forth: warm start and bisection
    got, work = _eval_in_order(table, x, ncomp, order)
    np.testing.assert_allclose(got[:, :ncomp], f(x), rtol=1e-11, atol=1e-9)
    assert np.all(got[:, ncomp:] == 0.0)
    assert 0 <= work[2] < 29 and np.isnan(work[0]) and np.isnan(work[1])   # only its slot


def test_find_row_warm_start_and_span():
    table = tables.spline_table(np.arange(10.0), np.arange(10.0) ** 2)
    work = np.full(1, np.nan)
    assert ke.find_row(table, 3.5, work, 0) == 3 and work[0] == 3
    assert ke.find_row(table, 4.2, work, 0) == 4 and work[0] == 4      # next row
    assert ke.find_row(table, 9.0, work, 0) == 8                       # the end belongs to the last interval
    assert ke.find_row(table, 0.0, work, 0) == 0
    for bad in (-1e-9, 9.0 + 1e-9, np.nan):
        with pytest.raises(ValueError, match="outside the sampled span"):
            ke.find_row(table, bad, work, 0)


def test_spline_eval_many_matches_scipy():
    from scipy.interpolate import CubicSpline

    t = np.linspace(0.0, 10.0, 21)
    v = np.stack([np.sin(t), np.cos(t), np.exp(-t)], axis=1)
    x = np.linspace(0.0, 10.0, 333)
    np.testing.assert_allclose(ke.spline_eval_many(tables.spline_table(t, v), x, 3), CubicSpline(t, v)(x),
                               rtol=0, atol=1e-14)


def _scipy_table(t, v):
    """The table of scipy's not-a-knot CubicSpline (what spline_table computed before)."""
    from scipy.interpolate import CubicSpline

    c = CubicSpline(t, v, bc_type="not-a-knot").c       # (4, n - 1, ncomp), highest power first
    table = np.zeros((t.shape[0], 1 + 4 * v.shape[1]))
    table[:, 0] = t
    for k in range(v.shape[1]):
        table[:-1, 1 + 4 * k:5 + 4 * k] = c[::-1, :, k].T
        table[-1, 1 + 4 * k] = v[-1, k]
    return table


def _field_like(t, rng):
    """Three components of very different scales: a field in nT-like numbers, a density-like
    decaying exponential, and noise (a spline far from its data's smoothness)."""
    return np.stack([3e4 * np.sin(t / 900.0) + 1e4 * np.cos(t / 5000.0), 1e-12 * np.exp(-t / 1e5),
                     rng.normal(size=t.shape[0])], axis=1)


@pytest.mark.parametrize("n", [4, 5, 7, 100, 4321])
def test_spline_table_on_even_steps_is_scipys_bit_for_bit(n):
    """The environment tables are sampled at even steps: there the compiled solver gives
    scipy's CubicSpline coefficients exactly (LAPACK's banded solver pivots on no row)."""
    rng = np.random.default_rng(n)
    t = np.linspace(0.0, 86400.0, n)
    v = _field_like(t, rng)
    np.testing.assert_array_equal(tables.spline_table(t, v), _scipy_table(t, v))


@pytest.mark.parametrize("n", [5, 100, 4321])
def test_spline_table_on_uneven_steps_agrees_with_scipy(n):
    """On uneven steps the two eliminations differ (scipy's pivots): the knot values and slopes
    agree to 1e-15 of each component's scale, the spline's values between the knots to 1e-15
    (the cubic and quadratic coefficients are differences of nearly equal slopes over the
    step: their last digits are ill-conditioned in both)."""
    rng = np.random.default_rng(n)
    t = np.cumsum(rng.uniform(0.2, 3.0, n))
    v = _field_like(t, rng)
    ours, ref = tables.spline_table(t, v), _scipy_table(t, v)
    for k in range(3):
        cols = slice(1 + 4 * k, 3 + 4 * k)      # c0 (values), c1 (slopes)
        np.testing.assert_allclose(ours[:, cols], ref[:, cols], rtol=0, atol=2e-15 * np.max(np.abs(ref[:, cols])))
    x = np.sort(rng.uniform(t[0], t[-1], 2000))
    got, want = ke.spline_eval_many(ours, x, 3), ke.spline_eval_many(ref, x, 3)
    for k in range(3):
        scale = np.max(np.abs(v[:, k]))
        np.testing.assert_allclose(got[:, k], want[:, k], rtol=0, atol=4e-15 * scale)


def test_spline_table_imports_no_scipy():
    """A spline table needs no scipy (issue 25: scipy.interpolate cost ~0.6-1.3 s of every run)."""
    import subprocess
    import sys

    code = ("import sys, numpy as np; from orbatt.environment.tables import spline_table; "
            "spline_table(np.arange(6.0), np.arange(6.0) ** 3); "
            "print(sorted(m for m in sys.modules if m.startswith(('scipy.interpolate', 'scipy.linalg'))))")
    # the first run may compile the table's kernel (numba's compiler imports scipy.linalg for
    # its LAPACK bindings; a cold cache depends on which tests ran before): the second loads it
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"      # (numba itself imports scipy's top level, ~15 ms)


def test_sample_along_orbit():
    s = tables.sample_along_orbit(ORBIT, 100.0, 1000.0, 7 * u.s)
    assert s.t[0] == 100.0 and s.t[-1] == 1000.0 and np.all(np.diff(s.t) <= 7.0 + 1e-12)
    assert len(s.t) == 130                          # ceil(900 / 7) = 129 intervals
    pos, vel = ORBIT.state(s.t)
    np.testing.assert_array_equal(s.position, pos)
    np.testing.assert_array_equal(s.velocity, vel)
    assert abs((s.time[-1] - EPOCH).to_value(u.s) - 1000.0) < 1e-6
    undated = tables.sample_along_orbit(KeplerOrbit(7000 * u.km, 0.0, 0.0, 0.0, 0.0), 0.0, 10.0, 1.0)
    assert undated.time is None and undated.t.size == 11  # no epoch: samples without dates (exponential drag)
    with pytest.raises(InputError, match="t1"):
        tables.sample_along_orbit(ORBIT, 10.0, 10.0, 1.0)
    with pytest.raises(InputError, match="step"):
        tables.sample_along_orbit(ORBIT, 0.0, 10.0, -1.0)
    with pytest.raises(InputError, match="values"):
        tables.spline_table(np.arange(5.0), np.zeros((5, 5)))


def _table_error(evaluate, step, span, direction=False):
    """Largest |table - library| at the quarter and mid points, relative to max |library|."""
    s = tables.sample_along_orbit(ORBIT, 0.0, span, step)
    table = tables.tabulate(s, evaluate)
    ncomp = table.shape[1] // 4
    x = np.concatenate([s.t[:-1] + f * np.diff(s.t) for f in (0.25, 0.5, 0.75)])
    ref = np.asarray(evaluate(EPOCH + x * u.s, ORBIT.state(x)[0]), dtype=float).reshape(len(x), ncomp)
    got = ke.spline_eval_many(table, x, ncomp)
    if direction:
        ref /= np.linalg.norm(ref, axis=1)[:, None]
        got /= np.linalg.norm(got, axis=1)[:, None]
    return np.abs(got - ref).max() / np.abs(ref).max()


def test_magnetic_field_table_error_at_default_step():
    err = _table_error(IGRFField().field, tables.MAGNETIC_FIELD_STEP, 5600.0)
    assert err < 1e-6
    assert err > 1e-9                     # the measured 1.8e-7 (a cubic's error, not zero)
    assert _table_error(DipoleField(EPOCH).field, tables.MAGNETIC_FIELD_STEP, 5600.0) < 1e-6


def test_sun_table_error_at_default_step():
    err = _table_error(lambda t, r: sun_position(t), tables.SUN_STEP, 86400.0, direction=True)
    assert err < 1e-6


def test_density_table_error_at_default_step():
    err = _table_error(NRLMSIS(150.0, 150.0, 4.0).density, tables.DENSITY_STEP, 5600.0)
    assert err < 1e-4

"""orbatt.environment.tables and the compiled piece evaluator: exactness on polynomials, the
warm-started interval search, orbit sampling, the not-a-knot spline of the Earth-orientation
nodes against scipy, and the interpolation error of each environment table with its default
pieces along a 400 km orbit (the numbers the module states)."""
import numba as nb
import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

from orbatt.core import environment as ke
from orbatt.environment import tables
from orbatt.environment.atmosphere import NRLMSIS, PiecewiseExponentialAtmosphere
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
    rate = np.zeros((t.shape[0], 3))
    for j in order:
        v = ke.piece_eval(table, t[j], ncomp, 2, work)
        out[j, 0], out[j, 1], out[j, 2], out[j, 3] = v
        if ncomp >= 3:
            _, d = ke.piece_eval_rate(table, t[j], 2, work)
            rate[j, 0], rate[j, 1], rate[j, 2] = d
    return out, rate, work


@pytest.mark.parametrize("ncomp", [1, 2, 3, 4])
@pytest.mark.parametrize("degree", [3, 12])
def test_piece_table_is_exact_on_polynomials(ncomp, degree):
    """A polynomial of the pieces' degree is reproduced (values and rates), whatever the order
    of the times (warm start and bisection), with the table's layout and only its own slot."""
    rng = np.random.default_rng(ncomp + 10 * degree)
    t = tables.piece_times(3.0, 2000.0, tables.Pieces(450.0, degree))
    assert t.size == 5 * degree + 1 and t[0] == 3.0 and t[-1] == 2000.0
    coef = rng.normal(size=(degree + 1, ncomp))
    f = lambda x: sum(coef[p] * ((x[:, None] - 1000.0) / 1000.0) ** p for p in range(degree + 1))  # noqa: E731
    df = lambda x: sum(p * coef[p] * ((x[:, None] - 1000.0) / 1000.0) ** (p - 1) / 1000.0  # noqa: E731
                       for p in range(1, degree + 1))
    table = tables.piece_table(t, f(t) if ncomp > 1 else f(t)[:, 0], degree)
    assert table.shape == (6, ke.PIECE_HEADER + ncomp * (degree + 1))
    np.testing.assert_array_equal(table[:, 0], t[::degree])
    x = np.concatenate([rng.uniform(t[0], t[-1], 500), t])
    order = rng.permutation(len(x))
    got, rate, work = _eval_in_order(table, x, ncomp, order)
    np.testing.assert_allclose(got[:, :ncomp], f(x), rtol=1e-11, atol=1e-11)
    assert np.all(got[:, ncomp:] == 0.0)
    if ncomp >= 3:
        np.testing.assert_allclose(rate, df(x)[:, :3], rtol=1e-9, atol=1e-12)
    assert 0 <= work[2] < 5 and np.isnan(work[0]) and np.isnan(work[1])   # only its slot


def test_piece_table_is_continuous_at_the_knots():
    """Adjacent pieces share their end node: the table is continuous (to round-off) across the
    knots even where the field is far from a polynomial."""
    t = tables.piece_times(0.0, 3000.0, tables.Pieces(500.0, 6))
    table = tables.piece_table(t, np.sin(t / 97.0), 6)
    knots = table[1:-1, 0]
    left = ke.piece_eval_many(table, np.nextafter(knots, -np.inf), 1)[:, 0]
    right = ke.piece_eval_many(table, knots, 1)[:, 0]
    np.testing.assert_allclose(left, np.sin(knots / 97.0), rtol=0, atol=1e-14)
    np.testing.assert_allclose(right, np.sin(knots / 97.0), rtol=0, atol=1e-14)


def test_find_row_warm_start_and_span():
    t = tables.piece_times(0.0, 9.0, tables.Pieces(1.0, 2))
    table = tables.piece_table(t, t ** 2, 2)
    work = np.full(1, np.nan)
    assert ke.find_row(table, 3.5, work, 0) == 3 and work[0] == 3
    assert ke.find_row(table, 4.2, work, 0) == 4 and work[0] == 4      # next row
    assert ke.find_row(table, 9.0, work, 0) == 8                       # the end belongs to the last interval
    assert ke.find_row(table, 0.0, work, 0) == 0
    for bad in (-1e-9, 9.0 + 1e-9, np.nan):
        with pytest.raises(ValueError, match="outside the sampled span"):
            ke.find_row(table, bad, work, 0)


def test_piece_table_refuses_bad_input():
    t = tables.piece_times(0.0, 10.0, tables.Pieces(5.0, 4))
    with pytest.raises(InputError, match="values"):
        tables.piece_table(t, np.zeros((t.size, 5)), 4)
    with pytest.raises(InputError, match="piece_times of degree 3"):
        tables.piece_table(t, np.zeros(t.size), 3)
    with pytest.raises(InputError, match="non-finite"):
        tables.piece_table(t, np.full(t.size, np.nan), 4)
    with pytest.raises(InputError, match="pieces"):
        tables.piece_times(0.0, 10.0, tables.Pieces(0.0, 4))


def _spline(t, v):
    return ke.not_a_knot_table(np.ascontiguousarray(t), np.ascontiguousarray(v))


def _cubic_values(table, x):
    """The spline table's cubics at ``x`` (numpy, for the comparison with scipy's)."""
    i = np.clip(np.searchsorted(table[:, 0], x, side="right") - 1, 0, table.shape[0] - 2)
    s = x - table[i, 0]
    ncomp = (table.shape[1] - 1) // 4
    return np.stack([sum(table[i, 1 + 4 * k + p] * s ** p for p in range(4)) for k in range(ncomp)], axis=1)


def _scipy_table(t, v):
    """The table of scipy's not-a-knot CubicSpline."""
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
def test_not_a_knot_table_on_even_steps_is_scipys_bit_for_bit(n):
    """The Earth-orientation nodes (:mod:`orbatt.environment.frames`) are evenly spaced: there
    the compiled solver gives scipy's CubicSpline coefficients exactly (LAPACK's banded solver
    pivots on no row)."""
    rng = np.random.default_rng(n)
    t = np.linspace(0.0, 86400.0, n)
    v = _field_like(t, rng)
    np.testing.assert_array_equal(_spline(t, v), _scipy_table(t, v))


@pytest.mark.parametrize("n", [5, 100, 4321])
def test_not_a_knot_table_on_uneven_steps_agrees_with_scipy(n):
    """On uneven steps the two eliminations differ (scipy's pivots): the knot values and slopes
    agree to 1e-15 of each component's scale, the spline's values between the knots to 1e-15
    (the cubic and quadratic coefficients are differences of nearly equal slopes over the
    step: their last digits are ill-conditioned in both)."""
    rng = np.random.default_rng(n)
    t = np.cumsum(rng.uniform(0.2, 3.0, n))
    v = _field_like(t, rng)
    ours, ref = _spline(t, v), _scipy_table(t, v)
    for k in range(3):
        cols = slice(1 + 4 * k, 3 + 4 * k)      # c0 (values), c1 (slopes)
        np.testing.assert_allclose(ours[:, cols], ref[:, cols], rtol=0, atol=2e-15 * np.max(np.abs(ref[:, cols])))
    x = np.sort(rng.uniform(t[0], t[-1], 2000))
    got, want = _cubic_values(ours, x), _cubic_values(ref, x)
    for k in range(3):
        scale = np.max(np.abs(v[:, k]))
        np.testing.assert_allclose(got[:, k], want[:, k], rtol=0, atol=4e-15 * scale)


def test_piece_table_imports_no_scipy():
    """A piece table needs no scipy (issue 25: scipy.interpolate cost ~0.6-1.3 s of every run)."""
    import subprocess
    import sys

    code = ("import sys, numpy as np; from orbatt.environment import tables as T; "
            "t = T.piece_times(0.0, 6.0, T.Pieces(2.0, 3)); T.piece_table(t, t ** 3, 3); "
            "print(sorted(m for m in sys.modules if m.startswith(('scipy.interpolate', 'scipy.linalg'))))")
    # the first run may compile the table's kernel (numba's compiler imports scipy.linalg for
    # its LAPACK bindings; a cold cache depends on which tests ran before): the second loads it
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"      # (numba itself imports scipy's top level, ~15 ms)


def test_sample_pieces():
    s = tables.sample_pieces(ORBIT, 100.0, 1000.0, tables.Pieces(400.0, 8))
    assert s.t.size == 3 * 8 + 1 and s.t[0] == 100.0 and s.t[-1] == 1000.0 and s.t[8] == 400.0
    assert np.all(np.diff(s.t) > 0.0)
    pos, vel = ORBIT.state(s.t)
    np.testing.assert_array_equal(s.position, pos)
    np.testing.assert_array_equal(s.velocity, vel)
    with pytest.raises(InputError, match="t1"):
        tables.sample_pieces(ORBIT, 10.0, 10.0, tables.Pieces(400.0, 8))


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


def _table_error(evaluate, pieces, span, direction=False):
    """Largest |table - library| at 39 points inside every piece, relative to max |library|."""
    s = tables.sample_pieces(ORBIT, 0.0, span, pieces)
    table = tables.tabulate(s, evaluate, pieces.degree)
    ncomp = (table.shape[1] - ke.PIECE_HEADER) // (pieces.degree + 1)
    knots = table[:, 0]
    f = np.linspace(0.0, 1.0, 41)[1:-1]
    x = (knots[:-1, None] + f[None, :] * np.diff(knots)[:, None]).ravel()
    ref = np.asarray(evaluate(EPOCH + x * u.s, ORBIT.state(x)[0]), dtype=float).reshape(len(x), ncomp)
    got = ke.piece_eval_many(table, x, ncomp)
    if direction:
        ref /= np.linalg.norm(ref, axis=1)[:, None]
        got /= np.linalg.norm(got, axis=1)[:, None]
    return np.abs(got - ref).max() / np.abs(ref).max()


def test_magnetic_field_table_error_at_default_step():
    """600 s pieces of degree 12: 1.1e-9 (the 20 s cubic splines before them: 1.1e-7 on the
    same points), with 10 knots per orbit instead of 280."""
    err = _table_error(IGRFField().field, tables.MAGNETIC_FIELD_PIECES, 11200.0)
    assert 1e-10 < err < 1e-8             # the measured 1.1e-9 (an interpolation error, not zero)
    assert _table_error(DipoleField(EPOCH).field, tables.MAGNETIC_FIELD_PIECES, 11200.0) < 1e-12


def test_sun_table_error_at_default_step():
    err = _table_error(lambda t, r: sun_position(t), tables.SUN_PIECES, 86400.0, direction=True)
    assert err < 1e-12


def test_density_table_error_at_default_step():
    """NRLMSIS's own noise sets the error, not the pieces: the library (single precision,
    the time of day in whole seconds) scatters about a smooth curve by 3.4e-6 (standard
    deviation) and at most 1.6e-5 of the largest density along this orbit (112,001 points).
    The error at a point is its own noise plus the noise its piece carries from its 13 samples
    (Lebesgue constant 2.5; 1.45 for independent noise). Which bits of that noise fall where
    depends on the CPU, its size does not: measured 1.7e-5 (Intel, AVX-512) and 1.92e-5 (AMD
    EPYC, numpy's AVX-512 and AVX2 paths alike); the 30 s cubic spline before: 1.8e-5 on the
    same points. The bound, 3e-5, is about twice the largest single excursion of the noise and
    6 standard deviations of the point's error. (The noise hides the pieces' own error up to
    1800 s pieces of degree 12 or 600 s of degree 6, 2.2e-5 and 2.3e-5; 2400 s pieces: 2.6e-4.)"""
    err = _table_error(NRLMSIS(150.0, 150.0, 4.0).density, tables.DENSITY_PIECES, 11200.0)
    assert err < 3e-5


def test_layered_density_table_error():
    """The piecewise exponential atmosphere jumps at its layers' bases: short cubic pieces,
    1.3e-5 along this orbit (the 30 s cubic spline before: 1.9e-5 on the same points)."""
    err = _table_error(PiecewiseExponentialAtmosphere().density, tables.LAYERED_DENSITY_PIECES, 11200.0)
    assert err < 1.9e-5


def test_breaks_cut_the_pieces_where_the_field_jumps():
    """A field with a jump: with the jump as a break no piece straddles it, the piece ending
    there takes the value just before it, and the table is the smooth field on both sides."""
    smooth = lambda t: np.sin(t / 300.0)  # noqa: E731
    field = lambda time, r: smooth((time - EPOCH).to_value(u.s)) + ((time - EPOCH).to_value(u.s) >= 1000.0)  # noqa: E731
    pieces = tables.Pieces(600.0, 12)
    table = tables.tabulate_along_orbit(ORBIT, 0.0, 2500.0, pieces, field, breaks=[1000.0, -5.0, 3000.0])
    assert 1000.0 in table[:, 0] and table[0, 0] == 0.0 and table[-1, 0] == 2500.0
    x = np.concatenate([np.linspace(0.0, 2500.0, 1001), [999.0, 999.9, 1000.1]])
    x = x[x != 1000.0]                  # (at the knot itself, either side's value)
    want = smooth(x) + (x >= 1000.0)
    # (the end value before the break is the field BREAK_LEAD earlier: off by f' 1e-3 s ~ 3e-6 here)
    np.testing.assert_allclose(ke.piece_eval_many(table, x, 1)[:, 0], want, rtol=0, atol=5e-6)
    plain = tables.tabulate_along_orbit(ORBIT, 0.0, 2500.0, pieces, field)
    assert np.abs(ke.piece_eval_many(plain, x, 1)[:, 0] - want).max() > 0.05      # it rings without the break


def test_nrlmsis_density_across_midnight():
    """NRLMSIS's density jumps at each UTC midnight (its day of the year, 2.6e-3 at 400 km): the
    density table has a knot there and holds the library's values on both sides."""
    from orbatt.torques import EnvironmentTorques, Facet

    epoch = Time("2024-03-19T23:50:00", scale="utc")
    orbit = KeplerOrbit(6778.137 * u.km, 0.0005, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, epoch=epoch)
    atm = NRLMSIS(150.0, 150.0, 4.0)
    env = EnvironmentTorques(orbit, 1200.0 * u.s, facets=[Facet(0.01 * u.m**2, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0] * u.m)],
                             drag=True, atmosphere=atm)
    table = env.field_table("density")
    assert np.isclose(table[:, 0], 600.0, rtol=0, atol=1e-6).sum() == 1      # midnight, 600 s after the epoch
    x = np.concatenate([np.linspace(0.0, 1200.0, 241), [599.0, 599.5, 600.0, 600.5, 601.0]])
    got = ke.piece_eval_many(table, x, 1)[:, 0] * 1e-9
    ref = atm.density(epoch + x * u.s, orbit.state(x)[0])
    assert np.abs(got / ref - 1.0).max() < 5e-5

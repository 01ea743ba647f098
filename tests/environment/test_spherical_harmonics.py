"""orbatt.environment.spherical_harmonics against ppigrf itself: the coefficient file read
without pandas and the Schmidt semi-normalized Legendre functions are ppigrf's bit for bit,
and a magnetic-field table is built without importing ppigrf or pandas (issue 25)."""
import subprocess
import sys

import numpy as np
import pytest

from orbatt.environment.spherical_harmonics import igrf14_file, read_shc, schmidt_legendre

ppigrf = pytest.importorskip("ppigrf.ppigrf")


def test_read_shc_is_ppigrfs():
    times, g, h, keys = read_shc(igrf14_file())
    gdf, hdf = ppigrf.read_shc(ppigrf.shc_fn_igrf14)
    assert keys == [tuple(int(x) for x in k) for k in gdf.columns]
    np.testing.assert_array_equal(g, gdf.values.astype(np.float64))
    np.testing.assert_array_equal(h, hdf.values.astype(np.float64))
    np.testing.assert_array_equal(times, gdf.index.values.astype("datetime64[ns]").astype(np.int64) / 1e9)
    assert g.shape == (27, 104) and np.all(h[:, [k[1] == 0 for k in keys]] == 0.0)


def test_decimal_years_as_ppigrf_counts_them(tmp_path):
    """Epochs inside a year (not in IGRF-14's file) are placed as ppigrf places them."""
    f = tmp_path / "x.shc"
    f.write_text("# test\n1 1 3 2 1\n 2020.5 2021.25 2024.75\n 1 0 1 2 3\n 1 1 4 5 6\n 1 -1 7 8 9\n")
    times, g, h, keys = read_shc(f)
    ref = ppigrf.read_shc(str(f))[0].index.values.astype("datetime64[ns]").astype(np.int64) / 1e9
    np.testing.assert_array_equal(times, ref)
    assert keys == [(1, 0), (1, 1)] and h[:, 1].tolist() == [7.0, 8.0, 9.0]


def test_schmidt_legendre_is_ppigrfs():
    keys = read_shc(igrf14_file())[3]
    theta = np.concatenate([np.linspace(0.0, 180.0, 181), np.random.default_rng(3).uniform(0.0, 180.0, 500)])
    p, dp = schmidt_legendre(theta, keys)
    p_ref, dp_ref = ppigrf.get_legendre(theta, keys)
    np.testing.assert_array_equal(p, p_ref)
    np.testing.assert_array_equal(dp, dp_ref)
    # P_1^0 = cos, P_1^1 = sin (Schmidt semi-normalized), P_2^0 = (3 cos^2 - 1) / 2
    th = np.radians(theta)
    np.testing.assert_allclose(p[:, keys.index((1, 0))], np.cos(th), atol=1e-15)
    np.testing.assert_allclose(p[:, keys.index((1, 1))], np.sin(th), atol=1e-15)
    np.testing.assert_allclose(p[:, keys.index((2, 0))], 1.5 * np.cos(th) ** 2 - 0.5, atol=1e-15)


def test_field_table_imports_neither_ppigrf_nor_pandas():
    code = """
import sys
import numpy as np
from astropy import units as u
from astropy.time import Time
from orbatt.environment.magnetic import IGRFField
t = Time("2025-03-20T00:00:00", scale="utc") + np.arange(3) * 60.0 * u.s
b = IGRFField().field(t, np.array([[6778.0, 0.0, 0.0], [0.0, 6778.0, 0.0], [0.0, 0.0, 6778.0]]))
assert b.shape == (3, 3) and np.all(np.abs(b) < 1e-4)
print(sorted(m for m in sys.modules if m.split('.')[0] in ('ppigrf', 'pandas')))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"

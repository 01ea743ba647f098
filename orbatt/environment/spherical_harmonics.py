"""IGRF's coefficient file and the Schmidt semi-normalized Legendre functions, without pandas.

``ppigrf`` (the source of orbatt's IGRF-14 coefficients and of its Legendre recursion) imports
pandas at its own import, ~0.35 s of every run with a magnetic field. This module reads the
same ``.shc`` file that ships with ``ppigrf`` (found without importing it) and computes the same
Legendre functions with the same arithmetic, so the field is ``ppigrf``'s bit for bit
(``tests/environment/test_spherical_harmonics.py`` compares both with ``ppigrf``'s own
``read_shc`` and ``get_legendre``).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["igrf14_file", "read_shc", "schmidt_legendre"]


def igrf14_file():
    """Path of ``IGRF14.shc``, the coefficient file of the installed ``ppigrf`` (not imported)."""
    import importlib.util

    spec = importlib.util.find_spec("ppigrf")
    if spec is None or not spec.submodule_search_locations:
        raise InputError("magnetic_field: the IGRF coefficients come with the package ppigrf, which is not "
                         "installed; pip install ppigrf")
    return Path(list(spec.submodule_search_locations)[0]) / "IGRF14.shc"


def _unix_seconds_of_year(year):
    """UTC seconds since 1970 of the decimal year ``year`` (a fraction of the year's days, as
    ``ppigrf.yearfrac_to_datetime`` counts them)."""
    whole = int(year)
    start = np.datetime64(f"{whole:04d}-01-01T00:00:00", "ns").astype(np.int64)
    leap = whole % 4 == 0 and (whole % 100 != 0 or whole % 400 == 0)
    frac_ns = round((year - whole) * (365 + leap) * 86400e9)
    return (start + frac_ns) / 1e9


def read_shc(path):
    """The coefficients of a spherical-harmonic ``.shc`` file (the format of ``ppigrf``'s files).

    Parameters
    ----------
    path : str or Path
        The file: ``#`` comment lines, a line ``N_MIN N_MAX N_TIMES ...``, a line of the
        epochs (decimal years), then one line ``n m value...`` per coefficient (``m < 0``: the
        ``h`` coefficient of order ``|m|``).

    Returns
    -------
    times : ndarray (n_epochs,)
        The epochs, UTC seconds since 1970 (no leap seconds).
    g, h : ndarray (n_epochs, n_coefficients)
        Gauss coefficients (the file's unit, nT for IGRF); ``h`` is 0 for ``m = 0``.
    keys : list of (n, m)
        Degree and order of each column, in the file's order of the ``g`` lines.
    """
    lines = [ln for ln in Path(path).read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    years = [float(x) for x in lines[1].split()]
    coeffs = {}
    for ln in lines[2:]:
        parts = ln.split()
        coeffs[(int(parts[0]), int(parts[1]))] = [float(x) for x in parts[2:]]
    keys = [k for k in coeffs if k[1] >= 0]
    g = np.array([coeffs[k] for k in keys], dtype=np.float64).T
    h = np.array([coeffs[(n, -m)] if m > 0 else [0.0] * len(years) for n, m in keys], dtype=np.float64).T
    times = np.array([_unix_seconds_of_year(y) for y in years])
    return times, np.ascontiguousarray(g), np.ascontiguousarray(h), keys


def schmidt_legendre(theta_deg, keys):
    """Schmidt semi-normalized associated Legendre functions and their colatitude derivatives.

    The recursion of Wertz, *Spacecraft Attitude Determination and Control* (1978), App. H,
    operation for operation as ``ppigrf.ppigrf.get_legendre`` writes it (the same bits).

    Parameters
    ----------
    theta_deg : array_like
        Colatitudes (deg), any shape (flattened to ``N``).
    keys : list of (n, m)
        Degree and order of each column.

    Returns
    -------
    P, dP : ndarray (N, len(keys))
        ``P_n^m(cos theta)`` and ``dP_n^m / d theta`` (per radian).
    """
    nmax = max(k[0] for k in keys)
    mmax = max(k[1] for k in keys)
    theta = np.radians(np.asarray(theta_deg, dtype=np.float64).flatten()[:, None])
    sinth, costh = np.sin(theta), np.cos(theta)
    zero = np.zeros_like(theta)
    P = {(0, 0): np.ones_like(theta)}
    dP = {(0, 0): zero}
    S = {(0, 0): 1.0}
    for n in range(1, nmax + 1):
        for m in range(0, min(n + 1, mmax + 1)):
            if n == m:
                P[n, n] = sinth * P[n - 1, m - 1]
                dP[n, n] = sinth * dP[n - 1, m - 1] + costh * P[n - 1, n - 1]
            elif n == 1:
                P[n, m] = costh * P[n - 1, m]
                dP[n, m] = costh * dP[n - 1, m] - sinth * P[n - 1, m]
            else:
                knm = ((n - 1) ** 2 - m ** 2) / ((2 * n - 1) * (2 * n - 3))
                p2, dp2 = P.get((n - 2, m), zero), dP.get((n - 2, m), zero)
                P[n, m] = costh * P[n - 1, m] - knm * p2
                dP[n, m] = costh * dP[n - 1, m] - sinth * P[n - 1, m] - knm * dp2
            if m == 0:
                S[n, 0] = S[n - 1, 0] * (2.0 * n - 1) / n
            else:
                S[n, m] = S[n, m - 1] * math.sqrt((n - m + 1) * (int(m == 1) + 1.0) / (n + m))
    out_p = np.hstack([P[k] * S[k] if k != (0, 0) else P[k] for k in keys])
    out_dp = np.hstack([dP[k] * S[k] if k != (0, 0) else dP[k] for k in keys])
    return out_p, out_dp

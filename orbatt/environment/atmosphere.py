"""Atmospheric density along an orbit: exponential, piecewise exponential (Vallado) and
NRLMSIS 2.1 (through ``pymsis``).

Every model answers ``density(t, r_gcrs_km) -> rho`` (kg/m^3, shape ``(N,)``) for astropy
instants ``t`` (``(N,)`` or scalar) and geocentric GCRS positions ``r_gcrs_km`` ``(N, 3)``
in km. The two exponential models depend on ``|r|`` only and also give
:meth:`kernel_params` for the compiled :func:`orbatt.core.environment.exponential_density`
and :func:`orbatt.core.environment.piecewise_density`; NRLMSIS is sampled along the orbit
and interpolated (:mod:`orbatt.environment.tables`).

Altitude of the exponential models: ``h = |r| - R`` with ``R`` the equatorial radius (a
sphere, as in the issue's formula and Basilisk's ``exponentialAtmosphere``); NRLMSIS uses
the geodetic (WGS84) height.
"""
from __future__ import annotations

import numpy as np
from astropy import units as u

from .. import units as U
from ..errors import InputError
from .frames import R_EARTH_WGS84, as_time_array, as_vectors, geodetic

__all__ = ["ExponentialAtmosphere", "PiecewiseExponentialAtmosphere", "NRLMSIS", "R_EARTH_WGS84",
           "VALLADO_TABLE"]

DENSITY = u.kg / u.m**3

#: Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed. (2013), Table 8-4
#: (exponential atmosphere, from CIRA-72 / US Standard Atmosphere 1976):
#: rows ``(base altitude h0 km, nominal density rho0 kg/m^3, scale height H km)``, a layer a
#: line of the block below.
VALLADO_TABLE = np.array([[float(x) for x in row.split()] for row in """
    h0     rho0        H
    0      1.225       7.249
    25     3.899e-2    6.349
    30     1.774e-2    6.682
    40     3.972e-3    7.554
    50     1.057e-3    8.382
    60     3.206e-4    7.714
    70     8.770e-5    6.549
    80     1.905e-5    5.799
    90     3.396e-6    5.382
    100    5.297e-7    5.877
    110    9.661e-8    7.263
    120    2.438e-8    9.473
    130    8.484e-9    12.636
    140    3.845e-9    16.149
    150    2.070e-9    22.523
    180    5.464e-10   29.740
    200    2.789e-10   37.105
    250    7.248e-11   45.546
    300    2.418e-11   53.628
    350    9.518e-12   53.298
    400    3.725e-12   58.515
    450    1.585e-12   60.828
    500    6.967e-13   63.822
    600    1.454e-13   71.835
    700    3.614e-14   88.667
    800    1.170e-14   124.64
    900    5.245e-15   181.05
    1000   3.019e-15   268.00
""".strip().splitlines()[1:]])


def _positive(value, unit, name, example, allow_plain=False):
    out = U.strip(value, unit, name, allow_plain=allow_plain)
    if out.shape != () or not out > 0.0:
        kind = U.dimension_phrase(unit).split(" ", 1)[1]
        raise InputError(f"{name}: {value!r} must be one positive {kind}, e.g. '{example}'")
    return float(out)


def _radii(r_gcrs_km):
    return np.linalg.norm(as_vectors(r_gcrs_km, "r_gcrs_km", u.km), axis=1)


class ExponentialAtmosphere:
    """``rho = density0 exp(-(h - altitude0) / scale_height)``, ``h = |r| - body_radius``.

    Parameters
    ----------
    density0 : Quantity (mass density) or str
        Density at ``altitude0``, e.g. ``"3e-12 kg/m3"``.
    altitude0 : Quantity (length) or str
        Reference altitude above the sphere of radius ``body_radius``.
    scale_height : Quantity (length) or str
        Scale height, ``> 0``.
    body_radius : Quantity (length), str or float (km), optional
        Radius of the sphere altitudes are counted from; default WGS84's equatorial radius
        (6378.137 km).
    """

    name = "exponential"

    def __init__(self, density0, altitude0, scale_height, body_radius=R_EARTH_WGS84):
        self.density0 = _positive(density0, DENSITY, "density0", "3e-12 kg/m3")
        alt = U.strip(altitude0, U.LENGTH, "altitude0")
        if alt.shape != ():
            raise InputError(f"altitude0: expected one altitude, got {altitude0!r}")
        self.altitude0 = float(alt)
        self.scale_height = _positive(scale_height, U.LENGTH, "scale_height", "60 km")
        self.body_radius = _positive(body_radius, U.LENGTH, "body_radius", "6378.137 km", allow_plain=True)

    def kernel_params(self):
        """``[rho0 kg/m^3, h0 km, H km, R km]`` for
        :func:`orbatt.core.environment.exponential_density`."""
        return np.array([self.density0, self.altitude0, self.scale_height, self.body_radius])

    def density(self, t, r_gcrs_km):
        """Density (kg/m^3), shape ``(N,)``; ``t`` is not used (kept for the common
        signature)."""
        h = _radii(r_gcrs_km) - self.body_radius
        return self.density0 * np.exp(-(h - self.altitude0) / self.scale_height)

    def __repr__(self):
        return (f"ExponentialAtmosphere(density0='{self.density0:g} kg/m3', altitude0='{self.altitude0:g} km', "
                f"scale_height='{self.scale_height:g} km', body_radius={self.body_radius!r})")


class PiecewiseExponentialAtmosphere:
    """The piecewise exponential atmosphere of Vallado (2013), Table 8-4.

    Layer ``k`` (base altitude ``h0_k``) serves ``h0_k <= h < h0_{k+1}``:
    ``rho = rho0_k exp(-(h - h0_k) / H_k)``, ``h = |r| - body_radius``; the first layer also
    below 0 km and the last (1000 km) above; the 28 layers from 0 to 1000 km are the rows of
    :data:`VALLADO_TABLE`.

    Source: D. A. Vallado, *Fundamentals of Astrodynamics and Applications*, 4th ed.,
    Microcosm Press, 2013, Table 8-4 (CIRA-72 below 25 km the US Standard Atmosphere 1976).

    Parameters
    ----------
    body_radius : Quantity (length), str or float (km), optional
        Default WGS84's equatorial radius (6378.137 km), as in Vallado.
    """

    name = "piecewise-exponential"
    table = VALLADO_TABLE

    def __init__(self, body_radius=R_EARTH_WGS84):
        self.body_radius = _positive(body_radius, U.LENGTH, "body_radius", "6378.137 km", allow_plain=True)

    def kernel_params(self):
        """``[R, h0_0, rho0_0, H_0, h0_1, ...]`` (km, kg/m^3, km) for
        :func:`orbatt.core.environment.piecewise_density`."""
        return np.concatenate([[self.body_radius], self.table.ravel()])

    def density(self, t, r_gcrs_km):
        """Density (kg/m^3), shape ``(N,)``; ``t`` is not used."""
        h = _radii(r_gcrs_km) - self.body_radius
        k = np.clip(np.searchsorted(self.table[:, 0], h, side="right") - 1, 0, len(self.table) - 1)
        h0, rho0, H = self.table[k].T
        return rho0 * np.exp(-(h - h0) / H)

    def __repr__(self):
        return f"PiecewiseExponentialAtmosphere(body_radius={self.body_radius!r})"


class NRLMSIS:
    """NRLMSIS 2.1 total mass density through ``pymsis`` (Emmert et al. 2022).

    Space weather is given, never looked up: ``pymsis`` would otherwise download
    CelesTrak's index file. The same values hold for the whole run (daily Ap mode).

    Parameters
    ----------
    f107 : float
        Daily F10.7 solar radio flux of the previous day (sfu), e.g. 150.
    f107a : float
        81-day centred average of F10.7 (sfu).
    ap : float
        Daily geomagnetic Ap index, e.g. 4 (quiet) .. 400 (storm).

    Notes
    -----
    ``pymsis`` passes its inputs in single precision and truncates the time of day to
    whole seconds: densities carry a relative noise of about 1e-7.
    """

    name = "nrlmsis"

    def __init__(self, f107, f107a, ap):
        vals = []
        for name, v, example in (("f107", f107, 150), ("f107a", f107a, 150), ("ap", ap, 4)):
            try:
                x = float(v)
            except (TypeError, ValueError):
                raise InputError(f"{name}: {v!r} is not a number; give e.g. {name} = {example}") from None
            if not (np.isfinite(x) and x >= 0.0):
                raise InputError(f"{name}: {v!r} must be a finite number >= 0, e.g. {name} = {example}")
            vals.append(x)
        self.f107, self.f107a, self.ap = vals

    def density(self, t, r_gcrs_km):
        """Total mass density (kg/m^3), shape ``(N,)``, at geodetic (WGS84) coordinates of
        the GCRS positions (:func:`orbatt.environment.frames.geodetic`)."""
        from pymsis import calculate

        r = as_vectors(r_gcrs_km, "r_gcrs_km", u.km)
        t = as_time_array(t, r.shape[0])
        lat, lon, alt = geodetic(t, r)
        n = r.shape[0]
        # UTC calendar time from Unix seconds (a leap second 23:59:60 runs on continuously;
        # astropy's datetime64 conversion refuses it)
        dates = (np.asarray(t.utc.unix, dtype=np.float64) * 1e6).astype(np.int64).astype("datetime64[us]")
        out = calculate(dates, lon, lat, alt, np.full(n, self.f107), np.full(n, self.f107a),
                        np.full((n, 7), self.ap), version=2.1)
        return np.asarray(out[:, 0], dtype=np.float64)

    def __repr__(self):
        return f"NRLMSIS(f107={self.f107:g}, f107a={self.f107a:g}, ap={self.ap:g})"

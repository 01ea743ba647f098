"""The Sun: its geocentric position (astropy) and the shadow function (conical or cylindrical).

* :func:`sun_position` - geocentric GCRS position of the Sun (km) from astropy's built-in
  ephemeris (``get_body("sun", t)`` with ``solar_system_ephemeris`` ``"builtin"``: ERFA's
  ``epv00``, about 1e-7 au in position). Nothing is downloaded. The position is the one
  astropy's GCRS gives (light-time corrected; the apparent direction differs from the
  geometric one by the aberration, ~20 arcsec, which does not matter for radiation pressure).
* :func:`shadow` - the fraction ``nu`` of the solar disc seen from the satellite (0 umbra,
  1 full Sun): conical (umbra and penumbra, apparent-disc overlap, Montenbruck & Gill,
  *Satellite Orbits*, 2000, §3.4.2) or cylindrical. Compiled twins:
  :func:`orbatt.core.environment.shadow_conical`, :func:`orbatt.core.environment.shadow_cylindrical`.

Constants: :data:`SRP_FLUX` = 1361 W/m^2 at 1 au (total solar irradiance, IAU 2015
Resolution B3 nominal value; Kopp & Lean 2011), :data:`AU` (km, IAU 2012),
:data:`R_SUN` (km, IAU 2015 nominal), :data:`SPEED_OF_LIGHT` (m/s).
"""
from __future__ import annotations

import numpy as np
from astropy import constants as const
from astropy import units as u

from ..errors import InputError
from .frames import R_EARTH_WGS84, as_time_array, as_vectors, offline_iers

__all__ = ["sun_position", "shadow", "SRP_FLUX", "AU", "R_SUN", "SPEED_OF_LIGHT", "SHADOW_KINDS"]

#: solar flux at 1 au (W/m^2): the IAU 2015 B3 nominal total solar irradiance
SRP_FLUX = 1361.0
#: astronomical unit (km), IAU 2012 Resolution B2
AU = float(const.au.to_value(u.km))
#: nominal solar radius (km), IAU 2015 Resolution B3
R_SUN = float(const.R_sun.to_value(u.km))
#: speed of light (m/s); the radiation pressure at 1 au is SRP_FLUX / SPEED_OF_LIGHT (N/m^2)
SPEED_OF_LIGHT = float(const.c.to_value(u.m / u.s))
#: the shadow models :func:`shadow` knows
SHADOW_KINDS = ("conical", "cylindrical")


def sun_position(t):
    """Geocentric position of the Sun in GCRS components (km).

    Parameters
    ----------
    t : astropy.time.Time
        Instants, shape ``(N,)`` (or scalar, then ``N = 1``).

    Returns
    -------
    ndarray (N, 3)
        km, GCRS (orbatt's inertial ``S`` when an epoch is given).
    """
    from astropy.coordinates import GCRS, get_body, solar_system_ephemeris

    t = as_time_array(t)
    with offline_iers(), solar_system_ephemeris.set("builtin"):
        sun = get_body("sun", t).transform_to(GCRS(obstime=t))
    return np.ascontiguousarray(sun.cartesian.xyz.to_value(u.km).T, dtype=np.float64)


def shadow(r_sat_km, r_sun_km, kind="conical", body_radius=R_EARTH_WGS84, sun_radius=R_SUN):
    """Shadow function ``nu``: the visible fraction of the solar disc (0 umbra ... 1 full Sun).

    Parameters
    ----------
    r_sat_km, r_sun_km : array_like (N, 3) or (3,)
        Satellite and Sun positions relative to the occulting body's centre, same frame, km.
    kind : {"conical", "cylindrical"}
        Conical: the body's and the Sun's apparent discs (radii ``b = asin(R_body / |r_sat|)``,
        ``a = asin(R_sun / |r_sun - r_sat|)``, separation ``c``) and the area of their
        overlap: ``nu = 1`` for ``c >= a + b``, 0 for ``c <= b - a``, else
        ``1 - A / (pi a^2)`` with ``A`` the overlap area (an annular eclipse, ``c <= a - b``,
        gives ``1 - b^2 / a^2``), computed without cancellation (agrees with the compiled
        kernel to ~1e-15). Cylindrical: 0 behind the body within the radius
        ``body_radius`` of the Sun line, else 1.
    body_radius, sun_radius : float
        km; defaults WGS84's equatorial radius and the nominal solar radius.

    Returns
    -------
    ndarray (N,)
        ``nu`` in [0, 1].
    """
    if kind not in SHADOW_KINDS:
        raise InputError(f"kind: {kind!r} is not a shadow model; use one of {', '.join(SHADOW_KINDS)}")
    rs = as_vectors(r_sat_km, "r_sat_km", u.km)
    rsun = as_vectors(r_sun_km, "r_sun_km", u.km)
    rs, rsun = np.broadcast_arrays(rs, rsun)
    if kind == "cylindrical":
        e = rsun / np.linalg.norm(rsun, axis=1)[:, None]
        along = np.sum(rs * e, axis=1)
        perp2 = np.sum(rs * rs, axis=1) - along**2
        return np.where((along < 0.0) & (perp2 < body_radius**2), 0.0, 1.0)
    d = rsun - rs
    dn = np.linalg.norm(d, axis=1)
    rn = np.linalg.norm(rs, axis=1)
    a = np.arcsin(np.minimum(sun_radius / dn, 1.0))
    b = np.arcsin(np.minimum(body_radius / rn, 1.0))
    c = np.arctan2(np.linalg.norm(np.cross(-rs, d), axis=1), np.sum(-rs * d, axis=1))
    with np.errstate(invalid="ignore", divide="ignore"):
        # the overlap as two circular segments r^2 (phi - sin phi) / 2 (see
        # orbatt.core.environment.shadow_conical): chord half-length y from the side
        # differences, phi - sin phi by its series for small phi
        y = 0.5 * np.sqrt(np.maximum((a + b - c) * (b + c - a) * (c + a - b) * (a + b + c), 0.0)) / c
        ta = 2.0 * np.arctan2(y, (c**2 + a**2 - b**2) / (2.0 * c))
        tb = 2.0 * np.arctan2(y, (c**2 + b**2 - a**2) / (2.0 * c))
        area = 0.5 * (a**2 * _phi_minus_sin(ta) + b**2 * _phi_minus_sin(tb))
        partial = 1.0 - area / (np.pi * a**2)
    return np.select([c >= a + b, c <= b - a, c <= a - b], [1.0, 0.0, 1.0 - b**2 / a**2], partial)


def _phi_minus_sin(phi):
    p2 = phi * phi
    series = phi * p2 * (1.0 / 6.0 - p2 * (1.0 / 120.0 - p2 * (1.0 / 5040.0 - p2 * (1.0 / 362880.0
                                                                                    - p2 / 39916800.0))))
    return np.where(phi >= 0.25, phi - np.sin(phi), series)

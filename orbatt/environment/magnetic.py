"""The geomagnetic field along an orbit: IGRF-14 (through ``ppigrf``) and its tilted dipole.

Both models answer ``field(t, r_gcrs_km) -> B``, ``(N, 3)`` in tesla, GCRS (inertial ``S``)
components, for astropy instants ``t`` (shape ``(N,)``) and geocentric GCRS positions in km.
The position is rotated to the Earth-fixed ITRS (:mod:`orbatt.environment.frames`), the
field is evaluated there and rotated back.

Coefficients: the IGRF-14 Gauss coefficients of the file that ships with ``ppigrf``
(``IGRF14.shc``, epochs 1900-2030 every 5 years, the last one from the secular variation),
interpolated linearly in time between epochs as ``ppigrf`` does; reference radius
``a = 6371.2 km``. Times outside 1900-2030 are refused.

* :class:`IGRFField` - the full expansion (degrees 1-13). It evaluates the series of
  ``ppigrf.igrf_gc`` (geocentric radius, colatitude, longitude; Schmidt semi-normalized
  Legendre functions of ``ppigrf.ppigrf.get_legendre``, computed the same way by
  :func:`~orbatt.environment.spherical_harmonics.schmidt_legendre`) with the coefficients of *each* instant,
  which ``ppigrf.igrf_gc`` would do only on a dates x points grid. ``(B_r, B_theta, B_phi)``
  (radial, south, east) become ITRS Cartesian components with the spherical unit vectors at
  the point.
* :class:`DipoleField` - the degree-1 terms ``g10, g11, h11`` frozen at one epoch: a centred
  dipole, ``B = a^3 [3 (m . r^) r^ - m] / r^3`` with ``m = (g11, h11, g10)`` in ITRS
  (``V = a (a/r)^2 (g10 cos theta + (g11 cos phi + h11 sin phi) sin theta)``, ``B = -grad V``).
"""
from __future__ import annotations

import warnings

import numpy as np

from ..epoch import parse_epoch
from ..errors import InputError
from .frames import as_time_array, as_vectors, gcrs_to_itrs, itrs_to_gcrs, rotation_gcrs_to_itrs
from .spherical_harmonics import igrf14_file, read_shc, schmidt_legendre

__all__ = ["GeomagneticField", "IGRFField", "DipoleField", "igrf_coefficients", "check_igrf_instants",
           "IGRF_REFERENCE_RADIUS", "IGRF_SPAN"]

#: IGRF's reference radius (km), as in ``ppigrf``
IGRF_REFERENCE_RADIUS = 6371.2
#: the instants IGRF-14 covers (UTC dates), those of ppigrf's coefficient file
IGRF_SPAN = ("1900-01-01", "2030-01-01")
#: nT -> T
NANOTESLA = 1e-9
#: points per block of the series evaluation (bounds the memory of the design matrices)
_BLOCK = 4096


def _coefficient_table():
    """``(t_utc_unix_seconds, g, h, keys)`` of ppigrf's IGRF-14 file: ``g``, ``h`` of shape
    ``(n_epochs, n_coefficients)`` (nT), ``keys`` the ``(n, m)`` of each column (read without
    importing ppigrf and pandas: :mod:`orbatt.environment.spherical_harmonics`)."""
    return read_shc(igrf14_file())


_TABLE = None


def _table():
    global _TABLE
    if _TABLE is None:
        _TABLE = _coefficient_table()
    return _TABLE


def _unix_seconds(t, name):
    """UTC seconds since 1970 of astropy instants, checked against IGRF's span."""
    times = _table()[0]
    # UTC calendar seconds (no leap seconds), as ppigrf's datetimes count them: astropy's
    # Unix time, a float (a leap second 23:59:60 runs on continuously from 23:59:59; no
    # datetime64[ns] overflow beyond 2262)
    with warnings.catch_warnings():  # ERFA's "dubious year" far from today: refused below
        warnings.simplefilter("ignore")
        s = np.atleast_1d(np.asarray(t.utc.unix, dtype=np.float64))
    if np.any(s < times[0]) or np.any(s > times[-1]):
        lo, hi = (_iso(x) for x in (s.min(), s.max()))
        when = lo if lo == hi else f"{lo}..{hi}"
        raise InputError(f"{name}: {when} is outside IGRF-14's span "
                         f"{IGRF_SPAN[0]}..{IGRF_SPAN[1]}; give instants inside it")
    return s


def check_igrf_instants(t, name="t"):
    """Refuse (:class:`~orbatt.errors.InputError` naming ``name``) astropy instants ``t``
    outside :data:`IGRF_SPAN`; without ERFA's warnings for dates far from today."""
    _unix_seconds(as_time_array(t, name=name), name)


def _iso(unix_seconds):
    """ISO date and time (to the second) of Unix seconds, without ERFA's warnings."""
    return str(np.datetime64(int(unix_seconds), "s"))


def igrf_coefficients(t, name="t"):
    """IGRF-14 Gauss coefficients at astropy instants ``t``, linear in time between epochs.

    Returns
    -------
    g, h : ndarray (N, n_coefficients)
        nT; column ``k`` is degree/order ``keys[k]`` (``h`` is 0 for ``m = 0``).
    keys : list of (n, m)
    """
    t = as_time_array(t, name=name)
    s = _unix_seconds(t, name)
    times, g, h, keys = _table()
    gi = np.stack([np.interp(s, times, g[:, k]) for k in range(g.shape[1])], axis=-1)
    hi = np.stack([np.interp(s, times, h[:, k]) for k in range(h.shape[1])], axis=-1)
    return gi, hi, keys


def _spherical(x):
    """Radius (km), colatitude and east longitude (deg) of ITRS positions ``x`` (N, 3), and
    the unit vectors ``r^, theta^ (south), phi^ (east)`` in ITRS, each (N, 3)."""
    r = np.linalg.norm(x, axis=1)
    rho = np.hypot(x[:, 0], x[:, 1])
    theta = np.arctan2(rho, x[:, 2])
    phi = np.arctan2(x[:, 1], x[:, 0])
    ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    e_r = np.stack([st * cp, st * sp, ct], axis=1)
    e_t = np.stack([ct * cp, ct * sp, -st], axis=1)
    e_p = np.stack([-sp, cp, np.zeros_like(sp)], axis=1)
    return r, np.degrees(theta), np.degrees(phi), e_r, e_t, e_p


def _series(r, theta_deg, phi_deg, g, h, keys):
    """``(B_r, B_theta, B_phi)`` (nT) of the spherical-harmonic series, one coefficient row
    per point: the formulas of ``ppigrf.igrf_gc``."""
    a = IGRF_REFERENCE_RADIUS
    n = np.array([k[0] for k in keys], dtype=np.float64)[None, :]
    m = np.array([k[1] for k in keys], dtype=np.float64)[None, :]
    P, dP = schmidt_legendre(theta_deg, keys)
    phi = np.radians(phi_deg)[:, None]
    cmp, smp = np.cos(m * phi), np.sin(m * phi)
    ratio = (a / r)[:, None]
    gc = g * cmp + h * smp              # g cos(m phi) + h sin(m phi)
    gs = -g * smp + h * cmp             # d/dphi of the above, over m
    b_r = np.sum((n + 1.0) * ratio ** (n + 2.0) * P * gc, axis=1)
    b_t = -np.sum(ratio ** (n + 2.0) * dP * gc, axis=1)
    b_p = -np.sum(ratio ** (n + 2.0) * m * P * gs, axis=1) / np.sin(np.radians(theta_deg))
    return b_r, b_t, b_p


class GeomagneticField:
    """Base of the field models: :meth:`field` rotates the positions to ITRS, calls the
    subclass's ``field_itrs(t, r_itrs_km) -> B (N, 3) T, ITRS`` and rotates ``B`` back."""

    def check_instants(self, t):
        """Refuse instants the model does not cover (before any frame transform)."""

    def field(self, t, r_gcrs_km):
        """Geomagnetic field at geocentric GCRS positions.

        Parameters
        ----------
        t : astropy.time.Time
            Instants, shape ``(N,)`` (or scalar): the Earth's orientation (and, for IGRF,
            the coefficients; 1900-2030).
        r_gcrs_km : array_like (N, 3)
            Positions in GCRS, km.

        Returns
        -------
        ndarray (N, 3)
            ``B`` in tesla, GCRS components.
        """
        r = as_vectors(r_gcrs_km, "r_gcrs_km")
        t = as_time_array(t, r.shape[0])
        self.check_instants(t)
        rot = rotation_gcrs_to_itrs(t)      # once for both ways
        return itrs_to_gcrs(t, self.field_itrs(t, gcrs_to_itrs(t, r, rot)), rot)


class IGRFField(GeomagneticField):
    """The International Geomagnetic Reference Field (IGRF-14, degrees 1-13) via ``ppigrf``.

    Parameters
    ----------
    max_degree : int, optional
        Truncate the series at this degree (1..13; default 13, the full model).

    Notes
    -----
    The coefficients follow each instant (secular variation), unlike :class:`DipoleField`.
    Not defined at the poles' axis itself (``sin theta = 0``), as in ``ppigrf``.
    """

    name = "igrf"

    def __init__(self, max_degree=13):
        if not (isinstance(max_degree, (int, np.integer)) and 1 <= max_degree <= 13):
            raise InputError(f"max_degree: {max_degree!r} must be an integer in 1..13 (IGRF's degrees)")
        self.max_degree = int(max_degree)

    def check_instants(self, t):
        _unix_seconds(t, "t")

    def field_itrs(self, t, r_itrs_km):
        """Field (T) in ITRS components at Earth-fixed positions ``r_itrs_km`` (N, 3)."""
        x = as_vectors(r_itrs_km, "r_itrs_km")
        t = as_time_array(t, x.shape[0])
        g, h, keys = igrf_coefficients(t)
        use = np.array([k[0] <= self.max_degree for k in keys])
        keys = [k for k, ok in zip(keys, use) if ok]
        g, h = g[:, use], h[:, use]
        out = np.empty_like(x)
        for lo in range(0, x.shape[0], _BLOCK):
            sl = slice(lo, lo + _BLOCK)
            r, th, ph, e_r, e_t, e_p = _spherical(x[sl])
            b_r, b_t, b_p = _series(r, th, ph, g[sl], h[sl], keys)
            out[sl] = b_r[:, None] * e_r + b_t[:, None] * e_t + b_p[:, None] * e_p
        return out * NANOTESLA

    def __repr__(self):
        return f"IGRFField(max_degree={self.max_degree})"


class DipoleField(GeomagneticField):
    """A centred, tilted dipole: IGRF-14's degree-1 coefficients ``g10, g11, h11`` at ``epoch``.

    The dipole is fixed in the Earth (ITRS) and keeps the coefficients of ``epoch`` at every
    instant; it turns with the Earth. Its field equals IGRF truncated to degree 1 at
    ``epoch`` (``tests/environment/test_magnetic_field.py``).

    Parameters
    ----------
    epoch : astropy.time.Time or str
        The instant of the coefficients (a string is parsed as UTC), inside 1900-2030.

    Attributes
    ----------
    coefficients : ndarray (3,)
        ``(g10, g11, h11)`` in nT.
    moment_itrs : ndarray (3,)
        ``m = (g11, h11, g10)`` (nT), ITRS components: ``B = (a / r)^3 [3 (m.r^) r^ - m]``
        (``-m`` is the direction of the Earth's dipole moment).
    """

    name = "dipole"

    def __init__(self, epoch):
        self.epoch = parse_epoch(epoch, "epoch")
        if self.epoch is None:
            raise InputError("epoch: the dipole needs the epoch of its IGRF coefficients, e.g. '2024-01-01T00:00:00'")
        g, h, keys = igrf_coefficients(self.epoch, "epoch")
        self.coefficients = np.array([g[0, keys.index((1, 0))], g[0, keys.index((1, 1))],
                                      h[0, keys.index((1, 1))]])
        g10, g11, h11 = self.coefficients
        self.moment_itrs = np.array([g11, h11, g10])

    def field_itrs(self, t, r_itrs_km):
        """Field (T) in ITRS components at Earth-fixed positions ``r_itrs_km`` (N, 3); the
        dipole does not change with ``t``."""
        x = as_vectors(r_itrs_km, "r_itrs_km")
        r = np.linalg.norm(x, axis=1)[:, None]
        e = x / r
        m = self.moment_itrs[None, :]
        b = (IGRF_REFERENCE_RADIUS / r) ** 3 * (3.0 * np.sum(m * e, axis=1)[:, None] * e - m)
        return b * NANOTESLA

    def __repr__(self):
        return f"DipoleField(epoch={self.epoch.utc.isot!r})"

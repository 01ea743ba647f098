"""Earth-fixed frames and geodetic coordinates along an orbit, through astropy.

orbatt's inertial frame ``S`` is astropy's ``GCRS`` (geocentric) whenever an epoch is given
(``docs/design.md`` §11); the field libraries want Earth-fixed coordinates (``ITRS``) or geodetic
ones (WGS84). Every function here takes the instants as an astropy ``Time`` array ``t`` of
shape ``(N,)`` (or a scalar ``Time``, used for every row) and vectors as float arrays
``(N, 3)`` in km (positions) or any unit (free vectors such as a magnetic field).

GCRS -> ITRS for a geocentric position is a rotation (bias-precession-nutation, Earth
rotation, polar motion): :func:`rotation_gcrs_to_itrs` takes that matrix from astropy (the
images of the three basis vectors) and the other functions apply it, so positions and free
vectors go through the same matrix.

Earth orientation data come from the tables that ship with astropy (``astropy-iers-data``);
nothing is downloaded (:func:`offline_iers`). Outside the tables' span astropy extrapolates
(UT1-UTC held, mean polar motion) and warns; the error is then of the order of an arcsecond
in the Earth-fixed longitude.
"""
from __future__ import annotations

import contextlib

import numpy as np
from astropy import units as u

from .. import units as U
from ..errors import InputError

__all__ = ["offline_iers", "load_earth_orientation", "earth_orientation_cache", "as_time_array", "as_vectors",
           "rotation_gcrs_to_itrs", "rotation_gcrs_to_itrs_astropy", "celestial_to_intermediate", "gcrs_to_itrs", "itrs_to_gcrs", "geodetic",
           "ground_point_gcrs", "geodetic_up_gcrs",
           "EARTH_ROTATION_RATE", "R_EARTH_WGS84", "DatesWarning", "one_dates_warning"]

#: Earth's equatorial radius (km), WGS84 ``a``: the sphere below the exponential atmospheres
#: and the default occulting body of the shadow function
R_EARTH_WGS84 = 6378.137
#: Earth's mean rotation rate (rad/s) relative to the inertial frame (IERS Conventions 2010,
#: the value of the WGS84/GRS80 ``omega``), for a co-rotating atmosphere ``omega_E x r``.
EARTH_ROTATION_RATE = 7.292115e-5


@contextlib.contextmanager
def offline_iers():
    """Context in which astropy uses only its bundled Earth orientation tables: no download
    (``iers.conf.auto_download = False``) and no error for predictions older than 30 days
    (``auto_max_age = None``); the table itself parsed once per installation
    (:func:`load_earth_orientation`)."""
    from astropy.utils import iers

    with iers.conf.set_temp("auto_download", False), iers.conf.set_temp("auto_max_age", None):
        load_earth_orientation()
        yield


#: where this process's Earth orientation table came from: None (not loaded yet), "cache" or
#: "astropy" (parsed, and the cache written)
EOP_SOURCE = None


def earth_orientation_cache():
    """The cache file of the parsed Earth orientation table, named for the astropy and
    ``astropy-iers-data`` versions that made it."""
    import hashlib

    import astropy

    try:
        from importlib.metadata import version

        data = version("astropy-iers-data")
    except Exception:  # noqa: BLE001 - no such distribution: astropy's own version names it
        data = "?"
    key = hashlib.sha1(f"{astropy.__version__}|{data}".encode()).hexdigest()[:16]
    from ..cachedir import cache_folder

    return cache_folder() / f"iers-{key}.pickle"


def load_earth_orientation():
    """Make astropy's Earth orientation table (UT1 - UTC, polar motion) this process's, from
    orbatt's cache when it is there: astropy parses its bundled text table in ~1-2.5 s at the
    first UT1 of each process; the parsed table is kept as a pickle beside numba's cache
    (:func:`earth_orientation_cache`, written atomically; an unreadable one is parsed again).
    Call inside :func:`offline_iers`'s settings."""
    global EOP_SOURCE
    if EOP_SOURCE is not None:
        return
    import os
    import pickle

    from astropy.utils import iers

    path = earth_orientation_cache()
    table = None
    try:
        table = pickle.loads(path.read_bytes())
        if not isinstance(table, iers.IERS):
            table = None
    except Exception:  # noqa: BLE001 - missing or unreadable: parse the table again
        table = None
    if table is not None:
        iers.earth_orientation_table.set(table)
        EOP_SOURCE = "cache"
        return
    table = iers.earth_orientation_table.get()
    EOP_SOURCE = "astropy"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_bytes(pickle.dumps(table, protocol=pickle.HIGHEST_PROTOCOL))
        os.replace(tmp, path)
    except OSError:  # a read-only cache: parse in every process
        pass


class DatesWarning(UserWarning):
    """The instants of a run lie outside astropy's bundled Earth orientation or leap-second
    tables: the frame rotations (and the Sun) extrapolate them."""


@contextlib.contextmanager
def one_dates_warning(what):
    """Gather astropy's and ERFA's warnings about dates outside their tables (one per call and
    quantity: tens of lines over a run's environment tables) into one :class:`DatesWarning`
    naming ``what`` (e.g. the epoch); other warnings pass through."""
    import warnings

    from astropy.utils.exceptions import AstropyWarning
    from erfa import ErfaWarning

    caught = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            yield
    finally:  # also when the body raises: the warnings it gave still come out
        _replay(caught, what, ErfaWarning, AstropyWarning)


def _replay(caught, what, *date_categories):
    """Re-emit the warnings ``caught`` once each, those of ``date_categories`` as one
    :class:`DatesWarning` about ``what``."""
    import warnings

    dates = [w for w in caught if issubclass(w.category, date_categories)]
    seen = set()
    for w in caught:
        key = (w.category, str(w.message))
        if w not in dates and key not in seen:
            seen.add(key)
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if dates:
        said = " ".join(str(dates[0].message).split())[:160]
        warnings.warn(f"{what} lies outside the Earth orientation and leap-second tables bundled with astropy; the "
                      f"frames are extrapolated (arcsecond level; astropy said: {said})", DatesWarning, stacklevel=4)


def as_time_array(t, n=None, name="t"):
    """``t`` as a 1-D astropy ``Time`` of length ``n`` (a scalar ``Time`` is repeated).

    Raises
    ------
    InputError
        ``t`` is not a ``Time`` or its length is not ``n``.
    """
    from astropy.time import Time

    if not isinstance(t, Time):
        raise InputError(f"{name}: expected an astropy Time array, got {type(t).__name__}; "
                         "build one with astropy.time.Time(epoch) + seconds * u.s")
    if t.ndim == 0:
        return t.reshape((1,)) if n is None else t.reshape((1,))[np.zeros(n, dtype=int)]
    if t.ndim != 1 or (n is not None and t.shape[0] != n):
        raise InputError(f"{name}: expected a Time array of shape ({n},), got shape {t.shape}; "
                         "give one instant per row of the positions")
    return t


def as_vectors(v, name, unit=None):
    """``v`` as a float64 array ``(N, 3)`` (a single 3-vector becomes ``(1, 3)``); a
    Quantity is converted to ``unit`` first.

    Raises
    ------
    InputError
        Wrong shape, wrong dimension or non-finite values.
    """
    if isinstance(v, u.Quantity):
        if unit is None:
            raise InputError(f"{name}: give plain numbers here, not a Quantity ({v.unit})")
        try:
            v = v.to_value(unit)
        except u.UnitConversionError:
            raise InputError(f"{name}: {v.unit} is not {U.dimension_phrase(unit)}; give e.g. '7000 {unit}'") from None
    arr = np.asarray(v, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{name}: expected an array of shape (N, 3), got shape {np.shape(v)}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: contains non-finite values; give finite vectors")
    return arr


def rotation_gcrs_to_itrs(t):
    """Rotation matrices ``R`` with ``x_ITRS = R x_GCRS``, shape ``(N, 3, 3)``.

    The IAU 2006/2000A celestial-to-terrestrial matrix of ERFA (``erfa.c2t06a``: bias,
    precession, nutation, Earth rotation angle, polar motion) at the instants' TT and UT1, with
    the polar motion of astropy's bundled IERS table: what astropy's ``GCRS -> ITRS`` transform
    of a geocentric position computes (agreement 3e-16 on a day of minutes), ~20x faster than
    transforming basis vectors with astropy; for many instants the bias-precession-nutation
    part comes from :func:`celestial_to_intermediate`'s nodes (another ~30x on a table of a day
    at 20 s; round-off level). Instants outside the IERS table go through
    astropy's transform (its extrapolation and warnings).

    Parameters
    ----------
    t : astropy.time.Time
        Instants, shape ``(N,)`` or scalar (then ``N = 1``).

    Returns
    -------
    ndarray (N, 3, 3)
        Orthogonal to round-off; columns are the ITRS components of the GCRS basis vectors.
    """
    import erfa
    from astropy.utils import iers

    t = as_time_array(t)
    with offline_iers():
        try:
            xp, yp, status = iers.earth_orientation_table.get().pm_xy(t, return_status=True)
            if np.all(np.asarray(status) >= 0):  # every instant inside the table
                tt, ut1 = t.tt, t.ut1
                # erfa.c2t06a, its steps spelled out (the same bits) with the slowly varying
                # celestial-to-intermediate matrix from celestial_to_intermediate
                rpom = erfa.pom00(xp.to_value(u.rad), yp.to_value(u.rad), erfa.sp00(tt.jd1, tt.jd2))
                R = erfa.c2tcio(celestial_to_intermediate(tt.jd1, tt.jd2), erfa.era00(ut1.jd1, ut1.jd2), rpom)
                return np.ascontiguousarray(np.broadcast_to(R, (t.shape[0], 3, 3)))
        except (ValueError, IndexError):  # astropy's own path below says what is wrong
            pass
    return rotation_gcrs_to_itrs_astropy(t)


#: spacing (days) of the nodes at which :func:`celestial_to_intermediate` evaluates ERFA's
#: ``c2i06a`` for many instants (10 minutes; the shortest nutation periods are ~5 days)
C2I_NODE_STEP = 600.0 / 86400.0
#: fewer instants than this: ``c2i06a`` at each
C2I_DIRECT_BELOW = 64


def celestial_to_intermediate(jd1, jd2):
    """The celestial-to-intermediate matrix (IAU 2006/2000A: bias, precession, nutation;
    ``erfa.c2i06a``) at TT Julian dates ``jd1 + jd2``, shape ``(N, 3, 3)``.

    ``c2i06a`` sums the 1365-term nutation series (~45 us per instant, nearly all of an
    environment table's frame cost). The matrix changes slowly (precession, nutation periods of
    5 days and more), so for many instants it is evaluated at nodes every
    :data:`C2I_NODE_STEP` over their span and each element is interpolated by the not-a-knot
    cubic spline of the environment tables: the interpolation error is below 1e-18 (a term of
    period P and amplitude A: ~ 5/384 A (2 pi h / P)^4), so the result agrees with ``c2i06a``
    at each instant to round-off (<= 1e-15; ``tests/environment/test_frames.py``).
    """
    import erfa

    from ..core.environment import not_a_knot_table

    jd1 = np.asarray(jd1, dtype=np.float64)
    jd2 = np.asarray(jd2, dtype=np.float64)
    x = (jd1 - jd1[0]) + (jd2 - jd2[0])         # days since the first instant
    lo, hi = float(np.min(x)), float(np.max(x))
    n = int(np.ceil((hi - lo) / C2I_NODE_STEP)) + 1
    if x.shape[0] < max(C2I_DIRECT_BELOW, 2 * n) or not np.all(np.isfinite(x)):
        return erfa.c2i06a(jd1, jd2)
    n = max(n, 4)
    nodes = np.linspace(lo, hi, n)
    m = erfa.c2i06a(np.full(n, jd1[0]), jd2[0] + nodes).reshape(n, 9)
    h = nodes[1] - nodes[0]
    i = np.clip(np.floor((x - lo) / h).astype(np.int64), 0, n - 2)
    s = (x - nodes[i])[:, None]
    out = np.empty((x.shape[0], 9))
    for k in range(0, 9, 3):                   # tables of at most 4 components
        c = not_a_knot_table(nodes, np.ascontiguousarray(m[:, k:k + 3]))[i]
        out[:, k:k + 3] = c[:, 1::4] + s * (c[:, 2::4] + s * (c[:, 3::4] + s * c[:, 4::4]))
    return out.reshape(-1, 3, 3)


def rotation_gcrs_to_itrs_astropy(t):
    """:func:`rotation_gcrs_to_itrs` through astropy's frame transform of the GCRS basis
    vectors (1000 km long), for instants outside the IERS table (astropy extrapolates)."""
    from astropy.coordinates import GCRS, ITRS, CartesianRepresentation

    n = t.shape[0]
    tt = t[np.repeat(np.arange(n), 3)]
    basis = np.tile(np.eye(3) * 1000.0, (n, 1))
    with offline_iers():
        g = GCRS(CartesianRepresentation(basis.T * u.km), obstime=tt)
        x = g.transform_to(ITRS(obstime=tt)).cartesian.xyz.to_value(u.km).T / 1000.0
    return np.ascontiguousarray(x.reshape(n, 3, 3).transpose(0, 2, 1))


def gcrs_to_itrs(t, r_gcrs_km, rotation=None):
    """Geocentric GCRS positions (or free vectors) to ITRS components.

    Parameters
    ----------
    t : astropy.time.Time
        Instants, shape ``(N,)`` (or scalar).
    r_gcrs_km : array_like (N, 3)
        GCRS components (km for positions; any unit for a free vector).
    rotation : ndarray (N, 3, 3), optional
        :func:`rotation_gcrs_to_itrs` of ``t`` when the caller has it already (one ERFA
        evaluation for a round trip; ~45 us per instant).

    Returns
    -------
    ndarray (N, 3)
        ITRS components, same unit.
    """
    r = as_vectors(r_gcrs_km, "r_gcrs_km", u.km)
    t = as_time_array(t, r.shape[0])
    return np.einsum("nij,nj->ni", rotation_gcrs_to_itrs(t) if rotation is None else rotation, r)


def itrs_to_gcrs(t, v_itrs, rotation=None):
    """ITRS components of vectors (a field, a position) to GCRS components: the inverse
    rotation of :func:`gcrs_to_itrs` (a free vector is rotated, not translated).

    Parameters
    ----------
    t : astropy.time.Time
        Instants, shape ``(N,)`` (or scalar).
    v_itrs : array_like (N, 3)
        ITRS components, any unit (plain numbers).
    rotation : ndarray (N, 3, 3), optional
        :func:`rotation_gcrs_to_itrs` of ``t`` when the caller has it already.

    Returns
    -------
    ndarray (N, 3)
        GCRS components, same unit.
    """
    v = as_vectors(v_itrs, "v_itrs")
    t = as_time_array(t, v.shape[0])
    return np.einsum("nji,nj->ni", rotation_gcrs_to_itrs(t) if rotation is None else rotation, v)


def ground_point_gcrs(t, latitude, longitude, height):
    """GCRS positions (km, ``(N, 3)``) of a point fixed on the rotating Earth at the instants
    ``t``: geodetic WGS84 ``latitude``, ``longitude`` (rad) and ``height`` (m), to ITRS by ERFA's
    ``gd2gc``, then :func:`itrs_to_gcrs`."""
    import erfa

    t = as_time_array(t)
    x = erfa.gd2gc(1, float(longitude), float(latitude), float(height)) / 1000.0  # WGS84 = 1; m -> km
    return itrs_to_gcrs(t, np.broadcast_to(x, (t.shape[0], 3)))


def geodetic_up_gcrs(t, r_gcrs_km):
    """The geodetic vertical at geocentric GCRS positions: the unit outward normal of the WGS84
    ellipsoid through each point, in GCRS components (``(N, 3)``, plain numbers). Minus it
    points from the point at the geodetic nadir (the point of the ellipsoid below it, where
    the normal meets the surface). ERFA's ``gc2gde`` gives the geodetic latitude ``phi`` and
    longitude ``lambda`` of the ITRS position; the normal is ``(cos phi cos lambda, cos phi sin
    lambda, sin phi)`` in ITRS, rotated back to GCRS by the same matrix (:func:`rotation_gcrs_to_itrs`).

    Parameters
    ----------
    t : astropy.time.Time
        Instants, shape ``(N,)`` (or scalar).
    r_gcrs_km : array_like (N, 3)
        Positions in GCRS, km (above the Earth's centre: not at it).
    """
    import erfa

    r = as_vectors(r_gcrs_km, "r_gcrs_km", u.km)
    t = as_time_array(t, r.shape[0])
    rot = rotation_gcrs_to_itrs(t)
    x = np.einsum("nij,nj->ni", rot, r)
    lon, lat, _ = erfa.gc2gde(WGS84_A_M, WGS84_F, x * 1000.0)
    cl = np.cos(lat)
    n_itrs = np.stack([cl * np.cos(lon), cl * np.sin(lon), np.sin(lat)], axis=-1)
    return np.einsum("nji,nj->ni", rot, n_itrs)


def geodetic(t, r_gcrs_km):
    """Geodetic coordinates (WGS84) of geocentric GCRS positions.

    Parameters
    ----------
    t : astropy.time.Time
        Instants, shape ``(N,)`` (or scalar).
    r_gcrs_km : array_like (N, 3)
        Positions in GCRS, km.

    Returns
    -------
    lat_deg, lon_deg, alt_km : ndarray (N,)
        Geodetic latitude (deg), east longitude in ``[-180, 180)`` (deg) and height above
        the WGS84 ellipsoid (km).
    """
    import erfa

    x = gcrs_to_itrs(t, r_gcrs_km)
    # astropy's EarthLocation.to_geodetic("WGS84") without importing astropy.coordinates, the
    # same operations (tests/environment/test_frames.py): ERFA's gc2gde in metres, the
    # longitude wrapped to [0, 2 pi) rad, then to [-180, 180) deg, as astropy's Longitude does
    lon, lat, h = erfa.gc2gde(WGS84_A_M, WGS84_F, x * 1000.0)
    lon = _wrap(_wrap(lon, _RAD_360, _RAD_360) * _DEG_PER_RAD, 180.0, 360.0)
    return (np.asarray(lat * _DEG_PER_RAD, dtype=np.float64), np.asarray(lon, dtype=np.float64),
            np.asarray(h * 0.001, dtype=np.float64))


#: WGS84 ellipsoid: equatorial radius (m) and flattening, astropy's and ERFA's values
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
#: astropy's unit scales: rad -> deg, and 360 deg in rad
_DEG_PER_RAD = 57.29577951308232
_RAD_360 = 360.0 * 0.017453292519943295


def _wrap(angle, wrap_angle, full):
    """Angles wrapped into ``[wrap_angle - full, wrap_angle)``: astropy's ``Angle.wrap_at``
    arithmetic (the same bits)."""
    floor = wrap_angle - full
    out = np.array(angle, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        wraps = (out - floor) // full
    if np.any(np.isfinite(wraps) & (wraps != 0)):
        out -= wraps * full
        out[out >= wrap_angle] -= full
        out[out < floor] += full
    return out

"""Orbits from a two-line element set (``docs/design.md`` §11): SGP4 (the ``sgp4`` package) gives
the TEME state, astropy rotates it to GCRS (orbatt's inertial frame ``S`` when there is an
epoch), and the orbit is sampled once and interpolated like a REBOUND orbit
(:class:`~orbatt.orbits.sampled.SampledOrbit`)."""
from __future__ import annotations

import contextlib
import math
import os
import re
import warnings

import numpy as np
from astropy import units as u

from .. import units as U
from ..environment.frames import offline_iers
from ..epoch import epoch_string, parse_epoch
from ..errors import InputError
from .base import GM_EARTH
from .sampled import SampledOrbit

__all__ = ["TleOrbit", "TleDatesWarning", "parse_tle", "read_tle_file", "tle_checksum", "tle_epoch",
           "MAX_TLE_DAYS", "MAX_TLE_FILE_BYTES"]

#: most bytes of a TLE file (:func:`read_tle_file`): a name line and two lines are ~170
MAX_TLE_FILE_BYTES = 4096
#: farthest a TLE orbit may reach from the TLE's epoch (days): SGP4's error grows by about
#: 1 to 3 km a day, and after a year the orbit is no longer the satellite's
MAX_TLE_DAYS = 366.0

#: half-width (s) of the central difference of the SGP4 velocity that gives the accelerations
ACCEL_DELTA = 1.0


class TleDatesWarning(UserWarning):
    """A TLE orbit's dates lie outside astropy's bundled Earth orientation or leap-second
    tables: the TEME -> GCRS rotation extrapolates them."""


@contextlib.contextmanager
def _one_dates_warning(span):
    """Gather astropy's and ERFA's warnings about dates outside their tables (one per call
    and quantity: tens of lines) into one :class:`TleDatesWarning` naming the TLE and
    ``span()`` (the dates, text); other warnings pass through."""
    from astropy.utils.exceptions import AstropyWarning
    from erfa import ErfaWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    dates = [w for w in caught if issubclass(w.category, (ErfaWarning, AstropyWarning, TleDatesWarning))]
    for w in caught:
        if w not in dates:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if dates:
        own = [w for w in dates if issubclass(w.category, TleDatesWarning)]
        if own:
            message = str(own[0].message)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                message = (f"tle: the dates {span()} lie outside the Earth orientation and leap-second tables "
                           "bundled with astropy; TEME -> GCRS extrapolates them (arcsecond level; astropy said: "
                           f"{dates[0].message})")
        warnings.warn(message, TleDatesWarning, stacklevel=4)


def tle_checksum(line):
    """The TLE checksum of ``line``'s first 68 characters: the sum of its digits, each ``-``
    counting 1, modulo 10."""
    return sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68]) % 10


def parse_tle(lines, name="tle"):
    """``(title, line1, line2)`` of a TLE given as 2 lines (or 3 with a name line first).

    Checks the line count, each line's length (69 characters), line numbers (``1``, ``2``),
    checksums, the matching catalogue numbers, and that SGP4 accepts the elements.

    Raises
    ------
    InputError
        Naming ``name`` (``"tle"``), the line and the fix.
    """
    if isinstance(lines, str):
        lines = lines.splitlines()
    try:
        lines = [str(x).rstrip() for x in lines if str(x).strip()]
    except TypeError:
        raise InputError(f"{name}: expected the two lines of a TLE as a list of strings, got {lines!r}") from None
    title = ""
    if len(lines) == 3:
        title, lines = lines[0].strip().removeprefix("0 "), lines[1:]
    if len(lines) != 2:
        raise InputError(f"{name}: expected 2 lines (or a name line and 2 lines), got {len(lines)}; "
                         "give ['1 25544U ...', '2 25544 ...']")
    for k, line in enumerate(lines, start=1):
        if len(line) != 69:
            raise InputError(f"{name}: line {k} has {len(line)} characters, not 69: {line!r}")
        if line[0] != str(k) or line[1] != " ":
            raise InputError(f"{name}: line {k} must start with '{k} ', got {line[:2]!r} (lines out of order?)")
        bad = next((j for j, c in enumerate(line) if not " " <= c <= "~"), None)
        if bad is not None:
            raise InputError(f"{name}: line {k} has {line[bad]!r} at column {bad + 1}, not an ASCII character; a TLE "
                             "is ASCII digits, letters, spaces, '.', '+' and '-' (copy it again)")
        if not line[68].isdigit() or int(line[68]) != tle_checksum(line):
            raise InputError(f"{name}: line {k} checksum is {line[68]!r}, the line gives {tle_checksum(line)}; "
                             "the line is corrupted (copy it again)")
    if lines[0][2:7] != lines[1][2:7]:
        raise InputError(f"{name}: catalogue numbers differ ({lines[0][2:7]!r} on line 1, {lines[1][2:7]!r} "
                         "on line 2); both lines must be of one satellite")
    _check_fields(lines[0], lines[1], name)
    sat = _satrec(lines[0], lines[1], name)
    if sat.error:
        from sgp4.api import SGP4_ERRORS

        raise InputError(f"{name}: SGP4 refuses these elements: {SGP4_ERRORS.get(sat.error, sat.error)}")
    return title, lines[0], lines[1]


#: the fields of a TLE checked before SGP4 reads them: ``(line, first column, last column
#: (1-based, inclusive), what, pattern, low, high, unit)``; SGP4 itself reads a blank field
#: as 0 and a day 0 or 999 as a date, and such TLEs ran
_FIELDS = (
    (1, 19, 20, "epoch year", r"\d\d", None, None, ""),
    (1, 21, 32, "epoch day of the year", r" *-?\d{1,3}\.\d+", 1.0, None, ""),
    (2, 9, 16, "inclination", r" *-?\d{1,3}\.\d+", 0.0, 180.0, " deg"),
    (2, 18, 25, "right ascension of the node", r" *-?\d{1,3}\.\d+", 0.0, 360.0, " deg"),
    (2, 27, 33, "eccentricity", r"\d{7}", None, None, ""),
    (2, 35, 42, "argument of perigee", r" *-?\d{1,3}\.\d+", 0.0, 360.0, " deg"),
    (2, 44, 51, "mean anomaly", r" *-?\d{1,3}\.\d+", 0.0, 360.0, " deg"),
    (2, 53, 63, "mean motion", r" *-?\d{1,2}\.\d+", 0.0, None, " rev/day"),
)


def _check_fields(line1, line2, name):
    """Refuse a TLE whose epoch or elements are malformed or out of range, naming the field,
    its columns and value (SGP4 reads several of them silently)."""
    for k, c0, c1, what, pattern, lo, hi, unit in _FIELDS:
        text = (line1, line2)[k - 1][c0 - 1:c1]
        where = f"{name}: line {k} columns {c0}-{c1} ({what}) {text!r}"
        if not re.fullmatch(pattern, text):
            form = ("7 digits, the decimal point assumed (0007417 for 0.0007417)" if what == "eccentricity"
                    else "2 digits" if what == "epoch year" else "a decimal number")
            raise InputError(f"{where} is not {form}; the line is corrupted (copy it again)")
        value = float(text)
        if what == "epoch day of the year":
            year = int(line1[18:20])
            year += 1900 if year >= 57 else 2000
            hi = 366.0 + (year % 4 == 0 and (year % 100 != 0 or year % 400 == 0))  # day 1.0: 1 January, 0 h
            if not lo <= value < hi:
                raise InputError(f"{where} must be in [1, {hi:g}) in {year} (day 1.0 is 1 January, 0 h); the "
                                 "line is corrupted (copy it again)")
        elif what == "mean motion":
            if not value > lo:
                raise InputError(f"{where} must be positive{unit}; the line is corrupted (copy it again)")
        elif lo is not None and not lo <= value <= hi:
            raise InputError(f"{where} must be in [{lo:g}, {hi:g}]{unit}; the line is corrupted (copy it again)")


def tle_epoch(line1, line2, name="tle"):
    """The epoch of a TLE (its line 1, columns 19-32) as an astropy ``Time`` in UTC, as SGP4
    reads it (the instant its ``tsince = 0``)."""
    from astropy.time import Time

    sat = _satrec(line1, line2, name)
    return Time(sat.jdsatepoch, sat.jdsatepochF, format="jd", scale="utc")


def read_tle_file(path, name="tle_file"):
    """The lines of a TLE file (2 lines, or a name line and 2 lines); see :func:`parse_tle`.

    Only a regular file of at most :data:`MAX_TLE_FILE_BYTES` is read (a device such as
    ``/dev/zero``, a FIFO or a folder is refused unread), as UTF-8 text without
    NUL bytes (the TLE lines themselves must be ASCII).

    Raises
    ------
    InputError
        Naming ``name`` (``"tle_file"``), the path and the fix.
    """
    import stat

    where = f"{name}: {str(path)!r}"
    try:  # non-blocking: opening a FIFO does not wait for a writer; fstat then sees what was opened
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise InputError(f"{name}: cannot read {str(path)!r} ({exc.strerror}); give the path of a TLE file") from None
    except ValueError as exc:  # e.g. a NUL in the path
        raise InputError(f"{where} is not a usable path ({exc}); give the path of a TLE file") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise InputError(f"{where} is not a regular file (a folder, device or FIFO); give the path of a TLE file")
    with os.fdopen(fd, "rb") as f:
        if st.st_size > MAX_TLE_FILE_BYTES:
            raise InputError(f"{where} is {st.st_size} bytes; a TLE file holds one TLE (2 lines, or a name line "
                             f"and 2 lines: under {MAX_TLE_FILE_BYTES} bytes)")
        try:
            data = f.read(MAX_TLE_FILE_BYTES + 1)
        except OSError as exc:
            raise InputError(f"{name}: cannot read {str(path)!r} ({exc.strerror}); give the path of a TLE "
                             "file") from None
    if len(data) > MAX_TLE_FILE_BYTES:
        raise InputError(f"{where} grew past {MAX_TLE_FILE_BYTES} bytes while read; give the path of a TLE file")
    if b"\0" in data:
        raise InputError(f"{where} holds NUL bytes at offset {data.index(bytes(1))} (UTF-16 or a binary file?); "
                         "save it as ASCII text")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{where} is not UTF-8 text (byte {data[exc.start]:#04x} at offset {exc.start}: Latin-1?); "
                         "save it as ASCII text") from None
    return parse_tle(text, name)


def _satrec(line1, line2, name):
    from sgp4.api import Satrec

    try:
        return Satrec.twoline2rv(line1, line2)
    except (ValueError, IndexError) as exc:
        raise InputError(f"{name}: SGP4 cannot read these lines ({exc})") from None


class TleOrbit(SampledOrbit):
    """The orbit of a two-line element set, propagated by SGP4 and interpolated.

    Parameters
    ----------
    tle : sequence of str or str
        The two lines (optionally a name line first), or their text.
    t_end : Quantity (time) or str
        End of the sampled span after ``epoch`` (``> 0``).
    t_start : Quantity (time) or str
        Start of the sampled span (default 0; negative: before ``epoch``, which SGP4
        propagates as well as after). The environment tables of
        :class:`~orbatt.torques.EnvironmentTorques` sample a margin either side of a run
        (:func:`orbatt.torques.sample_margin`); a scenario samples its TLE over it.
    epoch : astropy.time.Time or str, optional
        The instant ``t = 0`` (UTC unless a ``Time`` says otherwise). Default: the TLE's epoch.
        A later epoch starts the run later (SGP4 accuracy degrades by ~1 to 3 km per day from
        the TLE's epoch).
    samples_per_orbit : int
        Samples per revolution ``N`` (default 128), equally spaced in eccentric anomaly of the
        mean elements, so denser near perigee.

    Notes
    -----
    Frames and time: SGP4 gives position and velocity in TEME at ``tsince`` minutes after the
    TLE epoch (``tsince = (t + epoch - tle_epoch) / 60`` with the UTC Julian dates SGP4
    expects); astropy transforms them to GCRS at ``obstime = epoch + t`` (``TEME -> ITRS ->
    GCRS``, IERS tables bundled with astropy). ``S`` is GCRS. The central body is the Earth
    (``gm`` = astropy ``GM_earth``, used by the gravity gradient; SGP4 itself uses WGS-72).

    Accelerations (the third Hermite datum) are central differences of the GCRS velocity,
    ``(v(t + d) - v(t - d)) / 2d`` with ``d = 1 s`` (:data:`ACCEL_DELTA`): truncation error
    ``d^2 |v'''| / 6`` ~ 1e-12 km/s^2 in LEO, far below what the interpolation needs.

    Interpolation error (quintic Hermite, :mod:`orbatt.core.sampled`), measured for the ISS at
    the default ``N = 128`` against SGP4 + astropy evaluated directly at 300 random times over
    two days: 1.3e-4 km (13 cm) in position, 3.7e-5 km/s in velocity. It is set by SGP4
    itself, not by the polynomial: SGP4's velocity is not exactly the time derivative of its
    position (they differ by ~1e-5 km/s), so the Hermite data are slightly inconsistent and the
    error falls only as ``h`` (``N = 32``: 5e-4 km), vanishing at the samples and at interval
    midpoints (8e-6 km). ``tests/test_tle_orbit.py`` checks < 1 m. SGP4 itself is a km-level
    model of the real orbit.

    Raises
    ------
    InputError
        A malformed TLE (line count or length, line numbers, checksum, catalogue numbers),
        elements SGP4 refuses, or an SGP4 error along the span (e.g. a decayed orbit), each
        naming ``tle``; a non-positive ``t_end``, a positive ``t_start``.
    """

    name = "tle"
    span_hint = "build it with a larger t_end"

    def __init__(self, tle, t_end, *, epoch=None, samples_per_orbit=128, t_start=0.0 * u.s):
        with _one_dates_warning(lambda: f"around {epoch_string(self.epoch)}"):
            self._build(tle, t_end, epoch, samples_per_orbit, t_start)

    def _build(self, tle, t_end, epoch, samples_per_orbit, t_start):
        self.title, self.line1, self.line2 = parse_tle(tle)
        self._sat = _satrec(self.line1, self.line2, "tle")
        sat = self._sat
        self.tle_epoch = tle_epoch(self.line1, self.line2)
        self.epoch = self.tle_epoch if epoch is None else parse_epoch(epoch)
        self.gm = GM_EARTH
        self.central_body = "earth"
        self.n_mean = sat.no_kozai / 60.0  # rad/s
        self.period_value = 2.0 * math.pi / self.n_mean
        te = U.strip(t_end, U.TIME, "t_end")
        if te.shape != () or not te > 0:
            raise InputError(f"t_end: {t_end!r} must be one positive time, e.g. '1 d'")
        self.t_end = float(te)
        ts = U.strip(t_start, U.TIME, "t_start")
        if ts.shape != () or not (ts <= 0 and np.isfinite(ts)):
            raise InputError(f"t_start: {t_start!r} must be one time <= 0 (s before the epoch), e.g. '-1 h'")
        self.t_start = float(ts)
        n = int(samples_per_orbit) if np.ndim(samples_per_orbit) == 0 else -1
        if n != samples_per_orbit or n < 8:
            raise InputError(f"samples_per_orbit: {samples_per_orbit!r} must be an integer >= 8 (default 128)")
        self.samples_per_orbit = n
        self.offset = float((self.epoch - self.tle_epoch).to_value(u.s))
        reach = max(abs(self.offset + self.t_start), abs(self.offset + self.t_end)) / 86400.0
        if not reach <= MAX_TLE_DAYS:
            raise InputError(f"tle: the orbit would reach {reach:.4g} days from the TLE's epoch "
                             f"{epoch_string(self.tle_epoch)}; SGP4 drifts by kilometres a day and means nothing "
                             f"past {MAX_TLE_DAYS:g} days: start (epoch) and end (t_end) within {MAX_TLE_DAYS:g} days "
                             "of the TLE's epoch, or use a TLE of the run's dates")
        t = self._sample_times()
        pos, vel = self.sgp4_gcrs(np.concatenate([t, t - ACCEL_DELTA, t + ACCEL_DELTA]))
        m = t.size
        acc = (vel[2 * m:] - vel[m:2 * m]) / (2.0 * ACCEL_DELTA)
        table = np.ascontiguousarray(np.column_stack([t, pos[:m], vel[:m], acc]))
        table.flags.writeable = False
        self._table = table

    @classmethod
    def from_file(cls, path, t_end, **options):
        """Build from a TLE file (2 lines, or a name line and 2 lines)."""
        return cls(list(read_tle_file(path)), t_end, **options)

    def _sample_times(self):
        """Sample times ``t_start .. t_end`` (s), equal steps ``2 pi / N`` in the mean elements'
        eccentric anomaly from ``t = 0`` (a sample), the two intervals at each end evened out
        (no sliver)."""
        sat, nm = self._sat, self.n_mean
        e = float(sat.ecco)

        def ecc_anomaly(tau):  # tau: s since the TLE epoch
            M = sat.mo + nm * tau
            E = M
            for _ in range(50):
                E = E - (E - e * math.sin(E) - M) / (1.0 - e * math.cos(E))
            return E

        dE = 2.0 * math.pi / self.samples_per_orbit
        E0 = ecc_anomaly(self.offset)

        def inner(t_edge):  # the samples strictly between 0 and t_edge, from 0 outwards
            k = int(math.floor(abs(ecc_anomaly(self.offset + t_edge) - E0) / dE))
            E = E0 + math.copysign(dE, t_edge) * np.arange(1, k + 1)
            t = (E - e * np.sin(E) - sat.mo) / nm - self.offset
            t = t[(t > min(0.0, t_edge)) & (t < max(0.0, t_edge))]
            if t.size and abs(t_edge - t[-1]) < 0.5 * abs(t[-1] - (t[-2] if t.size > 1 else 0.0)):
                t = t[:-1]  # the last interval would be a sliver: stretch the one before
            return t

        before = inner(self.t_start)[::-1] if self.t_start < 0.0 else np.empty(0)
        start = [self.t_start] if self.t_start < 0.0 else []
        return np.concatenate([start, before, [0.0], inner(self.t_end), [self.t_end]])

    def sgp4_gcrs(self, t):
        """SGP4 position (km) and velocity (km/s) in GCRS at ``t`` (s since the epoch, 1-D):
        the reference the interpolation is measured against.

        Raises
        ------
        InputError
            An SGP4 error code at some time (e.g. the orbit decays), naming ``tle``.
        """
        from astropy.coordinates import GCRS, TEME, CartesianDifferential, CartesianRepresentation
        from sgp4.api import SGP4_ERRORS

        t = np.asarray(t, dtype=np.float64)
        sat = self._sat
        days = (self.offset + t) / 86400.0
        err, r, v = sat.sgp4_array(np.full(t.shape, sat.jdsatepoch), sat.jdsatepochF + days)
        if np.any(err):
            k = int(np.flatnonzero(err)[0])
            raise InputError(f"tle: SGP4 fails {t[k]:.0f} s after the epoch: "
                             f"{SGP4_ERRORS.get(int(err[k]), int(err[k]))}; shorten t_end or use a newer TLE")
        with _one_dates_warning(lambda: epoch_string(self.epoch)):
            obstime = self.epoch + t * u.s
        rep = CartesianRepresentation(r.T * u.km, differentials=CartesianDifferential(v.T * u.km / u.s))
        # the bundled Earth orientation tables, extrapolated beyond them: one warning says so
        with offline_iers(), _one_dates_warning(lambda: f"{epoch_string(obstime[0])} .. {epoch_string(obstime[-1])}"):
            g = TEME(rep, obstime=obstime).transform_to(GCRS(obstime=obstime))
        pos = g.cartesian.xyz.to_value(u.km).T
        vel = g.cartesian.differentials["s"].d_xyz.to_value(u.km / u.s).T
        return np.ascontiguousarray(pos), np.ascontiguousarray(vel)

    def describe(self):
        """Plain description: ``type = "tle"``, the two lines and the name, ``tle_epoch``,
        ``epoch``, ``period_s``, ``t_start_s``, ``t_end_s``, ``samples_per_orbit``,
        ``n_samples``, the ``frame`` (GCRS) and the sgp4 version."""
        import sgp4

        return {"type": "tle", "name": self.title, "line1": self.line1, "line2": self.line2,
                "tle_epoch": epoch_string(self.tle_epoch), "epoch": epoch_string(self.epoch),
                "period_s": self.period_value, "t_start_s": self.t_start, "t_end_s": self.t_end,
                "samples_per_orbit": self.samples_per_orbit,
                "n_samples": int(self._table.shape[0]), "frame": "GCRS", "central_body": "earth",
                "sgp4_version": sgp4.__version__}

"""Epochs: the one parser of the instant ``time = 0`` and its two string forms.

An epoch is an :class:`astropy.time.Time` (any astropy scale) or an ISO 8601 calendar string
taken as UTC; one trailing ``Z`` is accepted, other forms (``"J2000"``, ``"...ZZ"``), dates that
do not exist and seconds 60 where UTC has no leap second are refused. Every module that reads an epoch (orbit providers, the
Dataset builder, the accessor, the AEM writer and reader) calls :func:`parse_epoch`.
"""
from __future__ import annotations

import re
import warnings

from .errors import InputError

__all__ = ["parse_epoch", "iso_epoch", "epoch_string"]


#: ISO 8601 calendar date and time, UTC: ``YYYY-MM-DD[Thh:mm[:ss[.fff]]][Z]`` (``T`` or a space)
_ISO = re.compile(r"(?P<date>\d{4}-\d{2}-\d{2})(?:[T ](?P<hour>\d{2}):(?P<minute>\d{2})"
                  r"(?::(?P<second>\d{2})(?:\.\d+)?)?)?Z?")


def parse_epoch(epoch, name="epoch"):
    """The epoch as one astropy ``Time``, or None.

    Parameters
    ----------
    epoch : None, astropy.time.Time or str
        A scalar ``Time`` (kept as is, in its own scale) or an ISO 8601 calendar string
        (``"2024-01-01T00:00:00"``, optionally with one trailing ``Z``), taken as UTC; a
        second 60 only where UTC has a leap second.
    name : str
        The field named in error messages.

    Returns
    -------
    astropy.time.Time or None

    Raises
    ------
    InputError
        A string that is no ISO calendar time (``"J2000"``, ``"...ZZ"``), an invalid date or
        leap second, a ``Time`` array, or another type.
    """
    if epoch is None:
        return None
    from astropy.time import Time

    if isinstance(epoch, Time):
        if epoch.shape != ():
            raise InputError(f"{name}: expected one instant, got an array of shape {epoch.shape}")
        return epoch
    if isinstance(epoch, str):
        s = epoch.strip()
        m = _ISO.fullmatch(s)
        if m is None:
            raise InputError(f"{name}: {epoch!r} is not a time in ISO 8601 calendar form; write e.g. "
                             "'2024-01-01T00:00:00Z' (UTC)")
        try:
            with warnings.catch_warnings():  # ERFA's "dubious year" and friends: checked below
                warnings.simplefilter("ignore")
                t = Time(s[:-1] if s.endswith("Z") else s, scale="utc")
                shown = t.isot
        except ValueError:
            raise InputError(f"{name}: {epoch!r} is not a time astropy parses; write e.g. "
                             "'2024-01-01T00:00:00Z' (UTC)") from None
        if m["second"] is not None and int(m["second"]) >= 60:
            # astropy moves an invalid leap second to the next day silently: a real one
            # (23:59:60 on a day that ends with one) reads back as 23:59:60
            if int(m["second"]) > 60 or shown[11:19] != f"{m['hour']}:{m['minute']}:60":
                raise InputError(f"{name}: {epoch!r} is no leap second: UTC has a second 60 only at 23:59 of the "
                                 "days that end with a leap second (e.g. 2016-12-31T23:59:60); give a valid time")
        elif shown[:10] != s[:10]:
            raise InputError(f"{name}: {epoch!r} is not a calendar date; give a valid time")
        return t
    raise InputError(f"{name}: expected an astropy Time or an ISO string, got {type(epoch).__name__}")


def iso_epoch(epoch) -> str | None:
    """ISO 8601 UTC string with nanosecond digits (``...T..:..:..fffffffffZ``) of an epoch, or
    None; the form of the Dataset's ``epoch`` attribute and of its CF time units."""
    t = parse_epoch(epoch)
    if t is None:
        return None
    t = t.utc
    t.precision = 9
    return t.isot + "Z"


def epoch_string(epoch) -> str:
    """ISO 8601 UTC string with millisecond digits and no ``Z`` (the ``epoch`` of an orbit
    provider's ``describe()``)."""
    return parse_epoch(epoch).utc.isot

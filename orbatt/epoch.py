"""Epochs: the one parser of the instant ``time = 0`` and its two string forms.

An epoch is an :class:`astropy.time.Time` (any astropy scale) or an ISO 8601 string taken as
UTC; a trailing ``Z`` is accepted. Every module that reads an epoch (orbit providers, the
Dataset builder, the accessor, the AEM writer and reader) calls :func:`parse_epoch`.
"""
from __future__ import annotations

from .errors import InputError

__all__ = ["parse_epoch", "iso_epoch", "epoch_string"]


def parse_epoch(epoch, name="epoch"):
    """The epoch as one astropy ``Time``, or None.

    Parameters
    ----------
    epoch : None, astropy.time.Time or str
        A scalar ``Time`` (kept as is, in its own scale) or an ISO 8601 string astropy parses
        (``"2024-01-01T00:00:00"``, optionally with a trailing ``Z``), taken as UTC.
    name : str
        The field named in error messages.

    Returns
    -------
    astropy.time.Time or None

    Raises
    ------
    InputError
        A string astropy does not parse, a ``Time`` array, or another type.
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
        try:
            return Time(s[:-1] if s.endswith("Z") else s, scale="utc")
        except ValueError:
            raise InputError(f"{name}: {epoch!r} is not a time astropy parses; write e.g. "
                             "'2024-01-01T00:00:00Z' (UTC)") from None
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

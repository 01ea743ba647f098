"""The time axis of a result (design: :mod:`orbatt.dataset.build`'s docstring): the CF
attributes of ``time`` in the file (:func:`cf_time_attrs`), those of ``elapsed``
(:func:`elapsed_attrs`), the float times of any result (:func:`elapsed_values`,
:func:`elapsed_unit`), and the nominal epoch of a run without one (:data:`NOMINAL_EPOCH`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["NOMINAL_EPOCH", "NOMINAL_COMMENT", "LEAP_SECONDS", "cf_time_attrs", "elapsed_attrs", "elapsed_values",
           "elapsed_unit"]


#: the nominal epoch of a dimensional run without one: its ``time`` coordinate counts from
#: here (UTC; within numpy's datetime64[ns] range, so every reader decodes it alike)
NOMINAL_EPOCH = "2000-01-01T00:00:00Z"
NOMINAL_COMMENT = ("no epoch: time counts from the start of the run, placed on the nominal epoch "
                   f"{NOMINAL_EPOCH} (no calendar meaning; elapsed holds the seconds)")
#: CF 1.11 section 4.4 leap-second statement of a time coordinate counted from a real epoch
#: (orbatt's elapsed seconds are SI seconds, leap seconds included, :mod:`orbatt.dataset.netcdf`)
LEAP_SECONDS = "leap_seconds: utc"


def cf_time_attrs(epoch, dimensionless):
    """The attributes of the ``time`` coordinate in the file (CF form: the in-memory
    Dataset decodes it, moving ``units`` and ``calendar`` into its encoding).

    Parameters
    ----------
    epoch : str or None
        ISO 8601 UTC epoch (:func:`orbatt.epoch.iso_epoch`), or None (dimensional: the
        :data:`NOMINAL_EPOCH`).
    dimensionless : bool
        A dimensionless problem: plain numbers in the problem's time unit (``units = "1"``).

    Returns
    -------
    dict
        ``long_name``, ``standard_name``, ``axis``, then ``units_metadata`` (and ``comment``
        without an epoch), ``units = "seconds since <epoch>"`` and ``calendar = "standard"``;
        for a dimensionless problem ``units = "1"``.
    """
    if dimensionless:
        return {"long_name": "dimensionless time (unit 1/n, n the problem's rate scale)", "standard_name": "time",
                "axis": "T", "units": "1"}
    attrs = {"long_name": "time (UTC)" if epoch else "time on the nominal epoch", "standard_name": "time",
             "axis": "T"}
    if epoch:
        attrs["units_metadata"] = LEAP_SECONDS
    else:
        attrs.update(units_metadata="leap_seconds: none", comment=NOMINAL_COMMENT)
    attrs.update(units=f"seconds since {epoch or NOMINAL_EPOCH}", calendar="standard")
    return attrs


def elapsed_values(ds) -> np.ndarray:
    """The float64 times of a result (a Dataset or a :class:`Content`) for arithmetic: its
    ``elapsed`` coordinate (seconds since the epoch or the start, or the dimensionless time);
    for a Dataset without one, ``time`` itself where it is numeric, else its datetimes less the
    epoch (or :data:`NOMINAL_EPOCH`) in seconds."""
    if "elapsed" in ds.coords:
        return np.asarray(ds["elapsed"].values, dtype=np.float64)
    t = np.asarray(ds["time"].values)
    if t.dtype.kind != "M":
        return t.astype(np.float64)
    start = np.datetime64(str(ds.attrs.get("epoch") or NOMINAL_EPOCH).rstrip("Z"), "ns")
    return (t - start) / np.timedelta64(1, "s")


def elapsed_unit(ds) -> str:
    """``"s"``, or ``"1"`` for a dimensionless result (the unit of :func:`elapsed_values`)."""
    if "elapsed" in ds.coords:
        return str(ds["elapsed"].attrs.get("units", "s"))
    return "1" if ds["time"].attrs.get("units") == "1" else "s"


def elapsed_attrs(epoch, dimensionless):
    """The attributes of the ``elapsed`` coordinate (seconds, or the dimensionless time unit):
    the values the integration computed, for arithmetic."""
    if dimensionless:
        return {"units": "1", "long_name": "dimensionless time since the start (the same values as time)"}
    return {"units": "s", "long_name": "elapsed time since the epoch" if epoch else
            "elapsed time since the start of the run"}

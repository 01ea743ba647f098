"""The eclipses of a run with solar radiation pressure and a shadow model: ``eclipse_entry`` and
``eclipse_exit`` (UTC) along the dimension ``eclipse`` (``docs/design.md`` §6).

Each eclipse is the time the orbit spends in the Earth's shadow as the SRP term models it: from
the penumbra's outer edge to the penumbra's outer edge again (conical model), or inside the
cylinder (cylindrical). They depend on the orbit and the Sun only, so they are found here,
along the orbit over the run's span, by the compiled scan and bisection of the shadow's outer
edge function (:func:`orbatt.core.switches.eclipse_times`: the function the step loop lands
on); an eclipse under way at the run's start has no entry (NaT), one under way at its end no
exit. In the file they are float64 ``seconds since <epoch>`` (CF, whole microseconds), like
``time``, along an unlimited ``eclipse`` dimension (an append adds the later part's eclipses:
:func:`orbatt.dataset.netcdf.write_netcdf`); the in-memory Dataset holds them as
``datetime64[ns]`` (:func:`decode_variables`, :func:`file_variables`).
"""
from __future__ import annotations

import numpy as np

from ..core.switches import eclipse_times
from .variable import Var
from .timeaxis import LEAP_SECONDS, NOMINAL_EPOCH

__all__ = ["TIME_VARIABLES", "ECLIPSE_SAMPLING_S", "eclipse_variables", "decode_variables", "file_variables"]

#: the datetime variables besides ``time`` (CF-encoded in the file as it is)
TIME_VARIABLES = ("eclipse_entry", "eclipse_exit")
#: the orbit is sampled this often (s) before each shadow edge is bisected: an eclipse
#: shorter than this may be missed (a LEO eclipse lasts ~35 min, its penumbra ~10 s)
ECLIPSE_SAMPLING_S = 10.0

_MEANING = {"eclipse_entry": "entry into the Earth's shadow (UTC): the shadow function leaves 1",
            "eclipse_exit": "exit from the Earth's shadow (UTC): the shadow function reaches 1"}


def eclipse_variables(potential, t, epoch):
    """``{"eclipse_entry": Var, "eclipse_exit": Var}`` (file form) of a run over the times
    ``t`` (s since ``epoch``, an ISO UTC string or None) under ``potential``; empty unless
    it has SRP with a shadow model (``potential.srp``, ``potential.shadow``)."""
    if not getattr(potential, "srp", False) or getattr(potential, "shadow", "none") == "none" or len(t) < 2:
        return {}
    t0, t1 = float(t[0]), float(t[-1])
    span = getattr(potential, "span", None)
    if span is not None:  # the Sun's table covers the sampled span
        t0, t1 = max(t0, float(span[0])), min(t1, float(span[1]))
    entry, exit_ = (np.round(x, 6) for x in eclipse_times(*potential.kernel_model(), t0, t1, ECLIPSE_SAMPLING_S))
    ref = epoch or NOMINAL_EPOCH
    out = {}
    for name, values in (("eclipse_entry", entry), ("eclipse_exit", exit_)):
        out[name] = Var(("eclipse",), values, {
            "long_name": _MEANING[name], "units_metadata": LEAP_SECONDS,
            "comment": f"the {potential.shadow} shadow model's outer edge; NaT where the run "
                       f"{'began' if name == 'eclipse_entry' else 'ended'} inside the shadow",
            "units": f"seconds since {ref}", "calendar": "standard"})
    return out


def decode_variables(variables):
    """``variables`` (name -> variable) with those of :data:`TIME_VARIABLES` in the file's form
    decoded to ``datetime64[ns]`` (``units`` and ``calendar`` moved into the encoding); a new
    dict. Decoded to the nearest microsecond (the file holds whole microseconds:
    :func:`file_variables` writes back the same numbers)."""
    return {k: (_decode(v) if k in TIME_VARIABLES and " since " in str(v.attrs.get("units", "")) else v)
            for k, v in variables.items()}


def _decode(var):
    import xarray as xr

    attrs = dict(var.attrs)
    units = attrs.pop("units")
    calendar = attrs.pop("calendar", "standard")
    ref = np.datetime64(units.split(" since ", 1)[1].strip().rstrip("Z"), "ns")
    secs = np.asarray(var.values, dtype=np.float64)
    bad = ~np.isfinite(secs)
    us = np.round(np.where(bad, 0.0, secs) * 1e6).astype(np.int64)
    dates = ref + us.astype("timedelta64[us]").astype("timedelta64[ns]")
    dates[bad] = np.datetime64("NaT")
    return xr.Variable(var.dims, dates, attrs, encoding={"units": units, "calendar": calendar, "dtype": np.float64})


def file_variables(ds):
    """``{name: Var}``: the :data:`TIME_VARIABLES` of the in-memory Dataset ``ds`` in the file's
    form: float64 seconds (whole microseconds) since the epoch they were decoded from, NaN for
    NaT."""
    out = {}
    for name in TIME_VARIABLES:
        if name not in ds.variables or ds[name].dtype.kind != "M":
            continue
        var = ds[name].variable
        units = var.encoding.get("units") or f"seconds since {ds.attrs.get('epoch') or NOMINAL_EPOCH}"
        ref = np.datetime64(units.split(" since ", 1)[1].strip().rstrip("Z"), "ns")
        values = np.asarray(var.values, dtype="datetime64[ns]")
        us = (values - ref).astype("timedelta64[us]").astype(np.int64)
        secs = us / 1e6
        secs[np.isnat(values)] = np.nan
        out[name] = Var(var.dims, secs, dict(var.attrs, units=units, calendar="standard"))
    return out

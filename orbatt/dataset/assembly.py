"""Assembling an :class:`xarray.Dataset` from ready variables, without xarray's merge and
alignment machinery: :func:`variable` and :func:`assemble`.

``xr.Dataset(data_vars, coords=coords)`` merges, aligns and copies every variable and checks
each array against every duck-array library installed (importing dask, pint, sparse ... the
first time, ~0.5 s). orbatt's builders make variables that already agree (one ``time`` axis,
fixed component axes), so :func:`assemble` only computes the dimension sizes, makes the
default pandas index of each dimension coordinate and hands everything to xarray's direct
constructor. The result is identical to ``xr.Dataset(data_vars, coords=coords, attrs=attrs)``
(same variables in the same order, indexes, attributes, dtypes; tested), in a fraction of
the time (measured: 560 -> 140 us for a run's Dataset; 75 us with the variables made without
xarray's constructors, checked at import against them). Where xarray lacks the direct
constructor, or its direct paths do not make what the public ones make (checked at import),
or the fast paths are off (``ORBATT_FAST_PATHS=0``, :mod:`orbatt.fast_paths`), everything
goes through xarray's public constructors and decoder.
"""
from __future__ import annotations

import re
import threading
from collections import OrderedDict

import numpy as np
import pandas as pd
import xarray as xr
from xarray.indexes import PandasIndex

from .. import fast_paths
from ..fast_paths import ENABLED as FAST_PATHS

__all__ = ["variable", "assemble", "decode_time"]


def decode_time(var) -> xr.Variable:
    """The ``time`` coordinate ``var`` (an :class:`xarray.Variable` or a
    :class:`~orbatt.dataset.content.Var` in the file's CF form) decoded as
    :func:`xarray.open_dataset` decodes it: ``"seconds since <epoch>"`` to ``datetime64[ns]``
    (``units`` and ``calendar`` moved to the encoding); a dimensionless time (``"1"``) stays.

    orbatt's own times (float64 seconds within ~142 years of an ISO UTC epoch in 1900 .. 2100) are decoded
    directly, as xarray's pandas path does (the epoch in ns plus the seconds times 1e9 cast to
    int64; xarray's coder costs ~1.5 ms a call), where :func:`_fast_decode_works` found the
    two equal in this version of xarray; anything else goes to xarray's CF decoder.
    """
    var = _as_variable(var)
    units = str(var.attrs.get("units", ""))
    if " since " not in units:
        return var
    fast = _fast_decode(var, units)
    if fast is not None:
        return fast
    out = xr.conventions.decode_cf_variable("time", var)
    return xr.Variable(out.dims, np.asarray(out.values), out.attrs, encoding=out.encoding)


#: an ISO 8601 UTC epoch as orbatt writes it (``2024-01-01T00:00:00.000000000Z``, or without
#: the fraction), after ``seconds since``
_EPOCH_RE = re.compile(r"seconds since (\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d{1,9})?)Z")
#: larger |seconds| than this (~142 years) are left to xarray: from an epoch in 1900 .. 2100
#: they stay inside datetime64[ns]'s 1677 .. 2262
_FAST_SPAN_S = 4.5e9
_FAST_STATE = {}
_FAST_FIRST, _FAST_LAST = np.datetime64("1900-01-01", "ns"), np.datetime64("2100-01-01", "ns")


def _fast_decode(var, units):
    """:func:`decode_time`'s direct path, or None where it does not apply (or the fast paths
    are off)."""
    if not FAST_PATHS:
        return None
    m = _EPOCH_RE.fullmatch(units)
    values = var.values
    if m is None or values.dtype != np.float64 or values.ndim != 1 or var.attrs.get("calendar") != "standard":
        return None
    with np.errstate(invalid="ignore"):
        if values.size and not (np.abs(values).max() <= _FAST_SPAN_S):  # NaN, inf or far: xarray
            return None
    if not _fast_decode_works():
        return None
    start = np.datetime64(m.group(1), "ns")
    if not _FAST_FIRST <= start < _FAST_LAST:
        return None
    dates = start + (values * np.int64(1_000_000_000)).astype(np.int64).astype("timedelta64[ns]")
    attrs = {k: v for k, v in var.attrs.items() if k not in ("units", "calendar")}
    # (fastpath: a datetime64[ns] numpy array is kept as it is, without xarray's ~0.2 ms of
    # conversion checks; the result is compared with the public path in _fast_decode_works)
    return xr.Variable(var.dims, dates, attrs, encoding={"units": units, "calendar": "standard",
                                                         "dtype": values.dtype}, fastpath=True)


def _fast_decode_works():
    """Whether :func:`_fast_decode` gives what xarray's decoder gives (values, attributes,
    encoding), checked once on awkward values (fractions of a second that are not binary,
    negative times, large ones)."""
    ok = _FAST_STATE.get("ok")
    if ok is None:
        _FAST_STATE["ok"] = False  # the comparison below calls _fast_decode
        try:
            t = np.array([0.0, 0.1, 0.3, 4.35, 1.0 / 3.0, -0.7, -30.0, 5550.02, 86400.123456789, 1e7 + 0.3,
                          3.15e8 + 1e-3, -4.4e9, 4.4e9])
            ref = xr.Variable(("time",), t, {"long_name": "t", "units": "seconds since 2024-02-29T12:34:56.123456789Z",
                                               "calendar": "standard"})
            theirs = xr.conventions.decode_cf_variable("time", ref)
            _FAST_STATE["ok"] = True
            ours = _fast_decode(ref, ref.attrs["units"])
            ok = (ours is not None and ours.dtype == theirs.dtype and np.array_equal(ours.values, theirs.values)
                  and type(ours.data) is type(np.asarray(theirs.values))
                  and ours.attrs == theirs.attrs and ours.encoding == theirs.encoding)
        except Exception:  # noqa: BLE001  (any surprise: xarray's decoder)
            ok = False
        _FAST_STATE["ok"] = bool(ok)
    return ok


def variable(dims, data, attrs) -> xr.Variable:
    """An :class:`xarray.Variable` of ``data`` with ``attrs``.

    A numeric or string ``numpy.ndarray`` is wrapped as it is (no copy, and none of the
    duck-array checks that import dask the first time); anything else goes through xarray's
    usual conversion.
    """
    if type(data) is np.ndarray and data.dtype.kind in "fiubU":
        if DIRECT:  # set at the end of this module
            dims = tuple(dims)
            if len(dims) == data.ndim and len(set(dims)) == len(dims):
                return _direct_variable(dims, data, attrs)
        return xr.Variable(dims, data, attrs, fastpath=True)
    return xr.Variable(dims, data, attrs)


_new = object.__new__


def _direct_variable(dims, data, attrs):
    """What ``xr.Variable(dims, data, attrs, fastpath=True)`` makes of a numpy array and a
    tuple of as many distinct dimension names, with its attributes set directly (its
    ``__init__`` costs ~2 us a variable, a sixth of a run's Dataset)."""
    var = _new(xr.Variable)
    var._data = data
    var._dims = dims
    var._attrs = dict(attrs) if attrs else None
    var._encoding = None
    return var


def _direct_works():
    """Whether :func:`_direct_variable` makes what xarray's constructor makes in this version
    of xarray (its slots are those assigned, and they hold the same; compared slot by slot:
    ``identical`` would import dask)."""
    try:
        if set(xr.Variable.__slots__) | set(getattr(xr.Variable.__mro__[1], "__slots__", ())) != {
                "_attrs", "_data", "_dims", "_encoding"}:
            return False
        data = np.arange(6.0).reshape(2, 3)
        attrs = {"units": "1"}
        ours, theirs = _direct_variable(("a", "b"), data, attrs), xr.Variable(("a", "b"), data, attrs, fastpath=True)
        return (type(ours) is type(theirs) and ours.attrs is not attrs
                and all(getattr(ours, k) == getattr(theirs, k) for k in ("_dims", "_attrs", "_encoding"))
                and ours._data is theirs._data and _index_copy_works())
    except Exception:  # noqa: BLE001  (any surprise: the public constructor)
        return False


def _index_copy_works():
    """Whether :func:`_shallow_copy` then the attribute setters make what
    ``copy(deep=False)`` then the setters make of an index variable."""
    var = xr.Variable(("t",), np.arange(3.0), {"units": "s"}, fastpath=True)
    index = PandasIndex(pd.Index(var.values), "t", coord_dtype=var.dtype)
    template = index.create_variables({"t": var})["t"]
    ours, theirs = _shallow_copy(template), template.copy(deep=False)
    for v in (ours, theirs):
        v.attrs = {"long_name": "x"}
        v.encoding = {"dtype": "f8"}
    return (type(ours) is type(theirs)
            and all(getattr(ours, k) == getattr(theirs, k) for k in ("_dims", "_attrs", "_encoding"))
            and ours._data is theirs._data)


def _as_variable(var):
    """``var`` if it is an :class:`xarray.Variable`, else the variable of its ``dims``,
    ``values`` and ``attrs`` (an :class:`orbatt.dataset.content.Var`)."""
    return var if isinstance(var, xr.Variable) else variable(var.dims, var.values, var.attrs)


def _sizes(variables):
    """``{dim: size}`` in order of first appearance; a size that disagrees raises."""
    sizes = {}
    for name, var in variables.items():
        for dim, n in zip(var.dims, var.shape):
            if sizes.setdefault(dim, n) != n:
                raise ValueError(f"{name}: dimension {dim!r} has size {n} here and {sizes[dim]} elsewhere")
    return sizes


def assemble(data_vars, coords, attrs, *, direct=True) -> xr.Dataset:
    """``xr.Dataset(data_vars, coords=coords, attrs=attrs)``, built directly.

    Parameters
    ----------
    data_vars, coords : dict of str -> xarray.Variable or Var
        The data variables and the coordinates (:class:`xarray.Variable` or anything with
        ``dims``, ``values`` and ``attrs``), in the order the Dataset lists them. A
        coordinate named after its only dimension (``time``, ``quat`` ...) gets xarray's
        default pandas index, as with the public constructor.
    attrs : dict
        Global attributes (copied).
    direct : bool
        False: use the public constructor (the reference the direct path is tested against).

    Returns
    -------
    xarray.Dataset
        Data variables first, then coordinates, each in the given order.
    """
    data_vars = {k: _as_variable(v) for k, v in data_vars.items()}
    coords = {k: _as_variable(v) for k, v in coords.items()}
    construct = getattr(xr.Dataset, "_construct_direct", None)
    if not direct or not DIRECT or construct is None:
        return xr.Dataset(data_vars, coords=coords, attrs=attrs)
    attrs = dict(attrs)
    variables = dict(data_vars)
    indexes = {}
    for name, var in coords.items():
        if var.dims == (name,):
            indexes[name], variables[name] = _indexed(name, var)
        else:
            variables[name] = var
    return construct(variables, set(coords), _sizes(variables), attrs, indexes)


#: ``(index, index variable)`` of small numeric dimension coordinates (``quat``, ``axis`` ...,
#: and the ``time`` of a run with few outputs), most recently used last: xarray never changes
#: an index in place (its operations make new ones) and pandas keeps its own read-only copy of
#: the values, so Datasets share them; each Dataset gets its own variable (a shallow copy with
#: its attributes)
_SMALL_INDEXES: OrderedDict = OrderedDict()
_SMALL_INDEXES_LOCK = threading.Lock()
_SMALL = 64
#: most indexes kept
SMALL_INDEX_CACHE_SIZE = 256


def _indexed(name, var):
    """xarray's default index of the dimension coordinate ``name`` and its index variable
    (with ``var``'s attributes)."""
    values = var.values
    key = (name, values.dtype.str, values.tobytes()) if values.size <= _SMALL and values.dtype.kind in "iuf" else None
    cached = None
    if key is not None:
        with _SMALL_INDEXES_LOCK:
            cached = _SMALL_INDEXES.get(key)
            if cached is not None:
                _SMALL_INDEXES.move_to_end(key)
    if cached is None:
        index = PandasIndex(pd.Index(values), name, coord_dtype=values.dtype)
        indexed = index.create_variables({name: var})[name]
        if key is not None:
            with _SMALL_INDEXES_LOCK:
                _SMALL_INDEXES[key] = (index, indexed.copy(deep=False))
                while len(_SMALL_INDEXES) > SMALL_INDEX_CACHE_SIZE:
                    _SMALL_INDEXES.popitem(last=False)
        return index, indexed
    index, template = cached
    indexed = _shallow_copy(template) if DIRECT else template.copy(deep=False)
    indexed.attrs = var.attrs
    indexed.encoding = var.encoding
    return index, indexed


def _shallow_copy(template):
    """``template.copy(deep=False)`` of an index variable whose attributes and encoding are
    set next: the same dimensions and (immutable, pandas-backed) data, without xarray's
    constructor."""
    out = _new(type(template))
    out._dims = template._dims
    out._data = template._data
    out._attrs = None
    out._encoding = None
    return out


def _construct_works():
    """Whether :func:`assemble`'s direct path makes the Dataset it should: its variables in
    order, sizes, pandas indexes, values and attributes (checked on a small Dataset by what it
    holds: ``xr.Dataset`` itself, or ``identical``, would import dask and pint)."""
    global DIRECT
    DIRECT = True
    try:
        t = np.array([0.0, 1.0, 2.5])
        q = np.arange(12.0).reshape(3, 4)
        ds = assemble({"q": variable(("time", "quat"), q, {"long_name": "q"})},
                      {"time": variable(("time",), t, {"units": "s"}),
                       "quat": variable(("quat",), np.array(["w", "x", "y", "z"]), {})}, {"title": "x"})
        return (type(ds) is xr.Dataset and list(ds.variables) == ["q", "time", "quat"]
                and list(ds.data_vars) == ["q"] and dict(ds.sizes) == {"time": 3, "quat": 4}
                and list(ds.indexes) == ["time", "quat"] and ds.attrs == {"title": "x"}
                and np.array_equal(ds.indexes["time"].values, t) and list(ds.indexes["quat"]) == ["w", "x", "y", "z"]
                and np.array_equal(ds["q"].values, q) and ds["q"].attrs == {"long_name": "q"}
                and ds["time"].attrs == {"units": "s"} and ds["q"].dims == ("time", "quat")
                and ds.indexes["time"].get_loc(2.5) == 2)
    except Exception:  # noqa: BLE001  (any surprise: the public constructors)
        return False
    finally:
        DIRECT = False


#: xarray's constructors bypassed (:func:`_direct_variable`, :func:`_shallow_copy`, the
#: direct Dataset constructor of :func:`assemble`): a fast path of :mod:`orbatt.fast_paths`,
#: checked once against the public constructors at import
DIRECT = FAST_PATHS and _direct_works()
DIRECT = DIRECT and _construct_works()
fast_paths.report("xarray-direct", lambda: bool(DIRECT))

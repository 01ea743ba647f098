"""Checks of orbatt's files before anything is read or written (issue 34): which NetCDF library
writes and reads them (:func:`check_engine`), whether a path holds an orbatt result that may be
replaced (:func:`is_orbatt_result`, :func:`check_replaceable`: the CLI's ``-o``,
:func:`~orbatt.dataset.netcdf.write_netcdf`, ``ds.orbatt.to_netcdf``), whether a file's header
declares sizes it cannot hold or the machine cannot load (:func:`check_declared_size`), and
whether the global attributes orbatt reads are intact (:func:`check_global_attributes`), and
whether samples appended to a file are of its run (:func:`check_same_run`; a run continued to a
later ``t_end``, :func:`same_scenario`, is the same run).
"""
from __future__ import annotations

import json
import os

import tomllib

import numpy as np

from ..errors import InputError

__all__ = ["check_engine", "is_orbatt_result", "check_replaceable", "check_declared_size", "available_memory",
           "check_global_attributes", "check_same_run", "SAME_RUN_ATTRS", "JSON_ATTRS", "INTEGER_ATTRS",
           "MAX_COMPRESSION", "MEMORY_SHARE", "short_text", "MERGED", "CONTINUED_KEYS", "merged_values",
           "same_scenario", "continued_scenario"]


def _default_engine():
    try:
        import netCDF4  # noqa: F401

        return "netcdf4"
    except ImportError:
        pass
    try:
        import h5netcdf  # noqa: F401
        import h5py  # noqa: F401

        return "h5netcdf"
    except ImportError:
        raise InputError("NetCDF: neither netCDF4 nor h5netcdf (with h5py) is installed; "
                         "pip install 'orbatt[io]'") from None


def check_engine(engine):
    """The NetCDF library to use: ``"netcdf4"`` or ``"h5netcdf"`` (``None``: netCDF4 if
    installed, else h5netcdf); raises :class:`InputError` for another name or neither
    installed."""
    engine = _default_engine() if engine is None else str(engine).lower()
    if engine not in ("netcdf4", "h5netcdf"):
        raise InputError(f"engine: {engine!r} is not 'netcdf4' or 'h5netcdf' (orbatt files are "
                         "netCDF-4/HDF5: chunked, compressed and appendable)")
    return engine


def is_orbatt_result(path) -> bool:
    """True when ``path`` is a file (or Zarr store) orbatt wrote: a NetCDF file, or a Zarr
    folder, with the global attribute ``orbatt_version``. Reads the header only; a file that
    cannot be opened as NetCDF is not an orbatt result."""
    from pathlib import Path

    p = Path(path)
    if p.is_dir():
        for meta in (".zattrs", "zarr.json"):
            try:
                if '"orbatt_version"' in (p / meta).read_text(errors="replace"):
                    return True
            except OSError:
                continue
        return False
    if not p.is_file():
        return False
    try:
        with open(p, "rb") as f:
            if f.read(8) != b"\x89HDF\r\n\x1a\n":  # netCDF-4 is HDF5; orbatt writes nothing else
                return False
        engine = check_engine(None)
        if engine == "netcdf4":
            import netCDF4

            with netCDF4.Dataset(os.fspath(p), "r") as f:
                return "orbatt_version" in f.ncattrs()
        import h5netcdf

        with h5netcdf.File(os.fspath(p), "r") as f:
            return "orbatt_version" in f.attrs
    except Exception:  # noqa: BLE001 - any failure to read it: not a result
        return False


def check_replaceable(path, *, what="path", zarr=False, ours=None):
    """Refuse to write over what is at ``path`` unless it is an earlier orbatt result: the check
    of the CLI's ``-o`` (:func:`orbatt.dataset.check_output_path`), of :func:`write_netcdf` and
    of ``ds.orbatt.to_netcdf``.

    Parameters
    ----------
    path : str or os.PathLike
    what : str
        The option, function or field named in the message (``"-o"``, ``"write_netcdf"``).
    zarr : bool
        Accept an existing Zarr store (a folder named ``*.zarr``) that orbatt wrote.
    ours : callable, optional
        ``ours(path) -> bool``: whether an existing file may be replaced (default
        :func:`is_orbatt_result`).

    Raises
    ------
    InputError
        ``path`` is a symbolic link (orbatt never writes through a link nor replaces one: the
        atomic rename would put a file where the link was), a folder (other than an orbatt
        Zarr store with ``zarr``), or anything else that exists and is not ``ours``: a
        user's file, a FIFO, another program's NetCDF file.
    """
    from pathlib import Path

    s = os.fspath(path)
    p = Path(s)
    if p.is_symlink():
        raise InputError(f"{what}: {s!r} is a symbolic link; orbatt never writes through or replaces a link: "
                         "give the path of the file it points to, or another path")
    if p.is_dir() and not (zarr and p.suffix == ".zarr"):
        raise InputError(f"{what}: {s!r} is a folder; give a file in it such as '{p / 'result.nc'}'")
    if p.exists() and not (ours or is_orbatt_result)(p):
        raise InputError(f"{what}: {s!r} exists and is not an orbatt result; orbatt overwrites only its own "
                         "results: give another path or remove that file")


#: zlib (deflate) stores at most ~1032 bytes of values in one byte: a file declaring more than this
#: many bytes of values per byte of file lacks its data (unwritten chunks: a damaged file)
MAX_COMPRESSION = 2000
#: declared sizes below this are not compared with the file's size
_PLAUSIBLE_BELOW = 256 * 2**20
#: ``open_dataset(load=True)`` refuses a file whose values need more than this share of the
#: memory available (:func:`available_memory`)
MEMORY_SHARE = 0.5


def available_memory():
    """Bytes of memory available to a new allocation (Linux ``MemAvailable``; else the free
    physical pages), or None where it cannot be found."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def _declared(name, engine):
    """``(bytes of every variable's values as declared, samples along time)`` read from the
    header of ``name`` alone, or None where the header cannot be read (xarray then says why)."""
    try:
        if engine == "netcdf4":
            import netCDF4

            with netCDF4.Dataset(name, "r") as f:
                items = [(v.shape, getattr(v.dtype, "itemsize", 8)) for v in f.variables.values()]
                n = len(f.dimensions["time"]) if "time" in f.dimensions else 0
        else:
            import h5netcdf

            with h5netcdf.File(name, "r") as f:
                items = [(v.shape, getattr(v.dtype, "itemsize", 8)) for v in f.variables.values()]
                n = f.dimensions["time"].size if "time" in f.dimensions else 0
    except Exception:  # noqa: BLE001 - the reader below names the problem
        return None
    total = sum(float(np.prod(shape, dtype=np.float64)) * max(int(size), 1) for shape, size in items)
    return total, int(n)


def check_declared_size(name, engine, *, load=False):
    """Refuse, before reading any value, a file whose header declares far more values than it
    can hold (:data:`MAX_COMPRESSION`: its data are missing) and, with ``load``, one whose
    values need more than :data:`MEMORY_SHARE` of the available memory; the message names the
    samples and the sizes."""
    found = _declared(name, engine)
    if found is None:
        return
    total, n = found
    size = os.path.getsize(name)
    if total > _PLAUSIBLE_BELOW and total > MAX_COMPRESSION * size:
        raise InputError(f"{name}: damaged: it declares {n} samples ({total / 1e9:.3g} GB of values) in "
                         f"{size / 1e6:.3g} MB, more than compression can hold: its data are missing (a truncated or "
                         "edited file)")
    avail = available_memory() if load else None
    if avail is not None and total > MEMORY_SHARE * avail:
        raise InputError(f"{name}: {n} samples ({total / 1e9:.3g} GB of values) are more than this machine can "
                         f"hold ({avail / 1e9:.3g} GB available); open it lazily (orbatt.open_dataset(path, "
                         "chunks={}) with dask) or select times with xarray")


#: global attributes written as JSON text: ``{name: type of the value}`` (:func:`check_global_attributes`)
JSON_ATTRS = {"method_settings": dict, "integration_stats": dict, "potential": dict, "orbit": dict, "wheels": list,
              "sweep_parameters": dict, "sweep_outputs": list, "sweep_run": dict, "continuation": dict}
#: global attributes that are whole numbers: ``{name: (low, high)}`` (None: unbounded)
INTEGER_ATTRS = {"integration_complete": (0, 1), "sweep_cases": (0, None), "sweep_samples": (0, None),
                 "sweep_grid_points": (0, None), "sweep_resampled_cases": (0, None), "sweep_seed": (0, None),
                 "sweep_output_times": (0, None)}


def _integer(value):
    """The whole number ``value`` holds (an integer, a one-element integer array, or a float
    with an integer value), else None."""
    v = np.asarray(value)
    if v.size != 1 or v.dtype.kind not in "iuf":
        return None
    x = v.reshape(()).item()
    if isinstance(x, float) and not (np.isfinite(x) and x == int(x)):
        return None
    return int(x)


def check_global_attributes(attrs):
    """Refuse an orbatt file whose global attributes orbatt reads are damaged (a truncated or
    edited file): the JSON ones (:data:`JSON_ATTRS`) must hold JSON of their type, the whole
    numbers (:data:`INTEGER_ATTRS`) whole numbers in their range. Raises
    :class:`~orbatt.errors.InputError` naming the attribute."""
    for key, kind in JSON_ATTRS.items():
        if key not in attrs:
            continue
        text = attrs[key]
        if isinstance(text, bytes):
            text = text.decode("utf-8", "replace")
        if not isinstance(text, str):
            raise InputError(f"global attribute {key!r} is damaged: {short_text(repr(text), 60)} is not JSON text")
        try:
            value = json.loads(text)
        except ValueError as exc:
            raise InputError(f"global attribute {key!r} is damaged: not JSON ({short_text(exc, 80)}); the file was "
                             "truncated or edited: write it again with orbatt") from None
        if not isinstance(value, kind):
            raise InputError(f"global attribute {key!r} is damaged: JSON {type(value).__name__}, not a "
                             f"{'JSON object' if kind is dict else 'JSON list'}")
    for key, (low, high) in INTEGER_ATTRS.items():
        if key not in attrs:
            continue
        x = _integer(attrs[key])
        if x is None or x < low or (high is not None and x > high):
            want = f"{low} or {high}" if high == low + 1 else f"a whole number >= {low}"
            raise InputError(f"global attribute {key!r} is damaged: {short_text(repr(attrs[key]), 60)}, not {want}; the "
                             "file was truncated or edited: write it again with orbatt")


def short_text(exc, n=120):
    """``exc`` as one line of at most ``n`` characters (messages quoting a library's error)."""
    text = " ".join(str(exc).split())
    return text if len(text) <= n else text[:n] + "..."


#: global attributes that say which run a file holds: samples appended must have the same
#: (where both the file and the new samples have one)
SAME_RUN_ATTRS = ("scenario", "potential", "orbit", "unit_system")
#: dimensions along which appended samples add entries (their variables are not compared)
_GROWING = ("time", "eclipse")
#: dimensions of variables that sum up the samples (``mode_entry_time``: the earliest entry of each
#: mode): an append merges them (:func:`merged_values`) instead of comparing them
MERGED = ("mode_index",)
#: the keys of a scenario that may differ between the runs of one file: the end of the run
#: (``orbatt run --append`` continues a run to a later ``t_end``)
CONTINUED_KEYS = (("integration", "t_end"),)
#: the keys of the ``potential`` and ``orbit`` descriptions that follow the end of the run (the
#: span the fields are sampled over)
SPAN_KEYS = ("sampled_span_s",)


def _without_spans(d):
    if isinstance(d, dict):
        return {k: _without_spans(v) for k, v in d.items() if k not in SPAN_KEYS}
    if isinstance(d, list):
        return [_without_spans(v) for v in d]
    return d


def same_description(a, b):
    """Whether two JSON descriptions (the ``potential``, the ``orbit``) are of one run: equal once
    the spans a continuation extends (:data:`SPAN_KEYS`) are left out."""
    if str(a) == str(b):
        return True
    try:
        return _without_spans(json.loads(str(a))) == _without_spans(json.loads(str(b)))
    except ValueError:
        return False


def merged_values(old, new):
    """A summary variable (:data:`MERGED`) of a file and of samples appended to it: the earliest
    time of each entry (``mode_entry_time``: NaN where neither entered it)."""
    return np.fmin(np.asarray(old, dtype=np.float64), np.asarray(new, dtype=np.float64))


def same_scenario(a, b):
    """Whether the scenario texts ``a`` and ``b`` (TOML) are of one run: equal once the keys a
    continuation may change (:data:`CONTINUED_KEYS`) are left out (texts that do not parse:
    equal as texts)."""
    if str(a) == str(b):
        return True
    try:
        ta, tb = tomllib.loads(str(a)), tomllib.loads(str(b))
    except (tomllib.TOMLDecodeError, TypeError, ValueError):
        return False
    for table, key in CONTINUED_KEYS:
        for t in (ta, tb):
            if isinstance(t.get(table), dict):
                t[table].pop(key, None)
    return ta == tb


def _shown(values, n=6):
    flat = np.asarray(values).ravel()
    text = np.array2string(flat[:n], precision=17, separator=", ")
    return text[:-1] + ", ...]" if flat.size > n else text


def check_same_run(f, piece, attrs, engine, name):
    """Refuse samples ``piece`` (file form) of another run than the open file ``f`` holds,
    naming what differs: a variable's dimensions, shape or ``units``, the values of a variable
    that does not grow with the samples (``inertia``, the wheels' axes ...), or one of
    :data:`SAME_RUN_ATTRS` (the scenario text, the potential, the orbit)."""
    def var_attrs(v):
        return dict(v.attrs) if engine == "h5netcdf" else {k: v.getncattr(k) for k in v.ncattrs()}

    for vname, var in piece.variables.items():
        fv = f.variables[vname]
        kind = np.dtype(var.dtype).kind
        if kind not in "fiubM":  # labels (text: a character dimension in the file)
            continue
        if tuple(fv.dimensions) != tuple(var.dims):
            raise InputError(f"append: {vname} has dimensions {tuple(fv.dimensions)} in {name} and {tuple(var.dims)} "
                             "in the new samples; append only samples of the same run")
        shape_f = tuple(n for d, n in zip(fv.dimensions, fv.shape) if d not in _GROWING)
        shape_p = tuple(n for d, n in zip(var.dims, var.shape) if d not in _GROWING)
        if shape_f != shape_p:
            raise InputError(f"append: {vname} has shape {shape_f} in {name} and {shape_p} in the new samples "
                             "(other than along time); append only samples of the same run")
        u_file, u_new = var_attrs(fv).get("units"), var.attrs.get("units")
        if u_file is not None and u_new is not None and str(u_file) != str(u_new):
            raise InputError(f"append: {vname} is in {str(u_file)!r} in {name} and in {str(u_new)!r} in the new "
                             "samples; convert them to the file's units, or write a new file")
        if any(d in _GROWING or d in MERGED for d in var.dims) or kind not in "fiub":
            continue
        values = np.asarray(var.values)
        old = np.asarray(fv[...])
        if old.shape != values.shape or not np.array_equal(old, values, equal_nan=kind == "f"):
            unit = "" if u_new is None or str(u_new) == "1" else f" {u_new}"
            raise InputError(f"append: the new samples are of another run: {vname} is {_shown(old)}{unit} in {name} "
                             f"and {_shown(values)}{unit} in the new samples; append only samples of the same run")
    get = (lambda k: f.attrs.get(k)) if engine == "h5netcdf" else (
        lambda k: f.getncattr(k) if k in f.ncattrs() else None)
    for key in SAME_RUN_ATTRS:
        a, b = get(key), attrs.get(key)
        if a is not None and b is not None and (same_scenario(a, b) if key == "scenario" else
                                                same_description(a, b) if key in ("potential", "orbit") else False):
            continue
        if a is not None and b is not None and str(a) != str(b):
            raise InputError(f"append: the new samples are of another run: their global attribute {key!r} differs "
                             f"from that of {name}; append only samples of the same run")


def continued_scenario(path, scenario):
    """``scenario`` set to continue the run in the file ``path`` (``orbatt run --append``): a
    copy whose ``state0`` is the file's ``continuation`` (:meth:`orbatt.State.from_record`: the
    state at its last sample, the flight software's state after the tick there, the tick grid
    and the step loop's memory) and whose ``times`` are that sample's time and the scenario's
    output times after it. Its run gives the single run's samples after the file's, bit for bit
    (from a file that ends where the scenario's outputs fall, and tables of fields along the
    orbit, which are laid out over a run's whole span, aside: docs/flight-software.md).

    Raises
    ------
    InputError
        The file holds no state to continue from, is of another run (its scenario differs other
        than in ``t_end``), or already reaches the scenario's ``t_end``.
    """
    import copy

    from ..state import State

    name = os.fspath(path)
    try:
        attrs = _global_attributes(name, check_engine(None))
    except (OSError, ValueError, KeyError) as exc:
        raise InputError(f"--append: {name} cannot be read as NetCDF ({short_text(exc)}); give a result of "
                         "'orbatt run', or leave --append out to write a new file") from None
    if "orbatt_version" not in attrs:
        raise InputError(f"--append: {name} was not written by orbatt; give a result of 'orbatt run'")
    rec, text = attrs.get("continuation"), attrs.get("scenario")
    if rec is None:
        raise InputError(f"--append: {name} holds no state to continue from (an ensemble, a sweep, or a file of an "
                         "earlier orbatt); run the scenario whole into a new file (leave --append out)")
    if text is None or not same_scenario(text, scenario.text):
        raise InputError(f"--append: {name} holds a run of another scenario (they differ other than in [integration] "
                         "t_end); append only to a run of this scenario, or write a new file")
    state = State.from_record(scenario.body, rec)
    times = np.asarray(scenario.times, dtype=np.float64)
    if not times[-1] > state.t:
        raise InputError(f"--append: {name} already ends at t = {state.t!r} s, and this scenario's t_end is "
                         f"{float(times[-1])!r} s; give a later [integration] t_end to continue the run")
    out = copy.copy(scenario)
    out.state0 = state
    out.times = np.concatenate([[state.t], times[times > state.t]])
    return out


def _global_attributes(name, engine):
    """The global attributes of the NetCDF file ``name`` (text as ``str``)."""
    if engine == "netcdf4":
        import netCDF4

        with netCDF4.Dataset(name) as f:
            return {k: f.getncattr(k) for k in f.ncattrs()}
    import h5netcdf

    with h5netcdf.File(name, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}

"""NetCDF export and import of orbatt Datasets: :func:`write_netcdf` (whole, or appended as a
run goes; :class:`NetCDFWriter`), :func:`open_dataset`, and the file form
(:func:`encode` / :func:`decode`, :func:`encoding`).

float64 is stored losslessly (zlib + shuffle), chunked along an unlimited ``time`` dimension.
The time axis (:mod:`orbatt.dataset.build`): in the file ``time`` holds the elapsed seconds
as float64 with the CF encoding ``units = "seconds since <epoch>"``, ``calendar =
"standard"`` (the nominal epoch ``2000-01-01T00:00:00Z`` for a run without one), and
``elapsed`` the same values in ``s``. :func:`open_dataset` and plain :func:`xarray.open_dataset`
both decode ``time`` to ``datetime64[ns]`` (the form ``Scenario.run()`` gives) and keep
``elapsed`` as float seconds, bit for bit, without warnings. A dimensionless run keeps
``units = "1"`` on both: its time unit is the problem's own (``1/n``), which CF's time units
cannot express.

Files of earlier orbatt versions (attitude quantities in kg km^2 ..., ``time`` alone, with the
reference year 0001 without an epoch) open in the current form with :func:`open_dataset`
(:func:`decode`): values in a kernel unit are multiplied by ``1e6`` and relabelled in SI,
``elapsed`` is added and ``time`` decoded on the current epoch or nominal epoch.

Leap seconds: orbatt integrates in SI seconds from the epoch and turns times into dates with
astropy, which counts leap seconds (``epoch + t`` is ``t`` SI seconds later, also across a leap
second). That is CF 1.11's ``units_metadata = "leap_seconds: utc"`` (elapsed time with leap
seconds, on the ``standard`` calendar). Tools that ignore leap seconds (cftime, numpy, hence
xarray's decoding and the ``time`` coordinate) are off by one second per leap second inserted
between the epoch and a sample; ``elapsed`` is exact. Two engines write the same
netCDF-4/HDF5 layout: netCDF4 and h5netcdf (:func:`check_engine`).
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import sys
import threading
from contextlib import contextmanager
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError, not_a_file
from ..units import LEGACY_OUTPUT
from .atomic import TEMP_PREFIX, replacing
from .build import LABEL_COORDS, UNIT_SYSTEM, orbatt_version, utc_now
from .content import Content, Var
from .eclipses import TIME_VARIABLES, decode_variables, file_variables
from .file_checks import (INTEGER_ATTRS, JSON_ATTRS, MERGED, available_memory, check_declared_size, check_engine,
                          check_global_attributes, check_replaceable, check_same_run, is_orbatt_result,
                          merged_values, short_text)
from .netcdf_direct import writable, write_content
from .timeaxis import LEAP_SECONDS, NOMINAL_COMMENT, NOMINAL_EPOCH, cf_time_attrs, elapsed_attrs, elapsed_values

if TYPE_CHECKING:  # annotations only: xarray is imported where a Dataset is read or made
    import xarray as xr

__all__ = ["write_netcdf", "open_dataset", "NetCDFWriter", "check_engine", "encode", "decode", "encoding",
           "is_orbatt_result", "check_replaceable", "check_global_attributes", "JSON_ATTRS", "INTEGER_ATTRS",
           "check_declared_size", "available_memory",
           "TEMP_PREFIX", "DEFAULT_CHUNK_TIME", "LEAP_SECONDS", "NOMINAL_EPOCH", "NOMINAL_COMMENT",
           "LEGACY_NOMINAL_REFERENCE"]

DEFAULT_CHUNK_TIME = 16384
#: the reference date orbatt <= 0.3.0.dev0 wrote for a dimensional run without an epoch (read,
#: never written: it decoded to cftime objects with two warnings; now :data:`NOMINAL_EPOCH`)
LEGACY_NOMINAL_REFERENCE = "0001-01-01 00:00:00"
_SECONDS = ("seconds", "second", "secs", "sec", "s")


def encode(ds: xr.Dataset) -> xr.Dataset:
    """The file form: ``time`` as float64 ``seconds since <epoch>`` (the ``elapsed`` values,
    :func:`file_time`), the eclipse times likewise (:func:`orbatt.dataset.eclipses.file_variables`),
    no stale encodings."""
    out = ds.drop_encoding()  # new variables (attribute dicts copied, data shared)
    dated = file_variables(ds)
    if "time" in ds.coords or dated:
        from .assembly import assemble

        coords = {k: (file_time(ds) if k == "time" else out[k].variable) for k in out.coords}
        data = {k: dated.get(k, out[k].variable) for k in out.data_vars}
        out = assemble(data, coords, out.attrs)  # the order kept
    return out


def file_time(ds) -> Var:
    """The ``time`` coordinate of the Dataset ``ds`` in the file's CF form.

    ``datetime64`` times are written as the ``elapsed`` seconds (exact; computed from the
    datetimes and the epoch only where ``elapsed`` is missing) with ``units = "seconds since
    <epoch>"`` (the global ``epoch``, or :data:`NOMINAL_EPOCH`) and ``calendar``; float times
    in ``s`` (orbatt's in-memory form before issue 26) are given the same attributes; a
    dimensionless time (``"1"``) is kept as it is.
    """
    time = ds["time"].variable
    attrs = dict(time.attrs)
    epoch = ds.attrs.get("epoch") or None
    if time.dtype.kind == "M":
        ref = epoch or NOMINAL_EPOCH
        values = elapsed_values(ds)
        for k in ("units", "calendar"):
            attrs.pop(k, None)
        attrs.update(units=f"seconds since {ref}", calendar="standard")
        return Var(time.dims, values, attrs)
    if attrs.get("units") == "s":
        return Var(time.dims, np.asarray(time.values, dtype=np.float64), cf_time_attrs(epoch, False))
    return Var(time.dims, np.asarray(time.values), attrs)


def decode(ds: xr.Dataset) -> xr.Dataset:
    """The in-memory form of a Dataset opened with ``decode_times=False`` (inverse of
    :func:`encode`): ``time`` decoded to ``datetime64[ns]`` as xarray decodes it, label
    coordinates as strings. A file of an earlier orbatt is turned into the current form:
    values in kernel units (``"kg km^2 s^-1"`` ...) multiplied by ``1e6`` into SI,
    ``elapsed`` added, the year-0001 reference replaced by :data:`NOMINAL_EPOCH`."""
    import xarray as xr

    from .assembly import decode_time

    scaled = {}
    for name, var in ds.variables.items():
        conv = LEGACY_OUTPUT.get(var.attrs.get("units"))
        if conv is not None:
            scaled[name] = xr.Variable(var.dims, np.asarray(var.values) * conv[1], dict(var.attrs, units=conv[0]))
    if scaled:
        ds = ds.assign({k: v for k, v in scaled.items() if k in ds.data_vars})
        ds = ds.assign_coords({k: v for k, v in scaled.items() if k in ds.coords})
        ds.attrs["unit_system"] = UNIT_SYSTEM
    if "time" in ds.coords:
        ds = _decode_time_axis(ds, xr, decode_time)
    dated = decode_variables({k: ds[k].variable for k in TIME_VARIABLES if k in ds.data_vars})
    if dated:
        ds = ds.assign(dated)
    for name in LABEL_COORDS:
        if name in ds.coords and ds[name].dtype.kind in "OS":
            vals = np.array([v.decode() if isinstance(v, bytes) else str(v) for v in ds[name].values])
            ds = ds.assign_coords({name: xr.Variable(ds[name].dims, vals, ds[name].attrs)})
    return ds


def _decode_time_axis(ds, xr, decode_time):
    """``ds`` with ``time`` decoded (and ``elapsed`` added to a file that lacks it)."""
    time = ds["time"].variable
    units = str(time.attrs.get("units", ""))
    legacy = "elapsed" not in ds.variables
    values = np.asarray(time.values)
    if " since " in units:
        head, ref = (x.strip() for x in units.split(" since ", 1))
        if head.lower() not in _SECONDS:
            raise InputError(f"time: units {units!r}; orbatt files use 'seconds since <epoch>'")
        real = ref not in (LEGACY_NOMINAL_REFERENCE, NOMINAL_EPOCH)
        if real and "epoch" not in ds.attrs:
            ds.attrs["epoch"] = ref
        epoch = ds.attrs.get("epoch") if real else None
        attrs = cf_time_attrs(epoch, False) if legacy else dict(time.attrs)
        if not legacy or real:
            attrs.update(units=units)  # the file's own reference, as xarray reads it
        elapsed = (values, elapsed_attrs(epoch, False))
        try:
            time = decode_time(xr.Variable(("time",), values.astype(np.float64), attrs))
        except (ValueError, TypeError, OverflowError, ArithmeticError) as exc:  # pandas/cftime on a bad date
            raise InputError(f"time: units {units!r}: {ref!r} is not a date orbatt can read ({type(exc).__name__}); "
                             "orbatt files use 'seconds since <ISO 8601 UTC epoch>'") from None
    elif units == "1":
        if not legacy:
            return ds
        time = xr.Variable(("time",), values, cf_time_attrs(None, True))
        elapsed = (values, elapsed_attrs(None, True))
    else:
        return ds
    ds = ds.assign_coords(time=time)
    if legacy:
        ds = ds.assign_coords(elapsed=("time",) + elapsed)
    return ds


def encoding(ds: xr.Dataset, complevel: int, chunk_time: int) -> dict:
    """Per-variable NetCDF encoding (of a Dataset or a :class:`Content`): no fill values,
    labels as char arrays, chunks of ``chunk_time`` samples along ``time`` (one ``case`` per
    chunk) with a Fletcher-32 checksum each (reading a damaged chunk fails), zlib + shuffle on
    floats when ``complevel > 0`` (lossless)."""
    enc = {}
    for name, var in ds.variables.items():
        e = {}
        if var.dtype.kind in "fiu":
            e["_FillValue"] = None
        if var.dtype.kind in "US":
            e["dtype"] = "S1"
        if "time" in var.dims:
            e["chunksizes"] = tuple(chunk_time if d == "time" else (1 if d == "case" else n)
                                    for d, n in zip(var.dims, var.shape))
            e["fletcher32"] = True  # a checksum per chunk: damage is detected on reading
            if var.dtype.kind == "f" and complevel > 0:
                e.update(zlib=True, complevel=int(complevel), shuffle=True)
        enc[name] = e
    return enc


def write_netcdf(ds: xr.Dataset, path, *, engine=None, append=False, complevel=1,
                 chunk_time=DEFAULT_CHUNK_TIME):
    """Write an orbatt Dataset to a netCDF-4 file, or append its samples to one.

    Parameters
    ----------
    ds : xarray.Dataset or Content
        An orbatt Dataset (:func:`to_dataset`) or a slice of one along ``time``, or the
        :class:`~orbatt.dataset.content.Content` of one (:func:`dataset_content`).
    path : str or os.PathLike
    engine : {"netcdf4", "h5netcdf"}, optional
        Library used; default netCDF4 if installed, else h5netcdf (needs h5py). Both write the
        same netCDF-4/HDF5 layout and can append to each other's files.
    append : bool
        False (default): create or overwrite ``path``. True: add the samples of ``ds`` after
        those in ``path`` (created if missing). The variables and their non-time coordinates
        must match; a first sample at the file's last time (as when a run is propagated
        segment by segment) is dropped; an earlier one is refused. The new part's eclipses
        follow the file's (``eclipse`` is unlimited; one under way at the boundary stays one
        eclipse). ``integration_stats``
        numbers are summed, ``integration_complete`` is the AND of both, and ``history`` and
        ``date_modified`` record the append.
    complevel : int
        zlib level (0 = no compression, 1 default: fast, lossless; shuffle filter on).
    chunk_time : int
        Samples per chunk along ``time`` (HDF5 chunk shapes are ``(chunk_time, 4)`` etc.).

    Raises
    ------
    KeyboardInterrupt
        After the write, when Ctrl-C came during it: SIGINT is held back while the file is
        written (in the main thread), so the file is complete either way.

    Notes
    -----
    ``time`` is an unlimited dimension. Values are stored as float64 without fill values:
    reading gives them back bit for bit.

    Every write is atomic (:mod:`orbatt.dataset.atomic`): a new file is written to a temporary
    file beside ``path`` (``.tmp-<name>.<pid>.<hex>``), an append goes into a copy of ``path``
    there (so it costs a copy of the file), then it is flushed to disk and renamed over
    ``path``. A kill during the write leaves the earlier file, never a partial one under
    ``path``; the temporary file it leaves is removed by the next write of ``path``. Use
    :func:`orbatt.dataset.paths.check_output_path` first to refuse, before a long computation,
    paths that cannot be written.

    Only an earlier orbatt result is replaced or appended to (:func:`check_replaceable`): an
    :class:`~orbatt.errors.InputError` refuses a symbolic link, a folder and any other file
    at ``path`` before anything is written.

    With the netCDF4 engine, a new file of plain numpy variables is written by
    :mod:`orbatt.dataset.netcdf_direct` (the file xarray writes, without importing dask);
    anything else by xarray.
    """
    engine = check_engine(engine)
    path = os.fspath(path)
    check_replaceable(path, what="write_netcdf")
    with _interrupts_deferred(path) as interrupted:
        if append and os.path.exists(path):
            with replacing(path) as tmp:  # append to a copy, renamed over path
                shutil.copyfile(path, tmp)
                _append(_as_dataset(ds), tmp, engine, name=path)
        else:
            form = _file_content(ds) if engine == "netcdf4" else None
            enc = encoding(form, complevel, chunk_time) if form is not None else None
            if form is not None and "time" in form.sizes and writable(form.variables, form.attrs, enc):
                with replacing(path) as tmp:
                    write_content(tmp, form.variables, set(form.coords), form.attrs, encoding=enc,
                                  unlimited_dims=_unlimited(form.sizes))
            else:
                enc_ds = encode(_as_dataset(ds))
                _write_replacing(enc_ds, path, engine=engine, format="NETCDF4",
                                 unlimited_dims=_unlimited(enc_ds.sizes),
                                 encoding=encoding(enc_ds, complevel, chunk_time))
    if interrupted:
        raise KeyboardInterrupt


def _unlimited(sizes):
    """The unlimited dimensions of a new file: ``time``, and ``eclipse`` where the run has one
    (an append adds the new part's eclipses: :func:`_append_eclipses`)."""
    return ["time"] + (["eclipse"] if "eclipse" in sizes else [])


def _append_eclipses(f, piece, engine, name):
    """Add the eclipses of the new samples ``piece`` (file form) after those of the open file
    ``f``: an eclipse under way at the boundary (the file's last without an exit, the new part's
    first without an entry) becomes one. Files written before the ``eclipse`` dimension was
    unlimited take no new eclipse: refused, naming the file, rather than dropped."""
    if "eclipse_entry" not in piece.variables:
        return
    ent, ext = (np.asarray(piece[k].values, dtype=np.float64) for k in ("eclipse_entry", "eclipse_exit"))
    fe, fx = f.variables["eclipse_entry"], f.variables["eclipse_exit"]
    m = int(fe.shape[0])
    if m and ent.size and np.isnan(float(fx[m - 1])) and np.isnan(ent[0]):
        fx[m - 1] = ext[0]  # the eclipse under way at the boundary: one eclipse
        ent, ext = ent[1:], ext[1:]
    if not ent.size:
        return
    if not f.dimensions["eclipse"].isunlimited():
        raise InputError(f"append: {name} holds a fixed number of eclipses (written before the eclipse dimension "
                         f"was unlimited) and the new samples have {ent.size} more; write the whole run to a new "
                         "file")
    if engine == "h5netcdf":
        f.resize_dimension("eclipse", m + ent.size)
    fe[m:m + ent.size] = ent
    fx[m:m + ent.size] = ext


def _as_dataset(ds):
    """``ds`` as an :class:`xarray.Dataset` (a :class:`Content` is turned into one)."""
    return ds.to_dataset() if isinstance(ds, Content) else ds


def _file_content(ds):
    """The file form (:func:`encode`) of ``ds`` as a :class:`Content` of numpy arrays, or None
    where a variable holds anything else (dask arrays ...)."""
    if isinstance(ds, Content):
        data_vars, coords, attrs = ds.data_vars, ds.coords, ds.attrs
    else:
        plain = {}
        for name, var in ds.variables.items():
            values = var.data
            if name == "time":
                continue  # file_time below
            if type(values) is not np.ndarray:
                return None
            plain[name] = Var(var.dims, values, var.attrs)
        if "time" in ds.variables:
            plain["time"] = file_time(ds)
        data_vars = {k: plain[k] for k in ds.data_vars}
        coords = {k: plain[k] for k in ds.coords}
        attrs = ds.attrs
    return Content(data_vars, coords, attrs)


def _write_replacing(ds: xr.Dataset, path, **to_netcdf):
    """``ds.to_netcdf`` into a new temporary file beside ``path`` (``.tmp-<name>.<pid>.<hex>``),
    flushed to disk, then renamed over ``path`` (:func:`orbatt.dataset.atomic.replacing`)."""
    with replacing(path) as tmp:
        ds.to_netcdf(tmp, **to_netcdf)


@contextmanager
def _interrupts_deferred(path):
    """Hold Ctrl-C (SIGINT) back while a file is written; yield a list that is non-empty when
    one came.

    A ``KeyboardInterrupt`` raised inside the NetCDF libraries can leave xarray's backend lock
    held (a deadlock in ``store.close()``) and a partial file; deferred, the write finishes
    (``write_netcdf`` then raises ``KeyboardInterrupt`` itself). Only in the main thread, and
    only when SIGINT has Python's default handler; elsewhere nothing changes.
    """
    hits = []
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield hits
        return

    def hold(signum, frame):
        if not hits:
            print(f"orbatt: interrupt: finishing the write of {path} first", file=sys.stderr, flush=True)
        hits.append(signum)

    signal.signal(signal.SIGINT, hold)
    try:
        yield hits
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def _append(ds: xr.Dataset, path, engine, name=None):
    """Append ``ds``'s samples into the file ``path`` in place (``name``: the file named in
    messages)."""
    name = path if name is None else name
    piece = encode(ds)
    t_new = piece["time"].values
    if engine == "netcdf4":
        import netCDF4

        f = netCDF4.Dataset(path, "a")
        f.set_auto_maskandscale(False)
    else:
        import h5netcdf

        f = h5netcdf.File(path, "a")
    try:
        names_file = set(f.variables)
        names_piece = set(piece.variables)
        if names_file != names_piece:
            raise InputError(f"append: {name} has variables {sorted(names_file - names_piece)} the new "
                             f"samples lack, and they have {sorted(names_piece - names_file)} it lacks")
        tvar = f.variables["time"]
        units_file = tvar.attrs["units"] if engine == "h5netcdf" else tvar.getncattr("units")
        if units_file != piece["time"].attrs["units"]:
            raise InputError(f"append: time units differ ({units_file!r} in {name}, "
                             f"{piece['time'].attrs['units']!r} new); different epochs cannot be appended")
        n0 = f.dimensions["time"].size if engine == "h5netcdf" else len(f.dimensions["time"])
        start = 0
        if n0 > 0:
            last = float(np.asarray(tvar[n0 - 1]))
            if t_new.size and t_new[0] == last:
                start = 1
            if t_new.size > start and t_new[start] <= last:
                raise InputError(f"append: new samples start at time {float(t_new[start])!r}, not after the "
                                 f"last time {last!r} of {name}; append only later samples")
        check_same_run(f, piece, ds.attrs, engine, name)
        n = t_new.size - start
        if n <= 0:
            return
        if engine == "h5netcdf":
            f.resize_dimension("time", n0 + n)
        for vname, var in piece.variables.items():
            if "time" not in var.dims:
                continue
            ax = var.dims.index("time")
            idx_new = [slice(None)] * var.ndim
            idx_new[ax] = slice(start, None)
            idx_file = [slice(None)] * var.ndim
            idx_file[ax] = slice(n0, n0 + n)
            f.variables[vname][tuple(idx_file)] = np.asarray(var.values)[tuple(idx_new)]
        _append_eclipses(f, piece, engine, name)
        for vname, var in piece.variables.items():  # summaries of the samples (mode_entry_time): merged
            if "time" not in var.dims and any(d in MERGED for d in var.dims):
                f.variables[vname][...] = merged_values(f.variables[vname][...], var.values)
        # global attributes
        get = (lambda k: f.attrs.get(k)) if engine == "h5netcdf" else (
            lambda k: f.getncattr(k) if k in f.ncattrs() else None)

        def put(k, v):
            if engine == "h5netcdf":
                f.attrs[k] = v
            else:
                f.setncattr(k, v)

        stats = _sum_stats(get("integration_stats"), ds.attrs.get("integration_stats"))
        if stats is not None:
            put("integration_stats", stats)
        comp = get("integration_complete")
        if comp is not None:
            put("integration_complete", np.int8(int(np.asarray(comp)) and int(ds.attrs.get("integration_complete", 1))))
        # where a run continued from the file starts: the new last sample's (none if it has none),
        # and the scenario that runs the whole file (a later t_end)
        cont = ds.attrs.get("continuation")
        if cont is not None:
            put("continuation", cont)
        elif get("continuation") is not None:
            if engine == "h5netcdf":
                del f.attrs["continuation"]
            else:
                f.delncattr("continuation")
        for key in ("scenario", "potential"):  # the run the whole file holds now (a later t_end)
            if ds.attrs.get(key) is not None:
                put(key, ds.attrs[key])
        now = utc_now()
        put("date_modified", now)
        hist = get("history") or ""
        put("history", f"{hist}\n{now} orbatt {orbatt_version()}: appended {n} samples".lstrip("\n"))
    finally:
        f.close()


def _sum_stats(a, b):
    """Sum the numbers of two JSON stats texts (keys of either kept)."""
    if a is None or b is None:
        return a
    try:
        da, db = json.loads(str(a)), json.loads(str(b))
    except ValueError:
        return a
    out = dict(da)
    for k, v in db.items():
        if k in out and isinstance(out[k], (int, float)) and isinstance(v, (int, float)) \
                and not isinstance(v, bool):
            out[k] = out[k] + v
        elif k not in out:
            out[k] = v
    return json.dumps(out, sort_keys=True)


class NetCDFWriter:
    """Write a long run to a netCDF file piece by piece, as it goes.

    Each :meth:`append` leaves a complete, readable file behind (each piece is added to a copy
    of the file, renamed over it: :func:`write_netcdf`), so a run interrupted or killed at any
    moment keeps what was written before.

    Parameters
    ----------
    path : str or os.PathLike
        Created (or overwritten) by the first :meth:`append`.
    engine, complevel, chunk_time
        As in :func:`write_netcdf`.

    Examples
    --------
    >>> with NetCDFWriter("run.nc") as w:                     # doctest: +SKIP
    ...     for piece in segments:                            # Trajectory pieces
    ...         w.append(to_dataset(piece, scenario_text=text))
    """

    def __init__(self, path, *, engine=None, complevel=1, chunk_time=DEFAULT_CHUNK_TIME):
        self.path = os.fspath(path)
        self.engine = check_engine(engine)
        self.complevel = complevel
        self.chunk_time = chunk_time
        self._started = False
        self.samples = 0

    def append(self, ds: xr.Dataset):
        """Add the samples of ``ds`` (an orbatt Dataset) at the end of the file."""
        if not self._started:
            write_netcdf(ds, self.path, engine=self.engine, complevel=self.complevel,
                         chunk_time=self.chunk_time)
            self._started = True
        else:
            write_netcdf(ds, self.path, engine=self.engine, append=True)
        self.samples = _time_length(self.path, self.engine)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def _time_length(path, engine):
    if engine == "netcdf4":
        import netCDF4

        with netCDF4.Dataset(path) as f:
            return len(f.dimensions["time"])
    import h5netcdf

    with h5netcdf.File(path, "r") as f:
        return f.dimensions["time"].size


def open_dataset(path, *, engine=None, load=False, **kwargs) -> xr.Dataset:
    """Open an orbatt NetCDF file, giving back the Dataset :func:`to_dataset` built.

    Parameters
    ----------
    path : str or os.PathLike
    engine : {"netcdf4", "h5netcdf"}, optional
        Default as in :func:`write_netcdf`.
    load : bool
        Read all values into memory now (default: lazily, as :func:`xarray.open_dataset`).
    **kwargs
        Passed to :func:`xarray.open_dataset` (e.g. ``chunks`` for dask).

    Returns
    -------
    xarray.Dataset
        The form ``Scenario.run()`` gives (:mod:`orbatt.dataset.build`): ``time`` as
        ``datetime64[ns]`` UTC (decoded as plain :func:`xarray.open_dataset` decodes it),
        ``elapsed`` in float seconds, label coordinates as strings, every value bit for bit
        as written. A file of an earlier orbatt comes in the same form (:func:`decode`).
    """
    import xarray as xr

    engine = check_engine(engine)
    kwargs.setdefault("decode_times", False)
    kwargs.setdefault("decode_timedelta", False)
    name = os.fspath(path)
    why = not_a_file(name)  # before opening: a FIFO would block
    if why is not None:
        raise InputError(f"{name}: {why}; give a result of 'orbatt run' or 'orbatt sweep'")
    try:
        with open(name, "rb") as f:
            head = f.read(8)
    except OSError as exc:
        raise InputError(f"{name}: cannot read it ({exc.strerror or exc})") from None
    if head != b"\x89HDF\r\n\x1a\n":  # orbatt writes netCDF-4 (HDF5) only
        what = "a netCDF-3 file" if head.startswith(b"CDF") else "not a NetCDF file"
        raise InputError(f"{name}: {what}, not written by orbatt; give a result of 'orbatt run' or 'orbatt sweep'")
    check_declared_size(name, engine, load=load)  # before xarray reads the time index
    try:
        ds = xr.open_dataset(name, engine=engine, **kwargs)
    except Exception as exc:  # noqa: BLE001 - the libraries raise OSError, ValueError, KeyError, ...
        raise InputError(f"{name}: cannot be read as NetCDF ({type(exc).__name__}: {short_text(exc)}); the file is "
                         "damaged or truncated") from None
    if "orbatt_version" not in ds.attrs:
        ds.close()
        raise InputError(f"{name}: a NetCDF file not written by orbatt (no orbatt_version attribute); give a "
                         "result of 'orbatt run' or 'orbatt sweep'")
    try:
        check_global_attributes(ds.attrs)
        ds = decode(ds)
    except InputError as exc:
        ds.close()
        raise InputError(f"{name}: {exc}") from None
    except (ValueError, TypeError, KeyError, OverflowError, ArithmeticError) as exc:
        ds.close()
        raise InputError(f"{name}: damaged: its variables cannot be decoded ({type(exc).__name__}: "
                         f"{short_text(exc)})") from None
    if load:
        try:
            ds = ds.load()
        except Exception as exc:  # noqa: BLE001
            ds.close()
            raise InputError(f"{name}: damaged: reading its values failed ({type(exc).__name__}: "
                             f"{short_text(exc)})") from None
    return ds

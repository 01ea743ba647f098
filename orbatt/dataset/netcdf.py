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
        _check_same_run(f, piece, ds.attrs, engine, name)
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
        now = utc_now()
        put("date_modified", now)
        hist = get("history") or ""
        put("history", f"{hist}\n{now} orbatt {orbatt_version()}: appended {n} samples".lstrip("\n"))
    finally:
        f.close()


#: global attributes that say which run a file holds: samples appended must have the same
#: (where both the file and the new samples have one)
SAME_RUN_ATTRS = ("scenario", "potential", "orbit", "unit_system")
#: dimensions along which appended samples add entries (their variables are not compared)
_GROWING = ("time", "eclipse")


def _shown(values, n=6):
    flat = np.asarray(values).ravel()
    text = np.array2string(flat[:n], precision=17, separator=", ")
    return text[:-1] + ", ...]" if flat.size > n else text


def _check_same_run(f, piece, attrs, engine, name):
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
        if any(d in _GROWING for d in var.dims) or kind not in "fiub":
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
        if a is not None and b is not None and str(a) != str(b):
            raise InputError(f"append: the new samples are of another run: their global attribute {key!r} differs "
                             f"from that of {name}; append only samples of the same run")


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
        raise InputError(f"{name}: cannot be read as NetCDF ({type(exc).__name__}: {_short(exc)}); the file is "
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
                         f"{_short(exc)})") from None
    if load:
        try:
            ds = ds.load()
        except Exception as exc:  # noqa: BLE001
            ds.close()
            raise InputError(f"{name}: damaged: reading its values failed ({type(exc).__name__}: "
                             f"{_short(exc)})") from None
    return ds


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
              "sweep_parameters": dict, "sweep_outputs": list, "sweep_run": dict}
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
            raise InputError(f"global attribute {key!r} is damaged: {_short(repr(text), 60)} is not JSON text")
        try:
            value = json.loads(text)
        except ValueError as exc:
            raise InputError(f"global attribute {key!r} is damaged: not JSON ({_short(exc, 80)}); the file was "
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
            raise InputError(f"global attribute {key!r} is damaged: {_short(repr(attrs[key]), 60)}, not {want}; the "
                             "file was truncated or edited: write it again with orbatt")


def _short(exc, n=120):
    text = " ".join(str(exc).split())
    return text if len(text) <= n else text[:n] + "..."

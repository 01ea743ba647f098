"""Writing an orbatt result to a new netCDF-4 file with the netCDF4 library directly
(:func:`write_content`), the file xarray's ``to_netcdf`` writes for it.

xarray's writer imports dask and dask.distributed whenever they are installed (it asks dask
for its scheduler, and every variable it encodes passes its duck-array checks): ~0.5 s of a
warm ``orbatt run``. orbatt's results hold plain numeric arrays, string label coordinates and
string or numeric attributes, so the few steps of xarray's netCDF-4 encoding they need are
done here, in xarray's order and with its arguments to the netCDF4 library: the CF
``coordinates`` attributes, label strings as ``S1`` character arrays with ``_Encoding``
(``string<N>`` dimensions), the unlimited dimension first, then every dimension as the
variables meet it, each variable created with xarray's default settings updated by its
encoding, attributes in order, values written as they are. The file is the same as xarray's
(tested: structure, HDF5 attribute types, values). :func:`writable` says which contents this
covers; :func:`orbatt.dataset.netcdf.write_netcdf` hands the others to xarray.
"""
from __future__ import annotations

import numbers

import numpy as np

__all__ = ["write_content", "writable"]

#: xarray's defaults for ``netCDF4.Dataset.createVariable``, which a variable's encoding updates
_CREATE_DEFAULTS = dict(zlib=False, complevel=4, shuffle=True, fletcher32=False, contiguous=False, chunksizes=None,
                        endian="native", least_significant_digit=None)
#: encoding keys this writer passes on (those of :func:`orbatt.dataset.netcdf.encoding`)
_ENCODING_KEYS = {"_FillValue", "dtype", "chunksizes", "fletcher32", "zlib", "complevel", "shuffle"}


def _plain_attr(value) -> bool:
    """An attribute value xarray writes with ``setncattr`` unchanged: a string, or a real
    number (not a bool)."""
    if isinstance(value, (bool, np.bool_)):
        return False
    return isinstance(value, (str, numbers.Real, np.integer, np.floating))


def writable(variables, attrs, encoding) -> bool:
    """Whether :func:`write_content` covers these variables (name -> object with ``dims``,
    ``values``, ``attrs``), global ``attrs`` and per-variable ``encoding``: numpy arrays of
    float, signed integer or unicode dtype; plain attributes (no ``_FillValue``, ``bounds`` or
    ``coordinates`` among them); encodings with :func:`orbatt.dataset.netcdf.encoding`'s keys."""
    if not all(isinstance(k, str) and _plain_attr(v) for k, v in attrs.items()) or "coordinates" in attrs:
        return False
    for name, var in variables.items():
        values = var.values
        if not isinstance(name, str) or not name or "/" in name or type(values) is not np.ndarray:
            return False
        if values.dtype.kind not in "fiU" or values.dtype.byteorder == ">" or values.ndim != len(var.dims):
            return False
        if values.dtype.kind == "U" and (values.size == 0 or values.ndim != 1):
            return False
        if any(k in var.attrs for k in ("_FillValue", "bounds", "coordinates", "_Encoding")):
            return False
        if not all(isinstance(k, str) and _plain_attr(v) for k, v in var.attrs.items()):
            return False
        enc = encoding.get(name, {})
        if not set(enc) <= _ENCODING_KEYS or enc.get("_FillValue") is not None:
            return False
        if enc.get("dtype") != ("S1" if values.dtype.kind == "U" else None):
            return False
    return True


def _coordinates(variables, coord_names):
    """``{name: "c1 c2"}``: the non-dimension coordinates of each data variable (those whose
    dimensions it has), as xarray's CF encoding lists them."""
    dims_of = {name: set(variables[name].dims) for name in coord_names}
    non_dim = [c for c in coord_names if (c,) != tuple(variables[c].dims) and c not in variables[c].dims]
    out = {}
    for name, var in variables.items():
        if name in non_dim or name in var.dims:
            continue
        found = sorted(c for c in non_dim if dims_of[c] <= set(var.dims))
        if found:
            out[name] = " ".join(found)
    return out, set(non_dim) - {c for text in out.values() for c in text.split()}


def _encoded(name, var, coordinates, encoding, unlimited):
    """``(dims, values, attrs, createVariable arguments)`` of one variable in the file."""
    attrs = dict(var.attrs)
    if name in coordinates:
        attrs["coordinates"] = coordinates[name]
    enc = dict(encoding)
    values = var.values
    dims = tuple(var.dims)
    if values.dtype.kind == "U":
        if enc.pop("dtype", None) != "S1":
            raise ValueError(f"{name}: unicode values need the encoding dtype 'S1'")
        attrs["_Encoding"] = "utf-8"
        encoded = np.array([x.encode("utf-8") for x in values.ravel()], dtype=bytes)
        width = max(encoded.dtype.itemsize, 1)
        values = encoded.view("S1").reshape(encoded.shape + (width,))
        dims = dims + (f"string{width}",)
    chunks = enc.get("chunksizes")
    if chunks is not None and any(c > n and d not in unlimited for c, n, d in zip(chunks, values.shape, dims)):
        del enc["chunksizes"]  # as xarray: a chunk longer than a fixed dimension is dropped
    args = dict(_CREATE_DEFAULTS)
    fill = enc.pop("_FillValue", None)
    if enc.pop("zlib", False):
        enc["compression"] = "zlib"
    args.update(enc)
    return dims, values, attrs, dict(args, fill_value=fill)


def write_content(path, variables, coord_names, attrs, *, encoding, unlimited_dims=("time",)):
    """Write a new netCDF-4 file ``path`` (overwritten) as ``xarray.Dataset.to_netcdf(path,
    engine="netcdf4", format="NETCDF4", encoding=encoding, unlimited_dims=unlimited_dims)``
    writes the same Dataset.

    Parameters
    ----------
    path : str
    variables : dict of str -> Var
        Every variable (``dims``, ``values``, ``attrs``) in the Dataset's order; checked with
        :func:`writable` by the caller.
    coord_names : set of str
        Which of them are coordinates.
    attrs : dict
        Global attributes.
    encoding : dict of str -> dict
        Per-variable encoding (:func:`orbatt.dataset.netcdf.encoding`).
    unlimited_dims : sequence of str
        Dimensions written unlimited (each must be a dimension of the variables).
    """
    import netCDF4

    coordinates, unattached = _coordinates(variables, coord_names)
    attrs = dict(attrs)
    if unattached:
        attrs["coordinates"] = " ".join(sorted(unattached))
    unlimited = set(unlimited_dims)
    encoded = {name: _encoded(name, var, coordinates, encoding.get(name, {}), unlimited)
               for name, var in variables.items()}
    sizes = {d: None for d in unlimited_dims}
    for dims, values, _, _ in encoded.values():
        sizes.update(zip(dims, values.shape))
    with netCDF4.Dataset(path, mode="w", clobber=True, diskless=False, persist=False, format="NETCDF4") as f:
        for key, value in attrs.items():
            f.setncattr(key, value)
        for dim, n in sizes.items():
            f.createDimension(dim, None if dim in unlimited else n)
        for name, (dims, values, var_attrs, args) in encoded.items():
            nc = f.createVariable(varname=name, datatype=values.dtype, dimensions=dims, **args)
            nc.setncatts(var_attrs)
            nc.set_auto_maskandscale(False)
            nc.set_auto_chartostring(False)
            nc[...] = values

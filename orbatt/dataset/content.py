"""The content of a result Dataset as plain numpy arrays: :class:`Var` and :class:`Content`.

:func:`orbatt.dataset.build.dataset_content` computes a run's variables into a
:class:`Content`; :meth:`Content.to_dataset` makes the :class:`xarray.Dataset` of it (the one
:func:`orbatt.to_dataset` returns), :func:`orbatt.dataset.netcdf.write_netcdf` writes it as it
is. ``orbatt run`` goes from the scenario to the file this way without importing xarray and
pandas (~0.3 s of a warm run). A :class:`Content` reads like a Dataset where the command line
needs it: ``content["q"].values``, ``content["q"].attrs``, ``content.attrs``, ``"r" in content``.
"""
from __future__ import annotations

import numpy as np

from .variable import Var

__all__ = ["Var", "Content"]


class Content:
    """The variables and global attributes of a Dataset before xarray.

    Parameters
    ----------
    data_vars, coords : dict of str -> Var
        Data variables and coordinates, in the order the Dataset lists them (data variables
        first). A coordinate named after its only dimension is a dimension coordinate.
    attrs : dict
        Global attributes.
    """

    def __init__(self, data_vars: dict, coords: dict, attrs: dict):
        self.data_vars = data_vars
        self.coords = coords
        self.attrs = attrs

    @property
    def variables(self) -> dict:
        """Every variable: the data variables, then the coordinates."""
        return {**self.data_vars, **self.coords}

    @property
    def sizes(self) -> dict:
        """``{dimension: length}`` in order of first appearance."""
        sizes = {}
        for var in self.variables.values():
            for dim, n in zip(var.dims, np.shape(var.values)):
                sizes.setdefault(dim, n)
        return sizes

    def __getitem__(self, name) -> Var:
        var = self.data_vars.get(name)
        return var if var is not None else self.coords[name]

    def __contains__(self, name) -> bool:
        return name in self.data_vars or name in self.coords

    def to_dataset(self):
        """The :class:`xarray.Dataset` of this content (arrays shared, not copied), with
        ``time`` decoded as :func:`xarray.open_dataset` decodes it from the file (a CF
        ``"seconds since <epoch>"`` time becomes ``datetime64[ns]``, its ``units`` and
        ``calendar`` going into the variable's encoding: :mod:`orbatt.dataset.build`)."""
        from .assembly import assemble, decode_time
        from .eclipses import decode_variables

        coords = self.coords
        if "time" in coords:
            coords = dict(coords, time=decode_time(coords["time"]))
        return assemble(decode_variables(self.data_vars), coords, self.attrs)

    def __repr__(self):
        return f"Content({len(self.data_vars)} variables, sizes {self.sizes})"

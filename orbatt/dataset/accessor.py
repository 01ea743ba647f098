"""``ds.orbatt``: the stateless accessor of an orbatt Dataset - variables as astropy
Quantities and unit conversion (with the CF spellings of :mod:`orbatt.units`), the epoch and
absolute times, the stored scenario and integration metadata, export, and quick plots.
"""
from __future__ import annotations

import json

import numpy as np
import xarray as xr
from astropy import units as u

from ..epoch import parse_epoch
from ..errors import InputError
from ..units import parse_unit, unit_string
from . import plots
from .aem import is_orbatt_aem, write_aem
from .netcdf import write_netcdf
from .paths import check_output_path
from .timeaxis import elapsed_unit, elapsed_values

__all__ = ["OrbattAccessor"]


@xr.register_dataset_accessor("orbatt")
class OrbattAccessor:
    """``ds.orbatt``: units, time, I/O and plots for an orbatt Dataset (stateless)."""

    def __init__(self, ds: xr.Dataset):
        self._ds = ds

    def __repr__(self):
        """What the Dataset holds, with units: title, unit system, outputs and span, the
        epoch, the method, the orbit, the cases of an ensemble or sweep."""
        ds, a = self._ds, self._ds.attrs
        t = elapsed_values(ds)
        tu = elapsed_unit(ds)
        span = f"{t[0]:.6g} .. {t[-1]:.6g}" if t.size else "empty"
        lines = [f"<orbatt Dataset: {a.get('title', 'orbatt result')}>",
                 f"  units:   {a.get('unit_system', '?')}",
                 f"  time:    {t.size} outputs, {span} {'(dimensionless)' if tu == '1' else 's'}"]
        if self.epoch is not None:
            lines.append(f"  epoch:   {a['epoch']} UTC")
        lines.append(f"  method:  {a.get('method', '?')} {json.dumps(self.settings)}")
        if "orbit" in a:
            orb = json.loads(a["orbit"])
            lines.append(f"  orbit:   {orb.get('type', '?')} about {orb.get('central_body', '?')}")
        for dim in ("case", "ensemble"):
            if dim in ds.dims:
                lines.append(f"  {dim}s:   {ds.sizes[dim]}")
        if not int(a.get("integration_complete", 1)):
            lines.append("  INCOMPLETE: the integration stopped early")
        return "\n".join(lines)

    # units ------------------------------------------------------------------------------
    def unit(self, name):
        """astropy unit of variable ``name`` (from its ``units`` attribute; ``"time"``: the
        unit of ``elapsed``, s or dimensionless, :meth:`quantity`)."""
        if name == "time":
            return parse_unit(elapsed_unit(self._ds))
        if name not in self._ds.variables:
            raise InputError(f"name: {name!r} is not a variable of this dataset; have "
                             f"{sorted(self._ds.variables)}")
        units = self._ds[name].attrs.get("units")
        if units is None:
            raise InputError(f"{name}: has no 'units' attribute")
        return parse_unit(units)

    def quantity(self, name):
        """Values of variable ``name`` as an :class:`astropy.units.Quantity`.

        Parameters
        ----------
        name : str
            A data variable or numeric coordinate (``"omega"``, ``"elapsed"``, ...);
            ``"time"`` gives the ``elapsed`` values (``time`` itself holds datetimes).
        """
        unit = self.unit(name)
        if name == "time":
            return elapsed_values(self._ds) * unit
        return np.asarray(self._ds[name].values) * unit

    def to(self, name, unit) -> xr.DataArray:
        """Variable ``name`` converted to ``unit``, as a DataArray with updated ``units``.

        Parameters
        ----------
        name : str
            A variable; ``"time"`` converts ``elapsed`` (``time`` holds datetimes).
        unit : str or astropy Unit
            E.g. ``"degree s-1"``, ``"deg/s"`` or ``u.deg / u.s`` for ``omega``.

        Raises
        ------
        InputError
            The units are not convertible (e.g. a dimensionless problem's ``"1"`` to
            ``"deg/s"``).
        """
        if name == "time":  # time holds datetimes: its numbers are elapsed's
            name = "elapsed"
        target = parse_unit(unit) if isinstance(unit, str) else u.Unit(unit)
        src = self.unit(name)
        try:
            factor = src.to(target)
        except u.UnitConversionError:
            raise InputError(f"{name}: cannot convert {self._ds[name].attrs['units']!r} to "
                             f"{unit_string(target)!r}") from None
        da = self._ds[name]
        out = da.copy(data=np.asarray(da.values) * factor)
        out.attrs["units"] = unit_string(target)
        return out

    def convert(self, **units) -> xr.Dataset:
        """A copy of the Dataset with the named variables converted, e.g.
        ``ds.orbatt.convert(omega="degree s-1", euler_313="degree")``."""
        ds = self._ds.copy()
        for name, unit in units.items():
            ds[name] = self.to(name, unit)
        return ds

    # metadata ---------------------------------------------------------------------------
    @property
    def dimensionless(self) -> bool:
        """True for a dimensionless problem (``elapsed`` and ``time`` in units ``"1"``)."""
        return elapsed_unit(self._ds) == "1"

    @property
    def epoch(self):
        """The epoch (``time = 0``) as an :class:`astropy.time.Time` (UTC), or None."""
        s = self._ds.attrs.get("epoch")
        return parse_epoch(str(s)) if s else None

    def times(self):
        """Absolute times (:class:`astropy.time.Time`: the epoch plus ``elapsed``, leap seconds
        counted) if there is an epoch, else the ``elapsed`` Quantity."""
        ep = self.epoch
        tq = self.quantity("time")
        return tq if ep is None else ep + tq

    @property
    def scenario(self):
        """The scenario's TOML text, or None."""
        return self._ds.attrs.get("scenario")

    @property
    def settings(self) -> dict:
        """The integration method's settings (parsed from ``method_settings``)."""
        return json.loads(self._ds.attrs.get("method_settings", "{}"))

    @property
    def stats(self) -> dict:
        """Integration statistics (parsed from ``integration_stats``)."""
        return json.loads(self._ds.attrs.get("integration_stats", "{}"))

    # I/O --------------------------------------------------------------------------------
    def to_netcdf(self, path, **kwargs):
        """Write to NetCDF (:func:`write_netcdf`; ``append=True`` adds samples). As ``orbatt
        run -o`` (:func:`orbatt.dataset.check_output_path`): only a new file or an earlier
        orbatt result is written, never a link, a folder or any other file
        (:class:`~orbatt.errors.InputError`)."""
        check_output_path(path, what="to_netcdf")
        write_netcdf(self._ds, path, **kwargs)

    def to_aem(self, path, **kwargs):
        """Write ``q`` as a CCSDS AEM (:func:`orbatt.dataset.aem.write_aem`); as ``--aem``, only a
        new file or an earlier orbatt AEM is written (:func:`orbatt.dataset.check_output_path`)."""
        if path is not None:
            check_output_path(path, what="to_aem", ours=is_orbatt_aem)
        return write_aem(self._ds, path, **kwargs)

    # plots (orbatt.dataset.plots) --------------------------------------------------------
    def plot_state(self, case=None, fig=None, time="auto"):
        """The paper's figure layout: ``q`` (left) and ``Q`` (right) against time
        (:func:`orbatt.dataset.plots.plot_state`; ``time``: ``"auto"``, ``"utc"``,
        ``"orbits"`` or ``"time"``). Returns the matplotlib Figure."""
        return plots.plot_state(self._ds, case=case, fig=fig, time=time)

    def plot_attitude(self, case=None, unit="degree", fig=None, time="auto"):
        """Unwrapped Euler angles against time (:func:`orbatt.dataset.plots.plot_attitude`).
        Returns the Figure."""
        return plots.plot_attitude(self._ds, case=case, unit=unit, fig=fig, time=time)

    def plot_drift(self, case=None, fig=None, time="auto"):
        """Drift of the energy, or of the Jacobi integral, or the energy change where nothing
        is conserved, and of the constraints, on log axes
        (:func:`orbatt.dataset.plots.plot_drift`). Returns the Figure."""
        return plots.plot_drift(self._ds, case=case, fig=fig, time=time)

    def figures(self):
        """The engineering figures this Dataset's content calls for, e.g. ``("pointing",
        "rates", "wheels", "torques")`` (:func:`orbatt.dataset.figure_data.choose_figures`)."""
        from .figure_data import choose_figures

        return choose_figures(self._ds)

    def plot_figure(self, figure, fig=None, time="auto"):
        """Draw one engineering figure by name (``"pointing"``, ``"rates"``, ``"wheels"``,
        ``"torques"``, ``"drift"``; :func:`orbatt.dataset.figures.draw`); an ensemble draws every
        case. Returns the Figure."""
        from .figures import draw

        return draw(self._ds, figure, fig=fig, time=time)

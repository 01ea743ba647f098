"""Results as an :class:`xarray.Dataset`: building from a :class:`~orbatt.trajectory.Trajectory`
(:mod:`~orbatt.dataset.build`), NetCDF export/import, whole or appended as a run goes
(:mod:`~orbatt.dataset.netcdf`), checks of output paths (:mod:`~orbatt.dataset.paths`), the
``ds.orbatt`` accessor (:mod:`~orbatt.dataset.accessor`),
quick plots (:mod:`~orbatt.dataset.plots`), the engineering figures chosen from a result's content
(:mod:`~orbatt.dataset.figure_data`, :mod:`~orbatt.dataset.figures`) and their files
(:mod:`~orbatt.dataset.figure_files`), and CCSDS AEM files (:mod:`~orbatt.dataset.aem`).

Layout (``docs/design.md`` §6)
------------------------------
Dimensions and their coordinates (every coordinate is numeric, as CF requires of coordinate
variables; the names are in a label coordinate beside it):

* ``time`` - ``datetime64[ns]`` UTC (the epoch, or the nominal epoch 2000-01-01T00:00:00Z
  of a run without one, plus the elapsed seconds), with the coordinate ``elapsed`` beside
  it: float64 seconds since the epoch, for arithmetic; a dimensionless problem has float64
  numbers in its own time unit (``1``) in both (:mod:`orbatt.dataset.build`: the time axis);
* ``quat`` - ``0 1 2 3``, labels ``w x y z`` (``quat_label``): quaternion component,
  **scalar first**, ``0`` is the paper's ``q0`` (the scalar ``w``);
* ``axis`` - ``1 2 3``, labels ``x y z`` (``axis_label``): component along axis 1, 2, 3 of
  the frame the variable names (the paper's ``b_i`` or ``s_i``);
* ``euler_313_angle`` - ``0 1 2``, labels ``phi theta psi``: the paper's 3-1-3 angles (eq. 12);
* ``euler_321_angle`` - ``0 1 2``, labels ``roll pitch yaw``: angles of ``q_orbital`` about
  the along-track, orbit-normal and radial axes (:func:`orbatt.orbital.lvlh_angles`)
  (only with an orbit);
* ``case`` - ``0 .. E-1``: ensemble member (only for ensembles; the first dimension).

The quaternion index matches the paper's subscripts (``q.sel(quat=0)`` is ``q0``) and the axis
index matches ``I1, I2, I3`` and ``g1, g2, g3``: ``q.sel(quat=k)`` and ``g.sel(axis=k)`` refer
to the same body axis ``k``.

Frames (``docs/design.md`` §1): ``S`` inertial (space), ``B`` body principal axes, ``O`` orbital
(``o1`` radial outwards, ``o3`` along ``r x v``, ``o2 = o3 x o1``). Quaternion variables carry
``quaternion_order = "w x y z"`` and ``frames = "B relative to S"`` (the rotation that turns the
``S`` axes into the ``B`` axes, ``x_S = q x_B q~``); vector variables carry ``frame``, the frame
of their components.

Variables: ``q``, ``Q`` (the canonical state), ``omega``, ``g`` (body), ``G`` (space),
``energy = kinetic_energy + potential_energy``, ``q_norm_error = |q| - 1``, ``qQ = q.Q``,
``euler_313``, ``inertia``; with an orbit also ``r``, ``p`` (``O`` relative to ``S``),
``true_anomaly``, ``position``, ``velocity`` (in ``S``), ``q_orbital = p~ q`` (``B`` relative to
``O``) and ``euler_321`` (its roll, pitch, yaw about ``o2, o3, o1``; :func:`orbatt.orbital.lvlh_angles`).

Units: dimensional problems write the attitude family in SI (inertia kg m^2, momenta
kg m^2 s^-1, energies J, torques N m; :data:`orbatt.units.DIMENSIONAL_UNITS`) and orbit
positions in km; dimensionless ones ``"1"`` everywhere except angles (``"rad"``). Every
``units`` attribute is a CF/UDUNITS spelling from :data:`orbatt.units.CF_UNITS` that
:class:`astropy.units.Unit` parses.

Global attributes: ``Conventions = "CF-1.11"``, ``title``, ``source``, ``references``,
``orbatt_version``, ``method``, ``method_settings`` and ``integration_stats`` (JSON text),
``integration_complete`` (1 or 0), ``potential`` and ``orbit`` (JSON text of their
``describe()``), ``unit_system``, ``epoch`` (ISO 8601 UTC, only when the problem has one),
``scenario`` (the scenario's TOML text, when given), ``wheels`` (with reaction wheels: JSON
text of each wheel's ``describe()``, its limits ``max_speed_rad_s`` and ``max_torque_N_m``
included, null for none), ``date_created``, ``history``.

NetCDF (:func:`write_netcdf`, :func:`open_dataset`): float64 stored losslessly (zlib + shuffle),
chunked along an unlimited ``time`` dimension, so that :class:`NetCDFWriter` (or
``write_netcdf(..., append=True)``) can add samples as a long run goes. In the file ``time``
has the CF encoding ``units = "seconds since <epoch>"``, ``calendar = "standard"``; plain
:func:`xarray.open_dataset` and :func:`open_dataset` both give back the in-memory form bit for
bit (files of earlier versions: :func:`open_dataset` converts them).
"""
from __future__ import annotations

from ..epoch import iso_epoch
from ..orbital import lvlh_angles
from ..quaternion import to_euler321
from ..units import CF_UNITS, DIMENSIONAL_UNITS, DIMENSIONLESS_UNITS, parse_unit, unit_string
from .aem import read_aem, write_aem
from .build import (AXIS_INDEX, AXIS_LABELS, CONVENTIONS, EULER_313_LABELS, EULER_321_LABELS, FRAMES,
                    LABEL_COORDS, QUAT_INDEX, QUAT_LABELS, QUATERNION_ORDER, REFERENCE, cf_variable,
                    dataset_content, global_attrs, orbatt_version, to_dataset, to_json, utc_now)
from .content import Content
from .netcdf import (DEFAULT_CHUNK_TIME, TEMP_PREFIX, NetCDFWriter, check_engine, decode, encode, encoding,
                     open_dataset, write_netcdf)
from .paths import check_output_path, file_name, is_orbatt_result

__all__ = [
    "to_dataset", "dataset_content", "Content", "global_attrs", "open_dataset", "write_netcdf", "NetCDFWriter", "OrbattAccessor",
    "read_aem", "write_aem", "check_output_path", "file_name", "is_orbatt_result", "TEMP_PREFIX",
    "cf_variable", "check_engine", "encode", "encoding", "decode", "iso_epoch", "to_json", "utc_now",
    "orbatt_version", "to_euler321", "lvlh_angles", "unit_string", "parse_unit",
    "QUATERNION_ORDER", "QUAT_INDEX", "QUAT_LABELS", "AXIS_INDEX", "AXIS_LABELS", "EULER_313_LABELS",
    "EULER_321_LABELS", "LABEL_COORDS", "CONVENTIONS", "FRAMES", "REFERENCE", "CF_UNITS", "DIMENSIONAL_UNITS",
    "DIMENSIONLESS_UNITS", "DEFAULT_CHUNK_TIME",
]


def __getattr__(name):
    if name == "OrbattAccessor":
        from .accessor import OrbattAccessor

        return OrbattAccessor
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""The torque terms of :class:`orbatt.EnvironmentTorques`, each described once at the API
level (``docs/design.md`` §8, §10): what a scenario writes, what the kernel gets and what a
Dataset records.

A :class:`Term` extends a kernel :class:`~orbatt.core.kinds.TermKind` (its code, name,
description and flags, :mod:`orbatt.core.kinds`) with

* its **scenario keys** in ``[torques]`` (:class:`TomlKey`: the dimension, default and meaning
  the reference ``docs/scenarios.md`` prints, the physical range, the parser's kind and the
  :class:`~orbatt.EnvironmentTorques` argument it becomes);
* its **row builder**: the kernel row ``(kind, params, table)`` of :func:`orbatt.core.model.build`
  from an :class:`~orbatt.EnvironmentTorques` (internal units; tables from its
  :meth:`~orbatt.EnvironmentTorques.field_table`);
* its **Dataset fields** (:class:`FieldVar`): the environment along the orbit it records,
  and the function that evaluates them.

Generated from :data:`TERMS`: the ``[torques]`` keys and their reference rows
(:data:`orbatt.scenario.torques_schema.TORQUE_KEYS`, the ``[torques]`` part of
:data:`orbatt.scenario.schema.KEY_DOCS` and of :data:`orbatt.scenario.ranges.RANGES`), the
terms of the model :meth:`orbatt.EnvironmentTorques.build_model` makes (in the order of
:data:`TERMS`), the fields of :meth:`orbatt.EnvironmentTorques.fields` and their Dataset
variables (:data:`FIELD_VARIABLES`), and :data:`orbatt.torques.TERM_NAMES`.

Adding a torque term: its :class:`~orbatt.core.kinds.TermKind` and kernel branch
(:mod:`orbatt.core.kinds`, ``core.model.term_value``), a :class:`Term` here, and the
:class:`~orbatt.EnvironmentTorques` keyword its key names.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from astropy import units as u

from .core import kernel_floats
from .core import environment as kenv
from .core import model as km
from .core.kinds import BY_CODE, TermKind
from .environment import sun as esun
from .environment.atmosphere import ExponentialAtmosphere
from .environment.frames import EARTH_ROTATION_RATE, R_EARTH_WGS84
from .units import from_kernel, to_kernel

__all__ = ["TomlKey", "FieldVar", "Term", "TERMS", "BY_KEY", "FIELD_VARIABLES", "SHADOW_CODES", "torque_key_docs",
           "torque_ranges"]

#: the SRP term's shadow models by name (``[environment] shadow``)
SHADOW_CODES = {"none": km.SHADOW_NONE, "cylindrical": km.SHADOW_CYLINDRICAL, "conical": km.SHADOW_CONICAL}


@dataclass(frozen=True)
class TomlKey:
    """One key of the scenario's ``[torques]`` table.

    Attributes
    ----------
    key : str
        The TOML key.
    dimension, default, meaning : str
        The reference's columns (``docs/scenarios.md``; :data:`orbatt.scenario.schema.KEY_DOCS`).
    kind : {"flag", "vector"}
        ``true | false``, or 3 quantities of ``unit`` within ``range``.
    argument : str
        The :class:`~orbatt.EnvironmentTorques` keyword it becomes.
    unit : str
        The quantities' unit (SI; a vector key), the parser's and the argument's.
    range : tuple or None
        ``(high, unit)``: the bound of each component's magnitude (a vector key), in
        :data:`orbatt.scenario.ranges.RANGES`.
    """

    key: str
    dimension: str
    default: str
    meaning: str
    kind: str
    argument: str
    unit: str = ""
    range: tuple | None = None


@dataclass(frozen=True)
class FieldVar:
    """A Dataset variable of an environment field along the orbit: ``(time, *dims)``."""

    name: str
    dims: tuple
    unit: str
    long_name: str
    attrs: dict


@dataclass(frozen=True)
class Term:
    """A torque term of :class:`~orbatt.EnvironmentTorques` (module docstring).

    Attributes
    ----------
    kind : TermKind
        The kernel's descriptor (:mod:`orbatt.core.kinds`).
    keys : tuple of TomlKey
        Its ``[torques]`` keys (none: the gravity gradient, which ``[potential] kind`` brings).
    enabled : callable
        ``enabled(torques) -> bool``: whether an :class:`~orbatt.EnvironmentTorques` has it.
    row : callable
        ``row(torques) -> (kind, params, table)``: its kernel row (internal units).
    fields : tuple of FieldVar
        The environment fields it records along the orbit.
    sample : callable or None
        ``sample(torques, t, pos, time, tabs) -> {name: values}``: its fields at the times
        ``t`` (s) and positions ``pos`` (km, inertial), ``time`` the instants (or None), from
        the kernel's tables ``tabs`` where they hold ``t`` (else the models).
    """

    kind: TermKind
    keys: tuple
    enabled: Callable
    row: Callable
    fields: tuple = ()
    sample: Callable | None = None

    @property
    def name(self):
        return self.kind.name


def _gravity_gradient_row(tq):
    return (km.GRAVITY_GRADIENT, [float(tq.params[0])], None)


def _drag_row(tq):
    F = np.array([f.row(f.drag_coefficient * f.area.to_value(u.km**2)) for f in tq.facets])
    omega = EARTH_ROTATION_RATE if tq.corotation else 0.0
    if isinstance(tq.atmosphere, ExponentialAtmosphere):  # closed form in the kernel (issue 25), no table
        rho0, h0, H, R = tq.atmosphere.kernel_params()
        return (km.DRAG, km.drag_params(F, omega, (to_kernel(rho0, "density"), h0, H, R)), None)  # kg km^-3, km
    return (km.DRAG, km.drag_params(F, omega), tq.field_table("density"))


def _srp_row(tq):
    sun = tq.field_table("sun")
    F = np.array([f.row(f.area.to_value(u.km**2)) for f in tq.facets])
    pressure = esun.SRP_FLUX / esun.SPEED_OF_LIGHT * 1e3  # N m^-2 -> kg km^-1 s^-2
    return (km.SRP, km.srp_params(F, pressure, esun.AU, SHADOW_CODES[tq.shadow], R_EARTH_WGS84, esun.R_SUN), sun)


def _magnetic_row(tq):
    field = tq.field_table("field")
    return (km.MAGNETIC, to_kernel(tq.residual_dipole, "dipole"), field)


def _constant_row(tq):
    return (km.CONSTANT_TORQUE, to_kernel(tq.constant_torque, "torque"), None)


def _table_values(tabs, name, t, width):
    return kenv.piece_eval_many(tabs[name], kernel_floats(t), width)


def _drag_fields(tq, t, pos, time, tabs):
    if "density" in tabs:
        return {"density": from_kernel(_table_values(tabs, "density", t, 1)[:, 0], "density")}
    return {"density": np.asarray(tq.atmosphere.density(time, pos), dtype=np.float64)}


def _srp_fields(tq, t, pos, time, tabs):
    sun = _table_values(tabs, "sun", t, 3) if "sun" in tabs else np.asarray(esun.sun_position(time), dtype=np.float64)
    d = sun - pos
    return {"sun_direction": d / np.linalg.norm(d, axis=-1, keepdims=True),
            "shadow": (np.ones(t.shape) if tq.shadow == "none" else
                       esun.shadow(pos, sun, kind=tq.shadow, body_radius=R_EARTH_WGS84))}


def _magnetic_fields(tq, t, pos, time, tabs):
    if "field" in tabs:
        return {"magnetic_field": _table_values(tabs, "field", t, 3)}
    return {"magnetic_field": np.asarray(tq.magnetic_field.field(time, pos), dtype=np.float64)}


def _flag(key, meaning, argument=None):
    return TomlKey(key, "true | false", "false", meaning, "flag", argument or key)


_INERTIAL = {"frame": "S"}

#: the torque terms, in the kernel's order (the model's rows after the orbit)
TERMS = (
    Term(BY_CODE[km.GRAVITY_GRADIENT], (), lambda tq: tq.gravity_gradient, _gravity_gradient_row),
    Term(BY_CODE[km.DRAG], (_flag("drag", "aerodynamic drag of the facets (needs [[body.facets]])"),),
         lambda tq: tq.drag, _drag_row,
         (FieldVar("density", (), "kg m^-3", "atmospheric density along the orbit", {}),), _drag_fields),
    Term(BY_CODE[km.SRP], (_flag("srp", "solar radiation pressure on the facets (needs facets and an epoch: [orbit] "
                                        "epoch or a TLE's)"),),
         lambda tq: tq.srp, _srp_row,
         (FieldVar("sun_direction", ("axis",), "1", "unit vector from the body to the Sun (inertial components)",
                   _INERTIAL),
          FieldVar("shadow", (), "1", "shadow function: 0 = umbra ... 1 = full Sun", {})), _srp_fields),
    Term(BY_CODE[km.MAGNETIC], (TomlKey("residual_dipole", "magnetic moment (A m2), 3 values", "none",
                                        "the body's dipole m: torque m x B (body axes)", "vector",
                                        "residual_dipole", "A m2", (1e5, "A m2")),),
         lambda tq: tq.residual_dipole is not None, _magnetic_row,
         (FieldVar("magnetic_field", ("axis",), "T", "geomagnetic field along the orbit (inertial components)",
                   _INERTIAL),), _magnetic_fields),
    Term(BY_CODE[km.CONSTANT_TORQUE], (TomlKey("constant", "torque (N m), 3 values", "none",
                                               "a constant body torque (body axes: thruster misalignment, "
                                               "outgassing); needs no orbit (also with kind = 'torque-free')",
                                               "vector", "constant_torque", "N m", (1e4, "N m")),),
         lambda tq: tq.constant_torque is not None, _constant_row),
)
#: the terms by their ``[torques]`` keys
BY_KEY = {k.key: (term, k) for term in TERMS for k in term.keys}
#: the Dataset variables of the environment fields: ``name -> (dims, unit, long_name, attrs)``
FIELD_VARIABLES = {f.name: (f.dims, f.unit, f.long_name, f.attrs) for term in TERMS for f in term.fields}


def torque_key_docs():
    """``{key: (dimension, default, meaning)}`` of the ``[torques]`` keys, in the order of
    :data:`TERMS` (the ``[torques]`` part of :data:`orbatt.scenario.schema.KEY_DOCS`)."""
    return {k.key: (k.dimension, k.default, k.meaning) for term in TERMS for k in term.keys}


def torque_ranges():
    """``{key: (high, unit)}``: the physical range of each vector key of ``[torques]`` (the
    magnitude of each component; :data:`orbatt.scenario.ranges.RANGES`)."""
    return {k.key: k.range for term in TERMS for k in term.keys if k.range is not None}

"""The one assembler of the kernel model (``docs/design.md`` §8): every run of
:func:`orbatt.propagate` - the single run, the ensemble, each orbit group of a sweep - and the
Dataset's control variables get their model ``(terms, params, table)``
(:mod:`orbatt.core.model`) from :func:`assemble`.

Each part gives its own rows: the potential its orbit row and term rows (its
:meth:`~orbatt.potentials.Potential.kernel_model`, built once: the orbit provider's row and,
for :class:`~orbatt.EnvironmentTorques`, the terms of :mod:`orbatt.terms`; unpacked by
:func:`model_rows`), the body's reaction wheels their extended state
(:func:`orbatt.control.wheels_row`), the control law its row (``model_row`` of
:class:`~orbatt.PDControl`, :class:`~orbatt.BDotControl`, reading the fields the potential
sampled along the orbit, :meth:`~orbatt.EnvironmentTorques.field_table`);
:func:`orbatt.core.model.build` packs them once, in that order.

The control law is a peer of the potential: ``propagate(..., control=law)`` hands it to
:func:`assemble` beside the potential (:func:`control_of` resolves it against the older
spelling, a law carried by ``EnvironmentTorques(control=)``). The law reads the orbit of the
potential's row 0 and, where it needs a field along the orbit (the Sun for ``target = "sun"``,
the magnetic field for B-dot), the potential's samples of it.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .control import wheels_row
from .laws import LAW_CLASSES
from .core import control as kc
from .core import model as km
from .errors import InputError

__all__ = ["KernelSpec", "assemble", "command_size", "controller_start", "control_of", "model_rows",
           "FLIGHT_SOFTWARE_KINDS"]

#: the kinds of rows with the flight-software slots (:data:`orbatt.core.control.FLIGHT_SOFTWARE`)
#: and a discrete state in ``y`` after the wheels' momenta
FLIGHT_SOFTWARE_KINDS = (km.PD_CONTROL, km.BDOT_CONTROL, km.MODES, km.MOMENTUM_DUMP, km.NAVIGATION)


class KernelSpec(NamedTuple):
    """The model as the compiled kernels take it (the term list of :mod:`orbatt.core.model`),
    always passed to them together and in this order (``*spec``)."""

    terms: np.ndarray
    params: np.ndarray
    table: np.ndarray


def command_size(model):
    """The number of state components that hold the flight software's commands (issue 32):
    the ``nz`` slots of the model's control rows (0 without a law that has a period), after
    ``q, Q`` and the wheels' momenta."""
    return controller_start(model).size


def controller_start(model):
    """The initial values of the controllers' state components (:func:`command_size` of them):
    all 0 (finite: the step loop's error norm reads them); the driver's first tick issues the
    held commands and starts a mode sequence (:func:`orbatt.core.gyrostat.tick`), a PD law's
    integral of its error starts at 0."""
    terms, params, _ = model
    out = []
    for j in range(1, terms.shape[0]):
        kind, p0 = int(terms[j, km.KIND]), int(terms[j, km.P0])
        if kind not in FLIGHT_SOFTWARE_KINDS:
            continue
        out.append(np.zeros(int(params[p0 + kc.CTL_NZ])))
    return np.concatenate(out) if out else np.empty(0)


def model_rows(model):
    """``(orbit row, term rows)`` of a built model ``(terms, params, table)``: the rows
    ``(kind, params, table or None)`` :func:`orbatt.core.model.build` packs into it again."""
    terms, params, table = model

    def row(j):
        t = table[terms[j, km.R0]:terms[j, km.R1]] if terms[j, km.R1] > terms[j, km.R0] else None
        return (int(terms[j, km.KIND]), params[terms[j, km.P0]:terms[j, km.P1]], t)

    return row(0), [row(j) for j in range(1, terms.shape[0])]


def _potential_model(potential):
    """The potential's own model: its ``kernel_model()`` (:class:`orbatt.potentials.Potential`,
    built once, fresh copies), or that of its kernel specification ``kind``, ``params``,
    ``table`` (:func:`orbatt.core.model.from_spec`)."""
    table = np.asarray(potential.table, dtype=np.float64)
    if table.ndim != 2:
        raise InputError(f"potential.table: expected a 2-D array, got shape {table.shape}")
    if hasattr(potential, "kernel_model"):
        return potential.kernel_model()
    try:  # from_spec copies params and table into fresh arrays
        return km.from_spec(int(potential.kind), potential.params, table)
    except ValueError as exc:
        raise InputError(f"potential: {exc}") from None


def control_of(potential, control=None):
    """The control law of a run: ``control`` (given beside the potential) or the one the
    potential carries (``EnvironmentTorques(control=)``), or None.

    Raises
    ------
    InputError
        ``control`` is not a control law (:data:`orbatt.laws.LAWS`), or both the argument
        and the potential hold one.
    """
    carried = getattr(potential, "control", None)
    if control is None:
        return carried
    if not isinstance(control, LAW_CLASSES):
        raise InputError(f"control: expected one of {', '.join(c.__name__ for c in LAW_CLASSES)}, got "
                         f"{type(control).__name__}")
    if carried is not None and carried is not control:
        raise InputError(f"control: the potential already carries a control law ({carried!r}); give the law once, "
                         "either as propagate(..., control=law) or as EnvironmentTorques(..., control=law)")
    return control


def _field_tables(potential, control):
    """``tables(name)`` for ``control.model_row``: the potential's samples of a field along
    the orbit (:meth:`orbatt.EnvironmentTorques.field_table`); a potential that samples none
    is refused naming what the law reads."""
    tables = getattr(potential, "field_table", None)
    if tables is not None:
        return tables
    what = {"sun": "the Sun's position", "field": "the magnetic field"}

    def refuse(name):
        raise InputError(f"control: {control!r} reads {what.get(name, name)} along the orbit, which "
                         f"{type(potential).__name__} does not sample; give the potential as orbatt.EnvironmentTorques("
                         "orbit, t_end, ...) with the field it needs (magnetic_field=..., or an epoch for the Sun)")
    return refuse


def assemble(potential, bodies, control=None) -> KernelSpec:
    """The :class:`KernelSpec` of a run: ``potential``'s orbit and terms, then the wheels of
    ``bodies`` (the members share them) and the control law (``control``, or the one the
    potential carries: :func:`control_of`), after the potential's ``check_body`` (if any)
    accepted every body.

    Parameters
    ----------
    potential : Potential or object with ``kind``, ``params``, ``table``
        An orbatt potential (:mod:`orbatt.potentials`, :class:`orbatt.EnvironmentTorques`).
    bodies : list of RigidBody
        The members (:func:`orbatt.methods.problem.bodies_of`).
    control : PDControl or BDotControl, optional
        The control law, a peer of the potential: it reads the potential's orbit (row 0) and
        the fields the potential samples along it.

    Returns
    -------
    KernelSpec
        Writeable C-contiguous arrays (one numba specialization of every kernel), internal
        units.
    """
    if not all(hasattr(potential, a) for a in ("kind", "params", "table")):
        raise InputError(f"potential: expected an orbatt Potential (with kind, params, table), got "
                         f"{type(potential).__name__}")
    if hasattr(potential, "check_body"):
        for b in set(bodies):
            potential.check_body(b)
    wheels = bodies[0].wheels
    control = control_of(potential, control)
    if not wheels and control is None:
        return KernelSpec(*_potential_model(potential))
    orbit_row, rows = model_rows(_potential_model(potential))
    if wheels:
        rows.append(wheels_row(wheels))
    if control is not None:
        tables = _field_tables(potential, control)
        own = control.model_rows(wheels, tables) if hasattr(control, "model_rows") else [control.model_row(wheels,
                                                                                                         tables)]
        if control.reads_orbit and orbit_row[0] == km.ORBIT_NONE:
            raise InputError(f"control: {control!r} reads the orbit (its target or its field), and "
                             f"{type(potential).__name__} has none; give a potential with an orbit (a gravity gradient, "
                             "orbatt.EnvironmentTorques(orbit, t_end, ...))")
        rows.extend(own)
        navigation = getattr(control, "navigation", None)
        if navigation is not None:  # the sensors and the filter (orbatt.sensors): their state after the laws'
            z0 = 8 + len(wheels) + sum(int(p[kc.CTL_NZ]) for k, p, _ in own if k in FLIGHT_SOFTWARE_KINDS)
            rows.extend(navigation.model_rows(z0, tables))
    return KernelSpec(*km.build(orbit=orbit_row, terms=rows))

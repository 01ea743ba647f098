"""The variables of a controlled run or of a body with reaction wheels (issue 12): the torque
the control applies, the B-dot dipole, the wheels' speeds and momenta, and the body rate and
kinetic energy of the gyrostat (which replace the rigid body's in :func:`to_dataset`).

Computed from the outputs by :func:`orbatt.core.gyrostat.evaluate_extended`, the kernel the
integration used; nothing is integrated here.
"""
from __future__ import annotations

import numpy as np

from .. import canonical as cn
from ..core import kernel_floats
from ..core import gyrostat as kg
from ..core import potentials as kp
from ..methods.problem import kernel_spec
from ..model_assembly import command_size
from ..core import control as kc
from ..core import model as km
from ..core import mode_state
from ..laws import law_of
from ..units import from_kernel
from .content import Var
from .navigation import navigation_variables

__all__ = ["control_variables", "wheel_coordinates"]


def _var(dims, data, units, long_name, **extra):
    attrs = {"units": units, "long_name": long_name}
    attrs.update(extra)
    return Var(tuple(dims), np.asarray(data), attrs)


def control_variables(trajectory, body, inertia, t, tdims, units):
    """The control and wheel variables of ``trajectory`` (an empty dict for a rigid body
    without control).

    Parameters
    ----------
    trajectory : Trajectory
        Its ``control`` law (if any) and ``wheel_momenta`` (the wheels' state).
    body : RigidBody
        The body (its ``wheels``).
    inertia : ndarray (3,) or (E, 3)
        Principal moments of each member (kg km^2).
    t : ndarray (N,)
        Output times (s).
    tdims : tuple
        ``("time",)`` or ``("case", "time")``.
    units : dict
        The unit spellings of the values: :data:`orbatt.units.INTERNAL_UNITS` (the kernels';
        :func:`orbatt.dataset.build.si_form` turns them into SI at the Dataset boundary) or
        :data:`orbatt.units.DIMENSIONLESS_UNITS`.

    Returns
    -------
    dict of Var
        ``omega`` (rad/s) and ``kinetic_energy`` (body + rotors, kg km^2 s^-2) of the gyrostat,
        and ``wheel_momentum`` (kg km^2/s, axial, absolute), ``wheel_speed`` (rad/s, relative to
        the body), ``wheel_torque`` (N m, motor) with a ``wheel`` dimension; with a control law
        ``torque_control`` (N m, body axes) and, for B-dot and momentum dumping, ``dipole_control``
        (A m^2).
    """
    control = trajectory.control
    wheels = body.wheels
    if control is None and not wheels:
        return {}
    ens = len(tdims) == 2
    q = np.asarray(trajectory.q, dtype=np.float64)
    Q = np.asarray(trajectory.Q, dtype=np.float64)
    h = trajectory.wheel_momenta
    members = q.shape[0] if ens else 1
    n = len(wheels)
    qs = q.reshape(members, -1, 4)
    Qs = Q.reshape(members, -1, 4)
    hs = (np.zeros(qs.shape[:2] + (0,)) if h is None else np.asarray(h, dtype=np.float64).reshape(members, -1, n))
    z = getattr(trajectory, "command", None)  # the flight software's held commands (issue 32)
    zs = (np.zeros(qs.shape[:2] + (0,)) if z is None else
          np.asarray(z, dtype=np.float64).reshape(members, qs.shape[1], -1))
    I = np.broadcast_to(np.asarray(inertia, dtype=np.float64), (members, 3))
    model = kernel_spec(trajectory.potential, [body], control)
    if command_size(model) != zs.shape[-1]:
        raise ValueError(f"the trajectory holds {zs.shape[-1]} flight-software commands, its control law "
                         f"{command_size(model)}: its `command` is missing or from another law")
    out = {k: [] for k in ("omega", "hvec", "tau", "m", "u")}
    for e in range(members):
        Y = np.ascontiguousarray(np.concatenate([qs[e], Qs[e], hs[e], zs[e]], axis=1))
        res = kg.evaluate_extended(kernel_floats(t), Y, kernel_floats(I[e]), *model, kp.new_work())
        for k, v in zip(out, res):
            out[k].append(v)
    shape = (lambda a: a) if ens else (lambda a: a[0])
    omega, hvec, tau, m, u = (shape(np.stack(out[k])) for k in out)
    vv = tdims + ("axis",)
    wv = tdims + ("wheel",)
    data = {}
    if wheels:
        iw = np.array([w.inertia for w in wheels])
        axes = np.array([w.axis for w in wheels])
        hw = shape(hs)
        g = cn.body_momentum(q, Q)
        T = 0.5 * np.sum((g - hvec) * omega, axis=-1) + np.sum(hw * hw / (2.0 * iw), axis=-1)
        data["omega"] = _var(vv, omega, units["rate"], "angular velocity of the body (body components)", frame="B",
                             comment="gyrostat: omega = J^-1 (g - h), J = I - sum Iw a a^T")
        data["kinetic_energy"] = _var(tdims, T, units["energy"], "kinetic energy of the body and the rotors",
                                      comment="1/2 (g - h).omega + sum h_k^2 / (2 Iw_k)")
        data["wheel_momentum"] = _var(wv, hw, units["momentum"], "axial angular momentum of each reaction wheel",
                                      comment="h_k = Iw_k (a_k.omega + speed_k), absolute")
        data["wheel_speed"] = _var(wv, hw / iw - np.einsum("...i,ki->...k", omega, axes), units["rate"],
                                   "speed of each reaction wheel relative to the body")
        data["wheel_torque"] = _var(wv, from_kernel(u, "torque"), "N m", "motor torque of each reaction wheel",
                                    comment="dh_k/dt; the body feels -u_k a_k")
    if control is not None:
        data["torque_control"] = _var(vv, from_kernel(tau, "torque"), "N m",
                                      "torque the attitude control applies to the body (body components)", frame="B",
                                      control_law=control.law,
                                      comment=("reaction of the wheels' motors (internal)" if
                                               getattr(control, "actuator", "") == "wheels" else "external torque"))
        outputs = {"dipole": m}  # the kernel's outputs a law may write (orbatt.laws.LawVar.values)
        for var in law_of(control).variables_of(control.settings()):
            data[var.name] = _var(vv, from_kernel(outputs[var.values], var.kind), var.unit, var.long_name, frame="B")
        col = mode_column(model, n)
        if col is not None:  # a mode sequence (orbatt.modes): its state (mode, entry time, ...)
            names = control.names
            mode = zs[..., col].reshape(q.shape[:-1])
            data["mode"] = _var(tdims, np.where(np.isnan(mode), -1, mode).astype(np.int8), "1",
                                "mode of the flight software's sequence", flag_values=np.arange(len(names), dtype=np.int8),
                                flag_meanings=" ".join(names),
                                comment="the mode at the output time (a transition at a tick acts from that tick)")
            entry = mode_entry_times(zs if ens else zs[0], col, len(names))
            data["mode_entry_time"] = _var(tdims[:-1] + ("mode_index",), entry, units["time"],
                                           "time each mode of the sequence began (NaN: not entered by the last output)",
                                           comment="mode_index k is flag value k of the variable mode: "
                                                   + ", ".join(f"{k} = {nm}" for k, nm in enumerate(names)))
        navigation = getattr(control, "navigation", None)
        if navigation is not None:  # the sensors and the filter (issue 33)
            data.update(navigation_variables(model, qs if ens else qs[0], shape(zs), t, tdims, n, navigation))
    return data


def mode_column(model, nwheels):
    """The column of a mode sequence's state in a trajectory's ``command`` (None without one)."""
    terms, params, _ = model
    for j in range(1, terms.shape[0]):
        if int(terms[j, km.KIND]) == km.MODES:
            return int(params[terms[j, km.P0] + kc.CTL_Z0]) - 8 - nwheels
    return None


def mode_entry_times(command, column, count):
    """The time each mode of a sequence began, from its state along the outputs.

    Parameters
    ----------
    command : ndarray (..., n_outputs, n_commands)
        The flight software's states at the outputs (a trajectory's ``command``), kernel units.
    column : int
        Where the sequence's state begins in them (:func:`mode_column`; its layout:
        :mod:`orbatt.core.mode_state`).
    count : int
        The sequence's number of modes.

    Returns
    -------
    ndarray (..., count)
        The entry times (s, the kernels' time), exact also for a mode entered and left between
        two outputs; NaN for a mode not entered by the last output.
    """
    z = np.asarray(command, dtype=np.float64)
    mode = z[..., column + mode_state.MODE]
    began = z[..., column + mode_state.ENTRIES:column + mode_state.ENTRIES + count]
    entered = mode[..., None] >= np.arange(count)  # (an unset state, NaN: none)
    at = np.where(entered, began, np.inf).min(axis=-2, initial=np.inf)
    return np.where(np.isinf(at), np.nan, at)


def wheel_coordinates(body, units):
    """The ``wheel`` coordinate and the wheels' axes (``wheel_axis``) of a body with wheels."""
    if not body.wheels:
        return {}
    n = len(body.wheels)
    return {"wheel": _var(("wheel",), np.arange(n), "1", "reaction wheel index"),
            "wheel_axis": _var(("wheel", "axis"), np.array([w.axis for w in body.wheels]), "1",
                               "spin axis of each reaction wheel (body components)", frame="B"),
            "wheel_inertia": _var(("wheel",), np.array([w.inertia for w in body.wheels]), units["inertia"],
                                  "axial moment of inertia of each rotor")}

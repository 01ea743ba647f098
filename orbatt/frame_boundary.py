"""The boundary between the user's body frame ``B`` and the principal frame ``P`` the kernels
integrate in (a body given by a full inertia tensor, :mod:`orbatt.body_frame`).

The change is made once per run, here, and nowhere else:

* **in** (:func:`principal_run`, called by :func:`orbatt.propagate`): the bodies become their
  :attr:`~orbatt.RigidBody.principal` bodies (principal moments, wheel axes ``R^T a``), the
  initial state ``q_P = q_B r``, ``Q_P = Q_B r``, and every body-fixed input of the potential
  and the control law turns by ``R^T`` where it enters the kernel model
  (:func:`principal_potential`, :func:`principal_control`): the heavy top's centre of mass, the
  facets' normals and centres of pressure, the residual dipole, the constant body torque, a PD
  law's body axis ``target_axis`` (Sun, ground) and its target attitude ``target_q`` (inertial,
  or relative to the orbital frame: ``target_q r``; the default orbital target, the identity,
  becomes ``r``). Initial rates, ``euler_313`` and frames of ``[initial]`` are taken in ``B`` by
  :class:`orbatt.State` (``State.from_omega`` of a tensor body: ``g = I_B omega + h``).
* **limits per body axis** (a PD law's ``max_torque``, ideal or on wheels; the magnetorquers'
  ``max_dipole``; B-dot's ``max_dipole``; dumping's ``dump_max_dipole``) clip each axis of ``B``:
  the law's copy in ``P`` carries ``limit_axes = R``, its rows the slots
  :data:`orbatt.core.control.LIMIT_FRAME`, and the kernels clip ``R^T clip(R v_P)``; a PD law's
  integral is then held in ``B`` components (its anti-windup gate per body axis).
* **sensors and the filter** (:func:`principal_navigation`): the gyro's and the magnetometer's
  biases, the star tracker's boresight and misalignment turn by ``R^T``; the noise is drawn per
  axis of ``P``: for isotropic noise (the gyro's, the magnetometer's, the Sun sensor's, the
  filter's initial errors, a star tracker with ``noise_roll = noise``) the same distribution as
  per body axis, but not the same realization as a principal-axes run of the same seed. A star
  tracker's ``noise_roll`` (about the body axis nearest the boresight, as without a tensor) is
  kept when that body axis is principal (``R^T diag(sigma^2) R`` diagonal to
  :data:`NOISE_DIAGONAL`), else refused.
* **out**: the :class:`~orbatt.trajectory.Trajectory` holds ``q_B = q_P r~`` and ``Q_B = Q_P
  r~`` and the user's body, potential and law (:func:`body_trajectory`); the Dataset
  (:func:`principal_trajectory` to compute with the kernels, then :func:`body_variables`)
  turns every body-axes variable (``frame = "B"``: ``omega``, ``g``, the torques, ``wheel_axis``,
  ``dipole_control``, ``knowledge_error``, ``bias_estimate``, ``gyro_bias``, ``gyro_measurement``
  ...) back with ``R``, and the attitude family (``q_orbital``, ``q_estimate``, the Euler angles)
  with ``r~``, while ``q`` and ``Q`` are the Trajectory's own (bit for bit; ``(q_B r) r~`` may
  differ in the last bit); ``knowledge_sigma`` is made in ``B`` from ``R P_att R^T``
  (:func:`orbatt.dataset.navigation.navigation_variables`); it records ``inertia_tensor``
  (``B``) and ``principal_axes`` (``R``) beside the principal moments ``inertia``.
* **sweeps** (``[sweep]`` of a tensor scenario; its inertia is not swept: the cases share one
  principal frame): each case is built as its single run (the user's body and ``State`` in
  ``B``, ``State.from_omega`` per case) and run through :func:`principal_run` by
  :func:`orbatt.propagate`, so that it equals its single run bit for bit; the per-case outputs
  derived with the kernels (:func:`orbatt.crossings.study_series`, the energy, a PD law's own
  pointing error, the knowledge error, a mode's entry) take the case's outputs into ``P`` with
  :func:`principal_outputs`, as the Dataset does, and give body vectors back in ``B``; the
  others (the states, pointing errors about a body axis, ``final_wheel_momentum``) are computed
  in ``B`` from the Trajectory's ``q_B``, ``Q_B`` and the user's wheel axes.

A diagonal tensor has no frame (``RigidBody.frame`` None): nothing here touches its run, which
stays bit for bit the principal-axes run. A law of a tensor body without a finite per-axis
limit gets no limit frame in its row (``framed = 0``): the arithmetic it had before. The held commands of a run (``Trajectory.command``) stay in ``P`` (a PD law's
integral with a limit frame: in ``B``).
"""
from __future__ import annotations

import copy
import dataclasses

import numpy as np

from . import quaternion as qt
from .control import BDotControl, PDControl
from .errors import InputError
from .modes import ModeSequence
from .orbital import lvlh_angles
from .potentials import GravityGradient, HeavyTop, TorqueFree
from .state import State
from .torques import TERM_KEYWORDS, EnvironmentTorques, Facet

__all__ = ["frame_of", "principal_run", "principal_potential", "principal_control", "principal_navigation",
           "body_trajectory", "principal_trajectory", "principal_outputs", "body_variables", "NOISE_DIAGONAL"]

def frame_of(bodies):
    """The :class:`~orbatt.body_frame.BodyFrame` shared by ``bodies`` (a RigidBody or a list),
    or None when their axes are principal; members with different frames are refused (one
    kernel model serves them all)."""
    bodies = bodies if isinstance(bodies, (list, tuple)) else [bodies]
    frames = [getattr(b, "frame", None) for b in bodies]
    f = frames[0]
    if any((g is None) != (f is None) or (g is not None and g.key() != f.key()) for g in frames[1:]):
        raise InputError("body: the members of an ensemble have inertia tensors with different principal axes; "
                         "orbatt integrates them in one principal frame: give members whose tensors share "
                         "their principal axes")
    return f


def principal_control(law, frame):
    """``law`` (PDControl, BDotControl, ModeSequence or None) with its body-fixed settings in
    ``P`` and its sensors' (:func:`principal_navigation`), marked with the axes its per-axis
    limits clip along (module docstring); ``law`` itself when ``frame`` is None."""
    if frame is None or law is None:
        return law
    out = _principal_law(law, frame)
    navigation = getattr(law, "navigation", None)
    if navigation is not None:
        out.navigation = principal_navigation(navigation, frame)
    return out


def _principal_law(law, frame):
    if isinstance(law, ModeSequence):
        out = copy.copy(law)
        out.modes = []
        for m in law.modes:
            mm = copy.copy(m)
            mm.law = principal_control(m.law, frame)
            out.modes.append(mm)
        return out
    if not isinstance(law, (PDControl, BDotControl)):
        raise InputError(f"control: {type(law).__name__} is not known to orbatt.frame_boundary, which turns a law's "
                         "body-fixed settings into the principal frame of a full inertia tensor; give the inertia as "
                         "principal moments")
    out = copy.copy(law)
    out.__dict__.pop("_rows", None)
    out.limit_axes = frame.R  # max_torque, max_dipole, dump_max_dipole clip along B's axes (orbatt.core.control)
    if isinstance(law, BDotControl):
        return out
    if law.target_axis is not None:
        out.target_axis = frame.to_principal(law.target_axis)
    elif law.target not in ("sun", "ground"):  # an attitude target (inertial, or relative to a frame)
        tq = law.target_q if law.target_q is not None else np.array([1.0, 0.0, 0.0, 0.0])
        out.target_q = frame.attitude_to_principal(tq)
    return out


#: how close to diagonal (relative to its largest entry) the star tracker's noise covariance must
#: be in ``P`` for the kernel, which draws and weighs it per axis
NOISE_DIAGONAL = 1e-12


def principal_navigation(navigation, frame):
    """A copy of the :class:`~orbatt.sensors.Navigation` ``navigation`` in ``P`` (module
    docstring): the gyro's and the magnetometer's biases, the star tracker's boresight and
    misalignment turned by ``R^T``, the star tracker's noise per principal axis, and ``axes``
    (``R``), with which the Dataset turns the filter's covariance back to ``B``.

    Raises
    ------
    InputError
        A star tracker whose noise about the boresight (``noise_roll``) differs from ``noise``
        while the body axis it acts about is not a principal axis: its covariance is not
        diagonal in ``P``, and the kernel draws the noise per axis.
    """
    out = copy.copy(navigation)
    out.axes = frame.R
    if navigation.gyro is not None:
        out.gyro = copy.copy(navigation.gyro)
        out.gyro.bias = frame.to_principal(navigation.gyro.bias)
    if navigation.magnetometer is not None:
        out.magnetometer = copy.copy(navigation.magnetometer)
        out.magnetometer.bias = frame.to_principal(navigation.magnetometer.bias)
    st = navigation.star_tracker
    if st is not None:
        out.star_tracker = copy.copy(st)
        out.star_tracker.boresight = frame.to_principal(st.boresight)
        out.star_tracker.misalignment = frame.to_principal(st.misalignment)
        out.star_tracker.per_axis = _principal_sigma(st, frame)
    return out


def _principal_sigma(st, frame):
    """The star tracker's 1-sigma noise per principal axis: its body axes' (isotropic: the same
    values), or the diagonal of ``R^T diag(sigma^2) R`` when that is diagonal."""
    sigma = st.sigma()
    if st.noise_roll == st.noise:
        return sigma
    cov = frame.R.T @ np.diag(sigma ** 2) @ frame.R
    off = np.abs(cov - np.diag(np.diag(cov))).max()
    if off > NOISE_DIAGONAL * np.abs(cov).max():
        raise InputError(f"[sensors.star_tracker] noise_roll: {st.noise_roll:.6g} rad differs from noise = "
                         f"{st.noise:.6g} rad about body axis {int(np.argmax(np.abs(st.boresight))) + 1}, which is not a "
                         "principal axis of the full [body] inertia tensor; orbatt integrates in the principal axes "
                         "and draws the star tracker's noise per principal axis; give noise_roll = noise (isotropic "
                         "noise, the same in any axes), or a tensor one of whose principal axes is that body axis")
    return np.sqrt(np.diag(cov))


def principal_potential(potential, frame):
    """``potential`` with its body-fixed inputs (and a law it carries) in ``P``; itself when
    ``frame`` is None. Made once per potential and frame (kept on the potential)."""
    if frame is None:
        return potential
    cache = potential.__dict__.setdefault("_principal", {}) if hasattr(potential, "__dict__") else {}
    hit = cache.get(frame.key())
    if hit is None:
        hit = cache[frame.key()] = _rotated(potential, frame)
    return hit


def _rotated(potential, frame):
    if type(potential) in (TorqueFree, GravityGradient):
        return potential  # no body-fixed input: the moments come with the body
    out = copy.copy(potential)
    for k in ("_kernel_cache", "_principal"):
        out.__dict__.pop(k, None)
    if type(potential) is HeavyTop:
        p = np.array(potential.params, dtype=np.float64)
        p[1:] = frame.to_principal(p[1:])
        p.flags.writeable = False
        out.params = p
        return out
    if type(potential) is not EnvironmentTorques:
        raise InputError(f"potential: {type(potential).__name__} has no known body-fixed inputs to turn into the "
                         "principal frame of a full inertia tensor; give the inertia as principal moments")
    for name in TERM_KEYWORDS:
        if getattr(potential, name, None) is not None:
            raise InputError(f"{name}: a torque term without a known frame change; give the inertia as principal "
                             "moments")
    out.facets = [Facet(f.area, frame.to_principal(f.normal), frame.to_principal(f.position.value) * f.position.unit,
                        f.drag_coefficient, f.specular, f.diffuse) for f in potential.facets]
    for name in ("residual_dipole", "constant_torque"):  # plain floats in their units (A m^2, N m)
        v = getattr(potential, name)
        if v is not None:
            setattr(out, name, frame.to_principal(v.value) * v.unit if hasattr(v, "unit") else frame.to_principal(v))
    out.control = principal_control(potential.control, frame)
    return out


def principal_run(body, state0, potential, control):
    """``(frame, body, state0, potential, control)`` of a run in ``P``: the inputs of
    :func:`orbatt.propagate` (``body`` a RigidBody or a list) turned into the principal frame
    of their tensor, or returned as they are with ``frame`` None. ``control``: the law given
    beside the potential (None when the potential carries it)."""
    bodies = body if isinstance(body, (list, tuple)) else None
    frame = frame_of(body) if (bodies is None or bodies) else None
    if frame is None:
        return None, body, state0, potential, control
    pbody = [b.principal for b in bodies] if bodies is not None else body.principal
    if not isinstance(state0, State):
        raise InputError("state0: expected an orbatt.State (built with the body)")
    if getattr(state0.body, "frame", None) is None or state0.body.frame.key() != frame.key() or (
            bodies is not None and state0.body is not bodies[0] and state0.body.principal != pbody[0]):
        raise InputError("state0: the state was built with another body than the one propagated (its body frame "
                         "differs); build it with State(body, ...) of the body given by its inertia tensor")
    pstate = frame.principal_state(state0)
    return frame, pbody, pstate, principal_potential(potential, frame), principal_control(control, frame)


def body_trajectory(tr, frame, body, potential, control):
    """The trajectory ``tr`` of a run in ``P`` as the user's: ``q_B = q_P r~``, ``Q_B = Q_P r~``
    and the user's ``body`` (the first of an ensemble), ``potential`` and ``control``; ``tr``
    itself when ``frame`` is None. ``command`` (the flight software's held commands, kernel
    state) stays in ``P``."""
    if frame is None:
        return tr
    return dataclasses.replace(tr, body=body, potential=potential, control=control,
                               q=frame.attitude_to_body(tr.q), Q=frame.attitude_to_body(tr.Q))


def principal_trajectory(tr):
    """A user's trajectory (body frame ``B``) in ``P`` for the kernels that derive the
    Dataset's variables from it; ``tr`` itself for a body whose axes are principal."""
    frame = getattr(tr.body, "frame", None)
    if frame is None:
        return tr
    pot = principal_potential(tr.potential, frame)
    carried = getattr(tr.potential, "control", None)
    control = getattr(pot, "control", None) if tr.control is carried else principal_control(tr.control, frame)
    return dataclasses.replace(tr, body=tr.body.principal, potential=pot, control=control,
                               q=frame.attitude_to_principal(tr.q), Q=frame.attitude_to_principal(tr.Q))


def principal_outputs(potential, body, q, Q):
    """``(potential, body, q, Q)`` of a run's outputs in ``B`` (``q, Q (..., 4)``, the user's
    ``potential`` with the law it carries, the user's ``body``) in ``P``, for the kernels that
    derive a sweep's per-case outputs from them (:func:`orbatt.crossings.study_series`): the
    principal potential and body, ``q_B r`` and ``Q_B r`` (what :func:`principal_trajectory`
    does to a Trajectory); as given for a body whose axes are principal."""
    frame = getattr(body, "frame", None)
    if frame is None:
        return potential, body, q, Q
    return (principal_potential(potential, frame), body.principal,
            np.ascontiguousarray(frame.attitude_to_principal(q)), np.ascontiguousarray(frame.attitude_to_principal(Q)))


#: body-axes variables made in B already: the tensor, and the filter's 1-sigma per body axis
#: (the square root of the diagonal of R P R^T, :func:`orbatt.dataset.navigation.navigation_variables`)
_IN_B = ("inertia_tensor", "knowledge_sigma")


def _columns(a, b, c):
    return np.stack([a, b, c], axis=-1)


def body_variables(body, data, coords, run_qQ=None):
    """``(data, coords)`` (name -> :class:`~orbatt.dataset.content.Var`, computed in ``P``) in
    the body frame of ``body``: body-axes variables (``frame = "B"``, an ``axis`` dimension)
    times ``R``, the attitude family times ``r~`` (``q``, ``Q``, ``q_orbital``; ``euler_313``
    and ``euler_321`` made again from them), ``inertia`` marked as the principal moments, and
    the tensor recorded (``inertia_tensor``, ``principal_axes``). A body given by principal
    moments: unchanged; a diagonal tensor only gets ``inertia_tensor``. ``run_qQ``: the run's
    ``(q, Q)`` in ``B`` (its :class:`~orbatt.trajectory.Trajectory`'s), written as they are
    rather than turned back from ``P`` (``(q_B r) r~`` may differ from ``q_B`` in the last bit),
    so that the Dataset holds the run's attitude bit for bit (a sweep's case its single run's)."""
    from .dataset.content import Var

    if body.tensor is None:
        return data, coords
    frame = body.frame
    inertia = data["inertia"]
    lead = inertia.dims[:-1]
    moments = np.asarray(inertia.values, dtype=np.float64)  # (3,) or (E, 3): each member's (ensembles over bodies)
    own = np.array(body.tensor)
    tensor = np.empty(moments.shape[:-1] + (3, 3))
    for idx in np.ndindex(moments.shape[:-1]):
        m = moments[idx]
        tensor[idx] = own if np.array_equal(m, body.inertia_value) else (
            np.diag(m) if frame is None else frame.R @ np.diag(m) @ frame.R.T)
    data = dict(data)
    data["inertia_tensor"] = Var(lead + ("axis", "axis_column"), tensor, {
        "units": inertia.attrs["units"], "frame": "B",
        "long_name": "inertia tensor about the centre of mass (body components)",
        "comment": "as given ([body] inertia); off-diagonal entries I_xy = -integral of x y dm; "
                   "I_B = R diag(inertia) R^T with R = principal_axes"})
    if frame is None:
        return data, coords
    R = np.array(frame.R)
    data["principal_axes"] = Var(("axis", "axis_column"), R, {
        "units": "1", "long_name": "principal axes of inertia (columns, body components)",
        "comment": "x_B = R x_P: column k is principal axis k, the axis of the principal moment inertia[k]; "
                   "orbatt integrates in P and writes every body-axes variable in B"})
    data["inertia"] = Var(inertia.dims, inertia.values, dict(inertia.attrs, frame="P", long_name=(
        "principal moments of inertia (I1, I2, I3) about the principal axes (principal_axes)")))

    def turned(variables):
        out = {}
        for name, var in variables.items():
            if var.attrs.get("frame") == "B" and var.dims[-1:] == ("axis",) and name not in _IN_B:
                var = Var(var.dims, frame.to_body(var.values), var.attrs)
            elif name in ("q", "Q") and run_qQ is not None:
                var = Var(var.dims, np.array(run_qQ[name == "Q"], dtype=np.float64), var.attrs)
            elif name in ("q", "Q", "q_orbital", "q_estimate"):
                var = Var(var.dims, frame.attitude_to_body(var.values), var.attrs)
            out[name] = var
        return out

    data, coords = turned(data), turned(coords)
    e = data["euler_313"]
    data["euler_313"] = Var(e.dims, _columns(*qt.to_euler313(data["q"].values)), e.attrs)
    if "euler_321" in data:
        e = data["euler_321"]
        data["euler_321"] = Var(e.dims, _columns(*lvlh_angles(data["q_orbital"].values)), e.attrs)
    return data, coords

"""One chunk of a sweep: the physics of its cases and its Dataset (what every task runs).

A chunk is a range of cases computed together: its cases are grouped by identical orbit and
each group is **one ensemble call** of :func:`orbatt.propagate`. Every per-case quantity
(initial state, pointing error, energy) is computed per case - elementwise, with sums over
the last axis written out - never through BLAS or a reduction across cases: a member's
result must not depend on how many members share the call, nor on the CPU (issue 14).
Quantities are in internal units (:mod:`orbatt.units`); frames as in ``docs/design.md`` §1.
"""
from __future__ import annotations

import copy
import dataclasses
import functools
import json
import time
import warnings

import numpy as np

from .. import canonical as cn
from .. import quaternion as qt
from ..core import kernel_floats
from ..core import evaluation as kev
from ..core import potentials as kp
from ..core import gyrostat as kg
from ..methods.problem import kernel_spec
from ..dataset import AXIS_INDEX, AXIS_LABELS, DIMENSIONAL_UNITS, DIMENSIONLESS_UNITS, QUAT_INDEX, QUAT_LABELS
from ..dataset import cf_variable, to_dataset
from ..errors import IntegrationError
from ..frame_boundary import principal_outputs
from ..laws import law_of
from ..scenario import FieldContext, Scenario, build_kepler_orbit, build_potential, build_rebound_orbit, parse
from ..scenario.binary_schema import BinarySpec
from ..units import from_kernel, to_output
from ..scenario.sweep_schema import (INERTIA_PARAMETERS, ORBIT_PARAMETERS, RATE_PARAMETERS,
                                     sweep_units)
from .sampling import nominal_rates
from .case_groups import path_groups
from .binary_chunk import compute_binary_chunk
from .case_coords import parameter_coordinates
from .stats import add_stats
from ..sweep_outputs import DIMS, OUTPUTS, study_outputs, target_pointing_error, variable_shape
from ..state import State, unit_quaternion
from ..orbital import body_rate_from_orbital
from ..orbits.base import as_times
from ..propagation import propagate
from ..trajectory import Trajectory
from ..body import RigidBody

__all__ = ["run_chunk", "compute_chunk", "orbit_groups", "initial_states", "propagate_group", "pointing_error",
           "conserved_energy", "scenario_from_text", "chunk_dataset", "concat_cases"]

_ELEMENT = {"orbit_a": "a", "orbit_e": "e", "orbit_i": "i", "orbit_raan": "raan", "orbit_argp": "argp",
            "orbit_true_anomaly": "anomaly", "orbit_mean_anomaly": "anomaly"}


@functools.lru_cache(maxsize=4)
def scenario_from_text(text, source):
    """The :class:`~orbatt.scenario.Scenario` of a scenario text (cached per process, so a
    worker builds a scenario's orbit and kernels once; warnings silenced: the driver warned)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Scenario(parse(text, source), path=source)


def run_chunk(job, on_cases=None, scenario=None):
    """Task function: compute one chunk from its payload (:meth:`orbatt.sweep.Sweep.job`);
    the Dataset's ``sweep_chunk_seconds`` attribute holds the task's wall time.
    ``on_cases(k)``, if given, is called as each group of ``k`` cases is done (progress per
    case in this process); ``scenario``: the nominal scenario of ``job["text"]`` when this
    process has it (else built from the text, once per process)."""
    t0 = time.perf_counter()
    threads = job.get("numba_threads")
    if threads:
        import numba

        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    sc = scenario if scenario is not None and scenario.text == job["text"] else \
        scenario_from_text(job["text"], job["source"])
    ds = compute_chunk(sc, sc.spec.sweep, job, sweep_units(sc.spec.sweep, sc.spec.dimensionless), on_cases)
    ds.attrs["sweep_chunk_seconds"] = time.perf_counter() - t0
    return ds


def orbit_groups(sc, spec, values, n):
    """``[(orbit, potential, idx)]``: the chunk's ``n`` cases grouped by identical orbit, in
    order of first appearance (one group with the nominal orbit when no element varies)."""
    swept = [k for k in ORBIT_PARAMETERS if k in spec.parameters]
    if not swept:
        return [(sc.orbit, sc.potential, np.arange(n))]

    cols = np.stack([values[k] for k in swept], axis=-1)
    keys, first, inverse = np.unique(cols, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    ctx = FieldContext(sc.name)
    out = []
    for g in np.argsort(first):
        o = dict(sc.spec.orbit)
        for k, v in zip(swept, keys[g]):
            o[_ELEMENT[k]] = float(v)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # periapsis warnings: the nominal scenario already warned
            orbit = build_kepler_orbit(ctx, o)
            if o["provider"] == "rebound":
                orbit = build_rebound_orbit(ctx, o, orbit, float(sc.times[-1]))
            # the single run's builder: the gravity gradient, or the environment torques and
            # control law along this orbit (sampled over the run as the case's own run samples them)
            potential = build_potential(dataclasses.replace(sc.spec, orbit=o), orbit, float(sc.times[-1]))
        out.append((orbit, potential, np.flatnonzero(inverse == g)))
    return out


def initial_states(sc, spec, values, axis, inertia, orbit, idx):
    """``(q, Q)`` (m, 4) of the cases ``idx``, inertial components (``docs/sweeps.md``: the
    initial state of a case): built from each case's attitude and rates with its own inertia
    ``inertia[idx]`` and ``orbit``; the nominal state as is when no parameter touches it."""

    m = idx.size
    frame = sc.spec.frame
    touches = (any(k in spec.parameters for k in INERTIA_PARAMETERS + RATE_PARAMETERS + ("attitude_angle",))
               or (frame == "orbital" and any(k in spec.parameters for k in ORBIT_PARAMETERS)))
    if not touches:
        st = sc.state0
        return np.broadcast_to(st.q, (m, 4)).copy(), np.broadcast_to(st.Q, (m, 4)).copy()
    ini = sc.spec.initial
    w = np.array(np.broadcast_to(nominal_rates(sc), (m, 3)))
    for k, name in enumerate(RATE_PARAMETERS):
        if name in values:
            w[:, k] = values[name][idx]
    if frame == "orbital":
        q_nom = ini["q"] if "q" in ini else qt.from_euler313(*ini["euler_313"])
        q_nom = q_nom / qt.norm(q_nom)
    else:
        q_nom = sc.state0.q
    q_c = np.array(np.broadcast_to(q_nom, (m, 4)))
    if "attitude_angle" in spec.parameters:
        q_c = qt.mul(q_c, qt.from_axis_angle(axis[idx], values["attitude_angle"][idx]))
    if frame == "orbital":

        t0 = as_times(float(sc.times[0]))
        q = qt.mul(orbit.orbital_quaternion(t0), q_c)
        w = body_rate_from_orbital(orbit, t0, q_c, w)
    else:
        q = q_c
    q = unit_quaternion(q)
    if sc.body.wheels or sc.body.frame is not None:
        # a gyrostat (Q holds the wheels' momentum too) or a full inertia tensor (g = I_B omega, in
        # B): State.from_omega of each case, as the case's own run builds it (a tensor is not swept)
        iu = sc.body.inertia_unit
        Q = np.empty((m, 4))
        for e in range(m):
            body = sc.body if sc.body.frame is not None else RigidBody(
                inertia[idx[e]].tolist() if sc.body.dimensionless else inertia[idx[e]] * iu, wheels=sc.body.wheels)
            Q[e] = State.from_omega(body, q[e], w[e] if body.dimensionless else w[e] * body.rate_unit).Q
        return q, Q
    st = State(sc.body, q, cn.momentum_from_omega(q, w, inertia[idx]))
    return st.q, st.Q


def noise_potential(potential, case):
    """``potential`` whose control law's sensors (:class:`orbatt.Navigation`) draw the noise of
    sweep case ``case`` (the ``case`` word of the key: :mod:`orbatt.core.noise`), sharing its
    tables and kernel model (shallow copies); ``potential`` itself without sensors."""
    law = getattr(potential, "control", None)
    nav = getattr(law, "navigation", None)
    if nav is None:
        return potential
    nav_k, law_k, pot_k = copy.copy(nav), copy.copy(law), copy.copy(potential)
    pot_k.__dict__.pop("_principal", None)  # (a tensor body's copy in P, orbatt.frame_boundary: the nominal's)
    nav_k.case = int(case)
    law_k.navigation = nav_k
    pot_k.control = law_k
    return pot_k


def propagate_group(sc, bodies, q0, Q0, potential, cases=None):
    """Ensemble propagation of one group: ``(trajectory or None, q, Q, failed, stats)``,
    ``q, Q`` (m, N, 4); the trajectory's ``wheel_momenta`` (m, N, n) hold the wheels' momenta
    of a gyrostat. A member that fails is rerun alone and left NaN (members are independent,
    so the others' results do not change). ``cases`` (m,): the members' case numbers, which
    a law with sensors needs (each case draws its own noise, :func:`noise_potential`): each
    member then runs alone."""

    kw = dict(sc.settings)
    m = q0.shape[0]
    failed = np.zeros(m, dtype=bool)
    noisy = cases is not None and getattr(getattr(potential, "control", None), "navigation", None) is not None
    if not noisy:
        try:
            tr = propagate(bodies if len(bodies) > 1 else bodies[0], State(sc.body, q0, Q0), potential, sc.times,
                           method=sc.method, **kw)
            return tr, tr.q, tr.Q, failed, dict(tr.stats)
        except IntegrationError:
            pass
    N = sc.times.size
    q = np.full((m, N, 4), np.nan)
    Q = np.full((m, N, 4), np.nan)
    W = None
    stats = {}
    tr = None
    for e in range(m):
        b = bodies[e] if len(bodies) > 1 else bodies[0]
        pot = noise_potential(potential, cases[e]) if noisy else potential
        try:
            t1 = propagate([b], State(sc.body, q0[e:e + 1], Q0[e:e + 1]), pot, sc.times, method=sc.method, **kw)
        except IntegrationError:
            failed[e] = True
            continue
        tr = t1
        q[e], Q[e] = t1.q[0], t1.Q[0]
        x1 = t1.extended  # the wheels' momenta and the flight software's held commands
        if x1 is not None:
            if W is None:
                W = np.full((m, N, x1.shape[-1]), np.nan)
            W[e] = x1[0]
        add_stats(stats, t1.stats)
    if tr is not None:
        nw = 0 if tr.wheel_momenta is None else tr.wheel_momenta.shape[-1]
        tr = dataclasses.replace(tr, q=q, Q=Q, wheel_momenta=None if W is None or not nw else W[..., :nw],
                                 command=None if W is None or W.shape[-1] == nw else W[..., nw:])
    return tr, q, Q, failed, stats


def _norm3(v):
    """``|v|`` of 3-vectors ``v (..., 3)``, per vector (written out, left to right)."""
    return np.sqrt(v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1] + v[..., 2] * v[..., 2])


def pointing_error(spec, q, p):
    """Angle (rad) between the body and the reference frame at every output.

    Parameters
    ----------
    spec : SweepSpec
        Its ``pointing_axis`` (body components) selects the angle between that body axis and
        the reference axis with the same components; None: the whole attitude's rotation angle.
    q : ndarray (m, N, 4)
        Attitudes (body -> inertial).
    p : ndarray (N, 4) or None
        Orbital quaternion (orbital -> inertial) for the orbital reference; None: inertial.

    Returns
    -------
    ndarray (m, N)
    """
    q_rel = q if p is None else qt.mul(qt.conj(p)[None], q)
    if spec.pointing_axis is None:
        return 2.0 * np.arctan2(_norm3(q_rel[..., 1:]), np.abs(q_rel[..., 0]))
    b = spec.pointing_axis
    b_ref = qt.rotate(q_rel, b)  # the body axis in reference-frame components
    cos = b_ref[..., 0] * b[0] + b_ref[..., 1] * b[1] + b_ref[..., 2] * b[2]
    return np.arctan2(_norm3(np.cross(b_ref, b)), cos)


def conserved_energy(spec, potential, orbit, inertia, q, Q, t, body=None):
    """The conserved energy of members ``q, Q (m, 4)`` at time ``t``: ``H = T + U``
    (``spec.energy == "hamiltonian"``) or the Jacobi integral ``H - n h.G`` (``"jacobi"``:
    ``n`` the orbit's mean motion, ``h`` its normal, ``G`` the space angular momentum);
    ``inertia (m, 3)`` the principal moments. Energy unit of the scenario (kg km^2 s^-2, or
    plain). ``body``: the members' body; one given by a full inertia tensor has ``q, Q`` of its
    body frame ``B``, evaluated in its principal frame (``q_B r``, the principal potential:
    :func:`orbatt.frame_boundary.principal_outputs`; ``H`` and ``G`` do not depend on the body
    axes)."""
    if body is not None:
        potential, _, q, Q = principal_outputs(potential, body, q, Q)
    g = cn.body_momentum(q, Q)
    T = 0.5 * (g[:, 0] * g[:, 0] / inertia[:, 0] + g[:, 1] * g[:, 1] / inertia[:, 1]
               + g[:, 2] * g[:, 2] / inertia[:, 2])
    Upot = np.empty(q.shape[0])
    tt = np.array([t], dtype=np.float64)
    model = potential.kernel_model()
    for e in range(q.shape[0]):
        if not np.all(np.isfinite(q[e])):
            Upot[e] = np.nan
            continue
        Upot[e] = kev.evaluate_many(tt, kernel_floats(q[e:e + 1]), kernel_floats(inertia[e]), *model,
                                   kp.new_work())[0][0]
    H = T + Upot
    if spec.energy == "jacobi":
        h = qt.rotate(orbit.orbital_quaternion(np.array(0.0)), np.array([0.0, 0.0, 1.0]))
        G = cn.space_momentum(q, Q)
        H = H - orbit.n_value * (G[:, 0] * h[0] + G[:, 1] * h[1] + G[:, 2] * h[2])
    return H


def compute_chunk(sc, spec, job, units, on_cases=None):
    """Compute the cases of a task's payload ``job`` (:meth:`orbatt.sweep.Sweep.job`).

    Parameters
    ----------
    sc : Scenario
        The nominal scenario.
    spec : SweepSpec
        Its ``[sweep]`` table.
    job : dict
        ``start``, ``stop``, ``values`` (the chunk's parameter values), ``axis``.
    units : dict
        CF unit string of every parameter (:func:`~orbatt.scenario.sweep_schema.parameter_units`).
    on_cases : callable, optional
        Called with the number of cases of each group as it is done (binary chunks: once, at
        the end).

    Returns
    -------
    xarray.Dataset
        The cases' outputs along ``case``; ``integration_stats`` (JSON) summed over groups.
    """

    if isinstance(sc.spec, BinarySpec):  # a binary: each case its own coupled run (binary_chunk.py)
        ds = compute_binary_chunk(sc, spec, job, units)
        if on_cases is not None:
            on_cases(job["stop"] - job["start"])
        return ds
    start, stop = job["start"], job["stop"]
    n = stop - start
    values = job["values"]
    axis = job["axis"]
    dimless = sc.spec.dimensionless
    inertia = np.array(np.broadcast_to(sc.spec.inertia, (n, 3)), dtype=np.float64)
    for k, name in enumerate(INERTIA_PARAMETERS):
        if name in values:
            inertia[:, k] = values[name]
    vary_inertia = any(k in spec.parameters for k in INERTIA_PARAMETERS) and not spec.paths
    all_bodies = None
    if vary_inertia:

        iu = sc.body.inertia_unit
        all_bodies = [RigidBody(inertia[e].tolist() if dimless else inertia[e] * iu, wheels=sc.body.wheels)
                      for e in range(n)]
    outs = set(spec.outputs)
    res = {name: np.empty((n, 4)) for name in ("q_initial", "Q_initial", "q_final", "Q_final")}
    res.update(inertia=inertia, failed=np.zeros(n, dtype=bool), pointing_error=np.full(n, np.nan),
               energy_error=np.full(n, np.nan))
    study = [OUTPUTS[o] for o in spec.outputs if OUTPUTS[o].compute is not None]
    for o in study:  # NaN until computed (-1 for a flag: failed)
        for var in o.variables:
            shape = (n,) + variable_shape(var, sc)
            res[var.name] = np.full(shape, -1, dtype=np.int8) if var.kind == "flag" else np.full(shape, np.nan)
    stats = {}
    pieces = []
    for group_sc, idx, bodies, q0, Q0 in _groups(sc, spec, values, axis, inertia, n, all_bodies if vary_inertia
                                                 else None):
        orbit, potential = group_sc.orbit, group_sc.potential
        inertia[idx] = [b.inertia_value for b in bodies] if len(bodies) == idx.size else inertia[idx]
        # each case draws its own sensor noise (its number: the case word of the noise key)
        words = None if "sensors.case" in spec.paths else start + idx
        tr, q, Q, bad, st = propagate_group(group_sc, bodies, q0, Q0, potential, cases=words)
        add_stats(stats, st)
        res["failed"][idx] = bad
        res["q_initial"][idx], res["Q_initial"][idx] = q0, Q0
        res["q_final"][idx], res["Q_final"][idx] = q[:, -1], Q[:, -1]
        if {"max_pointing_error", "tumbling"} & outs:
            p = orbit.orbital_quaternion(sc.times) if spec.pointing_reference == "orbital" else None
            res["pointing_error"][idx] = np.max(pointing_error(spec, q, p), axis=-1)
        if study:
            _study_of_group(sc, spec, potential, orbit, bodies, inertia, idx, tr, q, Q, bad, res)
        if "final_energy_error" in outs:
            E0 = conserved_energy(spec, potential, orbit, inertia[idx], q[:, 0], Q[:, 0], float(sc.times[0]),
                                  bodies[0])
            E1 = conserved_energy(spec, potential, orbit, inertia[idx], q[:, -1], Q[:, -1], float(sc.times[-1]),
                                  bodies[0])
            res["energy_error"][idx] = (E1 - E0) / np.abs(E0)
        if "trajectory" in outs:
            body0 = bodies[0]
            full = Trajectory(body=body0, potential=potential, t=sc.times, q=q, Q=Q,
                              inertia=inertia[idx], method=tr.method if tr is not None else sc.method,
                              settings=tr.settings if tr is not None else {}, stats=st, complete=True,
                              wheel_momenta=None if tr is None else tr.wheel_momenta,
                              command=None if tr is None else tr.command)
            with np.errstate(invalid="ignore"):
                piece = to_dataset(full, scenario_text=sc.text, title=f"orbatt sweep: {sc.name}")
            piece = piece.assign_coords(case=("case", start + idx, piece["case"].attrs))
            if any(k in spec.parameters for k in ORBIT_PARAMETERS):
                for name in ("r", "p", "true_anomaly", "position", "velocity"):
                    if name in piece:
                        piece[name] = piece[name].expand_dims(case=piece["case"].size).copy()
            pieces.append(piece)
        if on_cases is not None:
            on_cases(int(idx.size))

    return chunk_dataset(sc, spec, start + np.arange(n), values, axis, units, res, stats, pieces)


class _Group:
    """The part of a :class:`~orbatt.scenario.Scenario` a group of cases shares: the nominal
    scenario with another orbit and potential (named parameters vary the orbit)."""

    def __init__(self, sc, orbit, potential):
        self.times, self.settings, self.method, self.body = sc.times, sc.settings, sc.method, sc.body
        self.orbit, self.potential = orbit, potential


def _groups(sc, spec, values, axis, inertia, n, all_bodies):
    """``(scenario, idx, bodies, q0, Q0)`` of every group of the chunk: by their scenario paths
    (:func:`orbatt.sweep.case_groups.path_groups`), else by orbit (named parameters)."""
    if spec.paths:
        yield from path_groups(sc, spec, values, n)
        return
    for orbit, potential, idx in orbit_groups(sc, spec, values, n):
        q0, Q0 = initial_states(sc, spec, values, axis, inertia, orbit, idx)
        bodies = [all_bodies[e] for e in idx] if all_bodies is not None else [sc.body]
        yield _Group(sc, orbit, potential), idx, bodies, q0, Q0


def _study_of_group(sc, spec, potential, orbit, bodies, inertia, idx, tr, q, Q, failed, res):
    """The study outputs (:mod:`orbatt.sweep.study`) of the cases ``idx`` of one orbit group into
    ``res``, case by case (a failed case keeps NaN, and -1 for the saturation flags)."""
    control = getattr(potential, "control", None)
    by_target = control is not None and law_of(control).holds_frame(control.settings())
    p = None
    if orbit is not None and ((by_target and control.target == "orbital") or spec.pointing_reference == "orbital"):
        p = orbit.orbital_quaternion(sc.times)
    W = None if tr is None else tr.extended  # the wheels' momenta, then the held commands

    # a PD law pointing an axis (Sun, ground target) or holding the geodetic nadir: its own error,
    # as the kernel computes it along the run's orbit and tables
    by_law = (control is not None and not by_target and getattr(control, "law", None) == "pd")
    frame = bodies[0].frame  # a full inertia tensor: the law's error in its principal frame, as its run's
    law_potential, law_body = principal_outputs(potential, bodies[0], q[:0], Q[:0])[:2]
    model = kernel_spec(law_potential, [law_body]) if by_law else None

    def pointing(t, qq):
        if by_law:
            qk = qq if frame is None else frame.attitude_to_principal(qq)
            return kg.law_errors(kernel_floats(t), np.ascontiguousarray(qk), *model, kp.new_work())
        pp = None if p is None else (p if t is sc.times else orbit.orbital_quaternion(t))
        if by_target:
            return target_pointing_error(control, qq, pp)
        return pointing_error(spec, qq[None], pp if spec.pointing_reference == "orbital" else None)[0]

    for j, e in enumerate(idx):
        if failed[j]:
            continue
        body = bodies[j] if len(bodies) > 1 else bodies[0]
        h = None if W is None else np.ascontiguousarray(W[j])
        qj, Qj = np.ascontiguousarray(q[j]), np.ascontiguousarray(Q[j])
        for name, v in study_outputs(sc, spec, potential, body, inertia[e], qj, Qj, h, pointing).items():
            if name in res:  # only the variables of the outputs asked have a place
                res[name][e] = v


def chunk_dataset(sc, spec, case, values, axis, units, res, stats, pieces):
    """The Dataset of a chunk's cases ``case`` (``docs/sweeps.md``: Outputs).

    ``res`` holds the per-case results (internal units): ``q_initial, Q_initial, q_final,
    Q_final`` (n, 4), ``inertia`` (n, 3), ``failed``, ``pointing_error`` (rad),
    ``energy_error``; ``pieces`` the trajectory Datasets of the orbit groups (or none).
    """
    import xarray as xr

    dimless = sc.spec.dimensionless
    UN = DIMENSIONLESS_UNITS if dimless else DIMENSIONAL_UNITS  # written in SI (orbatt.units.to_output)
    outs = set(spec.outputs)
    perr = res["pointing_error"]
    coords = {"case": cf_variable(("case",), case, "1", "sweep case (index into the sampled parameters)"),
              "axis": cf_variable(("axis",), AXIS_INDEX, "1", "vector component index (axis 1, 2, 3 of the named frame)"),
              "axis_label": xr.Variable(("axis",), np.array(AXIS_LABELS), {"long_name": "vector component name"})}
    if "final_state" in outs:
        coords["quat"] = cf_variable(("quat",), QUAT_INDEX, "1", "quaternion component index (0 = scalar part)",
                              quaternion_order="w x y z")
        coords["quat_label"] = xr.Variable(("quat",), np.array(QUAT_LABELS), {"long_name": "quaternion component name"})
    coords.update(parameter_coordinates(spec, values, units))
    if axis is not None:
        coords["attitude_axis"] = cf_variable(("case", "axis"), axis, "1",
                                       "axis of the initial attitude perturbation (unit vector)", frame="B")
    data = {}
    qattrs = {"quaternion_order": "w x y z", "frames": "B relative to S"}
    if "final_state" in outs:
        data["q_initial"] = cf_variable(("case", "quat"), res["q_initial"], "1", "initial attitude quaternion", **qattrs)
        data["Q_initial"] = cf_variable(("case", "quat"), to_output(res["Q_initial"], "momentum", dimless),
                                        UN["momentum"], "initial conjugate momentum")
        data["q_final"] = cf_variable(("case", "quat"), res["q_final"], "1", "final attitude quaternion (at the last output time)",
                               **qattrs)
        data["Q_final"] = cf_variable(("case", "quat"), to_output(res["Q_final"], "momentum", dimless),
                                      UN["momentum"], "final conjugate momentum")
    if "trajectory" not in outs:
        data["inertia"] = cf_variable(("case", "axis"), to_output(res["inertia"], "inertia", dimless), UN["inertia"],
                                      "principal moments of inertia (I1, I2, I3)",
                                      frame="B" if getattr(sc.body, "frame", None) is None else "P")
        data.update(_tensor_variables(sc.body, UN, dimless))
    ref = (f"body axis {spec.pointing_axis.tolist()} vs the same axis of the {spec.pointing_reference} frame"
           if spec.pointing_axis is not None else f"rotation angle of the attitude relative to the "
                                                  f"{spec.pointing_reference} frame")
    if "max_pointing_error" in outs:
        data["max_pointing_error"] = cf_variable(("case",), perr, "rad", "maximum pointing error over the output times",
                                          definition=ref)
    if "tumbling" in outs:
        data["tumbling"] = cf_variable(("case",), np.where(np.isnan(perr), -1, perr > spec.tumbling_angle).astype(np.int8),
                                "1", "tumbling flag: maximum pointing error above tumbling_angle",
                                flag_values=np.array([-1, 0, 1], dtype=np.int8),
                                flag_meanings="failed not_tumbling tumbling", tumbling_angle_rad=spec.tumbling_angle,
                                definition=ref)
    if "final_energy_error" in outs:
        what = ("H = T + U" if spec.energy == "hamiltonian" else "the Jacobi integral H - n h.G")
        data["final_energy_error"] = cf_variable(("case",), res["energy_error"], "1", f"relative change of the conserved energy "
                                          f"(E(t_end) - E(t0)) / |E(t0)|, E = {what}")
    data.update(_study_variables(sc, spec, UN, res, coords))
    data["integration_failed"] = cf_variable(("case",), res["failed"].astype(np.int8), "1",
                                      "1 where the integration of the case stopped (its values are NaN)",
                                      flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="ok failed")
    if pieces:
        ds = concat_cases(pieces).sortby("case").drop_attrs(deep=False)
        ds = ds.assign_coords(coords).assign(data)
    else:
        ds = xr.Dataset(data, coords=coords)
    ds.attrs["integration_stats"] = json.dumps(stats, sort_keys=True)
    return ds


def _tensor_variables(body, UN, dimless):
    """A full inertia tensor's variables, as its single run's Dataset has them
    (:func:`orbatt.frame_boundary.body_variables`): ``inertia_tensor`` (``B``) and
    ``principal_axes`` (``R``, whose columns the moments ``inertia`` are about); none for a
    body whose axes are principal."""
    frame = getattr(body, "frame", None)
    if frame is None:
        return {}
    dims = ("axis", "axis_column")
    return {"inertia_tensor": cf_variable(dims, to_output(np.array(body.tensor), "inertia", dimless), UN["inertia"],
                                          "inertia tensor about the centre of mass (body components)", frame="B",
                                          comment="as given ([body] inertia); I_B = R diag(inertia) R^T with R = "
                                                  "principal_axes; the principal moments inertia are about the "
                                                  "principal axes (frame P)"),
            "principal_axes": cf_variable(dims, np.array(frame.R), "1",
                                          "principal axes of inertia (columns, body components)",
                                          comment="x_B = R x_P: column k is the axis of the principal moment "
                                                  "inertia[k]; every body-axes output is in B")}


def _study_variables(sc, spec, UN, res, coords):
    """The Dataset variables of the study outputs in ``res`` (their descriptors,
    :data:`orbatt.sweep_outputs.OUTPUTS`; SI), with the coordinates of their dimensions
    (:data:`orbatt.sweep_outputs.DIMS`: ``wheel``, ``mode_index``) added to ``coords``."""
    dimless = sc.spec.dimensionless
    data = {}
    for key in spec.outputs:
        o = OUTPUTS[key]
        if o.compute is None:
            continue
        for var in o.variables:
            name = var.long_name if isinstance(var.long_name, str) else var.long_name(spec, UN)
            extra = dict(var.attrs(spec))
            if var.kind == "flag":
                extra.update(flag_values=np.array([-1, 0, 1], dtype=np.int8), flag_meanings="failed " + var.flags)
            data[var.name] = cf_variable(("case",) + var.dims, var.written(res[var.name], dimless), var.unit(UN), name,
                                         **extra)
            for d in var.dims:
                if d not in coords and DIMS[d].coordinate is not None:
                    values, unit, long_name, attrs = DIMS[d].coordinate(sc)
                    coords[d] = cf_variable((d,), values, unit, long_name, **attrs)
    return data


def concat_cases(pieces):
    """Datasets of disjoint case ranges joined along ``case`` (attributes of the first)."""
    import xarray as xr

    if len(pieces) == 1:
        return pieces[0]
    return xr.concat(pieces, dim="case", data_vars="minimal", coords="minimal", compat="override", join="exact",
                     combine_attrs="override")

"""The per-case outputs of a sweep (``[sweep] outputs``, ``docs/sweeps.md``: Outputs), each
**one descriptor** (issue 32 item 1), as :mod:`orbatt.laws` is for a control law: its key, what
it needs of the scenario, the ``[sweep]`` keys it reads (thresholds), its Dataset variables
(dimensions beyond ``case``, unit kind, long name, attributes) and, for a study output, its
compute function. The schema's checks (:mod:`orbatt.scenario.study_schema`), the reference
(``docs/scenarios.md``, :func:`outputs_markdown`), the chunk's storage and Dataset
(:mod:`orbatt.sweep.chunk`) are generated from :data:`OUTPUTS`.

A new output is one :class:`SweepOutput` here (with a compute function, and a :data:`NEEDS`
or :data:`THRESHOLDS` entry if it brings a new one) plus its tests.

Study outputs (issue 23) are computed per case from that case's own outputs (no reduction
across cases, so a case's numbers do not depend on the cases sharing its chunk). Times where
a quantity falls through a threshold are located between the output times, on the cubic
through the four outputs around the crossing (:func:`orbatt.crossings.crossing_time`) and then on the
continuous solution (:func:`orbatt.crossings.refine_crossing`), not rounded to the output grid; the body rate,
the control torque, the dipole and the wheels' speeds come from the kernel the integration
used (:func:`orbatt.core.gyrostat.evaluate_extended`). Internal units in, SI out where the
Dataset says so. The outputs computed over a whole group of cases (the trajectory, the states,
the pointing error and tumbling, the energy) have no compute function here: their variables
are written by :func:`orbatt.sweep.chunk.chunk_dataset`.

This module sits outside :mod:`orbatt.sweep` so that the schema (:mod:`orbatt.scenario`)
reads it without importing the sweep package (data flows scenario -> sweep).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

from . import quaternion as qt
from . import units as U
from .dataset.control import mode_column, mode_entry_times
from .dataset.navigation import estimate_at, knowledge_error, navigation_column
from .laws import LAWS, MODE_SEQUENCE, law_of
from .methods.problem import kernel_spec
from .crossings import crossing_time, refine_crossing, study_series
from .frame_boundary import principal_outputs
from .pointing import INDEX_KINDS, index_attrs, index_value
from .units import from_kernel, to_output

__all__ = ["OutputVar", "OutputDim", "DIMS", "Threshold", "SweepOutput", "OUTPUTS", "DEFAULT_OUTPUTS", "NEEDS", "THRESHOLDS", "Case",
           "window_start", "target_pointing_error",
           "study_outputs", "variable_shape", "outputs_markdown", "users_of", "per_component_outputs",
           "POINTING_INDICES", "pointing_index"]


@dataclass(frozen=True)
class OutputVar:
    """One Dataset variable of an output: ``("case",) + dims``; ``kind`` the quantity
    (a key of :data:`orbatt.units.DIMENSIONAL_UNITS`, written with
    :func:`orbatt.units.to_output`; ``"torque"``/``"dipole"``: a kernel quantity written in SI by
    :func:`orbatt.units.from_kernel`; ``"flag"``: int8 -1 failed, 0 / 1 with ``flags`` the meanings
    of 0 and 1); ``long_name`` a text or ``long_name(spec, units) -> str``; ``attrs(spec) ->
    dict`` more CF attributes."""

    name: str
    dims: tuple
    kind: str
    long_name: object
    attrs: Callable = lambda spec: {}
    flags: str = ""

    def unit(self, units):
        return {"torque": "N m", "dipole": "A m^2", "flag": "1"}.get(self.kind) or units[self.kind]

    def written(self, values, dimensionless):
        """The values as the Dataset holds them (from the internal units of the results)."""
        if self.kind in ("torque", "dipole"):
            return from_kernel(values, self.kind)
        if self.kind == "flag":
            return values
        return to_output(values, self.kind, dimensionless)


@dataclass(frozen=True)
class Threshold:
    """A ``[sweep]`` key an output reads: its unit (:mod:`orbatt.units`), whether plain numbers
    are read as radians whatever the scenario (``angle``), the admitted interval ``(low, high]``
    and the message of a value outside it; ``required``: the outputs that read it need it."""

    unit: object
    angle: bool = False
    high: float = math.inf
    outside: str = "must be positive"
    required: bool = True


#: the [sweep] keys outputs read (SweepSpec has an attribute of each name), internal units
THRESHOLDS = {
    "detumble_rate": Threshold(U.RATE),
    "settling_angle": Threshold(U.ANGLE, angle=True, high=math.pi, outside="is outside (0, 180] deg"),
    "window": Threshold(U.TIME, required=False),
    "confidence": Threshold(U.DIMENSIONLESS, angle=True, high=math.nextafter(1.0, 0.0), outside="is outside (0, 1)",
                            required=False),
    "stability_window": Threshold(U.TIME),
}


def _dipole_laws():
    return " or ".join(f"{x.title}, law = {x.name!r}" for x in LAWS.values() if x.writes("dipole_control"))


#: what an output may need of the scenario: ``need -> (test(control, wheels) -> bool, phrase)``;
#: ``control`` the [control] settings (or None), ``wheels`` the number of reaction wheels
NEEDS = {
    "wheels": (lambda control, wheels: wheels > 0, "reaction wheels ([[body.wheels]])"),
    "control": (lambda control, wheels: control is not None, "a [control] law"),
    "dipole": (lambda control, wheels: control is not None and law_of(control).writes("dipole_control"),
               f"a [control] law with magnetorquers ({_dipole_laws()})"),
    "target": (lambda control, wheels: control is not None and law_of(control).name == "pd",
               "a [control] law with a target (law = 'pd')"),
    "modes": (lambda control, wheels: control is not None and law_of(control) is MODE_SEQUENCE,
              "a mode sequence ([[control.modes]])"),
    # (the scenario parser marks the law's settings it hands the [sweep] table with the estimator)
    "estimator": (lambda control, wheels: control is not None and bool(control.get("estimator")),
                  "an attitude filter ([estimator] with [sensors])"),
}


@dataclass(frozen=True)
class SweepOutput:
    """One ``[sweep] outputs`` name (module docstring).

    Attributes
    ----------
    key : str
    meaning : str
        One line for the reference.
    variables : tuple of OutputVar
    needs : tuple of str
        Keys of :data:`NEEDS`.
    keys : tuple of str
        The ``[sweep]`` keys it reads: its thresholds (:data:`THRESHOLDS`, read and checked by
        :mod:`orbatt.scenario.study_schema`) and the pointing keys (``pointing_axis``,
        ``pointing_reference``, ``tumbling_angle``: :mod:`orbatt.scenario.sweep_schema`).
    compute : callable or None
        ``compute(case) -> {variable: value}`` of one :class:`Case` (internal units); None:
        computed over the group by :mod:`orbatt.sweep.chunk`.
    refuse : callable
        ``refuse(control) -> str or None``: why a scenario that has its needs still cannot.
    """

    key: str
    meaning: str
    variables: tuple
    needs: tuple = ()
    keys: tuple = ()
    compute: Callable | None = None
    refuse: Callable = lambda control: None

    @property
    def names(self):
        return tuple(v.name for v in self.variables)


@dataclass(frozen=True)
class OutputDim:
    """A dimension of the outputs' variables beyond ``case``: ``size(sc)`` its length for the
    nominal scenario ``sc``, ``coordinate(sc) -> (values, units, long_name, attrs)`` its
    coordinate variable (None: the chunk's Dataset has it)."""

    size: Callable
    coordinate: Callable | None = None


#: the dimensions the study outputs' variables have beyond ``case``
DIMS = {
    "axis": OutputDim(lambda sc: 3),
    "wheel": OutputDim(lambda sc: len(sc.body.wheels),
                       lambda sc: (np.arange(len(sc.body.wheels)), "1", "reaction wheel index", {})),
    "mode_index": OutputDim(lambda sc: len(sc.potential.control.names),
                            lambda sc: (np.arange(len(sc.potential.control.names)), "1",
                                        "mode of the sequence (flag value of the single run's mode)",
                                        {"mode_names": " ".join(sc.potential.control.names)})),
}


def variable_shape(var, sc):
    """The shape of a variable's values per case for the nominal scenario ``sc``."""
    return tuple(DIMS[d].size(sc) for d in var.dims)


def users_of(key):
    """The outputs that read the ``[sweep]`` key ``key``."""
    return tuple(o.key for o in OUTPUTS.values() if key in o.keys)

#: a saturation limit counts as reached within this relative margin (the law clips to the limit)
SATURATION_MARGIN = 1e-9


def window_start(sc, window=None):
    """The start (s) of the window the pointing error is summarized over: ``t_end - window``
    (``window`` in s), else the last orbit, else the last 10 % of the run."""
    t0, t1 = float(sc.times[0]), float(sc.times[-1])
    if window is None:
        period = getattr(sc.orbit, "period_value", None) if sc.orbit is not None else None
        window = period if period is not None and period < t1 - t0 else 0.1 * (t1 - t0)
    return max(t0, t1 - window)


def target_pointing_error(control, q, p):
    """Angle (rad) between the attitudes ``q (N, 4)`` and a PD law's target: the orbital frame
    ``p (N, 4)`` (times ``target_q`` when given) or the inertial ``target_q``."""
    if control.target == "orbital":
        qt_ = p if control.target_q is None else qt.mul(p, control.target_q)
    else:
        qt_ = np.broadcast_to(control.target_q, q.shape)
    e = qt.mul(qt.conj(qt_), q)
    v = np.sqrt(e[..., 1] * e[..., 1] + e[..., 2] * e[..., 2] + e[..., 3] * e[..., 3])
    return 2.0 * np.arctan2(v, np.abs(e[..., 0]))


class Case:
    """What the compute functions of :data:`OUTPUTS` read of one case: its scenario ``sc``
    (output times, orbit), ``spec`` (the [sweep] table), ``potential`` (with its control law),
    ``body`` (with its wheels), ``inertia (3,)`` (its principal moments), ``q, Q (N, 4)`` (of its
    body axes: a full inertia tensor's body frame ``B``, as its Trajectory has them), ``h (N,
    k)`` or None (the wheels' momenta, then the flight software's held commands) and
    ``pointing(t, q) -> (n,)`` (the pointing error, rad, that the settling time and the window
    use); the kernel's series computed once, when first read (a tensor body's in its principal
    frame, body vectors back in ``B``: :func:`orbatt.crossings.study_series`)."""

    def __init__(self, sc, spec, potential, body, inertia, q, Q, h, pointing):
        self.sc, self.spec, self.potential, self.body, self.inertia = sc, spec, potential, body, inertia
        self.t, self.q, self.Q, self.h, self.pointing = sc.times, q, Q, h, pointing

    @cached_property
    def series(self):
        """``(omega, tau, m, u)``: :func:`study_series`."""
        return study_series(self.potential, self.body, self.inertia, self.t, self.q, self.Q, self.h)

    @property
    def omega(self):
        return self.series[0]

    @cached_property
    def pointing_error(self):
        return self.pointing(self.t, self.q)

    @cached_property
    def kernel(self):
        """The kernel model of the case's run (:func:`~orbatt.methods.problem.kernel_spec`; a
        body given by a full inertia tensor: in its principal frame, as the run's)."""
        potential, body, _, _ = principal_outputs(self.potential, self.body, self.q[:0], self.Q[:0])
        return kernel_spec(potential, [body])

    @cached_property
    def knowledge_error(self):
        """``(N, 3)`` the rotation vector (rad, body axes) from the filter's estimate to the truth,
        as the run's Dataset has it (:mod:`orbatt.dataset.navigation`; a full inertia tensor: in
        its principal frame, turned to ``B`` by ``R``)."""
        nw = len(self.body.wheels)
        col, _ = navigation_column(self.kernel, nw)
        z = self.h[:, nw:]
        frame = getattr(self.body, "frame", None)
        if frame is None:
            return knowledge_error(self.q, estimate_at(self.t, z, col))
        return frame.to_body(knowledge_error(frame.attitude_to_principal(self.q), estimate_at(self.t, z, col)))

    @cached_property
    def wheel_speed(self):
        """``(N, n)`` each wheel's speed relative to the body, rad/s."""
        wheels, omega, t, h = self.body.wheels, self.omega, self.t, self.h
        iw = np.array([wh.inertia for wh in wheels])
        axes = np.array([wh.axis for wh in wheels])
        speed = np.zeros((t.size, len(wheels)))
        for k in range(len(wheels)):  # h_k / Iw_k - a_k . omega, written out (no BLAS)
            a = axes[k]
            speed[:, k] = h[:, k] / iw[k] - (omega[:, 0] * a[0] + omega[:, 1] * a[1] + omega[:, 2] * a[2])
        return speed

    def located(self, x, level, quantity):
        """:func:`crossing_time` of ``x``, located on the continuous solution where it falls
        between two outputs (:func:`refine_crossing`; the cubic through the outputs where that
        cannot be done)."""
        t = self.t
        coarse = crossing_time(t, x, level)
        if not math.isfinite(coarse) or coarse == t[0]:
            return coarse
        k = int(np.flatnonzero(x >= level)[-1])
        fine = refine_crossing(self.sc, self.potential, self.body, t, k, self.q, self.Q, self.h, quantity, level)
        return coarse if fine is None else fine


def _rate(omega):
    """``|omega|`` per row, written out."""
    return np.sqrt(omega[:, 0] * omega[:, 0] + omega[:, 1] * omega[:, 1] + omega[:, 2] * omega[:, 2])


def _detumble_time(c):
    return {"detumble_time": c.located(_rate(c.omega), c.spec.detumble_rate, lambda w, qf, tf: _rate(w))}


def _settling(c):
    """The earliest time after which the pointing error stays below ``settling_angle``."""
    return c.located(c.pointing_error, c.spec.settling_angle, lambda w, qf, tf: c.pointing(tf, qf))


def _pointing_error(c):
    w = c.pointing_error[c.t >= window_start(c.sc, c.spec.window)]
    return {"pointing_error_max": float(np.max(w)) if w.size else math.nan,
            "pointing_error_rms": float(np.sqrt(np.sum(w * w) / w.size)) if w.size else math.nan}


def _max_wheel_speed(c):
    t = c.t
    return {"max_wheel_speed": np.max(np.abs(c.wheel_speed), axis=0) if t.size else np.full(len(c.body.wheels), np.nan)}


def _wheel_saturated(c):
    top = _max_wheel_speed(c)["max_wheel_speed"]
    u = c.series[3]
    sat = np.zeros(len(c.body.wheels), dtype=bool)
    for k, wh in enumerate(c.body.wheels):
        if wh.max_speed_rad_s is not None:
            sat[k] |= top[k] >= wh.max_speed_rad_s * (1.0 - SATURATION_MARGIN)
        if wh.max_torque_n_m is not None and u.shape[1]:
            sat[k] |= from_kernel(np.max(np.abs(u[:, k])), "torque") >= wh.max_torque_n_m * (1.0 - SATURATION_MARGIN)
    return {"wheel_saturated": sat}


def _max_norm(v):
    return float(np.max(np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1] + v[:, 2] * v[:, 2])))


def _final_wheel_momentum(c):
    """``sum_k h_k a_k`` at the last output, body axes (internal momentum unit), written out."""
    H = np.zeros(3)
    for k, wh in enumerate(c.body.wheels):
        H = H + c.h[-1, k] * np.asarray(wh.axis, dtype=np.float64)
    return {"final_wheel_momentum": H}


def _mode_entry_time(c):
    """The time each mode began, from the sequence's state along the outputs (as the single
    run's Dataset: :func:`orbatt.dataset.control.mode_entry_times`)."""
    nw = len(c.body.wheels)
    entry = mode_entry_times(c.h, nw + mode_column(c.kernel, nw), len(c.potential.control.names))
    return {"mode_entry_time": entry}


_LOCATED = "cubic through 4 outputs"


def _window_text(spec, units):
    return "over the last orbit, else the last 10 % of the run" if spec.window is None else \
        f"over the last {spec.window:g} {units['time']} of the run"


def pointing_index(name, meaning, series, needs=(), keys=("pointing_axis", "pointing_reference")):
    """The :class:`SweepOutput` of the ECSS pointing index ``name`` (a key of
    :data:`orbatt.pointing.INDEX_KINDS`: ``ape``, ``rpe``, ``mpe``, and ``ake``, ``rke``, ``mke``
    of the knowledge error): :func:`orbatt.pointing.index_value` of the error series
    ``series(case) -> (N,) or (N, 3)`` (rad) at ``[sweep] confidence`` (``docs/pointing-budgets.md``)."""
    windowed = INDEX_KINDS[name][1]

    def compute(c):
        return {name: index_value(name, c.t, series(c), c.spec.confidence, c.spec.stability_window, "[sweep] ")}

    return SweepOutput(name, f"{name.upper()}: {meaning}, at confidence over the output times (temporal)",
                       (OutputVar(name, (), "angle", f"{name.upper()} at the confidence level (temporal "
                                                     f"interpretation, ECSS-E-ST-60-10C): {meaning}",
                                  lambda spec: index_attrs(name, spec.confidence, spec.stability_window,
                                                           spec.requirement.get(name))),),
                       needs=needs, compute=compute,
                       keys=("confidence",) + (("stability_window",) if windowed else ()) + ("requirement",) + keys)


#: every output that may be asked for, in the order the Dataset and the reference list them
OUTPUTS = {o.key: o for o in (
    SweepOutput("trajectory", "every case's whole trajectory (as `orbatt run` writes it), along case",
                (OutputVar("q", ("time", "quat"), "one", "attitude quaternion"),
                 OutputVar("Q", ("time", "quat"), "momentum", "conjugate momentum"))),
    SweepOutput("final_state", "the initial and final attitude and conjugate momentum",
                (OutputVar("q_initial", ("quat",), "one", "initial attitude quaternion"),
                 OutputVar("Q_initial", ("quat",), "momentum", "initial conjugate momentum"),
                 OutputVar("q_final", ("quat",), "one", "final attitude quaternion"),
                 OutputVar("Q_final", ("quat",), "momentum", "final conjugate momentum"))),
    SweepOutput("max_pointing_error", "largest pointing error over the output times (pointing_axis, "
                                      "pointing_reference)",
                (OutputVar("max_pointing_error", (), "angle", "maximum pointing error over the output times"),),
                keys=("pointing_axis", "pointing_reference")),
    SweepOutput("tumbling", "1 where max_pointing_error exceeds tumbling_angle",
                (OutputVar("tumbling", (), "flag", "tumbling flag"),),
                keys=("tumbling_angle", "pointing_axis", "pointing_reference")),
    SweepOutput("final_energy_error", "relative change of the conserved energy (no [torques] or [control])",
                (OutputVar("final_energy_error", (), "one", "relative change of the conserved energy"),)),
    SweepOutput("detumble_time", "time after which |omega| stays below detumble_rate",
                (OutputVar("detumble_time", (), "time", "time after which |omega| stays below detumble_rate "
                                                           "(NaN: never)",
                           lambda spec: dict(detumble_rate=spec.detumble_rate, located=_LOCATED)),),
                keys=("detumble_rate",), compute=_detumble_time),
    SweepOutput("settling_time", "time after which the pointing error (to the law's target, else pointing_axis / "
                                 "pointing_reference) stays below settling_angle",
                (OutputVar("settling_time", (), "time", "time after which the pointing error stays below "
                                                           "settling_angle (NaN: never)",
                           lambda spec: dict(settling_angle_rad=spec.settling_angle, located=_LOCATED)),),
                keys=("settling_angle", "pointing_axis", "pointing_reference"),
                compute=lambda c: {"settling_time": _settling(c)}),
    SweepOutput("pointing_error", "largest and root mean square pointing error over window",
                (OutputVar("pointing_error_max", (), "angle",
                           lambda spec, units: f"largest pointing error {_window_text(spec, units)}"),
                 OutputVar("pointing_error_rms", (), "angle", lambda spec, units: "root mean square pointing error "
                           f"{_window_text(spec, units)} (output times)")),
                keys=("window", "pointing_axis", "pointing_reference"), compute=_pointing_error),
    SweepOutput("max_wheel_speed", "largest |speed| of each wheel relative to the body",
                (OutputVar("max_wheel_speed", ("wheel",), "rate",
                           "largest |speed| of each wheel relative to the body (output times)"),),
                needs=("wheels",), compute=_max_wheel_speed),
    SweepOutput("wheel_saturated", "1 where a wheel reached max_speed or max_torque",
                (OutputVar("wheel_saturated", ("wheel",), "flag", "a wheel reached max_speed or max_torque",
                           flags="free saturated"),),
                needs=("wheels",), compute=_wheel_saturated),
    SweepOutput("max_control_torque", "largest |torque| the control applied",
                (OutputVar("max_control_torque", (), "torque", "largest |torque| the control applied (output times)"),),
                needs=("control",), compute=lambda c: {"max_control_torque": _max_norm(c.series[1])}),
    SweepOutput("max_dipole", "largest |dipole| of the magnetorquers",
                (OutputVar("max_dipole", (), "dipole", "largest |B-dot dipole| (output times)"),),
                needs=("dipole",), compute=lambda c: {"max_dipole": _max_norm(c.series[2])}),
    SweepOutput("slew_time", "time after which the attitude error to the law's target stays below settling_angle "
                             "(settling_time's computation, the law's target only)",
                (OutputVar("slew_time", (), "time", "time after which the attitude error to the control law's "
                                                       "target stays below settling_angle (NaN: never)",
                           lambda spec: dict(settling_angle_rad=spec.settling_angle, located=_LOCATED)),),
                needs=("target",), keys=("settling_angle",), compute=lambda c: {"slew_time": _settling(c)}),
    SweepOutput("max_rate", "largest |omega| over the output times (variable max_body_rate: [control] max_rate is "
                            "the PD's limit)",
                (OutputVar("max_body_rate", (), "rate", "largest |omega| of the body over the output times"),),
                compute=lambda c: {"max_body_rate": float(np.max(_rate(c.omega)))}),
    SweepOutput("final_wheel_momentum", "the wheels' total angular momentum at the end, body axes",
                (OutputVar("final_wheel_momentum", ("axis",), "momentum",
                           "total angular momentum of the reaction wheels at the last output (body components)",
                           lambda spec: dict(frame="B", comment="sum_k h_k a_k")),),
                needs=("wheels",), compute=_final_wheel_momentum),
    SweepOutput("mode_entry_time", "time each mode of the sequence began",
                (OutputVar("mode_entry_time", ("mode_index",), "time",
                           "time each mode of the sequence began (NaN: not entered by the last output)"),),
                needs=("modes",), compute=_mode_entry_time),
    pointing_index("ape", "absolute performance error (the pointing error to the law's target, else pointing_axis / "
                          "pointing_reference)", lambda c: c.pointing_error),
    pointing_index("rpe", "relative performance error (the pointing error minus its stability window's mean)",
                   lambda c: c.pointing_error),
    pointing_index("mpe", "mean performance error (the pointing error's mean over its stability window)",
                   lambda c: c.pointing_error),
    pointing_index("ake", "absolute knowledge error (the rotation from the filter's estimate to the truth)",
                   lambda c: c.knowledge_error, needs=("estimator",), keys=()),
    pointing_index("rke", "relative knowledge error (the knowledge error minus its stability window's mean)",
                   lambda c: c.knowledge_error, needs=("estimator",), keys=()),
    pointing_index("mke", "mean knowledge error (the knowledge error's mean over its stability window)",
                   lambda c: c.knowledge_error, needs=("estimator",), keys=()),
)}
#: the outputs that are ECSS pointing indices (they read [sweep] requirement)
POINTING_INDICES = tuple(o.key for o in OUTPUTS.values() if "requirement" in o.keys)
DEFAULT_OUTPUTS = ("final_state", "max_pointing_error", "tumbling")


def study_outputs(sc, spec, potential, body, inertia, q, Q, h, pointing):
    """The study outputs of one case among ``spec.outputs`` (those with a compute function),
    internal units: ``{variable: value}``, exactly the variables of the outputs asked
    (:class:`Case` for the arguments)."""
    c = Case(sc, spec, potential, body, inertia, q, Q, h, pointing)
    out = {}
    for key in spec.outputs:
        o = OUTPUTS[key]
        if o.compute is not None:
            out.update(o.compute(c))
    return out


def per_component_outputs(ds):
    """The float variables of the study outputs in ``ds`` that have a dimension beyond ``case``
    (``max_wheel_speed``, ``final_wheel_momentum``, ``mode_entry_time``): ``orbatt info``
    prints a row per component."""
    return [v.name for o in OUTPUTS.values() if o.compute is not None for v in o.variables
            if v.dims and v.kind != "flag" and v.name in ds]


def outputs_markdown():
    """The reference's table of the outputs (``docs/scenarios.md``)."""
    rows = ["| output | needs | reads | variables | meaning |", "|---|---|---|---|---|"]
    for o in OUTPUTS.values():
        needs = "; ".join(NEEDS[n][1] for n in o.needs)
        keys = ", ".join(f"`{k}`" for k in o.keys)
        var = ", ".join(f"`{v.name}` ({', '.join(('case',) + v.dims)}; {v.unit(U.DIMENSIONAL_UNITS)})"
                        for v in o.variables)
        rows.append(f"| `{o.key}` | {needs} | {keys} | {var} | {o.meaning.replace('|', chr(92) + '|')} |")
    return rows

"""The outputs of a control study, per case of a sweep (issue 23; ``docs/sweeps.md``: Study
outputs): detumble and settling times, the pointing error over a window, the wheels' largest
speeds and saturation, the largest control torque and B-dot dipole.

Everything is computed per case from that case's own outputs (no reduction across cases, so
a case's numbers do not depend on the cases sharing its chunk). Times where a quantity falls
through a threshold are located between the output times, on the cubic through the four
outputs around the crossing (:func:`crossing_time`), not rounded to the output grid; the body
rate, the control torque, the dipole and the wheels' speeds come from the kernel the
integration used (:func:`orbatt.core.gyrostat.evaluate_extended`). Internal units in, SI out
where the Dataset says so (``chunk_dataset``).
"""
from __future__ import annotations

import math

import numpy as np

from .. import canonical as cn
from .. import quaternion as qt
from ..core import kernel_floats
from ..core import gyrostat as kg
from ..core import potentials as kp
from ..methods.problem import kernel_spec
from ..units import from_kernel

__all__ = ["STUDY_OUTPUTS", "crossing_time", "window_start", "study_series", "target_pointing_error",
           "study_outputs"]

#: the study outputs of a sweep and the variables each one adds
STUDY_OUTPUTS = {"detumble_time": ("detumble_time",), "settling_time": ("settling_time",),
                 "pointing_error": ("pointing_error_max", "pointing_error_rms"),
                 "max_wheel_speed": ("max_wheel_speed",), "wheel_saturated": ("wheel_saturated",),
                 "max_control_torque": ("max_control_torque",), "max_dipole": ("max_dipole",)}
#: a saturation limit counts as reached within this relative margin (the law clips to the limit)
SATURATION_MARGIN = 1e-9


def crossing_time(t, x, level):
    """The earliest time after which ``x`` stays below ``level`` until the end.

    Parameters
    ----------
    t : ndarray (N,)
        Output times, increasing.
    x : ndarray (N,)
        The quantity at the outputs.
    level : float

    Returns
    -------
    float
        ``t[0]`` when ``x`` is below ``level`` at every output; NaN when it is not below at the
        last output (or a value is NaN); otherwise the root in ``(t[k], t[k+1]]`` (``k`` the last
        output at or above ``level``) of the cubic through the four outputs around it (two
        when the run has fewer), found by bisection to the last bit.
    """
    n = t.size
    if n == 0 or not np.all(np.isfinite(x)) or x[-1] >= level:
        return math.nan
    above = np.flatnonzero(x >= level)
    if above.size == 0:
        return float(t[0])
    k = int(above[-1])
    j0 = min(max(k - 1, 0), max(n - 4, 0))
    pts = np.arange(j0, min(j0 + 4, n))
    tk, xk = t[pts], x[pts] - level

    def f(s):  # Lagrange form: exact at the outputs
        total = 0.0
        for i in range(pts.size):
            w = 1.0
            for j in range(pts.size):
                if j != i:
                    w *= (s - tk[j]) / (tk[i] - tk[j])
            total += xk[i] * w
        return total

    lo, hi = float(t[k]), float(t[k + 1])  # f(lo) >= 0 > f(hi)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if f(mid) >= 0.0:
            lo = mid
        else:
            hi = mid
    return hi


#: outputs of the re-integration over the output interval of a crossing (:func:`refine_crossing`)
REFINE_POINTS = 65


def refine_crossing(sc, potential, body, t, k, q, Q, h, quantity, level):
    """The crossing of ``level`` in ``(t[k], t[k+1]]`` located on the continuous solution: the
    case integrated again from its output ``k`` to ``k + 1`` (the same method and tolerances)
    with :data:`REFINE_POINTS` outputs, and :func:`crossing_time` on those.

    ``quantity(omega, q, t) -> (n,)`` gives the quantity from the body rate and the attitude at
    the fine outputs ``t``. Returns None where the interval cannot be integrated again (the coarse
    estimate then stands): a wheel at its speed limit, a failed re-integration, or a fine run
    that does not end below ``level``.
    """
    from ..control import ReactionWheel
    from ..body import RigidBody
    from ..propagation import propagate
    from ..state import State
    from ..errors import OrbattError
    from astropy import units as u

    tf = np.linspace(float(t[k]), float(t[k + 1]), REFINE_POINTS)
    period = getattr(getattr(potential, "control", None), "period", None)
    if period is not None and float(t[k]) % period != 0.0:
        # a flight software holds a command issued before t[k]: a run from t[k] would issue
        # another (on a tick it issues the same one, and the fine run is the case's own)
        return None
    try:
        b = body
        if body.wheels:  # the wheels at their speeds of output k (relative to the body)
            omega_k = study_series(potential, body, body.inertia_value, t[k:k + 1], q[k:k + 1], Q[k:k + 1],
                                   h[k:k + 1])[0][0]
            wheels = []
            for j, wh in enumerate(body.wheels):
                speed = h[k, j] / wh.inertia - float(np.dot(wh.axis, omega_k))
                wheels.append(ReactionWheel(wh.axis, wh.inertia_kg_m2 * u.kg * u.m**2, speed * u.rad / u.s,
                                            max_torque=None if wh.max_torque_n_m is None else wh.max_torque_n_m * u.N * u.m,
                                            max_speed=None if wh.max_speed_rad_s is None
                                            else wh.max_speed_rad_s * u.rad / u.s))
            b = RigidBody(from_kernel(body.inertia_value, "inertia") * u.kg * u.m**2, wheels=wheels)
        tr = propagate(b, State(b, q[k], Q[k]), potential, tf, method=sc.method, **sc.settings)
    except (OrbattError, ValueError):
        return None
    hf = None if tr.extended is None else np.ascontiguousarray(tr.extended)
    omega = study_series(potential, b, b.inertia_value, tf, np.ascontiguousarray(tr.q), np.ascontiguousarray(tr.Q),
                         hf)[0]
    x = quantity(omega, np.ascontiguousarray(tr.q), tf)
    if not x[-1] < level:
        return None
    return crossing_time(tf, x, level)


def window_start(sc, window=None):
    """The start (s) of the window the pointing error is summarized over: ``t_end - window``
    (``window`` in s), else the last orbit, else the last 10 % of the run."""
    t0, t1 = float(sc.times[0]), float(sc.times[-1])
    if window is None:
        period = getattr(sc.orbit, "period_value", None) if sc.orbit is not None else None
        window = period if period is not None and period < t1 - t0 else 0.1 * (t1 - t0)
    return max(t0, t1 - window)


def study_series(potential, body, inertia, t, q, Q, h):
    """``(omega, tau, m, u)`` of one case along its outputs: body rate (rad/s), control torque
    and B-dot dipole (internal units, body axes) and the wheels' motor torques, from the kernel
    the integration used; the rigid body's ``omega = I^-1 g`` and zeros without wheels or
    control."""
    control = getattr(potential, "control", None)
    if control is None and not body.wheels:
        omega = cn.body_rate(q, Q, inertia)
        z = np.zeros_like(omega)
        return omega, z, z, np.zeros((t.size, 0))
    model = kernel_spec(potential, [body])
    Y = np.ascontiguousarray(np.concatenate([q, Q, np.zeros((t.size, 0)) if h is None else h], axis=1))
    omega, _, tau, m, u = kg.evaluate_extended(kernel_floats(t), Y, kernel_floats(inertia), *model,
                                               kp.new_work())
    return omega, tau, m, u


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


def _rate(omega):
    """``|omega|`` per row, written out."""
    return np.sqrt(omega[:, 0] * omega[:, 0] + omega[:, 1] * omega[:, 1] + omega[:, 2] * omega[:, 2])


def _located(sc, potential, body, t, q, Q, h, x, level, quantity):
    """:func:`crossing_time` of ``x``, located on the continuous solution where it falls
    between two outputs (:func:`refine_crossing`; the cubic through the outputs where that
    cannot be done)."""
    coarse = crossing_time(t, x, level)
    if not math.isfinite(coarse) or coarse == t[0]:
        return coarse
    k = int(np.flatnonzero(x >= level)[-1])
    fine = refine_crossing(sc, potential, body, t, k, q, Q, h, quantity, level)
    return coarse if fine is None else fine


def study_outputs(sc, spec, potential, body, inertia, q, Q, h, pointing):
    """The study outputs of one case (``spec.outputs``), internal units.

    Parameters
    ----------
    sc : Scenario
        The nominal scenario (output times, orbit).
    spec : SweepSpec
    potential, body
        The case's potential (with its control law) and body (with its wheels).
    inertia : ndarray (3,)
    q, Q : ndarray (N, 4)
    h : ndarray (N, n) or None
        The wheels' momenta.
    pointing : callable
        ``pointing(t, q) -> (n,)``: the pointing error (rad) at times ``t`` and attitudes
        ``q (n, 4)`` that the settling time and the window use.

    Returns
    -------
    dict
        ``detumble_time``, ``settling_time`` (s, NaN if never), ``pointing_error_max``,
        ``pointing_error_rms`` (rad), ``max_wheel_speed`` (n,), ``wheel_saturated`` (n,) (bool),
        ``max_control_torque`` (internal torque unit), ``max_dipole`` (1e-6 A m^2): exactly the
        variables of the outputs asked (:data:`STUDY_OUTPUTS`), none that were only computed alongside.
    """
    t = sc.times
    outs = set(spec.outputs)
    out = {}
    omega, tau, m, u = study_series(potential, body, inertia, t, q, Q, h)
    perr = pointing(t, q)
    if "detumble_time" in outs:
        out["detumble_time"] = _located(sc, potential, body, t, q, Q, h, _rate(omega), spec.detumble_rate,
                                        lambda w, qf, tf: _rate(w))
    if "settling_time" in outs:
        out["settling_time"] = _located(sc, potential, body, t, q, Q, h, perr, spec.settling_angle,
                                        lambda w, qf, tf: pointing(tf, qf))
    if "pointing_error" in outs:
        w = perr[t >= window_start(sc, spec.window)]
        out["pointing_error_max"] = float(np.max(w)) if w.size else math.nan
        out["pointing_error_rms"] = float(np.sqrt(np.sum(w * w) / w.size)) if w.size else math.nan
    if {"max_wheel_speed", "wheel_saturated"} & outs:
        wheels = body.wheels
        iw = np.array([wh.inertia for wh in wheels])
        axes = np.array([wh.axis for wh in wheels])
        speed = np.zeros((t.size, len(wheels)))
        for k in range(len(wheels)):  # h_k / Iw_k - a_k . omega, written out (no BLAS)
            a = axes[k]
            speed[:, k] = h[:, k] / iw[k] - (omega[:, 0] * a[0] + omega[:, 1] * a[1] + omega[:, 2] * a[2])
        top = np.max(np.abs(speed), axis=0) if t.size else np.full(len(wheels), np.nan)
        out["max_wheel_speed"] = top
        sat = np.zeros(len(wheels), dtype=bool)
        for k, wh in enumerate(wheels):
            if wh.max_speed_rad_s is not None:
                sat[k] |= top[k] >= wh.max_speed_rad_s * (1.0 - SATURATION_MARGIN)
            if wh.max_torque_n_m is not None and u.shape[1]:
                sat[k] |= from_kernel(np.max(np.abs(u[:, k])), "torque") >= wh.max_torque_n_m * (1.0 - SATURATION_MARGIN)
        out["wheel_saturated"] = sat
    if "max_control_torque" in outs:
        out["max_control_torque"] = float(np.max(np.sqrt(tau[:, 0] * tau[:, 0] + tau[:, 1] * tau[:, 1]
                                                         + tau[:, 2] * tau[:, 2])))
    if "max_dipole" in outs:
        out["max_dipole"] = float(np.max(np.sqrt(m[:, 0] * m[:, 0] + m[:, 1] * m[:, 1] + m[:, 2] * m[:, 2])))
    # outputs computed together (the wheels' speeds and saturation) are returned only if asked
    asked = {name for o in outs if o in STUDY_OUTPUTS for name in STUDY_OUTPUTS[o]}
    return {name: v for name, v in out.items() if name in asked}

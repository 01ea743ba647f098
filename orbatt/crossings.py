"""Where a quantity of one run falls through a level, located between its output times (the
sweep's study outputs, :mod:`orbatt.sweep_outputs`): on the cubic through the four outputs
around the crossing (:func:`crossing_time`), then on the continuous solution, the case
integrated again over that output interval (:func:`refine_crossing`); and the kernel's series
they read (:func:`study_series`: the body rate, the control torque, the dipole, the wheels'
motor torques). Internal units; frames as ``docs/design.md`` §1.
"""
from __future__ import annotations

import math

import numpy as np

from . import canonical as cn
from .core import kernel_floats
from .core import gyrostat as kg
from .core import potentials as kp
from .frame_boundary import principal_outputs
from .methods.problem import kernel_spec
from .units import from_kernel

__all__ = ["crossing_time", "refine_crossing", "study_series", "REFINE_POINTS"]


def study_series(potential, body, inertia, t, q, Q, h):
    """``(omega, tau, m, u)`` of one case along its outputs: body rate (rad/s), control torque
    and B-dot dipole (internal units, body axes) and the wheels' motor torques, from the kernel
    the integration used; the rigid body's ``omega = I^-1 g`` and zeros without wheels or
    control. ``q, Q`` the attitude and momentum of ``body``'s axes, ``inertia`` its principal
    moments: a body given by a full inertia tensor is evaluated in its principal frame and its
    vectors come back in the body frame ``B`` (``R v_P``, as its Dataset's)."""
    frame = getattr(body, "frame", None)
    if frame is not None:
        potential, pbody, qp, Qp = principal_outputs(potential, body, q, Q)
        omega, tau, m, u = study_series(potential, pbody, inertia, t, qp, Qp, h)
        return frame.to_body(omega), frame.to_body(tau), frame.to_body(m), u
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
    from .control import ReactionWheel
    from .body import RigidBody
    from .propagation import propagate
    from .state import State
    from .errors import OrbattError
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
            inertia = body.inertia_value if body.frame is None else body.tensor  # a full tensor: B's
            b = RigidBody(from_kernel(inertia, "inertia") * u.kg * u.m**2, wheels=wheels)
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

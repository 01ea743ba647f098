"""The extended right-hand side: reaction wheels (the body as a gyrostat) and control laws in
the canonical variables (``docs/design.md`` §10).

State ``y = (q, Q, h_1 .. h_n)``: ``h_k`` the axial angular momentum of wheel ``k`` (absolute:
``h_k = Iw_k (a_k . omega + speed_k)``, ``speed_k`` the rotor's rate relative to the body).
``g = 1/2 Im(q~ Q)`` is the **total** angular momentum (body + rotors, body axes), and the
body rate is ``omega = J^-1 (g - h)`` with ``h = sum h_k a_k`` and ``J = diag(I) - sum Iw_k
a_k a_k^T`` (``I`` the principal moments of the whole spacecraft, rotors locked). The kinetic
energy ``T = 1/2 (g - h).J^-1 (g - h)`` gives Hamilton's equations of eq. (7) with ``a = (0,
2 omega)``::

    dq/dt = 1/4 q a,    dQ/dt = 1/4 Q a - G,    dh_k/dt = u_k

(``G`` the terms' generalized gradient plus ``-2 q (0, tau)`` for the external control torque;
``u_k`` the motor torques, which move momentum between rotor and body and leave ``G`` of the
whole unchanged). With no wheels, ``J = diag(I)`` and this is eq. (7) of the rigid body with
the control laws of :mod:`orbatt.core.control` added.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline
from . import control as ctl
from .environment import piece_eval, piece_eval_rate
from .model import (BDOT_CONTROL, FLAGS, KIND, MODES, ORBIT_KEPLER_ANOMALY, P0, P1, PD_CONTROL, R0, R1, WHEELS, orbit_at,
                    orbit_radial, terms_at, time_of_s)
from .model import MAGNETORQUERS, MOMENTUM_DUMP, NAVIGATION, VECTOR_SENSOR
from . import estimator as est
from .kepler import anomaly_of_time
from .mode_state import ENTRY, HOLD_BEGAN, HOLDS, MODE, enter_mode
from .qalg import cross, qconj, qmul, qmul_pure, rotate_inv, vadd
from .torques import gradient_of_torque

# the slot offsets (orbatt.core.control's layouts) as module constants, folded by numba
_W_AXIS, _W_IW = ctl.WHEEL.axis, ctl.WHEEL.iw
_PD_ACTUATOR = ctl.PD_ACTUATOR
_CTL_PERIOD, _CTL_PHASE, _CTL_Z0, _CTL_NZ = ctl.CTL_PERIOD, ctl.CTL_PHASE, ctl.CTL_Z0, ctl.CTL_NZ
_PD_KI, _PD_ZI, _PD_TMAX, _PD_TARGET = ctl.PD.ki, ctl.PD.zi, ctl.PD.max_torque, ctl.PD.target
_CTL_MODE = ctl.CTL_MODE
_MD_COUNT, _MD_COND = ctl.MODES.count, ctl.MODES.conditions
_MD_FIELDS = ctl.MODE_FIELDS
_MD_TIME, _MD_RATE, _MD_SETTLED, _MD_HOLD = (ctl.MODE_UNTIL_TIME, ctl.MODE_UNTIL_RATE, ctl.MODE_UNTIL_SETTLED,
                                             ctl.MODE_HOLD)


@jit_inline
def is_flight_software(kind):
    """Whether a row kind carries the flight-software slots (:data:`orbatt.core.control.FLIGHT_SOFTWARE`)."""
    return kind == PD_CONTROL or kind == BDOT_CONTROL or kind == MODES or kind == MOMENTUM_DUMP or kind == NAVIGATION


@jit_inline
def current_mode(terms, params, y):
    """The mode the model's sequence is in (its state ``y[z0]``; -1 without a sequence)."""
    for j in range(1, terms.shape[0]):
        if terms[j, KIND] == MODES:
            return y[int(params[terms[j, P0] + _CTL_Z0]) + MODE]
    return -1.0


@jit_inline
def row_active(params, p0, mode):
    """Whether a law's row acts in ``mode`` (:func:`current_mode`): a row of no mode always."""
    rm = params[p0 + _CTL_MODE]
    return rm < 0.0 or rm == mode


@jit_inline
def wheel_row(terms):
    """The start of the wheels' parameters in ``params`` (``-1``: no wheels)."""
    for j in range(1, terms.shape[0]):
        if terms[j, KIND] == WHEELS:
            return terms[j, P0]
    return -1


@jit_inline
def body_rate(g, y, inertia, params, w0):
    """``(omega, h)``: the body rate ``J^-1 (g - h)`` and the wheels' momentum ``h`` (body
    axes) for the total momentum ``g`` and the wheels' axial momenta ``y[8:]`` (wheel
    parameters from ``params[w0]``; ``w0 < 0``: a rigid body, ``omega = g / I``)."""
    if w0 < 0:
        return (g[0] / inertia[0], g[1] / inertia[1], g[2] / inertia[2]), (0.0, 0.0, 0.0)
    j00, j11, j22 = inertia[0], inertia[1], inertia[2]
    j01 = j02 = j12 = 0.0
    h0 = h1 = h2 = 0.0
    for k in range(int(params[w0])):
        w = w0 + 1 + ctl.WHEEL_SIZE * k
        a0, a1, a2 = params[w + _W_AXIS], params[w + _W_AXIS + 1], params[w + _W_AXIS + 2]
        iw = params[w + _W_IW]
        j00 -= iw * a0 * a0
        j11 -= iw * a1 * a1
        j22 -= iw * a2 * a2
        j01 -= iw * a0 * a1
        j02 -= iw * a0 * a2
        j12 -= iw * a1 * a2
        hk = y[8 + k]
        h0 += hk * a0
        h1 += hk * a1
        h2 += hk * a2
    return cofactor_solve(j00, j11, j22, j01, j02, j12, (g[0] - h0, g[1] - h1, g[2] - h2)), (h0, h1, h2)


@jit_inline
def cofactor_solve(j00, j11, j22, j01, j02, j12, x):
    """``J^-1 x`` for the symmetric positive definite ``J`` of entries ``j..``, by cofactors (the
    operations :func:`body_rate` and the lanes' form, :mod:`orbatt.core.held_commands`, share)."""
    x0, x1, x2 = x
    c00 = j11 * j22 - j12 * j12
    c01 = j02 * j12 - j01 * j22
    c02 = j01 * j12 - j02 * j11
    c11 = j00 * j22 - j02 * j02
    c12 = j01 * j02 - j00 * j12
    c22 = j00 * j11 - j01 * j01
    det = j00 * c00 + j01 * c01 + j02 * c02
    return ((c00 * x0 + c01 * x1 + c02 * x2) / det, (c01 * x0 + c11 * x1 + c12 * x2) / det,
            (c02 * x0 + c12 * x1 + c22 * x2) / det)


@jit_inline
def wheel_count(params, w0):
    """The number of reaction wheels (``w0``: :func:`wheel_row`)."""
    return 0 if w0 < 0 else int(params[w0])


@jit_inline
def control_torques(t, q, omega, y, terms, params, table, work, w0, u, r, xhat, v, dz):
    """``(tau_ext, tau_applied, m)``: the external control torque (ideal PD and B-dot, body
    axes), the torque the control applies to the body (external or the wheels' reaction),
    and the B-dot dipole, for the orbit's ``r, xhat, v`` at ``t`` (:func:`orbit_radial`);
    the wheels' motor torques go into ``u`` (zero without a wheel-actuated law). A law with a
    flight-software period (``params[p0 + CTL_PERIOD] > 0``) applies the command it holds in
    ``y[z0:z0 + nz]`` (the torque, the motor torques or the dipole; :func:`tick` wrote it)
    instead of evaluating itself; the wheels' speed limits and the field ``B(t)`` act at every
    instant. A continuous PD law with an integral gain writes its integral's rate (d/dt, the
    anti-windup gate applied) into ``dz[zi:zi + 3]``."""
    for k in range(u.shape[0]):
        u[k] = 0.0
    ext = (0.0, 0.0, 0.0)
    app = (0.0, 0.0, 0.0)
    m = (0.0, 0.0, 0.0)
    n = terms.shape[0]
    mode = current_mode(terms, params, y)
    for j in range(1, n):
        kind = terms[j, KIND]
        p0 = terms[j, P0]
        if is_flight_software(kind):
            if not row_active(params, p0, mode):  # a law of another mode of the sequence
                continue
        if kind == PD_CONTROL:
            wheels = params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_WHEELS
            mtq = params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_MAGNETORQUERS
            b = (0.0, 0.0, 0.0)
            mmax = 0.0
            if mtq:  # the field B(t) (body axes) and the limit, from the companion row
                b, mmax = magnetorquer_field(j, t, q, terms, params, table, work)
            if params[p0 + _CTL_PERIOD] > 0.0:
                z0 = int(params[p0 + _CTL_Z0])
                if wheels:
                    for k in range(u.shape[0]):
                        u[k] = y[z0 + k]
                    tb = ctl.wheel_reaction(omega, y, params, w0, u)
                    app = vadd(app, tb)
                elif mtq:  # the dipole held since the tick, in the field of now
                    m = (y[z0], y[z0 + 1], y[z0 + 2])
                    tau = cross(m, b)
                    ext = vadd(ext, tau)
                    app = vadd(app, tau)
                else:
                    tau = (y[z0], y[z0 + 1], y[z0 + 2])
                    ext = vadd(ext, tau)
                    app = vadd(app, tau)
                continue
            aux, aux_rate = pd_row_target(j, t, terms, params, table, work)
            tau, raw, e = ctl.pd_torque(q, omega, params, p0, r, xhat, v, aux, aux_rate, y)
            ki = params[p0 + _PD_KI]
            if ki > 0.0:
                zi = int(params[p0 + _PD_ZI])
                tmax = params[p0 + _PD_TMAX]
                for k in range(3):
                    dz[zi + k] = ctl.windup_gate(raw[k], e[k], ki, tmax)
            if wheels:
                tb = ctl.wheel_torques(tau, omega, y, params, p0, w0, u)
                app = vadd(app, tb)
            else:
                if mtq:  # the part of the command normal to B: m x B
                    m = ctl.pd_dipole(tau, b, mmax, params, p0)
                    tau = cross(m, b)
                ext = vadd(ext, tau)
                app = vadd(app, tau)
        elif kind == BDOT_CONTROL:
            b_s, bdot_s = piece_eval_rate(table[terms[j, R0]:terms[j, R1]], t, terms[j, FLAGS], work)
            if params[p0 + _CTL_PERIOD] > 0.0:
                z0 = int(params[p0 + _CTL_Z0])
                m = (y[z0], y[z0 + 1], y[z0 + 2])
                b = rotate_inv(q, b_s)
            else:
                m, b = ctl.bdot_dipole(q, omega, b_s, bdot_s, params, p0)
            tau = cross(m, b)
            ext = vadd(ext, tau)
            app = vadd(app, tau)
        elif kind == MOMENTUM_DUMP:  # magnetorquers unloading the wheels: the external torque m x B(t)
            b4 = piece_eval(table[terms[j, R0]:terms[j, R1]], t, 3, terms[j, FLAGS], work)
            b = rotate_inv(q, (b4[0], b4[1], b4[2]))
            if params[p0 + _CTL_PERIOD] > 0.0:  # the dipole held since the last tick
                z0 = int(params[p0 + _CTL_Z0])
                m = (y[z0], y[z0 + 1], y[z0 + 2])
            else:
                m = ctl.dump_dipole(ctl.wheels_momentum(y, params, w0), b, params, p0)
            tau = cross(m, b)
            ext = vadd(ext, tau)
            app = vadd(app, tau)
    return ext, app, m


@jit_inline
def extended_rates(t, dtds, r, xhat, v, y, inertia, terms, params, table, work, dy):
    """``dy/ds`` of the gyrostat with control (module docstring) into ``dy`` (``len(y)``
    components: 8 plus one per wheel) for the orbit's ``t, dt/ds, r, xhat, v``
    (:func:`orbatt.core.model.orbit_at`, evaluated once for a group of lanes)."""
    q = (y[0], y[1], y[2], y[3])
    Q = (y[4], y[5], y[6], y[7])
    w0 = wheel_row(terms)
    w = qmul(qconj(q), Q)
    omega, _ = body_rate((0.5 * w[1], 0.5 * w[2], 0.5 * w[3]), y, inertia, params, w0)
    a = (2.0 * omega[0], 2.0 * omega[1], 2.0 * omega[2])  # the pure quaternion (0, 2 omega)
    qd = qmul_pure(q, a)
    Qd = qmul_pure(Q, a)
    _, G = terms_at(t, q, inertia, terms, params, table, work, r, xhat, v)
    nw = wheel_count(params, w0)
    for k in range(8 + nw, y.shape[0]):  # the controllers' states: held commands are constant
        dy[k] = 0.0                      # between ticks (a continuous integral's rate follows)
    ext, _, _ = control_torques(t, q, omega, y, terms, params, table, work, w0, dy[8:8 + nw], r, xhat, v, dy)
    Gc = gradient_of_torque(q, ext)
    for k in range(4):
        dy[k] = dtds * (0.25 * qd[k])
        dy[4 + k] = dtds * (0.25 * Qd[k] - G[k] - Gc[k])
    for k in range(nw):  # the rotors' friction: an internal torque
        dy[8 + k] -= ctl.wheel_friction(omega, y, params, w0, k)
    for k in range(8, y.shape[0]):  # the wheels' and the controllers' rates (control_torques wrote d/dt)
        dy[k] *= dtds


@jit
def rhs_extended(s, y, inertia, terms, params, table, work, dy):
    """``dy/ds`` of the gyrostat with control (module docstring) into ``dy`` (``len(y)``
    components: 8 plus one per wheel); ``s`` the time, or the eccentric anomaly
    (``dy/ds = dt/ds dy/dt``, :func:`orbatt.core.hamiltonian.rhs`)."""
    # the orbit once for the terms and the control law (an extended model has >= 1 term)
    t, dtds, r, xhat, v = orbit_at(s, terms, params, table, work)
    extended_rates(t, dtds, r, xhat, v, y, inertia, terms, params, table, work, dy)


@jit
def evaluate_extended(t, Y, inertia, terms, params, table, work):
    """At the times ``t (N,)`` and states ``Y (N, 8 + n)``: the body rate ``omega (N, 3)``, the
    wheels' momentum ``h (N, 3)`` (body axes), the torque the control applies to the body
    ``tau (N, 3)``, the B-dot dipole ``m (N, 3)`` and the motor torques ``u (N, n)`` (for the
    outputs of a result)."""
    N = Y.shape[0]
    w0 = wheel_row(terms)
    nw = wheel_count(params, w0)
    nz = 0
    for j in range(1, terms.shape[0]):
        if is_flight_software(terms[j, KIND]):
            nz += int(params[terms[j, P0] + _CTL_NZ])
    if Y.shape[1] != 8 + nw + nz:
        raise ValueError("evaluate_extended: the states lack the wheels' momenta or the flight software's held "
                         "commands of the model (8 + wheels + commands columns)")
    omega = np.empty((N, 3))
    h = np.empty((N, 3))
    tau = np.empty((N, 3))
    m = np.empty((N, 3))
    u = np.zeros((N, nw))
    scratch = np.empty(Y.shape[1])  # (the integrals' rates: not an output)
    for i in range(N):
        y = Y[i]
        q = (y[0], y[1], y[2], y[3])
        w = qmul(qconj(q), (y[4], y[5], y[6], y[7]))
        om, hv = body_rate((0.5 * w[1], 0.5 * w[2], 0.5 * w[3]), y, inertia, params, w0)
        r, xhat, v = orbit_radial(t[i], terms, params, table, work)
        _, app, mi = control_torques(t[i], q, om, y, terms, params, table, work, w0, u[i], r, xhat, v, scratch)
        for k in range(3):
            omega[i, k] = om[k]
            h[i, k] = hv[k]
            tau[i, k] = app[k]
            m[i, k] = mi[k]
    return omega, h, tau, m, u


@jit_inline
def error_angle(e):
    """The rotation angle (rad) of a PD law's error ``e = sgn(q_e0) Im(q_e)``: ``2 asin |e|``."""
    return 2.0 * math.asin(min(1.0, math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])))


@jit
def law_errors(t, q, terms, params, table, work):
    """The attitude error angle (rad, ``(N,)``) of the model's first PD law at the times ``t
    (N,)`` for the true attitudes ``q (N, 4)``: ``2 asin |e|`` of the law's own error
    (:func:`orbatt.core.control.pd_error`: any target, orbital, inertial, Sun, ground or nadir,
    with its table); NaN without a PD law."""
    N = t.shape[0]
    out = np.full(N, np.nan)
    for j in range(1, terms.shape[0]):
        if terms[j, KIND] != PD_CONTROL:
            continue
        p0 = terms[j, P0]
        for i in range(N):
            r, xhat, v = orbit_radial(t[i], terms, params, table, work)
            aux, aux_rate = pd_row_target(j, t[i], terms, params, table, work)
            e, _ = ctl.pd_error((q[i, 0], q[i, 1], q[i, 2], q[i, 3]), params, p0, r, xhat, v, aux, aux_rate)
            out[i] = error_angle(e)
        break
    return out


# ---------------------------------------------------------------------------------------
# The flight software's ticks (issue 32): laws evaluated at t_k = phase + k period, held


@jit_inline
def _grid_after(t, phase, period):
    """The first tick ``phase + k period`` strictly after ``t`` (``k`` an integer; the same
    expression for every caller, so that a landing time compares equal)."""
    k = math.floor((t - phase) / period) + 1.0
    tk = phase + k * period
    while tk <= t:
        k += 1.0
        tk = phase + k * period
    return tk


@jit_inline
def grid_time(t, phase, period):
    """The tick ``phase + k period`` nearest to ``t``: the flight software's clock at a tick
    whose state's time ``t`` is off by rounding (the eccentric anomaly's: an ulp or so)."""
    return phase + math.floor((t - phase) / period + 0.5) * period


@jit_inline
def on_grid(s, t, phase, period, terms, params, t_grid):
    """Whether ``s`` (the independent variable; ``t`` its time) is a tick ``phase + k period``
    as :func:`next_tick` gives them (in the eccentric anomaly: the tick's anomaly). ``t_grid``:
    the time of the tick the step loop landed on (:func:`next_tick_grid`: ``s`` is its anomaly
    exactly), which spares Kepler's equation for a row whose tick it is; NaN: unknown."""
    tk = grid_time(t, phase, period)
    if terms[0, KIND] == ORBIT_KEPLER_ANOMALY:
        if tk == t_grid:
            return True
        return anomaly_of_time(tk, params[terms[0, P0]:terms[0, P1]]) == s
    return tk == s


@jit
def has_ticks(terms, params):
    """Whether a control law of the model runs at a flight-software period, or the model has a
    mode sequence (a continuous one, without a period, begins in its first mode at the
    driver's start tick too: :mod:`orbatt.core.mode_events`)."""
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        if kind == MODES or (is_flight_software(kind) and params[terms[j, P0] + _CTL_PERIOD] > 0.0):
            return True
    return False


@jit
def next_tick(s, terms, params):
    """The first flight-software tick after ``s`` of the model's laws, in the step loops'
    independent variable (the time, or the eccentric anomaly: :func:`orbit_at`); ``inf`` if
    none. The step loops land on it as on a breakpoint."""
    return next_tick_grid(s, terms, params, math.nan)[0]


@jit
def next_tick_grid(s, terms, params, t_grid):
    """``(s_k, t_k)``: :func:`next_tick` and its time (what :func:`tick` takes as ``t_grid``);
    ``(inf, nan)`` if none. Rows whose ticks fall at the same time share one solution of
    Kepler's equation. ``t_grid``: the time of the tick ``s`` is (the step loop landed on it;
    spares the map from ``s`` to the time), NaN if unknown: the same result either way (from a
    time rounded below the tick, the tick's own anomaly ``s`` is passed over below)."""
    best = np.inf
    best_t = math.nan
    last_t = math.nan
    last_s = math.nan
    kind0 = terms[0, KIND]
    orb = params[terms[0, P0]:terms[0, P1]]
    t = t_grid if t_grid == t_grid else time_of_s(s, terms, params)
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        if not is_flight_software(kind):
            continue
        p0 = terms[j, P0]
        period = params[p0 + _CTL_PERIOD]
        if period > 0.0:
            tk = _grid_after(t, params[p0 + _CTL_PHASE], period)
            sk = tk
            if kind0 == ORBIT_KEPLER_ANOMALY:
                sk = last_s if tk == last_t else anomaly_of_time(tk, orb)
                while sk <= s:  # (rounding of the map to the anomaly)
                    tk = _grid_after(tk, params[p0 + _CTL_PHASE], period)
                    sk = anomaly_of_time(tk, orb)
                last_t = tk
                last_s = sk
            if sk < best:
                best = sk
                best_t = tk
    return best, best_t


@jit
def tick(s, y, inertia, terms, params, table, work, start, t_grid):
    """The flight software at ``s`` (the step loops' independent variable) on the state ``y``:
    each law with a period evaluates itself on ``y`` and writes the command it holds until
    its next tick into ``y[z0:z0 + nz]`` (the PD law's torque, or its wheels' motor torques
    clipped to the motors' limits; B-dot's dipole). ``start``: the start of a run (the driver
    calls it once, before the step loop), where every law evaluates and a mode sequence begins
    in its first mode; else the laws whose tick ``s`` is evaluate (the loop landed on a tick of
    one of them; ``t_grid``: that tick's time, :func:`next_tick_grid`, NaN if unknown)."""
    t, _, r, xhat, v = orbit_at(s, terms, params, table, work)
    q = (y[0], y[1], y[2], y[3])
    w = qmul(qconj(q), (y[4], y[5], y[6], y[7]))
    omega, _ = body_rate((0.5 * w[1], 0.5 * w[2], 0.5 * w[3]), y, inertia, params, wheel_row(terms))
    tick_on(s, t, r, xhat, v, omega, y, terms, params, table, work, start, t_grid)


@jit_inline
def tick_on(s, t, r, xhat, v, omega, y, terms, params, table, work, start, t_grid):
    """:func:`tick` for the orbit ``t, r, xhat, v`` at ``s`` (:func:`orbit_at`) and the body
    rate ``omega`` of ``y`` (:func:`body_rate`), which its caller shares (:func:`orbatt.core.
    held_commands.wheel_tick`)."""
    q = (y[0], y[1], y[2], y[3])
    w0 = wheel_row(terms)
    nav = -1
    for j in range(1, terms.shape[0]):  # the sensors and the filter first (issue 33)
        if terms[j, KIND] == NAVIGATION:
            nav = terms[j, P0]
            if start or on_grid(s, t, params[nav + _CTL_PHASE], params[nav + _CTL_PERIOD], terms, params, t_grid):
                sun = (0.0, 0.0, 0.0)
                if terms[j, R1] > terms[j, R0]:
                    s4 = piece_eval(table[terms[j, R0]:terms[j, R1]], t, 3, terms[j, FLAGS], work)
                    sun = (s4[0], s4[1], s4[2])
                est.navigation_tick(t, y, q, omega, r, xhat, sun, params, nav, start)
                for jv in range(j + 1, terms.shape[0]):  # its vector sensors (they follow its row)
                    if terms[jv, KIND] != VECTOR_SENSOR:
                        break
                    v4 = piece_eval(table[terms[jv, R0]:terms[jv, R1]], t, 3, terms[jv, FLAGS], work)
                    est.vector_tick(t, y, q, r, xhat, (v4[0], v4[1], v4[2]), params, nav, terms[jv, P0])
    # what the flight software knows: the estimate, when the laws act on it (else the truth)
    q, omega = est.estimate_feedback(y, params, nav, q, omega)
    for j in range(1, terms.shape[0]):  # the mode sequence next: its transition, then the laws
        if terms[j, KIND] == MODES:
            mode_transition(s, t, y, q, omega, terms, params, table, work, r, xhat, v, j, start, t_grid)
    mode = current_mode(terms, params, y)
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        if kind != PD_CONTROL and kind != BDOT_CONTROL and kind != MOMENTUM_DUMP:
            continue
        p0 = terms[j, P0]
        if not row_active(params, p0, mode):
            continue
        period = params[p0 + _CTL_PERIOD]
        if not period > 0.0:
            continue
        z0 = int(params[p0 + _CTL_Z0])
        if not start and not on_grid(s, t, params[p0 + _CTL_PHASE], period, terms, params, t_grid):
            continue
        if kind == PD_CONTROL:
            pd_tick(j, t, q, omega, r, xhat, v, y, w0, terms, params, table, work)
        elif kind == MOMENTUM_DUMP:  # the dumping dipole of the wheels' momentum and the field at the tick
            b4 = piece_eval(table[terms[j, R0]:terms[j, R1]], t, 3, terms[j, FLAGS], work)
            m = ctl.dump_dipole(ctl.wheels_momentum(y, params, w0), rotate_inv(q, (b4[0], b4[1], b4[2])), params, p0)
            y[z0] = m[0]
            y[z0 + 1] = m[1]
            y[z0 + 2] = m[2]
        else:
            b_s, bdot_s = piece_eval_rate(table[terms[j, R0]:terms[j, R1]], t, terms[j, FLAGS], work)
            m, _ = ctl.bdot_dipole(q, omega, b_s, bdot_s, params, p0)
            y[z0] = m[0]
            y[z0 + 1] = m[1]
            y[z0 + 2] = m[2]


@jit_inline
def pd_tick(j, t, q, omega, r, xhat, v, y, w0, terms, params, table, work):
    """PD row ``j`` at its tick: its command (the torque, the wheels' motor torques or the
    dipole) into ``y[z0:]`` and its discrete integral ``s_k+1 = s_k + period e_k``, for the
    attitude ``q`` and rate ``omega`` the flight software knows and the orbit ``t, r, xhat, v``."""
    p0 = terms[j, P0]
    z0 = int(params[p0 + _CTL_Z0])
    aux, aux_rate = pd_row_target(j, t, terms, params, table, work)
    tau, raw, e = ctl.pd_torque(q, omega, params, p0, r, xhat, v, aux, aux_rate, y)
    if params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_WHEELS:
        ctl.wheel_commands(tau, params, p0, w0, y[z0:z0 + wheel_count(params, w0)])
    elif params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_MAGNETORQUERS:  # the dipole, held
        b, mmax = magnetorquer_field(j, t, q, terms, params, table, work)
        m = ctl.pd_dipole(tau, b, mmax, params, p0)
        y[z0] = m[0]
        y[z0 + 1] = m[1]
        y[z0 + 2] = m[2]
    else:
        y[z0] = tau[0]
        y[z0 + 1] = tau[1]
        y[z0 + 2] = tau[2]
    ki = params[p0 + _PD_KI]
    if ki > 0.0:  # the discrete integral: s_k+1 = s_k + period e_k (anti-windup gated)
        zi = int(params[p0 + _PD_ZI])
        tmax = params[p0 + _PD_TMAX]
        for k in range(3):
            y[zi + k] += params[p0 + _CTL_PERIOD] * ctl.windup_gate(raw[k], e[k], ki, tmax)


@jit_inline
def magnetorquer_field(j, t, q, terms, params, table, work):
    """``(B, m_max)``: for PD row ``j`` on magnetorquers, the field at ``t`` in the body axes of
    ``q`` (T) and the per-axis dipole limit, from its companion :data:`MAGNETORQUERS` row (the
    first after ``j``: :meth:`orbatt.PDControl.model_rows` puts it there)."""
    jm = j + 1
    while terms[jm, KIND] != MAGNETORQUERS:
        jm += 1
    b4 = piece_eval(table[terms[jm, R0]:terms[jm, R1]], t, 3, terms[jm, FLAGS], work)
    return rotate_inv(q, (b4[0], b4[1], b4[2])), params[terms[jm, P0] + ctl.MTQ_MAX_DIPOLE]


@jit_inline
def pd_row_target(j, t, terms, params, table, work):
    """``(position, rate)`` of PD row ``j``'s target table at ``t`` (inertial, km and km/s): the
    Sun's position (its rate left out: zeros), or a ground target's position and velocity;
    zeros without a table."""
    pos = (0.0, 0.0, 0.0)
    rate = (0.0, 0.0, 0.0)
    if terms[j, R1] > terms[j, R0]:
        target = params[terms[j, P0] + _PD_TARGET]
        if target == ctl.TARGET_GROUND or target == ctl.TARGET_NADIR:
            pos, rate = piece_eval_rate(table[terms[j, R0]:terms[j, R1]], t, terms[j, FLAGS], work)
        else:
            s4 = piece_eval(table[terms[j, R0]:terms[j, R1]], t, 3, terms[j, FLAGS], work)
            pos = (s4[0], s4[1], s4[2])
    return pos, rate


@jit_inline
def mode_error_angle(t, q, m, terms, params, table, work, r, xhat, v):
    """The attitude error angle (rad) of the PD law of mode ``m`` of the model's sequence at
    the time ``t`` (orbit ``r, xhat, v``) and attitude ``q``; ``inf`` without one."""
    angle = np.inf
    for j in range(1, terms.shape[0]):
        if terms[j, KIND] == PD_CONTROL and params[terms[j, P0] + _CTL_MODE] == float(m):
            aux, aux_rate = pd_row_target(j, t, terms, params, table, work)
            e, _ = ctl.pd_error(q, params, terms[j, P0], r, xhat, v, aux, aux_rate)
            angle = error_angle(e)
    return angle


@jit
def mode_transition(s, t, y, q, omega, terms, params, table, work, r, xhat, v, jm, start, t_grid):
    """The mode sequence of row ``jm`` at a tick ``s`` (time ``t``) on the state ``y``: at the
    start of a run (its state unset), mode 0 from ``t``; on one of its ticks, leave the current
    mode for the next when its ``until_time`` has passed since it began, or when its other
    conditions (``|omega| < until_rate``; the attitude error of the mode's PD law ``<
    until_settled``; all those given) have held for ``hold``; the last mode stays. The state:
    :mod:`orbatt.core.mode_state` (finite: the error norm reads it). The clock is the tick's
    own time (:func:`grid_time`), not the state's, an ulp below it in the eccentric anomaly."""
    p0 = terms[jm, P0]
    z = int(params[p0 + _CTL_Z0])
    phase, period = params[p0 + _CTL_PHASE], params[p0 + _CTL_PERIOD]
    ticks = period > 0.0 and on_grid(s, t, phase, period, terms, params, t_grid)
    clock = grid_time(t, phase, period) if ticks else t
    if start:  # (a run may start between two ticks: then at its own time)
        enter_mode(y, z, 0, clock)
        return
    if not ticks:  # not one of its ticks (or a sequence without a period: orbatt.core.mode_events)
        return
    m = int(y[z + MODE])
    if m >= int(params[p0 + _MD_COUNT]) - 1:
        return
    c = p0 + _MD_COND + _MD_FIELDS * m
    leave = clock - y[z + ENTRY] >= params[c + _MD_TIME]
    rate, settled = params[c + _MD_RATE], params[c + _MD_SETTLED]
    if rate < np.inf or settled < np.inf:
        holds = True
        if rate < np.inf:
            holds = math.sqrt(omega[0] * omega[0] + omega[1] * omega[1] + omega[2] * omega[2]) < rate
        if settled < np.inf:
            holds = holds and mode_error_angle(t, q, m, terms, params, table, work, r, xhat, v) < settled
        if holds:
            if y[z + HOLDS] == 0.0:
                y[z + HOLD_BEGAN] = clock
                y[z + HOLDS] = 1.0
            if clock - y[z + HOLD_BEGAN] >= params[c + _MD_HOLD]:
                leave = True
        else:
            y[z + HOLDS] = 0.0
    if leave:
        enter_mode(y, z, m + 1, clock)

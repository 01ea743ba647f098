"""What the step loops save when the flight software's laws hold their commands between ticks
(:func:`orbatt.core.gyrostat.tick`): the extended right-hand side (:mod:`orbatt.core.gyrostat`)
of a lockstep group of lanes in structure-of-arrays form (:func:`rhs_extended_lanes`), and the
derivative after a tick that changed only the wheels' motor torques (:func:`wheel_command_rates`).

The group's right-hand side: each of its parts is one loop over the lanes, lanes innermost,
with the model's rows and the wheels outside, so that LLVM vectorizes it.

A lane's column of the result is, bit for bit, what :func:`orbatt.core.gyrostat.rhs_extended`
gives for that member alone: every lane runs the same IEEE operations in the same order (the
loops are reordered across lanes, never within one lane's arithmetic, and numba allows no
contraction into fused multiply-adds). The flight software's commands are what makes this
possible: a law with a period holds its command in the state (:func:`orbatt.core.gyrostat.tick`),
so between ticks the control is a few lane-wise operations on that state. Models whose control
is evaluated at every stage (a continuous law, a mode sequence, the PD law on magnetorquers)
take each lane's scalar code (:func:`orbatt.core.gyrostat.extended_rates`), as before.

Measured on ``benchmarks/basilisk_fsw.py``'s loop (gravity gradient, three wheels, a PD law on
them at 10 Hz; 32 lanes): 36.5 ns per lane and evaluation, against 94 with each lane's scalar
code, the same bits (``benchmarks/README.md``).

The derivative after a tick: a step that ends on a tick ends with the derivative there under the
old command (the last stage of ``bs32`` and ``dopri5`` is evaluated at the step's end). When the
only laws are PD laws on the wheels (:func:`wheel_ticks_only`), the new command changes only
the wheels' rows of the derivative (the motor torques, the speed limits, the friction: the
body feels them through ``h``, not through the external torque), so the loop rewrites those
rows instead of evaluating the whole right-hand side again: the same bits as a full evaluation
(tested), one right-hand side fewer per tick. The tick's laws and that rewrite share one orbit and
one body rate (:func:`wheel_tick`).
"""
from __future__ import annotations

import math

from ._jit import jit, jit_inline
from . import control as ctl
from .environment import piece_eval, piece_eval_rate
from .gyrostat import (body_rate, cofactor_solve, extended_rates, is_flight_software, on_grid, pd_tick, row_active,
                       tick_on, wheel_count, wheel_row)
from .model import (BDOT_CONTROL, FLAGS, KIND, MODES, MOMENTUM_DUMP, NAVIGATION, P0, PD_CONTROL, R0, R1, orbit_at,
                    terms_lanes)
from .qalg import cross, qconj, qmul, qmul_pure, rotate_inv
from .torques import gradient_of_torque

__all__ = ["LANE_SCRATCH", "held_lanes", "rhs_extended_lanes", "wheel_ticks_only", "wheel_command_rates", "wheel_tick", "pd_ticks"]

#: rows of the scratch ``S (LANE_SCRATCH, L)`` that :func:`rhs_extended_lanes` takes
LANE_SCRATCH = 22

_W_AXIS, _W_IW, _W_SMAX = ctl.WHEEL.axis, ctl.WHEEL.iw, ctl.WHEEL.speed_max
_W_COULOMB, _W_VISCOUS, _W_WIDTH = ctl.WHEEL.coulomb, ctl.WHEEL.viscous, ctl.WHEEL.width
_CTL_PERIOD, _CTL_PHASE, _CTL_Z0 = ctl.CTL_PERIOD, ctl.CTL_PHASE, ctl.CTL_Z0
_PD_ACTUATOR = ctl.PD_ACTUATOR


@jit
def held_lanes(terms, params):
    """Whether every control law of the model holds its command between ticks in a form the
    structure-of-arrays right-hand side takes: each PD law (on wheels or ideal torque), B-dot
    and momentum-dumping row has a period, and there is no mode sequence."""
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        p0 = terms[j, P0]
        if kind == MODES:
            return False
        if kind == PD_CONTROL or kind == BDOT_CONTROL or kind == MOMENTUM_DUMP:
            if not params[p0 + _CTL_PERIOD] > 0.0:
                return False
            if kind == PD_CONTROL and params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_MAGNETORQUERS:
                return False
    return True


@jit_inline
def _body_rates(Y, nl, I, params, w0, nw, S):
    """The lanes' body rates ``omega = J^-1 (g - h)`` into ``S[4:7]`` (``g`` from ``S[10:13]``;
    :func:`orbatt.core.gyrostat.body_rate`'s operations; ``S[13:19]`` and ``S[19:22]`` scratch
    for ``J`` and ``h``)."""
    X = S[10:13]
    OM = S[4:7]
    if w0 < 0:
        for i in range(3):
            for l in range(nl):
                OM[i, l] = X[i, l] / I[i, l]
        return
    J = S[13:19]
    H = S[19:22]
    for l in range(nl):
        J[0, l] = I[0, l]
        J[1, l] = I[1, l]
        J[2, l] = I[2, l]
        J[3, l] = 0.0
        J[4, l] = 0.0
        J[5, l] = 0.0
        H[0, l] = 0.0
        H[1, l] = 0.0
        H[2, l] = 0.0
    for k in range(nw):
        w = w0 + 1 + ctl.WHEEL_SIZE * k
        a0, a1, a2 = params[w + _W_AXIS], params[w + _W_AXIS + 1], params[w + _W_AXIS + 2]
        iw = params[w + _W_IW]
        for l in range(nl):
            J[0, l] -= iw * a0 * a0
            J[1, l] -= iw * a1 * a1
            J[2, l] -= iw * a2 * a2
            J[3, l] -= iw * a0 * a1
            J[4, l] -= iw * a0 * a2
            J[5, l] -= iw * a1 * a2
            hk = Y[8 + k, l]
            H[0, l] += hk * a0
            H[1, l] += hk * a1
            H[2, l] += hk * a2
    for l in range(nl):
        OM[0, l], OM[1, l], OM[2, l] = cofactor_solve(J[0, l], J[1, l], J[2, l], J[3, l], J[4, l], J[5, l],
                                                      (X[0, l] - H[0, l], X[1, l] - H[1, l], X[2, l] - H[2, l]))


@jit_inline
def _held_field_torque(Y, nl, z0, b, E):
    """``E += m x B`` per lane: the dipole ``m`` held in ``Y[z0:z0 + 3]`` in the field ``b``
    (inertial) seen in each lane's body axes."""
    for l in range(nl):
        q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
        tau = cross((Y[z0, l], Y[z0 + 1, l], Y[z0 + 2, l]), rotate_inv(q, b))
        E[0, l] = E[0, l] + tau[0]
        E[1, l] = E[1, l] + tau[1]
        E[2, l] = E[2, l] + tau[2]


@jit
def rhs_extended_lanes(s, Y, nl, I, terms, params, table, work, dY, S):
    """:func:`orbatt.core.gyrostat.rhs_extended` for lanes ``0..nl-1`` of ``Y (n, L)`` (inertia
    ``I (3, L)``) at the common ``s``, into ``dY (n, L)``; ``S (LANE_SCRATCH, L)`` scratch. The
    orbit is evaluated once for the group; a model whose laws hold their commands
    (:func:`held_lanes`) runs the structure-of-arrays form (module docstring), any other each
    lane's scalar operations. Either way a lane's column is its member's derivative exactly.
    Pass borrowed arrays (:func:`orbatt.core._jit.borrow`)."""
    t, dtds, r, xhat, v = orbit_at(s, terms, params, table, work)
    if not held_lanes(terms, params):
        for l in range(nl):
            extended_rates(t, dtds, r, xhat, v, Y[:, l], I[:, l], terms, params, table, work, dY[:, l])
        return
    n = Y.shape[0]
    w0 = wheel_row(terms)
    nw = wheel_count(params, w0)
    G = S[0:4]
    OM = S[4:7]
    E = S[7:10]
    X = S[10:13]
    # the total momentum g = 1/2 Im(q~ Q), then the body rates
    for l in range(nl):
        w = qmul(qconj((Y[0, l], Y[1, l], Y[2, l], Y[3, l])), (Y[4, l], Y[5, l], Y[6, l], Y[7, l]))
        X[0, l] = 0.5 * w[1]
        X[1, l] = 0.5 * w[2]
        X[2, l] = 0.5 * w[3]
    _body_rates(Y, nl, I, params, w0, nw, S)
    # the terms' generalized gradient (one loop over the lanes per term)
    if terms.shape[0] > 1:
        terms_lanes(t, Y, nl, I, terms, params, table, work, r, xhat, v, G)
    else:
        for i in range(4):
            for l in range(nl):
                G[i, l] = 0.0
    # the held commands (orbatt.core.gyrostat.control_torques): the wheels' motor torques into
    # dY[8:8 + nw], the external control torque into E
    for k in range(8, n):
        for l in range(nl):
            dY[k, l] = 0.0
    for i in range(3):
        for l in range(nl):
            E[i, l] = 0.0
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        p0 = terms[j, P0]
        if is_flight_software(kind):
            if not row_active(params, p0, -1.0):
                continue
        if kind == PD_CONTROL:
            z0 = int(params[p0 + _CTL_Z0])
            if params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_WHEELS:
                for k in range(nw):  # orbatt.core.control.wheel_reaction: no torque past a speed limit
                    w = w0 + 1 + ctl.WHEEL_SIZE * k
                    a0, a1, a2 = params[w + _W_AXIS], params[w + _W_AXIS + 1], params[w + _W_AXIS + 2]
                    iw = params[w + _W_IW]
                    smax = params[w + _W_SMAX]
                    for l in range(nl):
                        uk = Y[z0 + k, l]
                        speed = Y[8 + k, l] / iw - (a0 * OM[0, l] + a1 * OM[1, l] + a2 * OM[2, l])
                        if (speed >= smax and uk > 0.0) or (speed <= -smax and uk < 0.0):
                            uk = 0.0
                        dY[8 + k, l] = uk
            else:
                for i in range(3):
                    for l in range(nl):
                        E[i, l] = E[i, l] + Y[z0 + i, l]
        elif kind == BDOT_CONTROL:
            b_s, _ = piece_eval_rate(table[terms[j, R0]:terms[j, R1]], t, terms[j, FLAGS], work)
            _held_field_torque(Y, nl, int(params[p0 + _CTL_Z0]), b_s, E)
        elif kind == MOMENTUM_DUMP:
            b4 = piece_eval(table[terms[j, R0]:terms[j, R1]], t, 3, terms[j, FLAGS], work)
            _held_field_torque(Y, nl, int(params[p0 + _CTL_Z0]), (b4[0], b4[1], b4[2]), E)
    # Hamilton's equations (orbatt.core.gyrostat.extended_rates)
    for l in range(nl):
        q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
        Q = (Y[4, l], Y[5, l], Y[6, l], Y[7, l])
        a = (2.0 * OM[0, l], 2.0 * OM[1, l], 2.0 * OM[2, l])
        qd = qmul_pure(q, a)
        Qd = qmul_pure(Q, a)
        Gc = gradient_of_torque(q, (E[0, l], E[1, l], E[2, l]))
        for k in range(4):
            dY[k, l] = dtds * (0.25 * qd[k])
            dY[4 + k, l] = dtds * (0.25 * Qd[k] - G[k, l] - Gc[k])
    for k in range(nw):  # the rotors' friction (orbatt.core.control.wheel_friction)
        w = w0 + 1 + ctl.WHEEL_SIZE * k
        c = params[w + _W_COULOMB]
        b = params[w + _W_VISCOUS]
        if c == 0.0 and b == 0.0:
            continue
        a0, a1, a2 = params[w + _W_AXIS], params[w + _W_AXIS + 1], params[w + _W_AXIS + 2]
        iw = params[w + _W_IW]
        width = params[w + _W_WIDTH]
        for l in range(nl):
            speed = Y[8 + k, l] / iw - (a0 * OM[0, l] + a1 * OM[1, l] + a2 * OM[2, l])
            dY[8 + k, l] -= c * math.tanh(speed / width) + b * speed
    for k in range(8, n):
        for l in range(nl):
            dY[k, l] *= dtds


@jit
def wheel_ticks_only(terms, params):
    """Whether the model's laws are all PD laws on the reaction wheels with a period (no other
    law, no mode sequence): a tick then changes only the wheels' rows of the derivative
    (:func:`wheel_command_rates`). 0: no; 1: yes, with sensors; 2: yes, without sensors (the
    tick of :func:`pd_ticks`)."""
    found = False
    sensors = False
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        p0 = terms[j, P0]
        if kind == MODES or kind == BDOT_CONTROL or kind == MOMENTUM_DUMP:
            return 0
        if kind == NAVIGATION:
            sensors = True
        if kind == PD_CONTROL:
            if not (params[p0 + _CTL_PERIOD] > 0.0 and params[p0 + _PD_ACTUATOR] == ctl.ACTUATOR_WHEELS):
                return 0
            found = True
    if not found:
        return 0
    return 1 if sensors else 2


@jit
def wheel_command_rates(s, y, inertia, terms, params, table, work, dy):
    """After a tick of a model of :func:`wheel_ticks_only`: ``dy`` holds the derivative at ``(s,
    y)`` under the commands before the tick; rewrite its wheels' rows ``dy[8:8 + nw]`` for the
    commands ``y`` holds now (the motor torques zeroed past a speed limit, less the friction,
    times ``dt/ds``), the operations of :func:`orbatt.core.gyrostat.extended_rates`. The other
    rows do not depend on the wheels' commands."""
    _, dtds, _, _, _ = orbit_at(s, terms, params, table, work)
    q = (y[0], y[1], y[2], y[3])
    w = qmul(qconj(q), (y[4], y[5], y[6], y[7]))
    omega, _ = body_rate((0.5 * w[1], 0.5 * w[2], 0.5 * w[3]), y, inertia, params, wheel_row(terms))
    wheel_rows(dtds, omega, y, terms, params, dy)


@jit
def wheel_tick(s, y, inertia, terms, params, table, work, t_grid, dy, lean):
    """:func:`orbatt.core.gyrostat.tick` at ``s`` and then :func:`wheel_command_rates`, for a
    model of :func:`wheel_ticks_only`, sharing their orbit and body rate (the laws leave the
    attitude and the wheels' momenta as they are): the same numbers as the two calls, ~80 ns
    less a tick on the 10 Hz loop on wheels (``docs/design.md`` §4). ``lean``: the model has no
    sensors (:func:`wheel_ticks_only` 2), so its laws run as :func:`pd_ticks`,
    without walking the rows for sensors and modes."""
    t, dtds, r, xhat, v = orbit_at(s, terms, params, table, work)
    q = (y[0], y[1], y[2], y[3])
    w = qmul(qconj(q), (y[4], y[5], y[6], y[7]))
    omega, _ = body_rate((0.5 * w[1], 0.5 * w[2], 0.5 * w[3]), y, inertia, params, wheel_row(terms))
    if lean:  # (wheel_ticks_only 2: PD laws alone, no sensors)
        pd_ticks(s, t, r, xhat, v, omega, y, terms, params, table, work, t_grid)
    else:
        tick_on(s, t, r, xhat, v, omega, y, terms, params, table, work, False, t_grid)
    wheel_rows(dtds, omega, y, terms, params, dy)


@jit_inline
def pd_ticks(s, t, r, xhat, v, omega, y, terms, params, table, work, t_grid):
    """:func:`orbatt.core.gyrostat.tick_on` for a model whose flight software is PD laws alone, each with a period
    (no sensors, no mode sequence, no other law): the rows whose tick ``s`` is, on the truth."""
    q = (y[0], y[1], y[2], y[3])
    w0 = wheel_row(terms)
    for j in range(1, terms.shape[0]):
        if terms[j, KIND] == PD_CONTROL:
            p0 = terms[j, P0]
            if on_grid(s, t, params[p0 + _CTL_PHASE], params[p0 + _CTL_PERIOD], terms, params, t_grid):
                pd_tick(j, t, q, omega, r, xhat, v, y, w0, terms, params, table, work)


@jit_inline
def wheel_rows(dtds, omega, y, terms, params, dy):
    """The wheels' rows ``dy[8:8 + nw]`` of the derivative for the commands ``y`` holds (body
    rate ``omega``; ``dt/ds``), as :func:`orbatt.core.gyrostat.extended_rates` forms them."""
    w0 = wheel_row(terms)
    nw = wheel_count(params, w0)
    u = dy[8:8 + nw]
    for k in range(nw):
        u[k] = 0.0
    for j in range(1, terms.shape[0]):
        p0 = terms[j, P0]
        if terms[j, KIND] == PD_CONTROL and row_active(params, p0, -1.0):
            z0 = int(params[p0 + _CTL_Z0])
            for k in range(nw):
                u[k] = y[z0 + k]
            ctl.wheel_reaction(omega, y, params, w0, u)
    for k in range(nw):
        dy[8 + k] -= ctl.wheel_friction(omega, y, params, w0, k)
    for k in range(8, 8 + nw):
        dy[k] *= dtds

"""Mode sequences without a flight-software period (issue 32, item 4): the transitions located
on the continuous solution (compiled, no units; ``docs/design.md`` §4).

A sequence with a ``period`` (:func:`orbatt.core.gyrostat.mode_transition`) decides at its
ticks. Without one, its laws are continuous and so is the sequence: it leaves a mode at the
instant its condition is met, found by the one adaptive step loop (:mod:`orbatt.core.rk_loop`)
with the tools it has for the torques' kinks:

* **the conditions' crossings** are a switching function of the sequence (after the terms' own,
  :mod:`orbatt.core.switches`): ``g = max(|omega| / until_rate - 1, angle / until_settled - 1)``
  over the current mode's conditions (``angle`` the attitude error of the mode's PD law), NaN
  where the mode has neither (or is the last). ``g < 0`` is "they all hold". The loop locates
  its roots on the step's Hermite interpolant of the whole state and retakes the step to end
  there, as for a facet's edge.
* **the times** ``entry + until_time`` and ``began + hold`` (while the conditions hold) are
  knots of the loop, like the ticks of a law with a period (:func:`next_event`).
* at every accepted step end the loop calls :func:`advance`: the conditions' flag follows the
  crossing it landed on (its direction: the sign of the function before it), or the sign of
  ``g`` where ``|g|`` exceeds the anti-chatter band (a crossing that the band hid); a mode whose
  time has come is left (and the next one's conditions are taken at once, so that a mode
  with ``hold = 0`` whose conditions already hold is passed through at the same instant). A
  mode left at the knot of its ``entry + until_time`` or ``began + hold`` hands that time to
  the next as its entry, exactly (the state's time there may lie an ulp off it).

The state is the periodic sequence's (:mod:`orbatt.core.mode_state`): ``(mode, entry time, time
the conditions began to hold, whether they hold)``, then each mode's entry time;
:func:`orbatt.core.gyrostat.tick` begins it (mode 0) at the driver's start tick, then
:func:`advance` (``start``) takes the first mode's conditions.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline
from . import control as ctl
from .gyrostat import body_rate, mode_error_angle, wheel_row
from .kepler import anomaly_of_time
from .mode_state import ENTRY, HOLD_BEGAN, HOLDS, MODE, enter_mode
from .model import KIND, MODES, ORBIT_KEPLER_ANOMALY, P0, P1, orbit_at
from .qalg import qconj, qmul

__all__ = ["is_continuous_sequence", "sequence_count", "condition_value", "mode_values", "advance", "next_event"]

_CTL_PERIOD, _CTL_Z0 = ctl.CTL_PERIOD, ctl.CTL_Z0
_MD_COUNT, _MD_COND, _MD_FIELDS = ctl.MODES.count, ctl.MODES.conditions, ctl.MODE_FIELDS
_MD_TIME, _MD_RATE, _MD_SETTLED, _MD_HOLD = (ctl.MODE_UNTIL_TIME, ctl.MODE_UNTIL_RATE, ctl.MODE_UNTIL_SETTLED,
                                             ctl.MODE_HOLD)


@jit_inline
def is_continuous_sequence(terms, params, j):
    """Whether row ``j`` is a mode sequence without a flight-software period."""
    return terms[j, KIND] == MODES and not params[terms[j, P0] + _CTL_PERIOD] > 0.0


@jit
def sequence_count(terms, params):
    """The number of continuous mode sequences of the model (their switching functions)."""
    n = 0
    for j in range(1, terms.shape[0]):
        if is_continuous_sequence(terms, params, j):
            n += 1
    return n


@jit_inline
def _attitude_rate(y, inertia, terms, params):
    """``(q, omega)``: the attitude and the body rate (body axes) of the state ``y``."""
    q = (y[0], y[1], y[2], y[3])
    w = qmul(qconj(q), (y[4], y[5], y[6], y[7]))
    omega, _ = body_rate((0.5 * w[1], 0.5 * w[2], 0.5 * w[3]), y, inertia, params, wheel_row(terms))
    return q, omega


@jit
def condition_value(t, q, omega, jm, m, terms, params, table, work, r, xhat, v):
    """``g``, the switching function of mode ``m`` of the sequence of row ``jm`` (module
    docstring) at the time ``t``, attitude ``q`` and body rate ``omega``: negative where all its
    rate and attitude conditions hold; NaN where it has none or is the last mode."""
    p0 = terms[jm, P0]
    if m >= int(params[p0 + _MD_COUNT]) - 1:
        return math.nan
    c = p0 + _MD_COND + _MD_FIELDS * m
    rate, settled = params[c + _MD_RATE], params[c + _MD_SETTLED]
    if not (rate < np.inf or settled < np.inf):
        return math.nan
    g = -np.inf
    if rate < np.inf:
        g = max(g, math.sqrt(omega[0] * omega[0] + omega[1] * omega[1] + omega[2] * omega[2]) / rate - 1.0)
    if settled < np.inf:  # the attitude error of the mode's PD law
        g = max(g, mode_error_angle(t, q, m, terms, params, table, work, r, xhat, v) / settled - 1.0)
    return g


@jit
def mode_values(s, y, inertia, terms, params, table, work, out):
    """The continuous sequences' switching functions at ``s`` (the step loops' independent
    variable) and the state ``y`` (all its components) into ``out[:n]``, in row order; returns
    ``n`` (:func:`sequence_count`)."""
    n = 0
    if sequence_count(terms, params) == 0:
        return 0
    t, _, r, xhat, v = orbit_at(s, terms, params, table, work)
    q, omega = _attitude_rate(y, inertia, terms, params)
    for j in range(1, terms.shape[0]):
        if is_continuous_sequence(terms, params, j):
            z = int(params[terms[j, P0] + _CTL_Z0])
            out[n] = condition_value(t, q, omega, j, int(y[z + MODE]), terms, params, table, work, r, xhat, v)
            n += 1
    return n


@jit_inline
def _reached(s, t, te, terms, params):
    """Whether the time ``te`` has come at ``s`` (time ``t``): in the eccentric anomaly, the
    anomaly :func:`next_event` gives it, so that a landing on it compares equal."""
    if te <= t:
        return True
    if terms[0, KIND] == ORBIT_KEPLER_ANOMALY:
        return anomaly_of_time(te, params[terms[0, P0]:terms[0, P1]]) <= s
    return False


@jit_inline
def _landed_on(s, te, terms, params):
    """Whether ``s`` is the knot :func:`next_event` gives the time ``te``."""
    if terms[0, KIND] == ORBIT_KEPLER_ANOMALY:
        return anomaly_of_time(te, params[terms[0, P0]:terms[0, P1]]) == s
    return te == s


@jit
def advance(s, y, inertia, terms, params, table, work, g_now, landed, now_holds, band, start):
    """The continuous sequences at ``s`` (an accepted step end, or the run's start) on the
    state ``y`` (module docstring): their conditions' flags, then each mode whose time has come
    left for the next. ``g_now``: the sequences' switching functions at ``s`` on ``y``
    (:func:`mode_values`, which the step loop has evaluated there already; not read at the
    ``start``); ``landed``: the index (among the continuous sequences) of the one whose
    switching function the step ended on (-1: none), ``now_holds`` whether its conditions hold
    past that crossing; ``band``: the anti-chatter band of :mod:`orbatt.core.switches`;
    ``start``: take the conditions as they are. Returns ``(mode_changed, flag_changed)``."""
    mode_changed = False
    flag_changed = False
    if sequence_count(terms, params) == 0:
        return mode_changed, flag_changed
    t, _, r, xhat, v = orbit_at(s, terms, params, table, work)
    q, omega = _attitude_rate(y, inertia, terms, params)
    i = -1
    for j in range(1, terms.shape[0]):
        if not is_continuous_sequence(terms, params, j):
            continue
        i += 1
        p0 = terms[j, P0]
        z = int(params[p0 + _CTL_Z0])
        count = int(params[p0 + _MD_COUNT])
        first = True
        now = t  # the sequence's clock: the time of the knot a mode was left at, else the state's
        for _ in range(count):
            m = int(y[z + MODE])
            if m >= count - 1:
                break
            c = p0 + _MD_COND + _MD_FIELDS * m
            if first and not start:  # the current mode's: the loop's value at this step end
                g = g_now[i]
            else:  # a mode just begun (or the start): its own conditions
                g = condition_value(t, q, omega, j, m, terms, params, table, work, r, xhat, v)
            if g == g:
                holds = y[z + HOLDS] == 1.0
                if first and i == landed:  # the crossing the loop landed on: its direction
                    holds = now_holds
                elif start or not first:  # a mode just begun: its conditions as they are
                    holds = g < 0.0
                elif g < -band:  # out of the anti-chatter band: the sign is the truth
                    holds = True
                elif g > band:
                    holds = False
                if holds and y[z + HOLDS] == 0.0:
                    y[z + HOLD_BEGAN] = now
                    y[z + HOLDS] = 1.0
                    flag_changed = True
                elif not holds and y[z + HOLDS] == 1.0:
                    y[z + HOLDS] = 0.0
                    flag_changed = True
            # the time the mode's end came: until_time after its entry, or hold after its
            # conditions began to hold (the earlier)
            te = np.inf
            if params[c + _MD_TIME] < np.inf and _reached(s, t, y[z + ENTRY] + params[c + _MD_TIME], terms, params):
                te = y[z + ENTRY] + params[c + _MD_TIME]
            if y[z + HOLDS] == 1.0 and _reached(s, t, y[z + HOLD_BEGAN] + params[c + _MD_HOLD], terms, params):
                te = min(te, y[z + HOLD_BEGAN] + params[c + _MD_HOLD])
            if not te < np.inf:
                break
            if _landed_on(s, te, terms, params):  # the knot of that time: its time, not the state's
                now = te                          # (in the eccentric anomaly an ulp off it)
            enter_mode(y, z, m + 1, now)
            mode_changed = True
            first = False
    return mode_changed, flag_changed


@jit
def next_event(s, y, terms, params):
    """The first time after ``s`` (in the step loops' independent variable) at which a
    continuous sequence's mode may end: ``entry + until_time``, or ``began + hold`` while its
    conditions hold; ``inf`` if none. The loop lands on it as on a tick."""
    best = np.inf
    for j in range(1, terms.shape[0]):
        if not is_continuous_sequence(terms, params, j):
            continue
        p0 = terms[j, P0]
        z = int(params[p0 + _CTL_Z0])
        m = int(y[z + MODE])
        if m >= int(params[p0 + _MD_COUNT]) - 1:
            continue
        c = p0 + _MD_COND + _MD_FIELDS * m
        for k in range(2):
            if k == 0:
                if not params[c + _MD_TIME] < np.inf:
                    continue
                te = y[z + ENTRY] + params[c + _MD_TIME]
            else:
                if y[z + HOLDS] != 1.0:
                    continue
                te = y[z + HOLD_BEGAN] + params[c + _MD_HOLD]
            se = te
            if terms[0, KIND] == ORBIT_KEPLER_ANOMALY:
                se = anomaly_of_time(te, params[terms[0, P0]:terms[0, P1]])
            if se > s and se < best:
                best = se
    return best

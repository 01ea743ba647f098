"""Switching functions of a model and their location inside a step (compiled, no units;
``docs/design.md`` §4, issue 25).

Some terms are smooth except on surfaces in the state space or along the orbit where their
torque has a kink or a jump: a facet's ``max(0, cos theta)`` (drag: against the flow; SRP:
against the Sun), the shadow function's edges (conical: penumbra, umbra and annular edges,
where ``nu`` has a kink; cylindrical: the one edge, where it jumps). A step that straddles one
has an error the embedded estimate sees badly: the step loop (:mod:`orbatt.core.rk_loop`)
rejected a third of its attempts on the disturbed scenarios. Here each such surface is a
**switching function** ``g_k(s, q)``, dimensionless, ``O(1)``, zero on the surface:

=================  ==========================================  =======================
term               functions (in the model's row order)        value
=================  ==========================================  =======================
drag               one per facet                               ``n . v^`` (body axes)
SRP                one per facet                               ``n . s^`` (body axes)
SRP, conical       penumbra, umbra, annular edges              ``(c - (a + b)) / a``,
                                                               ``(c - (b - a)) / a``,
                                                               ``(c - (a - b)) / a``
SRP, cylindrical   the edge                                    ``rho / R - 1``
=================  ==========================================  =======================

(``a, b, c``: :func:`orbatt.core.environment.conical_geometry`; ``rho``: the distance from the
shadow's axis behind the body, the distance from the centre in front.) A facet's function is
NaN where its term vanishes (no density, umbra): no switch there.

The loop evaluates them at every accepted step end (:func:`switch_values`) and keeps, for
each, a reference in the model's scratch ``work[SWITCH_SLOT + k]``: its value at the current
step's start, or NaN while it is **disarmed**. A trial step whose end has an armed function of
the other sign (:func:`crossed`) is located (:func:`locate`: the earliest root on the cubic
Hermite interpolant of ``q`` between the step's ends, Illinois' regula falsi to ~1e-13 of the
step) and retaken to end there, as on an output time. **Anti-chatter**: the function landed on
is disarmed, and it is armed again only once it is farther than :data:`REARM` from zero at a
step end (:func:`update`); so a facet edge-on for a whole arc (``|cos theta| < REARM``) is one
switch, not one per oscillation. A root within :data:`AT_START` of the step's start disarms
its function without a retake. At most :data:`~orbatt.core.potentials.MAX_SWITCHES` functions
are tracked (a model's first ones).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit
from . import environment as env
from .model import (DRAG, DRAG_HEADER, FLAGS, KIND, NO_SWITCHES, P0, R0, R1, SHADOW_CONICAL, SHADOW_CYLINDRICAL,
                    SRP, SRP_HEADER, orbit_at, term_constants)
from .potentials import MAX_SWITCHES, SWITCH_SLOT
from .mode_events import mode_values, sequence_count
from .qalg import rotate_inv
from .torques import FACET_SIZE

__all__ = ["REARM", "AT_START", "switch_count", "switch_values", "loop_switches", "loop_switch_values", "shadow_edges",
           "crossed", "locate", "update",
           "shadow_crossings", "eclipse_times", "MAX_SWITCHES", "SWITCH_SLOT"]

#: a disarmed function is armed again once ``|g| > REARM`` at a step end
REARM = 1.0e-3
#: a root closer than this fraction of the step to its start is taken as the start's
AT_START = 1.0e-9
#: Illinois' iteration stops when the bracket is narrower than this fraction of the step
THETA_TOL = 1.0e-13


@jit
def switch_count(terms, params):
    """The number of switching functions of the model (at most :data:`MAX_SWITCHES`); 0 when
    row 0 has the :data:`orbatt.core.model.NO_SWITCHES` flag."""
    if (terms[0, FLAGS] & NO_SWITCHES) != 0:
        return 0
    n = 0
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        p0 = terms[j, P0]
        if kind == DRAG:
            n += int(params[p0 + 1])
        elif kind == SRP:
            n += int(params[p0 + 5])
            shadow = params[p0 + 2]
            if shadow == SHADOW_CONICAL:
                n += 3
            elif shadow == SHADOW_CYLINDRICAL:
                n += 1
    return min(n, MAX_SWITCHES)


@jit
def loop_switches(terms, params):
    """``(n, nfac)``: the switching functions the step loop tracks - the terms' first ``nfac``
    (:func:`switch_count`), then one per continuous mode sequence
    (:mod:`orbatt.core.mode_events`, which the model's ``NO_SWITCHES`` flag does not turn off) -
    at most :data:`MAX_SWITCHES` in all."""
    nseq = sequence_count(terms, params)
    nfac = min(switch_count(terms, params), MAX_SWITCHES - nseq)
    return nfac + nseq, nfac


@jit
def loop_switch_values(s, y, inertia, terms, params, table, work, out, nfac):
    """The step loop's switching functions (:func:`loop_switches`) at ``s`` and the whole state
    ``y`` (principal moments ``inertia``) into ``out``: the terms' first ``nfac``, then the
    continuous mode sequences'. Returns their number."""
    n = 0
    if nfac > 0:
        n = switch_values(s, y, terms, params, table, work, out[:nfac])
    return n + mode_values(s, y, inertia, terms, params, table, work, out[nfac:])


@jit
def switch_values(s, q, terms, params, table, work, out):
    """The switching functions at ``s`` (the step loops' independent variable) and the
    attitude ``q`` (4 components) into ``out[:n]``; returns ``n`` (:func:`switch_count`
    without its flag test)."""
    t, _, r, xhat, v = orbit_at(s, terms, params, table, work)
    qq = (q[0], q[1], q[2], q[3])
    n = 0
    cap = min(out.shape[0], MAX_SWITCHES)
    for j in range(1, terms.shape[0]):
        kind = terms[j, KIND]
        if kind != DRAG and kind != SRP:
            continue
        _, p0, c = term_constants(j, t, terms, params, table, work, r, xhat, v)
        u = rotate_inv(qq, (c[1], c[2], c[3]))
        if kind == DRAG:
            nf = int(params[p0 + 1])
            b0 = p0 + DRAG_HEADER
        else:
            nf = int(params[p0 + 5])
            b0 = p0 + SRP_HEADER
        for f in range(nf):
            if n >= cap:
                return n
            b = b0 + f * FACET_SIZE
            if c[0] == 0.0:
                out[n] = math.nan
            else:  # the torque's own expression (orbatt.core.torques.facet_torque)
                out[n] = params[b + 1] * u[0] + params[b + 2] * u[1] + params[b + 3] * u[2]
            n += 1
        if kind == SRP:
            ne, edges = shadow_edges(j, t, r, xhat, terms, params, table, work)
            for e in range(ne):
                if n >= cap:
                    return n
                out[n] = edges[e]
                n += 1
    return n


@jit
def shadow_edges(j, t, r, xhat, terms, params, table, work):
    """``(n, (e0, e1, e2))``: the shadow's edge functions of the SRP term of row ``j`` at the
    time ``t`` and the orbit's ``r``, ``xhat`` (the module's table; the unused ones 0): conical
    ``n = 3`` (penumbra, umbra, annular), cylindrical ``n = 1``, no shadow ``n = 0``. The
    first is the outer edge: negative in the shadow."""
    p0 = terms[j, P0]
    shadow = params[p0 + 2]
    if shadow != SHADOW_CONICAL and shadow != SHADOW_CYLINDRICAL:
        return 0, (0.0, 0.0, 0.0)
    sun = env.piece_eval(table[terms[j, R0]:terms[j, R1]], t, 3, terms[j, FLAGS], work)
    rs = (r * xhat[0], r * xhat[1], r * xhat[2])
    if shadow == SHADOW_CONICAL:
        a, b, c = env.conical_geometry(rs, sun, params[p0 + 3], params[p0 + 4])
        return 3, ((c - (a + b)) / a, (c - (b - a)) / a, (c - (a - b)) / a)
    along, perp2 = env.cylindrical_geometry(rs, sun)
    return 1, (math.sqrt(perp2 if along < 0.0 else perp2 + along * along) / params[p0 + 3] - 1.0, 0.0, 0.0)


@jit
def _outer_edge(t, j, terms, params, table, work):
    """The outer shadow edge function of the SRP term of row ``j`` at the time ``t``."""
    _, _, r, xhat, _ = orbit_at(t, terms, params, table, work)
    return shadow_edges(j, t, r, xhat, terms, params, table, work)[1][0]


@jit
def shadow_crossings(terms, params, table, t0, t1, dt, out):
    """The times in ``[t0, t1]`` where the first shadowed SRP term's outer edge function
    changes sign (a model whose orbit is in time, not in the eccentric anomaly): sampled every
    ``dt`` (at most), each sign change bisected to ~1e-12 of the time; ``out[0, i]`` the time,
    ``out[1, i]`` -1 at an entry into the shadow, +1 at an exit. Returns their number (at most
    ``out.shape[1]``; 0 without a shadowed SRP term)."""
    j = -1
    for i in range(1, terms.shape[0]):
        if terms[i, KIND] == SRP and (params[terms[i, P0] + 2] == SHADOW_CONICAL
                                      or params[terms[i, P0] + 2] == SHADOW_CYLINDRICAL):
            j = i
            break
    if j < 0 or not (t1 > t0):
        return 0
    work = np.full(SWITCH_SLOT, np.nan)
    steps = max(1, int(math.ceil((t1 - t0) / dt)))
    ta = t0
    ga = _outer_edge(ta, j, terms, params, table, work)
    n = 0
    for i in range(1, steps + 1):
        tb = t1 if i == steps else t0 + (t1 - t0) * (i / steps)
        gb = _outer_edge(tb, j, terms, params, table, work)
        if (ga < 0.0) != (gb < 0.0) and n < out.shape[1]:
            lo, hi = ta, tb
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if not (mid > lo and mid < hi):
                    break
                if (_outer_edge(mid, j, terms, params, table, work) < 0.0) == (ga < 0.0):
                    lo = mid
                else:
                    hi = mid
            out[0, n] = 0.5 * (lo + hi)
            out[1, n] = 1.0 if ga < 0.0 else -1.0
            n += 1
        ta, ga = tb, gb
    return n


def eclipse_times(terms, params, table, t0, t1, dt=10.0):
    """``(entry, exit)``: float64 arrays of the same length, the times (the model's time unit)
    of each eclipse's entry into and exit from the first shadowed SRP term's shadow (its outer
    edge: the penumbra's, conical) within ``[t0, t1]``, in order; NaN where the run starts or
    ends inside an eclipse. Both empty without a shadowed SRP term or an eclipse. ``dt``: the
    sampling (s) before bisection; an eclipse shorter than it may be missed."""
    cap = int(math.ceil((t1 - t0) / dt)) + 2 if t1 > t0 else 2
    out = np.empty((2, cap))
    n = shadow_crossings(terms, params, table, float(t0), float(t1), float(dt), out)
    entry, exit_ = [], []
    for t, kind in zip(out[0, :n], out[1, :n]):
        if kind < 0:
            entry.append(t)
            exit_.append(math.nan)
        elif entry and math.isnan(exit_[-1]):
            exit_[-1] = t
        else:  # the run started in the shadow
            entry.append(math.nan)
            exit_.append(t)
    return np.array(entry, dtype=np.float64), np.array(exit_, dtype=np.float64)


@jit
def crossed(work, g, n):
    """Whether an armed function ``k < n`` (reference ``work[SWITCH_SLOT + k]``) has the other
    sign in ``g`` (a trial step's end)."""
    for k in range(n):
        g0 = work[SWITCH_SLOT + k]
        g1 = g[k]
        if g0 != 0.0 and g1 == g1 and g0 == g0 and (g0 > 0.0) != (g1 > 0.0):
            return True
    return False


@jit
def _hermite_q(theta, hh, y0, f0, y1, f1, qt):
    """The state (``qt``'s length of components: ``q`` and what follows) at the fraction
    ``theta`` of the step ``hh`` on the cubic Hermite interpolant of the step's ends ``(y0,
    f0)``, ``(y1, f1)`` (``f = dy/ds``), into ``qt``."""
    t2 = theta * theta
    t3 = t2 * theta
    h00 = 2.0 * t3 - 3.0 * t2 + 1.0
    h10 = t3 - 2.0 * t2 + theta
    h01 = 3.0 * t2 - 2.0 * t3
    h11 = t3 - t2
    for i in range(qt.shape[0]):
        qt[i] = h00 * y0[i] + h01 * y1[i] + hh * (h10 * f0[i] + h11 * f1[i])


@jit
def locate(s, hh, y0, f0, y1, f1, g, n, nfac, inertia, terms, params, table, work, scratch):
    """``(theta, k)``: the earliest root, as a fraction of the step ``[s, s + hh]``, of the
    armed functions (:func:`loop_switch_values`, ``nfac`` of the terms) that changed sign
    (reference ``work[SWITCH_SLOT + k]`` at ``s``, ``g[k]`` at ``s + hh``), on the cubic Hermite
    interpolant of the state (:func:`_hermite_q`: ``q``, and the rest for a mode sequence's
    conditions), by Illinois' regula falsi; ``(1, -1)`` if none. ``theta`` is the bracket's end
    past the root (the function has its new sign there, or is 0). ``scratch``: at least
    ``len(y0) + n`` floats."""
    nc = y0.shape[0]
    qt = scratch[:nc]
    gt = scratch[nc:]
    best = 1.0
    kbest = -1
    for k in range(n):
        ga = work[SWITCH_SLOT + k]
        gb = g[k]
        if not (ga != 0.0 and gb == gb and ga == ga and (ga > 0.0) != (gb > 0.0)):
            continue
        newpos = gb > 0.0  # the new sign (gb itself may become 0 below)
        a = 0.0
        b = 1.0
        side = 0
        for _ in range(100):
            if b - a <= THETA_TOL:
                break
            if gb == 0.0:  # the root itself
                break
            x = b - gb * (b - a) / (gb - ga)
            if not (x > a and x < b):
                x = 0.5 * (a + b)
            if x >= best:  # only an earlier root matters: is there one before the best?
                x = best
            _hermite_q(x, hh, y0, f0, y1, f1, qt)
            loop_switch_values(s + x * hh, qt, inertia, terms, params, table, work, gt, nfac)
            gx = gt[k]
            if gx != gx:  # the function vanished inside: no root of it there
                a = b = 1.0
                break
            if gx == 0.0 or (gx > 0.0) == newpos:  # the new sign: the root is at or before x
                b = x
                gb = gx
                if side == 1:
                    ga *= 0.5
                side = 1
            else:
                if x >= best:  # the old sign at the best root so far: this one is later
                    a = b = 1.0
                    break
                a = x
                ga = gx
                if side == -1:
                    gb *= 0.5
                side = -1
        if b < best:
            best = b
            kbest = k
    return best, kbest


@jit
def update(work, g, n, landed):
    """The references after an accepted step ending where the functions are ``g``: an armed
    function takes its value there (NaN where it vanished: disarmed), a disarmed one is armed
    when ``|g| > REARM``; the function ``landed`` (the step ended on its root; -1: none) and any
    other within 1e-9 of zero there (a simultaneous root) are disarmed."""
    for k in range(n):
        gk = g[k]
        if k == landed or (landed >= 0 and abs(gk) < 1.0e-9):
            work[SWITCH_SLOT + k] = math.nan
        elif abs(gk) > REARM or work[SWITCH_SLOT + k] == work[SWITCH_SLOT + k]:
            work[SWITCH_SLOT + k] = gk

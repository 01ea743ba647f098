"""The building blocks of the adaptive Runge-Kutta step loop (:mod:`orbatt.core.rk_loop`): the
per-trajectory (or per-group) integrator state arrays, Hairer's initial step, the error norm,
the PI step-size controller, acceptance and rejection, the landing on output times and
breakpoints, and the Runge-Kutta pairs the loop runs (:data:`TABLEAUS`).

Every helper is inlined (``jit_inline``) into the one loop and works on scalars or on one
member's components, so the single trajectory and the lockstep lanes run the same
operations (``docs/design.md`` §4).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import (DONE, FLAG_NONFINITE, MAX_STEPS, NDIM, NONFINITE, PAUSED, STEP_TOO_SMALL, jit, jit_inline)
from . import bs32_coefficients as _bs
from . import dop853_coefficients as _dp
from . import dopri5_coefficients as _d5
from . import verner98_coefficients as _vn
from .dop853_coefficients import ORDER
from .model import orbit_at

__all__ = ["new_state", "momentum_scale", "hinit_guess", "hinit_refine", "hinit_refine_order", "error_norm",
           "plan_step", "controller", "controller9", "controller_pow", "pi_step", "next_after_accept",
           "next_after_reject", "reject_nonfinite", "reject_step", "accept_step", "hinit_norms", "hinit_der2",
           "all_finite", "failure", "begin_attempt", "TABLEAUS", "PAIRS",
           "SAFETY", "FAC_MIN", "FAC_MAX", "BETA", "LAND_MARGIN", "ST_T", "ST_H", "ST_FACOLD", "ST_HMIN", "ST_SWITCH_T",
           "ST_SWITCH_K", "ST_SIZE", "CNT_STEPS", "CNT_REJECTED", "CNT_NFEV", "CNT_IOUT", "CNT_NREC", "CNT_FLAGS",
           "CNT_SWITCHES", "CNT_SIZE"]

SAFETY = 0.9
FAC_MIN = 0.333  # h_new >= FAC_MIN h   (Hairer's fac1)
FAC_MAX = 6.0    # h_new <= FAC_MAX h   (Hairer's fac2)
#: PI control: ``h_new = h / (err^(1/8) / facold^BETA / SAFETY)`` (Hairer's ``beta``)
BETA = 0.04
#: a step lands on the next output time when it would otherwise stop within 1 % of it
LAND_MARGIN = 1.01

# ---------------------------------------------------------------------------------------
# Per-trajectory state arrays (resumable integrator). ``st`` (float64):
ST_T = 0          # current time
ST_H = 1          # step size to try next (0: choose one, Hairer's hinit)
ST_FACOLD = 2     # previous error (the PI controller's memory, exponent BETA)
ST_HMIN = 3       # a floor on the step size set by the driver (0: none; see the module docstring)
ST_SWITCH_T = 4   # a located switch the next steps land on (orbatt.core.switches) ...
ST_SWITCH_K = 5   # 0 before the first call, then 1 + (its function's index + 1, or 0: none)
ST_SIZE = 6
# ``cnt`` (int64):
CNT_STEPS = 0     # accepted steps
CNT_REJECTED = 1  # rejected steps (error too large or non-finite)
CNT_NFEV = 2      # right-hand-side evaluations
CNT_IOUT = 3      # index of the next output time
CNT_NREC = 4      # rows written to the record buffer (record_all mode)
CNT_FLAGS = 5     # FLAG_* bits of orbatt.core._jit (and, for groups, the failing lane)
CNT_SWITCHES = 6  # trial steps retaken to end on a located switch (orbatt.core.switches)
CNT_SIZE = 7


def new_state(batch=None, width=NDIM):
    """Fresh ``(st, cnt, f0)`` arrays, for one trajectory or a ``batch`` of them, of states of
    ``width`` components (8, plus one per reaction wheel)."""
    shape = () if batch is None else (batch,)
    return (np.zeros(shape + (ST_SIZE,)), np.zeros(shape + (CNT_SIZE,), dtype=np.int64),
            np.zeros(shape + (width,)))


# ---------------------------------------------------------------------------------------
# Shared inline helpers: tolerances, Hairer's initial step, error norm, controller, landing


@jit_inline
def momentum_scale(inertia):
    """``max(I1, I2, I3)``: the absolute tolerance of ``Q`` is ``atol`` times this."""
    return max(inertia[0], max(inertia[1], inertia[2]))


@jit_inline
def hinit_guess(dnf, dny):
    """Hairer's first guess of the initial step from the scaled norms of ``f`` and ``y``."""
    if dnf <= 1e-10 or dny <= 1e-10:
        return 1.0e-6
    return math.sqrt(dny / dnf) * 0.01


@jit_inline
def hinit_refine(der2, dnf, h0):
    """Hairer's second estimate from the scaled second derivative ``der2`` (squared norm of
    ``f(t + h0, y + h0 f) - f``) at the trial step ``h0``."""
    der12 = max(math.sqrt(der2) / h0, math.sqrt(dnf))
    if der12 <= 1e-15:
        return max(1.0e-6, h0 * 1.0e-3)
    return (0.01 / der12) ** (1.0 / ORDER)


@jit_inline
def hinit_refine_order(der2, dnf, h0, order):
    """:func:`hinit_refine` for a pair of order ``order`` (Hairer's ``iord``): ``(0.01 /
    der12)^(1/order)``."""
    der12 = max(math.sqrt(der2) / h0, math.sqrt(dnf))
    if der12 <= 1e-15:
        return max(1.0e-6, h0 * 1.0e-3)
    return (0.01 / der12) ** (1.0 / order)


@jit_inline
def error_norm(e5, e3, hh, n):
    """Hairer's error of a step of size ``hh`` from the sums of squares ``e5``, ``e3`` over
    ``n`` components."""
    deno = e5 + 0.01 * e3
    if deno <= 0.0:
        deno = 1.0
    return abs(hh) * e5 * math.sqrt(1.0 / (n * deno))


@jit_inline
def plan_step(t, h, max_step, t_next):
    """``(hh, landing)``: the step to attempt from ``t``; shortened to land on ``t_next``
    when it would otherwise stop within :data:`LAND_MARGIN` of it."""
    hh = min(h, max_step)
    if t + LAND_MARGIN * hh >= t_next:
        return _to_knot(t_next, t), True
    return hh, False


@jit
def _to_knot(t_next, t):
    """``t_next - t``, compiled once and called: a call keeps :func:`plan_step`'s landing a
    branch, which the processor predicts, where LLVM may turn it into a select that waits for
    the step size, that is for the last step's error and controller. The same numbers; measured
    on the 10 Hz loop of one trajectory (``bs32``, a landing every step): 1-3 % (0.77-0.80
    against 0.79-0.81 us a tick, interleaved)."""
    return t_next - t


@jit_inline
def controller(err, facold, hh):
    """``(fac11, hnew)``: ``err^(1/8)`` and the PI controller's next step after an attempt of
    size ``hh`` with error ``err`` (finite)."""
    return pi_step(math.sqrt(math.sqrt(math.sqrt(err))), facold, hh)  # err ** (1/8)


@jit_inline
def controller9(err, facold, hh):
    """:func:`controller` for a pair whose embedded solution has order 8 (Verner's 9(8)):
    ``(fac11, hnew)`` with ``fac11 = err^(1/9)``."""
    return pi_step(err ** (1.0 / 9.0), facold, hh)


@jit_inline
def controller_pow(err, facold, hh, expo):
    """:func:`controller` for a pair whose controller exponent is ``expo`` (1 / (the embedded
    order + 1); Dormand-Prince 5(4): 1/5): ``(fac11, hnew)`` with ``fac11 = err^expo``."""
    return pi_step(err ** expo, facold, hh)


@jit_inline
def pi_step(fac11, facold, hh):
    """``(fac11, hnew)``: the PI controller's next step after an attempt of size ``hh`` whose
    error to the power 1/(order + 1) is ``fac11`` (``facold``: the previous error, exponent
    :data:`BETA`), bounded by :data:`FAC_MIN`, :data:`FAC_MAX` and the safety factor."""
    fac = fac11 / facold ** BETA if BETA != 0.0 else fac11
    fac = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, fac / SAFETY))
    return fac11, hh / fac


@jit_inline
def next_after_accept(hnew, hh, h, max_step, rejected_before, landing):
    """The step after an accepted one: capped by ``max_step``, no increase right after a
    rejection, and after a landing (a shortened step says little) the earlier proposal."""
    hnew = min(hnew, max_step)
    if rejected_before:
        hnew = min(hnew, hh)
    if landing:
        hnew = max(hnew, h)
    return hnew


@jit_inline
def next_after_reject(hh, fac11):
    """The step after a rejection for a too large (finite) error."""
    return hh / min(1.0 / FAC_MIN, fac11 / SAFETY)


@jit_inline
def reject_nonfinite(cnt, flags, hh):
    """Count a rejection for a non-finite error or derivative: ``(flags, h, rejected)`` with
    the non-finite flag set, the step cut tenfold and ``rejected`` True."""
    cnt[CNT_REJECTED] += 1
    return flags | FLAG_NONFINITE, 0.1 * hh, True


@jit_inline
def reject_step(cnt, flags, hh, fac11):
    """Count a rejection for a too large (finite) error: ``(flags, h, rejected)`` with the
    non-finite flag cleared, the smaller step (:func:`next_after_reject`) and ``rejected``
    True."""
    cnt[CNT_REJECTED] += 1
    return flags & ~FLAG_NONFINITE, next_after_reject(hh, fac11), True


@jit_inline
def accept_step(cnt, flags, err, hnew, hh, h, max_step, rejected_before, landing):
    """Count an accepted step of size ``hh`` and error ``err``: ``(flags, facold, hnew,
    rejected)`` with the non-finite flag cleared, the controller's memory, the next step
    (:func:`next_after_accept` of the controller's proposal ``hnew``) and ``rejected``
    False."""
    cnt[CNT_STEPS] += 1
    return (flags & ~FLAG_NONFINITE, max(err, 1.0e-4),
            next_after_accept(hnew, hh, h, max_step, rejected_before, landing), False)


@jit_inline
def hinit_norms(y, f, atol, aQ, rtol):
    """``(dnf, dny)``: the squared scaled norms of ``f`` and ``y`` (Hairer's ``hinit``); ``y``
    and ``f`` are the components of one member (``q``, ``Q``, then the wheels' momenta,
    weighted as ``Q``)."""
    dnf = 0.0
    dny = 0.0
    for i in range(y.shape[0]):
        sk = (atol if i < 4 else aQ) + rtol * abs(y[i])
        a = f[i] / sk  # squares as products: the same bits compiled and interpreted
        b = y[i] / sk
        dnf += a * a
        dny += b * b
    return dnf, dny


@jit_inline
def hinit_der2(y, f0, f1, atol, aQ, rtol):
    """The squared scaled norm of ``f1 - f0`` (Hairer's second-derivative estimate)."""
    der2 = 0.0
    for i in range(y.shape[0]):
        sk = (atol if i < 4 else aQ) + rtol * abs(y[i])
        d = (f1[i] - f0[i]) / sk
        der2 += d * d
    return der2


@jit_inline
def all_finite(v, n):
    """Whether the first ``n`` components of ``v`` are finite."""
    for i in range(n):
        if not (abs(v[i]) < np.inf):
            return False
    return True


@jit_inline
def failure(flags):
    """The status of a run whose step size underflowed."""
    return NONFINITE if (flags & FLAG_NONFINITE) != 0 else STEP_TOO_SMALL


@jit_inline
def begin_attempt(attempts, budget, cnt, max_steps, t, h, max_step, t_out, i_out, hmin, flags, t_brk):
    """``(status, hh, landing, t_next)`` before a step attempt towards the next output time
    ``t_out[i_out]`` or the next breakpoint ``t_brk`` if earlier
    (:func:`orbatt.core.model.next_breakpoint`), ``t_next``: :data:`DONE` to attempt the
    step ``hh`` (:func:`plan_step`), else why to stop (budget of this call, ``max_steps``:
    accepted, rejected and retaken attempts, step-size underflow)."""
    t_next = t_out[i_out]
    if t_brk < t_next:
        t_next = t_brk
    if attempts >= budget:
        return PAUSED, 0.0, False, t_next
    if cnt[CNT_STEPS] + cnt[CNT_REJECTED] + cnt[CNT_SWITCHES] >= max_steps:
        return MAX_STEPS, 0.0, False, t_next
    hh, landing = plan_step(t, h, max_step, t_next)
    if hh <= 0.0 or (hh <= hmin and not landing):
        return failure(flags), hh, landing, t_next
    return DONE, hh, landing, t_next


#: the Runge-Kutta pairs the step loop runs: ``(N_STAGES, A_PTR, A_COL, A_VAL, C, B, E_HI,
#: E_LO)``; DOP853's error norm takes both estimates, Verner's 9(8) pair, Dormand-Prince 5(4) and
#: Bogacki-Shampine 3(2) one (``E_LO`` unused)
TABLEAUS = {"dop853": (_dp.N_STAGES, _dp.A_PTR, _dp.A_COL, _dp.A_VAL, _dp.C, _dp.B, _dp.E5, _dp.E3),
            "verner98": (_vn.N_STAGES, _vn.A_PTR, _vn.A_COL, _vn.A_VAL, _vn.C, _vn.B, _vn.E, _vn.E),
            "dopri5": (_d5.N_STAGES, _d5.A_PTR, _d5.A_COL, _d5.A_VAL, _d5.C, _d5.B, _d5.E, _d5.E),
            "bs32": (_bs.N_STAGES, _bs.A_PTR, _bs.A_COL, _bs.A_VAL, _bs.C, _bs.B, _bs.E, _bs.E)}
#: how the step loop controls each pair: ``(k, order, last_new)``: the controller's exponent
#: ``1/k`` (the error estimate's order + 1), the order of Hairer's initial step, and whether the
#: tableau's last stage is ``f(t + h, y_new)`` (FSAL inside the tableau: Dormand-Prince 5(4),
#: Bogacki-Shampine 3(2); the others evaluate the next step's first stage on acceptance)
PAIRS = {"dop853": (8, _dp.ORDER, False), "verner98": (9, _dp.ORDER, False),
         "dopri5": (5, _d5.ORDER, _d5.LAST_STAGE_IS_NEW), "bs32": (3, _bs.ORDER, _bs.LAST_STAGE_IS_NEW)}


@jit_inline
def stage_orbits(t, hh, t_new, C, n_stages, last_new, terms, params, table, work, orbs):
    """The orbit (:func:`orbatt.core.model.orbit_at`: ``t, dt/ds, r, xhat, v`` in ``orbs[s, :9]``)
    at the stages ``1..n_stages - 1`` of a step of ``hh`` from ``t`` (nodes ``C``; ``last_new``:
    the last stage at ``t_new`` itself), in the stages' order: the calls the stages would make,
    so the same bits (the Kepler warm start's memory included). One trajectory's stages form a
    chain, each stage's input the last one's output; the orbit does not depend on the state, and
    evaluated together before the stages it leaves that chain (measured on the 10 Hz loop on
    wheels, ``bs32``: ~1.0 -> ~0.75 us a tick; ``docs/design.md`` §4)."""
    for s in range(1, n_stages):
        ts = t + C[s] * hh
        if last_new:
            if s == n_stages - 1:
                ts = t_new
        o_t, o_dtds, o_r, o_xhat, o_v = orbit_at(ts, terms, params, table, work)
        orbs[s, 0] = o_t
        orbs[s, 1] = o_dtds
        orbs[s, 2] = o_r
        for i in range(3):
            orbs[s, 3 + i] = o_xhat[i]
            orbs[s, 6 + i] = o_v[i]

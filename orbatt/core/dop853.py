"""Compiled adaptive Runge-Kutta DOP853 on Hamilton's equations (eq. 7), whole step loop in
numba; one trajectory (:func:`advance`), an ensemble of independent members in parallel
(:func:`advance_batch`, each member bitwise as alone), or an ensemble in lockstep groups
(:func:`advance_lanes`, vectorized over the members of a group, see below).

Method: the explicit embedded Runge-Kutta pair of order 8(5,3) of Dormand & Prince
(coefficients: :mod:`orbatt.core.dop853_coefficients`), with the error estimate and step-size
control of Hairer's ``dop853.f`` (Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., Sect.
II.10): 12 stages, the last derivative reused as the first of the next step (FSAL), error norm

    err = |h| e5 / sqrt(n (e5 + 0.01 e3)),  e5 = sum(((E5 . K)_i / sk_i)^2), e3 likewise,
    sk_i = atol_i + rtol max(|y_i|, |y_new_i|),   atol_i = atol (q), atol * max(I) (Q)

(scipy's ``DOP853`` norm, with the absolute tolerance of the momentum block scaled by the
largest moment of inertia: ``atol`` bounds the absolute error of ``q`` and of ``Q / max(I)``, a
body rate in rad per time unit, whatever the unit of ``Q`` - kg km^2 s^-1 makes ``Q`` ~1e-7 for
a small satellite and ~1e17 for a moon), new step
``h / clip(err^(1/8) / facold^0.04 / 0.9, 1/6, 1/0.333)`` (Hairer's PI control with
``beta = 0.04``: measured 2x fewer rejected steps than ``beta = 0``, same work-precision), no
increase right after a rejection. A non-finite error estimate rejects the step with
``h / 10``; a step size below 10 ulps of the time span (or below the floor ``st[ST_HMIN]``
the driver may set: the eccentric-anomaly form of :mod:`orbatt.methods.dop853` maps the time
form's floor to the anomaly at periapsis) ends the run (:data:`NONFINITE` if the
last failure was non-finite, else :data:`STEP_TOO_SMALL`). The controller, the landing on
output times and Hairer's initial step are inline helpers shared by the single and the lane
loops.

Verner's 9(8) pair (:data:`advance_verner98`, :data:`advance_batch_verner98` and their
``_wide`` forms for extended models; coefficients: :mod:`orbatt.core.verner98_coefficients`)
runs in the same loop: 16 stages, no
FSAL (the first stage of the next step is evaluated on acceptance, as DOP853's FSAL stage),
error ``err = |h| sqrt(e / n)``, ``e = sum(((E . K)_i / sk_i)^2)`` with ``E = b - bhat``, and
the same controller with ``err^(1/9)`` (:func:`controller9`). On the Keplerian benchmark it needs
~17 % fewer right-hand-side evaluations than DOP853 at 1e-9 rad, ~9 % fewer at 1e-6 rad, and
~10 % more on the torque-free body (``benchmarks/verner98.py``). A binary's coupled orbit and
attitudes (:mod:`orbatt.core.mutual`) run in the same loop (:data:`advance_coupled`, ``_verner98``).

Breakpoints: steps also land on the knots of the model's tables, a sampled orbit's samples and
the environment tables (:func:`orbatt.core.model.next_breakpoint`), where the right-hand
side's third derivative jumps; nothing is recorded there.

Output: the integrator lands exactly on every requested output time (the step before it is
shortened, the step size proposed before shortening is kept for the step after), so outputs
carry the full accuracy of step-end values - no interpolation (``docs/design.md`` §4).
Alternatively every accepted step is recorded (``record_all``).

Resumable: the whole integrator state lives in small per-trajectory arrays (``y``, ``st``,
``cnt``, ``f0`` and the model's ``work``), and :func:`advance` returns after ``budget``
step attempts; calling it again continues exactly as if it had not stopped (the Python
driver uses this for progress reports and for a clean stop on KeyboardInterrupt).

The right-hand side is :func:`orbatt.core.hamiltonian.rhs` on a model ``terms, params,
table`` (:mod:`orbatt.core.model`); numerics notes in :mod:`orbatt.core._jit`.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from ._jit import (BAD_LANE_SHIFT, BUFFER_FULL, DONE, EPS, FLAG_BITS, FLAG_F0_VALID, FLAG_NONFINITE,
                   FLAG_REJECTED, MAX_STEPS, NDIM, NONFINITE, PAUSED, STEP_TOO_SMALL, borrow, jit, jit_inline,
                   jit_parallel, keepalive)
from . import dop853_coefficients as _dp
from . import verner98_coefficients as _vn
from .dop853_coefficients import ORDER
from .gyrostat import rhs_extended
from .hamiltonian import rhs, rhs_inline
from .model import next_breakpoint
from .mutual import C_ATOL, hinit_der2_vec, hinit_norms_vec, rhs_coupled

#: the kernels, the state layout, and (re-exported for the Python drivers) the status codes and
#: flag names of :mod:`orbatt.core._jit`
__all__ = ["advance", "advance_wide", "advance_batch", "advance_batch_wide", "advance_verner98",
           "advance_wide_verner98", "advance_batch_verner98", "advance_batch_wide_verner98", "advance_coupled", "advance_coupled_verner98", "TABLEAUS", "new_state", "momentum_scale", "begin_attempt", "NDIM", "DONE", "PAUSED", "BUFFER_FULL",
           "NONFINITE", "STEP_TOO_SMALL", "MAX_STEPS", "FLAG_F0_VALID", "FLAG_REJECTED", "FLAG_NONFINITE",
           "FLAG_BITS", "BAD_LANE_SHIFT", "ST_T", "ST_H", "ST_FACOLD", "ST_HMIN", "ST_SIZE", "EPS", "CNT_STEPS",
           "CNT_REJECTED", "CNT_NFEV", "CNT_IOUT", "CNT_NREC", "CNT_FLAGS", "CNT_SIZE"]

# Step-size controller (Hairer's defaults for dop853): safety, bounds on h_new / h
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
ST_SIZE = 4
# ``cnt`` (int64):
CNT_STEPS = 0     # accepted steps
CNT_REJECTED = 1  # rejected steps (error too large or non-finite)
CNT_NFEV = 2      # right-hand-side evaluations
CNT_IOUT = 3      # index of the next output time
CNT_NREC = 4      # rows written to the record buffer (record_all mode)
CNT_FLAGS = 5     # FLAG_* bits of orbatt.core._jit (and, for groups, the failing lane)
CNT_SIZE = 6


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
        return t_next - t, True
    return hh, False


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
    step ``hh`` (:func:`plan_step`), else why to stop (budget of this call, ``max_steps``,
    step-size underflow)."""
    t_next = t_out[i_out]
    if t_brk < t_next:
        t_next = t_brk
    if attempts >= budget:
        return PAUSED, 0.0, False, t_next
    if cnt[CNT_STEPS] + cnt[CNT_REJECTED] >= max_steps:
        return MAX_STEPS, 0.0, False, t_next
    hh, landing = plan_step(t, h, max_step, t_next)
    if hh <= 0.0 or (hh <= hmin and not landing):
        return failure(flags), hh, landing, t_next
    return DONE, hh, landing, t_next


# ---------------------------------------------------------------------------------------
# One trajectory


def _initial_step_of(extended, coupled=False):
    """Hairer's ``hinit`` on the right-hand side of the rigid body, or of (``extended``)
    :func:`orbatt.core.gyrostat.rhs_extended` or (``coupled``) :func:`orbatt.core.mutual.rhs_coupled`."""

    def initial_step(t, y, f0, f1, ytmp, inertia, terms, params, table, work, rtol, atol, hmax):
        """Hairer's ``hinit`` (order 8): a first step from the sizes of ``y``, ``f`` and an
        estimate of the second derivative (one extra RHS evaluation)."""
        aQ = atol * momentum_scale(inertia)
        dnf, dny = hinit_norms_vec(y, f0, atol, inertia, rtol) if coupled else hinit_norms(y, f0, atol, aQ, rtol)
        h = min(hinit_guess(dnf, dny), hmax)
        if not (h > 0.0 and h < np.inf):
            return h
        for i in range(y.shape[0]):
            ytmp[i] = y[i] + h * f0[i]
        if coupled:  # constants: numba prunes the other branches (their callees are not compiled)
            rhs_coupled(t + h, ytmp, inertia, terms, params, table, work, f1)
        elif extended:
            rhs_extended(t + h, ytmp, inertia, terms, params, table, work, f1)
        else:
            rhs(t + h, ytmp, inertia, terms, params, table, work, f1)
        der2 = hinit_der2_vec(y, f0, f1, atol, inertia, rtol) if coupled else hinit_der2(y, f0, f1, atol, aQ, rtol)
        return min(100.0 * abs(h), hinit_refine(der2, dnf, h), hmax)

    return jit(initial_step)


_initial_step = _initial_step_of(False)
_initial_step_wide = _initial_step_of(True)
_initial_step_coupled = _initial_step_of(False, True)


#: the Runge-Kutta pairs the step loop runs: ``(N_STAGES, A_PTR, A_COL, A_VAL, C, B, E_HI,
#: E_LO)``; DOP853's error norm takes both estimates, Verner's 9(8) pair one (``E_LO`` unused)
TABLEAUS = {"dop853": (_dp.N_STAGES, _dp.A_PTR, _dp.A_COL, _dp.A_VAL, _dp.C, _dp.B, _dp.E5, _dp.E3),
            "verner98": (_vn.N_STAGES, _vn.A_PTR, _vn.A_COL, _vn.A_VAL, _vn.C, _vn.B, _vn.E, _vn.E)}


def _advance_of(width, extended, tableau="dop853", coupled=False):
    """The one-trajectory step loop for states of ``width`` components (0: any width,
    ``len(y)``), on the rigid body's right-hand side (inlined at the stages) or (``extended``)
    on :func:`orbatt.core.gyrostat.rhs_extended`, with the Runge-Kutta pair ``tableau`` (a key
    of :data:`TABLEAUS`: ``"dop853"``, or ``"verner98"``: Verner's 9(8) pair with the error
    ``err = |h| rms((E . K) / sk)`` and the controller's exponent 1/9, :func:`controller9`).
    ``width``, ``extended`` and the tableau are constants of
    the closure: numba prunes the branch not taken, so the rigid body's loop does not compile
    the extended right-hand side, and they keep the on-disk cache key the same from one process
    to the next (a closure over a dispatcher object would not: it pickles differently in every
    process). The rigid body's loop keeps the constant 8, which LLVM unrolls, so it runs as
    fast as before wider states existed (measured on the Keplerian case: 1.29 ms both). ``coupled``:
    :func:`orbatt.core.mutual.rhs_coupled`, ``inertia`` its constants ``c`` (``atol * c[C_ATOL + i]``)."""
    N_STAGES, A_PTR, A_COL, A_VAL, C, B, E5, E3 = TABLEAUS[tableau]
    verner = tableau == "verner98"

    def advance(y, st, cnt, f0, t_out, rec_t, out_y, record_all, inertia, terms, params, table,
                work, rtol, atol, max_step, max_steps, budget):
        """Advance one trajectory of states of ``ncomp`` components towards the output times
        ``t_out[cnt[CNT_IOUT]:]``.

        Parameters
        ----------
        y : (ncomp,) state ``(q, Q)`` (ncomp = 8), or ``(q, Q, h)`` with the reaction wheels' axial
            momenta ``h`` (ncomp = 8 + wheels; :mod:`orbatt.core.gyrostat`), at ``st[ST_T]``;
            updated in place.
        st, cnt, f0 : per-trajectory integrator state (:func:`new_state`); updated in place.
        t_out : (N,) increasing output times, all after ``st[ST_T]``.
        rec_t, out_y : outputs. Default mode: ``out_y[i]`` (N, ncomp) receives ``y(t_out[i])``
            (``rec_t`` unused). ``record_all``: every accepted step appends its time to
            ``rec_t`` and its state to ``out_y`` (capacity ``len(rec_t)``; returns
            :data:`BUFFER_FULL` when full); integration stops at ``t_out[-1]``.
        inertia : (3,) principal moments.
        terms, params, table, work : the model (:mod:`orbatt.core.model`) and its scratch.
        rtol, atol, max_step : tolerances (scipy's meaning) and the largest step allowed.
        max_steps : limit on step attempts (accepted + rejected) over the whole run.
        budget : step attempts allowed in this call.

        Returns a status code (:data:`DONE`, :data:`PAUSED`, ...).
        """
        ncomp = width if width > 0 else y.shape[0]
        nout = t_out.shape[0]
        Kown = np.empty((N_STAGES + 1, ncomp))
        tmpown = np.empty((2, ncomp))
        K = borrow(Kown)
        ytmp = borrow(tmpown[0])
        ynew = borrow(tmpown[1])
        y = borrow(y)
        f0 = borrow(f0)
        inertia = borrow(inertia)
        terms = borrow(terms)
        params = borrow(params)
        table = borrow(table)
        work = borrow(work)
        t = st[ST_T]
        h = st[ST_H]
        facold = st[ST_FACOLD]
        if facold <= 0.0:
            facold = 1.0e-4
        i_out = cnt[CNT_IOUT]
        flags = cnt[CNT_FLAGS]
        status = DONE
        if i_out >= nout:
            return DONE
        if (flags & FLAG_F0_VALID) == 0:
            if coupled:
                rhs_coupled(t, y, inertia, terms, params, table, work, f0)
            elif extended:
                rhs_extended(t, y, inertia, terms, params, table, work, f0)
            else:
                rhs(t, y, inertia, terms, params, table, work, f0)
            cnt[CNT_NFEV] += 1
            flags |= FLAG_F0_VALID
        for i in range(ncomp):
            K[0, i] = f0[i]
        if h <= 0.0:
            if coupled:
                h = _initial_step_coupled(t, y, f0, K[1], ytmp, inertia, terms, params, table, work, rtol, atol,
                                          min(max_step, t_out[nout - 1] - t))
            elif extended:
                h = _initial_step_wide(t, y, f0, K[1], ytmp, inertia, terms, params, table, work, rtol, atol,
                                      min(max_step, t_out[nout - 1] - t))
            else:
                h = _initial_step(t, y, f0, K[1], ytmp, inertia, terms, params, table, work, rtol, atol,
                                  min(max_step, t_out[nout - 1] - t))
            cnt[CNT_NFEV] += 1
            if not (h > 0.0 and h < np.inf):
                h = 1e-6 * max(1.0, abs(t_out[nout - 1] - t))
        reject = (flags & FLAG_REJECTED) != 0
        attempts = 0
        # step-size floor: 10 ulps of the largest time involved (Hairer's test uses |t| only,
        # which lets a run starting at t = 0 crawl with steps of 1e-300)
        hmin = max(st[ST_HMIN], 10.0 * EPS * max(abs(t), abs(t_out[nout - 1])))
        aQ = atol * momentum_scale(inertia)
        cap = rec_t.shape[0]
        t_brk = next_breakpoint(t, terms, params, table)
        while i_out < nout:
            if record_all and cnt[CNT_NREC] >= cap:
                status = BUFFER_FULL
                break
            status, hh, landing, t_next = begin_attempt(attempts, budget, cnt, max_steps, t, h, max_step, t_out, i_out,
                                                        hmin, flags, t_brk)
            if status != DONE:
                break
            # --- the 12 stages
            for s in range(1, N_STAGES):
                for i in range(ncomp):
                    ytmp[i] = 0.0
                for jj in range(A_PTR[s], A_PTR[s + 1]):
                    a = A_VAL[jj]
                    j = A_COL[jj]
                    for i in range(ncomp):
                        ytmp[i] += a * K[j, i]
                for i in range(ncomp):
                    ytmp[i] = y[i] + hh * ytmp[i]
                if coupled:
                    rhs_coupled(t + C[s] * hh, ytmp, inertia, terms, params, table, work, K[s])
                elif extended:
                    rhs_extended(t + C[s] * hh, ytmp, inertia, terms, params, table, work, K[s])
                else:
                    rhs_inline(t + C[s] * hh, ytmp, inertia, terms, params, table, work, K[s])
            cnt[CNT_NFEV] += N_STAGES - 1
            # --- 8th-order solution and error estimate
            e5 = 0.0
            e3 = 0.0
            for i in range(ncomp):
                acc = 0.0
                a5 = 0.0
                a3 = 0.0
                for j in range(N_STAGES):
                    kji = K[j, i]
                    acc += B[j] * kji
                    a5 += E5[j] * kji
                    if not verner:
                        a3 += E3[j] * kji
                ynew[i] = y[i] + hh * acc
                ai = atol * inertia[C_ATOL + i] if coupled else (atol if i < 4 else aQ)
                isk = 1.0 / (ai + rtol * max(abs(y[i]), abs(ynew[i])))
                a5 *= isk
                e5 += a5 * a5
                if not verner:
                    a3 *= isk
                    e3 += a3 * a3
            if verner:
                err = abs(hh) * math.sqrt(e5 / ncomp)
            else:
                err = error_norm(e5, e3, hh, ncomp)
            attempts += 1
            if not (err < np.inf):  # NaN or inf: shrink hard and retry
                flags, h, reject = reject_nonfinite(cnt, flags, hh)
                continue
            if verner:
                fac11, hnew = controller9(err, facold, hh)
            else:
                fac11, hnew = controller(err, facold, hh)
            if err <= 1.0:
                # accepted: FSAL derivative at the new point
                t_new = t_next if landing else t + hh
                if coupled:
                    rhs_coupled(t_new, ynew, inertia, terms, params, table, work, K[N_STAGES])
                elif extended:
                    rhs_extended(t_new, ynew, inertia, terms, params, table, work, K[N_STAGES])
                else:
                    rhs(t_new, ynew, inertia, terms, params, table, work, K[N_STAGES])
                cnt[CNT_NFEV] += 1
                if not all_finite(K[N_STAGES], ncomp):
                    flags, h, reject = reject_nonfinite(cnt, flags, hh)
                    continue
                flags, facold, hnew, reject = accept_step(cnt, flags, err, hnew, hh, h, max_step, reject, landing)
                for i in range(ncomp):
                    y[i] = ynew[i]
                    K[0, i] = K[N_STAGES, i]
                t = t_new
                if landing and t == t_out[i_out]:  # (else a breakpoint)
                    if not record_all:
                        for i in range(ncomp):
                            out_y[i_out, i] = y[i]
                    i_out += 1
                if t >= t_brk:
                    t_brk = next_breakpoint(t, terms, params, table)
                if record_all:
                    nrec = cnt[CNT_NREC]
                    rec_t[nrec] = t
                    for i in range(ncomp):
                        out_y[nrec, i] = y[i]
                    cnt[CNT_NREC] = nrec + 1
                h = hnew
            else:
                flags, h, reject = reject_step(cnt, flags, hh, fac11)
        st[ST_T] = t
        st[ST_H] = h
        st[ST_FACOLD] = facold
        for i in range(ncomp):
            f0[i] = K[0, i]
        flags = (flags & ~FLAG_REJECTED) | (FLAG_REJECTED if reject else 0)
        cnt[CNT_FLAGS] = flags
        cnt[CNT_IOUT] = i_out
        keepalive(Kown)
        keepalive(tmpown)
        return status

    return jit(advance)


#: the step loop of the rigid body, ``y = (q, Q)``
advance = _advance_of(NDIM, False)
#: the step loop of extended models (reaction wheels, control laws: :mod:`orbatt.core.gyrostat`),
#: states of any width (the gyrostat's ``(q, Q, h)``: one axial momentum per wheel); compiled on
#: first use only, so that the rigid body's loop does not carry the extended right-hand side
advance_wide = _advance_of(0, True)
#: the rigid body's step loop with Verner's 9(8) pair (:mod:`orbatt.core.verner98_coefficients`)
advance_verner98 = _advance_of(NDIM, False, "verner98")
#: :data:`advance_wide` with Verner's 9(8) pair (compiled on first use only)
advance_wide_verner98 = _advance_of(0, True, "verner98")
#: the loops of a binary's coupled orbit and attitudes (:mod:`orbatt.core.mutual`), DOP853, Verner 9(8)
advance_coupled = _advance_of(0, False, coupled=True)
advance_coupled_verner98 = _advance_of(0, False, "verner98", coupled=True)


def _batch_of(extended, tableau="dop853"):
    """The ensemble driver over members of :func:`advance` or (``extended``) :func:`advance_wide`,
    or with ``tableau="verner98"`` of :func:`advance_verner98` or :func:`advance_wide_verner98`
    (constants of the closure, as in :func:`_advance_of`)."""
    verner = tableau == "verner98"

    def advance_batch(Y, ST, CNT, F0, t_out, out_y, status, inertia, terms, params, table, WORK,
                      rtol, atol, max_step, max_steps, budget):
        """:func:`advance` (or :func:`advance_wide` for :data:`advance_batch_wide`) for an
        ensemble, in parallel over members (numba ``prange``).

        ``Y (E, n)``, ``ST (E, ST_SIZE)``, ``CNT (E, CNT_SIZE)``, ``F0 (E, n)``, ``WORK (E, w)``
        and ``inertia (E, 3)`` are per member; ``out_y (E, N, n)``; ``status (E,)`` receives
        each member's status (members already :data:`DONE` are skipped). Every member runs
        exactly the code of the one-trajectory loop, so its result is identical to a
        one-by-one propagation.
        """
        E = Y.shape[0]
        rec_t = np.empty(0)
        for e in nb.prange(E):
            if CNT[e, CNT_IOUT] >= t_out.shape[0]:
                status[e] = DONE
                continue
            if verner and extended:
                status[e] = advance_wide_verner98(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], False,
                                                  inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                                  max_steps, budget)
            elif verner:
                status[e] = advance_verner98(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], False, inertia[e],
                                             terms, params, table, WORK[e], rtol, atol, max_step, max_steps, budget)
            elif extended:
                status[e] = advance_wide(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], False, inertia[e],
                                         terms, params, table, WORK[e], rtol, atol, max_step, max_steps, budget)
            else:
                status[e] = advance(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], False, inertia[e],
                                    terms, params, table, WORK[e], rtol, atol, max_step, max_steps, budget)

    return jit_parallel(advance_batch)


advance_batch = _batch_of(False)
advance_batch_wide = _batch_of(True)
#: :data:`advance_batch` and :data:`advance_batch_wide` with Verner's 9(8) pair
advance_batch_verner98 = _batch_of(False, "verner98")
advance_batch_wide_verner98 = _batch_of(True, "verner98")

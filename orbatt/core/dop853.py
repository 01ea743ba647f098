"""Compiled adaptive Runge-Kutta DOP853 on Hamilton's equations (eq. 7), whole step loop in
numba; one trajectory (:func:`advance`), an ensemble of independent members in parallel
(:func:`advance_batch`, each member bitwise as alone), or an ensemble in lockstep groups
(:func:`advance_lanes`, vectorized over the members of a group, see below). All of them are
instances of the one step loop of :mod:`orbatt.core.rk_loop` (building blocks:
:mod:`orbatt.core.step_control`), for each pair (DOP853, Verner 9(8)), for the rigid body and
extended models.

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
output times and Hairer's initial step are the inline helpers of
:mod:`orbatt.core.step_control`.

Verner's 9(8) pair (:data:`advance_verner98`, :data:`advance_batch_verner98` and their
``_wide`` forms for extended models; coefficients: :mod:`orbatt.core.verner98_coefficients`)
runs in the same loop: 16 stages, no
FSAL (the first stage of the next step is evaluated on acceptance, as DOP853's FSAL stage),
error ``err = |h| sqrt(e / n)``, ``e = sum(((E . K)_i / sk_i)^2)`` with ``E = b - bhat``, and
the same controller with ``err^(1/9)`` (:func:`controller9`). On the Keplerian benchmark it needs
~17 % fewer right-hand-side evaluations than DOP853 at 1e-9 rad, ~9 % fewer at 1e-6 rad, and
~10 % more on the torque-free body (``benchmarks/verner98.py``). A binary's coupled orbit and
attitudes (:mod:`orbatt.core.mutual`) run in the same loop (:data:`advance_coupled`, ``_verner98``).

Dormand-Prince 5(4) (:data:`advance_dopri5`, :data:`advance_wide_dopri5`, their batch, group
and lanes forms; coefficients: :mod:`orbatt.core.dopri5_coefficients`) runs in the same loop: 7
stages, the seventh ``f(t + h, y_new)`` (FSAL inside the tableau: 6 evaluations per attempt),
the error of Verner's form with ``E = b - bhat`` of order 4 and the controller with ``err^(1/5)``
(Hairer's ``dopri5.f``). For the flight software's ticks (``benchmarks/tick_stepping.py``).
Bogacki-Shampine 3(2) (:data:`advance_bs32` and the same forms; coefficients:
:mod:`orbatt.core.bs32_coefficients`) likewise: 4 stages, the fourth ``f(t + h, y_new)`` (3
evaluations per attempt), the controller with ``err^(1/3)``; for ticks so dense that one step of
order 3 per tick meets the tolerance (``benchmarks/basilisk_fsw.py``).

Breakpoints: steps also land on the knots of the model's tables, a sampled orbit's samples and
the environment tables (:func:`orbatt.core.model.next_breakpoint`), where the right-hand
side's third derivative jumps; nothing is recorded there.

Output: the integrator lands exactly on every requested output time (the step before it is
shortened, the step size proposed before shortening is kept for the step after), so outputs
carry the full accuracy of step-end values - no interpolation (``docs/design.md`` §4).
Alternatively every accepted step is recorded (``record_all``).

Lockstep lanes (:data:`advance_lanes`, :data:`advance_lanes_verner98` and their ``_wide`` forms
for extended models): the members of a group share the time grid, so the orbit is evaluated
once per stage for the whole group, and the per-member arithmetic (eq. 7, the terms, the
gyrostat) runs in loops over the lanes that LLVM vectorizes (structure-of-arrays layout
``(component, lane)``). The error of a step is the largest of the members' norms, so every
member meets the tolerance it would meet alone; results agree with one-by-one runs to that
tolerance, not bitwise (the step sizes differ). Measured RHS cost per member on the Keplerian
case: 150 ns alone, 11 ns in a group of 16.

Resumable: the whole integrator state lives in small per-trajectory arrays (``y``, ``st``,
``cnt``, ``f0`` and the model's ``work``), and :func:`advance` returns after ``budget``
step attempts; calling it again continues exactly as if it had not stopped (the Python
driver uses this for progress reports and for a clean stop on KeyboardInterrupt).

The right-hand side is :func:`orbatt.core.hamiltonian.rhs` on a model ``terms, params,
table`` (:mod:`orbatt.core.model`); numerics notes in :mod:`orbatt.core._jit`.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ._jit import (BAD_LANE_SHIFT, BUFFER_FULL, DONE, EPS, FLAG_BITS, FLAG_F0_VALID, FLAG_NONFINITE,
                   FLAG_REJECTED, MAX_STEPS, NDIM, NONFINITE, PAUSED, STEP_TOO_SMALL, jit_parallel)
from .rk_loop import loop_of
from .step_control import (BETA, CNT_FLAGS, CNT_IOUT, CNT_NFEV, CNT_NREC, CNT_REJECTED, CNT_SIZE, CNT_STEPS,
                           CNT_SWITCHES, FAC_MAX, FAC_MIN, LAND_MARGIN, SAFETY, ST_FACOLD, ST_H, ST_HMIN, ST_SIZE,
                           ST_SWITCH_K, ST_SWITCH_T, ST_T, TABLEAUS, begin_attempt, momentum_scale, new_state)

#: the kernels, the state layout, and (re-exported for the Python drivers) the status codes and
#: flag names of :mod:`orbatt.core._jit`
__all__ = ["advance", "advance_wide", "advance_batch", "advance_batch_wide", "advance_verner98",
           "advance_wide_verner98", "advance_batch_verner98", "advance_batch_wide_verner98", "advance_coupled",
           "advance_coupled_verner98", "advance_group", "advance_group_wide", "advance_group_verner98",
           "advance_group_wide_verner98", "advance_lanes", "advance_lanes_wide", "advance_lanes_verner98",
           "advance_lanes_wide_verner98", "advance_dopri5", "advance_wide_dopri5", "advance_batch_dopri5",
           "advance_batch_wide_dopri5", "advance_group_dopri5", "advance_group_wide_dopri5", "advance_lanes_dopri5",
           "advance_lanes_wide_dopri5", "advance_bs32", "advance_wide_bs32", "advance_batch_bs32",
           "advance_batch_wide_bs32", "advance_group_bs32", "advance_group_wide_bs32", "advance_lanes_bs32",
           "advance_lanes_wide_bs32", "TABLEAUS", "new_state", "momentum_scale", "begin_attempt", "NDIM", "DONE",
           "PAUSED", "BUFFER_FULL", "NONFINITE", "STEP_TOO_SMALL", "MAX_STEPS", "FLAG_F0_VALID", "FLAG_REJECTED",
           "FLAG_NONFINITE", "FLAG_BITS", "BAD_LANE_SHIFT", "ST_T", "ST_H", "ST_FACOLD", "ST_HMIN", "ST_SWITCH_T",
           "ST_SWITCH_K", "ST_SIZE", "EPS", "CNT_STEPS", "CNT_REJECTED", "CNT_NFEV", "CNT_IOUT", "CNT_NREC", "CNT_FLAGS",
           "CNT_SWITCHES", "CNT_SIZE", "SAFETY",
           "FAC_MIN", "FAC_MAX", "BETA", "LAND_MARGIN"]

# ---------------------------------------------------------------------------------------
# One trajectory (rk_loop.loop_of with one lane)

#: the step loop of the rigid body, ``y = (q, Q)``
advance = loop_of(NDIM, False)
#: the step loop of extended models (reaction wheels, control laws: :mod:`orbatt.core.gyrostat`),
#: states of any width (the gyrostat's ``(q, Q, h)``: one axial momentum per wheel); compiled on
#: first use only, so that the rigid body's loop does not carry the extended right-hand side
advance_wide = loop_of(0, True)
#: the rigid body's step loop with Verner's 9(8) pair (:mod:`orbatt.core.verner98_coefficients`)
advance_verner98 = loop_of(NDIM, False, "verner98")
#: :data:`advance_wide` with Verner's 9(8) pair (compiled on first use only)
advance_wide_verner98 = loop_of(0, True, "verner98")
#: the loops of a binary's coupled orbit and attitudes (:mod:`orbatt.core.mutual`), DOP853, Verner 9(8)
#: the rigid body's and extended models' step loops with Dormand-Prince 5(4)
#: (:mod:`orbatt.core.dopri5_coefficients`; compiled on first use only)
advance_dopri5 = loop_of(NDIM, False, "dopri5")
advance_wide_dopri5 = loop_of(0, True, "dopri5")
#: the rigid body's and extended models' step loops with Bogacki-Shampine 3(2)
#: (:mod:`orbatt.core.bs32_coefficients`; compiled on first use only)
advance_bs32 = loop_of(NDIM, False, "bs32")
advance_wide_bs32 = loop_of(0, True, "bs32")
advance_coupled = loop_of(0, False, coupled=True)
advance_coupled_verner98 = loop_of(0, False, "verner98", coupled=True)

# ---------------------------------------------------------------------------------------
# A group of members in lockstep (rk_loop.loop_of with lanes): ``y (nl, n)``, ``f0 (nl, n)``,
# ``inertia (nl, 3)``, ``out_y (nl, N, n)``; ``st``, ``cnt``, ``work`` the group's

#: the rigid body's loop over a lockstep group, DOP853
advance_group = loop_of(NDIM, False, lanes=True)
#: extended models (wheels, control laws) in a lockstep group, DOP853
advance_group_wide = loop_of(0, True, lanes=True)
#: :data:`advance_group` and :data:`advance_group_wide` with Verner's 9(8) pair
advance_group_verner98 = loop_of(NDIM, False, "verner98", lanes=True)
advance_group_wide_verner98 = loop_of(0, True, "verner98", lanes=True)
#: :data:`advance_group` and :data:`advance_group_wide` with Dormand-Prince 5(4)
advance_group_dopri5 = loop_of(NDIM, False, "dopri5", lanes=True)
advance_group_wide_dopri5 = loop_of(0, True, "dopri5", lanes=True)
#: :data:`advance_group` and :data:`advance_group_wide` with Bogacki-Shampine 3(2)
advance_group_bs32 = loop_of(NDIM, False, "bs32", lanes=True)
advance_group_wide_bs32 = loop_of(0, True, "bs32", lanes=True)


def _batch_of(extended, tableau="dop853"):
    """The ensemble driver over members of :func:`advance` or (``extended``) :func:`advance_wide`,
    or with ``tableau="verner98"`` of :func:`advance_verner98` or :func:`advance_wide_verner98`,
    ``"dopri5"`` of :data:`advance_dopri5` or :data:`advance_wide_dopri5`, ``"bs32"`` of
    :data:`advance_bs32` or :data:`advance_wide_bs32` (constants of the closure, as in
    :func:`orbatt.core.rk_loop.loop_of`)."""
    verner = tableau == "verner98"
    dopri5 = tableau == "dopri5"
    bs32 = tableau == "bs32"

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
        # False, typed bool (not the literal False): the loops keep the one signature the
        # Python drivers compile them for (a literal compiled each loop a second time)
        record_all = rec_t.shape[0] > 0
        for e in nb.prange(E):
            if CNT[e, CNT_IOUT] >= t_out.shape[0]:
                status[e] = DONE
                continue
            if verner:
                if extended:
                    status[e] = advance_wide_verner98(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all,
                                                      inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                                      max_steps, budget)
                else:
                    status[e] = advance_verner98(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all,
                                                 inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                                 max_steps, budget)
            elif dopri5:
                if extended:
                    status[e] = advance_wide_dopri5(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all,
                                                    inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                                    max_steps, budget)
                else:
                    status[e] = advance_dopri5(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all,
                                               inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                               max_steps, budget)
            elif bs32:
                if extended:
                    status[e] = advance_wide_bs32(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all,
                                                  inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                                  max_steps, budget)
                else:
                    status[e] = advance_bs32(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all,
                                             inertia[e], terms, params, table, WORK[e], rtol, atol, max_step,
                                             max_steps, budget)
            elif extended:
                status[e] = advance_wide(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all, inertia[e],
                                         terms, params, table, WORK[e], rtol, atol, max_step, max_steps, budget)
            else:
                status[e] = advance(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], record_all, inertia[e],
                                    terms, params, table, WORK[e], rtol, atol, max_step, max_steps, budget)

    return jit_parallel(advance_batch)


advance_batch = _batch_of(False)
advance_batch_wide = _batch_of(True)
#: :data:`advance_batch` and :data:`advance_batch_wide` with Verner's 9(8) pair
advance_batch_verner98 = _batch_of(False, "verner98")
advance_batch_wide_verner98 = _batch_of(True, "verner98")
#: :data:`advance_batch` and :data:`advance_batch_wide` with Dormand-Prince 5(4)
advance_batch_dopri5 = _batch_of(False, "dopri5")
advance_batch_wide_dopri5 = _batch_of(True, "dopri5")
#: :data:`advance_batch` and :data:`advance_batch_wide` with Bogacki-Shampine 3(2)
advance_batch_bs32 = _batch_of(False, "bs32")
advance_batch_wide_bs32 = _batch_of(True, "bs32")


def _lanes_of(extended, tableau="dop853"):
    """The ensemble driver over lockstep groups of :data:`advance_group` (``extended``:
    :data:`advance_group_wide`; ``tableau="verner98"``, ``"dopri5"``, ``"bs32"``: their Verner,
    Dormand-Prince 5(4), Bogacki-Shampine 3(2) forms)."""
    verner = tableau == "verner98"
    dopri5 = tableau == "dopri5"
    bs32 = tableau == "bs32"

    def advance_lanes(Y, ST, CNT, F0, t_out, out_y, status, inertia, terms, params, table, WORK, lanes, rtol, atol,
                      max_step, max_steps, budget):
        """The group loop over the groups ``[g lanes, (g + 1) lanes)`` of an ensemble, in
        parallel over groups. ``ST, CNT, WORK, status`` have one row per group."""
        E = Y.shape[0]
        rec_t = np.empty(0)
        record_all = rec_t.shape[0] > 0  # False, typed bool (see advance_batch)
        for gi in nb.prange((E + lanes - 1) // lanes):  # (a group that is done returns DONE at once)
            a = gi * lanes
            b = min(E, a + lanes)
            if verner:
                if extended:
                    status[gi] = advance_group_wide_verner98(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b],
                                                             record_all, inertia[a:b], terms, params, table, WORK[gi],
                                                             rtol, atol, max_step, max_steps, budget)
                else:
                    status[gi] = advance_group_verner98(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b],
                                                        record_all, inertia[a:b], terms, params, table, WORK[gi], rtol,
                                                        atol, max_step, max_steps, budget)
            elif dopri5:
                if extended:
                    status[gi] = advance_group_wide_dopri5(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b],
                                                           record_all, inertia[a:b], terms, params, table, WORK[gi],
                                                           rtol, atol, max_step, max_steps, budget)
                else:
                    status[gi] = advance_group_dopri5(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b],
                                                      record_all, inertia[a:b], terms, params, table, WORK[gi], rtol,
                                                      atol, max_step, max_steps, budget)
            elif bs32:
                if extended:
                    status[gi] = advance_group_wide_bs32(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b],
                                                         record_all, inertia[a:b], terms, params, table, WORK[gi],
                                                         rtol, atol, max_step, max_steps, budget)
                else:
                    status[gi] = advance_group_bs32(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b],
                                                    record_all, inertia[a:b], terms, params, table, WORK[gi], rtol,
                                                    atol, max_step, max_steps, budget)
            elif extended:
                status[gi] = advance_group_wide(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b], record_all,
                                                inertia[a:b], terms, params, table, WORK[gi], rtol, atol, max_step,
                                                max_steps, budget)
            else:
                status[gi] = advance_group(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, rec_t, out_y[a:b], record_all,
                                           inertia[a:b], terms, params, table, WORK[gi], rtol, atol, max_step,
                                           max_steps, budget)

    return jit_parallel(advance_lanes)


#: DOP853 over an ensemble in lockstep groups: the rigid body, extended models
advance_lanes = _lanes_of(False)
advance_lanes_wide = _lanes_of(True)
#: :data:`advance_lanes` and :data:`advance_lanes_wide` with Verner's 9(8) pair
advance_lanes_verner98 = _lanes_of(False, "verner98")
advance_lanes_wide_verner98 = _lanes_of(True, "verner98")
#: :data:`advance_lanes` and :data:`advance_lanes_wide` with Dormand-Prince 5(4)
advance_lanes_dopri5 = _lanes_of(False, "dopri5")
advance_lanes_wide_dopri5 = _lanes_of(True, "dopri5")
#: :data:`advance_lanes` and :data:`advance_lanes_wide` with Bogacki-Shampine 3(2)
advance_lanes_bs32 = _lanes_of(False, "bs32")
advance_lanes_wide_bs32 = _lanes_of(True, "bs32")

"""The one adaptive Runge-Kutta step loop, written once and instantiated (:func:`loop_of`) for one
trajectory and for a group of ensemble members in lockstep ("lanes"), for each Runge-Kutta pair
of :data:`orbatt.core.step_control.TABLEAUS` (DOP853, Verner 9(8), Dormand-Prince 5(4)), for the
rigid body and for extended models (reaction wheels, control laws: :mod:`orbatt.core.gyrostat`),
and for a binary's coupled orbit and attitudes (:mod:`orbatt.core.mutual`, one trajectory).

The loop keeps its working copies in structure-of-arrays layout, lane index last: the state
``yg (n, nl)``, the stages ``K (stages + 1, n, nl)``. One trajectory is the group of one lane
(``nl = 1``, a constant of its closure, so the lane loops fold away and the single loop runs
the operations it always ran, bit for bit; its working arrays are the contiguous vectors its
right-hand side takes, which the loop indexes through ``(n, 1)`` views); a group of ``nl`` members shares the time, the step
size and the orbit's evaluation at each stage, and its per-member loops over the lanes
vectorize. Everything else - the stages, the error estimate, the controller, the landing on
output times and breakpoints, acceptance and rejection, the outputs (at the output times, or
every accepted step: ``record_all``) and the resumable state - is the same code for both. A
group's error is the largest of its members' norms, so every member meets the tolerance it
would meet alone; its counters count group steps and group right-hand-side evaluations.

What differs between the instantiations is a constant of the closure (numba prunes the
branches not taken, so a loop compiles only its own right-hand side): where the members come
from and go to (``y (n,)`` or ``Y (nl, n)``), and which right-hand side a stage calls:

=============  ============================================  ==============================================
instantiation  one trajectory                                lanes
=============  ============================================  ==============================================
rigid body     :func:`~orbatt.core.hamiltonian.rhs` (stages  :func:`~orbatt.core.hamiltonian.rhs_lanes`
               inline: ``rhs_inline``)
extended       :func:`~orbatt.core.gyrostat.rhs_extended`    :func:`~orbatt.core.held_commands.rhs_extended_lanes`
coupled        :func:`~orbatt.core.mutual.rhs_coupled`       (not instantiated)
=============  ============================================  ==============================================

The method and its controller are described in :mod:`orbatt.core.dop853`, which holds the
instances; the building blocks are in :mod:`orbatt.core.step_control`.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import (BAD_LANE_SHIFT, BUFFER_FULL, DONE, EPS, FLAG_BITS, FLAG_F0_VALID, FLAG_REJECTED, INTERPRETED,
                   borrow, borrow_model, jit, jit_inline, keepalive)
from .gyrostat import extended_rates, has_ticks, next_tick_grid, rhs_extended, tick
from .held_commands import LANE_SCRATCH, rhs_extended_lanes, wheel_tick, wheel_ticks_only
from .mode_events import advance as advance_modes, next_event, sequence_count
from .hamiltonian import rhs, rhs_inline, rhs_lanes
from .model import next_breakpoint
from .mutual import C_ATOL, hinit_der2_vec, hinit_norms_vec, rhs_coupled
from .potentials import MAX_SWITCHES, SWITCH_SLOT
from .step_control import (CNT_FLAGS, CNT_IOUT, CNT_NFEV, CNT_NREC, CNT_SWITCHES, ST_FACOLD, ST_H, ST_HMIN,
                           ST_SWITCH_K, ST_SWITCH_T, ST_T, PAIRS, TABLEAUS, accept_step, all_finite, begin_attempt,
                           controller, controller9, controller_pow, error_norm, hinit_der2, hinit_guess, hinit_norms,
                           hinit_refine, hinit_refine_order, momentum_scale, reject_nonfinite, reject_step,
                           stage_orbits)
from .switches import AT_START, REARM, crossed, locate, loop_switch_values, loop_switches, update

__all__ = ["loop_of", "stage_input", "ROOT_TOL", "MAX_REFINE"]

#: a mode sequence's crossing is landed on where its function, on the integrated state, is
#: within this of zero (its functions are relative: ``|omega| / until_rate - 1``)
ROOT_TOL = 1.0e-12
#: at most this many retakes refine one crossing (then the interpolant's root stands)
MAX_REFINE = 8


@jit_inline
def stage_input(ytmp, yg, K, s, hh, A_PTR, A_COL, A_VAL, ncomp, nl):
    """``ytmp = yg + hh sum_j a_sj K[j]``: the input of stage ``s`` (sparse tableau ``A_PTR,
    A_COL, A_VAL``) for the lanes ``(n, nl)``, lanes innermost (vectorized)."""
    for i in range(ncomp):
        for l in range(nl):
            ytmp[i, l] = 0.0
    for jj in range(A_PTR[s], A_PTR[s + 1]):
        a = A_VAL[jj]
        j = A_COL[jj]
        for i in range(ncomp):
            for l in range(nl):
                ytmp[i, l] += a * K[j, i, l]
    for i in range(ncomp):
        for l in range(nl):
            ytmp[i, l] = yg[i, l] + hh * ytmp[i, l]


if INTERPRETED:
    def stage_input(ytmp, yg, K, s, hh, A_PTR, A_COL, A_VAL, ncomp, nl):  # noqa: F811
        """:func:`stage_input` for the interpreted kernels (the cold start, :mod:`orbatt.coldstart`):
        the same elementwise IEEE operations in the same order for every component, so the same
        bits, as numpy array operations instead of Python's loops over components and lanes
        (those made the interpreted single loop, a group of one lane, ~30 % slower per step)."""
        y = ytmp[:ncomp, :nl]
        y[...] = 0.0
        for jj in range(A_PTR[s], A_PTR[s + 1]):
            y += A_VAL[jj] * K[A_COL[jj], :ncomp, :nl]
        y[...] = yg[:ncomp, :nl] + hh * y


def loop_of(width, extended, tableau="dop853", coupled=False, lanes=False):
    """The adaptive step loop for states of ``width`` components (0: any width, from the
    arrays), on the rigid body's right-hand side or (``extended``) the gyrostat's, or
    (``coupled``, one trajectory only) a binary's, with the Runge-Kutta pair ``tableau`` (a key
    of :data:`~orbatt.core.step_control.TABLEAUS`: ``"dop853"``, Hairer's error norm and the
    controller's exponent 1/8, ``"verner98"``: ``err = |h| rms((E . K) / sk)`` and 1/9, or
    ``"dopri5"``: the same norm and 1/5, its seventh stage ``f(t + h, y_new)`` taken as the next
    step's first: :data:`~orbatt.core.step_control.PAIRS`), for one trajectory or (``lanes``) a
    lockstep group.

    A step that lands on a flight-software tick (extended models) and locates no switch skips
    the derivative at its end under the old command (``"dop853"``, ``"verner98"``): the tick
    changes the command held in the state, and the loop evaluates the derivative once, after
    it (``"dopri5"``, ``"bs32"``: their last stage, rewritten: :mod:`orbatt.core.held_commands`).

    All five are constants of the closure: numba prunes the branches not taken, so the rigid
    body's loop does not compile the extended right-hand side, and they keep the on-disk cache
    key the same from one process to the next (a closure over a dispatcher object would not: it
    pickles differently in every process). The rigid body's loops keep the constant width 8,
    which LLVM unrolls. ``coupled``: :func:`orbatt.core.mutual.rhs_coupled`, ``inertia`` its
    constants ``c`` (absolute tolerances ``atol * c[C_ATOL + i]``)."""
    N_STAGES, A_PTR, A_COL, A_VAL, C, B, E5, E3 = TABLEAUS[tableau]
    CTRL_K, HINIT_ORDER, LAST_NEW = PAIRS[tableau]
    #: one error estimate, ``err = |h| rms((E . K) / sk)`` (Verner's 9(8), Dormand-Prince 5(4))
    VERNER = tableau != "dop853"
    CTRL9 = tableau == "verner98"
    CTRL_EXPO = 1.0 / CTRL_K
    WIDTH = width
    EXTENDED = extended
    COUPLED = coupled
    LANES = lanes
    #: one trajectory of the rigid body or an extended model locates the switching functions
    #: (orbatt.core.switches); lanes and the coupled form do not
    SWITCHES = not lanes and not coupled
    if coupled and lanes:
        raise ValueError("loop_of: the coupled form runs one trajectory (lanes=False)")

    def advance(y, st, cnt, f0, t_out, rec_t, out_y, record_all, inertia, terms, params, table, work, rtol, atol,
                max_step, max_steps, budget):
        """Advance one trajectory, or a group of members in lockstep, towards the output times
        ``t_out[cnt[CNT_IOUT]:]``.

        Parameters
        ----------
        y : state(s), updated in place: one trajectory ``(n,)``, ``(q, Q)`` (n = 8) or
            ``(q, Q, h)`` with the reaction wheels' axial momenta ``h`` (n = 8 + wheels;
            :mod:`orbatt.core.gyrostat`), at ``st[ST_T]``; lanes ``(nl, n)``, one row a member.
        st, cnt : integrator state (:func:`orbatt.core.step_control.new_state`) of the
            trajectory or of the group (one time, one step size); updated in place. A group's
            counters count group steps and group evaluations; on a failure
            ``(cnt[CNT_FLAGS] >> BAD_LANE_SHIFT) - 1`` is the first failing lane.
        f0 : the derivative at ``y`` (FSAL), shaped as ``y``; updated in place.
        t_out : (N,) increasing output times, all after ``st[ST_T]``.
        rec_t, out_y : outputs. Default mode: ``out_y[i]`` (N, n) receives ``y(t_out[i])``
            (lanes: ``out_y[l, i]``, ``(nl, N, n)``; ``rec_t`` unused). ``record_all``: every
            accepted step appends its time to ``rec_t`` and its state(s) to ``out_y`` (row
            ``cnt[CNT_NREC]``; capacity ``len(rec_t)``; returns :data:`BUFFER_FULL` when
            full); integration stops at ``t_out[-1]``.
        inertia : principal moments ``(3,)``, lanes ``(nl, 3)`` (coupled: the constants).
        terms, params, table, work : the model (:mod:`orbatt.core.model`) and its scratch (one
            for a group: one orbit).
        rtol, atol, max_step : tolerances (scipy's meaning) and the largest step allowed.
        max_steps : limit on step attempts (accepted + rejected + retaken for a switch) over the whole run.
        budget : step attempts allowed in this call.

        Returns a status code (:data:`DONE`, :data:`PAUSED`, ...).
        """
        nout = t_out.shape[0]
        i_out = cnt[CNT_IOUT]
        if i_out >= nout:
            return DONE
        if LANES:
            nl = y.shape[0]
            ncomp = WIDTH if WIDTH > 0 else y.shape[1]
        else:
            nl = 1
            ncomp = WIDTH if WIDTH > 0 else y.shape[0]
        terms, params, table, work = borrow_model(terms, params, table, work)
        inertia = borrow(inertia)
        if LANES:
            Kown = np.empty((N_STAGES + 1, ncomp, nl))
            tmpown = np.empty((3, ncomp, nl))
            K = borrow(Kown)
            yg = borrow(tmpown[0])
            ytmp = borrow(tmpown[1])
            ynew = borrow(tmpown[2])
        else:
            # the one lane's working arrays are the contiguous vectors the right-hand sides take
            # (as the single loop always had them); the loop indexes their (n, 1) views
            Kown = np.empty((N_STAGES + 1, ncomp))
            tmpown = np.empty((3, ncomp))
            K1 = borrow(Kown)
            y1 = borrow(tmpown[0])
            ytmp1 = borrow(tmpown[1])
            ynew1 = borrow(tmpown[2])
            K = K1[:, :, np.newaxis]
            yg = y1[:, np.newaxis]
            ytmp = ytmp1[:, np.newaxis]
            ynew = ynew1[:, np.newaxis]
        sown = np.empty((10, nl))
        sv = borrow(sown)
        oown = np.empty((N_STAGES, 9))  # the orbit at the stages (one extended trajectory)
        orbs = borrow(oown)
        xown = np.empty((LANE_SCRATCH, nl))  # the extended lanes' scratch
        S = borrow(xown)
        I = sv[0:3]  # noqa: E741 - the lanes' principal moments (3, nl)
        G = sv[3:7]  # scratch of rhs_lanes
        aQ = sv[7]   # the lanes' absolute tolerance of Q
        e5 = sv[8]   # the lanes' sums of squares of the error estimates
        e3 = sv[9]
        # --- the members in: (n, nl) working copies
        if LANES:
            for l in range(nl):
                for i in range(ncomp):
                    yg[i, l] = y[l, i]
                    K[0, i, l] = f0[l, i]
                for i in range(3):
                    I[i, l] = inertia[l, i]
                aQ[l] = atol * momentum_scale(inertia[l])
        else:
            for i in range(ncomp):
                yg[i, 0] = y[i]
                K[0, i, 0] = f0[i]
            aQ[0] = atol * momentum_scale(inertia)
        t = st[ST_T]
        h = st[ST_H]
        facold = st[ST_FACOLD]
        if facold <= 0.0:
            facold = 1.0e-4
        flags = cnt[CNT_FLAGS] & FLAG_BITS
        status = DONE
        # --- the flight software's ticks (orbatt.core.gyrostat.tick): a law with a period holds
        # its command in the state; the loop lands on its ticks and evaluates it there
        ticks = has_ticks(terms, params) if EXTENDED else False
        wheels_only = wheel_ticks_only(terms, params) if EXTENDED else 0  # > 0: a tick changes only h's rows
        # (the commands held from the start are issued by the driver before the first call:
        # orbatt.methods.dop853, tick(..., start=True))
        if (flags & FLAG_F0_VALID) == 0:
            if LANES:
                if EXTENDED:
                    rhs_extended_lanes(t, yg, nl, I, terms, params, table, work, K[0], S)
                else:
                    rhs_lanes(t, yg, nl, I, terms, params, table, work, G, K[0])
            elif COUPLED:
                rhs_coupled(t, y1, inertia, terms, params, table, work, K1[0])
            elif EXTENDED:
                rhs_extended(t, y1, inertia, terms, params, table, work, K1[0])
            else:
                rhs(t, y1, inertia, terms, params, table, work, K1[0])
            cnt[CNT_NFEV] += 1
            flags |= FLAG_F0_VALID
        if h <= 0.0:
            # Hairer's hinit (order 8) for each member, the smallest: a first step from the sizes
            # of y, f and an estimate of the second derivative (one extra evaluation)
            hmax = min(max_step, t_out[nout - 1] - t)
            for l in range(nl):
                if COUPLED:
                    dnf, dny = hinit_norms_vec(yg[:, l], K[0, :, l], atol, inertia, rtol)
                else:
                    dnf, dny = hinit_norms(yg[:, l], K[0, :, l], atol, aQ[l], rtol)
                hl = min(hinit_guess(dnf, dny), hmax)
                h = hl if l == 0 else min(h, hl)
            if h > 0.0 and h < np.inf:
                h0 = h
                for i in range(ncomp):
                    for l in range(nl):
                        ytmp[i, l] = yg[i, l] + h0 * K[0, i, l]
                if LANES:
                    if EXTENDED:
                        rhs_extended_lanes(t + h0, ytmp, nl, I, terms, params, table, work, K[1], S)
                    else:
                        rhs_lanes(t + h0, ytmp, nl, I, terms, params, table, work, G, K[1])
                elif COUPLED:
                    rhs_coupled(t + h0, ytmp1, inertia, terms, params, table, work, K1[1])
                elif EXTENDED:
                    rhs_extended(t + h0, ytmp1, inertia, terms, params, table, work, K1[1])
                else:
                    rhs(t + h0, ytmp1, inertia, terms, params, table, work, K1[1])
                for l in range(nl):
                    if COUPLED:
                        dnf, _ = hinit_norms_vec(yg[:, l], K[0, :, l], atol, inertia, rtol)
                        der2 = hinit_der2_vec(yg[:, l], K[0, :, l], K[1, :, l], atol, inertia, rtol)
                    else:
                        dnf, _ = hinit_norms(yg[:, l], K[0, :, l], atol, aQ[l], rtol)
                        der2 = hinit_der2(yg[:, l], K[0, :, l], K[1, :, l], atol, aQ[l], rtol)
                    if HINIT_ORDER == 8:
                        hl = min(100.0 * abs(h0), hinit_refine(der2, dnf, h0), hmax)
                    else:
                        hl = min(100.0 * abs(h0), hinit_refine_order(der2, dnf, h0, HINIT_ORDER), hmax)
                    h = hl if l == 0 else min(h, hl)
            cnt[CNT_NFEV] += 1
            if not (h > 0.0 and h < np.inf):
                h = 1e-6 * max(1.0, abs(t_out[nout - 1] - t))
        reject = (flags & FLAG_REJECTED) != 0
        attempts = 0
        # step-size floor: 10 ulps of the largest time involved (Hairer's test uses |t| only,
        # which lets a run starting at t = 0 crawl with steps of 1e-300)
        hmin = max(st[ST_HMIN], 10.0 * EPS * max(abs(t), abs(t_out[nout - 1])))
        cap = rec_t.shape[0]
        bad_lane = -1
        t_brk = next_breakpoint(t, terms, params, table)
        t_tick = np.inf
        t_grid = math.nan  # the time of the tick t_tick (its anomaly is t_tick: gyrostat.on_grid)
        if EXTENDED:
            if ticks:
                t_tick, t_grid = next_tick_grid(t, terms, params, math.nan)
        # --- mode sequences without a period (orbatt.core.mode_events): their transitions'
        # times are knots like the ticks, their conditions' crossings switching functions
        nseq = 0
        if SWITCHES and EXTENDED:
            nseq = sequence_count(terms, params)
            if nseq > 0:
                t_event = next_event(t, y1, terms, params)
                if t_event < t_tick:
                    t_tick = t_event
                    t_grid = math.nan
        # --- the switching functions (orbatt.core.switches): references armed at t, the switch
        # located by an earlier call that the next steps land on (t_sw, function k_sw)
        nsw = 0
        t_sw = np.inf
        k_sw = -1
        nfac = 0
        refine = 0     # retakes of the current mode crossing (orbatt.core.mode_events)
        h_aim = 0.0    # the next step's length aimed past a mode crossing the last one fell short of
        swown = np.empty((2, MAX_SWITCHES + 4))
        gnew = swown[0]
        gscr = np.empty(ncomp + MAX_SWITCHES + 4)
        if SWITCHES:
            # st[ST_SWITCH_K]: 0 at the first call (the references to arm), then 1 + (the
            # function of the located switch + 1, or 0); a resumed run keeps its references
            nsw, nfac = loop_switches(terms, params)
            if nsw > 0 and st[ST_SWITCH_K] == 0.0:
                loop_switch_values(t, y1, inertia, terms, params, table, work, gnew, nfac)
                update(work, gnew, nsw, k_sw)  # (-1 here; a literal -1 compiled update a second time)
            if nsw > 0 and st[ST_SWITCH_K] > 1.0:
                t_sw = st[ST_SWITCH_T]
                k_sw = int(st[ST_SWITCH_K]) - 2
        while i_out < nout:
            if record_all and cnt[CNT_NREC] >= cap:
                status = BUFFER_FULL
                break
            status, hh, landing, t_next = begin_attempt(attempts, budget, cnt, max_steps, t, h, max_step, t_out, i_out,
                                                        hmin, flags, min(min(t_brk, t_sw), t_tick))
            if status != DONE:
                break
            sw_land = landing and t_next == t_sw  # this attempt ends on the located switch
            t_new = t_next if landing else t + hh
            # --- the stages
            if EXTENDED and not LANES:  # one extended trajectory: the stages' orbit first
                stage_orbits(t, hh, t_new, C, N_STAGES, LAST_NEW, terms, params, table, work, orbs)
            for s in range(1, N_STAGES):
                stage_input(ytmp, yg, K, s, hh, A_PTR, A_COL, A_VAL, ncomp, nl)
                ts = t + C[s] * hh
                if LAST_NEW:  # (a constant: pruned from the other pairs' loops)
                    if s == N_STAGES - 1:  # f(t_new, y_new): at the step's end time itself
                        ts = t_new
                if LANES:
                    if EXTENDED:
                        rhs_extended_lanes(ts, ytmp, nl, I, terms, params, table, work, K[s], S)
                    else:
                        rhs_lanes(ts, ytmp, nl, I, terms, params, table, work, G, K[s])
                elif COUPLED:
                    rhs_coupled(ts, ytmp1, inertia, terms, params, table, work, K1[s])
                elif EXTENDED:
                    extended_rates(orbs[s, 0], orbs[s, 1], orbs[s, 2], (orbs[s, 3], orbs[s, 4], orbs[s, 5]),
                                   (orbs[s, 6], orbs[s, 7], orbs[s, 8]), ytmp1, inertia, terms, params, table, work,
                                   K1[s])
                else:
                    rhs_inline(ts, ytmp1, inertia, terms, params, table, work, K1[s])
            cnt[CNT_NFEV] += N_STAGES - 1
            # --- the solution and each member's error estimate (lanes innermost: vectorized)
            for l in range(nl):
                e5[l] = 0.0
                e3[l] = 0.0
            for i in range(ncomp):
                for l in range(nl):
                    acc = 0.0
                    a5 = 0.0
                    a3 = 0.0
                    for j in range(N_STAGES):
                        kji = K[j, i, l]
                        acc += B[j] * kji
                        a5 += E5[j] * kji
                        if not VERNER:
                            a3 += E3[j] * kji
                    ynew[i, l] = yg[i, l] + hh * acc
                    if COUPLED:
                        ai = atol * inertia[C_ATOL + i]
                    else:
                        ai = atol if i < 4 else aQ[l]
                    isk = 1.0 / (ai + rtol * max(abs(yg[i, l]), abs(ynew[i, l])))
                    a5 *= isk
                    e5[l] += a5 * a5
                    if not VERNER:
                        a3 *= isk
                        e3[l] += a3 * a3
            err = 0.0  # the group's: the largest of the members' errors
            for l in range(nl):
                if VERNER:
                    el = abs(hh) * math.sqrt(e5[l] / ncomp)
                else:
                    el = error_norm(e5[l], e3[l], hh, ncomp)
                if not (el < np.inf):
                    err = np.inf
                    bad_lane = l
                    break
                err = max(err, el)
            attempts += 1
            if not (err < np.inf):  # NaN or inf: shrink hard and retry
                flags, h, reject = reject_nonfinite(cnt, flags, hh)
                continue
            if CTRL9:
                fac11, hnew = controller9(err, facold, hh)
            elif VERNER:
                fac11, hnew = controller_pow(err, facold, hh, CTRL_EXPO)
            else:
                fac11, hnew = controller(err, facold, hh)
            sw_cross = False
            if SWITCHES:  # (a constant: `if` alone, so that numba prunes it from the other loops)
                if nsw > 0 and not sw_land:  # an armed switching function changed sign?
                    loop_switch_values(t_new, ynew1, inertia, terms, params, table, work, gnew, nfac)
                    sw_cross = crossed(work, gnew, nsw)
            if err <= 1.0 or sw_cross:
                # accepted (or to be located): the derivative at the new point (FSAL; Verner's
                # first stage; Dormand-Prince 5(4)'s last stage); none before a tick, which
                # changes the command (the derivative after it is evaluated below)
                at_tick = False
                if EXTENDED:
                    at_tick = t_new == t_tick and not sw_cross
                if LAST_NEW:
                    for i in range(ncomp):
                        for l in range(nl):
                            K[N_STAGES, i, l] = K[N_STAGES - 1, i, l]
                elif not at_tick:
                    if LANES:
                        if EXTENDED:
                            rhs_extended_lanes(t_new, ynew, nl, I, terms, params, table, work, K[N_STAGES], S)
                        else:
                            rhs_lanes(t_new, ynew, nl, I, terms, params, table, work, G, K[N_STAGES])
                    elif COUPLED:
                        rhs_coupled(t_new, ynew1, inertia, terms, params, table, work, K1[N_STAGES])
                    elif EXTENDED:
                        rhs_extended(t_new, ynew1, inertia, terms, params, table, work, K1[N_STAGES])
                    else:
                        rhs(t_new, ynew1, inertia, terms, params, table, work, K1[N_STAGES])
                    cnt[CNT_NFEV] += 1
                finite = True
                if LAST_NEW or not at_tick:
                    for l in range(nl):
                        if not all_finite(K[N_STAGES, :, l], ncomp):
                            finite = False
                            bad_lane = l
                            break
                if not finite:
                    flags, h, reject = reject_nonfinite(cnt, flags, hh)
                    continue
                if SWITCHES:
                    if sw_cross:
                        # the earliest root on the step's interpolant: retake the step to end there
                        theta, k = locate(t, t_new - t, y1, K1[0], ynew1, K1[N_STAGES], gnew, nsw, nfac, inertia,
                                          terms, params, table, work, gscr)
                        if k >= 0 and theta > AT_START:
                            t_sw = t + theta * (t_new - t)
                            k_sw = k
                            cnt[CNT_SWITCHES] += 1
                            continue
                        if k >= 0:  # a root at the step's start: disarmed, no retake
                            work[SWITCH_SLOT + k] = np.nan
                        if err > 1.0:
                            flags, h, reject = reject_step(cnt, flags, hh, fac11)
                            continue
                    if nseq > 0 and sw_land and k_sw >= nfac and refine < MAX_REFINE:
                        # a mode sequence's crossing (orbatt.core.mode_events): its function on the
                        # integrated state, not on the interpolant, to ROOT_TOL
                        loop_switch_values(t_new, ynew1, inertia, terms, params, table, work, gnew, nfac)
                        gl = gnew[k_sw]
                        ref = work[SWITCH_SLOT + k_sw]
                        if gl == gl and ref == ref and abs(gl) > ROOT_TOL:
                            refine += 1
                            if (gl > 0.0) != (ref > 0.0):  # past the root: locate it on this shorter step
                                theta, k = locate(t, t_new - t, y1, K1[0], ynew1, K1[N_STAGES], gnew, nsw, nfac,
                                                  inertia, terms, params, table, work, gscr)
                                if k >= 0 and theta > AT_START:
                                    t_sw = t + theta * (t_new - t)
                                    k_sw = k
                                    cnt[CNT_SWITCHES] += 1
                                    continue
                            elif abs(gl) < abs(ref):  # short of it: a plain step end, the next one aimed
                                h_aim = 2.0 * gl * (t_new - t) / (ref - gl)  # past the root (secant)
                                sw_land = False
                                t_sw = np.inf
                                k_sw = -1
                flags, facold, hnew, reject = accept_step(cnt, flags, err, hnew, hh, h, max_step, reject, landing)
                for i in range(ncomp):
                    for l in range(nl):
                        yg[i, l] = ynew[i, l]
                        K[0, i, l] = K[N_STAGES, i, l]
                t = t_new
                refine = 0
                if SWITCHES:
                    if nsw > 0 and sw_land:
                        loop_switch_values(t, y1, inertia, terms, params, table, work, gnew, nfac)
                    landed_seq = -1
                    now_holds = False
                    if nseq > 0 and sw_land and k_sw >= nfac:  # a mode sequence's conditions crossed:
                        landed_seq = k_sw - nfac              # which way (the sign before the root)
                        now_holds = work[SWITCH_SLOT + k_sw] > 0.0
                    if nsw > 0:
                        update(work, gnew, nsw, k_sw if sw_land else -1)
                    if sw_land:
                        t_sw = np.inf
                        k_sw = -1
                if EXTENDED:
                    if t == t_tick:  # a tick: the laws evaluate on the state (the next tick first: time only)
                        t_cur = t_grid
                        t_tick, t_grid = next_tick_grid(t, terms, params, t_cur)
                        if LANES:
                            if LAST_NEW and wheels_only > 0:  # K[0] is the derivative before the tick
                                for l in range(nl):  # (2: no sensors)
                                    wheel_tick(t, yg[:, l], I[:, l], terms, params, table, work, t_cur, K[0, :, l],
                                               wheels_only == 2)
                            else:
                                for l in range(nl):
                                    tick(t, yg[:, l], I[:, l], terms, params, table, work, False, t_cur)
                                rhs_extended_lanes(t, yg, nl, I, terms, params, table, work, K[0], S)
                                cnt[CNT_NFEV] += 1
                        else:
                            if LAST_NEW and wheels_only > 0:  # (orbatt.core.held_commands)
                                wheel_tick(t, y1, inertia, terms, params, table, work, t_cur, K1[0], wheels_only == 2)
                            else:
                                tick(t, y1, inertia, terms, params, table, work, False, t_cur)
                                rhs_extended(t, y1, inertia, terms, params, table, work, K1[0])
                                cnt[CNT_NFEV] += 1
                if SWITCHES and EXTENDED:
                    if nseq > 0:  # the continuous sequences: their flags, and a mode whose time came
                        # (gnew holds the functions at t on y1: this step end's, or the landing's)
                        mode_changed, _ = advance_modes(t, y1, inertia, terms, params, table, work, gnew[nfac:nsw],
                                                        landed_seq, now_holds, REARM, False)
                        if mode_changed:  # the new mode's law from here, its conditions armed
                            rhs_extended(t, y1, inertia, terms, params, table, work, K1[0])
                            cnt[CNT_NFEV] += 1
                            loop_switch_values(t, y1, inertia, terms, params, table, work, gnew, nfac)
                            for k in range(nfac, nsw):
                                work[SWITCH_SLOT + k] = gnew[k]
                        t_event = next_event(t, y1, terms, params)
                        if t_event < t_tick:
                            t_tick = t_event
                            t_grid = math.nan
                        if h_aim > 0.0:
                            hnew = min(hnew, h_aim)
                            h_aim = 0.0
                row = -1
                if landing and t == t_out[i_out]:  # (else a breakpoint)
                    if not record_all:
                        row = i_out
                    i_out += 1
                if t >= t_brk:
                    t_brk = next_breakpoint(t, terms, params, table)
                if record_all:
                    row = cnt[CNT_NREC]
                    rec_t[row] = t
                    cnt[CNT_NREC] = row + 1
                if row >= 0:  # --- the members out: an output row
                    if LANES:
                        for l in range(nl):
                            for i in range(ncomp):
                                out_y[l, row, i] = yg[i, l]
                    else:
                        for i in range(ncomp):
                            out_y[row, i] = yg[i, 0]
                h = hnew
            else:
                flags, h, reject = reject_step(cnt, flags, hh, fac11)
        # --- the members and the integrator state out
        if LANES:
            for l in range(nl):
                for i in range(ncomp):
                    y[l, i] = yg[i, l]
                    f0[l, i] = K[0, i, l]
        else:
            for i in range(ncomp):
                y[i] = yg[i, 0]
                f0[i] = K[0, i, 0]
        st[ST_T] = t
        st[ST_H] = h
        st[ST_FACOLD] = facold
        if SWITCHES:
            st[ST_SWITCH_T] = t_sw if k_sw >= 0 else 0.0
            st[ST_SWITCH_K] = k_sw + 2.0
        flags = (flags & ~FLAG_REJECTED) | (FLAG_REJECTED if reject else 0)
        if LANES:
            flags |= (bad_lane + 1) << BAD_LANE_SHIFT
        cnt[CNT_FLAGS] = flags
        cnt[CNT_IOUT] = i_out
        keepalive(Kown)
        keepalive(tmpown)
        keepalive(sown)
        keepalive(swown)
        keepalive(xown)
        keepalive(oown)
        return status

    return jit(advance)


"""Drivers of the compiled DOP853 kernels (:mod:`orbatt.core.dop853`): ``"dop853"`` (one
member, or an ensemble stepped member by member in parallel) and ``"dop853-lanes"`` (an
ensemble in lockstep groups)."""
from __future__ import annotations

import numpy as np

from ..core import dop853 as kd
from ..core import dop853_lanes as kdl
from ..core import model as km
from ..core import potentials as kp
from ..errors import InputError
from .base import Method, budget_limit, count_totals, group_sizes, register

__all__ = ["DOP853", "DOP853Lanes"]

#: counters summed into the statistics
_COUNTS = {"steps": kd.CNT_STEPS, "rejected_steps": kd.CNT_REJECTED, "rhs_evaluations": kd.CNT_NFEV}


@register
class DOP853(Method):
    """Adaptive Dormand-Prince 8(5,3) with Hairer's error estimate and step-size control,
    the whole step loop compiled; lands on every output time (step-end values)."""

    name = "dop853"
    order = 8
    adaptive = True
    extended = True
    options = {"max_step": "largest step allowed (time unit of the body); default no limit"}
    description = "compiled adaptive Dormand-Prince 8(5,3), Hairer's step-size control"

    def __init__(self, **kw):
        super().__init__(**kw)
        ms = self.opts.get("max_step", np.inf)
        try:
            ms = float(ms)
        except (TypeError, ValueError):
            raise InputError(f"max_step: {ms!r} is not a number") from None
        if not ms > 0:
            raise InputError(f"max_step: {ms!r} must be positive")
        self.max_step = ms

    def start(self, problem):
        super().start(problem)
        p = problem
        E = p.members
        self.Y = p.y0.copy()
        width = p.y0.shape[1]
        # the rigid body's loop, or the one of extended models (wheels, control laws)
        extended = (p.kernel.terms[0, km.FLAGS] & km.EXTENDED) != 0 or width != kd.NDIM
        self.one, self.batch = ((kd.advance_wide, kd.advance_batch_wide) if extended else
                                (kd.advance, kd.advance_batch))
        self.ST, self.CNT, self.F0 = kd.new_state(E, width)
        self.ST[:, kd.ST_T] = p.t0
        if self.step is not None:
            self.ST[:, kd.ST_H] = self.step
        self.WORK = kp.new_work(E)
        self.status = np.full(E, kd.PAUSED, dtype=np.int64)
        # kernel output times: those after t0 (outputs at t0 are the initial state)
        self.n0 = int(np.searchsorted(p.t_out, p.t0, side="right"))
        self.t_k = np.ascontiguousarray(p.t_out[self.n0:])
        if p.step_ends:
            self.rec_t = np.empty(256)
            self.rec_y = np.empty((256, width))
            self.n0 = 1
        else:
            self.out = np.empty((E, self.t_k.shape[0], width))

    def advance(self, budget):
        p = self.p
        budget = budget_limit(budget)
        if self.t_k.shape[0] == 0:
            return True
        if p.step_ends:
            while True:
                st = self.one(self.Y[0], self.ST[0], self.CNT[0], self.F0[0], self.t_k, self.rec_t, self.rec_y,
                                True, p.inertia[0], *p.kernel, self.WORK[0], self.rtol, self.atol,
                                self.max_step, self.max_steps, budget)
                if st != kd.BUFFER_FULL:
                    break
                n = self.rec_t.shape[0]
                self.rec_t = np.concatenate([self.rec_t, np.empty(n)])
                self.rec_y = np.concatenate([self.rec_y, np.empty((n, self.rec_y.shape[1]))])
            self.status[0] = st
        elif p.members == 1 and not p.ensemble:
            self.status[0] = self.one(self.Y[0], self.ST[0], self.CNT[0], self.F0[0], self.t_k, self.t_k,
                                        self.out[0], False, p.inertia[0], *p.kernel, self.WORK[0],
                                        self.rtol, self.atol, self.max_step, self.max_steps, budget)
        else:
            self.batch(self.Y, self.ST, self.CNT, self.F0, self.t_k, self.out, self.status, p.inertia,
                             *p.kernel, self.WORK, self.rtol, self.atol, self.max_step, self.max_steps, budget)
        return self.check_status(self.status)

    def failure_point(self, i):
        return float(self.ST[i, kd.ST_T]), i

    def _grid_outputs(self, counters):
        p = self.p
        n = int(counters[:, kd.CNT_IOUT].min())
        Y = np.concatenate([np.broadcast_to(p.y0[:, None, :], (p.members, self.n0, p.y0.shape[1])), self.out[:, :n]], axis=1)
        return p.t_out[:self.n0 + n], Y

    def outputs(self):
        p = self.p
        if p.step_ends:
            n = int(self.CNT[0, kd.CNT_NREC])
            t = np.concatenate([[p.t0], self.rec_t[:n]])
            Y = np.concatenate([p.y0[:1, None, :], self.rec_y[None, :n]], axis=1)
            return t, Y
        return self._grid_outputs(self.CNT)

    def stats(self):
        return count_totals(self.CNT, _COUNTS)

    def time_reached(self):
        return float(self.ST[:, kd.ST_T].min())


@register
class DOP853Lanes(DOP853):
    """DOP853 over an ensemble in lockstep groups (:func:`orbatt.core.dop853.advance_lanes`)."""

    name = "dop853-lanes"
    extended = False
    options = {"max_step": DOP853.options["max_step"],
               "lanes": "members per lockstep group (default 32)"}
    description = ("compiled DOP853 for ensembles: groups of members share the step size and the orbit "
                   "evaluation, vectorized over members (results agree with one-by-one runs to the tolerance, "
                   "not bitwise)")

    def __init__(self, **kw):
        super().__init__(**kw)
        lanes = self.opts.get("lanes", 32)
        if isinstance(lanes, bool) or not isinstance(lanes, (int, np.integer)) or lanes < 1:
            raise InputError(f"lanes: {lanes!r} is not a positive integer")
        self.lanes = int(lanes)

    def start(self, problem):
        if problem.step_ends:
            raise InputError("t_span: method 'dop853-lanes' needs output times t (e.g. t=[t0, t_end])")
        super().start(problem)
        G = (problem.members + self.lanes - 1) // self.lanes
        self.GST, self.GCNT, _ = kd.new_state(G)
        self.GST[:, kd.ST_T] = problem.t0
        if self.step is not None:
            self.GST[:, kd.ST_H] = self.step
        self.GWORK = kp.new_work(G)
        self.gstatus = np.full(G, kd.PAUSED, dtype=np.int64)

    def advance(self, budget):
        p = self.p
        if self.t_k.shape[0] == 0:
            return True
        kdl.advance_lanes(self.Y, self.GST, self.GCNT, self.F0, self.t_k, self.out, self.gstatus, p.inertia,
                         *p.kernel, self.GWORK, self.lanes, self.rtol, self.atol, self.max_step,
                         self.max_steps, budget_limit(budget))
        return self.check_status(self.gstatus)

    def failure_point(self, g):
        # the kernel stores the first failing lane + 1 above the flag bits of CNT_FLAGS
        lane = int(self.GCNT[g, kd.CNT_FLAGS] >> kd.BAD_LANE_SHIFT) - 1
        return float(self.GST[g, kd.ST_T]), g * self.lanes + max(lane, 0)

    def outputs(self):
        return self._grid_outputs(self.GCNT)

    def stats(self):
        s = count_totals(self.GCNT, _COUNTS, group_sizes(self.p.members, self.lanes, self.GCNT.shape[0]))
        s["group_steps"] = int(self.GCNT[:, kd.CNT_STEPS].sum())
        return s

    def time_reached(self):
        return float(self.GST[:, kd.ST_T].min())

    def settings(self):
        s = super().settings()
        s["lanes"] = self.lanes
        return s

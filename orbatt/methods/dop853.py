"""Drivers of the compiled DOP853, Verner 9(8), Dormand-Prince 5(4) and Bogacki-Shampine 3(2)
kernels (:mod:`orbatt.core.dop853`, the one step loop of :mod:`orbatt.core.rk_loop`): ``"dop853"``,
``"vern98"``, ``"dopri5"``, ``"bs32"`` (one member, or an ensemble stepped member by member in
parallel) and ``"dop853-lanes"``, ``"vern98-lanes"``, ``"dopri5-lanes"``, ``"bs32-lanes"`` (an
ensemble in lockstep groups)."""
from __future__ import annotations

import math
import warnings

import numpy as np

from ..core import control as kc
from ..core import dop853 as kd
from ..core import gyrostat as kg
from ..core import kepler as kk
from ..core import mode_events as kme
from ..core import model as km
from ..core import potentials as kp
from ..core import switches as ksw
from ..errors import InputError
from .base import Method, budget_limit, count_totals, group_sizes, register
from .problem import KernelSpec

__all__ = ["DOP853", "DOP853Lanes", "Vern98", "Vern98Lanes", "Dopri5", "Dopri5Lanes", "Bs32", "Bs32Lanes",
           "LockstepSwitchWarning",
           "tick_grid", "with_phase", "resume_stepper"]

#: counters summed into the statistics
_COUNTS = {"steps": kd.CNT_STEPS, "rejected_steps": kd.CNT_REJECTED, "rhs_evaluations": kd.CNT_NFEV,
           "switch_retakes": kd.CNT_SWITCHES}


def switches_off(kernel, switches):
    """``kernel`` itself, or (``switches`` False) a copy whose row 0 has the
    :data:`orbatt.core.model.NO_SWITCHES` flag: the step loops do not locate its switches."""
    if switches:
        return kernel
    terms = kernel.terms.copy()
    terms[0, km.FLAGS] |= km.NO_SWITCHES
    return KernelSpec(terms, kernel.params, kernel.table)


@register
class DOP853(Method):
    """Adaptive Dormand-Prince 8(5,3) with Hairer's error estimate and step-size control,
    the whole step loop compiled; lands on every output time (step-end values)."""

    name = "dop853"
    order = 8
    adaptive = True
    extended = True
    #: runs the flight software's ticks (a control law with a period) as knots of its loop
    ticks = True
    #: a run continued from a :class:`~orbatt.state.State` (:func:`orbatt.propagate` sets it before
    #: :meth:`start`): ``{"commands": bool, "phase": float or None, "stepper": dict or None}``:
    #: the flight software's state is in ``y0`` already (no tick at the start), the tick grid's
    #: origin, the step controller's memory (:func:`resume_stepper`)
    resume = None
    options = {"max_step": "largest step allowed (time unit of the body); default no limit",
               "independent_variable": "'auto' (default: the eccentric anomaly on a Keplerian orbit, else the "
                                       "time), 'eccentric-anomaly' or 'time'",
               "switches": "true (default): steps end on the zeros of the model's switching functions (a facet "
                           "edge-on to the flow or the Sun, the shadow's edges; one trajectory at a time, not "
                           "lanes); false: they straddle them"}
    description = "compiled adaptive Dormand-Prince 8(5,3), Hairer's step-size control"
    #: the compiled loops (one trajectory, ensemble) of the rigid body and of extended models
    loops = {False: (kd.advance, kd.advance_batch), True: (kd.advance_wide, kd.advance_batch_wide)}

    def __init__(self, **kw):
        super().__init__(**kw)
        ms = self.opts.get("max_step", np.inf)
        try:
            ms = float(ms)
        except (TypeError, ValueError):
            raise InputError(f"max_step: {ms!r} is not a number") from None
        if not ms > 0:
            raise InputError(f"max_step: {ms!r} must be positive")
        self.max_step = self.max_step_time = ms
        iv = self.opts.pop("independent_variable", "auto")
        if iv not in INDEPENDENT_VARIABLES:
            raise InputError(f"independent_variable: {iv!r} is not one of "
                             f"{', '.join(map(repr, INDEPENDENT_VARIABLES))}; give e.g. independent_variable = 'auto'")
        self.independent = iv
        self.anomaly = None
        sw = self.opts.get("switches", True)
        if not isinstance(sw, (bool, np.bool_)):
            raise InputError(f"switches: {sw!r} is not true or false; give switches = true (steps end on the "
                             "switching functions' zeros) or false")
        self.switches = bool(sw)

    def settings(self):
        s = super().settings()
        s["independent_variable"] = "eccentric-anomaly" if self.anomaly is not None else "time"
        return s

    def _independent_variable(self, problem):
        """Choose the independent variable (the option ``independent_variable``) once the
        output times ``self.t_k`` are known; for the eccentric anomaly, map them and
        ``max_step`` to it (:class:`EccentricAnomaly`). Returns the model the loops take."""
        self.anomaly = None
        self.max_step = self.max_step_time
        kernel = problem.kernel
        row = kernel.terms[0]
        keplerian = int(row[km.KIND]) == km.ORBIT_KEPLER and row[km.P1] - row[km.P0] >= kk.ORB_SIZE
        if self.independent == "time" or (self.independent == "auto" and not keplerian):
            return kernel
        if not keplerian:
            raise InputError("independent_variable: 'eccentric-anomaly' needs a Keplerian orbit (this model has "
                             "none, or a sampled one); give independent_variable = 'auto' or 'time'")
        an = EccentricAnomaly(kernel, problem.t0, self.t_k)
        if not an.increasing:
            if self.independent == "auto":  # outputs closer than the anomaly resolves: stay in time
                return kernel
            raise InputError("independent_variable: the output times are too close together to be told apart in "
                             "the eccentric anomaly; give independent_variable = 'time'")
        self.anomaly = an
        self.t_k = an.s_out
        self.max_step = an.max_step(self.max_step_time)
        return an.kernel

    def _start_states(self, st):
        """The start and the first step of the integrator states ``st`` in the independent
        variable."""
        st[:, kd.ST_T] = self.p.t0 if self.anomaly is None else self.anomaly.s0
        if self.anomaly is not None:
            st[:, kd.ST_HMIN] = self.anomaly.step_floor(self.p.t0, self.p.t_out[-1])
        if self.step is not None:
            st[:, kd.ST_H] = self.step if self.anomaly is None else self.anomaly.first_step(self.step)

    def _time(self, s):
        """The time of the independent variable's value ``s`` (float)."""
        return float(s) if self.anomaly is None else float(self.anomaly.times(np.array([float(s)]))[0])

    def start(self, problem):
        super().start(problem)
        p = problem
        E = p.members
        self.Y = p.y0.copy()
        width = p.y0.shape[1]
        # the rigid body's loop, or the one of extended models (wheels, control laws)
        extended = (p.kernel.terms[0, km.FLAGS] & km.EXTENDED) != 0 or width != kd.NDIM
        self.one, self.batch = self.loops[extended]
        self.ST, self.CNT, self.F0 = kd.new_state(E, width)
        self.WORK = kp.new_work(E)
        self.status = np.empty(E, dtype=np.int64)  # np.full without its Python-level wrapper
        self.status.fill(kd.PAUSED)
        # kernel output times: those after t0 (outputs at t0 are the initial state)
        self.n0 = int(np.searchsorted(p.t_out, p.t0, side="right"))
        self.t_k = np.ascontiguousarray(p.t_out[self.n0:])
        resume = self.resume or {}
        self.kernel = switches_off(with_phase(self._independent_variable(p), resume.get("phase")), self.switches)
        self._start_states(self.ST)
        resume_stepper(self, resume.get("stepper"))
        # the flight software's first tick (issue 32): the commands held from t0, in the initial
        # state that the outputs at t0 show (the loop's first call finds them set); a continued
        # run holds the state after the tick at t0 already (orbatt.State.command)
        self.y_start = p.y0
        if (p.kernel.terms[0, km.FLAGS] & km.EXTENDED) and not resume.get("commands") and \
                kg.has_ticks(self.kernel.terms, self.kernel.params):
            for e in range(E):
                kg.tick(self.ST[e, kd.ST_T], self.Y[e], p.inertia[e], *self.kernel, self.WORK[e], True, math.nan)
                # a mode sequence without a period takes its first mode's conditions as they are
                kme.advance(self.ST[e, kd.ST_T], self.Y[e], p.inertia[e], *self.kernel, self.WORK[e], np.empty(0), -1,
                            False, ksw.REARM, True)
            self.y_start = self.Y.copy()
        if p.step_ends:
            self.rec_t = np.empty(256)
            self.rec_y = np.empty((256, width))
            self.n0 = 1
        else:
            self.out = np.empty((E, self.t_k.shape[0], width))

    def stepper(self):
        """The step controller's memory where the run stands (``h``, ``facold`` per member,
        ``independent_variable``, ``method``): what a run continued from here needs to take the
        same steps (:class:`orbatt.state.State`, ``stepper``)."""
        keep = ~np.int64(kd.FLAG_F0_VALID | kd.FLAG_REJECTED)
        return {"h": self.ST[:, kd.ST_H].copy(), "facold": self.ST[:, kd.ST_FACOLD].copy(),
                "switch": self.ST[:, kd.ST_SWITCH_T:kd.ST_SWITCH_K + 1].copy(),
                "flags": self.CNT[:, kd.CNT_FLAGS] & ~keep, "f0": self.F0.copy(), "work": self.WORK.copy(),
                "independent_variable": self.settings()["independent_variable"], "method": self.name}

    def tick_grid(self):
        """``(period, phase)`` of the flight software's ticks of the model run, or None."""
        return tick_grid(self.kernel)

    def advance(self, budget):
        p = self.p
        budget = budget_limit(budget)
        if self.t_k.shape[0] == 0:
            return True
        if p.step_ends:
            while True:
                st = self.one(self.Y[0], self.ST[0], self.CNT[0], self.F0[0], self.t_k, self.rec_t, self.rec_y,
                                True, p.inertia[0], *self.kernel, self.WORK[0], self.rtol, self.atol,
                                self.max_step, self.max_steps, budget)
                if st != kd.BUFFER_FULL:
                    break
                n = self.rec_t.shape[0]
                self.rec_t = np.concatenate([self.rec_t, np.empty(n)])
                self.rec_y = np.concatenate([self.rec_y, np.empty((n, self.rec_y.shape[1]))])
            self.status[0] = st
        elif p.members == 1 and not p.ensemble:
            self.status[0] = self.one(self.Y[0], self.ST[0], self.CNT[0], self.F0[0], self.t_k, self.t_k,
                                        self.out[0], False, p.inertia[0], *self.kernel, self.WORK[0],
                                        self.rtol, self.atol, self.max_step, self.max_steps, budget)
        else:
            self.batch(self.Y, self.ST, self.CNT, self.F0, self.t_k, self.out, self.status, p.inertia,
                             *self.kernel, self.WORK, self.rtol, self.atol, self.max_step, self.max_steps, budget)
        return self.check_status(self.status)

    def failure_point(self, i):
        return self._time(self.ST[i, kd.ST_T]), i

    def _grid_outputs(self, counters):
        p = self.p
        n = int(counters[0, kd.CNT_IOUT] if counters.shape[0] == 1 else counters[:, kd.CNT_IOUT].min())
        # the initial state n0 times, then the outputs (np.concatenate of a broadcast, written directly)
        Y = np.empty((p.members, self.n0 + n, p.y0.shape[1]))
        Y[:, :self.n0] = self.y_start[:, None, :]
        Y[:, self.n0:] = self.out[:, :n]
        return p.t_out[:self.n0 + n], Y

    def _step_end_outputs(self, counters, rec_y):
        """``(t, Y)`` of a run that recorded every step end (one member): the times
        ``self.rec_t`` and states ``rec_y (cap, n)`` of the first ``counters[0, CNT_NREC]``."""
        p = self.p
        n = int(counters[0, kd.CNT_NREC])
        rec = self.rec_t[:n]
        if self.anomaly is not None:  # the step ends' times; the last lands on t_end itself
            rec = self.anomaly.times(rec)
            if n and counters[0, kd.CNT_IOUT] >= self.t_k.shape[0]:
                rec[-1] = p.t_out[-1]
        t = np.concatenate([[p.t0], rec])
        Y = np.concatenate([self.y_start[:1, None, :], rec_y[None, :n]], axis=1)
        return t, Y

    def outputs(self):
        if self.p.step_ends:
            return self._step_end_outputs(self.CNT, self.rec_y)
        return self._grid_outputs(self.CNT)

    def stats(self):
        return count_totals(self.CNT, _COUNTS)

    def time_reached(self):
        return self._time(self.ST[:, kd.ST_T].min())


def _ticking_rows(kernel):
    """The parameter offsets of the model's rows that run at a flight-software period."""
    terms, params = kernel.terms, kernel.params
    is_fsw = getattr(kg.is_flight_software, "py_func", kg.is_flight_software)
    return [int(terms[j, km.P0]) for j in range(1, terms.shape[0])
            if is_fsw(int(terms[j, km.KIND])) and params[int(terms[j, km.P0]) + kc.CTL_PERIOD] > 0.0]


def tick_grid(kernel):
    """``(period, phase)`` of the flight software's ticks ``phase + k period`` (the model's
    time unit; the flight software has one rate), or None without a law that has a period."""
    rows = _ticking_rows(kernel)
    if not rows:
        return None
    return float(kernel.params[rows[0] + kc.CTL_PERIOD]), float(kernel.params[rows[0] + kc.CTL_PHASE])


def with_phase(kernel, phase):
    """``kernel`` with its tick grid anchored at ``phase`` (a continued run keeps the grid of
    the run it continues: :attr:`orbatt.state.State.phase`); a copy of its ``params`` where that
    changes them, ``kernel`` itself where not (``phase`` None: the law's own)."""
    if phase is None:
        return kernel
    rows = [p0 for p0 in _ticking_rows(kernel) if kernel.params[p0 + kc.CTL_PHASE] != phase]
    if not rows:
        return kernel
    params = kernel.params.copy()
    for p0 in rows:
        params[p0 + kc.CTL_PHASE] = float(phase)
    return KernelSpec(kernel.terms, params, kernel.table)


def resume_stepper(method, stepper):
    """Put the step loop's memory ``stepper`` (:meth:`DOP853.stepper` of the run continued) into
    ``method``'s integrator states, as a resumed call finds them after a pause: the next step,
    the PI controller's last error and last rejection, the derivative at the start (FSAL), a
    located switch, the scratch array (the base of the eccentric anomaly's ``sin``/``cos``,
    Kepler's warm start, the switching functions' references: the numbers depend on them).
    Only from the same method in the same independent variable and model size (else the run
    starts afresh: Hairer's initial step)."""
    st, E = method.ST, method.ST.shape[0]
    if stepper is None or stepper.get("method") != method.name or \
            stepper.get("independent_variable") != method.settings()["independent_variable"] or \
            np.shape(stepper["f0"])[-1] != method.F0.shape[1] or np.shape(stepper["work"])[-1] != method.WORK.shape[1]:
        return False
    st[:, kd.ST_H] = np.broadcast_to(np.asarray(stepper["h"], dtype=np.float64), (E,))
    st[:, kd.ST_FACOLD] = np.broadcast_to(np.asarray(stepper["facold"], dtype=np.float64), (E,))
    st[:, kd.ST_SWITCH_T:kd.ST_SWITCH_K + 1] = np.broadcast_to(np.asarray(stepper["switch"], dtype=np.float64), (E, 2))
    method.CNT[:, kd.CNT_FLAGS] |= np.broadcast_to(np.asarray(stepper["flags"], dtype=np.int64), (E,))
    method.F0[:] = np.broadcast_to(np.asarray(stepper["f0"], dtype=np.float64), method.F0.shape)
    method.WORK[:] = np.broadcast_to(np.asarray(stepper["work"], dtype=np.float64), method.WORK.shape)
    return True


@register
class Vern98(DOP853):
    """Verner's 9(8) pair (16 stages, :mod:`orbatt.core.verner98_coefficients`) in the
    compiled step loop of :class:`DOP853` (same controller structure, exponent 1/9; error
    ``|h| rms((b - bhat) . K / sk)``); lands on every output time."""

    name = "vern98"
    order = 9
    description = "compiled adaptive Verner 9(8) (16 stages), Hairer-style PI step-size control"
    loops = {False: (kd.advance_verner98, kd.advance_batch_verner98),
             True: (kd.advance_wide_verner98, kd.advance_batch_wide_verner98)}


@register
class Dopri5(DOP853):
    """Dormand-Prince 5(4) (7 stages, FSAL inside the tableau: :mod:`orbatt.core.dopri5_coefficients`)
    in the compiled step loop of :class:`DOP853` (controller exponent 1/5; error ``|h| rms((b -
    bhat) . K / sk)``); lands on every output time. For flight software at a dense period,
    where one step per tick meets the tolerance: half DOP853's evaluations per tick
    (``benchmarks/tick_stepping.py``)."""

    name = "dopri5"
    order = 5
    description = "compiled adaptive Dormand-Prince 5(4) (7 stages, FSAL), Hairer-style PI step-size control"
    loops = {False: (kd.advance_dopri5, kd.advance_batch_dopri5),
             True: (kd.advance_wide_dopri5, kd.advance_batch_wide_dopri5)}


@register
class Bs32(DOP853):
    """Bogacki-Shampine 3(2) (4 stages, FSAL inside the tableau: :mod:`orbatt.core.bs32_coefficients`)
    in the compiled step loop of :class:`DOP853` (controller exponent 1/3; error ``|h| rms((b -
    bhat) . K / sk)``); lands on every output time. For flight software at a dense period, where
    one step of order 3 per tick meets the tolerance: 3 right-hand sides per tick (the stages; the
    derivative after the tick is the last stage's with, for PD laws on the wheels only, its wheels'
    rows rewritten: :mod:`orbatt.core.held_commands`; 4 with other laws) against DOP853's 12
    (``benchmarks/basilisk_fsw.py``)."""

    name = "bs32"
    order = 3
    description = "compiled adaptive Bogacki-Shampine 3(2) (4 stages, FSAL), Hairer-style PI step-size control"
    loops = {False: (kd.advance_bs32, kd.advance_batch_bs32),
             True: (kd.advance_wide_bs32, kd.advance_batch_wide_bs32)}


class LockstepSwitchWarning(UserWarning):
    """A lockstep-lanes method on an ensemble whose model has switching functions
    (:mod:`orbatt.core.switches`): slower than independent members there, and not bitwise."""


@register
class DOP853Lanes(DOP853):
    """DOP853 over an ensemble in lockstep groups (:data:`orbatt.core.dop853.advance_lanes`: the
    one step loop with a group of lanes); the rigid body and extended models (wheels, control
    laws)."""

    name = "dop853-lanes"
    options = {"max_step": DOP853.options["max_step"],
               "independent_variable": DOP853.options["independent_variable"],
               "lanes": "members per lockstep group (default 32)"}
    description = ("compiled DOP853 for ensembles: groups of members share the step size and the orbit "
                   "evaluation, vectorized over members (results agree with one-by-one runs to the tolerance, "
                   "not bitwise)")
    #: the compiled loops (one group, the ensemble's groups) of the rigid body and of extended models
    group_loops = {False: (kd.advance_group, kd.advance_lanes), True: (kd.advance_group_wide, kd.advance_lanes_wide)}

    def __init__(self, **kw):
        super().__init__(**kw)
        lanes = self.opts.get("lanes", 32)
        if isinstance(lanes, bool) or not isinstance(lanes, (int, np.integer)) or lanes < 1:
            raise InputError(f"lanes: {lanes!r} is not a positive integer; give e.g. lanes = 32")
        self.lanes = int(lanes)

    def start(self, problem):
        if kme.sequence_count(problem.kernel.terms, problem.kernel.params):
            raise InputError(f"method: {self.name!r} steps its members in lockstep and does not locate a mode "
                             "sequence's transitions without a period (each member's own instant); give "
                             "method = 'dop853' (members one by one), or a [control] period")
        super().start(problem)
        nsw = ksw.switch_count(self.kernel.terms, self.kernel.params)
        if nsw and problem.members > 1:
            warnings.warn(f"method {self.name!r}: the model's torques switch ({nsw} switching functions: facets "
                          "turning edge-on to the flow or the Sun, the shadow's edges); a lockstep group does not "
                          "land on them and steps every member across every other member's switches (on "
                          "cubesat-3u-disturbances 15x slower than 'dop853', whose members are independent and "
                          "bitwise their single runs); give method = 'dop853'", LockstepSwitchWarning, stacklevel=2)
        extended = self.one is self.loops[True][0]
        self.group, self.groups = self.group_loops[extended]
        G = (problem.members + self.lanes - 1) // self.lanes
        self.GST, self.GCNT, _ = kd.new_state(G)
        self._start_states(self.GST)
        self.GWORK = kp.new_work(G)
        self.gstatus = np.full(G, kd.PAUSED, dtype=np.int64)
        if problem.step_ends:  # one member (no ensemble): every step end, a group of one
            self.rec_y = self.rec_y[None]

    def advance(self, budget):
        p = self.p
        if self.t_k.shape[0] == 0:
            return True
        budget = budget_limit(budget)
        if p.step_ends:
            while True:
                st = self.group(self.Y, self.GST[0], self.GCNT[0], self.F0, self.t_k, self.rec_t, self.rec_y, True,
                                p.inertia, *self.kernel, self.GWORK[0], self.rtol, self.atol, self.max_step,
                                self.max_steps, budget)
                if st != kd.BUFFER_FULL:
                    break
                n = self.rec_t.shape[0]
                self.rec_t = np.concatenate([self.rec_t, np.empty(n)])
                self.rec_y = np.concatenate([self.rec_y, np.empty((1, n, self.rec_y.shape[2]))], axis=1)
            self.gstatus[0] = st
        else:
            self.groups(self.Y, self.GST, self.GCNT, self.F0, self.t_k, self.out, self.gstatus, p.inertia,
                        *self.kernel, self.GWORK, self.lanes, self.rtol, self.atol, self.max_step,
                        self.max_steps, budget)
        return self.check_status(self.gstatus)

    def stepper(self):
        """None: lockstep groups share a step (a continued run starts afresh)."""
        return None

    def failure_point(self, g):
        # the kernel stores the first failing lane + 1 above the flag bits of CNT_FLAGS
        lane = int(self.GCNT[g, kd.CNT_FLAGS] >> kd.BAD_LANE_SHIFT) - 1
        return self._time(self.GST[g, kd.ST_T]), g * self.lanes + max(lane, 0)

    def outputs(self):
        if self.p.step_ends:
            return self._step_end_outputs(self.GCNT, self.rec_y[0])
        return self._grid_outputs(self.GCNT)

    def stats(self):
        s = count_totals(self.GCNT, _COUNTS, group_sizes(self.p.members, self.lanes, self.GCNT.shape[0]))
        s["group_steps"] = int(self.GCNT[:, kd.CNT_STEPS].sum())
        return s

    def time_reached(self):
        return self._time(self.GST[:, kd.ST_T].min())

    def settings(self):
        s = super().settings()
        s["lanes"] = self.lanes
        return s


@register
class Vern98Lanes(DOP853Lanes):
    """Verner's 9(8) pair over an ensemble in lockstep groups (the one step loop of
    :class:`DOP853Lanes` with the pair of :class:`Vern98`)."""

    name = "vern98-lanes"
    order = 9
    description = ("compiled Verner 9(8) for ensembles: groups of members share the step size and the orbit "
                   "evaluation, vectorized over members (results agree with one-by-one runs to the tolerance, "
                   "not bitwise)")
    loops = Vern98.loops
    group_loops = {False: (kd.advance_group_verner98, kd.advance_lanes_verner98),
                   True: (kd.advance_group_wide_verner98, kd.advance_lanes_wide_verner98)}


@register
class Dopri5Lanes(DOP853Lanes):
    """Dormand-Prince 5(4) over an ensemble in lockstep groups (the one step loop of
    :class:`DOP853Lanes` with the pair of :class:`Dopri5`)."""

    name = "dopri5-lanes"
    order = 5
    description = ("compiled Dormand-Prince 5(4) for ensembles: groups of members share the step size and the "
                   "orbit evaluation, vectorized over members (results agree with one-by-one runs to the "
                   "tolerance, not bitwise)")
    loops = Dopri5.loops
    group_loops = {False: (kd.advance_group_dopri5, kd.advance_lanes_dopri5),
                   True: (kd.advance_group_wide_dopri5, kd.advance_lanes_wide_dopri5)}


@register
class Bs32Lanes(DOP853Lanes):
    """Bogacki-Shampine 3(2) over an ensemble in lockstep groups (the one step loop of
    :class:`DOP853Lanes` with the pair of :class:`Bs32`)."""

    name = "bs32-lanes"
    order = 3
    description = ("compiled Bogacki-Shampine 3(2) for ensembles: groups of members share the step size and the "
                   "orbit evaluation, vectorized over members (results agree with one-by-one runs to the "
                   "tolerance, not bitwise)")
    loops = Bs32.loops
    group_loops = {False: (kd.advance_group_bs32, kd.advance_lanes_bs32),
                   True: (kd.advance_group_wide_bs32, kd.advance_lanes_wide_bs32)}


#: the values of the option ``independent_variable``
INDEPENDENT_VARIABLES = ("auto", "eccentric-anomaly", "time")


class EccentricAnomaly:
    """The eccentric anomaly ``E`` as the step loops' independent variable on a Keplerian
    orbit (Sundman's transformation ``dt = (1 - e cos E) / n dE``; the kernels' orbit kind
    ``ORBIT_KEPLER_ANOMALY`` of :mod:`orbatt.core.model`): the orbit is closed-form at every
    stage, with no Kepler solve. Times map to anomalies by one Kepler solve each
    (:func:`orbatt.core.kepler.anomalies_at`, unreduced: continuous over revolutions), and
    back in closed form.

    Parameters
    ----------
    kernel : KernelSpec
        The model, its orbit of kind ``ORBIT_KEPLER`` (the ``orb`` vector of
        :mod:`orbatt.core.kepler`, the body's time unit).
    t0 : float
        The start time (the body's time unit).
    t_out : ndarray (N,)
        Output times after ``t0``, increasing.

    Attributes
    ----------
    s0, s_out : float, ndarray (N,)
        The anomalies of ``t0`` and ``t_out`` (rad).
    increasing : bool
        Whether ``s0, s_out`` strictly increase (outputs closer than the anomaly resolves do
        not).
    """

    def __init__(self, kernel, t0, t_out):
        row = kernel.terms[0]
        self.orb = np.ascontiguousarray(kernel.params[row[km.P0]:row[km.P1]])
        self.e = float(self.orb[1])
        self.n = float(self.orb[6])
        terms = kernel.terms.copy()
        terms[0, km.KIND] = km.ORBIT_KEPLER_ANOMALY
        self.kernel = KernelSpec(terms, kernel.params, kernel.table)
        s, self.increasing = kk.anomalies_at(np.concatenate(([float(t0)], t_out)), self.orb)
        self.s0 = float(s[0])
        self.s_out = s[1:]

    def times(self, s):
        """The times of the eccentric anomalies ``s`` (array, rad)."""
        return kk.times_at(np.ascontiguousarray(s, dtype=np.float64), self.orb)

    def max_step(self, max_step):
        """A step bound in time as one in the anomaly: ``dt/dE <= (1 + e) / n`` everywhere."""
        return max_step * self.n / (1.0 + self.e) if math.isfinite(max_step) else max_step

    def step_floor(self, t0, t_end):
        """The time form's floor on the step, 10 ulps of the largest time, as a step in the
        anomaly at periapsis (``dE/dt <= n / (1 - e)``). A periapsis too close to be resolved
        in time ends the run as fast as in time (the anomaly would crawl through it, with
        steps of 1e-21 s for ``e = 0.9999999``, instead); elsewhere the floor stays far below
        any step taken (~1e-13 rad for ``e = 0.99`` over 10 orbits)."""
        return 10.0 * kd.EPS * max(abs(t0), abs(t_end)) * self.n / (1.0 - self.e)

    def first_step(self, step):
        """A first step ``step`` in time as one in the anomaly, at the start."""
        return step * self.n / (1.0 - self.e * np.cos(self.s0))

"""The one entry point, :func:`propagate`, and the registry of integration methods.

Every method takes the same inputs (a body or bodies, a :class:`~orbatt.state.State`, a
:class:`~orbatt.potentials.Potential`, output times) and returns the same
:class:`~orbatt.trajectory.Trajectory` (times, ``q``, ``Q``, and the statistics ``steps``,
``rhs_evaluations`` or ``kicks``, ``rejected_steps``, ``wall_time_s``).

Methods (``method=``; :data:`METHODS` lists them, :func:`methods` describes them)
--------------------------------------------------------------------------------
``"dop853"`` (default)
    Adaptive Dormand-Prince 8(5,3) with Hairer's error estimate and step-size control
    (:mod:`orbatt.core.dop853`), the whole step loop compiled. ``rtol``/``atol`` mean what
    they mean in :func:`scipy.integrate.solve_ivp`. Outputs are step-end values: the
    integrator lands on every output time (no interpolation).
``"scipy-DOP853"``, ``"scipy-RK45"``, ``"scipy-RK23"``, ``"scipy-Radau"``, ``"scipy-BDF"``, ``"scipy-LSODA"``
    The reference path: scipy's solvers (Python step loop) on the compiled right-hand side,
    restarted at every output time so that outputs are step-end values too.
``"splitting2"``, ``"splitting4"``, ``"splitting6"`` (and named variants)
    Symplectic splitting (:mod:`orbatt.core.splitting`), fixed ``step``: Strang (order 2),
    McLachlan's 5-stage composition (order 4; ``"splitting4-yoshida"``,
    ``"splitting4-suzuki"`` are the alternatives), Kahan & Li's 9-stage composition (order
    6; ``"splitting6-yoshida"``). Keep ``|q| = 1`` and ``q.Q = 0`` to round-off and, for
    autonomous potentials, a bounded energy error over any number of steps. They are the
    tool for long runs and ensembles, not for short high-accuracy runs: for the paper's
    Keplerian case (10 orbits, 1e-9 rad) they need 3x (order 6) to 10x (order 4) the time of
    ``"dop853"`` (``benchmarks/README.md``).
``"rk4"``
    Classical fixed-step Runge-Kutta 4, compiled; a baseline.
``"dop853-lanes"``
    For ensembles: DOP853 on groups of ``lanes`` members (default 32) that share the step
    size (controlled by the group's largest error) and the orbit evaluation, with the
    per-member arithmetic vectorized. 5-10x the throughput of ``"dop853"`` on ensembles;
    each member is at least as accurate as alone, but results are not bitwise those of
    one-by-one runs.

Ensembles
---------
A ``state0`` holding ``E`` states and/or a list of ``E`` bodies runs all members in one call,
in parallel (numba ``prange``; ``NUMBA_NUM_THREADS`` sets the threads), and the outputs get a
leading member axis. With every method except ``"dop853-lanes"`` the result of each member is
bitwise identical to propagating it alone (adaptive methods step each member independently;
fixed-step methods run groups of members on the common grid, the orbit evaluated once per
group).

Progress and stopping
---------------------
The compiled loops run in chunks of about 0.25 s; between chunks ``progress`` is called and a
KeyboardInterrupt (Ctrl-C) is honoured: the result then holds the outputs computed so far and
``complete=False``. Resuming a chunked run is exact (results do not depend on the chunking).

Writing a method
----------------
Subclass :class:`Method`, set the class attributes, implement :meth:`Method.start`,
:meth:`Method.advance` and :meth:`Method.outputs`, and :func:`register` it. The driver
(:func:`propagate`) validates every input first, calls ``start`` once, then ``advance``
repeatedly with a step budget (so that long runs report progress and stop cleanly on
KeyboardInterrupt), and finally ``outputs``.
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from . import units as U
from .body import RigidBody
from .core import dop853 as kd
from .core import dop853_lanes as kdl
from .core import model as km
from .core._jit import BAD_LANE_SHIFT
from .core import potentials as kp
from .core import splitting as ks
from .core.hamiltonian import rhs as _rhs
from .errors import InputError, IntegrationError
from .state import State
from .trajectory import Trajectory

__all__ = ["propagate", "Method", "METHODS", "methods", "register", "ProgressInfo", "Problem"]

#: default limit on step attempts (per ensemble member)
DEFAULT_MAX_STEPS = 100_000_000
#: smallest rtol accepted (10 machine epsilons, as in Hairer's dop853)
MIN_RTOL = 10.0 * np.finfo(np.float64).eps
#: target wall time of one compiled call between progress reports / interrupt checks
CHUNK_SECONDS = 0.25


# ---------------------------------------------------------------------------------------
# The problem every method receives


@dataclass
class Problem:
    """A validated propagation problem, plain float64 arrays in the body's internal units.

    Attributes
    ----------
    t0 : float
        Start time (the epoch of ``y0``).
    t_out : ndarray (N,)
        Output times, increasing, ``>= t0``; ``t_out[0] == t0`` in ``t_span`` mode.
    step_ends : bool
        ``t_span`` mode: adaptive methods output every accepted step (``t_out`` then holds
        only ``[t0, t_end]``); fixed-step methods get the grid in ``t_out``.
    y0 : ndarray (E, 8)
        Initial ``(q, Q)`` of each member.
    inertia : ndarray (E, 3)
    kind, params, table :
        The potential kernel specification (:mod:`orbatt.core.potentials`).
    ensemble : bool
        Whether the caller asked for an ensemble (outputs get a leading member axis).
    """

    t0: float
    t_out: np.ndarray
    step_ends: bool
    y0: np.ndarray
    inertia: np.ndarray
    kind: int
    terms: np.ndarray
    params: np.ndarray
    table: np.ndarray
    ensemble: bool

    @property
    def members(self) -> int:
        return self.y0.shape[0]

    @property
    def t_end(self) -> float:
        return float(self.t_out[-1])


class ProgressInfo(NamedTuple):
    """What a progress callback receives after each compiled call."""

    fraction: float      #: of the time span done (slowest member, for ensembles)
    t: float             #: time reached (slowest member)
    t_end: float
    steps: int           #: steps so far (all members)
    wall_time_s: float   #: since the start of the integration


# ---------------------------------------------------------------------------------------
# Method base class and registry

METHODS: dict[str, type] = {}


def register(cls):
    """Class decorator: add a :class:`Method` subclass to :data:`METHODS` under ``cls.name``
    (and its ``aliases``)."""
    for key in (cls.name, *cls.aliases):
        if key in METHODS:
            raise ValueError(f"method name {key!r} is already registered")
        METHODS[key] = cls
    return cls


class Method:
    """Base class of integration methods (the subclass contract).

    Class attributes
    ----------------
    name : str
        Registry name (``method=`` of :func:`propagate`).
    aliases : tuple of str
        Other registry names.
    order : int
        Order of convergence.
    adaptive : bool
        Step size chosen from ``rtol``/``atol`` (True) or fixed ``step`` (False).
    symplectic : bool
    compiled : bool
        Whole step loop compiled (False: Python step loop).
    options : dict
        Extra keyword options accepted (name -> description).
    description : str

    Life cycle (called by :func:`propagate`, which has validated every argument):

    1. ``__init__(rtol=, atol=, step=, max_steps=, **options)``: check the options
       (raise :class:`~orbatt.errors.InputError` naming them);
    2. :meth:`start` (``problem``): allocate the per-member state;
    3. :meth:`advance` (``budget``) until it returns True: at most ``budget`` step attempts
       per member per call; raise :class:`~orbatt.errors.IntegrationError` (with ``t``)
       when a member cannot continue;
    4. :meth:`outputs` -> ``(n, Y)``: the first ``n`` outputs of every member,
       ``Y (E, n, 8)``, and the times ``t (n,)`` - callable at any point (partial results);
       :meth:`stats` -> dict; :meth:`time_reached` -> float (slowest member).
    """

    name = ""
    aliases: tuple = ()
    order = 0
    adaptive = False
    symplectic = False
    compiled = True
    options: dict = {}
    description = ""

    def __init__(self, *, rtol, atol, step, max_steps, **options):
        unknown = sorted(set(options) - set(self.options))
        if unknown:
            takes = ", ".join(sorted(self.options)) or "no options"
            raise InputError(f"{unknown[0]}: method {self.name!r} takes no option {unknown[0]!r} "
                             f"(it takes: {takes})")
        self.rtol = rtol
        self.atol = atol
        self.step = step
        self.max_steps = max_steps
        self.opts = dict(options)

    def settings(self) -> dict:
        s = {"order": self.order, "max_steps": self.max_steps}
        if self.adaptive:
            s.update(rtol=self.rtol, atol=self.atol)
            if self.step is not None:
                s["first_step"] = self.step
        else:
            s["step"] = self.step
        s.update(self.opts)
        return s

    def start(self, problem: Problem):  # pragma: no cover - abstract
        raise NotImplementedError

    def advance(self, budget: int) -> bool:  # pragma: no cover - abstract
        raise NotImplementedError

    def outputs(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def stats(self) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def time_reached(self) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    # helpers for subclasses
    def _fail(self, status, t, member, problem):
        where = f" (ensemble member {member})" if problem.ensemble else ""
        if status == kd.NONFINITE:
            msg = (f"method {self.name!r}: the state became non-finite (NaN or inf) at t = {t!r}{where}; "
                   "check the initial state and the potential's parameters, or reduce the step")
        elif status == kd.STEP_TOO_SMALL:
            msg = (f"method {self.name!r}: the step size underflowed at t = {t!r}{where}; the problem is "
                   "singular or far too stiff there, or rtol/atol are below what float64 can deliver")
        elif status == kd.MAX_STEPS:
            msg = (f"method {self.name!r}: max_steps = {self.max_steps} step attempts used up at t = {t!r}"
                   f"{where}; raise max_steps or loosen the tolerances / enlarge the step")
        else:  # pragma: no cover
            msg = f"method {self.name!r}: integration failed (status {status}) at t = {t!r}{where}"
        raise IntegrationError(msg, t=t)


def methods() -> dict:
    """``{name: description}`` of the registered methods (aliases included)."""
    return {k: f"{c.description} (order {c.order}, {'adaptive' if c.adaptive else 'fixed step'}"
               f"{', symplectic' if c.symplectic else ''}{', compiled' if c.compiled else ''})"
            for k, c in METHODS.items()}


# ---------------------------------------------------------------------------------------
# Compiled DOP853


def _budget_limit(budget):
    return int(min(max(budget, 1), 2**62))


@register
class DOP853(Method):
    name = "dop853"
    order = 8
    adaptive = True
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
        self.p = p = problem
        E = p.members
        self.Y = p.y0.copy()
        self.ST, self.CNT, self.F0 = kd.new_state(E)
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
            self.rec_y = np.empty((256, kd.NDIM))
            self.n0 = 1
        else:
            self.out = np.empty((E, self.t_k.shape[0], kd.NDIM))

    def advance(self, budget):
        p = self.p
        budget = _budget_limit(budget)
        if self.t_k.shape[0] == 0:
            return True
        if p.step_ends:
            while True:
                st = kd.advance(self.Y[0], self.ST[0], self.CNT[0], self.F0[0], self.t_k, self.rec_t, self.rec_y,
                                True, p.inertia[0], p.terms, p.params, p.table, self.WORK[0], self.rtol, self.atol,
                                self.max_step, self.max_steps, budget)
                if st != kd.BUFFER_FULL:
                    break
                n = self.rec_t.shape[0]
                self.rec_t = np.concatenate([self.rec_t, np.empty(n)])
                self.rec_y = np.concatenate([self.rec_y, np.empty((n, kd.NDIM))])
            self.status[0] = st
        elif p.members == 1 and not p.ensemble:
            self.status[0] = kd.advance(self.Y[0], self.ST[0], self.CNT[0], self.F0[0], self.t_k, self.t_k,
                                        self.out[0], False, p.inertia[0], p.terms, p.params, p.table, self.WORK[0],
                                        self.rtol, self.atol, self.max_step, self.max_steps, budget)
        else:
            kd.advance_batch(self.Y, self.ST, self.CNT, self.F0, self.t_k, self.out, self.status, p.inertia, p.terms,
                             p.params, p.table, self.WORK, self.rtol, self.atol, self.max_step, self.max_steps, budget)
        bad = np.flatnonzero((self.status != kd.DONE) & (self.status != kd.PAUSED))
        if bad.size:
            e = int(bad[0])
            self._fail(int(self.status[e]), float(self.ST[e, kd.ST_T]), e, p)
        return bool(np.all(self.status == kd.DONE))

    def outputs(self):
        p = self.p
        if p.step_ends:
            n = int(self.CNT[0, kd.CNT_NREC])
            t = np.concatenate([[p.t0], self.rec_t[:n]])
            Y = np.concatenate([p.y0[:1, None, :], self.rec_y[None, :n]], axis=1)
            return t, Y
        n = int(self.CNT[:, kd.CNT_IOUT].min())
        Y = np.concatenate([np.broadcast_to(p.y0[:, None, :], (p.members, self.n0, kd.NDIM)), self.out[:, :n]], axis=1)
        return p.t_out[:self.n0 + n], Y

    def stats(self):
        return {"steps": int(self.CNT[:, kd.CNT_STEPS].sum()),
                "rejected_steps": int(self.CNT[:, kd.CNT_REJECTED].sum()),
                "rhs_evaluations": int(self.CNT[:, kd.CNT_NFEV].sum())}

    def time_reached(self):
        return float(self.ST[:, kd.ST_T].min())


@register
class DOP853Lanes(DOP853):
    """DOP853 over an ensemble in lockstep groups (:func:`orbatt.core.dop853.advance_lanes`)."""

    name = "dop853-lanes"
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
        kdl.advance_lanes(self.Y, self.GST, self.GCNT, self.F0, self.t_k, self.out, self.gstatus, p.inertia, p.terms,
                         p.params, p.table, self.GWORK, self.lanes, self.rtol, self.atol, self.max_step,
                         self.max_steps, _budget_limit(budget))
        bad = np.flatnonzero((self.gstatus != kd.DONE) & (self.gstatus != kd.PAUSED))
        if bad.size:
            g = int(bad[0])
            lane = int(self.GCNT[g, kd.CNT_FLAGS] >> BAD_LANE_SHIFT) - 1
            self._fail(int(self.gstatus[g]), float(self.GST[g, kd.ST_T]), g * self.lanes + max(lane, 0), p)
        return bool(np.all(self.gstatus == kd.DONE))

    def _sizes(self):
        E = self.p.members
        return np.array([min(self.lanes, E - g * self.lanes) for g in range(self.GCNT.shape[0])])

    def outputs(self):
        p = self.p
        n = int(self.GCNT[:, kd.CNT_IOUT].min())
        Y = np.concatenate([np.broadcast_to(p.y0[:, None, :], (p.members, self.n0, kd.NDIM)), self.out[:, :n]], axis=1)
        return p.t_out[:self.n0 + n], Y

    def stats(self):
        nl = self._sizes()
        return {"steps": int((self.GCNT[:, kd.CNT_STEPS] * nl).sum()),
                "rejected_steps": int((self.GCNT[:, kd.CNT_REJECTED] * nl).sum()),
                "rhs_evaluations": int((self.GCNT[:, kd.CNT_NFEV] * nl).sum()),
                "group_steps": int(self.GCNT[:, kd.CNT_STEPS].sum())}

    def time_reached(self):
        return float(self.GST[:, kd.ST_T].min())

    def settings(self):
        s = super().settings()
        s["lanes"] = self.lanes
        return s


# ---------------------------------------------------------------------------------------
# Compiled fixed-step methods: splitting and RK4


class _FixedStep(Method):
    """Shared driver of the compiled fixed-step kernels (:mod:`orbatt.core.splitting`)."""

    kernel_method = ks.SPLITTING
    #: members per group in ensembles (the grid is common: results are those of one-by-one runs)
    LANES = 32

    def start(self, problem):
        self.p = p = problem
        E = p.members
        self.Y = p.y0.copy()
        self.ST, _ = ks.new_state(E)
        self.WORK = kp.new_work(1)
        self.t_k = np.ascontiguousarray(p.t_out)
        self.out = np.empty((E, self.t_k.shape[0], kd.NDIM))
        self.single = E == 1 and not p.ensemble
        G = 1 if self.single else (E + self.LANES - 1) // self.LANES
        self.status = np.full(G, kd.PAUSED, dtype=np.int64)
        _, self.GCNT = ks.new_state(G)
        self.GWORK = kp.new_work(G)
        self.setup(p)

    def setup(self, p):
        E = p.members
        self.flow = np.zeros(1, dtype=np.int64)
        self.weight = np.zeros(1)
        self.toff = np.zeros(1)
        self.AXES = np.ones((E, 3), dtype=np.int64)
        self.COEF = np.zeros((E, 4))

    def advance(self, budget):
        p = self.p
        budget = _budget_limit(budget)
        if self.single:
            self.status[0] = ks.advance(self.Y[0], self.ST[0], self.GCNT[0], self.t_k, self.out[0], p.t0,
                                        float(self.step), self.kernel_method, self.flow, self.weight, self.toff,
                                        self.AXES[0], self.COEF[0], p.inertia[0], p.terms, p.params, p.table,
                                        self.WORK[0], self.max_steps, budget)
        else:
            ks.advance_lanes(self.Y, self.ST, self.GCNT, self.t_k, self.out, self.status, p.t0, float(self.step),
                             self.kernel_method, self.flow, self.weight, self.toff, self.AXES, self.COEF, p.inertia,
                             p.terms, p.params, p.table, self.GWORK, self.LANES, self.max_steps, budget)
        bad = np.flatnonzero((self.status != kd.DONE) & (self.status != kd.PAUSED))
        if bad.size:
            g = int(bad[0])
            k = int(self.GCNT[g, ks.CNT_K])
            t = p.t0 + k * float(self.step)
            self._fail(int(self.status[g]), t, g * self.LANES, p)
        return bool(np.all(self.status == kd.DONE))

    def _sizes(self):
        if self.single:
            return np.ones(1, dtype=np.int64)
        E = self.p.members
        return np.array([min(self.LANES, E - g * self.LANES) for g in range(self.GCNT.shape[0])])

    def outputs(self):
        n = int(self.GCNT[:, ks.CNT_IOUT].min())
        return self.p.t_out[:n], self.out[:, :n]

    def stats(self):
        key = "kicks" if self.kernel_method == ks.SPLITTING else "rhs_evaluations"
        nl = self._sizes()
        return {"steps": int((self.GCNT[:, ks.CNT_STEPS] * nl).sum()), "rejected_steps": 0,
                key: int((self.GCNT[:, ks.CNT_EVALS] * nl).sum())}

    def time_reached(self):
        return self.p.t0 + float(self.GCNT[:, ks.CNT_K].min()) * float(self.step)


@register
class RK4(_FixedStep):
    name = "rk4"
    order = 4
    kernel_method = ks.RK4
    description = "classical Runge-Kutta 4, fixed step, compiled (a baseline; not symplectic)"


class Splitting(_FixedStep):
    """Symplectic splitting: a symmetric composition of Strang steps (coefficients in
    :data:`orbatt.core.splitting.COMPOSITIONS`)."""

    composition = "strang"
    symplectic = True
    options = {"kinetic": "decomposition of T: 'axes' (T1+T2+T3, DESIGN.md §4), 'shifted' (|g|^2/2I_mid + two "
                          "axis terms), or 'auto' (default: 'shifted' without a potential, 'axes' otherwise)"}

    def __init__(self, **kw):
        super().__init__(**kw)
        kin = self.opts.get("kinetic", "auto")
        if kin not in ("auto",) + ks.KINETIC:
            raise InputError(f"kinetic: {kin!r} is not one of 'auto', 'shifted', 'axes'")
        self.kinetic_option = kin

    def setup(self, p):
        kin = self.kinetic_option
        if kin == "auto":
            kin = "shifted" if p.terms.shape[0] == 1 else "axes"
        self.kinetic = kin
        self.flow, self.weight, self.toff = ks.sequence(ks.COMPOSITIONS[self.composition][1], kin)
        self.AXES, self.COEF = ks.rotation_setup(p.inertia, kin)

    def settings(self):
        s = super().settings()
        s["composition"] = self.composition
        s["kinetic"] = getattr(self, "kinetic", self.kinetic_option)
        return s


def _splitting(name, comp, aliases=()):
    order, gammas, ref = ks.COMPOSITIONS[comp]
    cls = type(f"Splitting_{comp}", (Splitting,), {
        "name": name, "aliases": aliases, "order": order, "composition": comp,
        "description": f"symplectic splitting, {ref}",
    })
    return register(cls)


_splitting("splitting2", "strang", ("splitting2-strang",))
_splitting("splitting4", "mclachlan4", ("splitting4-mclachlan",))
_splitting("splitting4-yoshida", "yoshida4")
_splitting("splitting4-suzuki", "suzuki4")
_splitting("splitting6", "kahanli6", ("splitting6-kahanli",))
_splitting("splitting6-yoshida", "yoshida6")


# ---------------------------------------------------------------------------------------
# scipy reference path


class Scipy(Method):
    """scipy's ODE solvers (:mod:`scipy.integrate`) on the compiled right-hand side, one
    member after the other, Python step loop. Each output time is a ``t_bound``: the solver
    is restarted there (with the last step size), so outputs are step-end values."""

    compiled = False
    solver = "DOP853"
    options = {"max_step": "largest step (scipy's max_step)"}

    def start(self, problem):
        from scipy import integrate

        self.p = p = problem
        self.cls = getattr(integrate, self.solver)
        E = p.members
        self.member = 0
        self.solver_obj = None
        self.i_out = np.zeros(E, dtype=np.int64)  # outputs done per member
        self.steps = np.zeros(E, dtype=np.int64)
        self.nfev = np.zeros(E, dtype=np.int64)
        self.t_now = np.full(E, p.t0)
        self.y_now = p.y0.copy()
        self.h_last = np.full(E, np.nan)
        if p.step_ends:
            self.rec_t = [p.t0]
            self.rec_y = [p.y0[0].copy()]
        else:
            self.out = np.empty((E, p.t_out.shape[0], kd.NDIM))
            n0 = int(np.searchsorted(p.t_out, p.t0, side="right"))
            self.out[:, :n0] = p.y0[:, None, :]
            self.i_out[:] = n0

    def _fun(self, e):
        p = self.p
        inertia = np.ascontiguousarray(p.inertia[e])
        work = kp.new_work()
        counter = self.nfev

        def fun(t, y):
            dy = np.empty(kd.NDIM)
            _rhs(t, np.ascontiguousarray(y, dtype=np.float64), inertia, p.terms, p.params, p.table, work, dy)
            counter[e] += 1
            return dy

        return fun

    def _new_solver(self, e, t_bound):
        # the same error norm as the compiled DOP853: atol on q, atol * max(I) on Q
        aQ = self.atol * float(np.max(self.p.inertia[e]))
        kw = {"rtol": self.rtol, "atol": np.array([self.atol] * 4 + [aQ] * 4)}
        if "max_step" in self.opts:
            kw["max_step"] = float(self.opts["max_step"])
        h = self.h_last[e]
        if h == h and h > 0:
            kw["first_step"] = min(h, t_bound - self.t_now[e])
        elif self.step is not None:
            kw["first_step"] = min(self.step, t_bound - self.t_now[e])
        self.solver_obj = self.cls(self._fun(e), self.t_now[e], self.y_now[e].copy(), t_bound, **kw)

    def advance(self, budget):
        p = self.p
        budget = _budget_limit(budget)
        n_targets = 1 if p.step_ends else p.t_out.shape[0]
        done = 0
        while self.member < p.members and done < budget:
            e = self.member
            if p.step_ends:
                target = p.t_end
                if self.t_now[e] >= target:
                    self.member += 1
                    self.solver_obj = None
                    continue
            else:
                if self.i_out[e] >= n_targets:
                    self.member += 1
                    self.solver_obj = None
                    continue
                target = float(p.t_out[self.i_out[e]])
            if self.solver_obj is None:
                self._new_solver(e, target)
                s = self.solver_obj
                # scipy loops for ever on a NaN step size (from a non-finite f(t0, y0))
                f0 = getattr(s, "f", np.zeros(1))
                if not (np.all(np.isfinite(f0)) and np.isfinite(getattr(s, "h_abs", 0.0))):
                    self._fail(kd.NONFINITE, float(s.t), e, p)
            s = self.solver_obj
            if self.steps[e] >= self.max_steps:
                self._fail(kd.MAX_STEPS, float(s.t), e, p)
            msg = s.step()
            done += 1
            self.steps[e] += 1
            if s.status == "failed" or not np.all(np.isfinite(s.y)):
                if not np.all(np.isfinite(s.y)):
                    self._fail(kd.NONFINITE, float(s.t_old if s.t_old is not None else s.t), e, p)
                raise IntegrationError(f"method {self.name!r}: scipy's {self.solver} failed at t = {float(s.t)!r}: "
                                       f"{msg}", t=float(s.t))
            self.t_now[e] = s.t
            self.y_now[e] = s.y
            if s.t_old is not None:
                self.h_last[e] = abs(s.t - s.t_old)
            if p.step_ends:
                self.rec_t.append(float(s.t))
                self.rec_y.append(s.y.copy())
            if s.status == "finished":
                self.t_now[e] = target  # solvers end exactly on t_bound
                if not p.step_ends:
                    self.out[e, self.i_out[e]] = s.y
                    self.i_out[e] += 1
                self.solver_obj = None
        return self.member >= p.members

    def outputs(self):
        p = self.p
        if p.step_ends:
            return np.array(self.rec_t), np.array(self.rec_y)[None]
        n = int(self.i_out.min())
        return p.t_out[:n], self.out[:, :n]

    def stats(self):
        return {"steps": int(self.steps.sum()), "rejected_steps": None, "rhs_evaluations": int(self.nfev.sum())}

    def time_reached(self):
        return float(self.t_now.min())


for _solver, _order in (("DOP853", 8), ("RK45", 5), ("RK23", 3), ("Radau", 5), ("BDF", 5), ("LSODA", 12)):
    register(type(f"Scipy_{_solver}", (Scipy,), {
        "name": f"scipy-{_solver}", "solver": _solver, "order": _order, "adaptive": True,
        "description": f"scipy.integrate.{_solver} (reference path, Python step loop)"}))
del _solver, _order


# ---------------------------------------------------------------------------------------
# Validation


def _resolve_method(method):
    if isinstance(method, type) and issubclass(method, Method):
        return method
    if isinstance(method, str):
        if method in METHODS:
            return METHODS[method]
        low = {k.lower(): v for k, v in METHODS.items()}
        if method.lower() in low:
            return low[method.lower()]
    known = ", ".join(repr(k) for k in METHODS)
    raise InputError(f"method: {method!r} is not a known method; choose one of {known} (or pass a Method subclass)")


def _bodies(body):
    if isinstance(body, RigidBody):
        return [body], False
    if isinstance(body, (list, tuple)) and body and all(isinstance(b, RigidBody) for b in body):
        if len({b.dimensionless for b in body}) != 1:
            raise InputError("body: an ensemble of bodies must be all dimensional or all dimensionless")
        return list(body), True
    raise InputError(f"body: expected a RigidBody or a non-empty list of RigidBody, got {type(body).__name__}")


def _times(value, name, body):
    if value is None:
        return None
    v = U.strip(value, body.time_unit, name, allow_plain=True)
    return np.atleast_1d(np.asarray(v, dtype=np.float64))


def _quote(value):
    return str(value) if hasattr(value, "unit") else repr(value)


def _positive(value, name, body=None, *, unit=None, allow_zero=False):
    raw = value
    if unit is not None and body is not None:
        if isinstance(value, (int, float, np.floating, np.integer)) and not math.isfinite(float(value)):
            raise InputError(f"{name}: {_quote(raw)} must be a finite positive number")
        value = U.strip(value, unit, name, allow_plain=True)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: {_quote(raw)} is not a number") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise InputError(f"{name}: {_quote(raw)} must be a finite {'non-negative' if allow_zero else 'positive'} "
                         "number")
    return v


def _progress_printer(stream=None):
    stream = stream or sys.stderr
    state = {"last": 0.0, "shown": False}

    def report(info: ProgressInfo):
        now = info.wall_time_s
        if not state["shown"] and now < 1.0:
            return  # runs shorter than a second show no bar
        if now - state["last"] < 0.2 and info.fraction < 1.0:
            return
        state["last"] = now
        state["shown"] = True
        width = 30
        fill = int(round(width * info.fraction))
        stream.write(f"\rorbatt: [{'#' * fill}{'.' * (width - fill)}] {100 * info.fraction:5.1f}%  "
                     f"t = {info.t:.6g}/{info.t_end:.6g}  {info.steps} steps  {info.wall_time_s:.1f} s")
        if info.fraction >= 1.0:
            stream.write("\n")
        stream.flush()

    return report


# ---------------------------------------------------------------------------------------
# The entry point


def propagate(body, state0, potential, t=None, *, t_span=None, method="dop853", rtol=1e-10, atol=1e-12,
              step=None, progress=None, max_steps=None, **options) -> Trajectory:
    """Propagate the attitude ``(q, Q)`` of a rigid body (or an ensemble) under a potential.

    Parameters
    ----------
    body : RigidBody or list of RigidBody
        The body; a list makes an ensemble over bodies (all dimensional or all
        dimensionless).
    state0 : State
        Initial canonical state at the start time. ``q`` of shape ``(4,)``, or ``(E, 4)``
        for an ensemble over initial states (broadcast against a list of ``E`` bodies).
    potential : Potential
        ``orbatt.TorqueFree()``, ``orbatt.HeavyTop(...)``, a gravity-gradient potential, or any
        object with the kernel specification ``kind``, ``params``, ``table``.
    t : array_like or Quantity (N,), optional
        Output times (s for dimensional bodies, plain numbers for dimensionless ones; a time
        Quantity is converted), strictly increasing. The propagation starts at ``t[0]``
        (``state0`` is the state there) unless ``t_span`` is given.
    t_span : (t0, t_end), optional
        Start and end. Without ``t``: outputs at ``t0`` and at every step end (adaptive
        methods; not for ensembles) or on the grid ``t0 + k step`` plus ``t_end`` (fixed-step
        methods). With ``t``: ``t`` must lie in ``[t0, t_end]``.
    method : str or Method subclass
        See :data:`METHODS` / :func:`methods`; default ``"dop853"``.
    rtol, atol : float
        Tolerances of adaptive methods (scipy's meaning, ``rtol >= 2.2e-15``), except that the
        absolute tolerance of the momentum ``Q`` is ``atol * max(I)``: ``atol`` bounds the
        absolute error of ``q`` and of ``Q / max(I)`` (a rate, rad per time unit), so it means
        the same for a 10 kg m^2 cubesat and a moon whatever the unit of ``Q``.
    step : float or Quantity
        The step of fixed-step methods (required there); the first step of adaptive ones.
    progress : None, True or callable
        ``True`` prints a progress bar on stderr; a callable receives a :class:`ProgressInfo`
        after every compiled call (about every 0.25 s) and may return ``False`` to stop
        (the result is then marked incomplete). Off by default.
    max_steps : int
        Limit on step attempts per member (default 1e8).
    **options
        Method options (``max_step`` for adaptive methods, ``kinetic`` for splitting).

    Returns
    -------
    Trajectory
        ``t (N,)``, ``q``/``Q`` ``(N, 4)`` or ``(E, N, 4)`` for ensembles, ``stats``
        (``steps``, ``rejected_steps``, ``rhs_evaluations`` or ``kicks``, ``wall_time_s``,
        ``members``), ``settings``, ``complete`` (False after a KeyboardInterrupt or a stop
        requested by the progress callback: then the outputs computed so far; for an ensemble
        the outputs every member has reached).

    Raises
    ------
    InputError
        Bad arguments (quoted in the message), before any integration.
    IntegrationError
        A member could not continue (non-finite state, step-size underflow, ``max_steps``);
        its ``t`` is the time reached, its ``trajectory`` what was computed until then.
    """
    cls = _resolve_method(method)
    bodies, body_ensemble = _bodies(body)
    b0 = bodies[0]
    # --- state
    if not isinstance(state0, State):
        raise InputError(f"state0: expected an orbatt.State, got {type(state0).__name__}; build one with "
                         "State(body, q, Q), State.from_omega or State.from_momentum")
    if state0.body.dimensionless != b0.dimensionless:
        raise InputError("state0: built for a body with different units (dimensional vs dimensionless) than body")
    y = np.asarray(state0.y, dtype=np.float64)
    if not np.all(np.isfinite(y)):
        raise InputError(f"state0: contains non-finite values (q = {state0.q!r}, Q = {state0.Q!r})")
    if y.ndim > 2:
        raise InputError(f"state0: an ensemble state must have q of shape (E, 4), got {state0.q.shape}")
    state_ensemble = y.ndim == 2
    y = np.atleast_2d(y)
    E = max(len(bodies), y.shape[0])
    if len(bodies) not in (1, E) or y.shape[0] not in (1, E):
        raise InputError(f"body/state0: {len(bodies)} bodies and {y.shape[0]} initial states do not broadcast to "
                         "one ensemble (give one of each, or N bodies and N states, or one and N)")
    y0 = np.ascontiguousarray(np.broadcast_to(y, (E, kd.NDIM)), dtype=np.float64).copy()
    inertia = np.ascontiguousarray(np.broadcast_to(np.array([b.inertia_value for b in bodies]), (E, 3)),
                                   dtype=np.float64).copy()
    ensemble = body_ensemble or state_ensemble
    # --- potential
    if not all(hasattr(potential, a) for a in ("kind", "params", "table")):
        raise InputError(f"potential: expected an orbatt Potential (with kind, params, table), got "
                         f"{type(potential).__name__}")
    if hasattr(potential, "check_body"):
        for b in set(bodies):
            potential.check_body(b)
    kind = int(potential.kind)
    # writeable C-contiguous float64 arrays: one numba specialization of every kernel
    params = np.array(potential.params, dtype=np.float64).ravel()
    table = np.asarray(potential.table, dtype=np.float64)
    if not (table.flags.c_contiguous and table.flags.writeable):
        table = np.array(table, order="C")
    if table.ndim != 2:
        raise InputError(f"potential.table: expected a 2-D array, got shape {table.shape}")
    sampled_span = None
    if kind == getattr(kp, "GRAVITY_GRADIENT_SAMPLED", -1) and params.size >= 3:
        sampled_span = (float(params[1]), float(params[2]))
    terms, params, table = (potential.kernel_model() if hasattr(potential, "kernel_model")
                            else km.from_spec(kind, params, table))
    # --- times
    tv = _times(t, "t", b0)
    span = _times(t_span, "t_span", b0)
    if tv is None and span is None:
        raise InputError("t: give the output times t, or t_span=(t0, t_end)")
    if span is not None:
        if span.shape != (2,):
            raise InputError(f"t_span: expected (t0, t_end), got {t_span!r}")
        if not span[1] > span[0]:
            raise InputError(f"t_span: the end {float(span[1])!r} is not after the start {float(span[0])!r}; "
                             "orbatt integrates forward in time (give t_end > t0)")
    if tv is not None:
        if tv.ndim != 1 or tv.size == 0:
            raise InputError(f"t: expected a 1-D array of output times, got shape {tv.shape}")
        d = np.diff(tv)
        if np.any(d <= 0):
            i = int(np.flatnonzero(d <= 0)[0])
            raise InputError(f"t: output times must increase strictly; t[{i + 1}] = {float(tv[i + 1])!r} follows "
                             f"t[{i}] = {float(tv[i])!r} (orbatt integrates forward in time)")
        if span is not None and (tv[0] < span[0] or tv[-1] > span[1]):
            raise InputError(f"t: the output times [{float(tv[0])!r} .. {float(tv[-1])!r}] leave t_span = "
                             f"({float(span[0])!r}, {float(span[1])!r})")
    t0 = float(span[0]) if span is not None else float(tv[0])
    t_last = float(span[1]) if span is not None else float(tv[-1])
    if sampled_span is not None and (t0 < sampled_span[0] or t_last > sampled_span[1]):
        raise InputError(f"t: the propagation [{t0!r}, {t_last!r}] leaves the span {list(sampled_span)} of the "
                         "sampled orbit; build the orbit over a longer span")
    # --- method settings
    rtol = _positive(rtol, "rtol")
    atol = _positive(atol, "atol", allow_zero=True)
    if cls.adaptive and rtol < MIN_RTOL:
        raise InputError(f"rtol: {rtol!r} is below {MIN_RTOL:.3g} (10 machine epsilons); float64 cannot deliver it")
    stepv = None
    if step is not None:
        stepv = _positive(step, "step", b0, unit=b0.time_unit)
    elif not cls.adaptive:
        raise InputError(f"step: method {cls.name!r} has a fixed step; give step= (e.g. a few seconds for an "
                         "orbiting body, 1e-2 of a rotation period in general)")
    if max_steps is None:
        max_steps = DEFAULT_MAX_STEPS
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps <= 0:
        raise InputError(f"max_steps: {max_steps!r} is not a positive integer")
    max_steps = int(max_steps)
    if progress is True:
        progress = _progress_printer()
    elif progress is False:
        progress = None
    if progress is not None and not callable(progress):
        raise InputError(f"progress: expected None, True or a callable, got {type(progress).__name__}")
    # --- output grid
    step_ends = False
    if tv is None:
        t_end = float(span[1])
        if cls.adaptive:
            if ensemble:
                raise InputError("t_span: an ensemble has no common step grid; give output times t (e.g. "
                                 "t=[t0, t_end])")
            t_out = np.array([t0, t_end])
            step_ends = True
        else:
            n = int(math.floor((t_end - t0) / stepv))
            if n + 1 > 50_000_000:
                raise InputError(f"t_span: {n} steps of {stepv!r} would all be outputs; give output times t")
            grid = t0 + np.arange(n + 1) * stepv
            # the grid, then t_end (a grid point within rounding of t_end is t_end)
            grid = grid[grid < t_end - 8 * np.finfo(float).eps * max(abs(t_end), abs(t0))]
            t_out = np.concatenate([grid, [t_end]])
    else:
        t_out = tv
    if not cls.adaptive:
        n_needed = math.ceil((float(t_out[-1]) - t0) / stepv - 1e-9)
        if n_needed > max_steps:
            raise InputError(f"step: {stepv!r} needs {n_needed} steps to reach {float(t_out[-1])!r}, more than "
                             f"max_steps = {max_steps}")
    problem = Problem(t0=t0, t_out=np.ascontiguousarray(t_out, dtype=np.float64), step_ends=step_ends, y0=y0,
                      inertia=inertia, kind=kind, terms=terms, params=params, table=table, ensemble=ensemble)
    m = cls(rtol=rtol, atol=atol, step=stepv, max_steps=max_steps, **options)
    m.start(problem)

    # --- run in compiled chunks
    complete = True
    stop_reason = None
    # first call: small (a quick first progress report, an early check of the speed), then
    # sized to take about CHUNK_SECONDS
    budget = max(16, 200_000 // E) if E > 1 else 5_000
    if not m.compiled:
        budget = 2_000
    start = time.perf_counter()

    def finish(complete, reason):
        wall = time.perf_counter() - start
        tt, Y = m.outputs()
        stats = dict(m.stats())
        stats["wall_time_s"] = wall
        stats["members"] = E
        if reason:
            stats["stopped"] = reason
        if not ensemble:
            Y = Y[0]
        return Trajectory(body=b0, potential=potential, t=np.array(tt, dtype=np.float64),
                          q=np.ascontiguousarray(Y[..., :4]), Q=np.ascontiguousarray(Y[..., 4:]),
                          inertia=inertia if body_ensemble else inertia[0].copy(), method=m.name,
                          settings=m.settings(), stats=stats, complete=complete)

    done = False
    try:
        while True:
            c0 = time.perf_counter()
            try:
                done = m.advance(budget)
            except IntegrationError as exc:
                exc.trajectory = finish(False, "error")
                raise
            except (ValueError, ArithmeticError) as exc:
                if isinstance(exc, InputError):
                    raise
                # raised inside a kernel (e.g. a sampled orbit asked outside its span)
                tr = m.time_reached()
                err = IntegrationError(f"method {m.name!r}: stopped near t = {tr!r}: {exc}", t=tr)
                err.trajectory = finish(False, "error")
                raise err from exc
            dt = time.perf_counter() - c0
            if progress is not None:
                tr = m.time_reached() if not done else problem.t_end
                span_len = problem.t_end - t0
                frac = 1.0 if done else min(1.0, max(0.0, (tr - t0) / span_len)) if span_len > 0 else 1.0
                keep = progress(ProgressInfo(frac, tr, problem.t_end, int(m.stats()["steps"]),
                                             time.perf_counter() - start))
                if keep is False and not done:
                    complete, stop_reason = False, "progress callback"
                    break
            if done:
                break
            # aim at CHUNK_SECONDS per call
            if dt > 0:
                budget = int(min(max(budget * min(4.0, CHUNK_SECONDS / dt), 1), 2**40))
            else:
                budget *= 4
    except KeyboardInterrupt:
        if not done:
            complete, stop_reason = False, "KeyboardInterrupt"
    return finish(complete, stop_reason)

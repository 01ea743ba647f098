"""The :class:`Method` base class (the subclass contract every integration method follows),
the registry :data:`METHODS`, and the helpers the drivers share: the status -> failure
handling, the step budget and the summing of integration statistics.

Writing a method
----------------
Subclass :class:`Method`, set the class attributes, implement :meth:`Method.start`,
:meth:`Method.advance`, :meth:`Method.outputs`, :meth:`Method.stats` and
:meth:`Method.time_reached`, and :func:`register` it. The driver
(:func:`orbatt.propagation.propagate`) validates every input first, calls ``start`` once,
then ``advance`` repeatedly with a step budget (so that long runs report progress and stop
cleanly on KeyboardInterrupt), and finally ``outputs``.
"""
from __future__ import annotations

import numpy as np

from ..core import dop853 as kd
from ..errors import InputError, IntegrationError
from .problem import Problem

__all__ = ["Method", "METHODS", "register", "methods", "resolve_method", "budget_limit", "count_totals",
           "group_sizes"]

#: ``{name: Method subclass}``, aliases included (filled by :func:`register`)
METHODS: dict[str, type] = {}


def register(cls):
    """Class decorator: add a :class:`Method` subclass to :data:`METHODS` under ``cls.name``
    (and its ``aliases``)."""
    for key in (cls.name, *cls.aliases):
        if key in METHODS:
            raise ValueError(f"method name {key!r} is already registered")
        METHODS[key] = cls
    return cls


def methods() -> dict:
    """``{name: description}`` of the registered methods (aliases included)."""
    return {k: f"{c.description} ("
               + ("closed form" if c.closed_form else
                  f"order {c.order}, {'adaptive' if c.adaptive else 'fixed step'}")
               + f"{', symplectic' if c.symplectic else ''}{', compiled' if c.compiled else ''})"
            for k, c in METHODS.items()}


def resolve_method(method) -> type:
    """The :class:`Method` subclass named by ``method`` (a registry name, matched
    case-insensitively if not exactly, or a subclass itself); :class:`InputError` otherwise."""
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


def budget_limit(budget) -> int:
    """The step budget of one compiled call, clipped to ``[1, 2**62]`` (an int64 in the kernels)."""
    return int(min(max(budget, 1), 2**62))


def group_sizes(members: int, per_group: int, groups: int) -> np.ndarray:
    """Members in each of ``groups`` consecutive groups of at most ``per_group`` members."""
    return np.array([min(per_group, members - g * per_group) for g in range(groups)])


def count_totals(counters: np.ndarray, columns: dict, sizes=None) -> dict:
    """Sum integration statistics over members or groups.

    Parameters
    ----------
    counters : ndarray (G, n) of int
        A kernel's counter rows (one per member or per group).
    columns : dict
        ``{statistic name: column of counters}``.
    sizes : ndarray (G,), optional
        Members in each row (a group's step counts for each of its members).

    Returns
    -------
    dict
        ``{statistic name: int total}``.
    """
    if sizes is not None:
        counters = counters * sizes[:, None]
    # one reduction for every column (one row: its values)
    totals = counters[0].tolist() if counters.shape[0] == 1 else counters.sum(axis=0).tolist()
    return {name: int(totals[col]) for name, col in columns.items()}


class Method:
    """Base class of integration methods (the subclass contract).

    Class attributes
    ----------------
    name : str
        Registry name (``method=`` of :func:`orbatt.propagate`).
    aliases : tuple of str
        Other registry names.
    order : int
        Order of convergence (0 for a closed-form solution).
    closed_form : bool
        Evaluates the exact solution at the output times instead of stepping (``"exact"``):
        no ``step`` needed; ``rtol``, ``atol``, ``step`` and ``max_steps`` are checked but
        do not change the result.
    adaptive : bool
        Step size chosen from ``rtol``/``atol`` (True) or fixed ``step`` (False).
    symplectic : bool
    compiled : bool
        Whole step loop compiled (False: Python step loop).
    extended : bool
        Takes extended models (reaction wheels, control laws: states wider than 8 and
        right-hand sides that read the body rate); the others refuse them.
    options : dict
        Extra keyword options accepted (name -> description).
    description : str

    Life cycle (called by :func:`orbatt.propagate`, which has validated every argument):

    1. ``__init__(rtol=, atol=, step=, max_steps=, **options)``: check the options
       (raise :class:`~orbatt.errors.InputError` naming them);
    2. :meth:`start` (``problem``, a :class:`~orbatt.methods.problem.Problem`): keep the
       problem as ``self.p`` (``super().start(problem)`` does it) and allocate the
       per-member state;
    3. :meth:`advance` (``budget``) until it returns True: at most ``budget`` step attempts
       per member per call; raise :class:`~orbatt.errors.IntegrationError` (with ``t``)
       when a member cannot continue - :meth:`check_status` and :meth:`fail` do it from the
       kernels' status codes;
    4. :meth:`outputs` -> ``(t, Y)``: the first ``n`` outputs of every member,
       ``Y (E, n, 8)``, and the times ``t (n,)`` - callable at any point (partial results);
       :meth:`stats` -> dict; :meth:`time_reached` -> float (slowest member).
    """

    name = ""
    aliases: tuple = ()
    order = 0
    closed_form = False
    adaptive = False
    symplectic = False
    compiled = True
    extended = False
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
        """The settings recorded with the result (``Trajectory.settings``)."""
        if self.closed_form:
            return {"closed_form": True, **self.opts}
        s = {"order": self.order, "max_steps": self.max_steps}
        if self.adaptive:
            s.update(rtol=self.rtol, atol=self.atol)
            if self.step is not None:
                s["first_step"] = self.step
        else:
            s["step"] = self.step
        s.update(self.opts)
        return s

    def start(self, problem: Problem):
        """Keep ``problem`` as ``self.p``; subclasses then allocate their state."""
        self.p = problem

    def advance(self, budget: int) -> bool:  # pragma: no cover - abstract
        raise NotImplementedError

    def outputs(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def stats(self) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def time_reached(self) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    # --- failure handling, shared by every driver

    def failure_point(self, i: int):
        """``(t, member)`` where entry ``i`` of the status array :meth:`check_status` was
        given has stopped (drivers whose status entries are not members override it)."""
        raise NotImplementedError  # pragma: no cover - abstract

    def check_status(self, status: np.ndarray) -> bool:
        """After a compiled call: raise for the first entry of ``status`` (kernel status
        codes, one per member or group) that failed, else return whether all are done."""
        if status.shape[0] == 1:  # one member or group: the same tests on a Python int
            code = int(status[0])
            if code != kd.DONE and code != kd.PAUSED:
                self.fail(code, *self.failure_point(0))
            return code == kd.DONE
        bad = np.flatnonzero((status != kd.DONE) & (status != kd.PAUSED))
        if bad.size:
            i = int(bad[0])
            t, member = self.failure_point(i)
            self.fail(int(status[i]), t, member)
        return bool(np.all(status == kd.DONE))

    def fail(self, status: int, t: float, member: int):
        """Raise the :class:`~orbatt.errors.IntegrationError` for kernel status ``status``
        of ``member`` at time ``t``."""
        where = f" (ensemble member {member})" if self.p.ensemble else ""
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

"""The :class:`Problem` every integration method receives, and the checks that build it
from the arguments of :func:`orbatt.propagate` (body, initial state, potential, times,
method settings). Every check raises :class:`~orbatt.errors.InputError` quoting the
argument, before any integration.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import canonical as cn
from .. import units as U
from ..body import RigidBody
from ..core import model as km
from ..core.dop853 import NDIM
from ..errors import InputError
from ..model_assembly import KernelSpec, assemble
from ..state import State

__all__ = ["Problem", "KernelSpec", "kernel_spec", "check_extended", "bodies_of", "initial_states", "time_span", "method_settings",
           "output_times", "DEFAULT_MAX_STEPS", "MIN_RTOL", "MAX_RTOL", "MAX_ATOL"]

#: default limit on step attempts (per ensemble member)
DEFAULT_MAX_STEPS = 100_000_000
#: smallest rtol accepted (10 machine epsilons, as in Hairer's dop853)
MIN_RTOL = 10.0 * np.finfo(np.float64).eps
#: largest rtol accepted: a relative error above 10% per step gives no accuracy at all
MAX_RTOL = 0.1
#: largest atol accepted: the quaternion has |q| = 1, so an absolute error above 1 leaves the
#: attitude uncontrolled (the momentum is controlled by rtol; give atol in its unit below 1)
MAX_ATOL = 1.0


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
        Initial ``(q, Q)`` of each member (``S`` <- ``B`` attitude; momentum in the body's
        units).
    inertia : ndarray (E, 3)
        Principal moments of each member.
    kernel : KernelSpec
        The compiled model (``terms``, ``params``, ``table``; the same names are properties
        of the problem).
    ensemble : bool
        Whether the caller asked for an ensemble (outputs get a leading member axis).
    """

    t0: float
    t_out: np.ndarray
    step_ends: bool
    y0: np.ndarray
    inertia: np.ndarray
    kernel: KernelSpec
    ensemble: bool

    @property
    def members(self) -> int:
        return self.y0.shape[0]

    @property
    def t_end(self) -> float:
        return float(self.t_out[-1])

    @property
    def terms(self) -> np.ndarray:
        return self.kernel.terms

    @property
    def torque_free(self) -> bool:
        """Whether no term acts on the body (an empty model)."""
        return self.kernel.terms.shape[0] == 1

    @property
    def params(self) -> np.ndarray:
        return self.kernel.params

    @property
    def table(self) -> np.ndarray:
        return self.kernel.table


# ---------------------------------------------------------------------------------------
# Checks of the arguments of propagate(), in the order propagate() applies them


def bodies_of(body):
    """``(bodies, ensemble)``: the list of :class:`~orbatt.body.RigidBody` and whether a list
    was given (an ensemble over bodies, all dimensional or all dimensionless)."""
    if isinstance(body, RigidBody):
        return [body], False
    if isinstance(body, (list, tuple)) and body and all(isinstance(b, RigidBody) for b in body):
        if len({b.dimensionless for b in body}) != 1:
            raise InputError("body: an ensemble of bodies must be all dimensional or all dimensionless")
        return list(body), True
    raise InputError(f"body: expected a RigidBody or a non-empty list of RigidBody, got {type(body).__name__}")


def initial_states(state0, bodies):
    """``(y0 (E, 8), inertia (E, 3), state_ensemble)``: the initial ``(q, Q)`` and the moments
    of every member, ``state0`` broadcast against ``bodies`` (fresh C-contiguous arrays)."""
    b0 = bodies[0]
    if not isinstance(state0, State):
        raise InputError(f"state0: expected an orbatt.State, got {type(state0).__name__}; build one with "
                         "State(body, q, Q), State.from_omega or State.from_momentum")
    if state0.body.dimensionless != b0.dimensionless:
        raise InputError("state0: built for a body with different units (dimensional vs dimensionless) than body")
    y = np.asarray(state0.y, dtype=np.float64)
    if not (all(map(math.isfinite, y.ravel().tolist())) if y.size <= 64 else np.isfinite(y).all()):
        raise InputError(f"state0: contains non-finite values (q = {state0.q!r}, Q = {state0.Q!r})")
    if y.ndim > 2:
        raise InputError(f"state0: an ensemble state must have q of shape (E, 4), got {state0.q.shape}")
    state_ensemble = y.ndim == 2
    y = y[None] if y.ndim == 1 else y  # np.atleast_2d
    E = max(len(bodies), y.shape[0])
    if len(bodies) not in (1, E) or y.shape[0] not in (1, E):
        raise InputError(f"body/state0: {len(bodies)} bodies and {y.shape[0]} initial states do not broadcast to "
                         "one ensemble (give one of each, or N bodies and N states, or one and N)")
    # fresh C-contiguous copies (a broadcast only where one side is a single member)
    y0 = np.array(y if y.shape[0] == E else np.broadcast_to(y, (E, NDIM)), dtype=np.float64, order="C")
    inertia = np.array([b.inertia_value for b in bodies], dtype=np.float64)
    if inertia.shape[0] != E:
        inertia = np.array(np.broadcast_to(inertia, (E, 3)), order="C")
    wheels = b0.wheels
    if any(b.wheels != wheels for b in bodies):
        raise InputError("body: the members of an ensemble must have the same reaction wheels")
    if state0.body.wheels != wheels:
        raise InputError("state0: built for a body with other reaction wheels than body (Q holds the wheels' "
                         "momentum); build it with State.from_omega(body, ...)")
    if wheels:  # the gyrostat's state (q, Q, h): the wheels' axial momenta from the body rate
        g = cn.body_momentum(y0[:, :4], y0[:, 4:])
        omega = (g - b0.rotor_momentum) / inertia
        y0 = np.ascontiguousarray(np.hstack([y0, np.array([b0.wheel_momenta(w) for w in omega])]))
    return y0, inertia, state_ensemble


def kernel_spec(potential, bodies, control=None) -> KernelSpec:
    """The :class:`KernelSpec` of ``potential`` acting on ``bodies`` under the control law
    ``control`` (or the one the potential carries): the one assembler,
    :func:`orbatt.model_assembly.assemble` (the potential's orbit and terms, the wheels, the
    control law)."""
    return assemble(potential, bodies, control)


def check_extended(cls, kernel):
    """Refuse a method that cannot run an extended model (wheels, control laws)."""
    if (kernel.terms[0, km.FLAGS] & km.EXTENDED) and not cls.extended:
        raise InputError(f"method: {cls.name!r} cannot integrate reaction wheels or a control law (the body rate "
                         "enters the right-hand side, and the wheels' momenta the state); use method = 'dop853'")


def _times(value, name, body):
    if value is None:
        return None
    v = U.strip(value, body.time_unit, name, allow_plain=True)
    return np.atleast_1d(np.asarray(v, dtype=np.float64))


def time_span(t, t_span, body, potential):
    """``(t0, t_end, tv)``: start and end of the propagation and the output times ``tv``
    (None in ``t_span`` mode), in ``body``'s time unit, checked against each other and
    against the potential's ``time_span`` (where it has one, e.g. a sampled orbit)."""
    tv = _times(t, "t", body)
    span = _times(t_span, "t_span", body)
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
        d = tv[1:] - tv[:-1]  # (np.diff's overhead is most of the cost for a few times)
        if not (d > 0).all():
            i = int(np.flatnonzero(d <= 0)[0])
            raise InputError(f"t: output times must increase strictly; t[{i + 1}] = {float(tv[i + 1])!r} follows "
                             f"t[{i}] = {float(tv[i])!r} (orbatt integrates forward in time)")
        if span is not None and (tv[0] < span[0] or tv[-1] > span[1]):
            raise InputError(f"t: the output times [{float(tv[0])!r} .. {float(tv[-1])!r}] leave t_span = "
                             f"({float(span[0])!r}, {float(span[1])!r})")
    t0 = float(span[0]) if span is not None else float(tv[0])
    t_end = float(span[1]) if span is not None else float(tv[-1])
    valid = getattr(potential, "time_span", None)
    if valid is not None and (t0 < valid[0] or t_end > valid[1]):
        raise InputError(f"t: the propagation [{t0!r}, {t_end!r}] leaves the span {[float(v) for v in valid]} of "
                         "the sampled orbit; build the orbit over a longer span")
    return t0, t_end, tv


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


def method_settings(cls, rtol, atol, step, max_steps, body):
    """``(rtol, atol, step, max_steps)`` checked for the method class ``cls``: plain floats,
    ``step`` in ``body``'s time unit (None for an adaptive method without a first step),
    ``max_steps`` an int (default :data:`DEFAULT_MAX_STEPS`)."""
    rtol = _positive(rtol, "rtol")
    atol = _positive(atol, "atol", allow_zero=True)
    if cls.adaptive and rtol < MIN_RTOL:
        raise InputError(f"rtol: {rtol!r} is below {MIN_RTOL:.3g} (10 machine epsilons); float64 cannot deliver it")
    if rtol > MAX_RTOL:
        raise InputError(f"rtol: {rtol!r} is above {MAX_RTOL:g}: a relative error above 10% per step gives no "
                         "accuracy at all; give e.g. rtol=1e-10")
    if atol > MAX_ATOL:
        raise InputError(f"atol: {atol!r} is above {MAX_ATOL:g}: |q| = 1, so an absolute error above 1 leaves the "
                         "attitude uncontrolled; give e.g. atol=1e-12")
    stepv = None
    if step is not None:
        stepv = _positive(step, "step", body, unit=body.time_unit)
    elif not cls.adaptive and not cls.closed_form:
        raise InputError(f"step: method {cls.name!r} has a fixed step; give step= (e.g. a few seconds for an "
                         "orbiting body, 1e-2 of a rotation period in general)")
    if max_steps is None:
        max_steps = DEFAULT_MAX_STEPS
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps <= 0:
        raise InputError(f"max_steps: {max_steps!r} is not a positive integer")
    return rtol, atol, stepv, int(max_steps)


def output_times(cls, t0, t_end, tv, step, max_steps, ensemble):
    """``(t_out, step_ends)``: the output times the method gets. Without output times
    ``tv`` (``t_span`` mode), adaptive methods record every step end (``t_out = [t0, t_end]``,
    ``step_ends`` True; not for ensembles) and fixed-step methods output the grid
    ``t0 + k step`` and ``t_end``. Fixed-step methods must reach the end in ``max_steps``.
    Closed-form methods output ``[t0, t_end]``, or the grid of ``step`` where one is given."""
    step_ends = False
    if tv is None:
        if cls.closed_form and step is None:
            t_out = np.array([t0, t_end])
        elif cls.adaptive:
            if ensemble:
                raise InputError("t_span: an ensemble has no common step grid; give output times t (e.g. "
                                 "t=[t0, t_end])")
            t_out = np.array([t0, t_end])
            step_ends = True
        else:
            n = int(math.floor((t_end - t0) / step))
            if n + 1 > 50_000_000:
                raise InputError(f"t_span: {n} steps of {step!r} would all be outputs; give output times t")
            grid = t0 + np.arange(n + 1) * step
            # the grid, then t_end (a grid point within rounding of t_end is t_end)
            grid = grid[grid < t_end - 8 * np.finfo(float).eps * max(abs(t_end), abs(t0))]
            t_out = np.concatenate([grid, [t_end]])
    else:
        t_out = tv
    if not cls.adaptive and not cls.closed_form:
        n_needed = math.ceil((float(t_out[-1]) - t0) / step - 1e-9)
        if n_needed > max_steps:
            raise InputError(f"step: {step!r} needs {n_needed} steps to reach {float(t_out[-1])!r}, more than "
                             f"max_steps = {max_steps}")
    return np.ascontiguousarray(t_out, dtype=np.float64), step_ends

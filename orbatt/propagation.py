"""The one entry point, :func:`propagate` (also ``orbatt.propagate``): validation of the
inputs (:mod:`orbatt.methods.problem`), then the run loop.

Every method (:mod:`orbatt.methods`; :data:`METHODS` lists them, :func:`methods` describes
them) takes the same inputs (a body or bodies, a :class:`~orbatt.state.State`, a
:class:`~orbatt.potentials.Potential`, output times) and returns the same
:class:`~orbatt.trajectory.Trajectory` (times, ``q``, ``Q``, and the statistics ``steps``,
``rhs_evaluations`` or ``kicks``, ``rejected_steps``, ``wall_time_s``).

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
The compiled loops run in chunks of about 0.25 s (:data:`CHUNK_SECONDS`); between chunks
``progress`` is called and a KeyboardInterrupt (Ctrl-C) is honoured: the result then holds
the outputs computed so far and ``complete=False``. Resuming a chunked run is exact (results
do not depend on the chunking).
"""
from __future__ import annotations

import time

import numpy as np

from .core import INTERPRETED
from .errors import InputError, IntegrationError
from .frame_boundary import body_trajectory, principal_run
from .model_assembly import control_of, controller_start
from .methods import METHODS, Method, methods, register
from .methods.base import resolve_method
from .methods.problem import (DEFAULT_MAX_STEPS, MIN_RTOL, Problem, bodies_of, check_extended, initial_states,
                              kernel_spec,
                              method_settings, output_times, time_span)
from .progress import ProgressInfo, progress_callback
from .trajectory import Trajectory

__all__ = ["propagate", "Method", "METHODS", "methods", "register", "ProgressInfo", "Problem", "DEFAULT_MAX_STEPS",
           "MIN_RTOL", "CHUNK_SECONDS"]

#: target wall time of one compiled call between progress reports / interrupt checks
CHUNK_SECONDS = 0.25


def propagate(body, state0, potential, t=None, *, t_span=None, method="dop853", rtol=1e-10, atol=1e-12,
              step=None, progress=None, max_steps=None, control=None, **options) -> Trajectory:
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
        object with the kernel specification ``kind``, ``params``, ``table`` (and optionally
        ``time_span``, the times it is defined at).
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
    control : PDControl or BDotControl, optional
        A control law in the loop, beside the potential (:mod:`orbatt.control`): it reads the
        potential's orbit (a PD law's orbital target) and the fields the potential samples along
        it (the Sun for ``target = "sun"``, the magnetic field for B-dot:
        :class:`orbatt.EnvironmentTorques` with ``magnetic_field=``). An inertial PD target
        needs no orbit (``TorqueFree()`` will do). The law may instead ride with the potential
        (``EnvironmentTorques(control=)``), not both. Needs an adaptive method.
    **options
        Method options (``max_step`` for adaptive methods, ``independent_variable`` for
        ``"dop853"`` and ``"dop853-lanes"``, ``kinetic`` for splitting).

    Returns
    -------
    Trajectory
        ``t (N,)``, ``q``/``Q`` ``(N, 4)`` or ``(E, N, 4)`` for ensembles, ``stats``
        (``steps``, ``rejected_steps``, ``rhs_evaluations`` or ``kicks``, ``wall_time_s``,
        ``members``; the compiled Runge-Kutta methods also ``switch_retakes``: trial steps
        retaken to end on a torque's switch, :mod:`orbatt.core.switches`), ``settings``, ``complete`` (False after a KeyboardInterrupt or a stop
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
    cls = resolve_method(method)
    user = (body, potential, control_of(potential, control))
    # a body given by a full inertia tensor runs in its principal frame (orbatt.frame_boundary)
    frame, body, state0, potential, control = principal_run(body, state0, potential,
                                                            None if user[2] is getattr(potential, "control", None)
                                                            else user[2])
    bodies, body_ensemble = bodies_of(body)
    y0, inertia, state_ensemble = initial_states(state0, bodies)
    ensemble = body_ensemble or state_ensemble
    control = control_of(potential, control)
    kernel = kernel_spec(potential, bodies, control)
    check_extended(cls, kernel)
    z0 = controller_start(kernel)
    nz = z0.size
    y0, z0, resume = _continued(state0, y0, z0)
    if nz:  # the controllers' states (held commands, integrals, modes), issued at the driver's first tick
        if not getattr(cls, "ticks", False):
            raise InputError(f"method: {cls.name!r} cannot run a control law with a flight-software period or an "
                             "integral (their states are knots and components of the compiled step loop); use "
                             "method = 'dop853' or 'vern98'")
        y0 = np.ascontiguousarray(np.hstack([y0, np.broadcast_to(z0, (y0.shape[0], nz))]))
    t0, t_end, tv = time_span(t, t_span, bodies[0], potential)
    if resume is not None and t0 != state0.t:
        raise InputError(f"t: the run starts at {t0!r} and state0 is the state at {state0.t!r}; continue a run from "
                         "the time of its state (t[0] = state0.t)")
    rtol, atol, stepv, max_steps = method_settings(cls, rtol, atol, step, max_steps, bodies[0])
    progress = progress_callback(progress)
    t_out, step_ends = output_times(cls, t0, t_end, tv, stepv, max_steps, ensemble)
    problem = Problem(t0=t0, t_out=t_out, step_ends=step_ends, y0=y0, inertia=inertia, kernel=kernel,
                      ensemble=ensemble)
    m = cls(rtol=rtol, atol=atol, step=stepv, max_steps=max_steps, **options)
    if resume is not None and hasattr(m, "resume"):
        m.resume = resume
    m.start(problem)

    def result(complete, reason, wall):
        tt, Y = m.outputs()
        stats = dict(m.stats())
        stats["wall_time_s"] = wall
        stats["members"] = problem.members
        if reason:
            stats["stopped"] = reason
        if not ensemble:
            Y = Y[0]
        nw = Y.shape[-1] - 8 - nz
        return Trajectory(body=bodies[0], potential=potential, control=control, t=np.array(tt, dtype=np.float64),
                          q=np.ascontiguousarray(Y[..., :4]), Q=np.ascontiguousarray(Y[..., 4:8]),
                          wheel_momenta=np.ascontiguousarray(Y[..., 8:8 + nw]) if nw else None,
                          command=np.ascontiguousarray(Y[..., 8 + nw:]) if nz else None,
                          inertia=inertia if body_ensemble else inertia[0].copy(), method=m.name,
                          settings=m.settings(), stats=stats, complete=complete,
                          continuation=_continuation(m, complete, resume))

    user_body = user[0][0] if isinstance(user[0], (list, tuple)) else user[0]
    return _run_chunks(m, problem, progress, lambda *a: body_trajectory(result(*a), frame, user_body, *user[1:]))


def _continued(state0, y0, z0):
    """``(y0, z0, resume)``: the initial states and the flight software's initial state of a
    run, and what its method needs to continue the run ``state0`` comes from (None for a new
    run): a :class:`~orbatt.state.State` with a time (:meth:`~orbatt.state.State.continuing`)
    brings the wheels' momenta and the flight software's state ``z`` (after the tick at its
    time, if one: no tick at the start), the tick grid's origin and the step controller's
    memory."""
    if getattr(state0, "t", None) is None:
        return y0, z0, None
    h, z = state0.wheel_momenta, state0.command
    if h is not None:
        if h.shape[-1] != y0.shape[1] - 8:
            raise InputError(f"state0: holds {h.shape[-1]} wheels' momenta and the body has {y0.shape[1] - 8} wheels; "
                             "continue a run with the body it was run with")
        y0[:, 8:] = h
    if z is not None and z.shape[-1] != z0.size:
        raise InputError(f"state0: holds {z.shape[-1]} components of the flight software's state and this model "
                         f"has {z0.size}; continue a run with the control law it was run with (a state that an "
                         "earlier orbatt saved, e.g. a file's `continuation`, may be laid out otherwise: a mode "
                         "sequence now keeps each mode's entry time; then run the scenario whole)")
    carried = z is not None and z.size > 0
    return y0, (z if carried else z0), {"commands": carried, "phase": state0.phase, "stepper": state0.stepper}


def _continuation(m, complete, resume):
    """What :meth:`orbatt.trajectory.Trajectory.state` needs besides the outputs: the tick
    grid (``period``, ``phase``) and, after a complete run, the step controller's memory at its
    end (methods that keep one: :meth:`orbatt.methods.dop853.DOP853.stepper`)."""
    grid = m.tick_grid() if hasattr(m, "tick_grid") else None
    stepper = m.stepper() if complete and hasattr(m, "stepper") else None
    period, phase = grid if grid is not None else (None, None)
    return {"period": period, "phase": phase, "stepper": stepper}


def _run_chunks(m: Method, problem: Problem, progress, result) -> Trajectory:
    """Call ``m.advance`` in compiled chunks of about :data:`CHUNK_SECONDS` until it is done,
    reporting to ``progress`` (None or a callable taking :class:`ProgressInfo`) between
    chunks, and return ``result(complete, stop_reason, wall_time_s)``.

    A KeyboardInterrupt or a progress callback returning False stops the run early
    (``complete`` False); an :class:`~orbatt.errors.IntegrationError` (also one made from a
    ValueError or ArithmeticError raised in a kernel) gets the partial result as its
    ``trajectory``.
    """
    E = problem.members
    complete, stop_reason = True, None
    # first call: small (a quick first progress report, an early check of the speed), then
    # sized to take about CHUNK_SECONDS
    budget = max(16, 200_000 // E) if E > 1 else 5_000
    if not m.compiled:
        budget = 2_000
    if INTERPRETED:  # kernels running as Python (orbatt.coldstart): ~1000x slower per step
        budget = 20
    start = time.perf_counter()

    def finish(complete, reason):
        return result(complete, reason, time.perf_counter() - start)

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
                span_len = problem.t_end - problem.t0
                frac = 1.0 if done else min(1.0, max(0.0, (tr - problem.t0) / span_len)) if span_len > 0 else 1.0
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

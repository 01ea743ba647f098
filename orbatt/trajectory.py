"""What a propagation returns before it becomes a Dataset: plain arrays plus provenance."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .body import RigidBody
from .potentials import Potential
from .state import State


@dataclass
class Trajectory:
    """Result of :func:`orbatt.propagate` (plain floats in the body's internal units).

    Attributes
    ----------
    body : RigidBody
        The body (for an ensemble over bodies: the first one; see ``inertia``).
    potential : Potential
        What acted on it (its ``orbit`` attribute, if any, is the orbit provider).
    t : ndarray (N,)
        Output times since the epoch (s, or dimensionless).
    q, Q : ndarray (N, 4) or (E, N, 4)
        Attitude (body -> space, scalar first) and conjugate momentum at ``t``; a leading
        ensemble axis ``E`` for ensembles.
    inertia : ndarray (3,) or (E, 3)
        Principal moments used (internal unit).
    method : str
        Integration method name.
    settings : dict
        The method's settings (rtol, atol, step, order, ...), plain values.
    stats : dict
        ``steps``, ``rhs_evaluations`` (or ``kicks``), ``rejected_steps``, ``wall_time_s`` (and
        ``switch_retakes`` for the compiled Runge-Kutta methods).
    complete : bool
        False if the run was interrupted (KeyboardInterrupt): ``t, q, Q`` then hold what was
        computed.
    wheel_momenta : ndarray (N, n) or (E, N, n), or None
        The reaction wheels' axial momenta ``h`` (kg km^2/s) of a body with wheels.
    command : ndarray (N, nz) or (E, N, nz), or None
        The commands the flight software holds (a law with a ``period``, issue 32), in kernel
        units: the PD law's torque (3) or its wheels' motor torques (one per wheel), B-dot's
        dipole (3); at an output time on a tick, the command issued there.
    control : PDControl or BDotControl, or None
        The control law in the loop (given to :func:`orbatt.propagate` beside the potential,
        or carried by it: :func:`orbatt.model_assembly.control_of`).
    continuation : dict or None
        What :meth:`state` needs besides the outputs to continue the run: the tick grid
        (``period``, ``phase``; None without one) and the step controller's memory at the end of
        a complete run (``stepper``; None where the method keeps none).
    """

    body: RigidBody
    potential: Potential
    t: np.ndarray
    q: np.ndarray
    Q: np.ndarray
    inertia: np.ndarray
    method: str
    settings: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    complete: bool = True
    wheel_momenta: np.ndarray = None
    control: object = None
    command: np.ndarray = None
    continuation: dict = None

    def __post_init__(self):
        if self.control is None:  # a law the potential carries (EnvironmentTorques(control=))
            self.control = getattr(self.potential, "control", None)

    @property
    def extended(self):
        """The state after ``Q`` (the kernels' ``y[8:]``): the wheels' momenta, then the held
        commands, as one array ``(..., N, n + nz)``; None for a rigid body without them."""
        parts = [x for x in (self.wheel_momenta, self.command) if x is not None]
        if not parts:
            return None
        return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=-1)

    def state(self, i=-1):
        """The :class:`~orbatt.state.State` at output ``i`` (default the last) to continue the run
        from with :func:`orbatt.propagate` (``t[0]`` = its time): ``q``, ``Q``, the wheels'
        momenta and the flight software's state bit for bit, the tick grid, and at the last
        output of a complete run the step controller's memory, so that the continued run gives
        this run's outputs bit for bit (:meth:`orbatt.state.State.of_trajectory`)."""
        return State.of_trajectory(self, i)

    @property
    def orbit(self):
        """The orbit provider driving the potential, or None."""
        return getattr(self.potential, "orbit", None)

    @property
    def is_ensemble(self) -> bool:
        return self.q.ndim == 3

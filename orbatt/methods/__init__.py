"""Integration methods: the :class:`Method` base class and registry (:mod:`.base`), the
:class:`Problem` every method receives (:mod:`.problem`), and the drivers.

Every method takes the same :class:`Problem` and gives :func:`orbatt.propagate` the same
outputs (times, ``(q, Q)``, and the statistics ``steps``, ``rhs_evaluations`` or ``kicks``,
``rejected_steps``).

Methods (``method=``; :data:`METHODS` lists them, :func:`methods` describes them)
--------------------------------------------------------------------------------
``"dop853"`` (default; :mod:`.dop853`)
    Adaptive Dormand-Prince 8(5,3) with Hairer's error estimate and step-size control
    (:mod:`orbatt.core.dop853`), the whole step loop compiled. ``rtol``/``atol`` mean what
    they mean in :func:`scipy.integrate.solve_ivp`. Outputs are step-end values: the
    integrator lands on every output time (no interpolation). On a Keplerian orbit it
    integrates in the eccentric anomaly (option ``independent_variable``, default
    ``"auto"``; ``"time"`` gives 0.1.0's numbers): the orbit is closed-form at every stage,
    half the time of the time form at the same accuracy.
``"vern98"`` (:mod:`.dop853`)
    Verner's 9(8) pair (16 stages, no FSAL) in the same compiled loop and options as
    ``"dop853"`` (also wheels and control laws; ensembles member by member, bitwise as alone). On the
    Keplerian benchmark at 1e-9 rad ~15-20 % less time than ``"dop853"``, ~10 % at 1e-6 rad;
    ~10 % slower on the torque-free body (``benchmarks/verner98.py``).
``"dopri5"`` (:mod:`.dop853`)
    Dormand-Prince 5(4) (7 stages, FSAL) in the same compiled loop and options as ``"dop853"``.
    For flight software at a dense period (``[control] period``), where one step per tick meets
    the tolerance anyway: 7 right-hand-side evaluations per tick against 12 of ``"dop853"`` at
    10 Hz (``benchmarks/tick_stepping.py``); without ticks ``"dop853"`` is the faster (2.6x fewer
    evaluations on the Keplerian case at rtol 1e-10).
``"bs32"`` (:mod:`.dop853`)
    Bogacki-Shampine 3(2) (4 stages, FSAL) in the same compiled loop and options as ``"dop853"``.
    For flight software at a period so dense that one step of order 3 per tick meets the
    tolerance: 3 right-hand sides per tick against 12 of ``"dop853"`` on the 10 Hz LVLH hold
    (``benchmarks/basilisk_fsw.py``); far slower than ``"dop853"`` without ticks or at tight
    tolerances.
``"dop853-lanes"`` (:mod:`.dop853`)
    For ensembles: DOP853 on groups of ``lanes`` members (default 32) that share the step
    size (controlled by the group's largest error) and the orbit evaluation, with the
    per-member arithmetic vectorized. 5-10x the throughput of ``"dop853"`` on ensembles;
    each member is at least as accurate as alone, but results are not bitwise those of
    one-by-one runs. Rigid bodies and extended models (wheels, control laws): the same compiled
    step loop as ``"dop853"`` (:mod:`orbatt.core.rk_loop`), instantiated for a group of lanes.
``"vern98-lanes"``, ``"dopri5-lanes"``, ``"bs32-lanes"`` (:mod:`.dop853`)
    ``"dop853-lanes"`` with Verner's 9(8) pair, with Dormand-Prince 5(4), with Bogacki-Shampine 3(2).
``"splitting2"``, ``"splitting4"``, ``"splitting6"`` (and named variants; :mod:`.fixed_step`)
    Symplectic splitting (:mod:`orbatt.core.splitting`), fixed ``step``: Strang (order 2),
    McLachlan's 5-stage composition (order 4; ``"splitting4-yoshida"``,
    ``"splitting4-suzuki"`` are the alternatives), Kahan & Li's 9-stage composition (order
    6; ``"splitting6-yoshida"``). Keep ``|q| = 1`` and ``q.Q = 0`` to round-off and, for
    autonomous potentials, a bounded energy error over any number of steps. They are the
    tool for long runs and ensembles, not for short high-accuracy runs: for the paper's
    Keplerian case (10 orbits, 1e-9 rad) they need 6x (order 6) to 18x (order 4) the time of
    ``"dop853"`` (``benchmarks/README.md``).
``"rk4"`` (:mod:`.fixed_step`)
    Classical fixed-step Runge-Kutta 4, compiled; a baseline.
``"scipy-DOP853"``, ``"scipy-RK45"``, ``"scipy-RK23"``, ``"scipy-Radau"``, ``"scipy-BDF"``, ``"scipy-LSODA"`` (:mod:`.scipy_ivp`)
    The reference path: scipy's solvers (Python step loop) on the compiled right-hand side,
    restarted at every output time so that outputs are step-end values too.
``"exact"`` (:mod:`.exact`)
    The torque-free rigid body in closed form (Jacobi elliptic functions,
    :mod:`orbatt.analytic`), evaluated at the output times: no steps, round-off accuracy
    at any time span. Torque-free problems only (``orbatt.TorqueFree()``, no torques, control
    or wheels; others are refused); ensembles supported. ``rtol``/``atol`` are checked but
    unused; ``step`` is not needed (in ``t_span`` mode it sets the output grid).

Writing a method: see :class:`Method` (the subclass contract) and :func:`register`.
"""
from __future__ import annotations

from .base import METHODS, Method, methods, register, resolve_method
from .dop853 import DOP853, DOP853Lanes, Bs32, Bs32Lanes, Dopri5, Dopri5Lanes, Vern98, Vern98Lanes
from .exact import Exact
from .fixed_step import RK4, FixedStep, Splitting
from .problem import KernelSpec, Problem
from .scipy_ivp import Scipy

__all__ = ["Method", "METHODS", "methods", "register", "resolve_method", "Problem", "KernelSpec", "DOP853",
           "DOP853Lanes", "Vern98", "Vern98Lanes", "Dopri5", "Dopri5Lanes", "Bs32", "Bs32Lanes", "Exact", "FixedStep", "RK4", "Splitting",
           "Scipy"]

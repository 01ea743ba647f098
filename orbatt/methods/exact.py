"""``"exact"``: the torque-free rigid body in closed form (Euler-Poinsot motion in Jacobi
elliptic functions, :mod:`orbatt.analytic`), evaluated at the output times instead of
integrated.

What it takes
-------------
Only torque-free problems: the potential ``orbatt.TorqueFree()`` (kind ``"torque-free"``)
with no term acting on the body - no heavy top, gravity gradient, environment torques,
control law or reaction wheels (each is refused with an :class:`~orbatt.errors.InputError`
naming it; use ``"dop853"`` there). An orbit without terms is accepted (it does not act on
the body). Ensembles over bodies and initial states are supported (each member is solved
on its own; results are bitwise those of one-by-one runs).

Settings
--------
There is nothing to converge: ``rtol``, ``atol`` and ``max_steps`` are checked like for any
method (so a scenario file's ``[integration]`` settings stay valid) but do not change the
result, and are not recorded in the settings. ``step`` is not needed; in ``t_span`` mode
without output times it sets the output grid ``t0 + k step`` (as for fixed-step methods),
else the outputs are ``t0`` and ``t_end``. The statistics count no steps and no right-hand
side evaluations (``steps = rhs_evaluations = rejected_steps = 0``) and give
``evaluations``, the number of (member, output time) pairs evaluated.

Accuracy and cost
-----------------
Those of :mod:`orbatt.analytic` (about ``4e-15`` for ``|t| <= 30``; the phase error grows as
``eps |lambda t|``), evaluated by the compiled kernels of :mod:`orbatt.core.free_body`: about
2 us per member, then 0.6-1 us per output time, whatever the time span (an integrator's cost
grows with it). Next to the separatrix (a spin about the intermediate axis) the motion itself
is ill-conditioned: the result is the exact motion of the initial state as given.
"""
from __future__ import annotations

import numpy as np

from ..core import free_body as fb
from ..core import model as km
from ..errors import InputError
from .base import Method, register

__all__ = ["Exact"]


def check_torque_free(name, terms):
    """Refuse a model with any term acting on the body (:class:`InputError`)."""
    if terms.shape[0] == 1:
        return
    acting = [km.KIND_DESCRIPTIONS.get(int(k), f"term kind {int(k)}") for k in terms[1:, km.KIND]]
    raise InputError(f"potential: method {name!r} solves only the torque-free rigid body (potential kind "
                     f"'torque-free', no torques, control or wheels), but {', '.join(acting)} "
                     f"act{'s' if len(acting) == 1 else ''} on the body here; use method = 'dop853' (or "
                     "another integrator), or potential 'torque-free'")


@register
class Exact(Method):
    """The torque-free rigid body in closed form (:mod:`orbatt.analytic`), evaluated at the
    output times; refuses every other problem."""

    name = "exact"
    closed_form = True
    description = ("closed-form torque-free rigid body (Jacobi elliptic functions, orbatt.analytic): no steps, "
                   "round-off accuracy; torque-free problems only")

    def start(self, problem):
        check_torque_free(self.name, problem.terms)
        super().start(problem)
        p = problem
        E = p.members
        self.out = np.empty((E, p.t_out.shape[0], p.y0.shape[1]))
        self.C = np.empty((E, fb.NC))
        if E == 1:
            fb.motion(p.inertia[0], p.y0[0], self.C[0])
            ok = self.C[0, fb.RHO2] > 0.0
        else:
            fb.motion_batch(p.inertia, p.y0, self.C)
            ok = (self.C[:, fb.RHO2] > 0.0).all()
        if not ok:  # (State refuses it; a hand-made Problem may not)
            raise InputError("state0: the zero quaternion is not an attitude; give a unit quaternion q "
                             "(scalar first)")
        self.done = 0  # outputs evaluated (every member)

    def advance(self, budget):
        """Evaluate up to ``budget`` further output times of every member."""
        p = self.p
        n = p.t_out.shape[0]
        stop = min(n, self.done + max(int(budget), 1))
        t = p.t_out[self.done:stop]
        if p.members == 1:
            fb.evaluate(self.C[0], p.y0[0], p.t0, t, self.out[0, self.done:stop])
        else:
            fb.evaluate_batch(self.C, p.y0, p.t0, t, self.out[:, self.done:stop])
        self.done = stop
        return stop == n

    def outputs(self):
        return self.p.t_out[:self.done], self.out[:, :self.done]

    def stats(self):
        return {"steps": 0, "rejected_steps": 0, "rhs_evaluations": 0,
                "evaluations": int(self.done * self.p.members)}

    def time_reached(self):
        return float(self.p.t_out[self.done - 1]) if self.done else self.p.t0

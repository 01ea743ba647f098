"""The reference path: scipy's ODE solvers (:mod:`scipy.integrate`, the classes behind
``solve_ivp``) on the compiled right-hand side (:func:`orbatt.core.hamiltonian.rhs`, or
:func:`orbatt.core.gyrostat.rhs_extended` for wheels and control),
registered as ``"scipy-DOP853"``, ``"scipy-RK45"``, ``"scipy-RK23"``, ``"scipy-Radau"``,
``"scipy-BDF"``, ``"scipy-LSODA"``."""
from __future__ import annotations

import numpy as np

from ..core import dop853 as kd
from ..core import potentials as kp
from ..core import model as km
from ..core.gyrostat import rhs_extended
from ..core.hamiltonian import rhs
from ..errors import IntegrationError
from .base import Method, budget_limit, register

__all__ = ["Scipy"]


class Scipy(Method):
    """scipy's ODE solvers on the compiled right-hand side, one member after the other,
    Python step loop. Each output time is a ``t_bound``: the solver is restarted there (with
    the last step size), so outputs are step-end values. Subclasses set ``solver`` (a class
    name in :mod:`scipy.integrate`)."""

    compiled = False
    extended = True
    solver = "DOP853"
    options = {"max_step": "largest step (scipy's max_step)"}

    def start(self, problem):
        from scipy import integrate

        super().start(problem)
        p = problem
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
            self.out = np.empty((E, p.t_out.shape[0], p.y0.shape[1]))
            n0 = int(np.searchsorted(p.t_out, p.t0, side="right"))
            self.out[:, :n0] = p.y0[:, None, :]
            self.i_out[:] = n0

    def _fun(self, e):
        kernel = self.p.kernel
        inertia = np.ascontiguousarray(self.p.inertia[e])
        work = kp.new_work()
        counter = self.nfev
        width = self.p.y0.shape[1]
        f = rhs_extended if (kernel.terms[0, km.FLAGS] & km.EXTENDED) != 0 else rhs

        def fun(t, y):
            dy = np.empty(width)
            f(t, np.ascontiguousarray(y, dtype=np.float64), inertia, *kernel, work, dy)
            counter[e] += 1
            return dy

        return fun

    def _new_solver(self, e, t_bound):
        # the same error norm as the compiled DOP853: atol on q, atol * max(I) on Q
        aQ = self.atol * float(np.max(self.p.inertia[e]))
        kw = {"rtol": self.rtol, "atol": np.array([self.atol] * 4 + [aQ] * (self.p.y0.shape[1] - 4))}
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
        budget = budget_limit(budget)
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
                    self.fail(kd.NONFINITE, float(s.t), e)
            s = self.solver_obj
            if self.steps[e] >= self.max_steps:
                self.fail(kd.MAX_STEPS, float(s.t), e)
            msg = s.step()
            done += 1
            self.steps[e] += 1
            if s.status == "failed" or not np.all(np.isfinite(s.y)):
                if not np.all(np.isfinite(s.y)):
                    self.fail(kd.NONFINITE, float(s.t_old if s.t_old is not None else s.t), e)
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

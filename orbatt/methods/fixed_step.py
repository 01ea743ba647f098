"""Drivers of the compiled fixed-step kernels (:mod:`orbatt.core.splitting`): classical
``"rk4"`` and the symplectic splitting family ``"splitting2"``, ``"splitting4"``,
``"splitting6"`` and their named variants (coefficients in
:data:`orbatt.core.splitting.COMPOSITIONS`)."""
from __future__ import annotations

import numpy as np

from ..core import dop853 as kd
from ..core import potentials as kp
from ..core import splitting as ks
from ..errors import InputError
from .base import Method, budget_limit, count_totals, group_sizes, register

__all__ = ["FixedStep", "RK4", "Splitting"]


class FixedStep(Method):
    """Shared driver of the compiled fixed-step kernels (:mod:`orbatt.core.splitting`).

    Subclasses set ``kernel_method`` (:data:`~orbatt.core.splitting.SPLITTING` or
    :data:`~orbatt.core.splitting.RK4`) and may override :meth:`setup` (the splitting
    sequence and rotation tables)."""

    kernel_method = ks.SPLITTING
    #: members per group in ensembles (the grid is common: results are those of one-by-one runs)
    LANES = 32

    def start(self, problem):
        super().start(problem)
        p = problem
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
        """The kernels' sequence and rotation arguments (unused by RK4)."""
        E = p.members
        self.flow = np.zeros(1, dtype=np.int64)
        self.weight = np.zeros(1)
        self.toff = np.zeros(1)
        self.AXES = np.ones((E, 3), dtype=np.int64)
        self.COEF = np.zeros((E, 4))

    def advance(self, budget):
        p = self.p
        budget = budget_limit(budget)
        if self.single:
            self.status[0] = ks.advance(self.Y[0], self.ST[0], self.GCNT[0], self.t_k, self.out[0], p.t0,
                                        float(self.step), self.kernel_method, self.flow, self.weight, self.toff,
                                        self.AXES[0], self.COEF[0], p.inertia[0], *p.kernel,
                                        self.WORK[0], self.max_steps, budget)
        else:
            ks.advance_lanes(self.Y, self.ST, self.GCNT, self.t_k, self.out, self.status, p.t0, float(self.step),
                             self.kernel_method, self.flow, self.weight, self.toff, self.AXES, self.COEF, p.inertia,
                             *p.kernel, self.GWORK, self.LANES, self.max_steps, budget)
        return self.check_status(self.status)

    def failure_point(self, g):
        return self.p.t0 + int(self.GCNT[g, ks.CNT_K]) * float(self.step), g * self.LANES

    def outputs(self):
        n = int(self.GCNT[:, ks.CNT_IOUT].min())
        return self.p.t_out[:n], self.out[:, :n]

    def stats(self):
        key = "kicks" if self.kernel_method == ks.SPLITTING else "rhs_evaluations"
        sizes = np.ones(1, dtype=np.int64) if self.single else group_sizes(self.p.members, self.LANES,
                                                                            self.GCNT.shape[0])
        s = count_totals(self.GCNT, {"steps": ks.CNT_STEPS, key: ks.CNT_EVALS}, sizes)
        return {"steps": s["steps"], "rejected_steps": 0, key: s[key]}

    def time_reached(self):
        return self.p.t0 + float(self.GCNT[:, ks.CNT_K].min()) * float(self.step)


@register
class RK4(FixedStep):
    name = "rk4"
    order = 4
    kernel_method = ks.RK4
    description = "classical Runge-Kutta 4, fixed step, compiled (a baseline; not symplectic)"


class Splitting(FixedStep):
    """Symplectic splitting: a symmetric composition of Strang steps (coefficients in
    :data:`orbatt.core.splitting.COMPOSITIONS`)."""

    composition = "strang"
    symplectic = True
    options = {"kinetic": "decomposition of T: 'axes' (T1+T2+T3, docs/design.md §4), 'shifted' (|g|^2/2I_mid + two "
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
            kin = "shifted" if p.torque_free else "axes"
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

"""The scenario object of a binary asteroid (:class:`BinaryScenario`): what
:func:`orbatt.scenario.load_scenario` returns for ``[orbit] provider = "coupled"``, with the
:class:`~orbatt.scenario.Scenario` interface the command line uses (``run``, ``run_content``,
``times``, ``name``, ``path``, ``method``)."""
from __future__ import annotations

import math

import numpy as np
from astropy import units as u

from .. import quaternion as qt
from .. import units as U
from ..binary import BinarySystem, Impulse, binary_content, propagate_binary
from ..binary.system import rtn_basis
from ..errors import InputError, ScenarioError
from .binary_schema import BinarySpec
from .build import MAX_ANGLE_PER_STEP, MAX_WORK_STEPS, build_output_times, run_to_content
from .fields import FieldContext

__all__ = ["BinaryScenario"]


def _orbital_frame_quaternion(r, v):
    """``p``: the orbital frame ``O`` -> inertial (columns o1, o2, o3 of ``docs/design.md`` §1)."""
    return qt.from_matrix(rtn_basis(r, v).T)


class BinaryScenario:
    """A validated binary study (:mod:`orbatt.scenario.binary_schema`).

    Attributes
    ----------
    system : BinarySystem
    y0 : ndarray
        The initial state of :mod:`orbatt.core.mutual` (inertial).
    times : ndarray
        Output times ``k * output_step`` (s).
    period : float
        The initial osculating period of the relative orbit (s; ``"N orbits"`` counts these).
    impulses : list of Impulse
    """

    def __init__(self, spec: BinarySpec, path=None):
        self.spec = spec
        self.path = path
        self.name = spec.name
        self.description = spec.description
        self.text = spec.text
        ctx = FieldContext(str(path) if path else spec.name)
        prim = spec.primary
        self.system = BinarySystem(spec.mass * u.kg, spec.inertia * U.INERTIA, spec.primary_mass * u.kg,
                                   None if prim is None else prim["inertia"] * U.INERTIA, potential=spec.potential_kind)
        o = spec.orbit
        try:
            if "position" in o:
                r, v = o["position"], o["velocity"]
            else:
                from ..orbits.kepler import KeplerOrbit

                kep = KeplerOrbit(o["a"] * u.km, o["e"], o["i"] * u.rad, o["raan"] * u.rad, o["argp"] * u.rad,
                                  true_anomaly=o["true_anomaly"] * u.rad, gm=self.system.gm * U.GM, body_radius=None)
                r, v = kep.state(0.0)
            init = spec.initial
            q, omega = init["q"], init.get("omega")
            # frame = "orbital": q and omega relative to O; O turns at |r x v| / r^2 about o3 (its
            # turn about o1, from an out-of-plane acceleration, is left out of this definition)
            if init["frame"] == "orbital":
                h = float(np.linalg.norm(np.cross(r, v)))
                if not h > 1e-12 * float(np.linalg.norm(r)) * float(np.linalg.norm(v)):
                    raise ctx.error("[initial] frame", "'orbital': the relative position and velocity are parallel "
                                                       "(a radial orbit: no orbit normal, no orbital frame); give q "
                                                       "and omega with frame = 'inertial', or a velocity with an "
                                                       "along-track part")
                p = _orbital_frame_quaternion(r, v)
                n_orb = np.linalg.norm(np.cross(r, v)) / float(r @ r)  # the orbital frame's rate, about o3
                omega = omega + qt.rotate_inv(q, np.array([0.0, 0.0, n_orb]))
                q = qt.mul(p, q)
            if omega is None:  # Q given: the body rate from g = 1/2 Im(q~ Q)
                omega = 0.5 * qt.mul(qt.conj(q), init["Q"])[1:] / spec.inertia
            kw = {} if prim is None else {"q_primary": prim["q"], "omega_primary": prim["omega"] * U.RATE}
            self.y0 = self.system.state(r * U.LENGTH, v * (U.LENGTH / U.TIME), q, omega * U.RATE, **kw)
        except ScenarioError:
            raise
        except InputError as exc:
            where = "[orbit] position" if "position" in o else "[orbit] a"
            raise ctx.error(where, str(exc).split(": ", 1)[-1]) from None
        mu = self.system.reduced_mass
        eps = 0.5 * float(np.sum((self.y0[3:6] / mu) ** 2)) - self.system.gm / float(np.linalg.norm(self.y0[0:3]))
        if not eps < 0:
            raise ctx.error("[orbit] velocity", "the relative orbit is not bound (energy >= 0); lower the speed")
        a = -self.system.gm / (2 * eps)
        self.period = 2 * math.pi * math.sqrt(a**3 / self.system.gm)
        self.times, self.t_end = build_output_times(ctx, spec.integration, self.period)
        self.impulses = [Impulse(float(t), tuple(map(float, dv))) for t, dv in spec.impulses]
        for j, k in enumerate(self.impulses):
            if k.time > self.times[-1]:
                raise ctx.error(f"[[orbit.impulses]] {j} time", f"{k.time:g} s is after the last output "
                                                               f"({self.times[-1]:g} s); move it or lengthen t_end")
        self.method = spec.integration["method"]
        self.settings = {k: spec.integration[k] for k in ("rtol", "atol", "composition") if k in spec.integration}
        if "step" in spec.integration:
            kind, value = spec.integration["step"]
            self.settings["step"] = value * self.period if kind == "orbits" else value
        spin = float(np.linalg.norm(omega))
        spin_primary = 0.0 if prim is None else float(np.linalg.norm(prim["omega"]))
        turning = ("primary", spin_primary) if spin_primary > spin else ("body", spin)
        self.work_steps = self._check_work(ctx, *turning)

    def _check_work(self, ctx, who, spin):
        """The lower estimate of one run's integration steps (:func:`orbatt.scenario.build.check_work`'s,
        for the coupled bodies): ``t_end / step`` for the splitting, else the relative orbit's
        angle (twice, as the gravity gradient sees it) and the faster body's turn over ``t_end``
        (``spin``, rad/s, of ``who``: ``"body"`` or ``"primary"``), at most
        :data:`~orbatt.scenario.build.MAX_ANGLE_PER_STEP` a step. A run above
        :data:`~orbatt.scenario.build.MAX_WORK_STEPS` is refused naming the key that dominates;
        a sweep bounds its cases by it (:func:`orbatt.sweep.cases.check_sweep_work`)."""
        t_end = self.t_end
        step = self.settings.get("step") if self.method == "splitting" else None
        orbit = 4 * math.pi * t_end / self.period
        steps = t_end / step if step is not None else (orbit + spin * t_end) / MAX_ANGLE_PER_STEP
        if steps <= MAX_WORK_STEPS:
            return steps
        if step is not None:
            where, what = "[integration] step", f"{step:.6g} s over t_end = {t_end:.6g} s is {steps:.3g} steps"
        elif spin * t_end >= orbit:
            where = "[primary] omega" if who == "primary" else "[initial] omega"
            what = (f"the {who} turns {spin * t_end:.3g} rad over t_end = {t_end:.6g} s: at least {steps:.3g} "
                    "integration steps")
        else:
            where, what = "[orbit]", (f"the orbit (period {self.period:.3g} s) goes round {t_end / self.period:.3g} "
                                      f"times: at least {steps:.3g} integration steps")
        raise ctx.error(where, f"{what}, more than {MAX_WORK_STEPS:.0e} (hours of computing); shorten [integration] "
                               "t_end" + (" or give a longer step" if step is not None else ""))

    def run(self, method=None, progress=False, **overrides):
        """Propagate and return the result :class:`xarray.Dataset` (:mod:`orbatt.binary.dataset`).

        Raises
        ------
        IntegrationError
            The bodies touched or the step loop failed; ``exc.dataset`` holds the outputs
            computed until then, marked incomplete.
        """
        return self.run_content(method, progress, **overrides).to_dataset()

    def run_content(self, method=None, progress=False, **overrides):
        """:meth:`run`'s result as a :class:`~orbatt.dataset.content.Content`; ``progress`` as
        for :func:`orbatt.propagate` (a KeyboardInterrupt also stops the run: the result then
        holds what was computed, ``integration_complete = 0``)."""
        m = method or self.method
        kw = {} if m == "splitting" else {"rtol": 1e-10, "atol": 1e-12}
        kw.update(self.settings)
        kw.update(overrides)
        if m != "splitting":  # the splitting's settings do not apply to the adaptive methods
            kw.pop("step", None)
            kw.pop("composition", None)
        return run_to_content(self.path or self.name, m, lambda: propagate_binary(
            self.system, self.y0, self.times, method=m, impulses=self.impulses, progress=progress, **kw),
            self._content)

    def _content(self, traj):
        return binary_content(traj, scenario_text=self.text, title=f"orbatt: {self.name}")

    def __repr__(self):
        return f"BinaryScenario({self.name!r}, method={self.method!r}, outputs={self.times.size})"

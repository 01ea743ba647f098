"""orbatt.methods.base: the registry, the subclass contract (a method written in a test),
the failure handling shared by the drivers, the statistics helpers; and the public names
of orbatt.propagation / orbatt.methods (the entry point is the function orbatt.propagate,
the module is orbatt.propagation)."""
from __future__ import annotations

import importlib.machinery
import types

import numpy as np
import pytest
from method_cases import angle

import orbatt
from orbatt import analytic
from orbatt.core import dop853 as kd
from orbatt.core import potentials as kp
from orbatt.errors import InputError, IntegrationError
from orbatt.methods import METHODS, Method, methods, register
from orbatt.methods.base import budget_limit, count_totals, group_sizes, resolve_method


def test_propagate_is_the_function_and_propagation_the_module():
    import orbatt.methods as om
    import orbatt.progress as op
    import orbatt.propagation as pm

    assert isinstance(orbatt.propagate, types.FunctionType)
    assert orbatt.propagate is pm.propagate and orbatt.propagate.__module__ == "orbatt.propagation"
    # no submodule of that name for the function to shadow
    assert importlib.machinery.PathFinder.find_spec("orbatt.propagate", orbatt.__path__) is None
    assert isinstance(orbatt.methods, types.ModuleType) and orbatt.methods is om
    for name in ("Method", "METHODS", "register", "Problem"):
        assert getattr(orbatt, name) is getattr(om, name) is getattr(pm, name)
    assert orbatt.ProgressInfo is op.ProgressInfo is pm.ProgressInfo
    assert pm.methods is om.methods is methods


def test_resolve_method():
    assert resolve_method("dop853") is METHODS["dop853"]
    assert resolve_method("Scipy-rk45") is METHODS["scipy-RK45"]
    assert resolve_method(METHODS["rk4"]) is METHODS["rk4"]
    with pytest.raises(InputError, match="method: 'rk5' is not a known method"):
        resolve_method("rk5")
    with pytest.raises(InputError, match="is not a known method"):
        resolve_method(int)


def test_register_refuses_a_taken_name():
    class Again(Method):
        name = "dop853"

    with pytest.raises(ValueError, match="'dop853' is already registered"):
        register(Again)
    assert METHODS["dop853"] is not Again


def test_statistics_helpers():
    assert budget_limit(0) == 1 and budget_limit(2.5e30) == 2**62 and budget_limit(7) == 7
    np.testing.assert_array_equal(group_sizes(70, 32, 3), [32, 32, 6])
    cnt = np.array([[3, 1, 9], [5, 0, 2]], dtype=np.int64)
    assert count_totals(cnt, {"steps": 0, "evals": 2}) == {"steps": 8, "evals": 11}
    assert count_totals(cnt, {"steps": 0, "rejected": 1}, np.array([2, 3])) == {"steps": 21, "rejected": 2}


def test_check_status_raises_for_the_first_failed_entry():
    class Probe(Method):
        name = "probe"

        def failure_point(self, i):
            return 10.0 * i, 100 + i

    m = Probe(rtol=1e-9, atol=1e-12, step=None, max_steps=50)
    m.start(orbatt.Problem(t0=0.0, t_out=np.array([0.0, 1.0]), step_ends=False, y0=np.zeros((3, 8)),
                           inertia=np.ones((3, 3)), kernel=None, ensemble=True))
    assert m.check_status(np.array([kd.DONE, kd.DONE, kd.DONE]))
    assert not m.check_status(np.array([kd.DONE, kd.PAUSED, kd.DONE]))
    with pytest.raises(IntegrationError, match=r"max_steps = 50 step attempts used up at t = 10\.0 "
                                               r"\(ensemble member 101\)") as exc:
        m.check_status(np.array([kd.PAUSED, kd.MAX_STEPS, kd.NONFINITE]))
    assert exc.value.t == 10.0
    with pytest.raises(IntegrationError, match="step size underflowed at t = 20.0"):
        m.check_status(np.array([kd.DONE, kd.DONE, kd.STEP_TOO_SMALL]))


def test_registry_and_custom_method(free):
    body, s0 = free
    for name, cls in METHODS.items():
        assert issubclass(cls, Method) and (cls.order > 0 or cls.closed_form) and cls.description
    assert METHODS["splitting4-mclachlan"] is METHODS["splitting4"]
    assert METHODS["splitting4"].order == 4 and METHODS["splitting4"].composition == "mclachlan4"
    descriptions = methods()
    assert set(descriptions) == set(METHODS)
    assert "symplectic" in descriptions["splitting6"] and "order 4" in descriptions["splitting4"]

    class Euler(Method):
        """Explicit Euler, a Python loop: the subclass contract in 30 lines."""
        name = "euler-test"
        order = 1
        description = "explicit Euler (test)"

        def start(self, p):
            from orbatt.core.hamiltonian import rhs
            self.p, self.rhs = p, rhs
            self.y = p.y0[0].copy()
            self.t = p.t0
            self.out = [self.y.copy()]
            self.n = 0

        def advance(self, budget):
            p = self.p
            work = kp.new_work()
            for target in p.t_out[len(self.out):]:
                while self.t < target - 1e-12:
                    h = min(self.step, target - self.t)
                    dy = np.empty(8)
                    self.rhs(self.t, self.y, p.inertia[0], *p.kernel, work, dy)
                    self.y = self.y + h * dy
                    self.t += h
                    self.n += 1
                self.out.append(self.y.copy())
            return True

        def outputs(self):
            return self.p.t_out[:len(self.out)], np.array(self.out)[None]

        def stats(self):
            return {"steps": self.n}

        def time_reached(self):
            return self.t

    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, 0.1], method=Euler, step=1e-4)
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, np.array([0.0, 0.1]))
    assert tr.method == "euler-test" and angle(tr.q, qref).max() < 1e-3

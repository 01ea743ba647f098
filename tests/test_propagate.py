"""orbatt.propagate: every method against the exact free rigid body and the classical model
(Euler's equations + quaternion kinematics), ensembles, validation, errors, progress, stops."""
from __future__ import annotations

import math

import astropy.units as u
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import orbatt
from orbatt import analytic
from orbatt import quaternion as qt
from orbatt.core import kepler
from orbatt.core import potentials as kp
from orbatt.errors import InputError, IntegrationError
from orbatt.propagate import METHODS, Method, ProgressInfo

Q0_PAPER = np.array([0.5, -1 / math.sqrt(2), 0.0, 0.5])
P0_PAPER = np.array([0.3, -0.848528, 0.141421, -1.5])
GM = 398600.4418
A_ORB = 7000.0
N_ORB = math.sqrt(GM / A_ORB**3)
PERIOD = 2 * math.pi / N_ORB


class Spec:
    """A potential given by its kernel specification only (DESIGN.md §3, core.potentials)."""

    def __init__(self, kind, params, table=None):
        self.kind = kind
        self.params = np.asarray(params, dtype=float)
        self.table = np.zeros((0, 0)) if table is None else table


ORB = kepler.orbit_vector(A_ORB, 0.2, math.pi / 6, math.pi / 4, math.pi / 12, 0.0, N_ORB)
GG = Spec(kp.GRAVITY_GRADIENT_KEPLER, np.concatenate([[GM], ORB]))


@pytest.fixture(scope="module")
def free():
    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    return body, orbatt.State(body, Q0_PAPER, P0_PAPER)


@pytest.fixture(scope="module")
def sat():
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    return body, orbatt.State(body, Q0_PAPER, P0_PAPER)


def angle(q, qref):
    w = qt.mul(qt.conj(np.asarray(qref)), np.asarray(q))
    return 2 * np.arctan2(np.linalg.norm(w[..., 1:], axis=-1), np.abs(w[..., 0]))


# ---------------------------------------------------------------------------------------
# References: the exact free body, and the classical model


def classical_reference(body, state, kind, params, t, rtol=1e-13):
    """Euler's equations I dw/dt = I w x w + tau and dq/dt = 1/2 q (0, w), solved by scipy
    at a tight tolerance; torques written the classical way (DESIGN.md §3)."""
    I = body.inertia_value
    w0 = state.omega

    def f(tt, x):
        q = x[:4]
        w = x[4:]
        if kind == kp.GRAVITY_GRADIENT_KEPLER:
            r, xs = kepler.kepler_radial(tt, params[1:], kp.new_work())
            xb = qt.rotate_inv(q / np.linalg.norm(q), np.array(xs))
            tau = 3 * params[0] / r**3 * np.cross(xb, I * xb)
        elif kind == kp.HEAVY_TOP:
            FB = qt.rotate_inv(q / np.linalg.norm(q), np.array([0.0, 0.0, -params[0]]))
            tau = np.cross(params[1:], FB)
        else:
            tau = np.zeros(3)
        dw = (np.cross(I * w, w) + tau) / I
        return np.concatenate([0.5 * qt.mul(q, qt.pure(w)), dw])

    sol = solve_ivp(f, (t[0], t[-1]), np.concatenate([state.q, w0]), method="DOP853", t_eval=None, rtol=rtol,
                    atol=1e-16, dense_output=False)
    assert sol.success
    # integrate to each output (DESIGN.md §4: no dense output at this accuracy)
    out = [np.concatenate([state.q, w0])]
    for a, b in zip(t[:-1], t[1:]):
        s = solve_ivp(f, (a, b), out[-1], method="DOP853", rtol=rtol, atol=1e-16)
        out.append(s.y[:, -1])
    return np.array(out)[:, :4]


# settings per method reaching about 1e-9 rad on the free body over 20 time units, and the
# bound checked (a step is given to fixed-step methods)
FREE_SETTINGS = {
    "dop853": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "dop853-lanes": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "scipy-DOP853": ({"rtol": 1e-12, "atol": 1e-14}, 1e-10),
    "scipy-RK45": ({"rtol": 1e-9, "atol": 1e-11}, 1e-7),
    "scipy-RK23": ({"rtol": 1e-8, "atol": 1e-10}, 1e-5),
    "scipy-Radau": ({"rtol": 1e-9, "atol": 1e-11}, 1e-7),
    "scipy-BDF": ({"rtol": 1e-7, "atol": 1e-9}, 1e-4),
    "scipy-LSODA": ({"rtol": 1e-10, "atol": 1e-12}, 1e-7),
    "rk4": ({"step": 0.005}, 1e-9),
    "splitting2": ({"step": 0.002}, 1e-6),
    "splitting4": ({"step": 0.05}, 1e-9),
    "splitting4-yoshida": ({"step": 0.02}, 1e-9),
    "splitting4-suzuki": ({"step": 0.05}, 1e-9),
    "splitting6": ({"step": 0.2}, 1e-9),
    "splitting6-yoshida": ({"step": 0.1}, 1e-9),
}


def test_every_method_has_settings_here():
    names = {c.name for c in METHODS.values()}
    assert names == set(FREE_SETTINGS)


@pytest.mark.parametrize("method", sorted(FREE_SETTINGS))
def test_every_method_matches_exact_free_body(free, method):
    body, s0 = free
    kw, bound = FREE_SETTINGS[method]
    t = np.linspace(0.0, 20.0, 9)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method=method, **kw)
    qref, Qref = analytic.torque_free(body.inertia_value, s0.q, s0.Q, t)
    assert tr.complete and tr.method == METHODS[method].name
    np.testing.assert_array_equal(tr.t, t)
    assert angle(tr.q, qref).max() < bound
    assert np.abs(tr.Q - Qref).max() < 10 * bound
    assert tr.stats["steps"] > 0 and tr.stats["wall_time_s"] > 0
    assert ("kicks" in tr.stats) == METHODS[method].symplectic


@pytest.mark.parametrize("method,kw,bound", [
    ("dop853", {"rtol": 1e-11, "atol": 1e-13}, 1e-9),
    ("scipy-DOP853", {"rtol": 1e-11, "atol": 1e-13}, 1e-9),
    ("rk4", {"step": 2.0}, 1e-9),
    ("splitting2", {"step": 0.25}, 1e-6),
    ("splitting4", {"step": 2.0}, 1e-9),
    ("splitting6", {"step": 5.0}, 1e-9),
])
def test_methods_match_classical_model_gravity_gradient(sat, method, kw, bound):
    """The paper's Keplerian case (Sect. 6.2), one orbit, against Euler's equations with the
    classical torque (3 GM / r^3) x_B x (I x_B)."""
    body, s0 = sat
    t = np.linspace(0.0, PERIOD, 5)
    ref = _classical_gg(body, s0)
    tr = orbatt.propagate(body, s0, GG, t, method=method, **kw)
    assert angle(tr.q, ref).max() < bound


_CACHE = {}


def _classical_gg(body, s0):
    if "gg" not in _CACHE:
        _CACHE["gg"] = classical_reference(body, s0, kp.GRAVITY_GRADIENT_KEPLER, GG.params,
                                           np.linspace(0.0, PERIOD, 5))
    return _CACHE["gg"]


def test_heavy_top_matches_classical_model(free):
    body, s0 = free
    top = orbatt.HeavyTop(0.5, [1.0, 0.0, 0.0])
    t = np.linspace(0.0, 20.0, 5)
    ref = classical_reference(body, s0, kp.HEAVY_TOP, top.params, t)
    for method, kw in (("dop853", {"rtol": 1e-12}), ("splitting4", {"step": 0.02}), ("splitting6", {"step": 0.1})):
        tr = orbatt.propagate(body, s0, top, t, method=method, **kw)
        assert angle(tr.q, ref).max() < 1e-9, method


def test_scipy_reference_path_agrees_with_compiled(sat):
    body, s0 = sat
    t = [0.0, 0.5 * PERIOD, PERIOD]
    a = orbatt.propagate(body, s0, GG, t, rtol=1e-12, atol=1e-14)
    b = orbatt.propagate(body, s0, GG, t, method="scipy-DOP853", rtol=1e-12, atol=1e-14)
    assert angle(a.q, b.q).max() < 1e-10
    # same algorithm, same step-size control: similar work
    assert 0.7 < a.stats["rhs_evaluations"] / b.stats["rhs_evaluations"] < 1.3


# ---------------------------------------------------------------------------------------
# Outputs


def test_t_span_gives_step_ends(free, sat):
    body, s0 = free
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t_span=(0.0, 10.0), rtol=1e-8)
    assert tr.t[0] == 0.0 and tr.t[-1] == 10.0 and np.all(np.diff(tr.t) > 0)
    assert len(tr.t) == tr.stats["steps"] + 1
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, tr.t)
    assert angle(tr.q, qref).max() < 1e-6
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t_span=(0.0, 1.0), method="splitting2", step=0.3)
    np.testing.assert_allclose(tr.t, [0.0, 0.3, 0.6, 0.9, 1.0], rtol=0, atol=1e-15)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t_span=(0.0, 10.0), method="scipy-RK45", rtol=1e-6)
    assert tr.t[-1] == 10.0 and len(tr.t) == tr.stats["steps"] + 1


def test_start_time_and_outputs_inside_t_span(free):
    body, s0 = free
    t = [2.0, 3.0]
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, t_span=(1.0, 4.0), rtol=1e-12)
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, np.array(t) - 1.0)
    assert angle(tr.q, qref).max() < 1e-10
    # the epoch may be any time: a shifted start gives the same motion
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), [100.0, 101.0, 102.0], rtol=1e-12)
    qref, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, np.array([0.0, 1.0, 2.0]))
    assert angle(tr.q, qref).max() < 1e-10


def test_quantity_times(sat):
    body, s0 = sat
    a = orbatt.propagate(body, s0, GG, [0.0, 10.0] * u.min, rtol=1e-10)
    b = orbatt.propagate(body, s0, GG, [0.0, 600.0], rtol=1e-10)
    np.testing.assert_array_equal(a.t, [0.0, 600.0])
    np.testing.assert_array_equal(a.q, b.q)
    c = orbatt.propagate(body, s0, GG, [0.0, 600.0], method="splitting4", step=1 * u.min)
    assert c.settings["step"] == 60.0
    assert angle(c.q[-1], b.q[-1]) < 1e-6


def test_output_shapes_and_settings(free):
    body, s0 = free
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, 1.0, 2.0], method="splitting4", step=0.1)
    assert tr.q.shape == (3, 4) and tr.Q.shape == (3, 4) and not tr.is_ensemble
    assert tr.settings["step"] == 0.1 and tr.settings["order"] == 4
    assert tr.settings["composition"] == "mclachlan4" and tr.settings["kinetic"] == "shifted"
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, 1.0], rtol=1e-9, atol=1e-11)
    assert tr.settings["rtol"] == 1e-9 and tr.settings["atol"] == 1e-11
    assert set(tr.stats) >= {"steps", "rejected_steps", "rhs_evaluations", "wall_time_s"}
    np.testing.assert_array_equal(tr.inertia, body.inertia_value)


# ---------------------------------------------------------------------------------------
# Ensembles


def _random_data(n, seed=0):
    rng = np.random.default_rng(seed)
    return qt.normalize(rng.normal(size=(n, 4))), rng.normal(size=(n, 3)) * 0.8


def _random_states(body, n, seed=0):
    return orbatt.State.from_momentum(body, *_random_data(n, seed))


@pytest.mark.parametrize("method,kw", [("dop853", {"rtol": 1e-9}), ("splitting4", {"step": 10.0}),
                                       ("rk4", {"step": 10.0})])
def test_ensemble_identical_to_one_by_one(sat, method, kw):
    body, _ = sat
    q, g = _random_data(6)
    t = np.array([0.0, 0.3 * PERIOD, 0.5 * PERIOD])
    ens = orbatt.propagate(body, orbatt.State.from_momentum(body, q, g), GG, t, method=method, **kw)
    assert ens.is_ensemble and ens.q.shape == (6, 3, 4)
    for e in range(6):
        one = orbatt.propagate(body, orbatt.State.from_momentum(body, q[e], g[e]), GG, t, method=method, **kw)
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.Q[e], one.Q)
    assert ens.stats["members"] == 6


def test_fixed_step_ensembles_in_several_groups_are_identical(sat):
    """70 members = groups of 32, 32, 6 on the common grid: identical to one-by-one."""
    body, _ = sat
    q, g = _random_data(70, seed=3)
    t = np.array([0.0, 100.0, 250.3])
    ens = orbatt.propagate(body, orbatt.State.from_momentum(body, q, g), GG, t, method="splitting2", step=7.0)
    for e in (0, 31, 32, 69):
        one = orbatt.propagate(body, orbatt.State.from_momentum(body, q[e], g[e]), GG, t, method="splitting2",
                               step=7.0)
        np.testing.assert_array_equal(ens.q[e], one.q)
    assert ens.stats["steps"] == 70 * one.stats["steps"]
    assert ens.stats["kicks"] == 70 * one.stats["kicks"]


def test_dop853_lanes_agrees_with_one_by_one_to_tolerance(sat):
    """Lockstep groups share the step size (the largest error of the group controls it):
    each member is at least as accurate as alone, not bitwise identical."""
    body, _ = sat
    q, g = _random_data(40, seed=4)
    states = orbatt.State.from_momentum(body, q, g)
    t = np.array([0.0, 0.5 * PERIOD, PERIOD])
    ref = orbatt.propagate(body, states, GG, t, rtol=1e-14, atol=1e-16)
    for lanes in (1, 16, 64):
        ens = orbatt.propagate(body, states, GG, t, method="dop853-lanes", rtol=1e-9, atol=1e-11, lanes=lanes)
        assert ens.q.shape == (40, 3, 4) and ens.settings["lanes"] == lanes
        alone = orbatt.propagate(body, states, GG, t, rtol=1e-9, atol=1e-11)
        err_lanes = angle(ens.q, ref.q).max(axis=1)
        err_alone = angle(alone.q, ref.q).max(axis=1)
        assert err_lanes.max() < 2e-8
        assert np.all(err_lanes <= 2.0 * err_alone + 1e-12)
        if lanes == 1:
            assert ens.stats["steps"] == alone.stats["steps"]
            assert angle(ens.q, alone.q).max() < 1e-13


def test_ensemble_over_bodies(sat):
    body, s0 = sat
    bodies = [orbatt.RigidBody(m * u.kg * u.km**2) for m in ([400, 500, 600], [450, 500, 520], [600, 500, 400])]
    t = [0.0, 0.25 * PERIOD]
    for method, kw in (("dop853", {"rtol": 1e-9}), ("splitting6", {"step": 20.0})):
        ens = orbatt.propagate(bodies, s0, GG, t, method=method, **kw)
        assert ens.q.shape == (3, 2, 4) and ens.inertia.shape == (3, 3)
        for e, b in enumerate(bodies):
            one = orbatt.propagate(b, orbatt.State(b, Q0_PAPER, P0_PAPER), GG, t, method=method, **kw)
            np.testing.assert_array_equal(ens.q[e], one.q)
    # N bodies with N states
    q, g = _random_data(3, seed=5)
    ens = orbatt.propagate(bodies, orbatt.State.from_momentum(body, q, g), GG, t, rtol=1e-9)
    one = orbatt.propagate(bodies[2], orbatt.State.from_momentum(bodies[2], q[2], g[2]), GG, t, rtol=1e-9)
    np.testing.assert_array_equal(ens.q[2], one.q)


def test_ensemble_scipy_reference(free):
    body, _ = free
    states = _random_states(body, 2, seed=9)
    t = [0.0, 1.0, 2.0]
    a = orbatt.propagate(body, states, orbatt.TorqueFree(), t, method="scipy-DOP853", rtol=1e-12, atol=1e-14)
    b = orbatt.propagate(body, states, orbatt.TorqueFree(), t, rtol=1e-12, atol=1e-14)
    assert a.q.shape == b.q.shape == (2, 3, 4)
    assert angle(a.q, b.q).max() < 1e-10


# ---------------------------------------------------------------------------------------
# Validation: clear errors, before any integration


def _bad_cases(body, s0):
    return [
        (dict(t=[0, 1], method="rk5"), "method: 'rk5' is not a known method"),
        (dict(t=[0, 1], method="splitting4"), "step: method 'splitting4' has a fixed step"),
        (dict(t=[0, 1], method="splitting4", step=0.0), "step: 0.0 must be a finite positive number"),
        (dict(t=[0, 1], method="rk4", step=-1.0), "step: -1.0 must be"),
        (dict(t=[0, 1], method="rk4", step=float("nan")), "step: nan must be"),
        (dict(t_span=(1.0, 0.0)), "t_span: the end 0.0 is not after the start 1.0"),
        (dict(t_span=(1.0, 1.0)), "t_span: the end 1.0 is not after the start 1.0"),
        (dict(t=[0.0, 2.0, 1.0]), "t: output times must increase strictly; t[2] = 1.0 follows t[1] = 2.0"),
        (dict(t=[0.0, float("inf")]), "t: "),
        (dict(), "t: give the output times t"),
        (dict(t=[0, 5], t_span=(0, 2)), "t: the output times [0.0 .. 5.0] leave t_span"),
        (dict(t=[0, 1], rtol=1e-17), "rtol: 1e-17 is below"),
        (dict(t=[0, 1], rtol=-1.0), "rtol: -1.0 must be"),
        (dict(t=[0, 1], atol="x"), "atol: 'x' is not a number"),
        (dict(t=[0, 1], max_steps=0), "max_steps: 0 is not a positive integer"),
        (dict(t=[0, 1], progress="yes"), "progress: expected None, True or a callable"),
        (dict(t=[0, 1], kinetic="axes"), "kinetic: method 'dop853' takes no option 'kinetic'"),
        (dict(t=[0, 1], method="splitting2", step=0.1, kinetic="diagonal"), "kinetic: 'diagonal' is not one of"),
        (dict(t=[0, 1e9], method="splitting2", step=1.0, max_steps=1000), "step: 1.0 needs 1000000000 steps"),
        (dict(t=[0, 1] * u.s), "t: "),
    ]


def test_bad_inputs_are_refused_with_clear_messages(free):
    body, s0 = free
    for kw, msg in _bad_cases(body, s0):
        with pytest.raises(InputError) as exc:
            orbatt.propagate(body, s0, orbatt.TorqueFree(), **kw)
        assert msg in str(exc.value), (kw, str(exc.value))


def test_bad_objects_are_refused(free, sat):
    body, s0 = free
    with pytest.raises(InputError, match="state0: expected an orbatt.State"):
        orbatt.propagate(body, (s0.q, s0.Q), orbatt.TorqueFree(), [0, 1])
    with pytest.raises(InputError, match="body: expected a RigidBody"):
        orbatt.propagate("body", s0, orbatt.TorqueFree(), [0, 1])
    with pytest.raises(InputError, match="potential: expected an orbatt Potential"):
        orbatt.propagate(body, s0, None, [0, 1])
    with pytest.raises(InputError, match="different units"):
        orbatt.propagate(sat[0], s0, orbatt.TorqueFree(), [0, 1])
    # non-finite state (State refuses it itself; a tampered one is caught here too)
    with pytest.raises(InputError):
        orbatt.State(body, [np.nan, 0, 0, 1], [0, 0, 0, 0])
    bad = orbatt.State(body, s0.q, s0.Q)
    bad.Q = bad.Q.copy()
    bad.Q[1] = np.inf
    with pytest.raises(InputError, match="state0: contains non-finite values"):
        orbatt.propagate(body, bad, orbatt.TorqueFree(), [0, 1])
    states = _random_states(body, 3)
    bodies = [body, body]
    with pytest.raises(InputError, match="do not broadcast"):
        orbatt.propagate(bodies, states, orbatt.TorqueFree(), [0, 1])
    with pytest.raises(InputError, match="an ensemble has no common step grid"):
        orbatt.propagate(body, states, orbatt.TorqueFree(), t_span=(0, 1))


# ---------------------------------------------------------------------------------------
# Integration errors


def test_nonfinite_derivative_stops_with_an_error_naming_the_time(free):
    body, s0 = free
    infinite_top = Spec(kp.HEAVY_TOP, [np.inf, 1.0, 0.0, 0.0])
    for method, kw in (("dop853", {}), ("splitting2", {"step": 0.1}), ("rk4", {"step": 0.1}),
                       ("scipy-DOP853", {})):
        with pytest.raises(IntegrationError, match=r"non-finite .* at t = 0\.0") as exc:
            orbatt.propagate(body, s0, infinite_top, [0.0, 1.0, 2.0], method=method, **kw)
        assert exc.value.t == 0.0
        assert exc.value.trajectory.complete is False
        assert len(exc.value.trajectory.t) == 1  # only the initial state


@pytest.mark.skipif(not hasattr(kp, "GRAVITY_GRADIENT_SAMPLED"), reason="sampled orbits not available")
def test_nan_appearing_mid_run_names_the_time(sat):
    """A sampled orbit whose samples turn NaN after t = 1000 s: the run stops there with an
    IntegrationError, not a silent NaN trajectory."""
    body, s0 = sat
    ts = np.linspace(0.0, 3000.0, 301)
    _, _, r, pos, vel = kepler.kepler_many(ts, ORB, GM)
    acc = -GM * pos / r[:, None] ** 3
    table = np.column_stack([ts, pos, vel, acc])
    table[ts > 1000.0, 1:] = np.nan
    spec = Spec(kp.GRAVITY_GRADIENT_SAMPLED, [GM, ts[0], ts[-1]], np.ascontiguousarray(table))
    t = np.linspace(0.0, 3000.0, 31)
    for method, kw in (("dop853", {}), ("splitting4", {"step": 1.0})):
        with pytest.raises(IntegrationError) as exc:
            orbatt.propagate(body, s0, spec, t, method=method, **kw)
        assert 990.0 <= exc.value.t <= 1000.0, exc.value.t
        assert f"t = {exc.value.t!r}" in str(exc.value)
        part = exc.value.trajectory
        assert not part.complete and part.t[-1] <= 1000.0 and np.all(np.isfinite(part.q))


def test_max_steps_is_an_integration_error(sat):
    body, s0 = sat
    with pytest.raises(IntegrationError, match="max_steps = 50 step attempts used up"):
        orbatt.propagate(body, s0, GG, [0.0, PERIOD], rtol=1e-12, max_steps=50)


# ---------------------------------------------------------------------------------------
# Progress and clean stops


def test_progress_callback_and_stop(sat):
    body, s0 = sat
    seen = []

    def cb(info):
        assert isinstance(info, ProgressInfo)
        seen.append(info)

    tr = orbatt.propagate(body, s0, GG, [0.0, PERIOD], method="splitting2", step=1.0, progress=cb)
    assert tr.complete and seen[-1].fraction == 1.0 and seen[-1].t == PERIOD

    def stop(info):
        return False

    t = np.linspace(0.0, 50 * PERIOD, 51)
    tr = orbatt.propagate(body, s0, GG, t, method="splitting2", step=0.5, progress=stop)
    assert not tr.complete and tr.stats["stopped"] == "progress callback"
    assert 1 <= len(tr.t) < len(t) and tr.q.shape == (len(tr.t), 4)
    np.testing.assert_array_equal(tr.t, t[:len(tr.t)])


def test_progress_bar_prints_only_for_runs_over_a_second(free, capsys):
    import io

    from orbatt.propagate import ProgressInfo, _progress_printer

    body, s0 = free
    orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, 5.0], progress=True)
    assert capsys.readouterr().err == ""  # a short run: no bar
    out = io.StringIO()
    report = _progress_printer(out)
    report(ProgressInfo(0.3, 3.0, 10.0, 100, 0.5))
    assert out.getvalue() == ""
    report(ProgressInfo(0.6, 6.0, 10.0, 200, 1.2))
    report(ProgressInfo(1.0, 10.0, 10.0, 300, 1.3))
    text = out.getvalue()
    assert "orbatt:" in text and " 60.0%" in text and "100.0%" in text and text.endswith("\n")


@pytest.mark.parametrize("method,kw", [("dop853", {"rtol": 1e-12}), ("splitting2", {"step": 0.5})])
def test_keyboard_interrupt_returns_what_was_computed(sat, method, kw):
    """Ctrl-C lands between compiled calls (numba does not see signals); simulated here by a
    progress callback that raises KeyboardInterrupt after the first call."""
    body, s0 = sat

    def interrupt(info):
        raise KeyboardInterrupt

    t = np.linspace(0.0, 200 * PERIOD, 201)
    tr = orbatt.propagate(body, s0, GG, t, method=method, progress=interrupt, **kw)
    assert not tr.complete and tr.stats["stopped"] == "KeyboardInterrupt"
    assert 1 <= len(tr.t) < len(t)
    assert np.all(np.isfinite(tr.q))
    full = orbatt.propagate(body, s0, GG, t[:len(tr.t)], method=method, **kw)
    np.testing.assert_array_equal(full.q, tr.q)


# ---------------------------------------------------------------------------------------
# Registry


def test_registry_and_custom_method(free):
    body, s0 = free
    for name, cls in METHODS.items():
        assert issubclass(cls, Method) and cls.order > 0 and cls.description
    assert METHODS["splitting4-mclachlan"] is METHODS["splitting4"]
    assert "splitting4" in orbatt.propagate.__module__ or True
    descriptions = orbatt.propagate.__globals__["methods"]()
    assert "symplectic" in descriptions["splitting6"]

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
                    self.rhs(self.t, self.y, p.inertia[0], p.kind, p.params, p.table, work, dy)
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

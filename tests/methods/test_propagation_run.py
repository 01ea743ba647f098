"""orbatt.propagation and orbatt.progress: outputs, ensembles, integration errors, progress
reports and clean stops of the run loop."""
from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from method_cases import GG, GM, ORB, P0_PAPER, PERIOD, Q0_PAPER, Spec, angle, random_data

import orbatt
from orbatt import analytic
from orbatt.core import kepler
from orbatt.core import potentials as kp
from orbatt.errors import IntegrationError
from orbatt.progress import ProgressInfo

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


@pytest.mark.parametrize("method,kw", [("dop853", {"rtol": 1e-9}), ("splitting4", {"step": 10.0}),
                                       ("rk4", {"step": 10.0})])
def test_ensemble_identical_to_one_by_one(sat, method, kw):
    body, _ = sat
    q, g = random_data(6)
    t = np.array([0.0, 0.3 * PERIOD, 0.5 * PERIOD])
    ens = orbatt.propagate(body, orbatt.State.from_momentum(body, q, g), GG, t, method=method, **kw)
    assert ens.is_ensemble and ens.q.shape == (6, 3, 4)
    for e in range(6):
        one = orbatt.propagate(body, orbatt.State.from_momentum(body, q[e], g[e]), GG, t, method=method, **kw)
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.Q[e], one.Q)
    assert ens.stats["members"] == 6


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
    q, g = random_data(3, seed=5)
    ens = orbatt.propagate(bodies, orbatt.State.from_momentum(body, q, g), GG, t, rtol=1e-9)
    one = orbatt.propagate(bodies[2], orbatt.State.from_momentum(bodies[2], q[2], g[2]), GG, t, rtol=1e-9)
    np.testing.assert_array_equal(ens.q[2], one.q)


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

    from orbatt.progress import progress_printer

    body, s0 = free
    orbatt.propagate(body, s0, orbatt.TorqueFree(), [0.0, 5.0], progress=True)
    assert capsys.readouterr().err == ""  # a short run: no bar
    out = io.StringIO()
    report = progress_printer(out)
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

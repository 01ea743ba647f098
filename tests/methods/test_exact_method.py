"""The method "exact" (orbatt.methods.exact, orbatt.core.free_body): the closed-form free rigid
body against the integrators at tight tolerance, against the documented closed form of
orbatt.analytic, its invariants, ensembles, the scenario path, and its refusals."""
from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest
from method_cases import GG, Q0_PAPER, angle
from scipy import special as sp

import orbatt
from orbatt import analytic
from orbatt import quaternion as qt
from orbatt.core import carlson as cr
from orbatt.core import free_body as fb
from orbatt.errors import InputError
from orbatt.methods import METHODS, methods
from orbatt.scenario import ScenarioError

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
TIGHT = {"rtol": 1e-13, "atol": 1e-15}


def state(body, q, g):
    """The canonical state of attitude ``q`` and body momentum ``g`` (Q = 2 q (0, g))."""
    q = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return orbatt.State(body, q, 2.0 * qt.mul(q, np.concatenate([[0.0], g])))


def cases(seed=3, n=24):
    """Random bodies and momenta, every kind of motion: generic, axis-symmetric (each pair of
    equal moments), near the separatrix (a spin about the middle axis perturbed by 1e-7),
    nearly degenerate moments (the Y form), and pure spins about each principal axis."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        I = rng.uniform(1.0, 2.0, 3)  # the triangle inequality holds
        g = rng.normal(size=3)
        q = rng.normal(size=4)
        kind = k % 6
        if kind == 1:
            I[k % 3] = I[(k + 1) % 3]
        elif kind == 2:
            g = 1e-7 * rng.normal(size=3)
            g[np.argsort(I)[1]] = 1.0
        elif kind == 3:
            I = np.sort(I)
            I[2] = I[1] * (1 + 1e-6)
        elif kind == 4:  # pure spin about axis k % 3 (smallest, middle or largest moment)
            g = np.zeros(3)
            g[k % 3] = rng.choice([-2.0, 2.0])
            q = np.array([1.0, 0.0, 0.0, 0.0])
        out.append((kind, I, q, g))
    return out


def test_registered_as_a_closed_form():
    cls = METHODS["exact"]
    assert cls.closed_form and not cls.adaptive and not cls.extended
    assert "closed form" in methods()["exact"] and "order" not in methods()["exact"]


def test_paper_torque_free_scenario_matches_dop853():
    """The shipped scenario (printed Q with q.Q = -9.7e-8, kept invariant by both) end to end:
    the same Dataset variables, and agreement with dop853 at rtol 1e-13 to 1e-12 rad."""
    sc = orbatt.load_scenario(SCEN / "paper-torque-free.toml")
    ex = sc.run(method="exact")
    ref = sc.run(**TIGHT)
    assert set(ex.data_vars) == set(ref.data_vars) and ex.attrs["method"] == "exact"
    np.testing.assert_array_equal(ex.time.values, ref.time.values)
    assert angle(ex.q.values, ref.q.values).max() < 1e-12
    assert np.abs(ex.Q.values - ref.Q.values).max() < 1e-11
    np.testing.assert_allclose(ex.qQ.values, ref.qQ.values[0], atol=1e-15)
    assert ex.orbatt.stats["steps"] == 0 and ex.orbatt.stats["evaluations"] == ex.time.size
    assert ex.orbatt.settings == {"closed_form": True}


@pytest.mark.parametrize("kind,I,q,g", cases())
def test_random_motions_match_dop853(kind, I, q, g):
    body = orbatt.RigidBody(I)
    s0 = state(body, q, g)
    T = 6.0 if kind == 2 else 20.0  # next to the separatrix errors grow as exp(lambda t)
    t = np.linspace(0.0, T, 11)
    ex = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact")
    ref = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, **TIGHT)
    assert angle(ex.q, ref.q).max() < 2e-10
    assert np.abs(ex.Q - ref.Q).max() < 2e-10 * np.abs(s0.Q).max()
    np.testing.assert_array_equal(ex.q[0], s0.q)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_pure_spins_are_uniform_rotations(axis):
    """A pure spin about each principal axis (Orekit's closed form fails about axes 2 and 3):
    q(t) = q0 exp(omega t / 2) to round-off, over 1e4 rotations."""
    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    q0 = np.array([0.5, -0.5, 0.5, 0.5])
    g = np.zeros(3)
    g[axis] = 3.0
    s0 = state(body, q0, g)
    t = np.linspace(0.0, 2e4, 7)
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact")
    w = g / body.inertia_value
    expected = qt.mul(q0, qt.exp(qt.pure(0.5 * w * t[:, None])))
    assert angle(tr.q, expected).max() < 1e-15 * np.abs(w).max() * t[-1] * 10
    np.testing.assert_allclose(tr.Q, s0.Q * 0 + 2 * qt.mul(tr.q, np.concatenate([[0.0], g])), atol=1e-13)


@pytest.mark.parametrize("kind,I,q,g", cases(seed=5, n=36))
def test_compiled_closed_form_is_orbatt_analytic(kind, I, q, g):
    """The compiled kernels evaluate orbatt.analytic's formulas: agreement to round-off
    (times of both signs; the separatrix case is ill-conditioned, hence |t| <= 10 there)."""
    s = state(orbatt.RigidBody(I), q, g)
    span = 10.0 if kind == 2 else 60.0
    t = np.concatenate([[0.0], np.random.default_rng(kind).uniform(-span, span, 40)])
    c = np.empty(fb.NC)
    fb.motion(np.asarray(I, dtype=float), s.y.copy(), c)
    out = np.empty((t.size, 8))
    fb.evaluate(c, s.y.copy(), 1.5, t + 1.5, out)
    qr, Qr = analytic.torque_free(I, s.q, s.Q, t)
    assert np.abs(out[:, :4] - qr).max() < 2e-13
    assert np.abs(out[:, 4:] - Qr).max() < 2e-13 * np.linalg.norm(s.Q)


def test_exact_separatrix_and_degenerate_cases():
    """On the separatrix exactly (D = I_mid) and for a sphere: agreement with orbatt.analytic
    and the invariants."""
    for I, g in (([1.5, 1.0, 0.75], [0.6, 0.0, 0.6]),   # g1 = g3: |g|^2 / 2T = I2 exactly
                 ([1.0, 1.0, 1.0], [0.3, -0.2, 0.5]), ([1.0, 2.0, 2.0], [0.3, -0.2, 0.5])):
        I = np.array(I)
        body = orbatt.RigidBody(I)
        s0 = state(body, [1.0, 0.0, 0.0, 0.0], np.array(g))
        t = np.linspace(0.0, 15.0, 16)
        tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact")
        qr, Qr = analytic.torque_free(I, s0.q, s0.Q, t)
        assert angle(tr.q, qr).max() < 1e-13
        assert np.abs(tr.Q - Qr).max() < 1e-13


def test_invariants_to_round_off_at_long_times():
    """|q| = 1, q.Q = 0, the energy and the inertial angular momentum G over t up to 1e6
    (about 1.6e5 rotations), to round-off."""
    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    s0 = state(body, Q0_PAPER, [0.5, 0.6, 0.4])
    t = np.concatenate([[0.0], np.geomspace(1e-3, 1e6, 200)])
    tr = orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact")
    I = body.inertia_value
    g = 0.5 * qt.mul(qt.conj(tr.q), tr.Q)[:, 1:]
    G = 0.5 * qt.mul(tr.Q, qt.conj(tr.q))[:, 1:]
    energy = 0.5 * (g**2 / I).sum(axis=1)
    assert np.abs(np.linalg.norm(tr.q, axis=1) - 1).max() < 1e-15
    assert np.abs(np.einsum("ij,ij->i", tr.q, tr.Q)).max() < 1e-15
    assert np.abs(energy / energy[0] - 1).max() < 1e-14
    assert np.abs(G - G[0]).max() < 1e-14 * np.linalg.norm(G[0])


def test_ensembles_are_one_by_one_runs(free):
    body, s0 = free
    rng = np.random.default_rng(7)
    q = rng.normal(size=(5, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    g = rng.normal(size=(5, 3))
    Q = 2 * qt.mul(q, np.concatenate([np.zeros((5, 1)), g], axis=1))
    bodies = [orbatt.RigidBody(rng.uniform(0.6, 1.4, 3)) for _ in range(5)]
    t = np.linspace(2.0, 30.0, 8)
    ens = orbatt.propagate(bodies, orbatt.State(body, q, Q), orbatt.TorqueFree(), t, method="exact")
    assert ens.q.shape == (5, 8, 4) and ens.stats["evaluations"] == 40
    for e in range(5):
        one = orbatt.propagate(bodies[e], orbatt.State(bodies[e], q[e], Q[e]), orbatt.TorqueFree(), t,
                               method="exact")
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.Q[e], one.Q)


def test_t_span_outputs_start_offset_and_chunks(free):
    body, s0 = free
    tf = orbatt.TorqueFree()
    tr = orbatt.propagate(body, s0, tf, t_span=(3.0, 10.0), method="exact")
    np.testing.assert_array_equal(tr.t, [3.0, 10.0])
    grid = orbatt.propagate(body, s0, tf, t_span=(3.0, 10.0), method="exact", step=0.5)
    np.testing.assert_allclose(grid.t, np.arange(3.0, 10.01, 0.5))
    qr, Qr = analytic.torque_free(body.inertia_value, s0.q, s0.Q, grid.t - 3.0)
    assert angle(grid.q, qr).max() < 1e-14
    # outputs inside t_span, tolerances and max_steps accepted and unused, progress reported
    seen = []
    many = np.linspace(4.0, 9.0, 20001)
    tr = orbatt.propagate(body, s0, tf, many, t_span=(3.0, 10.0), method="exact", rtol=1e-3, atol=1e-2,
                          max_steps=1, progress=lambda info: seen.append(info.fraction))
    qr, _ = analytic.torque_free(body.inertia_value, s0.q, s0.Q, many - 3.0)
    assert angle(tr.q, qr).max() < 1e-14 and tr.complete and seen[-1] == 1.0 and len(seen) >= 2


def test_refuses_what_is_not_torque_free(free, sat):
    body, s0 = free
    t = [0.0, 1.0]
    with pytest.raises(InputError, match=r"potential: method 'exact' solves only the torque-free rigid body.*"
                                         r"a heavy top acts on the body.*method = 'dop853'"):
        orbatt.propagate(body, s0, orbatt.HeavyTop(0.5, [1.0, 0.0, 0.0]), t, method="exact")
    with pytest.raises(InputError, match="the gravity gradient acts on the body"):
        orbatt.propagate(*sat, GG, t, method="exact")
    wheel = orbatt.ReactionWheel([1.0, 0.0, 0.0], "0.01 kg m2")
    rw = orbatt.RigidBody([10.0, 12.0, 14.0] * u.kg * u.m**2, wheels=[wheel])
    s_rw = orbatt.State.from_omega(rw, [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.01] * u.rad / u.s)
    with pytest.raises(InputError, match="method: 'exact' cannot integrate reaction wheels"):
        orbatt.propagate(rw, s_rw, orbatt.TorqueFree(), t, method="exact")
    with pytest.raises(InputError, match="max_step: method 'exact' takes no option 'max_step'"):
        orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact", max_step=1.0)
    with pytest.raises(InputError, match="rtol"):
        orbatt.propagate(body, s0, orbatt.TorqueFree(), t, method="exact", rtol=1.0)


def test_every_term_kind_is_described():
    """The refusal names what acts in words: every term kind of the kernel model has them."""
    from orbatt.core import model as km

    kinds = {km.HEAVY_TOP, km.CONSTANT_TORQUE, *km.ORBIT_TERMS, *km.VELOCITY_TERMS, *km.TABLE_TERMS,
             *km.EXTENDED_KINDS}
    assert set(km.KIND_DESCRIPTIONS) == kinds
    assert all(isinstance(d, str) and d for d in km.KIND_DESCRIPTIONS.values())


def test_scenario_refusal_names_the_method(tmp_path):
    text = (SCEN / "paper-heavy-top.toml").read_text()
    path = tmp_path / "top.toml"
    path.write_text(text.replace('method = "dop853"', 'method = "exact"'))
    assert 'method = "exact"' in path.read_text()
    with pytest.raises(ScenarioError, match=r"\[integration\] \(method 'exact'\): potential: .*heavy top"):
        orbatt.load_scenario(path).run()


def test_carlson_integrals_match_scipy():
    """R_F, R_C, R_J on the arguments the closed form uses (x, y in [0, 1], z = 1, p >= 1/2
    ... 100) and beyond, to a few eps relative."""
    rng = np.random.default_rng(11)
    for _ in range(3000):
        x, y = rng.uniform(0.0, 1.0, 2) ** 3
        z, p = 10.0 ** rng.uniform(-1, 2, 2)
        assert abs(cr.rf(x, y, z) / sp.elliprf(x, y, z) - 1) < 2e-15
        assert abs(cr.rc(x, z) / sp.elliprc(x, z) - 1) < 2e-15
        assert abs(cr.rj(x, y, z, p) / sp.elliprj(x, y, z, p) - 1) < 5e-15
    for e in (-0.9, -1e-3, -1e-4, 0.0, 1e-4, 1e-3, 5.0):
        assert abs(cr.rc1(e) / sp.elliprc(1.0, 1.0 + e) - 1) < 3e-16


def test_toml_method_exact_from_the_cli(tmp_path):
    """``[integration] method = "exact"`` in a file, and ``orbatt run --method exact``."""
    text = (SCEN / "paper-torque-free.toml").read_text().replace('method = "dop853"', 'method = "exact"')
    path = tmp_path / "free.toml"
    path.write_text(text)
    ds = orbatt.load_scenario(path).run()
    assert ds.attrs["method"] == "exact" and ds.orbatt.stats["steps"] == 0
    r = subprocess.run([sys.executable, "-m", "orbatt.cli", "run", str(SCEN / "paper-torque-free.toml"), "-o",
                        str(tmp_path / "a.nc"), "--method", "exact", "--quiet"], capture_output=True, text=True,
                       cwd=tempfile.gettempdir(), timeout=600)
    assert r.returncode == 0, r.stderr
    out = orbatt.open_dataset(tmp_path / "a.nc")
    assert out.attrs["method"] == "exact"
    np.testing.assert_allclose(out.q.values, ds.q.values, rtol=0, atol=1e-15)

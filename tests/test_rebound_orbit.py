"""The REBOUND orbit provider: agreement with Kepler, interpolation accuracy, J2 nodal
regression, third bodies, kernel, validation."""
import json
import math
import warnings

import astropy.units as u
import numpy as np
import pytest
from astropy.time import Time

from orbatt import quaternion as qt
from orbatt.core import potentials as kp
from orbatt.core import sampled as ks
from orbatt.errors import InputError
from orbatt.orbits import (GM_MOON, GM_SUN, J2_EARTH, R_J2_EARTH, KeplerOrbit, ReboundOrbit,
                           elements_from_state)

pytest.importorskip("rebound")

EPOCH = Time("2026-03-20T00:00:00", scale="utc")


@pytest.fixture(scope="module")
def paper():
    return KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg, true_anomaly=0 * u.deg,
                       body_radius=None)


@pytest.fixture(scope="module")
def paper_rebound(paper):
    return ReboundOrbit(paper, 10 * paper.period_value * u.s)


def _rel(a, b):
    return np.max(np.linalg.norm(a - b, axis=-1) / np.linalg.norm(b, axis=-1))


def test_two_body_ias15_agrees_with_kepler_over_10_orbits(paper, paper_rebound):
    ro = paper_rebound
    s = ro.samples
    assert s[0, 0] == 0.0 and ro.t_last >= 10 * paper.period_value
    pk, vk = paper.state(s[:, 0])
    assert _rel(s[:, 1:4], pk) < 1e-11  # REBOUND itself (measured 2.8e-12)
    assert _rel(s[:, 4:7], vk) < 1e-11
    assert _rel(s[:, 7:10], paper.acceleration(s[:, 0])) < 1e-11  # recomputed accelerations
    t = np.linspace(0, 10 * paper.period_value, 100001)
    pr, vr = ro.state(t)
    pk, vk = paper.state(t)
    err = _rel(pr, pk)
    assert err < 1e-9  # the requirement
    assert err < 1e-11  # what we measure: 4.8e-12 (REBOUND 2.8e-12 + interpolation 2.3e-12)
    assert _rel(vr, vk) < 5e-10  # the interpolant's derivative (measured 1.5e-10)
    assert np.max(qt.angle_between(ro.orbital_quaternion(t), paper.orbital_quaternion(t))) < 1e-10
    assert np.max(np.abs(ro.radius(t) / paper.radius(t) - 1)) < 1e-11
    assert np.max(np.abs(ro.true_anomaly(t) - paper.true_anomaly(t))) < 1e-8  # osculating, from v
    assert np.allclose(ro.orbital_rate(t), paper.orbital_rate(t), rtol=0, atol=1e-9 * paper.n_value)
    assert ro.period_value == paper.period_value and ro.gm == paper.gm


def test_two_body_whfast_agrees_with_kepler(paper):
    ro = ReboundOrbit(paper, 10 * paper.period_value * u.s, integrator="whfast")
    t = np.linspace(0, 10 * paper.period_value, 20001)
    assert _rel(ro.state(t)[0], paper.state(t)[0]) < 1e-9  # measured 1.9e-11 (uniform samples)
    s = ro.samples
    assert np.allclose(np.diff(s[:, 0]), ro.dt, rtol=1e-9)  # one sample per WHFast step
    assert _rel(s[:, 7:10], paper.acceleration(s[:, 0])) < 1e-11  # the Keplerian term is included


@pytest.mark.parametrize("a, e, bound", [(7000, 0.0, 1e-12), (7000, 0.2, 6e-12), (26600, 0.74, 2e-10)])
def test_interpolation_error_bounds(a, e, bound):
    """The documented accuracy of the quintic Hermite at 128 samples per orbit (two-body,
    so Kepler is the truth; REBOUND contributes < 1e-13 over 2 orbits)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        k = KeplerOrbit(a * u.km, e, 63.4 * u.deg, 30 * u.deg, 270 * u.deg, mean_anomaly=0.3 * u.rad)
    ro = ReboundOrbit(k, 2 * k.period_value * u.s)
    t = np.linspace(0, 2 * k.period_value, 100001)
    assert _rel(ro.state(t)[0], k.state(t)[0]) < bound
    # error ~ N^-6: halving the density costs ~64x
    ro64 = ReboundOrbit(k, 2 * k.period_value * u.s, samples_per_orbit=64)
    assert _rel(ro64.state(t)[0], k.state(t)[0]) > 10 * _rel(ro.state(t)[0], k.state(t)[0])


def test_sampled_kernel_matches_provider(paper, paper_rebound):
    ro = paper_rebound
    kind, params, table = ro.kernel()
    assert kind == kp.GRAVITY_GRADIENT_SAMPLED and params[0] == ro.gm
    assert params[1] == 0.0 and params[2] == ro.t_last and table is ro.samples
    rng = np.random.default_rng(3)
    t = np.concatenate([np.sort(rng.uniform(0, ro.t_last, 500)), rng.uniform(0, ro.t_last, 100),
                        [0.0, ro.t_last]])
    work = kp.new_work()
    r_ref = ro.radius(t)
    x_ref = ro.radial_direction(t)
    for ti, ri, xi in zip(t, r_ref, x_ref):
        r, x = ks.sampled_radial(ti, table, work)
        assert r == pytest.approx(ri, rel=1e-15)
        assert np.allclose(x, xi, rtol=0, atol=1e-15)
        i = ks.find_interval(table, ti, work)
        assert table[i, 0] <= ti <= table[i + 1, 0]
    with pytest.raises(ValueError, match="outside the sampled span"):
        ks.sampled_radial(ro.t_last + 1.0, table, work)
    with pytest.raises(ValueError, match="outside the sampled span"):
        ks.sampled_radial(-1.0, table, work)
    with pytest.raises(InputError, match="outside the sampled span"):
        ro.state(np.array([0.0, ro.t_last + 1.0]))


def test_interpolant_reproduces_the_samples(paper_rebound):
    s = paper_rebound.samples
    pos, vel, acc = ks.sampled_many(np.ascontiguousarray(s[:, 0]), s)
    assert np.allclose(pos, s[:, 1:4], rtol=0, atol=1e-11)
    assert np.allclose(vel, s[:, 4:7], rtol=0, atol=1e-14)
    assert np.allclose(acc, s[:, 7:10], rtol=0, atol=1e-17)


def test_j2_mean_nodal_regression_matches_classical_rate(paper):
    """30 days with J2: the fitted node drift vs -(3/2) n J2 (R/p)^2 cos i. The samples are
    exact REBOUND states, so a coarse sampling suffices here (fast)."""
    ro = ReboundOrbit(paper, 30 * u.day, perturbations=["j2"], samples_per_orbit=16)
    s = ro.samples
    el = elements_from_state(s[:, 1:4], s[:, 4:7], paper.gm)
    t = s[:, 0]
    slope = np.polyfit(t, np.unwrap(el["raan"]), 1)[0]

    def rate(a, e, inc):
        n = math.sqrt(paper.gm / a**3)
        return -1.5 * n * J2_EARTH * (R_J2_EARTH / (a * (1 - e * e))) ** 2 * math.cos(inc)

    # mean elements: time averages of the osculating ones (first order in J2)
    avg = lambda x: np.trapezoid(x, t) / (t[-1] - t[0])  # noqa: E731
    mean_rate = rate(avg(el["a"]), avg(el["e"]), avg(el["inc"]))
    assert abs(slope / mean_rate - 1) < 0.01  # measured 0.25 % (the rest is O(J2^2))
    assert abs(slope / rate(paper.a_value, paper.e, paper.inc) - 1) < 0.01  # initial osculating: 0.51 %
    assert slope * 30 * 86400 == pytest.approx(-3.55, abs=0.05)  # about -203 deg in 30 days
    # inclination has no secular drift under J2
    assert abs(np.polyfit(t, el["inc"], 1)[0]) * 30 * 86400 < 1e-4


def test_j2_whfast_agrees_with_ias15(paper):
    t_end = 2 * paper.period_value * u.s
    a = ReboundOrbit(paper, t_end, perturbations=["j2"])
    b = ReboundOrbit(paper, t_end, perturbations=["j2"], integrator="whfast", dt=paper.period_value / 1024 * u.s)
    t = np.linspace(0, 2 * paper.period_value, 5001)
    assert _rel(b.state(t)[0], a.state(t)[0]) < 1e-6  # WHFast is 2nd order in the J2 kick
    d = a.describe()
    assert d["j2"] == J2_EARTH and d["reference_radius_km"] == R_J2_EARTH
    # the orbital frame turns about o1 when J2 pushes out of plane: rate (r a_n / h, 0, h / r^2)
    w = a.orbital_rate(t)
    assert np.max(np.abs(w[:, 0])) > 1e-3 * paper.n_value and np.all(w[:, 1] == 0)
    dt = 0.5
    pq = a.orbital_quaternion
    tt = t[2:-2]
    pd = (pq(tt - 2 * dt) - 8 * pq(tt - dt) + 8 * pq(tt + dt) - pq(tt + 2 * dt)) / (12 * dt)
    wf = 2 * qt.mul(qt.conj(pq(tt)), pd)[:, 1:]
    assert np.allclose(wf, w[2:-2], rtol=0, atol=1e-7 * paper.n_value)


def test_moon_and_sun_from_the_builtin_ephemeris():
    from astropy.coordinates import get_body_barycentric_posvel

    k = KeplerOrbit(7000 * u.km, 0.01, 30 * u.deg, 45 * u.deg, 15 * u.deg, epoch=EPOCH)
    ro = ReboundOrbit(k, 0.25 * u.day, perturbations=["moon", "sun"])
    s = ro.samples
    x = s[0, 1:4]
    pe, _ = get_body_barycentric_posvel("earth", EPOCH, ephemeris="builtin")
    tidal = np.zeros(3)
    for name, gm in (("moon", GM_MOON), ("sun", GM_SUN)):
        pb, _ = get_body_barycentric_posvel(name, EPOCH, ephemeris="builtin")
        rb = (pb.xyz - pe.xyz).to_value(u.km)
        if name == "moon":
            assert 356000 < np.linalg.norm(rb) < 407000
        tidal += gm * ((rb - x) / np.linalg.norm(rb - x) ** 3 - rb / np.linalg.norm(rb) ** 3)
    perturbation = s[0, 7:10] + k.gm * x / np.linalg.norm(x) ** 3
    assert np.linalg.norm(perturbation - tidal) < 1e-8 * np.linalg.norm(tidal)  # 1e-9 km/s^2 scale
    two_body = ReboundOrbit(k, 0.25 * u.day)
    t = np.linspace(0, 0.25 * 86400, 501)
    dx = np.max(np.linalg.norm(ro.state(t)[0] - two_body.state(t)[0], axis=-1))
    assert 1e-4 < dx < 1.0  # km: lunisolar perturbation in LEO over 6 h
    d = ro.describe()
    json.dumps(d)
    assert d["perturbations"] == ["moon", "sun"] and d["epoch"].startswith("2026-03-20")
    # WHFast (Jacobi coordinates: central body, satellite, Moon, Sun) handles them too
    wh = ReboundOrbit(k, 0.25 * u.day, perturbations=["moon", "sun", "j2"], integrator="whfast",
                      dt=k.period_value / 512 * u.s)
    ias = ReboundOrbit(k, 0.25 * u.day, perturbations=["moon", "sun", "j2"])
    assert _rel(wh.state(t)[0], ias.state(t)[0]) < 1e-6


@pytest.mark.parametrize("kwargs, match", [
    (dict(perturbations=["j2", "mars"]), "perturbations: 'mars' is not known"),
    (dict(perturbations=["moon"]), "epoch: third bodies"),
    (dict(integrator="rk4"), "integrator: 'rk4' is not known"),
    (dict(samples_per_orbit=4), "samples_per_orbit: 4 must be an integer >= 8"),
    (dict(samples_per_orbit=10.5), "samples_per_orbit"),
    (dict(dt=10 * u.s), "dt: only used by integrator='whfast'"),
    (dict(integrator="whfast", epsilon=1e-9), "epsilon: only used by integrator='ias15'"),
    (dict(integrator="whfast", dt=-1 * u.s), "dt: .* must be a positive time"),
])
def test_bad_rebound_options(paper, kwargs, match):
    with pytest.raises(InputError, match=match):
        ReboundOrbit(paper, 100 * u.s, **kwargs)


def test_bad_rebound_setup():
    k = KeplerOrbit(7000 * u.km, 0.01, 0, 0, 0)
    with pytest.raises(InputError, match="t_end: .* must be one positive time"):
        ReboundOrbit(k, -5 * u.s)
    with pytest.raises(InputError, match="t_end: .* wrong dimension"):
        ReboundOrbit(k, 5 * u.km)
    with pytest.raises(InputError, match="initial: expected a KeplerOrbit"):
        ReboundOrbit("orbit", 5 * u.s)
    moon = KeplerOrbit(2000 * u.km, 0.01, 0, 0, 0, gm=4902.8 * u.km**3 / u.s**2, central_body="moon", epoch=EPOCH)
    with pytest.raises(InputError, match="third bodies of an Earth orbit"):
        ReboundOrbit(moon, 100 * u.s, perturbations=["sun"])
    with pytest.raises(InputError, match="j2: the J2 perturbation about 'moon' needs"):
        ReboundOrbit(moon, 100 * u.s, perturbations=["j2"])
    ok = ReboundOrbit(moon, 100 * u.s, perturbations=["J2"], j2=2.03e-4, reference_radius=1738 * u.km)
    assert ok.perturbations == ("j2",) and ok.j2 == 2.03e-4


def test_from_elements_and_describe():
    ro = ReboundOrbit.from_elements(7000 * u.km, 0.01, 30 * u.deg, 0 * u.deg, 0 * u.deg, t_end=600 * u.s,
                                    mean_anomaly=0.5 * u.rad, samples_per_orbit=64)
    d = ro.describe()
    json.dumps(d)
    assert d["type"] == "rebound" and d["integrator"] == "ias15" and d["perturbations"] == []
    assert d["n_samples"] == ro.samples.shape[0] and d["t_end_s"] == 600.0
    assert not ro.samples.flags.writeable


def test_environment_torques_on_a_rebound_orbit_sampled_over_the_run_only():
    """The environment tables sample a margin beyond the run; on a REBOUND orbit sampled over
    the run alone the margin is cut to it (issue 26: this failed at the run's start). The
    torques agree with the same environment on the Keplerian orbit REBOUND integrates
    (margin kept), to the tables' end intervals and the interpolation: measured 4.4e-11
    (drag), 1.9e-11 (magnetic), 7e-13 (gravity gradient), 4e-14 (SRP)."""
    from orbatt import RigidBody
    from orbatt.environment.atmosphere import PiecewiseExponentialAtmosphere
    from orbatt.environment.magnetic import DipoleField
    from orbatt.torques import EnvironmentTorques, Facet

    kep = KeplerOrbit(6778.137 * u.km, 0.001, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, epoch=EPOCH)
    reb = ReboundOrbit(kep, 1 * u.h)
    facets = [Facet(0.05 * u.m**2, [1.0, 0.0, 0.0], [0.05, 0.0, 0.02] * u.m, 2.2, 0.1, 0.3),
              Facet(0.02 * u.m**2, [0.0, 0.0, -1.0], [0.0, 0.01, -0.15] * u.m, 2.2, 0.0, 0.2)]
    kw = dict(facets=facets, drag=True, srp=True, residual_dipole=[0.01, 0.0, 0.003] * u.A * u.m**2,
              atmosphere=PiecewiseExponentialAtmosphere(), magnetic_field=DipoleField(EPOCH))
    env_reb = EnvironmentTorques(reb, 1 * u.h, **kw)
    env_kep = EnvironmentTorques(kep, 1 * u.h, **kw)
    body = RigidBody([0.04, 0.04, 0.007] * u.kg * u.m**2)
    rng = np.random.default_rng(26)
    t = np.concatenate([[0.0, 3600.0], rng.uniform(0.0, 3600.0, 40)])
    q = qt.normalize(rng.normal(size=(t.size, 4)))
    a, b = env_reb.term_torques(body, t, q), env_kep.term_torques(body, t, q)
    assert env_reb.term_names == env_kep.term_names == ["gravity_gradient", "drag", "srp", "magnetic"]
    for k, name in enumerate(env_reb.term_names):
        assert np.abs(a[:, k] - b[:, k]).max() < 1e-9 * np.abs(b[:, k]).max(), name
    with pytest.raises(InputError, match="t_end: .* outside the span .* larger t_end"):
        EnvironmentTorques(reb, 2 * u.h, **kw)


def test_particle_reads_fenced_the_public_way_gives_the_same_bits(paper, monkeypatch):
    """The fast path ``rebound-particles`` (orbatt.fast_paths) reads the particles from
    REBOUND's memory; its check against the attributes passes with this REBOUND, and the
    attributes alone give the same samples bit for bit (issue 34)."""
    from orbatt import fast_paths
    from orbatt.orbits import rebound as orb

    assert "rebound-particles" in fast_paths.PATHS and "rebound-particles" in fast_paths.active()
    monkeypatch.setitem(orb._RAW_READS, "ok", None if fast_paths.ENABLED else False)
    fast = ReboundOrbit(paper, paper.period_value * u.s, perturbations=("j2",)).samples
    assert orb._RAW_READS["ok"] is fast_paths.ENABLED and orb.raw_reads_in_use() is fast_paths.ENABLED
    monkeypatch.setitem(orb._RAW_READS, "ok", False)
    public = ReboundOrbit(paper, paper.period_value * u.s, perturbations=("j2",)).samples
    assert fast.shape == public.shape and fast.tobytes() == public.tobytes()
    assert not fast_paths.active()["rebound-particles"]


def test_particle_reads_turn_to_the_attributes_where_the_memory_disagrees(paper, monkeypatch):
    """A REBOUND whose particle struct no longer starts with x .. az: the first check sees it,
    the path turns off for the process, and the samples are the attributes' (still right)."""
    from orbatt.orbits import rebound as orb

    monkeypatch.setitem(orb._RAW_READS, "ok", False)
    want = ReboundOrbit(paper, 0.5 * paper.period_value * u.s, integrator="whfast").samples
    real = orb._raw_view
    monkeypatch.setattr(orb, "_raw_view", lambda sim, n: real(sim, n)[:, ::-1])  # another field order
    monkeypatch.setitem(orb._RAW_READS, "ok", None)
    got = ReboundOrbit(paper, 0.5 * paper.period_value * u.s, integrator="whfast").samples
    assert orb._RAW_READS["ok"] is False and not orb.raw_reads_in_use()
    assert got.tobytes() == want.tobytes()
    monkeypatch.setattr(orb, "_raw_view", lambda sim, n: (_ for _ in ()).throw(AttributeError("_particles")))
    monkeypatch.setitem(orb._RAW_READS, "ok", None)  # a REBOUND without the private array
    assert ReboundOrbit(paper, 0.5 * paper.period_value * u.s, integrator="whfast").samples.tobytes() == want.tobytes()
    assert orb._RAW_READS["ok"] is False

"""Objects answer in the user's units (issue 13 §4): KeplerOrbit's period, n, a as
Quantities (floats under ``*_value``), reprs with units, and ReboundOrbit from a
``rebound.Simulation`` the user built."""
from __future__ import annotations

import math
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest

import orbatt
from orbatt.errors import InputError
from orbatt.orbits import KeplerOrbit, ReboundOrbit


@pytest.fixture(scope="module")
def paper():
    return KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg, body_radius=None)


def test_kepler_answers_in_quantities(paper):
    assert paper.period.unit == u.s and paper.period.value == paper.period_value
    assert abs(paper.period.to_value(u.min) - 97.14) < 0.01
    assert paper.n.unit == u.rad / u.s and paper.n.value == paper.n_value
    assert paper.a == 7000 * u.km and paper.a_value == 7000.0
    au = KeplerOrbit(1 * u.AU, 0.0167, 0, 0, 0, gm="1.32712440018e11 km3 / s2")
    assert au.a.unit == u.AU and abs(au.a.value - 1) < 1e-15  # in the unit given
    assert abs(au.period.to_value(u.d) - 365.256) < 1e-3
    plain = KeplerOrbit(1.0, 0.1, 0, 0, 0, gm=1.0)
    assert plain.period.unit == u.one and plain.n.unit == u.one and plain.a.unit == u.one


def test_reprs_carry_units(paper):
    assert repr(orbatt.RigidBody([12, 15, 18] * u.kg * u.m**2)) == "RigidBody(inertia=[12, 15, 18] kg m^2)"
    assert repr(orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)) == "RigidBody(inertia=[400, 500, 600] kg km^2)"
    assert repr(orbatt.RigidBody([4e3, 5e3, 6e3] * u.kg * u.m**2)) == "RigidBody(inertia=[0.004, 0.005, 0.006] kg km^2)"
    assert repr(orbatt.RigidBody([1.0, 1.2, 1.5])) == "RigidBody(inertia=[1, 1.2, 1.5] (dimensionless))"
    r = repr(paper)
    assert r.startswith("KeplerOrbit(a=7000 km, central_body='custom'") or r.startswith("KeplerOrbit(a=7000 km")
    assert "i=30 deg" in r and "period=5828." in r and " s" in r
    assert repr(orbatt.GravityGradient(paper)) == f"GravityGradient(orbit={r})"


def test_dataset_accessor_repr():
    ds = orbatt.load_scenario(Path(__file__).resolve().parent.parent / "scenarios" / "paper-torque-free.toml").run()
    text = repr(ds.orbatt)
    assert text.splitlines()[0].startswith("<orbatt Dataset:") and "outputs" in text and "dimensionless" in text


def _two_body(units=None):
    import rebound

    sim = rebound.Simulation()
    if units:
        sim.units = units
    return sim


def test_rebound_orbit_from_a_simulation_in_km_s(paper):
    sim = _two_body()
    sim.G = 1.0
    r, v = paper.state(0.0)
    sim.add(m=paper.gm)
    sim.add(m=0.0, x=r[0], y=r[1], z=r[2], vx=v[0], vy=v[1], vz=v[2])
    ro = ReboundOrbit.from_simulation(sim, t_end=2 * paper.period, units=("km", "s"))
    t = np.linspace(0, 2 * paper.period_value, 501)
    assert np.max(np.linalg.norm(ro.state(t)[0] - paper.state(t)[0], axis=-1)) < 1e-7  # km
    assert abs(ro.gm - paper.gm) < 1e-9 and ro.perturbations == ("simulation",)
    assert ro.period.unit == u.s and abs(ro.period_value / paper.period_value - 1) < 1e-12


def test_rebound_orbit_from_a_simulation_with_its_own_units():
    # the Earth about the Sun in REBOUND's (au, yr, msun): units read from sim.units
    sim = _two_body(("au", "yr", "msun"))
    sim.add(m=1.0)
    sim.add(m=0.0, a=1.0, e=0.0167)
    ro = ReboundOrbit.from_simulation(sim, t_end=0.5)  # half a year, in the simulation's unit
    gm_sun = 39.476926421373 * (u.au**3 / u.yr**2)
    assert abs(ro.gm / gm_sun.to_value(u.km**3 / u.s**2) - 1) < 1e-12
    assert abs(ro.t_last - (0.5 * u.yr).to_value(u.s)) < 1e-3
    kep = KeplerOrbit(1 * u.au, 0.0167, 0, 0, 0, gm=gm_sun)
    t = np.linspace(0, ro.t_last, 101)
    rel = np.linalg.norm(ro.state(t)[0] - kep.state(t)[0], axis=-1) / kep.radius(t)
    assert np.max(rel) < 1e-10
    # normalized: plain numbers as REBOUND has them (G = 1)
    sim = _two_body()
    sim.add(m=1.0)
    sim.add(m=0.0, a=1.0, e=0.1)
    rn = ReboundOrbit.from_simulation(sim, t_end=2 * math.pi, units="normalized")
    assert rn.dimensionless and abs(rn.period_value - 2 * math.pi) < 1e-12


def test_rebound_simulation_without_units_refused():
    sim = _two_body()
    sim.add(m=1.0)
    sim.add(m=0.0, a=1.0)
    with pytest.raises(InputError, match="^units: the simulation's units are not set"):
        ReboundOrbit.from_simulation(sim, t_end=1.0)
    with pytest.raises(InputError, match="^particle/central: 5/0"):
        ReboundOrbit.from_simulation(sim, t_end=1.0, particle=5, units=("km", "s"))
    with pytest.raises(InputError, match="^units: .* is not \\(length, time\\)"):
        ReboundOrbit.from_simulation(sim, t_end=1.0, units=("s", "km"))


def test_orbit_quantities_in_one_call_are_the_separate_methods(paper):
    """``quantities(t)`` (one Kepler solve / one interpolation) gives the values of
    radius, orbital_quaternion, true_anomaly and state bit for bit."""
    t = np.linspace(0.0, 7000.0, 9)
    for orbit in (paper, ReboundOrbit(paper, 7000 * u.s)):
        r, p, f, pos, vel = orbit.quantities(t)
        pos1, vel1 = orbit.state(t)
        for a, b in ((r, orbit.radius(t)), (p, orbit.orbital_quaternion(t)), (f, orbit.true_anomaly(t)),
                     (pos, pos1), (vel, vel1)):
            assert a.shape == b.shape and a.tobytes() == b.tobytes()

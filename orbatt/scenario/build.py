"""Building the objects of a study from a validated :class:`~orbatt.scenario.schema.Spec`:
the orbit, the potential, the initial state and the output times.

Every builder takes a :class:`~orbatt.scenario.fields.FieldContext` and reports an
:class:`~orbatt.errors.InputError` of the object it builds as a
:class:`~orbatt.errors.ScenarioError` naming the file and the table.
"""
from __future__ import annotations

import math

import numpy as np

from .. import quaternion as qt
from .. import units as U
from ..errors import InputError, ScenarioError
from ..orbits import KeplerOrbit, ReboundOrbit, TleOrbit
from ..potentials import GravityGradient, HeavyTop, TorqueFree
from ..state import State
from ..orbital import state_from_orbital

__all__ = ["build_kepler_orbit", "build_rebound_orbit", "build_tle_orbit", "tle_period", "build_potential", "build_initial_state",
           "build_output_times"]


def build_kepler_orbit(ctx, o):
    """The :class:`~orbatt.orbits.KeplerOrbit` of a validated ``[orbit]`` table ``o``
    (internal units: km, rad; ``gm`` in km^3 s^-2; plain numbers in normalized units). For ``provider = "rebound"`` it is the
    initial osculating orbit (and gives the period for ``"N orbits"``)."""

    plain = o.get("dimensionless", False)  # normalized units: a and gm as plain numbers
    lu, gu = (1.0, 1.0) if plain else (U.LENGTH, U.GM)
    kw = {o["anomaly_kind"]: o["anomaly"] * U.ANGLE}
    if o["central_body"] is None:
        kw["gm"] = o["gm"] * gu
    else:
        kw["central_body"] = o["central_body"]
    if o["epoch"] is not None:
        kw["epoch"] = o["epoch"]
    try:  # a periapsis inside the central body warns (PeriapsisWarning), as the paper's Sect. 6.2 orbit does
        return KeplerOrbit(o["a"] * lu, o["e"], o["i"] * U.ANGLE, o["raan"] * U.ANGLE,
                           o["argp"] * U.ANGLE, **kw)
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def build_rebound_orbit(ctx, o, kepler, t_end):
    """The :class:`~orbatt.orbits.ReboundOrbit` from ``kepler`` (its initial osculating
    orbit) over ``[0, t_end]`` (s), with the table's perturbations and integrator."""

    try:
        return ReboundOrbit(kepler, t_end if kepler.dimensionless else t_end * U.TIME,
                            perturbations=o["perturbations"], integrator=o["integrator"])
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def tle_period(o):
    """Orbital period (s) of the TLE of a validated ``[orbit]`` table (from its mean motion;
    converts ``"N orbits"`` before the orbit is sampled)."""
    from sgp4.api import Satrec

    sat = Satrec.twoline2rv(o["tle"][-2], o["tle"][-1])
    return 2.0 * math.pi / (sat.no_kozai / 60.0)


def build_tle_orbit(ctx, o, t_end):
    """The :class:`~orbatt.orbits.TleOrbit` of a validated ``[orbit]`` table over
    ``[0, t_end]`` (s); an SGP4 failure along the span (a decayed orbit) names ``tle``."""
    try:
        return TleOrbit(o["tle"], t_end * U.TIME, epoch=o["epoch"])
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def build_output_times(ctx, integration, period):
    """``(times, t_end)``: the output times ``k * output_step``, ``k = 0 .. floor(t_end /
    output_step)`` (s, or dimensionless); ``period`` (s) converts ``"N orbits"``."""
    t_end = _duration(integration["t_end"], period)
    step_out = _duration(integration["output_step"], period)
    if step_out > t_end:
        raise ctx.error("[integration] output_step", f"{step_out:g} is longer than t_end = {t_end:g}")
    n = int(math.floor(t_end / step_out * (1 + 1e-12)))
    return np.arange(n + 1, dtype=np.float64) * step_out, t_end


def _duration(t, period):
    kind, value = t
    return value * period if kind == "orbits" else value


def build_potential(spec, orbit):
    """The potential of ``spec.potential_kind`` (a gravity gradient needs the ``orbit``)."""

    if spec.potential_kind == "torque-free":
        return TorqueFree()
    if spec.potential_kind == "heavy-top":
        h = spec.heavy_top
        if spec.dimensionless:
            return HeavyTop(h["mass_g"], h["center_of_mass"], sign=h["sign"])
        return HeavyTop(h["mass_g"] * U.MASS * U.LENGTH / U.TIME**2, h["center_of_mass"] * U.LENGTH,
                        sign=h["sign"])
    return GravityGradient(orbit)


def build_initial_state(ctx, spec, body, orbit):
    """The initial :class:`~orbatt.state.State` of ``[initial]``, in inertial components
    (converted from the orbital frame when ``frame = "orbital"``)."""

    ini = spec.initial
    try:
        if "euler_momenta" in ini:
            if spec.frame == "orbital":
                raise ctx.error("[initial] frame", "euler_momenta are inertial; use omega with frame = 'orbital'")
            return State.from_euler(body, ini["euler_313"], ini["euler_momenta"])
        q = ini["q"] if "q" in ini else qt.from_euler313(*ini["euler_313"])
        if spec.frame == "orbital":

            if "Q" in ini:
                raise ctx.error("[initial] Q", "Q is inertial; with frame = 'orbital' give omega (relative rates)")
            return state_from_orbital(body, orbit, q, ini["omega"] if body.dimensionless else ini["omega"] * U.RATE)
        if "Q" in ini:
            return State(body, q, ini["Q"])
        w = ini["omega"] if body.dimensionless else ini["omega"] * U.RATE
        return State.from_omega(body, q, w)
    except ScenarioError:
        raise
    except InputError as exc:
        raise ctx.error("[initial]", str(exc)) from None

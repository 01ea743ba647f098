"""Time scales of a scenario's torques and control laws, for the work estimate of
:func:`orbatt.scenario.build.check_work`.

A torque ``tau`` on a body of smallest principal moment ``I`` makes it librate (or spin up) at
about ``sqrt(tau / I)`` rad/s; a PD law at ``sqrt(kp / I)`` with a damping rate ``kd / I``
(1/s: an explicit method needs a step below a few ``I / kd``); B-dot damps at ``gain B^2 / I``;
wheels spinning with momentum ``h`` make the body nutate at ``h / I``. Any method needs at
least one step per :data:`~orbatt.scenario.build.MAX_ANGLE_PER_STEP` of these angles, so a
meaningless magnitude (a 3.4e10 m^2 plate, a 1e-14 kg m^2 body with CubeSat torques,
``kp = kd = 1e6`` on a microsatellite) is refused before the run, naming its key.

Each estimate bounds the torque from above along the orbit: drag at the periapsis (the density
there, at most sea level's, the orbital speed plus the atmosphere's rotation), solar radiation
pressure fully reflected, the field at the periapsis of a dipole of the Earth's strength. The
wheels' motor torques (``max_torque``) turn the body like any torque (the wheel-limited rate).

Beside the angles, work that is counted, not turned (:func:`counted_work`, in steps' worth):
the flight software's ticks (``[control] period``: the step loop lands on every tick), the
environment tables' pieces (each end a knot the loop lands on) and samples (an NRLMSIS or IGRF
evaluation costs about :data:`SAMPLE_STEPS` steps), and the output times (each about
:data:`OUTPUT_STEPS` steps: the dense output, the derived variables, the Dataset).
"""
from __future__ import annotations

import math

import numpy as np

from ..environment.atmosphere import PiecewiseExponentialAtmosphere
from ..environment.sun import SRP_FLUX
from ..laws import law_of
from ..orbits import R_EARTH
from ..units import from_kernel

__all__ = ["torque_rates", "counted_work", "B_SURFACE", "RHO_MAX", "NRLMSIS_FACTOR", "OUTPUT_STEPS", "SAMPLE_STEPS"]

#: the geomagnetic field's largest strength at the Earth's surface (T; IGRF: about 66 uT near
#: the south magnetic pole), scaled by ``(R / r)^3`` along the orbit
B_SURFACE = 6.7e-5
#: the densest air a drag torque meets (kg/m^3): sea level's 1.225, with a margin
RHO_MAX = 1.5
#: NRLMSIS's density at the most active space weather over Vallado's mean table, at most
NRLMSIS_FACTOR = 10.0
#: the Earth's rotation rate (rad/s): the co-rotating atmosphere's speed adds to the orbit's
_OMEGA_EARTH = 7.2921159e-5
#: what one output time costs, in steps (a lower estimate: the dense output, the derived
#: variables and the Dataset's ~360 bytes; 1.44e6 outputs of the disturbed CubeSat: minutes)
OUTPUT_STEPS = 5.0
#: what one sample of an environment table costs, in steps: an NRLMSIS density or an IGRF
#: field (tens of microseconds each), a cheaper closed form (a dipole, the Sun) one step
SAMPLE_STEPS = {"nrlmsis": 10.0, "igrf": 10.0}
#: solar radiation pressure at 1 au (N/m^2)
_P_SUN = SRP_FLUX / 299792458.0


def _periapsis(spec):
    """``(r_p km, v_p km/s)`` at the periapsis of ``spec``'s orbit (None without a dimensional
    orbit)."""
    o = spec.orbit
    if o is None or spec.dimensionless:
        return None
    if o["provider"] == "tle":
        from sgp4.api import Satrec

        sat = Satrec.twoline2rv(o["tle"][-2], o["tle"][-1])
        gm, n, e = 398600.4418, sat.no_kozai / 60.0, sat.ecco
        a = (gm / n**2) ** (1.0 / 3.0)
    else:
        gm = o["gm"] if o.get("gm") is not None else 398600.4418
        a, e = o["a"], o["e"]
    r_p = a * (1.0 - e)
    return r_p, math.sqrt(gm * (2.0 / r_p - 1.0 / a))


def _density_bound(env, altitude_km):
    """Upper bound of the density (kg/m^3) at ``altitude_km`` for ``[environment]`` ``env``."""
    h = max(altitude_km, 0.0)
    if "density0" in env:
        exponent = min(-(h - env["altitude0"]) / env["scale_height"], 700.0)
        rho = env["density0"] * math.exp(exponent)
    else:
        atm = PiecewiseExponentialAtmosphere()
        rho = float(atm.density(None, np.array([[atm.body_radius + h, 0.0, 0.0]]))[0])
        if env.get("atmosphere") == "nrlmsis":
            rho *= NRLMSIS_FACTOR
    return min(rho, RHO_MAX)


def _facet_torques(spec, peri):
    """``(torque N m, key)`` bounds of drag and SRP on the facets."""
    tq = spec.torques
    out = []
    if not (tq["drag"] or tq["srp"]):
        return out
    r_p, v_p = peri if peri is not None else (R_EARTH, 8.0)
    q_drag = 0.0
    if tq["drag"]:
        v = (v_p + _OMEGA_EARTH * r_p) * 1e3
        q_drag = 0.5 * _density_bound(tq["environment"], r_p - R_EARTH) * v * v
    for k, f in enumerate(tq["facets"]):
        area = f["area"]  # m2
        arm = float(np.linalg.norm(f["position"]))  # m
        pressure = q_drag * f["drag_coefficient"] + (2.0 * _P_SUN if tq["srp"] else 0.0)
        out.append((pressure * area * arm, f"[[body.facets]] {k + 1} area"))
    return out


def torque_rates(spec):
    """The time scales of ``spec``'s torques and control laws.

    Parameters
    ----------
    spec : orbatt.scenario.schema.Spec
        A validated dimensional scenario (a dimensionless one has no torques or control).

    Returns
    -------
    list of (float, str, str)
        ``(rate rad/s, key, what)``: each term's rate, the scenario key whose magnitude sets
        it, and a phrase saying what it is; empty without torques and control.
    """
    if spec.dimensionless or (spec.torques is None and spec.control is None):
        return []
    inertia = from_kernel(float(np.min(spec.inertia)), "inertia")  # kg m^2
    peri = _periapsis(spec)
    b = B_SURFACE if peri is None else B_SURFACE * min(1.0, (R_EARTH / peri[0]) ** 3)
    torques = []  # (N m, key)
    rates = []
    tq = spec.torques
    if tq is not None:
        torques += _facet_torques(spec, peri)
        if tq["residual_dipole"] is not None:
            torques.append((float(np.linalg.norm(tq["residual_dipole"])) * b, "[torques] residual_dipole"))
        if tq.get("constant") is not None:
            torques.append((float(np.linalg.norm(tq["constant"])), "[torques] constant"))
    rates += [(math.sqrt(t / inertia), key, f"a torque of up to {t:.3g} N m") for t, key in torques if t > 0]
    c = spec.control
    if c is not None:
        law = c["control"]
        if law is not None:
            rates += law_of(law).time_scales(law, inertia, b)
        for k, w in enumerate(c["wheels"]):
            speed = max(abs(w["speed"]), w["max_speed"] or 0.0)
            h = w["inertia"] * speed
            if h > 0:
                rates.append((h / inertia, f"[[body.wheels]] {k + 1} speed",
                              f"the nutation of wheel momentum {h:.3g} N m s"))
            tw = w.get("max_torque") or 0.0
            if tw > 0:  # the motor's reaction on the body: the wheel-limited rate
                rates.append((math.sqrt(tw / inertia), f"[[body.wheels]] {k + 1} max_torque",
                              f"a wheel's motor torque of up to {tw:.3g} N m"))
    return [(r, key, what + f" on a body of smallest moment {inertia:.3g} kg m2") for r, key, what in rates]


def _tables(spec):
    """``(name, Pieces, sample key)`` of the environment tables ``spec``'s run samples along the
    orbit (:meth:`orbatt.torques.EnvironmentTorques.field_table`)."""
    from ..environment.tables import DENSITY_PIECES, LAYERED_DENSITY_PIECES, MAGNETIC_FIELD_PIECES, SUN_PIECES

    tq, c = spec.torques, spec.control
    law = (None if c is None else c["control"]) or {}
    env = {} if tq is None else tq["environment"]
    out = []
    if tq is not None and tq["drag"] and "density0" not in env:  # the exponential atmosphere: a closed form
        nrlmsis = env.get("atmosphere") == "nrlmsis"
        out.append(("density", DENSITY_PIECES if nrlmsis else LAYERED_DENSITY_PIECES, "nrlmsis" if nrlmsis else ""))
    if (tq is not None and tq["srp"]) or law.get("target") == "sun":
        out.append(("sun", SUN_PIECES, ""))
    fields = ([env.get("magnetic_field")] if tq is not None and tq["residual_dipole"] is not None else [])
    fields += [c["magnetic_field"]] if c is not None and c["magnetic_field"] is not None else []
    if fields:
        out.append(("field", MAGNETIC_FIELD_PIECES, "igrf" if "igrf" in fields else ""))
    return out


def counted_work(spec, t_end, outputs=0):
    """The work of ``spec``'s run over ``t_end`` (s) that does not turn the body, in steps.

    Parameters
    ----------
    spec : orbatt.scenario.schema.Spec or None
    t_end : float
        The span (s; the time unit of a dimensionless scenario).
    outputs : int
        The output times.

    Returns
    -------
    list of (float, str, str)
        ``(steps, key, what)``: the flight software's ticks (``[control] period``), the
        environment tables' knots and samples (``[integration] t_end``), the outputs
        (``[integration] output_step``), each with the key that sets it and a phrase.
    """
    out = []
    if outputs:
        out.append((outputs * OUTPUT_STEPS, "[integration] output_step",
                    f"{outputs:.3g} output times (about {OUTPUT_STEPS:g} steps' work each)"))
    if spec is None or spec.dimensionless:
        return out
    c = spec.control
    period = None if c is None or c["control"] is None else c["control"].get("period")
    if period:
        out.append((t_end / period, "[control] period",
                    f"the flight software's {t_end / period:.3g} ticks (period {period:.3g} s, a step each)"))
    from ..environment.tables import TABLE_MARGIN

    knots = samples = 0.0
    names = []
    for name, pieces, kind in _tables(spec):
        n = math.ceil((t_end + 2.0 * TABLE_MARGIN) / pieces.length)
        knots += n
        samples += n * (pieces.degree + 1) * SAMPLE_STEPS.get(kind, 1.0)
        names.append(f"{name}{' (' + kind + ')' if kind else ''}")
    if names:
        out.append((knots + samples, "[integration] t_end",
                    f"the environment tables ({', '.join(names)}) sampled along the orbit: {knots:.3g} pieces, "
                    f"{samples:.3g} samples' worth"))
    return out

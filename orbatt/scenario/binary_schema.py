"""Scenario files of binary asteroids: ``[orbit] provider = "coupled"`` (``docs/design.md`` §12).

The relative orbit (primary -> secondary) is integrated with the attitudes. Schema (keys
not listed are refused; quantities carry units, dimensional scenarios only)::

    [body]        the secondary: mass (required), inertia = [I1, I2, I3]
    [initial]     q and omega | q and Q; frame = "inertial" (default) | "orbital"
                  (orbital: q relative to the orbital frame, omega relative to it, body axes)
    [potential]   kind = "coupled" (default: the second-order mutual potential acts on the
                  orbit and both bodies) | "gravity-gradient" (the orbit feels the point masses
                  only, the secondary the torque of eq. 20, the primary none)
    [orbit]       provider = "coupled", primary_mass (required);
                  a, e, i, raan, argp, true_anomaly: osculating elements about G (M1 + M2),
                  angles from the inertial frame (the primary's axes at q = identity);
                  or position = [x, y, z], velocity = [vx, vy, vz] (inertial)
                  [[orbit.impulses]] time, delta_v = [radial, along-track, normal]
    [primary]     optional (else a point mass): inertia (required), q (body -> inertial,
                  default identity), omega (body rates, default 0)
    [integration] method = "dop853" (default) | "vern98" | "splitting", rtol, atol, t_end,
                  output_step ("N orbits": the initial osculating period); splitting: step
                  (dividing output_step and the impulse times), composition = "strang" |
                  "yoshida4" (default) | "suzuki4" | "mclachlan4" | "yoshida6" | "kahanli6"

    [sweep]       scenario keys varied by their paths, run by ``orbatt sweep``
                  (:mod:`orbatt.scenario.binary_sweep_schema`; ``orbatt run`` runs the nominal case)

Refused with a coupled orbit (until asked for): [torques], [environment], [control],
[[body.facets]], [[body.wheels]]. ``[primary]`` without ``provider = "coupled"`` is refused.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import units as U
from ..body import check_triangle
from ..errors import InputError
from .binary_sweep_schema import parse_binary_sweep
from .fields import parse_choice, parse_plain_vector, parse_quantity, parse_time, parse_vector
from .key_docs import parse_key_docs
from .ranges import Range

__all__ = ["BinarySpec", "is_binary", "parse_binary", "BINARY_TABLES", "IMPULSE_KEYS", "BINARY_KEY_DOCS",
           "BINARY_RANGES", "BINARY_METHODS", "BINARY_POTENTIALS"]

BINARY_TABLES = {
    "body": {"mass", "inertia"},
    "initial": {"q", "Q", "omega", "frame"},
    "potential": {"kind"},
    "orbit": {"provider", "primary_mass", "a", "e", "i", "raan", "argp", "true_anomaly", "position", "velocity",
              "impulses"},
    "primary": {"inertia", "q", "omega"},
    "integration": {"method", "rtol", "atol", "t_end", "output_step", "step", "composition"},
}
#: the keys of each ``[[orbit.impulses]]`` table
IMPULSE_KEYS = ("time", "delta_v")
BINARY_METHODS = ("dop853", "vern98", "splitting")
#: what each key of :data:`BINARY_TABLES` (and of ``[[orbit.impulses]]``) is: ``(dimension,
#: default, meaning)`` by table, as :data:`orbatt.scenario.schema.KEY_DOCS` for a single body;
#: ``docs/scenarios.md`` shows them (:mod:`orbatt.scenario.reference`; a test keeps every key
#: described)
BINARY_KEY_DOCS = parse_key_docs("""
[body]
mass     mass                       required  the secondary's mass M2 (the body whose attitude is always integrated)
inertia  mass x length^2, 3 values  required  the secondary's principal moments [I1, I2, I3] (triangle inequality)

[initial]
q      plain, 4 values         required    the secondary's attitude quaternion (scalar first), body -> `frame`
Q      momentum, 4 values      -           conjugate momentum Q = 2 q (0, I omega), instead of omega (frame =
                                           'inertial' only)
omega  angular rate, 3 values  required    the secondary's body rates (relative to the orbital frame when frame =
                                           'orbital'); or Q
frame  'inertial' | 'orbital'  'inertial'  the frame q and omega are relative to: 'orbital' is that of the
                                           relative orbit (radial, along-track, normal; refused for a radial
                                           orbit, r parallel to v)

[potential]
kind  'coupled' | 'gravity-gradient'  'coupled'  'coupled': the mutual potential to second order acts on the orbit
                                                 and both bodies; 'gravity-gradient': the orbit feels the point masses
                                                 only, the secondary the torque of eq. 20, the primary none

[orbit]
provider      'coupled'               required            the relative orbit (primary -> secondary) integrated with
                                                          the attitudes: a binary asteroid
primary_mass  mass                    required            the primary's mass M1
a             length                  one of the two      osculating semi-major axis about G (M1 + M2)
e             plain                   with a              osculating eccentricity, 0 <= e < 1
i             angle                   with a              inclination to the inertial s1-s2 plane (the primary's
                                                          axes at q = identity)
raan          angle                   with a              right ascension of the ascending node
argp          angle                   with a              argument of periapsis
true_anomaly  angle                   with a              true anomaly at t = 0
position      length, 3 values        one of the two      relative position, inertial (instead of the elements)
velocity      speed, 3 values         with position       relative velocity, inertial
impulses      array of tables         none                [[orbit.impulses]]: velocity changes of the secondary
                                                          (keys below)

[orbit.impulses]
time     time                    required  when (> 0, at most the last output; on the step grid for the
                                           splitting); impulses at one time are applied in the order written
delta_v  speed, 3 values         required  the secondary's velocity change relative to the primary: radial,
                                           along-track, normal (the orbital frame at that time)

[primary]
inertia  mass x length^2, 3 values  required (with [primary])  the primary's principal moments; without [primary]
                                                               the primary is a point mass
q        plain, 4 values            identity                   the primary's attitude, body -> inertial
omega    angular rate, 3 values     zero                       the primary's body rates

[integration]
method       'dop853' | 'vern98' | 'splitting'  'dop853'               the adaptive loops, or the symplectic splitting
                                                                       (fixed step)
rtol         plain                              1e-10 (adaptive)       relative tolerance (dop853, vern98)
atol         plain                              1e-12 (adaptive)       absolute tolerance (dop853, vern98)
step         time or 'N orbits'                 required by splitting  the splitting's fixed step; divides
                                                                       output_step and the impulse times
composition  text                               'yoshida4'             the splitting's composition: 'strang',
                                                                       'yoshida4', 'suzuki4', 'mclachlan4',
                                                                       'yoshida6', 'kahanli6'
t_end        time or 'N orbits'                 required               the span ('N orbits': the initial
                                                                       osculating period)
output_step  time or 'N orbits'                 required               spacing of the output times
""")
#: the physical range of each numeric key (:class:`orbatt.scenario.ranges.Range`, by table as
#: in :data:`BINARY_KEY_DOCS`; angles: :data:`orbatt.scenario.ranges.ANGLE_LIMIT`)
BINARY_RANGES = {
    # an impulse's components: up to 100 times the Earth-Moon orbital speed (an asteroid's
    # kinetic impact gives mm/s); the speed of light is no impulse
    ("orbit.impulses", "delta_v"): Range(None, 100.0, "km / s", signed=True),
    ("body", "inertia"): Range(1e-14, 1e51, "kg m2"),
    ("primary", "inertia"): Range(1e-14, 1e51, "kg m2"),
    ("initial", "omega"): Range(None, 1e4, "rad / s", signed=True),
    ("primary", "omega"): Range(None, 1e4, "rad / s", signed=True),
}


def _bounds(table, key, unit):
    """``(low, high)`` of ``[table] key`` (:data:`BINARY_RANGES`) in the astropy ``unit``."""
    return BINARY_RANGES[table, key].bounds(unit)
BINARY_POTENTIALS = ("coupled", "gravity-gradient")
_ELEMENTS = ("a", "e", "i", "raan", "argp", "true_anomaly")


@dataclass
class BinarySpec:
    """The validated content of a binary scenario, in internal units (kg, km, s, rad)."""

    name: str
    description: str
    text: str
    mass: float
    inertia: np.ndarray
    primary_mass: float
    potential_kind: str
    initial: dict
    orbit: dict
    integration: dict
    primary: dict | None = None
    dimensionless: bool = False
    sweep: object = None  # the [sweep] table (a SweepSpec), if any
    impulses: list = field(default_factory=list)


def is_binary(data) -> bool:
    """Whether the parsed TOML ``data`` asks for a coupled orbit (or has a ``[primary]``)."""
    orbit = data.get("orbit")
    return "primary" in data or (isinstance(orbit, dict) and orbit.get("provider") == "coupled")


def _table(ctx, data, name):
    val = data.get(name, {})
    if not isinstance(val, dict):
        raise ctx.error(name, f"must be a table [{name}], got {val!r}")
    for k in val:
        if k not in BINARY_TABLES[name]:
            raise ctx.error(f"[{name}] {k}", f"not used with [orbit] provider = 'coupled'; allowed keys in [{name}]: "
                                             f"{', '.join(sorted(BINARY_TABLES[name]))}")
    return val


def _moments(ctx, where, raw):
    table = "primary" if where.startswith("[primary]") else "body"
    m = parse_vector(ctx, where, raw, 3, U.INERTIA, dimensionless=False, bounds=_bounds(table, "inertia", U.INERTIA))
    try:
        check_triangle(m)
    except InputError as exc:
        raise ctx.error(where, f"{raw!r}: {str(exc).split(': ', 1)[-1]}") from None
    return m


def _positive(ctx, where, raw, unit):
    v = parse_quantity(ctx, where, raw, unit, dimensionless=False)
    if not v > 0:
        raise ctx.error(where, f"{raw!r} must be positive")
    return v


def _attitude(ctx, table, where, required=True):
    out = {}
    if "q" in table:
        q = parse_plain_vector(ctx, f"[{where}] q", table["q"], 4)
        n = float(np.linalg.norm(q))
        if abs(n - 1) > 1e-6:
            raise ctx.error(f"[{where}] q", f"{table['q']!r} has |q| = {n:.9g}, not 1; give a unit quaternion "
                                            "(scalar first)")
        out["q"] = q / n
    elif required:
        raise ctx.error(f"[{where}] q", "missing; give the attitude q = [q0, q1, q2, q3] (scalar first)")
    else:
        out["q"] = np.array([1.0, 0.0, 0.0, 0.0])
    if "omega" in table:
        out["omega"] = parse_vector(ctx, f"[{where}] omega", table["omega"], 3, U.RATE, dimensionless=False,
                                    bounds=_bounds(where, "omega", U.RATE))
    elif "Q" in table:
        out["Q"] = parse_plain_vector(ctx, f"[{where}] Q", table["Q"], 4)
    elif required:
        raise ctx.error(f"[{where}]", "give omega (body rates) or Q with q")
    else:
        out["omega"] = np.zeros(3)
    return out


def parse_binary(ctx, data, text, source):
    """Validate a binary scenario (module docstring); raise :class:`ScenarioError` naming the key."""
    from pathlib import Path

    orbit = data.get("orbit")
    if not isinstance(orbit, dict) or orbit.get("provider") != "coupled":
        raise ctx.error("[primary]", "only used with [orbit] provider = 'coupled' (the orbit integrated with the "
                                     "attitudes); set provider = 'coupled' or remove [primary]")
    for key in data:
        if key in ("name", "description", "sweep") or key in BINARY_TABLES:
            continue
        if key in ("torques", "environment", "control"):
            raise ctx.error(f"[{key}]", "not supported with [orbit] provider = 'coupled' yet (refused until asked "
                                        "for); remove it")
        raise ctx.error(key, f"unknown table or key; allowed: {', '.join(sorted(BINARY_TABLES))}, name, description")
    for t in ("body", "initial", "integration"):
        if t not in data:
            raise ctx.error(f"[{t}]", "missing table; a binary scenario needs [body], [initial], [orbit], "
                                      "[integration]")
    body = _table(ctx, data, "body")
    if "mass" not in body:
        raise ctx.error("[body] mass", "missing; provider = 'coupled' needs the secondary's mass, e.g. '4.3e9 kg'")
    mass = _positive(ctx, "[body] mass", body["mass"], U.MASS)
    if "inertia" not in body:
        raise ctx.error("[body] inertia", "missing; give the principal moments [I1, I2, I3]")
    inertia = _moments(ctx, "[body] inertia", body["inertia"])
    o = _table(ctx, data, "orbit")
    if "primary_mass" not in o:
        raise ctx.error("[orbit] primary_mass", "missing; provider = 'coupled' needs the primary's mass")
    primary_mass = _positive(ctx, "[orbit] primary_mass", o["primary_mass"], U.MASS)
    orb = _parse_relative_orbit(ctx, o)
    primary = None
    if "primary" in data:
        p = _table(ctx, data, "primary")
        if "inertia" not in p:
            raise ctx.error("[primary] inertia", "missing; give the primary's principal moments (or remove [primary] "
                                                 "for a point mass)")
        primary = {"inertia": _moments(ctx, "[primary] inertia", p["inertia"]), **_attitude(ctx, p, "primary", False)}
        if "Q" in primary:
            raise ctx.error("[primary] Q", "not used; give omega")
    kind = parse_choice(ctx, "[potential] kind", _table(ctx, data, "potential").get("kind", "coupled"),
                        BINARY_POTENTIALS)
    init = _table(ctx, data, "initial")
    initial = _attitude(ctx, init, "initial")
    initial["frame"] = parse_choice(ctx, "[initial] frame", init.get("frame", "inertial"), ("inertial", "orbital"))
    if initial["frame"] == "orbital" and "Q" in initial:
        raise ctx.error("[initial] Q", "only with frame = 'inertial'; give omega relative to the orbital frame")
    g = _table(ctx, data, "integration")
    integ = {"method": parse_choice(ctx, "[integration] method", g.get("method", "dop853"), BINARY_METHODS)}
    for k in ("rtol", "atol"):
        if k in g:
            v = g[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (0 < v <= 0.1 and math.isfinite(v)):
                raise ctx.error(f"[integration] {k}", f"{v!r} must be a number in (0, 0.1], e.g. {k} = 1e-12")
            integ[k] = float(v)
    if integ["method"] == "splitting":
        from ..core.splitting import COMPOSITIONS

        if "step" not in g:
            raise ctx.error("[integration] step", "missing; method = 'splitting' needs a fixed step that divides "
                                                  "output_step, e.g. step = '0.01 orbits'")
        integ["step"] = parse_time(ctx, "[integration] step", g["step"], False, orb)
        integ["composition"] = parse_choice(ctx, "[integration] composition", g.get("composition", "yoshida4"),
                                            tuple(COMPOSITIONS))
    else:
        for k in ("step", "composition"):
            if k in g:
                raise ctx.error(f"[integration] {k}", "only used by method = 'splitting'; remove it")
    for k in ("t_end", "output_step"):
        if k not in g:
            raise ctx.error(f"[integration] {k}", "missing; give the span t_end and the output_step")
        integ[k] = parse_time(ctx, f"[integration] {k}", g[k], False, orb, bounds=(None, 1e15))
    impulses = _parse_impulses(ctx, o.get("impulses", []))
    name = data.get("name", Path(source).stem)
    desc = data.get("description", "")
    if not isinstance(name, str) or not isinstance(desc, str):
        raise ctx.error("name/description", "must be strings")
    sweep = parse_binary_sweep(ctx, data["sweep"], data, kind) if "sweep" in data else None
    return BinarySpec(name=name, description=desc, text=text, mass=mass, inertia=inertia, primary_mass=primary_mass,
                      potential_kind=kind, initial=initial, orbit=orb, integration=integ, primary=primary,
                      impulses=impulses, sweep=sweep)


def _parse_relative_orbit(ctx, o):
    has_el = [k for k in _ELEMENTS if k in o]
    has_rv = [k for k in ("position", "velocity") if k in o]
    if has_el and has_rv:
        raise ctx.error(f"[orbit] {has_rv[0]}", "give either the elements a, e, i, raan, argp, true_anomaly or "
                                                "position and velocity, not both")
    if has_rv:
        if len(has_rv) != 2:
            raise ctx.error("[orbit] velocity", "give both position and velocity (inertial, primary -> secondary)")
        return {"provider": "coupled", "position": parse_vector(ctx, "[orbit] position", o["position"], 3, U.LENGTH,
                                                               dimensionless=False),
                "velocity": parse_vector(ctx, "[orbit] velocity", o["velocity"], 3, U.LENGTH / U.TIME,
                                         dimensionless=False)}
    for k in _ELEMENTS:
        if k not in o:
            raise ctx.error(f"[orbit] {k}", "missing; give a, e, i, raan, argp, true_anomaly (or position and "
                                            "velocity)")
    out = {"provider": "coupled", "a": _positive(ctx, "[orbit] a", o["a"], U.LENGTH)}
    out["e"] = parse_quantity(ctx, "[orbit] e", o["e"], U.DIMENSIONLESS, dimensionless=True)
    if not 0 <= out["e"] < 1:
        raise ctx.error("[orbit] e", f"{o['e']!r} is outside [0, 1): the mutual orbit must be bound")
    for k in ("i", "raan", "argp", "true_anomaly"):
        out[k] = parse_quantity(ctx, f"[orbit] {k}", o[k], U.ANGLE, dimensionless=False)
    return out


def _parse_impulses(ctx, raw):
    if not isinstance(raw, list):
        raise ctx.error("[orbit] impulses", "write [[orbit.impulses]] tables with time and delta_v")
    out = []
    for j, imp in enumerate(raw):
        where = f"[[orbit.impulses]] {j}"
        if not isinstance(imp, dict) or set(imp) != set(IMPULSE_KEYS):
            raise ctx.error(where, f"{imp!r}: give exactly time = '...' and delta_v = [radial, along-track, normal]")
        t = parse_quantity(ctx, f"{where} time", imp["time"], U.TIME, dimensionless=False)
        if not t > 0:
            raise ctx.error(f"{where} time", f"{imp['time']!r} must be after the start (> 0)")
        dv = parse_vector(ctx, f"{where} delta_v", imp["delta_v"], 3, U.LENGTH / U.TIME, dimensionless=False,
                          bounds=_bounds("orbit.impulses", "delta_v", U.LENGTH / U.TIME))
        out.append((t, dv))
    return out

"""The scenario tables of the environment torques (issue 11, ``docs/design.md`` §10):
``[[body.facets]]``, ``[torques]`` and ``[environment]``.

```toml
[[body.facets]]                 # one table per flat plate, body axes
area = "0.06 m2"                # required, positive
normal = [0.0, 1.0, 0.0]        # required, outward unit normal
position = ["0 m", "0.1 m", "0.03 m"]   # required, centre of pressure from the centre of mass
drag_coefficient = 2.1          # default 2.2
specular = 0.1                  # SRP reflectivities, default 0; absorbed = 1 - specular - diffuse
diffuse = 0.3

[torques]
drag = true                     # default false; needs facets
srp = true                      # default false; needs facets and an [orbit] epoch
residual_dipole = ["0.005 A m2", "0 A m2", "0.002 A m2"]   # magnetic torque m x B (body axes)
constant = ["1e-7 N m", "0 N m", "-2e-7 N m"]   # a constant body torque (body axes; no orbit needed)

[environment]
atmosphere = "exponential"      # | "nrlmsis" | "none"   (default "exponential" when drag = true)
density0 = "3e-12 kg/m3"        # exponential: density0 exp(-(h - altitude0) / scale_height);
altitude0 = "400 km"            #   without these three keys, Vallado's piecewise table
scale_height = "60 km"          #   (orbatt.environment.atmosphere.PiecewiseExponentialAtmosphere)
corotation = true               # the atmosphere turns with the Earth (default true)
f107 = 150                      # nrlmsis space weather (all three required; never downloaded)
f107a = 150
ap = 4
magnetic_field = "igrf"         # | "dipole" | "none"  (default "igrf" with a residual dipole)
shadow = "conical"              # | "cylindrical" | "none" (default "conical")
```
The torques act with ``[potential] kind = "gravity-gradient"`` (the term that brings the
orbit); IGRF, the dipole, NRLMSIS and SRP need the orbit's epoch. A ``constant`` torque alone
reads no orbit: it acts with ``kind = "torque-free"`` too.
"""
from __future__ import annotations

import math

from astropy import units as u

from ..errors import InputError
from ..terms import BY_KEY
from ..torques import facet
from .fields import parse_choice, parse_quantity, parse_vector
from .ranges import RANGES

__all__ = ["FACET_KEYS", "TORQUE_KEYS", "ORBIT_FREE_KEYS", "ENVIRONMENT_KEYS", "parse_torques", "torque_arguments",
           "check_field_epoch"]

FACET_KEYS = {"area", "normal", "position", "drag_coefficient", "specular", "diffuse"}
#: the [torques] keys: those of the torque terms (:data:`orbatt.terms.TERMS`)
TORQUE_KEYS = set(BY_KEY)
#: the [torques] keys of terms that read no orbit (they act with kind = 'torque-free' too)
ORBIT_FREE_KEYS = {key for key, (term, _) in BY_KEY.items() if not term.kind.orbit}
ENVIRONMENT_KEYS = {"atmosphere", "density0", "altitude0", "scale_height", "corotation", "f107", "f107a", "ap",
                    "magnetic_field", "shadow"}
ATMOSPHERES = ("exponential", "nrlmsis", "none")
FIELDS = ("igrf", "dipole", "none")
SHADOWS = ("conical", "cylindrical", "none")


def check_field_epoch(ctx, field, epoch):
    """Refuse, naming ``[orbit] epoch``, an epoch outside IGRF-14's span 1900-2030 for the
    ``field`` model (``"igrf"`` or ``"dipole"``: both read IGRF's coefficients), before any
    frame transform warns about the year."""
    from ..environment.magnetic import check_igrf_instants

    try:
        check_igrf_instants(epoch, "[orbit] epoch")
    except InputError as exc:
        raise ctx.error("[orbit] epoch", f"{str(exc).split(': ', 1)[-1]} (magnetic_field = {field!r})") from None


def _bool(ctx, where, value):
    if not isinstance(value, bool):
        raise ctx.error(where, f"{value!r} is not true or false")
    return value


def _number(ctx, where, value, table, key):
    """A plain number inside the physical range of ``[table] key`` (:data:`RANGES`)."""
    lo, hi = RANGES[table, key].bounds(u.one)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or not lo <= value <= hi:
        raise ctx.error(where, f"{value!r} must be a plain number in the physical range [{lo:g}, {hi:g}]")
    return float(value)


def _facets(ctx, raw):
    if not isinstance(raw, list) or not all(isinstance(f, dict) for f in raw):
        raise ctx.error("[[body.facets]]", "must be an array of tables ([[body.facets]] ...)")
    out = []
    for k, f in enumerate(raw):
        where = f"[[body.facets]] {k + 1}"
        for key in f:
            if key not in FACET_KEYS:
                raise ctx.error(f"{where} {key}", f"unknown key; allowed: {', '.join(sorted(FACET_KEYS))}")
        for key in ("area", "normal", "position"):
            if key not in f:
                raise ctx.error(f"{where} {key}", "missing; a facet needs area, normal and position")
        area = parse_quantity(ctx, f"{where} area", f["area"], u.m**2, dimensionless=False,
                              bounds=RANGES["body.facets", "area"])
        normal = parse_vector(ctx, f"{where} normal", f["normal"], 3, u.one, dimensionless=True)
        pos = parse_vector(ctx, f"{where} position", f["position"], 3, u.m, dimensionless=False,
                           bounds=RANGES["body.facets", "position"])
        cd = _number(ctx, f"{where} drag_coefficient", f.get("drag_coefficient", 2.2), "body.facets", "drag_coefficient")
        cs = _number(ctx, f"{where} specular", f.get("specular", 0.0), "body.facets", "specular")
        cdf = _number(ctx, f"{where} diffuse", f.get("diffuse", 0.0), "body.facets", "diffuse")
        settings = {"area": area, "normal": normal.tolist(), "position": pos.tolist(), "drag_coefficient": cd,
                    "specular": cs, "diffuse": cdf}
        try:
            facet(settings, name=where)  # the plate's own rules
        except InputError as exc:
            raise ctx.error(where, str(exc).split(": ", 1)[-1]) from None
        out.append(settings)
    return out


def parse_torques(ctx, data, potential_kind, orbit, bdot=False):
    """The torque settings of a scenario, plain data (``None`` without ``[torques]``): a dict of
    ``facets`` (each plate's settings, :meth:`~orbatt.torques.Facet.settings`), ``drag``, ``srp``, ``residual_dipole``
    (A m^2 or None), ``constant`` (N m or None) and ``environment`` (the models' settings, SI floats); raises
    :class:`~orbatt.scenario.ScenarioError` naming the key. ``bdot``: a B-dot law reads
    ``[environment] magnetic_field`` (:mod:`orbatt.scenario.control_schema`)."""
    body = data.get("body", {})
    facets = _facets(ctx, body["facets"]) if "facets" in body else []
    if "torques" not in data:
        env = data.get("environment", {})
        if bdot and isinstance(env, dict) and set(env) <= {"magnetic_field"}:
            env = {}
        if env:
            raise ctx.error("[environment]", "only read with a [torques] table; add one or remove it")
        if facets:
            raise ctx.error("[[body.facets]]", "only read by [torques] drag or srp; add them or remove the facets")
        return None
    tq = data["torques"]
    env = data.get("environment", {})
    if not isinstance(env, dict):
        raise ctx.error("[environment]", "must be a table")
    for key in tq:
        if key not in TORQUE_KEYS:
            raise ctx.error(f"[torques] {key}", f"unknown key; allowed: {', '.join(sorted(TORQUE_KEYS))}")
    for key in env:
        if key not in ENVIRONMENT_KEYS:
            raise ctx.error(f"[environment] {key}", f"unknown key; allowed: {', '.join(sorted(ENVIRONMENT_KEYS))}")
    orbit_free = set(tq) <= ORBIT_FREE_KEYS and not env and not facets and not bdot
    free = ", ".join(repr(k) for k in sorted(ORBIT_FREE_KEYS))
    if orbit_free and potential_kind not in ("gravity-gradient", "torque-free"):
        raise ctx.error(f"[torques] {sorted(tq)[0]}" if tq else "[torques]",
                        f"acts with [potential] kind = 'torque-free' or 'gravity-gradient' (this scenario is "
                        f"{potential_kind!r})")
    if not orbit_free and (potential_kind != "gravity-gradient" or orbit is None):
        raise ctx.error("[torques]", f"the torques need an orbit: use [potential] kind = 'gravity-gradient' with an "
                                     f"[orbit] (this scenario is {potential_kind!r}); only {free} needs none")
    values = {key: _term_key(ctx, key, spec, tq) for key, (_, spec) in BY_KEY.items()}
    drag, srp, dipole = values["drag"], values["srp"], values["residual_dipole"]
    for name, on in (("drag", drag), ("srp", srp)):
        if on and not facets:
            raise ctx.error(f"[torques] {name}", "needs the body's flat plates: add [[body.facets]] tables")
    if facets and not (drag or srp):
        raise ctx.error("[[body.facets]]", "only read by [torques] drag or srp, both false here; set drag = true or "
                                           "srp = true, or remove the facets")
    epoch = None if orbit is None else orbit.get("epoch")
    atmosphere = parse_choice(ctx, "[environment] atmosphere", env.get("atmosphere", "exponential" if drag else "none"),
                              ATMOSPHERES)
    if drag and atmosphere == "none":
        raise ctx.error("[environment] atmosphere", "'none' with [torques] drag = true; choose 'exponential' or 'nrlmsis'")
    out_env = {"atmosphere": atmosphere, "shadow": parse_choice(ctx, "[environment] shadow",
                                                              env.get("shadow", "conical"), SHADOWS),
               "corotation": _bool(ctx, "[environment] corotation", env.get("corotation", True))}
    exp_keys = [k for k in ("density0", "altitude0", "scale_height") if k in env]
    if exp_keys and atmosphere != "exponential":
        raise ctx.error(f"[environment] {exp_keys[0]}", "only read by atmosphere = 'exponential'")
    if atmosphere == "exponential" and exp_keys:
        if len(exp_keys) != 3:
            missing = sorted({"density0", "altitude0", "scale_height"} - set(exp_keys))
            raise ctx.error(f"[environment] {missing[0]}", "missing; give density0, altitude0 and scale_height "
                                                           "together (or none: Vallado's table)")
        for k, unit in (("density0", u.kg / u.m**3), ("altitude0", u.km), ("scale_height", u.km)):
            out_env[k] = parse_quantity(ctx, f"[environment] {k}", env[k], unit, dimensionless=False,
                                        bounds=RANGES["environment", k])
        for k in ("density0", "scale_height"):
            if not out_env[k] > 0:
                raise ctx.error(f"[environment] {k}", f"{env[k]!r} must be positive")
    weather = [k for k in ("f107", "f107a", "ap") if k in env]
    if weather and atmosphere != "nrlmsis":
        raise ctx.error(f"[environment] {weather[0]}", "only read by atmosphere = 'nrlmsis'")
    if atmosphere == "nrlmsis":
        for k in ("f107", "f107a", "ap"):
            if k not in env:
                raise ctx.error(f"[environment] {k}", "missing; NRLMSIS needs the space weather f107, f107a and ap "
                                                      "(it is never downloaded)")
            out_env[k] = _number(ctx, f"[environment] {k}", env[k], "environment", k)
        if epoch is None:
            raise ctx.error("[orbit] epoch", "missing; NRLMSIS needs the date (give [orbit] epoch)")
    field = parse_choice(ctx, "[environment] magnetic_field",
                         env.get("magnetic_field", "igrf" if dipole is not None else "none"), FIELDS)
    if dipole is not None and field == "none":
        raise ctx.error("[environment] magnetic_field", "'none' with a [torques] residual_dipole; choose 'igrf' or "
                                                        "'dipole'")
    if field != "none" and dipole is None and not bdot:
        raise ctx.error("[environment] magnetic_field", "only read with a [torques] residual_dipole or a [control] "
                                                        "law on magnetorquers (B-dot, or a PD law's dump_gain)")
    if field != "none" and epoch is None:
        raise ctx.error("[orbit] epoch", f"missing; the {field} field needs the date (give [orbit] epoch)")
    if field != "none":
        check_field_epoch(ctx, field, epoch)
    if srp and epoch is None:
        raise ctx.error("[orbit] epoch", "missing; SRP needs the date to place the Sun (give [orbit] epoch)")
    out_env["magnetic_field"] = field
    return {"facets": facets, **values, "environment": out_env}


def _term_key(ctx, key, spec, tq):
    """The value of ``[torques] key`` (its :class:`~orbatt.terms.TomlKey` ``spec``): a flag
    (default false), or 3 quantities in the key's unit (SI floats; None when absent)."""
    where = f"[torques] {key}"
    if spec.kind == "flag":
        return _bool(ctx, where, tq.get(key, False))
    if key not in tq:
        return None
    return parse_vector(ctx, where, tq[key], 3, u.Unit(spec.unit), dimensionless=False, bounds=RANGES["torques", key])


def torque_arguments(torques):
    """The :class:`~orbatt.EnvironmentTorques` keywords of the term keys of a parsed
    ``[torques]`` (:func:`parse_torques`): flags as they are, vectors as Quantities (None when
    absent)."""
    out = {}
    for key, (_, spec) in BY_KEY.items():
        v = torques.get(key)
        out[spec.argument] = v * u.Unit(spec.unit) if spec.kind == "vector" and v is not None else v
    return out

"""The scenario tables of attitude control and reaction wheels (issue 12, ``docs/design.md`` §10):
``[control]`` and ``[[body.wheels]]``.

```toml
[control]
law = "pd"                      # | "bdot"
target = "orbital"              # | "inertial" (with target_q = [w, x, y, z]) | "sun" (with target_axis);
                                # orbital takes an optional target_q: the attitude relative to O
kp = "5e-4 N m"                 # PD: torque per unit quaternion error
kd = "1e-2 N m s"
max_torque = "2e-4 N m"         # per-axis saturation
actuator = "ideal"              # | "wheels": the torque comes from [[body.wheels]], which saturate
gain = "2e4 A m2 s / T"         # bdot: m = -gain dB/dt (body axes), clipped per axis
max_dipole = "0.1 A m2"

[[body.wheels]]                 # reaction wheels: the body becomes a gyrostat
axis = [1.0, 0.0, 0.0]          # unit spin axis, body axes
inertia = "4e-5 kg m2"          # axial moment of the rotor
speed = "1000 rpm"              # rotor speed relative to the body at t0
max_torque = "5e-3 N m"         # optional motor limits
max_speed = "6000 rpm"
```
B-dot reads ``[environment] magnetic_field`` (``"igrf"`` or ``"dipole"``, both need ``[orbit]
epoch``). Control needs an orbit (``[potential] kind = "gravity-gradient"``); wheels and control
need an adaptive method of the compiled ``dop853`` or scipy's (the body rate enters the
right-hand side).
"""
from __future__ import annotations

from astropy import units as u

from ..control import reaction_wheel
from ..errors import InputError
from ..laws import CONTROL_KEYS, LAWS, MODE_KEYS, control_law
from ..methods import METHODS
from .fields import parse_choice, parse_plain_vector, parse_quantity
from .ranges import RANGES
from .torques_schema import check_field_epoch

__all__ = ["CONTROL_KEYS", "WHEEL_KEYS", "parse_control"]

WHEEL_KEYS = {"axis", "inertia", "speed", "max_torque", "max_speed", "friction_coulomb", "friction_viscous",
              "friction_width"}
#: the wheels' friction keys: key -> (unit, zero allowed)
FRICTION_KEYS = {"friction_coulomb": (u.N * u.m, True), "friction_viscous": (u.N * u.m * u.s, True),
                 "friction_width": (u.rad / u.s, False)}
RATE = u.rad / u.s


def _positive(ctx, where, raw, unit, key):
    v = parse_quantity(ctx, where, raw, unit, dimensionless=False, bounds=RANGES[key])
    if not v > 0:
        raise ctx.error(where, f"{raw!r} must be positive")
    return v


def _api_error(ctx, where, exc):
    """The :class:`~orbatt.errors.ScenarioError` of an API object's ``exc`` (``"key: message"``):
    the key inside the table ``where`` (``"[control]"``, ``"[[body.wheels]] 2"``), or a
    table-qualified key (``"[[body.wheels]] axis"``) as it is."""
    key, _, msg = str(exc).partition(": ")
    return ctx.error(key if key.startswith("[") else f"{where} {key}", msg)


def _wheels(ctx, raw):
    """The plain settings of the wheels (:meth:`~orbatt.control.ReactionWheel.settings`),
    each checked by :class:`~orbatt.control.ReactionWheel` (the key named)."""
    if not isinstance(raw, list) or not all(isinstance(w, dict) for w in raw):
        raise ctx.error("[[body.wheels]]", "must be an array of tables ([[body.wheels]] ...)")
    out = []
    for k, w in enumerate(raw):
        where = f"[[body.wheels]] {k + 1}"
        for key in w:
            if key not in WHEEL_KEYS:
                raise ctx.error(f"{where} {key}", f"unknown key; allowed: {', '.join(sorted(WHEEL_KEYS))}")
        for key in ("axis", "inertia"):
            if key not in w:
                raise ctx.error(f"{where} {key}", "missing; a wheel needs axis and inertia")
        settings = {
            "axis": parse_plain_vector(ctx, f"{where} axis", w["axis"], 3).tolist(),
            "inertia": _positive(ctx, f"{where} inertia", w["inertia"], u.kg * u.m**2, ("body.wheels", "inertia")),
            "speed": (parse_quantity(ctx, f"{where} speed", w["speed"], RATE, dimensionless=False,
                                     bounds=RANGES["body.wheels", "speed"]) if "speed" in w else 0.0),
            "max_torque": (_positive(ctx, f"{where} max_torque", w["max_torque"], u.N * u.m,
                                     ("body.wheels", "max_torque")) if "max_torque" in w else None),
            "max_speed": (_positive(ctx, f"{where} max_speed", w["max_speed"], RATE, ("body.wheels", "max_speed"))
                          if "max_speed" in w else None)}
        for key, (unit, zero) in FRICTION_KEYS.items():
            v = None
            if key in w:
                v = parse_quantity(ctx, f"{where} {key}", w[key], unit, dimensionless=False,
                                   bounds=RANGES["body.wheels", key])
                if not (v > 0 or (zero and v == 0)):
                    raise ctx.error(f"{where} {key}", f"{w[key]!r} must be {'>= 0' if zero else 'positive'}")
            settings[key] = v
        try:
            reaction_wheel(settings, name=where)
        except InputError as exc:
            raise _api_error(ctx, where, exc) from None
        out.append(settings)
    return out


def _checked(ctx, settings, wheels):
    """``settings`` of a law, checked by its object (:func:`~orbatt.laws.control_law`, then
    its actuator against the ``wheels``' settings), the key named."""
    try:
        control_law(settings).check_wheels([reaction_wheel(w) for w in wheels])
    except InputError as exc:
        raise _api_error(ctx, "[control]", exc) from None
    return settings


def _law_settings(ctx, law, c, table="[control]"):
    """The settings (SI floats) of ``[control]`` ``c`` (or a mode's ``table``) for ``law``
    (:class:`orbatt.laws.Law`), each key parsed and checked as its
    :class:`~orbatt.laws.LawKey` says."""
    missing = [k for k in law.required if k not in c]
    if missing:
        raise ctx.error(f"{table} {missing[0]}", f"missing; {law.title} needs {' and '.join(law.required)}")
    out = {"law": law.name}
    for k in law.keys:
        where = f"{table} {k.key}"
        if k.key not in c:
            out[k.key] = k.fallback
        elif k.kind == "choice":
            out[k.key] = parse_choice(ctx, where, c[k.key], k.choices)
        elif k.kind == "vector":
            out[k.key] = parse_plain_vector(ctx, where, c[k.key], k.size).tolist()
        elif k.kind == "location":
            raw = c[k.key]
            if not isinstance(raw, list) or len(raw) != 3:
                raise ctx.error(where, f"expected [latitude, longitude, height], e.g. ['43.6 deg', '1.44 deg', '150 m'], "
                                       f"got {raw!r}")
            lat = parse_quantity(ctx, f"{where} latitude", raw[0], u.rad, dimensionless=True, bounds=(-1.5707963267948966,
                                                                                                    1.5707963267948966))
            lon = parse_quantity(ctx, f"{where} longitude", raw[1], u.rad, dimensionless=True, bounds=(-12.6, 12.6))
            h = parse_quantity(ctx, f"{where} height", raw[2], u.m, dimensionless=False, bounds=(-1.2e4, 1e5))
            out[k.key] = [lat, lon, h]
        else:
            v = parse_quantity(ctx, where, c[k.key], u.Unit(k.unit), dimensionless=False,
                               bounds=RANGES["control", k.key])
            if k.sign == "nonnegative" and v < 0:
                raise ctx.error(where, f"{c[k.key]!r} must not be negative")
            if k.sign == "positive" and not v > 0:
                raise ctx.error(where, f"{c[k.key]!r} must be positive")
            out[k.key] = v
    return out


def _law_fields(ctx, law, settings, data, orbit):
    """The magnetic field model the law reads (``"igrf"`` or ``"dipole"``, or None), after
    checking that what it reads along the orbit can be had: the Sun needs the epoch; the field
    needs ``[environment] magnetic_field`` and an epoch it covers."""
    fields = law.fields(settings)
    if "sun" in fields and orbit.get("epoch") is None:
        raise ctx.error("[orbit] epoch", "missing; target = 'sun' needs the date to place the Sun (give [orbit] epoch)")
    if "nadir" in fields and orbit.get("epoch") is None:
        raise ctx.error("[orbit] epoch", "missing; target = 'nadir' needs the date to turn the Earth (the geodetic "
                                         "vertical; give [orbit] epoch)")
    if "ground" in fields and orbit.get("epoch") is None:
        raise ctx.error("[orbit] epoch", "missing; target = 'ground' needs the date to turn the Earth (give [orbit] "
                                         "epoch)")
    if "field" not in fields:
        return None
    env = data.get("environment", {})
    field = env.get("magnetic_field") if isinstance(env, dict) else None
    if field is None or field == "none":
        raise ctx.error("[environment] magnetic_field", f"missing; {law.title} needs a field model: add "
                                                        "[environment] magnetic_field = 'igrf' or 'dipole'")
    field = parse_choice(ctx, "[environment] magnetic_field", field, ("igrf", "dipole"))
    epoch = orbit.get("epoch")
    if epoch is None:
        raise ctx.error("[orbit] epoch", f"missing; the {field} field of {law.title} needs the date (give [orbit] "
                                         "epoch)")
    check_field_epoch(ctx, field, epoch)
    return field


#: the laws ``[control] law`` names (a mode sequence is written [[control.modes]])
SINGLE_LAWS = tuple(name for name in LAWS if name != "modes")


def _mode_sequence(ctx, c, data, orbit, wheels, out):
    """``[[control.modes]]``: each mode's name, conditions and law's settings (checked as a
    single law's), the sequence's ``period``; the field the laws read."""
    for key in c:
        if key not in ("modes", "period"):
            raise ctx.error(f"[control] {key}", "not read with [[control.modes]]: give each mode its law's keys in its "
                                                "[[control.modes]] table (the period is the flight software's, here)")
    seq = LAWS["modes"]
    # without a period the laws are continuous and the transitions located on the solution
    period = _law_settings(ctx, seq, {"period": c["period"]})["period"] if "period" in c else None
    raw = c["modes"]
    if not isinstance(raw, list) or not raw or not all(isinstance(m, dict) for m in raw):
        raise ctx.error("[[control.modes]]", "must be a non-empty array of tables ([[control.modes]] ...)")
    modes, fields = [], set()
    for i, m in enumerate(raw):
        where = f"[[control.modes]] {i + 1}"
        if "law" not in m:
            raise ctx.error(f"{where} law", f"missing; give law = {' or '.join(map(repr, SINGLE_LAWS))}")
        law = LAWS[parse_choice(ctx, f"{where} law", m["law"], SINGLE_LAWS)]
        allowed = {"law", "period"} | set(law.units) | set(MODE_KEYS)
        for key in m:
            if key not in allowed:
                raise ctx.error(f"{where} {key}", f"not read by a mode of law = {law.name!r}; allowed: "
                                                  f"{', '.join(sorted(allowed - {'period'}))}")
        if "period" in m:
            raise ctx.error(f"{where} period", "the flight software has one rate: give period in [control] only")
        if "name" not in m or not isinstance(m["name"], str) or not m["name"].isidentifier():
            raise ctx.error(f"{where} name", f"missing or not a name ({m.get('name')!r}); give e.g. name = 'detumble'")
        settings = _law_settings(ctx, law, {k: v for k, v in m.items() if k in law.units or k == "law"}, where)
        settings["period"] = period
        _checked(ctx, settings, wheels)
        for key, (unit, _) in MODE_KEYS.items():
            if key == "name":
                settings[key] = m[key]
            elif key in m:
                v = parse_quantity(ctx, f"{where} {key}", m[key], u.Unit(unit), dimensionless=False,
                                   bounds=RANGES["control.modes", key])
                if not (v > 0 or (key == "hold" and v >= 0)):
                    raise ctx.error(f"{where} {key}", f"{m[key]!r} must be positive")
                settings[key] = v
            else:
                settings[key] = None
        field = _law_fields(ctx, law, settings, data, orbit)
        fields |= {field} - {None}
        modes.append(settings)
    settings = {"law": "modes", "modes": modes, "period": period}
    try:
        control_law(settings)
    except InputError as exc:
        raise _api_error(ctx, "[control]", exc) from None
    out["control"], out["magnetic_field"] = settings, (fields.pop() if fields else None)
    return out


def parse_control(ctx, data, potential_kind, orbit, dimensionless, method):
    """The control settings of a scenario, plain data: a dict of ``wheels`` (each wheel's
    settings, :meth:`~orbatt.control.ReactionWheel.settings`), ``control`` (the law's settings,
    :meth:`~orbatt.control.PDControl.settings`, or None; keys and rules from :data:`orbatt.laws.LAWS`) and ``magnetic_field`` (``"igrf"``,
    ``"dipole"`` or None: the field B-dot reads); None when the scenario has neither. The
    objects (:func:`~orbatt.control.reaction_wheel`, :func:`~orbatt.laws.control_law`)
    check their rules once; raises :class:`~orbatt.scenario.ScenarioError` naming the key."""
    body = data.get("body", {})
    has_wheels = "wheels" in body
    if "control" not in data and not has_wheels:
        return None
    if dimensionless:
        where = "[control]" if "control" in data else "[[body.wheels]]"
        raise ctx.error(where, "control and reaction wheels need a dimensional scenario ([body] inertia with units)")
    wheels = _wheels(ctx, body["wheels"]) if has_wheels else []
    if METHODS.get(method) is not None and not getattr(METHODS[method], "extended", False):
        what = "[control]" if "control" in data else "[[body.wheels]]"
        raise ctx.error("[integration] method", f"{method!r} cannot integrate {what} (the body rate enters the "
                                                "right-hand side); use method = 'dop853'")
    out = {"wheels": wheels, "control": None, "magnetic_field": None}
    if "control" not in data:
        return out
    c = data["control"]
    if not isinstance(c, dict):
        raise ctx.error("[control]", "must be a table")
    for key in c:
        if key not in CONTROL_KEYS:
            raise ctx.error(f"[control] {key}", f"unknown key; allowed: {', '.join(sorted(CONTROL_KEYS))}")
    if "modes" in c:
        if potential_kind != "gravity-gradient" or orbit is None:
            raise ctx.error("[control]", f"control needs an orbit: use [potential] kind = 'gravity-gradient' with an "
                                         f"[orbit] (this scenario is {potential_kind!r})")
        return _mode_sequence(ctx, c, data, orbit, wheels, out)
    if "law" not in c:
        raise ctx.error("[control] law", f"missing; give law = {' or '.join(map(repr, SINGLE_LAWS))}, or a sequence "
                                         "of modes [[control.modes]]")
    law = LAWS[parse_choice(ctx, "[control] law", c["law"], SINGLE_LAWS)]
    allowed = {"law"} | set(law.units)
    for key in c:
        if key not in allowed:
            raise ctx.error(f"[control] {key}", f"not read by law = {law.name!r}; remove it")
    if potential_kind != "gravity-gradient" or orbit is None:
        raise ctx.error("[control]", f"control needs an orbit: use [potential] kind = 'gravity-gradient' with an "
                                     f"[orbit] (this scenario is {potential_kind!r})")
    settings = _checked(ctx, _law_settings(ctx, law, c), wheels)
    out["control"], out["magnetic_field"] = settings, _law_fields(ctx, law, settings, data, orbit)
    return out

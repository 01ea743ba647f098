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

import numpy as np
from astropy import units as u

from ..control import BDotControl, PDControl, ReactionWheel, wheel_axes_span
from ..errors import InputError
from ..methods import METHODS
from .fields import parse_choice, parse_plain_vector, parse_quantity
from .ranges import RANGES
from .torques_schema import check_field_epoch

__all__ = ["CONTROL_KEYS", "WHEEL_KEYS", "LAWS", "parse_control"]

CONTROL_KEYS = {"law", "target", "target_q", "target_axis", "kp", "kd", "max_torque", "actuator", "gain",
                "max_dipole"}
WHEEL_KEYS = {"axis", "inertia", "speed", "max_torque", "max_speed"}
LAWS = ("pd", "bdot")
PD_KEYS = {"law", "target", "target_q", "target_axis", "kp", "kd", "max_torque", "actuator"}
BDOT_KEYS = {"law", "gain", "max_dipole"}
RATE = u.rad / u.s


def _nonnegative(ctx, where, raw, unit, key):
    v = parse_quantity(ctx, where, raw, unit, dimensionless=False, bounds=RANGES[key])
    if v < 0:
        raise ctx.error(where, f"{raw!r} must not be negative")
    return v


def _positive(ctx, where, raw, unit, key):
    v = parse_quantity(ctx, where, raw, unit, dimensionless=False, bounds=RANGES[key])
    if not v > 0:
        raise ctx.error(where, f"{raw!r} must be positive")
    return v


def _wheels(ctx, raw):
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
        axis = parse_plain_vector(ctx, f"{where} axis", w["axis"], 3)
        inertia = _positive(ctx, f"{where} inertia", w["inertia"], u.kg * u.m**2, ("body.wheels", "inertia"))
        speed = (parse_quantity(ctx, f"{where} speed", w["speed"], RATE, dimensionless=False,
                                bounds=RANGES["body.wheels", "speed"]) if "speed" in w else 0.0)
        tmax = (_positive(ctx, f"{where} max_torque", w["max_torque"], u.N * u.m, ("body.wheels", "max_torque"))
                if "max_torque" in w else None)
        smax = (_positive(ctx, f"{where} max_speed", w["max_speed"], RATE, ("body.wheels", "max_speed"))
                if "max_speed" in w else None)
        if smax is not None and abs(speed) > smax:
            raise ctx.error(f"{where} speed", f"{w['speed']!r} is above max_speed = {w['max_speed']!r}; lower the "
                                              "speed or raise max_speed")
        try:
            out.append(ReactionWheel(axis, inertia * u.kg * u.m**2, speed * RATE,
                                     max_torque=None if tmax is None else tmax * u.N * u.m,
                                     max_speed=None if smax is None else smax * RATE, name=where))
        except InputError as exc:
            key, _, msg = str(exc).partition(": ")
            raise ctx.error(f"{where} {key}", msg) from None
    return out


def parse_control(ctx, data, potential_kind, orbit, dimensionless, method):
    """The control settings of a scenario: a dict of ``wheels`` (list of
    :class:`~orbatt.control.ReactionWheel`), ``control`` (a :class:`~orbatt.control.PDControl`,
    :class:`~orbatt.control.BDotControl` or None) and ``magnetic_field`` (``"igrf"``,
    ``"dipole"`` or None: the field B-dot reads); None when the scenario has neither. Raises
    :class:`~orbatt.scenario.ScenarioError` naming the key."""
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
    if "law" not in c:
        raise ctx.error("[control] law", "missing; give law = 'pd' or 'bdot'")
    law = parse_choice(ctx, "[control] law", c["law"], LAWS)
    allowed = PD_KEYS if law == "pd" else BDOT_KEYS
    for key in c:
        if key not in allowed:
            raise ctx.error(f"[control] {key}", f"not read by law = {law!r}; remove it")
    if potential_kind != "gravity-gradient" or orbit is None:
        raise ctx.error("[control]", f"control needs an orbit: use [potential] kind = 'gravity-gradient' with an "
                                     f"[orbit] (this scenario is {potential_kind!r})")
    epoch = orbit.get("epoch")
    if law == "bdot":
        for key in ("gain", "max_dipole"):
            if key not in c:
                raise ctx.error(f"[control] {key}", "missing; B-dot needs gain and max_dipole")
        gain = _nonnegative(ctx, "[control] gain", c["gain"], u.A * u.m**2 * u.s / u.T, ("control", "gain"))
        mmax = _positive(ctx, "[control] max_dipole", c["max_dipole"], u.A * u.m**2, ("control", "max_dipole"))
        env = data.get("environment", {})
        field = env.get("magnetic_field") if isinstance(env, dict) else None
        if field is None or field == "none":
            raise ctx.error("[environment] magnetic_field", "missing; B-dot needs a field model: add [environment] "
                                                            "magnetic_field = 'igrf' or 'dipole'")
        field = parse_choice(ctx, "[environment] magnetic_field", field, ("igrf", "dipole"))
        if epoch is None:
            raise ctx.error("[orbit] epoch", f"missing; the {field} field of B-dot needs the date (give [orbit] epoch)")
        check_field_epoch(ctx, field, epoch)
        out["control"] = BDotControl(gain * u.A * u.m**2 * u.s / u.T, mmax * u.A * u.m**2)
        out["magnetic_field"] = field
        return out
    for key in ("kp", "kd"):
        if key not in c:
            raise ctx.error(f"[control] {key}", "missing; the PD law needs kp and kd")
    target = parse_choice(ctx, "[control] target", c.get("target", "orbital"), ("orbital", "inertial", "sun"))
    actuator = parse_choice(ctx, "[control] actuator", c.get("actuator", "ideal"), ("ideal", "wheels"))
    kw = {"kp": _nonnegative(ctx, "[control] kp", c["kp"], u.N * u.m, ("control", "kp")) * u.N * u.m,
          "kd": _nonnegative(ctx, "[control] kd", c["kd"], u.N * u.m * u.s, ("control", "kd")) * u.N * u.m * u.s,
          "actuator": actuator}
    if "max_torque" in c:
        kw["max_torque"] = _positive(ctx, "[control] max_torque", c["max_torque"], u.N * u.m,
                                     ("control", "max_torque")) * u.N * u.m
    if target == "inertial" and "target_q" not in c:
        raise ctx.error("[control] target_q", "missing; target = 'inertial' needs the attitude target_q = [w, x, y, z]")
    if "target_q" in c:
        if target == "sun":
            raise ctx.error("[control] target_q", "only read with target = 'inertial' or 'orbital' (target is 'sun')")
        kw["target_q"] = parse_plain_vector(ctx, "[control] target_q", c["target_q"], 4)
    if target == "sun":
        if "target_axis" not in c:
            raise ctx.error("[control] target_axis", "missing; target = 'sun' needs the body axis to point at the Sun")
        kw["target_axis"] = parse_plain_vector(ctx, "[control] target_axis", c["target_axis"], 3)
        if epoch is None:
            raise ctx.error("[orbit] epoch", "missing; target = 'sun' needs the date to place the Sun (give [orbit] "
                                             "epoch)")
    elif "target_axis" in c:
        raise ctx.error("[control] target_axis", f"only read with target = 'sun' (target is {target!r})")
    if actuator == "wheels":
        if not wheels:
            raise ctx.error("[control] actuator", "'wheels' needs [[body.wheels]]; add the wheels or use 'ideal'")
        if not wheel_axes_span(wheels):
            axes = np.array([w.axis for w in wheels])
            raise ctx.error("[[body.wheels]] axis", f"the {len(wheels)} wheel axes {axes.tolist()} do not span three "
                                                    "dimensions, which leaves an axis uncontrollable with actuator = "
                                                    "'wheels'; add or tilt a wheel")
    try:
        out["control"] = PDControl(target, **kw)
    except InputError as exc:
        key, _, msg = str(exc).partition(": ")
        raise ctx.error(f"[control] {key}", msg) from None
    return out

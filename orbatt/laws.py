"""The attitude control laws, each described once (issue 32; ``docs/design.md`` §10): what
a scenario writes, what the law reads, what the kernel gets and what a Dataset records.

A :class:`Law` is to a control law what :class:`orbatt.terms.Term` is to a torque term. It
holds

* its **scenario keys** in ``[control]`` (:class:`LawKey`: the dimension, default and meaning
  that ``docs/scenarios.md`` prints, the physical range, how the value is parsed and checked);
* its API class (:class:`orbatt.PDControl`, :class:`orbatt.BDotControl`), whose keyword
  arguments the keys are, and which builds the kernel row (``model_row``) with the named
  parameter slots of :mod:`orbatt.core.control` (:class:`~orbatt.core.slots.Slots`);
* **what it reads**: the environment fields along the orbit (``"sun"``, ``"field"``), the
  orbit itself, the wheels (:meth:`Law.fields`, :meth:`Law.reads_orbit`);
* its **Dataset variables** beyond ``torque_control`` (:class:`LawVar`);
* its **time scales** (the work estimate of :mod:`orbatt.scenario.work`) and whether it holds
  a frame (the settling time and the pointing figure read the frame it holds).

Generated from :data:`LAWS`: the ``[control]`` keys, their reference rows and ranges
(:data:`orbatt.scenario.schema.KEY_DOCS`, :data:`orbatt.scenario.ranges.RANGES`), the parser of
``[control]`` (:func:`orbatt.scenario.control_schema.parse_control`), the law of plain
settings (:func:`control_law`), the work estimate's time scales, the study outputs a law
allows (``max_dipole``), and the law's Dataset variables (:mod:`orbatt.dataset.control`).

Adding a law: its kernel (a function and its :class:`~orbatt.core.slots.Slots` in
:mod:`orbatt.core.control`, a branch in ``core.gyrostat.control_torques``), its API class
(:mod:`orbatt.control`) and its :class:`Law` here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from astropy import units as u

from .control import ACTUATORS, PERIOD_RANGE, TARGETS, BDotControl, PDControl
from .errors import InputError
from .modes import Mode, ModeSequence

__all__ = ["LawKey", "LawVar", "Law", "COMMON_KEYS", "LAWS", "LAW_CLASSES", "CONTROL_KEYS", "control_law", "law_of",
           "control_key_docs", "control_ranges"]


@dataclass(frozen=True)
class LawKey:
    """One key of a law in the scenario's ``[control]`` table.

    Attributes
    ----------
    key : str
        The TOML key (and the API class's keyword).
    dimension, default, meaning : str
        The reference's columns (``docs/scenarios.md``).
    kind : {"quantity", "choice", "vector"}
        A quantity of ``unit`` within ``range``; one of ``choices``; ``size`` plain numbers.
    unit : str
        The quantity's SI unit (the parser's, and the settings'); ``""`` otherwise.
    range : tuple or None
        ``(low, high)`` in ``unit`` (:data:`orbatt.scenario.ranges.RANGES`).
    sign : {"", "nonnegative", "positive"}
        The rule of a quantity's sign.
    choices : tuple
        The names a choice takes.
    size : int
        The components of a vector.
    required : bool
        The law needs it.
    fallback : object
        The setting of an absent key that is not required (a choice's default, or None).
    """

    key: str
    dimension: str
    default: str
    meaning: str
    kind: str = "quantity"
    unit: str = ""
    range: tuple | None = None
    sign: str = ""
    choices: tuple = ()
    size: int = 0
    required: bool = False
    fallback: object = None


@dataclass(frozen=True)
class LawVar:
    """A Dataset variable a law writes beyond ``torque_control``: ``(time, axis)``, body axes;
    ``values`` names the kernel output (``"dipole"``) and ``kind`` its
    :data:`orbatt.units.KERNEL_UNITS` quantity; ``when(settings) -> bool``: the settings under
    which the law writes it (None: always)."""

    name: str
    values: str
    kind: str
    unit: str
    long_name: str
    when: Callable | None = None


@dataclass(frozen=True)
class Law:
    """A control law (module docstring).

    Attributes
    ----------
    name : str
        ``[control] law``.
    title : str
        In words, for messages ("the PD law").
    summary : str
        One line for the reference.
    cls : type
        The API class; its keywords are the keys.
    keys : tuple of LawKey
    variables : tuple of LawVar
    fields : callable
        ``fields(settings) -> tuple``: the environment fields it reads along the orbit
        (``"sun"``: the Sun's position, needs the epoch; ``"field"``: the magnetic field).
    holds_frame : callable
        ``holds_frame(settings) -> bool``: it holds the body on a frame (the orbital frame or an
        inertial attitude), which the settling time and the pointing figure measure against.
    time_scales : callable
        ``time_scales(settings, inertia, b) -> [(rate, key, phrase)]``: its rates (1/s) for the
        smallest principal moment ``inertia`` (kg m^2) and the field's strength ``b`` (T).
    reads_orbit : callable
        ``reads_orbit(settings) -> bool``.
    """

    name: str
    title: str
    summary: str
    cls: type
    keys: tuple
    variables: tuple = ()
    fields: Callable = lambda s: ()
    holds_frame: Callable = lambda s: False
    time_scales: Callable = lambda s, inertia, b: []
    reads_orbit: Callable = lambda s: True

    @property
    def units(self):
        """``{key: SI unit or None}`` of the keys (None: a name or plain numbers)."""
        return {k.key: (k.unit or None) if k.kind == "quantity" else None for k in self.keys}

    @property
    def required(self):
        """The keys the law needs."""
        return tuple(k.key for k in self.keys if k.required)

    def writes(self, name, settings=None):
        """Whether the law writes the Dataset variable ``name`` (``torque_control``: all) with
        ``settings`` (a variable written under some settings only counts when they are given
        and say so)."""
        return name == "torque_control" or any(v.name == name for v in self.variables_of(settings))

    def variables_of(self, settings=None):
        """The :class:`LawVar` the law writes with ``settings`` (None: those it always writes)."""
        return tuple(v for v in self.variables if v.when is None or (settings is not None and v.when(settings)))


def _dumps(s):
    """Whether PD settings (plain, or a scenario's raw ``[control]``) dump the wheels' momentum."""
    return s.get("dump_gain") is not None


def _magnetorquers(s):
    """Whether PD settings make the torque with magnetorquers."""
    return s.get("actuator") == "magnetorquers"


def _pd_fields(s):
    target = s.get("target")
    return ((target,) if target in ("sun", "ground", "nadir") else ()) + \
        (("field",) if _dumps(s) or _magnetorquers(s) else ())


def _pd_scales(s, inertia, b):
    kp, kd = s["kp"], s["kd"]
    return [(math.sqrt(kp / inertia), "[control] kp", f"the PD law's bandwidth (kp = {kp:.3g} N m)"),
            (kd / inertia, "[control] kd", f"the PD law's damping rate (kd = {kd:.3g} N m s)")] + (
        [(s["dump_gain"], "[control] dump_gain", f"momentum dumping's rate (dump_gain = {s['dump_gain']:.3g} 1/s)")]
        if _dumps(s) else [])


def _bdot_scales(s, inertia, b):
    gain = s["gain"]
    return [(gain * b * b / inertia, "[control] gain", f"B-dot's damping rate (gain = {gain:.3g} A m2 s/T)")]


#: the keys every law takes: the flight software's rate
COMMON_KEYS = (LawKey("period", "time", "none (continuous)",
                      "the flight software's period: the law is evaluated at t_k = k period (time since the epoch) on "
                      "the state at t_k and its command (torque, wheels' motor torques, dipole) held until the next "
                      "tick (zero-order hold); none: a continuous law", unit="s", range=PERIOD_RANGE,
                      sign="positive"),)


PD = Law(
    "pd", "the PD law", "quaternion PD feedback", PDControl,
    (LawKey("target", " | ".join(map(repr, TARGETS)), "'orbital'",
            "hold the orbital frame (q_orbital -> 1), the attitude target_q, point target_axis at the Sun or at a "
            "ground target, or hold the geodetic nadir frame N (nadir: the orbital frame with its radial o1 replaced by "
            "the WGS84 ellipsoid's normal through the spacecraft, -n1 toward the point of the ellipsoid below it, n3 "
            "along n1 x v, n2 = n3 x n1); sun, ground and nadir need an epoch: [orbit] epoch or a TLE's",
            "choice", choices=tuple(TARGETS), fallback="orbital"),
     LawKey("actuator", " | ".join(map(repr, ACTUATORS)), "'ideal'",
            "an ideal external torque, the [[body.wheels]] (their axes must span 3 dimensions; their limits apply), "
            "or magnetorquers: the dipole m = (B x tau) / |B|^2 (body axes) clipped per axis to max_dipole makes the "
            "command's part normal to B (m x B, external; held between ticks with a period); reads [environment] "
            "magnetic_field", "choice", choices=ACTUATORS, fallback="ideal"),
     LawKey("kp", "torque (N m)", "required", "torque per unit quaternion error", unit="N m", range=(0.0, 1e6),
            sign="nonnegative", required=True),
     LawKey("kd", "torque x time (N m s)", "required", "torque per unit rate error (rad/s)", unit="N m s",
            range=(0.0, 1e6), sign="nonnegative", required=True),
     LawKey("max_torque", "torque (N m)", "none", "per-axis saturation of the commanded torque", unit="N m",
            range=(1e-12, 1e4), sign="positive"),
     LawKey("target_q", "plain, 4 values", "required for inertial",
            "target attitude [w, x, y, z], body -> inertial; with target = 'orbital' or 'nadir' (optional) the held "
            "attitude relative to that frame", "vector", size=4),
     LawKey("target_axis", "plain, 3 values", "required for sun, ground",
            "unit body axis to point at the Sun or the ground target", "vector", size=3),
     LawKey("target_location", "latitude, longitude (angles), height (length)", "required for ground",
            "the point on the rotating Earth to track (geodetic WGS84; needs an epoch): target_axis along the line "
            "of sight, its rate fed forward", "location", size=3),
     LawKey("max_rate", "angular rate", "none",
            "rate limit of an eigenaxis slew (Wie, Weiss & Arapostathis 1989): the commanded rate -(kp/kd) e is "
            "scaled to at most max_rate, max_torque acting as the acceleration limit; needs kd > 0",
            unit="rad / s", range=(1e-9, 10.0), sign="positive"),
     LawKey("ki", "torque / time (N m / s)", "none", "integral gain on the attitude error (PID), with anti-windup "
            "(no integration on an axis while its command saturates)", unit="N m / s", range=(0.0, 1e6),
            sign="nonnegative"),
     LawKey("dump_gain", "rate (1/s)", "none (no dumping)",
            "momentum management with actuator = 'wheels': magnetorquers dump the wheels' momentum h (body axes) with "
            "m = dump_gain (h x B) / |B|^2, each axis clipped to dump_max_dipole (m x B = -dump_gain h_perp, an "
            "external torque; the dipole is held between ticks with a period); reads [environment] magnetic_field",
            unit="1 / s", range=(1e-9, 10.0), sign="positive"),
     LawKey("dump_max_dipole", "magnetic moment (A m2)", "required with dump_gain",
            "per-axis limit of the dumping magnetorquers' dipole", unit="A m2", range=(1e-9, 1e5),
            sign="positive"),
     LawKey("max_dipole", "magnetic moment (A m2)", "required for bdot, and for pd with actuator = 'magnetorquers'",
            "per-axis limit of the magnetorquers' dipole (B-dot's; the PD law's with actuator = 'magnetorquers')",
            unit="A m2", range=(1e-9, 1e5), sign="positive")) + COMMON_KEYS,
    variables=(LawVar("dipole_control", "dipole", "dipole", "A m^2",
                      "momentum-dumping magnetic dipole (body components)", when=_dumps),
               LawVar("dipole_control", "dipole", "dipole", "A m^2",
                      "magnetorquers' dipole making the PD law's torque (body components)", when=_magnetorquers)),
    fields=_pd_fields, holds_frame=lambda s: s.get("target") in ("orbital", "inertial"), time_scales=_pd_scales,
    reads_orbit=lambda s: s.get("target") != "inertial" or _dumps(s) or _magnetorquers(s))

BDOT = Law(
    "bdot", "B-dot", "B-dot detumbling with magnetorquers", BDotControl,
    (LawKey("gain", "A m2 s / T", "required", "m = -gain dB/dt (body axes); reads [environment] magnetic_field",
            unit="A m2 s / T", range=(0.0, 1e12), sign="nonnegative", required=True),
     LawKey("max_dipole", "magnetic moment (A m2)", "required", "per-axis limit of the dipole", unit="A m2",
            range=(1e-9, 1e5), sign="positive", required=True)) + COMMON_KEYS,
    variables=(LawVar("dipole_control", "dipole", "dipole", "A m^2", "B-dot magnetic dipole (body components)"),),
    fields=lambda s: ("field",), time_scales=_bdot_scales)

#: the conditions of a mode (``[[control.modes]]``) besides its law's keys: key -> (SI unit, meaning)
MODE_KEYS = {"name": (None, "the mode's name (an identifier; a CF flag meaning of the Dataset's mode)"),
             "until_time": ("s", "leave the mode after this time in it"),
             "until_rate": ("rad / s", "leave once |omega| has stayed below this for hold"),
             "until_settled": ("rad", "leave once the PD law's attitude error has stayed below this for hold"),
             "hold": ("s", "how long until_rate / until_settled must hold (default 0)")}


def _sub_laws(s):
    return [(LAWS[m["law"]], m) for m in s.get("modes") or ()]


MODE_SEQUENCE = Law(
    "modes", "the mode sequence", "a sequence of laws ([[control.modes]]) left at the flight software's ticks",
    ModeSequence,
    (LawKey("modes", "array of tables", "none",
            "[[control.modes]]: each a mode with name, law and that law's keys, and until_time, until_rate, "
            "until_settled, hold; in order, the last stays", "modes"),) + COMMON_KEYS,
    variables=(LawVar("dipole_control", "dipole", "dipole", "A m^2", "magnetorquers' dipole (body components)"),),
    fields=lambda s: tuple(sorted({f for law, m in _sub_laws(s) for f in law.fields(m)})),
    time_scales=lambda s, inertia, b: [x for law, m in _sub_laws(s) for x in law.time_scales(m, inertia, b)],
    reads_orbit=lambda s: any(law.reads_orbit(m) for law, m in _sub_laws(s)))

#: the control laws by name (``[control] law``; a mode sequence is ``[[control.modes]]``)
LAWS = {law.name: law for law in (PD, BDOT, MODE_SEQUENCE)}
#: the API classes of the laws
LAW_CLASSES = tuple(law.cls for law in LAWS.values())
#: the ``[control]`` keys: ``law`` and every law's keys
CONTROL_KEYS = {"law"}.union(*({k.key for k in law.keys} for law in LAWS.values()))


def law_of(settings_or_name):
    """The :class:`Law` of a law's name, of its plain settings (``{"law": name, ...}``) or of an
    API law object; None for None."""
    if settings_or_name is None:
        return None
    if isinstance(settings_or_name, dict):
        settings_or_name = settings_or_name.get("law")
    name = getattr(settings_or_name, "law", settings_or_name)
    if name not in LAWS:
        raise InputError(f"law: {name!r} is not one of {', '.join(map(repr, LAWS))}")
    return LAWS[name]


def control_law(settings):
    """The law of plain ``settings`` (``{"law": name, key: value}``, SI floats in the units of
    the law's keys; the ``settings()`` of a law object): a :class:`~orbatt.PDControl` or
    :class:`~orbatt.BDotControl`, whose constructor checks every rule
    (:class:`~orbatt.errors.InputError` naming the key)."""
    settings = dict(settings)
    law = law_of(settings.pop("law", None))
    if law is MODE_SEQUENCE:
        return _mode_sequence(settings)
    units = law.units
    unknown = sorted(set(settings) - set(units))
    if unknown:
        raise InputError(f"{unknown[0]}: not read by law = {law.name!r}; its keys: {', '.join(units)}")
    kw = {k: v if units[k] is None or v is None else v * u.Unit(units[k]) for k, v in settings.items()}
    return law.cls(**kw)


def _mode_sequence(settings):
    """The :class:`~orbatt.modes.ModeSequence` of plain settings (``modes``: each mode's
    :data:`MODE_KEYS` and its law's settings; ``period``)."""
    unknown = sorted(set(settings) - {"modes", "period"})
    if unknown:
        raise InputError(f"{unknown[0]}: not read by a mode sequence; its keys: modes, period")
    period = settings.get("period")
    modes = []
    for m in settings.get("modes") or ():
        m = dict(m)
        kw = {k: m.pop(k) for k in list(m) if k in MODE_KEYS}
        kw = {k: v if MODE_KEYS[k][0] is None or v is None else v * u.Unit(MODE_KEYS[k][0]) for k, v in kw.items()}
        m.setdefault("period", period)
        modes.append(Mode(kw.pop("name", None), control_law(m), **kw))
    return ModeSequence(modes, period=None if period is None else period * u.s)


def reads_field(raw):
    """Whether a scenario's raw ``[control]`` table (before parsing) has a law that reads the
    magnetic field along the orbit (B-dot, a PD law that dumps momentum; any mode's), so that
    ``[environment] magnetic_field`` is read without ``[torques]``."""
    if not isinstance(raw, dict):
        return False
    if isinstance(raw.get("modes"), list):
        return any(reads_field(m) for m in raw["modes"])
    name = raw.get("law")
    law = LAWS.get(name) if isinstance(name, str) else None
    return law is not None and "field" in law.fields(raw)


def _owners(key):
    return [law.name for law in LAWS.values() if any(k.key == key for k in law.keys)]


def control_key_docs():
    """The ``[control]`` rows of the reference: ``{key: (dimension, default, meaning)}``, ``law``
    first, then each law's keys in order (a key of some laws only says whose)."""
    docs = {"law": (" | ".join(repr(n) for n in LAWS if n != "modes"), "required (or modes)",
                    "; ".join(f"{law.name}: {law.summary}" for law in LAWS.values() if law.name != "modes"))}
    for law in LAWS.values():
        for k in law.keys:
            if k.key in docs:
                continue
            owners = _owners(k.key)
            default = f"required for {', '.join(owners)}" if k.default == "required" else k.default
            docs[k.key] = (k.dimension, default, f"{', '.join(owners)}: {k.meaning}")
    return docs


def mode_key_docs():
    """The ``[[control.modes]]`` rows of the reference: a mode's conditions, then its law."""
    dims = {"name": "name", "until_time": "time", "until_rate": "angular rate", "until_settled": "angle",
            "hold": "time"}
    docs = {k: (dims[k], "required" if k == "name" else ("0 s" if k == "hold" else "none"), meaning)
            for k, (_, meaning) in MODE_KEYS.items()}
    docs["law"] = (" | ".join(repr(n) for n in LAWS if n != "modes"), "required",
                   "the mode's law, with that law's [control] keys (period excepted: the flight software's, in "
                   "[control])")
    return docs


def control_ranges():
    """``{key: (low, high, unit)}`` of the laws' quantity keys (one range per key: a key two
    laws share has one dimension and one range)."""
    out = {}
    for law in LAWS.values():
        for k in law.keys:
            if k.kind == "quantity" and k.range is not None:
                if k.key in out and out[k.key] != (*k.range, k.unit):
                    raise ValueError(f"[control] {k.key}: two laws give it different ranges")
                out[k.key] = (*k.range, k.unit)
    return out

"""Field parsers of scenario files: one TOML value in, a validated float (internal units) out.

Every parser takes a :class:`FieldContext` (which names the file) and ``where`` (the table
and key, e.g. ``"[orbit] a"``) and raises :class:`~orbatt.errors.ScenarioError` with the
file, the field, the value and the fix. Quantities are strings astropy parses (``"7000 km"``,
``"30 deg"``); plain numbers are taken as already in the internal unit only where the
scenario is dimensionless (:mod:`orbatt.units`).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
from astropy import units as u

from .. import units as U
from ..errors import ScenarioError
from .ranges import ANGLE_LIMIT, Range

__all__ = ["FieldContext", "parse_quantity", "parse_vector", "parse_plain_vector", "parse_choice", "parse_int",
           "parse_time", "check_integers", "INT64"]


@dataclass
class FieldContext:
    """Where a value comes from: ``source`` (a file name) prefixes every message."""

    source: str

    def error(self, where, msg):
        """A :class:`ScenarioError` ``"SOURCE: WHERE: MSG"``."""
        return ScenarioError(f"{self.source}: {where}: {msg}")


#: ``NUMBER UNIT``: one decimal number (optionally signed, with an exponent; ``nan``/``inf``
#: parse so that they can be refused by name), then the unit; the unit must not start with
#: another number (``"1 2 km"`` is refused, not read as ``1 (2 km)``)
_QUANTITY = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?nan|[+-]?inf)\s*(.*?)\s*", re.IGNORECASE)
#: nonzero magnitudes orbatt's equations take in internal units (products of a few of them
#: stay finite in float64); per-key physical ranges are narrower (:data:`orbatt.scenario.schema.RANGES`)
MAGNITUDE = (1e-100, 1e100)


def _split_quantity(ctx, where, text, unit):
    """``(number, astropy unit)`` of ``"NUMBER UNIT"``; the whole string must parse."""
    m = _QUANTITY.fullmatch(text)

    def example():
        return f"'1 {unit.to_string()}'" if unit != U.DIMENSIONLESS else "'0.5'"

    if m is None or (m.group(2) and m.group(2)[0] in "0123456789+-."):
        raise ctx.error(where, f"cannot parse {text!r} as one number and a unit; write e.g. {example()}")
    number, unit_text = float(m.group(1)), m.group(2)
    if not unit_text:
        return number, U.DIMENSIONLESS
    try:
        parsed = u.Unit(unit_text)
    except ValueError:
        raise ctx.error(where, f"{unit_text!r} in {text!r} is not a unit; write e.g. {example()}") from None
    if isinstance(parsed, u.FunctionUnitBase) or not isinstance(getattr(parsed, "scale", None), (int, float)):
        raise ctx.error(where, f"{unit_text!r} in {text!r} is a logarithmic unit; give the value in a linear unit, "
                               f"e.g. {example()}")
    if parsed.scale != 1 and not parsed.is_equivalent(U.DIMENSIONLESS):
        raise ctx.error(where, f"cannot parse {text!r} as one number and a unit; write e.g. {example()}")
    return number, parsed


def _check_value(ctx, where, value, x, unit, bounds):
    """Finite, a magnitude float64 arithmetic handles, and inside ``bounds`` (``(low, high)``
    in ``unit``, either may be None; inclusive; or a :class:`~orbatt.scenario.ranges.Range`,
    whose text the message quotes)."""
    shown = None
    if isinstance(bounds, Range):
        shown, bounds = bounds, bounds.bounds(unit)
    if not math.isfinite(x):
        raise ctx.error(where, f"{value!r} is not finite; give a finite value")
    if x != 0 and not MAGNITUDE[0] <= abs(x) <= MAGNITUDE[1]:
        raise ctx.error(where, f"{value!r} is {abs(x):.3g} {_unit_name(unit)} in magnitude, outside "
                               f"[{MAGNITUDE[0]:g}, {MAGNITUDE[1]:g}]; give a physical value")
    if bounds is not None:
        lo, hi = bounds
        if lo is not None and lo > 0 and x <= 0:
            raise ctx.error(where, f"{value!r} must be positive")
        if (lo is not None and x < lo) or (hi is not None and x > hi):
            if shown is not None:
                have = x * float((1.0 * unit).to_value(u.Unit(shown.unit))) if shown.unit else x
                raise ctx.error(where, f"{value!r} is {have:.6g}{' ' + shown.unit if shown.unit else ''}, outside "
                                       f"the physical range {shown.text()} of this key; give a value inside it")
            rng = (f"[{lo:g}, {hi:g}]" if lo is not None and hi is not None
                   else f">= {lo:g}" if lo is not None else f"<= {hi:g}")
            raise ctx.error(where, f"{value!r} is {x:.6g} {_unit_name(unit)}, outside the range {rng} "
                                   f"{_unit_name(unit)} orbatt accepts for this key")
    return x


def _unit_name(unit):
    return "" if unit == U.DIMENSIONLESS else U.unit_string(unit)


def parse_quantity(ctx, where, value, unit, *, dimensionless, bounds=None):
    """Parse one scalar: a Quantity string ``"NUMBER UNIT"``, or a plain number when
    ``dimensionless`` (or when ``unit`` is dimensionless).

    The rules: the whole string must parse (one number, then one unit: ``"1 2 km"`` and
    ``"0.01 planet orbits"`` are refused); the unit must have the dimension of ``unit``
    (``"98.2 deg deg"`` is a solid angle, not an angle); **angles always need an angle unit**
    (``"45"`` and ``45`` are refused; only a plain ``0`` is accepted), in dimensionless
    scenarios too; the value must be finite, of magnitude in :data:`MAGNITUDE` (or zero),
    and inside ``bounds``.

    Parameters
    ----------
    ctx : FieldContext
    where : str
        The field, e.g. ``"[orbit] a"``.
    value : str, int or float
        The TOML value.
    unit : astropy Unit
        The internal unit the value is returned in (:mod:`orbatt.units`).
    dimensionless : bool
        Whether the scenario is written in plain numbers (then a unit is refused, except on
        angles).
    bounds : (float or None, float or None), optional
        Inclusive range in ``unit`` (the key's physical range).

    Returns
    -------
    float
        The value in ``unit``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ctx.error(where, f"{value!r} is not a number or a quantity string")
    if bounds is None and _equal(unit, U.ANGLE):
        bounds = (-ANGLE_LIMIT, ANGLE_LIMIT)
    if isinstance(value, str):
        key = (value, unit, dimensionless, u.get_current_unit_registry())
        x = _PARSED.get(key)
        if x is None:
            x = _parse_quantity_string(ctx, where, value, unit, dimensionless)
            if len(_PARSED) < 4096:
                _PARSED[key] = x
        return _check_value(ctx, where, value, x, unit, bounds)
    x = _float(ctx, where, value)
    angle = _equal(unit, U.ANGLE)
    if angle and x != 0:
        raise ctx.error(where, f"{value!r} has no unit; an angle needs an angle unit: write '{value} deg' or "
                               f"'{value} rad'")
    if not (angle or dimensionless or _equal(unit, U.DIMENSIONLESS)):
        raise ctx.error(where, f"{value!r} has no unit; write it as a quantity string such as "
                               f"'{value} {unit.to_string()}'")
    return _check_value(ctx, where, value, x, unit, bounds)


def _float(ctx, where, value):
    """``float(value)`` of a TOML number; an integer too large for a float is refused by name."""
    try:
        return float(value)
    except OverflowError:
        raise ctx.error(where, f"an integer of {int(abs(value).bit_length() * 0.30103) + 1} digits is too large "
                               "for a float; give a physical value") from None


#: ``(unit, other) -> unit == other``: astropy's comparison of two units (~20 us: it converts
#: one into the other) for the few pairs a scenario compares
_EQUAL = {}


def _equal(unit, other) -> bool:
    """``unit == other``, remembered per pair."""
    key = (unit, other)
    same = _EQUAL.get(key)
    if same is None:
        same = bool(unit == other)
        if len(_EQUAL) < 1024:
            _EQUAL[key] = same
    return same


#: ``(text, unit, dimensionless, unit registry) -> value``: quantity strings parsed before
#: (astropy's unit parser takes ~0.1 ms a string; a scenario has a dozen, a sweep reads them
#: again per chunk). Only parses that succeeded are kept; the range check runs every time.
_PARSED = {}


def _parse_quantity_string(ctx, where, value, unit, dimensionless):
    """The value of the quantity string ``value`` in ``unit`` (:func:`parse_quantity`'s rules
    but the range check)."""
    angle = _equal(unit, U.ANGLE)
    number, qunit = _split_quantity(ctx, where, value, unit)
    if angle and qunit.physical_type != "angle":
        what = "no unit" if qunit == U.DIMENSIONLESS else f"the unit {qunit.to_string()!r} ({qunit.physical_type})"
        raise ctx.error(where, f"{value!r} has {what}; an angle needs an angle unit, e.g. '{number:g} deg' "
                               f"or '{number:g} rad'")
    if dimensionless and not angle and unit != U.DIMENSIONLESS and qunit != U.DIMENSIONLESS:
        raise ctx.error(where, f"{value!r} has a unit but [body] inertia is plain numbers (normalized "
                               "units); give a plain number or give the inertia with units")
    if not math.isfinite(number):
        raise ctx.error(where, f"{value!r} is not finite; give a finite value")
    try:
        return float((number * qunit).to_value(unit))
    except u.UnitConversionError:
        raise ctx.error(where, f"{value!r} has the wrong dimension; expected {U.dimension_phrase(unit)} such "
                               f"as '1 {unit.to_string()}'") from None


def parse_vector(ctx, where, value, n, unit, *, dimensionless, bounds=None):
    """A list of ``n`` scalars (:func:`parse_quantity` each, with ``bounds``) as an ``(n,)``
    float array in ``unit``."""
    if not isinstance(value, list) or len(value) != n:
        raise ctx.error(where, f"expected a list of {n} values, got {value!r}")
    return np.array([parse_quantity(ctx, f"{where}[{k}]", v, unit, dimensionless=dimensionless, bounds=bounds)
                     for k, v in enumerate(value)])


def parse_plain_vector(ctx, where, value, n):
    """A list of ``n`` finite plain numbers (quaternion components) as an ``(n,)`` float array."""
    if not isinstance(value, list) or len(value) != n or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise ctx.error(where, f"expected a list of {n} plain numbers, got {value!r}")
    a = np.array([_float(ctx, f"{where}[{k}]", v) for k, v in enumerate(value)])
    if not np.all(np.isfinite(a)):
        raise ctx.error(where, f"{value!r} contains non-finite numbers")
    big = np.abs(a) > MAGNITUDE[1]
    if np.any(big):
        raise ctx.error(where, f"{value!r}: {a[big][0]:.3g} is beyond {MAGNITUDE[1]:g} in magnitude; give physical "
                               "values")
    return a


def parse_choice(ctx, where, value, choices):
    """``value`` if it is one of ``choices``."""
    if value not in choices:
        raise ctx.error(where, f"{value!r} is not one of {', '.join(repr(c) for c in choices)}")
    return value


def parse_int(ctx, where, value, lo, hi=None):
    """An integer ``lo <= value`` (``< hi`` when given); booleans are refused."""
    if isinstance(value, bool) or not isinstance(value, int) or value < lo or (hi is not None and value >= hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi})"
        raise ctx.error(where, f"{value!r} must be an integer {rng}")
    return int(value)


def parse_time(ctx, where, value, dimensionless, orbit, *, bounds=None):
    """A duration: ``("orbits", N)`` for ``"N orbits"`` (needs an ``orbit``; the whole
    string must be one number and ``orbit``/``orbits``), else ``("time", t)`` with ``t`` in
    s (or a plain number when ``dimensionless``; :func:`parse_quantity` with ``bounds``, in
    s). Either must be positive."""
    if isinstance(value, str) and value.strip().lower().endswith(("orbits", "orbit")):
        m = _QUANTITY.fullmatch(value)
        if m is None or m.group(2).lower() not in ("orbit", "orbits"):
            raise ctx.error(where, f"{value!r}: write 'N orbits' with one number N (e.g. '2 orbits')")
        if orbit is None:
            raise ctx.error(where, f"{value!r} needs an [orbit]; give a time such as '100 s'")
        n = _check_value(ctx, where, value, float(m.group(1)), U.DIMENSIONLESS, None)
        if n <= 0:
            raise ctx.error(where, f"{value!r} must be positive")
        return ("orbits", n)
    t = parse_quantity(ctx, where, value, U.TIME, dimensionless=dimensionless, bounds=bounds)
    if t <= 0:
        raise ctx.error(where, f"{value!r} must be positive")
    return ("time", t)


#: the integers TOML holds (64-bit signed, TOML 1.0 "Integer"); tomllib reads any size
INT64 = (-2**63, 2**63 - 1)


def check_integers(ctx, data, where=""):
    """Refuse, naming the key, any integer of the TOML ``data`` (a table, nested tables and
    arrays) outside TOML's 64-bit range: such a number is no valid TOML, and converting it to
    a float overflows."""
    if isinstance(data, dict):
        for k, v in data.items():
            if isinstance(v, dict):
                check_integers(ctx, v, f"[{k}]" if not where else f"[{where.strip('[]')}.{k}]")
            elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                for i, x in enumerate(v):
                    check_integers(ctx, x, f"[[{where.strip('[]') + '.' if where else ''}{k}]] {i + 1}")
            else:
                check_integers(ctx, v, f"{where} {k}".strip())
    elif isinstance(data, list):
        for i, x in enumerate(data):
            check_integers(ctx, x, f"{where}[{i}]")
    elif isinstance(data, int) and not isinstance(data, bool) and not INT64[0] <= data <= INT64[1]:
        raise ctx.error(where, f"an integer of {int(abs(data).bit_length() * 0.30103) + 1} digits is outside TOML's "
                               "64-bit integer range (and too large for a float); give a physical value")

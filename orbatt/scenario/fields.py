"""Field parsers of scenario files: one TOML value in, a validated float (internal units) out.

Every parser takes a :class:`FieldContext` (which names the file) and ``where`` (the table
and key, e.g. ``"[orbit] a"``) and raises :class:`~orbatt.errors.ScenarioError` with the
file, the field, the value and the fix. Quantities are strings astropy parses (``"7000 km"``,
``"30 deg"``); plain numbers are taken as already in the internal unit only where the
scenario is dimensionless (:mod:`orbatt.units`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy import units as u

from .. import units as U
from ..errors import ScenarioError

__all__ = ["FieldContext", "parse_quantity", "parse_vector", "parse_plain_vector", "parse_choice", "parse_int",
           "parse_time"]


@dataclass
class FieldContext:
    """Where a value comes from: ``source`` (a file name) prefixes every message."""

    source: str

    def error(self, where, msg):
        """A :class:`ScenarioError` ``"SOURCE: WHERE: MSG"``."""
        return ScenarioError(f"{self.source}: {where}: {msg}")


def parse_quantity(ctx, where, value, unit, *, dimensionless):
    """Parse one scalar: a Quantity string, or a plain number when ``dimensionless`` (or when
    ``unit`` is dimensionless).

    Parameters
    ----------
    ctx : FieldContext
    where : str
        The field, e.g. ``"[orbit] a"``.
    value : str, int or float
        The TOML value.
    unit : astropy Unit
        The internal unit the value is returned in (:mod:`orbatt.units`); angles accept
        plain numbers (rad) always.
    dimensionless : bool
        Whether the scenario is written in plain numbers (then a unit is refused).

    Returns
    -------
    float
        The value in ``unit``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ctx.error(where, f"{value!r} is not a number or a quantity string")
    if isinstance(value, str):
        try:
            q = u.Quantity(value)
        except (TypeError, ValueError):
            raise ctx.error(where, f"cannot parse {value!r} as a quantity; write e.g. '1 {unit.to_string()}'") from None
        if dimensionless and unit not in (U.DIMENSIONLESS, U.ANGLE) and q.unit != U.DIMENSIONLESS:
            raise ctx.error(where, f"{value!r} has a unit but [body] inertia is plain numbers (normalized units); "
                                  "give a plain number or give the inertia with units")
        try:
            eq = u.dimensionless_angles() if unit == U.ANGLE else []
            return float(q.to_value(unit, equivalencies=eq))
        except u.UnitConversionError:
            raise ctx.error(where, f"{value!r} has the wrong dimension; expected a {unit.physical_type} such "
                                  f"as '1 {unit.to_string()}'") from None
    x = float(value)
    if not math.isfinite(x):
        raise ctx.error(where, f"{value!r} is not finite")
    if unit in (U.DIMENSIONLESS, U.ANGLE) or dimensionless:
        return x
    raise ctx.error(where, f"{value!r} has no unit; write it as a quantity string such as '{value} {unit.to_string()}'")


def parse_vector(ctx, where, value, n, unit, *, dimensionless):
    """A list of ``n`` scalars (:func:`parse_quantity` each) as an ``(n,)`` float array in ``unit``."""
    if not isinstance(value, list) or len(value) != n:
        raise ctx.error(where, f"expected a list of {n} values, got {value!r}")
    return np.array([parse_quantity(ctx, f"{where}[{k}]", v, unit, dimensionless=dimensionless)
                     for k, v in enumerate(value)])


def parse_plain_vector(ctx, where, value, n):
    """A list of ``n`` finite plain numbers (quaternion components) as an ``(n,)`` float array."""
    if not isinstance(value, list) or len(value) != n or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise ctx.error(where, f"expected a list of {n} plain numbers, got {value!r}")
    a = np.array(value, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ctx.error(where, f"{value!r} contains non-finite numbers")
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


def parse_time(ctx, where, value, dimensionless, orbit):
    """A duration: ``("orbits", N)`` for ``"N orbits"`` (needs an ``orbit``), else
    ``("time", t)`` with ``t`` in s (or a plain number when ``dimensionless``)."""
    if isinstance(value, str) and value.strip().endswith(("orbits", "orbit")):
        num = value.strip().split()[0]
        try:
            n = float(num)
        except ValueError:
            raise ctx.error(where, f"{value!r}: write 'N orbits' with a number N") from None
        if orbit is None:
            raise ctx.error(where, f"{value!r} needs an [orbit]; give a time such as '100 s'")
        return ("orbits", n)
    return ("time", parse_quantity(ctx, where, value, U.TIME, dimensionless=dimensionless))

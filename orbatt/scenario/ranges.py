"""The physical range of every numeric key of a scenario file: one table, :data:`RANGES`,
beside the key descriptions (:data:`orbatt.scenario.schema.KEY_DOCS`), which the field
parsers check and ``docs/scenarios.md`` shows (:mod:`orbatt.scenario.reference`).

The ranges are generous (a 1 g chip to a space station, a sounding rocket's spin, the
space weather of the strongest storms) but physical: a value outside describes no satellite,
and would make the equations stiff, overflow or run for hours. Dimensional ranges apply to
dimensional scenarios; a scenario in normalized units (plain-number ``[body] inertia``) is
bounded by the work estimate (:func:`orbatt.scenario.build.check_work`) instead, and by the
ranges of its plain keys (``e``, the reflectivities, the space weather).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from astropy import units as u

from .. import units as U
from ..laws import control_ranges
from ..terms import torque_ranges

__all__ = ["Range", "RANGES", "key_bounds", "range_text", "ANGLE_LIMIT"]

#: largest angle (rad) any angle key takes: 1000 rad, about 160 turns (an angle beyond a few
#: turns describes nothing more, and a huge one loses its digits modulo 2 pi)
ANGLE_LIMIT = 1000.0


#: ``(Range, unit) -> (low, high)``: :meth:`Range.bounds` computed before
_BOUNDS = {}


@dataclass(frozen=True)
class Range:
    """Inclusive physical range of one key, in ``unit`` (an astropy unit string; ``""`` for
    plain numbers).

    Attributes
    ----------
    low, high : float or None
        The bounds; None where the key has none on that side.
    unit : str
    signed : bool
        The value may take either sign and ``high`` bounds its magnitude (a component of a
        vector, a rate, an offset); ``low`` is then None.
    """

    low: float | None
    high: float | None
    unit: str = ""
    signed: bool = False

    def bounds(self, unit):
        """``(low, high)`` in the astropy ``unit`` (the key's internal unit)."""
        key = (self, unit)
        out = _BOUNDS.get(key)
        if out is None:  # a unit conversion (~50 us) once per key and unit: parsers call this per value
            out = _BOUNDS[key] = self._bounds(unit)
        return out

    def _bounds(self, unit):
        f = 1.0 if not self.unit else float((1.0 * u.Unit(self.unit)).to_value(unit))
        hi = None if self.high is None else self.high * f
        if self.signed:
            return (-hi, hi)
        return (None if self.low is None else self.low * f, hi)

    def text(self):
        """The range as a reader writes it: ``"[1e-14, 1e51] kg m2"``, ``"|x| <= 1e4 rad/s"``."""
        unit = f" {self.unit}" if self.unit else ""
        lo, hi = (None if x is None else f"{x:g}".replace("e+", "e") for x in (self.low, self.high))
        if self.signed:
            return f"|x| <= {hi}{unit}"
        if hi is None:
            return f">= {lo}{unit}"
        if lo is None:
            return f"<= {hi}{unit}"
        return f"[{lo}, {hi}]{unit}"


#: ``{(table, key): Range}``: the physical range of each numeric key (table as in
#: :data:`~orbatt.scenario.schema.KEY_DOCS`: ``"body.facets"`` for ``[[body.facets]]``).
#: Angle keys take any angle up to :data:`ANGLE_LIMIT` in magnitude.
RANGES = {
    ("body", "inertia"): Range(1e-14, 1e51, "kg m2"),
    ("body", "mass_g"): Range(0.0, 1e15, "N"),
    ("body", "center_of_mass"): Range(None, 1e3, "km", signed=True),
    ("body.wheels", "inertia"): Range(1e-9, 1e4, "kg m2"),
    ("body.wheels", "speed"): Range(None, 1e5, "rpm", signed=True),
    ("body.wheels", "max_torque"): Range(1e-9, 1e4, "N m"),
    ("body.wheels", "max_speed"): Range(1e-6, 1e5, "rpm"),
    ("body.wheels", "friction_coulomb"): Range(0.0, 10.0, "N m"),
    ("body.wheels", "friction_viscous"): Range(0.0, 10.0, "N m s"),
    ("body.wheels", "friction_width"): Range(1e-6, 1e3, "rad / s"),
    ("body.facets", "area"): Range(1e-8, 1e4, "m2"),
    ("body.facets", "position"): Range(None, 1e3, "m", signed=True),
    ("body.facets", "drag_coefficient"): Range(0.0, 10.0),
    ("body.facets", "specular"): Range(0.0, 1.0),
    ("body.facets", "diffuse"): Range(0.0, 1.0),
    ("environment", "density0"): Range(1e-25, 2.0, "kg / m3"),
    ("environment", "altitude0"): Range(0.0, 1e5, "km"),
    ("environment", "scale_height"): Range(1.0, 1e4, "km"),
    ("environment", "f107"): Range(50.0, 500.0),
    ("environment", "f107a"): Range(50.0, 500.0),
    ("environment", "ap"): Range(0.0, 400.0),
    ("initial", "omega"): Range(None, 1e4, "rad / s", signed=True),
    ("initial", "euler_momenta"): Range(None, 1e60, "kg m2 / s", signed=True),
    ("orbit", "a"): Range(1e-3, 1e12, "km"),
    ("orbit", "gm"): Range(1e-15, 1e12, "km3 / s2"),
    ("integration", "t_end"): Range(None, 1e15, "s"),
    ("integration", "output_step"): Range(1e-9, 1e15, "s"),
    ("integration", "step"): Range(1e-9, 1e15, "s"),
    # the [torques] keys' ranges: from their descriptors (orbatt.terms)
    **{("torques", key): Range(None, high, unit, signed=True) for key, (high, unit) in torque_ranges().items()},
    **{("control", key): Range(low, high, unit) for key, (low, high, unit) in control_ranges().items()},
    ("control.modes", "until_time"): Range(1e-6, 1e10, "s"),
    ("control.modes", "until_rate"): Range(1e-9, 10.0, "rad / s"),
    ("control.modes", "until_settled"): Range(1e-9, math.pi, "rad"),
    ("control.modes", "hold"): Range(0.0, 1e10, "s"),
}


def key_bounds(table, key, unit):
    """``(low, high)`` of ``[table] key`` in the astropy ``unit``, or None for a key without a
    range (an angle is bounded by :data:`ANGLE_LIMIT` in magnitude)."""
    if u.Unit(unit) == U.ANGLE:
        return (-ANGLE_LIMIT, ANGLE_LIMIT)
    r = RANGES.get((table, key))
    return None if r is None else r.bounds(unit)


def range_text(table, key, dimension=""):
    """The range of ``[table] key`` for the reference (``docs/scenarios.md``): the
    :data:`RANGES` entry's text, the angle limit for an angle, else ``""``."""
    r = RANGES.get((table, key))
    if r is not None:
        return r.text()
    if dimension.startswith("angle"):
        return f"|x| <= {ANGLE_LIMIT:g} rad ({math.degrees(ANGLE_LIMIT):.0f} deg)"
    return ""

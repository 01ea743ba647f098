"""orbatt's internal unit system and the one place where Quantities are stripped.

Kernels work in plain floats. For dimensional problems the API converts every input to
**kilograms, kilometres, seconds and radians** (inertia in kg km^2, momenta ``Q, g, G`` in
kg km^2 s^-1, energies in kg km^2 s^-2, GM in km^3 s^-2) and attaches these units again on
output. A *dimensionless* problem (inertia given as plain numbers, like the paper's
Sects. 6.1-6.2) keeps plain numbers throughout and says so with unit ``"1"``.
"""
from __future__ import annotations

import numpy as np
from astropy import units as u

from .errors import InputError

LENGTH = u.km
TIME = u.s
MASS = u.kg
ANGLE = u.rad
INERTIA = u.kg * u.km**2
MOMENTUM = u.kg * u.km**2 / u.s
ENERGY = u.kg * u.km**2 / u.s**2
RATE = u.rad / u.s
GM = u.km**3 / u.s**2
DIMENSIONLESS = u.dimensionless_unscaled


def strip(value, unit, name, *, allow_plain=False):
    """Convert ``value`` to a float64 array in ``unit``.

    Parameters
    ----------
    value : Quantity, str, float or array-like
        A Quantity (or a string astropy parses, ``"7000 km"``) of the dimension of ``unit``.
        A plain number is accepted only with ``allow_plain=True`` (then it is taken as
        already in ``unit``: this is how dimensionless problems pass their numbers), or when
        ``unit`` is itself dimensionless or an angle in radians.
    unit : astropy Unit
    name : str
        The field name used in error messages.
    """
    if isinstance(value, str):
        try:
            value = u.Quantity(value)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{name}: cannot parse {value!r} as a quantity ({exc}); write e.g. '1 {unit}'") from None
    if isinstance(value, u.Quantity):
        try:
            out = value.to_value(unit, equivalencies=u.dimensionless_angles() if unit.physical_type == "angle" else [])
        except u.UnitConversionError:
            raise InputError(f"{name}: {value} has the wrong dimension; expected a {unit.physical_type} "
                             f"such as '1 {unit.to_string()}'") from None
        out = np.asarray(out, dtype=np.float64)
    else:
        try:
            out = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"{name}: {value!r} is not a number or quantity") from None
        if not (allow_plain or unit in (DIMENSIONLESS, u.rad)):
            raise InputError(f"{name}: {value!r} has no unit; give a Quantity such as '{value} {unit.to_string()}'")
    if not np.all(np.isfinite(out)):
        raise InputError(f"{name}: {value!r} is not finite; give finite values")
    return out

"""orbatt's internal unit system and the one place where Quantities are stripped.

Kernels work in plain floats. For dimensional problems the API converts every input to
**kilograms, kilometres, seconds and radians** (inertia in kg km^2, momenta ``Q, g, G`` in
kg km^2 s^-1, energies in kg km^2 s^-2, GM in km^3 s^-2) and attaches these units again on
output. A *dimensionless* problem (inertia given as plain numbers, like the paper's
Sects. 6.1-6.2) keeps plain numbers throughout and says so with unit ``"1"``.

Outputs (Datasets, files, printed states) give the attitude family in SI: inertia in
kg m^2, momenta in kg m^2 s^-1, energies in J (:data:`DIMENSIONAL_UNITS`), each the kernel's
value times :data:`OUTPUT_SCALE` (``1e6``: km^2 -> m^2), applied once at the Dataset boundary
(:func:`to_output`); orbit positions stay in km. Files of earlier versions wrote the kernel
units; :data:`LEGACY_OUTPUT` says how their values are scaled on reading.

The unit strings orbatt writes (the ``units`` attribute of every Dataset variable) come from
the one table here: :data:`CF_UNITS` (CF/UDUNITS spellings and the astropy unit each parses
to), :data:`DIMENSIONAL_UNITS` / :data:`DIMENSIONLESS_UNITS` (the spelling of each quantity
kind in either unit system); :func:`unit_string` and :func:`parse_unit` convert between
strings and astropy units.
"""
from __future__ import annotations

import math

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
#: revolutions per minute (reaction-wheel speeds, ``"1000 rpm"``), enabled in astropy's parser:
#: the unit scenario files read, for Python too (``1000 * orbatt.rpm``, ``orbatt.units.rpm``;
#: ``u.Unit("rpm")`` once orbatt.units is imported)
RPM = u.def_unit("rpm", u.cycle / u.min, doc="revolutions per minute")
rpm = RPM
u.add_enabled_units([RPM])

#: CF/UDUNITS unit spellings orbatt writes, with the astropy unit each one parses to. Exponents
#: are spelled with ``^`` (``"kg km^2 s^-1"``): astropy, UDUNITS-2 (the CF unit library) and
#: pint's default registry all parse this form, while pint reads ``"s-1"`` as "s minus 1".
#: Every key round-trips: ``astropy.units.Unit(key) == CF_UNITS[key]`` (tested with all three).
CF_UNITS = {
    "1": u.dimensionless_unscaled,
    "rad": u.rad,
    "degree": u.deg,
    "s": u.s,
    "km": u.km,
    "m": u.m,
    "km s^-1": u.km / u.s,
    "m s^-1": u.m / u.s,
    "rad s^-1": u.rad / u.s,
    "degree s^-1": u.deg / u.s,
    "kg km^2": u.kg * u.km**2,
    "kg m^2": u.kg * u.m**2,
    "kg km^2 s^-1": u.kg * u.km**2 / u.s,
    "kg m^2 s^-1": u.kg * u.m**2 / u.s,
    "kg km^2 s^-2": u.kg * u.km**2 / u.s**2,
    "kg m^2 s^-2": u.kg * u.m**2 / u.s**2,
    "J": u.J,
    "km^3 s^-2": u.km**3 / u.s**2,
}

#: spellings orbatt 0.1 wrote (UDUNITS's bare exponents, ``"kg km2 s-1"``), still read by
#: :func:`parse_unit` so that files written before stay readable; never written.
LEGACY_UNITS = {k.replace("^", ""): v for k, v in CF_UNITS.items() if "^" in k}

#: time units of a CF ``"<unit> since <date>"`` string
CF_TIME_UNITS = {"seconds": u.s, "second": u.s, "secs": u.s, "sec": u.s, "s": u.s,
                 "minutes": u.min, "minute": u.min, "min": u.min, "hours": u.h, "hour": u.h,
                 "h": u.h, "days": u.day, "day": u.day, "d": u.day}

#: CF spelling of the internal unit system by quantity kind (the kernels' units: what
#: :func:`strip` gives, and what sweep parameters are sampled in)
INTERNAL_UNITS = {"time": "s", "angle": "rad", "rate": "rad s^-1", "inertia": "kg km^2",
                  "momentum": "kg km^2 s^-1", "energy": "kg km^2 s^-2", "length": "km",
                  "speed": "km s^-1", "one": "1"}
#: CF spelling by quantity kind of what orbatt writes for a dimensional problem (the
#: ``units`` attribute of a Dataset variable): SI for the attitude family (kg m^2,
#: kg m^2 s^-1, J), km and km s^-1 for orbit positions and velocities
DIMENSIONAL_UNITS = {"time": "s", "angle": "rad", "rate": "rad s^-1", "inertia": "kg m^2",
                     "momentum": "kg m^2 s^-1", "energy": "J", "length": "km",
                     "speed": "km s^-1", "one": "1"}
#: the same for a dimensionless problem: ``"1"`` everywhere except angles (``"rad"``)
DIMENSIONLESS_UNITS = {k: ("rad" if k == "angle" else "1") for k in DIMENSIONAL_UNITS}
#: output value = internal value * factor, by quantity kind (dimensional problems; kinds not
#: listed keep their values): kg km^2 -> kg m^2 is exactly a factor 10^6
OUTPUT_SCALE = {"inertia": 1e6, "momentum": 1e6, "energy": 1e6}
#: ``units`` attributes written by orbatt <= 0.3.0.dev0 for the attitude family (kernel units,
#: with or without ``^``) -> ``(the SI spelling written now, the factor its values take)``
LEGACY_OUTPUT = {}
for _kind in OUTPUT_SCALE:
    for _spelling in (INTERNAL_UNITS[_kind], INTERNAL_UNITS[_kind].replace("^", "")):
        LEGACY_OUTPUT[_spelling] = (DIMENSIONAL_UNITS[_kind], OUTPUT_SCALE[_kind])
del _kind, _spelling


#: the kernels' units against SI, by quantity (issue 32): ``kind -> (SI unit, SI -> kernel
#: factor, kernel -> SI factor)``, the one place the 1e+-6 of kg km^2 against kg m^2 is written.
#: The kernels run in kg, km, s: a torque in kg km^2 s^-2 = 1e6 N m; a magnetic dipole in
#: 1e-6 A m^2, so that ``m x B`` with ``B`` in T is such a torque; a density in kg km^-3. The
#: two factors are written both ways (not one as the other's reciprocal) so that values
#: convert with the exact operations they always did, bit for bit.
KERNEL_UNITS = {
    "torque": ("N m", 1e-6, 1e6),
    "torque_time": ("N m s", 1e-6, 1e6),
    "dipole": ("A m2", 1e-6, 1e6),
    "dipole_gain": ("A m2 s / T", 1e-6, 1e6),
    "inertia": ("kg m2", 1e-6, 1e6),
    "momentum": ("kg m2 / s", 1e-6, 1e6),
    "density": ("kg m-3", 1e9, 1e-9),
}


def to_kernel(values, kind):
    """SI ``values`` of quantity ``kind`` (:data:`KERNEL_UNITS`) in the kernels' unit: a float
    for a float, an array for an array-like (a new array); None stays None."""
    if values is None:
        return None
    factor = KERNEL_UNITS[kind][1]
    return values * factor if isinstance(values, float) else np.multiply(values, factor)


def from_kernel(values, kind):
    """Kernel ``values`` of quantity ``kind`` (:data:`KERNEL_UNITS`) in SI (its first column)."""
    if values is None:
        return None
    factor = KERNEL_UNITS[kind][2]
    return values * factor if isinstance(values, float) else np.multiply(values, factor)


def to_output(values, kind, dimensionless=False):
    """Values of quantity kind ``kind`` in internal units as written (SI for the attitude
    family, :data:`OUTPUT_SCALE`).

    Parameters
    ----------
    values : ndarray
        In the internal unit of ``kind`` (:data:`INTERNAL_UNITS`).
    kind : str
        A key of :data:`DIMENSIONAL_UNITS`.
    dimensionless : bool
        A dimensionless problem keeps its plain numbers (``values`` is returned as it is).

    Returns
    -------
    ndarray
        ``values * OUTPUT_SCALE[kind]`` (a new array), or ``values`` itself where no factor
        applies; in the unit ``DIMENSIONAL_UNITS[kind]``.
    """
    factor = None if dimensionless else OUTPUT_SCALE.get(kind)
    return values if factor is None else np.multiply(values, factor)


def _require_unit(value, unit, name, allow_plain):
    """Refuse a plain number for ``unit`` unless ``allow_plain`` or ``unit`` is dimensionless or
    radians (:func:`strip`)."""
    if not (allow_plain or unit is u.rad or unit is DIMENSIONLESS or unit in (DIMENSIONLESS, u.rad)):
        raise InputError(f"{name}: {value!r} has no unit; give a Quantity such as '{value} {unit.to_string()}'")


def _check_finite(out, value, name):
    """Refuse non-finite values ``out`` (a float or an array; the given ``value`` named in the
    message; small arrays checked on Python floats, numpy's calls cost ~2 us on a few)."""
    if type(out) is float or type(out) is np.float64:
        ok = math.isfinite(out)
    else:
        ok = all(map(math.isfinite, out.ravel().tolist())) if out.size <= 16 else np.isfinite(out).all()
    if not ok:
        raise InputError(f"{name}: {value!r} is not finite; give finite values")


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
    if type(value) is float:  # a plain number (the checks below, without numpy's ~2 us on a scalar)
        _require_unit(value, unit, name, allow_plain)
        _check_finite(value, value, name)
        return np.asarray(value, dtype=np.float64)
    if isinstance(value, str):
        try:
            value = u.Quantity(value)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{name}: cannot parse {value!r} as a quantity ({exc}); write e.g. '1 {unit}'") from None
    if isinstance(value, u.Quantity):
        try:
            # without equivalencies first (astropy converts between compatible units without
            # them alike): unit.physical_type costs ~5 us, and strip runs on every input
            out = value.to_value(unit)
        except u.UnitConversionError:
            out = None
        if out is None:
            try:
                if unit.physical_type != "angle":
                    raise u.UnitConversionError(name)
                out = value.to_value(unit, equivalencies=u.dimensionless_angles())
            except u.UnitConversionError:
                raise InputError(f"{name}: {value} has the wrong dimension; expected {dimension_phrase(unit)} "
                                 f"such as '1 {unit.to_string()}'") from None
        if type(out) is np.float64:  # one value: the check below without numpy's ~2 us on a scalar
            _check_finite(out, value, name)
            return np.asarray(out)
        out = np.asarray(out, dtype=np.float64)
    else:
        try:
            out = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"{name}: {value!r} is not a number or quantity") from None
        _require_unit(value, unit, name, allow_plain)
    _check_finite(out, value, name)
    return out


def dimension_phrase(unit) -> str:
    """The dimension of ``unit`` in words with its article, for messages: ``"a length"``,
    ``"an angular frequency"`` (the first of astropy's names), or ``"a quantity in A m2 s /
    T"`` where astropy has no name for it."""
    names = str(unit.physical_type).split("/")
    kind = "torque" if "torque" in names else names[0]  # N m: a torque in orbatt's keys, not an energy
    if kind == "unknown":
        return f"a quantity in {unit.to_string()}"
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def unit_string(unit) -> str:
    """CF/UDUNITS spelling of an astropy unit.

    Parameters
    ----------
    unit : astropy Unit or str
        A unit (a string is parsed first, :func:`parse_unit`).

    Returns
    -------
    str
        The :data:`CF_UNITS` key whose unit is written the same way (``"kg km^2 s^-1"``), or
        else the bases with ``^`` exponents (``"km^2 kg s^-3"``, :func:`caret_string`), or the
        FITS or generic spelling astropy gives. The result always parses back to an equal unit with
        :func:`astropy.units.Unit`.
    """
    unit = parse_unit(unit) if isinstance(unit, str) else u.Unit(unit)
    if unit == u.dimensionless_unscaled:
        return "1"
    rep = unit.to_string()
    for key, val in CF_UNITS.items():
        if val.to_string() == rep:
            return key
    caret = caret_string(unit)
    if caret is not None:
        return caret
    for fmt in ("fits", "generic"):
        try:
            s = unit.to_string(fmt)
        except (ValueError, u.UnitsError):
            continue
        try:
            if u.Unit(s) == unit:
                return s
        except ValueError:
            continue
    return unit.to_string()


def caret_string(unit):
    """``"kg km^2 s^-3"``: the bases of ``unit`` with ``^`` exponents, or ``None`` when the unit
    has a scale factor or a base whose name is not a plain word (then no such spelling)."""
    unit = u.Unit(unit)
    if unit.scale != 1.0 or not unit.bases:
        return None
    parts = []
    for base, power in sorted(zip(unit.bases, unit.powers), key=lambda bp: bp[1] < 0):
        name = base.to_string()
        if not name.isalpha():
            return None
        if power == 1:
            parts.append(name)
        elif float(power).is_integer():
            parts.append(f"{name}^{int(power)}")
        else:
            return None
    s = " ".join(parts)
    try:
        return s if u.Unit(s) == unit else None
    except ValueError:
        return None


def parse_unit(s):
    """astropy unit of a ``units`` attribute.

    Parameters
    ----------
    s : str
        A :data:`CF_UNITS` key, any string :class:`astropy.units.Unit` parses, or a CF time
        reference ``"seconds since 2024-01-01T00:00:00Z"`` (then the unit before ``since``).

    Raises
    ------
    InputError
        The string is not a unit.
    """
    if isinstance(s, u.UnitBase):
        return s
    s = str(s).strip()
    if s in CF_UNITS:
        return CF_UNITS[s]
    if s in LEGACY_UNITS:
        return LEGACY_UNITS[s]
    if " since " in s:
        head = s.split(" since ", 1)[0].strip().lower()
        if head in CF_TIME_UNITS:
            return CF_TIME_UNITS[head]
    try:
        return u.Unit(s)
    except ValueError:
        raise InputError(f"units: {s!r} is not a unit astropy parses; use a CF spelling such as "
                         f"'rad s^-1' or 'kg km^2'") from None

"""The one unit table (:mod:`orbatt.units`): CF spellings round-trip through astropy and
UDUNITS; internal units have table spellings. (Also reachable as ``orbatt.dataset.*``.)"""
import re

import pytest
from astropy import units as u

from orbatt import dataset as D
from orbatt import units as U
from orbatt.errors import InputError
from unit_support import same_in_pint, udunits_parses


def test_dataset_reexports_the_one_table():
    assert D.CF_UNITS is U.CF_UNITS
    assert D.DIMENSIONAL_UNITS is U.DIMENSIONAL_UNITS and D.DIMENSIONLESS_UNITS is U.DIMENSIONLESS_UNITS
    assert D.unit_string is U.unit_string and D.parse_unit is U.parse_unit


@pytest.mark.parametrize("spelling", list(D.CF_UNITS))
def test_cf_spelling_round_trips_through_astropy(spelling):
    unit = u.Unit(spelling)
    assert unit == D.CF_UNITS[spelling]
    assert unit.to_string() == D.CF_UNITS[spelling].to_string()
    assert D.unit_string(unit) == spelling
    assert D.parse_unit(spelling) == unit


def test_internal_units_have_table_spellings():
    from orbatt import units as U

    assert D.unit_string(U.RATE) == "rad s^-1"
    assert D.unit_string(U.INERTIA) == "kg km^2"
    assert D.unit_string(U.MOMENTUM) == "kg km^2 s^-1"
    assert D.unit_string(U.ENERGY) == "kg km^2 s^-2"
    assert D.unit_string(U.GM) == "km^3 s^-2"
    assert D.unit_string(U.DIMENSIONLESS) == "1"
    assert D.unit_string(u.deg / u.s) == "degree s^-1"
    assert D.unit_string("deg/s") == "degree s^-1"


def test_unit_string_falls_back_to_a_parseable_spelling():
    assert D.parse_unit("seconds since 2024-01-01T00:00:00Z") == u.s
    with pytest.raises(InputError, match="not a unit"):
        D.parse_unit("furlongs per fortnight please")


@pytest.mark.parametrize("spelling", list(D.CF_UNITS))
def test_cf_spellings_parse_in_udunits_and_pint(spelling):
    assert udunits_parses(spelling), spelling
    assert same_in_pint(spelling, D.CF_UNITS[spelling]), spelling


def test_caret_exponents_everywhere_and_old_spellings_still_read():
    bare = [k for k in D.CF_UNITS if re.search(r"[A-Za-z]-?[0-9]", k)]  # "km2", "s-1"
    assert not bare
    # orbatt 0.1 wrote "kg km2 s-1": still parsed, to the same unit, never written
    assert U.LEGACY_UNITS["kg km2 s-1"] == U.MOMENTUM
    for old, new in [("kg km2 s-1", "kg km^2 s^-1"), ("rad s-1", "rad s^-1"), ("km3 s-2", "km^3 s^-2"),
                     ("kg km2", "kg km^2"), ("kg km2 s-2", "kg km^2 s^-2"), ("km s-1", "km s^-1")]:
        assert D.parse_unit(old) == D.parse_unit(new) == D.CF_UNITS[new]
        assert D.unit_string(D.parse_unit(old)) == new


def test_fallback_spelling_has_carets_and_parses_everywhere():
    odd = u.kg * u.km**2 / u.s**3
    s = D.unit_string(odd)
    assert "^" in s and u.Unit(s) == odd
    assert udunits_parses(s) and same_in_pint(s, odd)

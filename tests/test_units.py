"""The one unit table (:mod:`orbatt.units`): CF spellings round-trip through astropy and
UDUNITS; internal units have table spellings. (Also reachable as ``orbatt.dataset.*``.)"""
import pytest
from astropy import units as u

from orbatt import dataset as D
from orbatt import units as U
from orbatt.errors import InputError


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

    assert D.unit_string(U.RATE) == "rad s-1"
    assert D.unit_string(U.INERTIA) == "kg km2"
    assert D.unit_string(U.MOMENTUM) == "kg km2 s-1"
    assert D.unit_string(U.ENERGY) == "kg km2 s-2"
    assert D.unit_string(U.GM) == "km3 s-2"
    assert D.unit_string(U.DIMENSIONLESS) == "1"
    assert D.unit_string(u.deg / u.s) == "degree s-1"
    assert D.unit_string("deg/s") == "degree s-1"


def test_unit_string_falls_back_to_a_parseable_spelling():
    odd = u.kg * u.km**2 / u.s**3
    s = D.unit_string(odd)
    assert u.Unit(s) == odd
    assert D.parse_unit("seconds since 2024-01-01T00:00:00Z") == u.s
    with pytest.raises(InputError, match="not a unit"):
        D.parse_unit("furlongs per fortnight please")


def test_cf_spellings_are_udunits_valid():
    cfunits = pytest.importorskip("cfunits")
    for s in D.CF_UNITS:
        assert cfunits.Units(s).isvalid, s

"""Unit-library checks shared by the unit tests: UDUNITS-2 and pint read a spelling as astropy does."""
import pytest


def udunits_parses(s):
    """True if UDUNITS-2 (the CF unit library) parses ``s``: through cf_units (whose wheel
    bundles the C library) or cfunits (which needs a system libudunits2); skip if neither."""
    try:
        import cf_units
    except ImportError:
        cf_units = None
    if cf_units is not None:
        try:
            cf_units.Unit(s)
            return True
        except ValueError:
            return False
    try:
        import cfunits
    except (ImportError, OSError, FileNotFoundError):
        pytest.skip("no UDUNITS-2 binding (cf_units, or cfunits with libudunits2)")
    return cfunits.Units(s).isvalid


def pint_unit(s):
    """The unit pint's default registry reads from ``s`` (skip without pint)."""
    pint = pytest.importorskip("pint")
    return pint.get_application_registry().Unit(s)


def same_in_pint(s, astropy_unit):
    """pint reads ``s`` as the astropy unit (compare the SI factor and dimension of both)."""
    pu = pint_unit(s)
    q = (1 * pu).to_base_units()
    si = (1 * astropy_unit).decompose()
    expect = {str(b): p for b, p in zip(si.unit.bases, si.unit.powers)}
    got = {k.replace("kilogram", "kg").replace("meter", "m").replace("second", "s").replace("radian", "rad").replace("ampere", "A"): v
           for k, v in q.unit_items()}
    return abs(q.magnitude - si.value) <= 1e-9 * abs(si.value) and got == expect

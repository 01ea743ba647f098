"""The one epoch parser (:mod:`orbatt.epoch`) and its two string forms."""
import pytest
from astropy.time import Time

from orbatt import dataset as D
from orbatt.epoch import epoch_string, iso_epoch, parse_epoch
from orbatt.errors import InputError
from orbatt.orbits import base


def test_strings_with_and_without_z_are_utc():
    a = parse_epoch("2024-01-01T00:00:00Z")
    b = parse_epoch(" 2024-01-01T00:00:00 ")
    assert a.scale == "utc" and a == b
    t = Time("2024-01-01T00:00:00", scale="tdb")
    assert parse_epoch(t) is t
    assert parse_epoch(None) is None and iso_epoch(None) is None


def test_string_forms():
    assert iso_epoch("2024-03-20T03:06:00") == "2024-03-20T03:06:00.000000000Z"
    assert iso_epoch(iso_epoch("2024-03-20T03:06:00.5Z")) == "2024-03-20T03:06:00.500000000Z"
    assert epoch_string("2024-03-20T03:06:00Z") == "2024-03-20T03:06:00.000"


@pytest.mark.parametrize("bad,match", [("yesterday", "not a time"), (3.0, "expected an astropy Time"),
                                       (Time(["2024-01-01", "2024-01-02"]), "one instant")])
def test_refusals_name_the_field(bad, match):
    with pytest.raises(InputError, match=f"^epoch: .*{match}"):
        parse_epoch(bad)
    with pytest.raises(InputError, match="^t0: "):
        parse_epoch(bad, name="t0")


def test_old_names_are_the_one_parser():
    assert D.iso_epoch is iso_epoch
    assert base.parse_epoch is parse_epoch and base.epoch_string is epoch_string

"""Corrupt TLEs and TLE files refused up front in one line naming the field (issue 26, item 6):
non-ASCII characters, out-of-range or blank fields that pass the checksum (SGP4 would read
them silently), TLE files that are not small regular text files, runs far from the TLE's
epoch; and a TLE dated beyond astropy's tables runs with one warning."""
import os
import threading
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest

import orbatt
from orbatt.errors import InputError, ScenarioError
from orbatt.orbits import TleOrbit
from orbatt.orbits.tle import MAX_TLE_DAYS, TleDatesWarning, parse_tle, read_tle_file, tle_checksum

L1 = "1 25544U 98067A   19343.69339541  .00001764  00000-0  38792-4 0  9991"
L2 = "2 25544  51.6439 211.2001 0007417  17.6667  85.6398 15.50103472202482"


def _fix(line):
    """``line`` with its checksum made right (a corruption the checksum does not see)."""
    return line[:68] + str(tle_checksum(line))


def _set(line, c0, text):
    """``line`` with ``text`` written from 1-based column ``c0``, checksum fixed."""
    return _fix(line[:c0 - 1] + text + line[c0 - 1 + len(text):])


CORRUPT = {
    # U+0665 ARABIC-INDIC DIGIT FIVE: isdigit(), counted by the checksum; SGP4 read 15.0
    "non-ASCII digit in the mean motion": (L1, _set(L2, 55, "\u0665"), r"line 2 has '\u0665' at column 55"),
    "epoch day 000": (_set(L1, 21, "000.69339541"), L2, r"columns 21-32 \(epoch day of the year\) '000.69339541' "
                                                        r"must be in \[1, 366\) in 2019"),
    "epoch day 367": (_set(L1, 21, "367.69339541"), L2, r"'367.69339541' must be in \[1, 366\)"),
    "epoch day 366 of 2019": (_set(L1, 21, "366.00000000"), L2, r"must be in \[1, 366\) in 2019"),
    "epoch day 999.99999999": (_set(L1, 21, "999.99999999"), L2, r"'999.99999999' must be in"),
    "epoch year blank": (_set(L1, 19, "  "), L2, r"columns 19-20 \(epoch year\) '  ' is not 2 digits"),
    "inclination 999.9999": (L1, _set(L2, 9, "999.9999"), r"columns 9-16 \(inclination\) '999.9999' must be in "
                                                          r"\[0, 180\] deg"),
    "negative inclination": (L1, _set(L2, 9, "-51.6439"), r"\(inclination\) '-51.6439' must be in \[0, 180\]"),
    "blank eccentricity": (L1, _set(L2, 27, "       "), r"columns 27-33 \(eccentricity\) '       ' is not 7 digits"),
    "right ascension 400": (L1, _set(L2, 18, "400.0000"), r"\(right ascension of the node\) '400.0000' must be in"),
    "negative mean motion": (L1, _set(L2, 53, "-5.50103472"), r"\(mean motion\) '-5.50103472' must be positive"),
    "zero mean motion": (L1, _set(L2, 53, " 0.00000000"), r"\(mean motion\) ' 0.00000000' must be positive"),
    "NUL in a line": (L1, L2[:30] + "\0" + L2[31:], r"line 2 has '\\x00' at column 31, not an ASCII character"),
}


@pytest.mark.parametrize("case", sorted(CORRUPT))
def test_corrupt_tles_are_refused_naming_the_field(case):
    line1, line2, match = CORRUPT[case]
    with pytest.raises(InputError, match=r"^tle: .*" + match + r".*(copy it again)"):
        parse_tle([line1, line2])


def test_valid_edge_fields_and_sgp4s_verification_tles_pass():
    parse_tle([_set(L1, 19, "20366.99999999"), L2])  # day 366 of a leap year
    parse_tle([L1, _set(L2, 9, "180.0000")])
    import sgp4

    text = (Path(sgp4.__file__).parent / "SGP4-VER.TLE").read_text().splitlines()
    pairs = [(a[:69], b[:69]) for a, b in zip(text, text[1:]) if a.startswith("1 ") and b.startswith("2 ")]
    passed = 0
    for a, b in pairs:
        if int(a[68]) != tle_checksum(a) or int(b[68]) != tle_checksum(b):
            continue  # the file keeps a few lines with wrong checksums
        try:
            parse_tle([a, b])
            passed += 1
        except InputError as exc:  # only SGP4's own refusal, never a field
            assert "SGP4 refuses" in str(exc), exc
    assert passed >= 29


SCEN = f"""
name = "tle-input"
[body]
inertia = ["12 kg m2", "110 kg m2", "115 kg m2"]
[initial]
frame = "orbital"
euler_313 = ["0 deg", "3 deg", "5 deg"]
omega = ["0 rad/s", "0 rad/s", "0 rad/s"]
[potential]
kind = "gravity-gradient"
[orbit]
provider = "tle"
{{orbit}}
[integration]
t_end = "600 s"
output_step = "60 s"
"""


@pytest.mark.parametrize("line1, line2, field", [
    (_set(L1, 21, "000.69339541"), L2, "columns 21-32 (epoch day of the year)"),
    (L1, _set(L2, 53, "-5.50103472"), "columns 53-63 (mean motion)"),
])
def test_scenario_names_the_tle_not_initial_q(tmp_path, line1, line2, field):
    path = tmp_path / "s.toml"
    path.write_text(SCEN.format(orbit=f'tle = ["{line1}", "{line2}"]'))
    with pytest.raises(ScenarioError) as err:
        orbatt.load_scenario(path)
    assert "[orbit]" in str(err.value) and f"tle: line {1 if line2 == L2 else 2} {field}" in str(err.value)
    assert "[initial]" not in str(err.value)


def _read_in_thread(path):
    """:func:`read_tle_file` in a thread that must end within 10 s (a FIFO must not block)."""
    out = {}

    def target():
        try:
            read_tle_file(path)
        except InputError as exc:
            out["error"] = str(exc)

    th = threading.Thread(target=target, daemon=True)
    th.start()
    th.join(10.0)
    assert not th.is_alive(), f"read_tle_file({path!r}) blocked"
    return out.get("error", "")


def test_tle_files_that_are_not_small_regular_text_are_refused(tmp_path):
    text = f"ISS\n{L1}\n{L2}\n"
    files = {"latin1.tle": ("ISS \xe9\n" + text[4:]).encode("latin-1"),
             "utf16.tle": text.encode("utf-16"),
             "nul.tle": text.replace("ISS", "IS\0").encode(),
             "big.tle": text.encode() + b" " * 10_000}
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    assert "not UTF-8 text (byte 0xe9 at offset 4: Latin-1?)" in _read_in_thread(tmp_path / "latin1.tle")
    assert "holds NUL bytes" in _read_in_thread(tmp_path / "utf16.tle")
    assert "holds NUL bytes at offset 2" in _read_in_thread(tmp_path / "nul.tle")
    assert "is 10" in _read_in_thread(tmp_path / "big.tle") and "under 4096 bytes" in _read_in_thread(
        tmp_path / "big.tle")
    assert "not a regular file" in _read_in_thread(tmp_path)
    for dev in ("/dev/zero", "/dev/urandom"):
        if os.path.exists(dev):
            assert _read_in_thread(dev).startswith(f"tle_file: '{dev}' is not a regular file")
    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "fifo")
        assert "not a regular file" in _read_in_thread(tmp_path / "fifo")
    # UTF-8 with a BOM and a non-ASCII name line is text: read
    (tmp_path / "bom.tle").write_bytes(("ISS \u00e9\n" + text[4:]).encode("utf-8-sig"))
    assert read_tle_file(tmp_path / "bom.tle")[0] == "ISS \u00e9"


def test_tle_file_in_a_scenario_names_tle_file(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SCEN.format(orbit='tle_file = "/dev/zero"'))
    with pytest.raises(ScenarioError, match=r"\[orbit\]: tle_file: '/dev/zero' is not a regular file"):
        orbatt.load_scenario(path)


@pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")  # the scenario's epoch 2219 (parse_epoch)
def test_runs_far_from_the_tles_epoch_are_refused(tmp_path):
    with pytest.raises(InputError, match=r"tle: the orbit would reach 7\.30\de\+04 days from the TLE's epoch "
                                         r"2019-12-09T16:38:29.363; .* within 366 days"):
        TleOrbit([L1, L2], 1 * u.h, epoch="2219-12-09T00:00:00")
    TleOrbit([L1, L2], 1 * u.h, epoch="2020-12-08T00:00:00")        # 364 days: fine
    with pytest.raises(InputError, match="would reach 367"):
        TleOrbit([L1, L2], 2 * u.d, epoch="2020-12-09T00:00:00")
    path = tmp_path / "s.toml"
    path.write_text(SCEN.format(orbit=f'tle = ["{L1}", "{L2}"]\nepoch = "2219-12-09T00:00:00"'))
    with pytest.raises(ScenarioError, match=r"\[orbit\]: tle: the orbit would reach"):
        orbatt.load_scenario(path)
    assert MAX_TLE_DAYS == 366.0


def test_a_tle_beyond_astropys_tables_runs_with_one_warning():
    future = _set(L1, 19, "45")                  # 2045: past the IERS predictions and leap seconds
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        orbit = TleOrbit([future, L2], 1 * u.h)
        pos, _ = orbit.state(np.linspace(0.0, 3600.0, 7))
    # (a ResourceWarning is another test's file collected meanwhile, not this orbit's)
    caught = [w for w in caught if not issubclass(w.category, ResourceWarning)]
    assert [w.category for w in caught] == [TleDatesWarning]
    assert "tle: the dates 2045-12-09" in str(caught[0].message)
    assert np.all(np.isfinite(pos)) and 6700 < np.linalg.norm(pos, axis=1).min()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        TleOrbit([L1, L2], 1 * u.h)              # inside the tables: no warning
    assert [w for w in caught if not issubclass(w.category, ResourceWarning)] == []

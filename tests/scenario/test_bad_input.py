"""Hostile scenario input (issue 14 §2, §3): every mutant is refused with one ScenarioError
that names the key, before anything is integrated; files that are not UTF-8 TOML are refused
by name in load_scenario and read_aem."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from not_utf8_files import not_utf8_files

import orbatt
from orbatt.errors import InputError, ScenarioError
from orbatt.scenario import load_scenario, parse

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
KEP = (SCEN / "paper-keplerian.toml").read_text()
FREE = (SCEN / "paper-torque-free.toml").read_text()
LEO = (SCEN / "gg-stabilized-leo.toml").read_text()


def edit(text, old, new):
    assert text.count(old) == 1, old
    return text.replace(old, new)


def kep(old, new):
    return edit(KEP, old, new)


# (id, scenario text, the key the message must name, a fragment of the message)
PARSE_CASES = [
    # non-finite, huge and tiny quantity strings get the checks plain numbers get
    ("nan t_end", kep('t_end = "2 orbits"', 't_end = "nan s"'), r"\[integration\] t_end", "not finite"),
    ("inf t_end", kep('t_end = "2 orbits"', 't_end = "inf s"'), r"\[integration\] t_end", "not finite"),
    ("nan orbits", kep('t_end = "2 orbits"', 't_end = "nan orbits"'), r"\[integration\] t_end", "not finite"),
    ("huge t_end", kep('t_end = "2 orbits"', 't_end = "1e300 s"'), r"\[integration\] t_end", "outside"),
    ("tiny output_step", kep('output_step = "10 s"', 'output_step = "1e-308 s"'), r"\[integration\] output_step",
     "magnitude"),
    ("huge a", kep('a = "7000 km"', 'a = "1e308 km"'), r"\[orbit\] a", "outside"),
    ("overflowing a", kep('a = "7000 km"', 'a = "1e400 km"'), r"\[orbit\] a", "not finite"),
    ("tiny gm", kep('central_body = "earth"', 'gm = "1e-308 km3 / s2"'), r"\[orbit\] gm", "outside"),
    ("huge gm", kep('central_body = "earth"', 'gm = "1e308 km3/s2"'), r"\[orbit\] gm", "outside"),
    ("tiny inertia", kep('"400 kg km2"', '"1e-300 kg m2"'), r"\[body\] inertia\[0\]", "outside"),
    ("huge omega", edit(LEO, 'omega = ["0 rad/s", "0 rad/s", "0 rad/s"]', 'omega = ["1e6 rad/s", "0 rad/s", "0 rad/s"]'),
     r"\[initial\] omega\[0\]", "outside"),
    ("huge Q", kep("Q = [0.3, -0.848528, 0.141421, -1.5]", "Q = [0.3, -0.848528, 0.141421, -1.5e300]"),
     r"\[initial\] Q", "beyond"),
    # angles need an angle unit; every quantity the dimension of its key
    ("deg deg", edit(LEO, 'i = "98.2 deg"', 'i = "98.2 deg deg"'), r"\[orbit\] i", "an angle needs an angle unit"),
    ("unitless angle string", kep('raan = "45 deg"', 'raan = "45"'), r"\[orbit\] raan", "has no unit"),
    ("unitless angle number", kep('raan = "45 deg"', "raan = 45"), r"\[orbit\] raan", "has no unit"),
    ("angle in metres", kep('argp = "15 deg"', 'argp = "15 m"'), r"\[orbit\] argp", "an angle needs an angle unit"),
    ("euler in rate", edit(LEO, 'euler_313 = ["0 deg", "3 deg", "5 deg"]', 'euler_313 = ["0 deg", "3 deg/s", "5 deg"]'),
     r"\[initial\] euler_313\[1\]", "an angle needs"),
    ("dimensionless euler without unit",
     edit(FREE, "q = [0.5, -0.7071067811865476, 0.0, 0.5]\nQ = [0.3, -0.848528, 0.141421, -1.5]",
          "euler_313 = [0.5, 1.0, 2.0]\neuler_momenta = [0.5, 0.6, 0.4]"), r"\[initial\] euler_313\[0\]", "no unit"),
    ("a in km2", kep('a = "7000 km"', 'a = "7000 km2"'), r"\[orbit\] a", "wrong dimension"),
    # the whole string parses, or it is refused
    ("1 2 orbits", kep('t_end = "2 orbits"', 't_end = "1 2 orbits"'), r"\[integration\] t_end", "one number N"),
    ("planet orbits", kep('t_end = "2 orbits"', 't_end = "0.01 planet orbits"'), r"\[integration\] t_end",
     "one number N"),
    ("1 2 s", kep('output_step = "10 s"', 'output_step = "1 2 s"'), r"\[integration\] output_step",
     "one number and a unit"),
    ("7000 1 km", kep('a = "7000 km"', 'a = "7000 1 km"'), r"\[orbit\] a", "one number and a unit"),
    ("trailing words", kep('a = "7000 km"', 'a = "7000 km please"'), r"\[orbit\] a", "not a unit"),
    # tolerances bounded, with the reason
    ("rtol 1e5", kep("rtol = 1e-12", "rtol = 1e5"), r"\[integration\] rtol", "above 0.1"),
    ("rtol 1e308", kep("rtol = 1e-12", "rtol = 1e308"), r"\[integration\] rtol", "above 0.1"),
    ("atol 1e10", kep("atol = 1e-12", "atol = 1e10"), r"\[integration\] atol", r"\|q\| = 1"),
    # method must be a name
    ("method list", kep('method = "dop853"', "method = []"), r"\[integration\] method", "is not one of"),
    ("method table", kep('method = "dop853"', "method = {}"), r"\[integration\] method", "is not one of"),
    ("method number", kep('method = "dop853"', "method = 5"), r"\[integration\] method", "is not one of"),
    # orbits that lie inside the central body
    ("a 3000 km", kep('a = "7000 km"', 'a = "3000 km"'), r"\[orbit\] a", "inside the central body"),
    ("a 1 m", kep('a = "7000 km"', 'a = "1 m"'), r"\[orbit\] a", "inside the central body"),
    # nesting too deep for the TOML parser
    ("deep array", kep('inertia = ["400 kg km2", "500 kg km2", "600 kg km2"]',
                       "inertia = " + "[" * 50_000 + "]" * 50_000), "TOML", "nested too deeply"),
]


@pytest.mark.parametrize("text,key,fragment", [c[1:] for c in PARSE_CASES], ids=[c[0] for c in PARSE_CASES])
def test_bad_values_are_refused_naming_the_key(text, key, fragment):
    with pytest.raises(ScenarioError, match=rf"^x\.toml: {key}.*{fragment}") as info:
        parse(text, "x.toml")
    assert "\n" not in str(info.value)


def test_plain_zero_angles_and_dimensionless_strings_stay_valid():
    spec = parse(kep('raan = "45 deg"', "raan = 0").replace("\ne = 0.2\n", '\ne = "0.2"\n'))
    assert spec.orbit["raan"] == 0.0 and spec.orbit["e"] == 0.2
    assert np.isclose(parse(kep('raan = "45 deg"', 'raan = "0.5 rad"')).orbit["raan"], 0.5)


def test_the_papers_orbit_with_periapsis_below_the_surface_still_loads():
    with pytest.warns(orbatt.orbits.PeriapsisWarning):
        sc = load_scenario(SCEN / "paper-keplerian.toml")
    assert sc.orbit.a_value == 7000.0


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("t_end,step", [('"1e9 orbits"', '"1 s"'), ('"1e7 s"', '"0.1 s"')])
def test_output_counts_that_cannot_fit_are_refused_naming_output_step(tmp_path, t_end, step):
    text = edit(edit(LEO, 't_end = "10 orbits"', f"t_end = {t_end}"), 'output_step = "30 s"', f"output_step = {step}")
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError, match=r"\[integration\] output_step: .* output times, more than 2e\+06"):
        load_scenario(write(tmp_path, text))
    assert time.perf_counter() - t0 < 5


@pytest.mark.parametrize("mutation,key", [
    (('omega = ["0.02 rad/s", "-0.01 rad/s", "0.05 rad/s"]', 'omega = ["9000 rad/s", "0 rad/s", "0 rad/s"]'),
     r"\[initial\]: the body turns"),
    (('t_end = "1 orbits"', 't_end = "1e8 orbits"'), r"\[orbit\] a: the orbit"),
])
def test_runs_that_cannot_end_are_refused_up_front(tmp_path, mutation, key):
    text = edit((SCEN / "molniya-tumbling.toml").read_text(), *mutation)
    if "orbits" in mutation[1]:
        text = edit(text, 'output_step = "60 s"', 'output_step = "1e7 s"')
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError, match=rf"{key} .* integration steps, more than 1e\+08"):
        load_scenario(write(tmp_path, text))
    assert time.perf_counter() - t0 < 5


def test_a_spin_at_the_work_limit_is_not_refused(tmp_path):
    """1000 rad/s over 12 h: 4.3e7 rad, 1.4e7 steps, under the estimate's limit (a long run:
    agreed to with yes=True)."""
    text = edit((SCEN / "molniya-tumbling.toml").read_text(),
                'omega = ["0.02 rad/s", "-0.01 rad/s", "0.05 rad/s"]', 'omega = ["1000 rad/s", "0 rad/s", "0 rad/s"]')
    sc = load_scenario(write(tmp_path, text), yes=True)
    assert np.isclose(np.linalg.norm(sc.state0.omega), 1000.0)


BINARY = {**not_utf8_files(FREE), "hdf5": b"\x89HDF\r\n\x1a\n" + bytes(64), "netcdf3": b"CDF\x01" + bytes(64)}


@pytest.mark.parametrize("kind", sorted(BINARY))
def test_files_that_are_not_utf8_toml_are_refused_naming_the_file(tmp_path, kind):
    p = tmp_path / "bad.toml"
    p.write_bytes(BINARY[kind])
    with pytest.raises(ScenarioError, match=rf"^{p}: (is not a TOML scenario|.*TOML)") as info:
        load_scenario(p)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("kind", ["binary", "latin-1 byte", "png"])
def test_read_aem_refuses_files_that_are_not_text(tmp_path, kind):
    p = tmp_path / "bad.aem"
    p.write_bytes(BINARY[kind])
    with pytest.raises(InputError, match=rf"^{p}: not an AEM: byte 0x[0-9a-f]+ at offset \d+ is not UTF-8"):
        orbatt.read_aem(p)

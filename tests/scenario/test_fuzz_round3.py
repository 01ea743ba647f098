"""Fuzz round 3 (issue 26, items 6 and 7 but the TLE and plot lines): every class of bad input
is refused in one line naming the key, before anything is integrated; the inputs that must
run (a real leap second with IGRF, a TLE past astropy's tables) run."""
from __future__ import annotations

import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt.errors import ScenarioError
from orbatt.scenario import load_scenario, parse
from orbatt.scenario.ranges import RANGES
from orbatt.scenario.reference import markdown
from orbatt.scenario.schema import KEY_DOCS

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
CUBESAT = (SCEN / "cubesat-3u-disturbances.toml").read_text()
WHEELS = (SCEN / "lvlh-hold-wheels.toml").read_text()
LEO = (SCEN / "gg-stabilized-leo.toml").read_text()
HYPERION = (SCEN / "hyperion-chaotic-normalized.toml").read_text()
DISPERSION = (SCEN / "gg-leo-dispersion.toml").read_text()
TLE_GG = (SCEN / "iss-tle-gravity-gradient.toml").read_text()

END_FACET = 'area = "0.01 m2"\nnormal = [0.0, 0.0, 1.0]'   # the +z end of the CubeSat (facet 5)
MSIS = "atmosphere = \"nrlmsis\"\nf107 = 150\nf107a = 150\nap = 4"
EXPONENTIAL = 'atmosphere = "exponential"\ndensity0 = "3e-12 kg/m3"\naltitude0 = "400 km"\nscale_height = "60 km"'
RANDOM = ('omega1 = { distribution = "normal", std = "0.01 deg/s" }\nomega2 = { distribution = "normal", std = "0.01 deg/s" }\n'
          'omega3 = { distribution = "normal", std = "0.01 deg/s" }\nattitude_angle = { distribution = "truncnormal", '
          'mean = "0 deg", std = "2 deg", low = "0 deg", high = "10 deg" }')
INERTIAS = ('inertia1 = { distribution = "normal", std = "0.6 kg m2" }\ninertia2 = { distribution = "normal", std = '
            '"3 kg m2" }\ninertia3 = { distribution = "normal", std = "3 kg m2" }')


def edit(text, *pairs):
    for old, new in zip(pairs[::2], pairs[1::2]):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


def cubesat(*pairs, short=True):
    """The disturbed CubeSat over two minutes (``short``), with ``pairs`` replaced."""
    text = edit(CUBESAT, 't_end = "1 d"', 't_end = "120 s"') if short else CUBESAT
    return edit(text, *pairs)


def grid(values):
    """The dispersion sweep with ``orbit_a`` as its only, grid, parameter over one orbit."""
    return edit(DISPERSION, "samples = 2000\n", "", RANDOM, "", INERTIAS, f"orbit_a = {{ values = [{values}] }}",
                't_end = "300 orbits"', 't_end = "1 orbits"')


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


# (id, scenario text, the key the message must name): refused when the file is read
PARSE_CASES = [
    # catch-all: log units, integers beyond 64 bits
    ("dex area", cubesat(END_FACET, END_FACET.replace('"0.01 m2"', '"0.034 dex(m2)"')), r"\[\[body.facets\]\] 5 area"),
    ("dB area", cubesat(END_FACET, END_FACET.replace('"0.01 m2"', '"1 dB(m2)"')), r"\[\[body.facets\]\] 5 area"),
    ("dex dipole", cubesat('"0.005 A m2"', '"0.005 dex(A m2)"'), r"\[torques\] residual_dipole\[0\]"),
    ("huge integer f107", cubesat("f107 = 150", "f107 = 1" + "0" * 400), r"\[environment\] f107"),
    ("huge integer in a facet", cubesat("drag_coefficient = 2.2\nspecular = 0.0\ndiffuse = 0.2\n\n[[body.facets]]",
                                        "drag_coefficient = " + "9" * 30 + "\nspecular = 0.0\ndiffuse = 0.2\n\n"
                                        "[[body.facets]]"), r"\[\[body.facets\]\] 5 drag_coefficient"),
    ("huge integer rtol", edit(LEO, "rtol = 1e-10", "rtol = " + "1" * 40), r"\[integration\] rtol"),
    # memory and hangs: the output count of normalized units
    ("100,000-value grid", grid(", ".join(f'"{7000 + k * 0.01:.2f} km"' for k in range(100_000))),
     r"\[sweep.parameters.orbit_a\] values"),
    # meaningless magnitudes: the physical range of each key
    ("facet area 3.4e10 m2", cubesat(END_FACET, END_FACET.replace('"0.01 m2"', '"3.4e10 m2"')),
     r"\[\[body.facets\]\] 5 area"),
    ("kd 1e100", edit(WHEELS, 'kd = "8e-2 N m s"', 'kd = "1e100 N m s"'), r"\[control\] kd"),
    ("dipole 5e9 A m2", cubesat('"0.005 A m2"', '"5e9 A m2"'), r"\[torques\] residual_dipole\[0\]"),
    ("density0 3 kg/m3", cubesat(MSIS, EXPONENTIAL.replace('"3e-12 kg/m3"', '"3 kg/m3"')), r"\[environment\] density0"),
    ("wheel 1e9 rpm", edit(WHEELS, 'speed = "2000 rpm"      # momentum bias along the orbit normal (o3)\nmax_torque = '
                                   '"5e-3 N m"\nmax_speed = "6000 rpm"', 'speed = "1e9 rpm"\nmax_torque = "5e-3 N m"'),
     r"\[\[body.wheels\]\] 3 speed"),
    ("drag coefficient 500", cubesat("drag_coefficient = 2.2\nspecular = 0.0\ndiffuse = 0.2\n\n[[body.facets]]",
                                     "drag_coefficient = 500\nspecular = 0.0\ndiffuse = 0.2\n\n[[body.facets]]"),
     r"\[\[body.facets\]\] 5 drag_coefficient"),
    ("angle of 1e6 deg", edit(LEO, 'i = "98.2 deg"', 'i = "1e6 deg"'), r"\[orbit\] i"),
    ("sweep rate spread 1e9 deg/s", edit(DISPERSION, 'omega1 = { distribution = "normal", std = "0.01 deg/s" }',
                                         'omega1 = { distribution = "normal", std = "1e9 deg/s" }'),
     r"\[sweep.parameters.omega1\] std"),
    # accepted before, refused now
    ("IGRF at 2500", cubesat("2025-03-20T00:00:00", "2500-01-01T00:00:00"), r"\[orbit\] epoch"),
    ("invalid leap second", cubesat("2025-03-20T00:00:00", "2017-06-30T23:59:60"), r"\[orbit\] epoch"),
    ("second 61", cubesat("2025-03-20T00:00:00", "2016-12-31T23:59:61"), r"\[orbit\] epoch"),
    ("epoch ZZ", cubesat("2025-03-20T00:00:00", "2025-03-20T00:00:00ZZ"), r"\[orbit\] epoch"),
    ("epoch J2000", cubesat("2025-03-20T00:00:00", "J2000"), r"\[orbit\] epoch"),
    ("grid point below the surface", grid('"7078 km", "3000 km"'), r"\[sweep.parameters.orbit_a\] values\[1\]"),
    ("facets read by no torque", cubesat("[torques]\ndrag = true\nsrp = true", "[torques]\ndrag = false\nsrp = false"),
     r"\[\[body.facets\]\]"),
    # refused under the wrong key or too late before
    ("f107 1000", cubesat("f107 = 150", "f107 = 1000"), r"\[environment\] f107"),
    ("altitude0 400 AU", cubesat(MSIS, EXPONENTIAL.replace('"400 km"', '"400 AU"')), r"\[environment\] altitude0"),
    ("scale_height 60 cm", cubesat(MSIS, EXPONENTIAL.replace('"60 km"', '"60 cm"')), r"\[environment\] scale_height"),
    ("IGRF epoch 2040", cubesat("2025-03-20T00:00:00", "2040-01-01T00:00:00"), r"\[orbit\] epoch"),
    ("IGRF epoch 1850", cubesat("2025-03-20T00:00:00", "1850-01-01T00:00:00"), r"\[orbit\] epoch"),
]


@pytest.mark.parametrize("text,key", [c[1:] for c in PARSE_CASES], ids=[c[0] for c in PARSE_CASES])
def test_bad_values_are_refused_naming_the_key(text, key):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ERFA "dubious year" lines before the refusal
        with pytest.raises(ScenarioError, match=rf"^s.toml: {key}: ") as info:
            parse(text, "s.toml")
    assert "\n" not in str(info.value)
    assert time.perf_counter() - t0 < 10.0


# (id, scenario text, the key the message must name): refused before the run by the work estimate
LOAD_CASES = [
    ("normalized output_step 1e-7", edit(HYPERION, "output_step = 0.0738099820962889", "output_step = 1e-7"),
     r"\[integration\] output_step"),
    ("normalized t_end 1e6", edit(HYPERION, 't_end = "50 orbits"', "t_end = 1e6"), r"\[integration\] output_step"),
    ("kp = kd = 1e6 without max_torque", edit(WHEELS, 'kp = "4e-3 N m"', 'kp = "1e6 N m"', 'kd = "8e-2 N m s"',
                                              'kd = "1e6 N m s"', 'max_torque = "4e-3 N m"\nactuator = "wheels"',
                                              'actuator = "ideal"'), r"\[control\] kd"),
    ("1e-14 kg m2 with torques", cubesat('inertia = ["0.0387 kg m2", "0.0387 kg m2", "0.0067 kg m2"]',
                                         'inertia = ["1e-14 kg m2", "1e-14 kg m2", "1e-14 kg m2"]', short=False),
     r"\[body\] inertia"),
    ("a fixed step of 1 us", edit(LEO, 'method = "dop853"', 'method = "splitting4"\nstep = "1e-6 s"'),
     r"\[integration\] step"),
    ("IGRF past 2030", cubesat("2025-03-20T00:00:00", "2029-12-31T00:00:00", 't_end = "120 s"', 't_end = "2 d"'),
     r"\[integration\] t_end"),
]


@pytest.mark.parametrize("text,key", [c[1:] for c in LOAD_CASES], ids=[c[0] for c in LOAD_CASES])
def test_runs_that_cannot_end_are_refused_naming_the_key(tmp_path, text, key):
    p = write(tmp_path, text)
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError, match=rf"s.toml: {key}: ") as info:
        load_scenario(p)
    assert "\n" not in str(info.value)
    assert time.perf_counter() - t0 < 30.0


def test_a_sweep_of_ten_million_cases_is_refused_before_drawing(tmp_path):
    from orbatt.sweep import load_sweep

    p = write(tmp_path, edit(DISPERSION, "samples = 2000", "samples = 10000000"))
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError, match=r"s.toml: \[sweep\] samples: 10000000 cases"):
        load_sweep(p)
    assert time.perf_counter() - t0 < 30.0


def test_a_random_orbit_inside_the_earth_is_refused_or_redrawn(tmp_path):
    from orbatt.errors import InputError
    from orbatt.sweep import load_sweep

    text = edit(DISPERSION, RANDOM, 'orbit_a = { distribution = "normal", std = "3000 km" }', INERTIAS, "",
                "samples = 2000", "samples = 200", 'on_invalid = "resample"\n', "")
    with pytest.raises(InputError, match=r"\[sweep.parameters\] orbit_a: case \d+ drew a = .* inside the Earth"):
        load_sweep(write(tmp_path, text))
    sweep = load_sweep(write(tmp_path, edit(text, "samples = 200", 'samples = 200\non_invalid = "resample"'), "r.toml"))
    assert sweep.resampled > 0 and np.all(sweep.values["orbit_a"] > 6378.1)


def test_a_leap_second_runs_with_igrf_and_the_field_is_continuous_across_it(tmp_path):
    from orbatt.environment.magnetic import DipoleField, IGRFField

    field = IGRFField()
    r = np.array([[6778.137, 0.0, 0.0], [0.0, 4000.0, 5000.0]])
    at = {s: field.field_itrs(Time([s] * 2, scale="utc"), r)
          for s in ("2016-12-31T23:59:59.999", "2016-12-31T23:59:60", "2016-12-31T23:59:60.5")}
    b0, b1 = at["2016-12-31T23:59:59.999"], at["2016-12-31T23:59:60"]
    assert np.all(np.abs(b1 - b0) <= 1e-9 * np.linalg.norm(b0, axis=1)[:, None])
    assert np.all(np.isfinite(at["2016-12-31T23:59:60.5"]))
    assert np.all(np.isfinite(DipoleField("2016-12-31T23:59:60").moment_itrs))
    # the scenario's environment tables (IGRF and NRLMSIS) are sampled across the leap second
    sc = load_scenario(write(tmp_path, cubesat("2025-03-20T00:00:00", "2016-12-31T23:59:60")))
    sc.potential.kernel_model()
    assert sc.orbit.epoch.isot == "2016-12-31T23:59:60.000"


def test_a_tle_past_the_bundled_tables_runs_with_one_dates_warning(tmp_path):
    text = edit(TLE_GG, "19343.69339541  .00001764  00000-0  38792-4 0  9991",
                "49343.69339541  .00001764  00000-0  38792-4 0  9994", 'epoch = "2019-12-09T17:38:29"', "")
    text = text.replace(text[text.index("t_end = "):text.index("\n", text.index("t_end = "))], 't_end = "300 s"')
    text = text.replace(text[text.index("output_step = "):text.index("\n", text.index("output_step = "))],
                        'output_step = "60 s"')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = load_scenario(write(tmp_path, text)).run()
    assert ds.sizes["time"] == 6
    assert ds.attrs["epoch"].startswith("2049-12-09")
    erfa = [w for w in caught if "ERFA" in str(w.message) and "astropy said" not in str(w.message)]
    assert not erfa, [str(w.message) for w in erfa]


def cli(*args):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=120)


@pytest.mark.parametrize("option", ["-o", "--aem"])
def test_an_empty_output_path_is_refused(tmp_path, option):
    r = cli("run", SCEN / "paper-torque-free.toml", option, "", "--quiet")
    assert r.returncode == 2
    errors = [line for line in r.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and f"{option}: '' is an empty path" in errors[0]
    assert not list(tmp_path.iterdir())


def test_every_range_is_of_a_documented_key_and_shown_in_the_reference():
    for table, key in RANGES:
        assert key in KEY_DOCS[table], (table, key)
    text = markdown()
    assert "| `area` | area | [1e-08, 10000] m2 |" in text
    assert "Angles always carry an angle unit" in text and "plain numbers (radians)" not in text


def test_dimension_wording():
    bad = [(edit(WHEELS, 'kp = "4e-3 N m"', 'kp = "4e-3 m"'), "expected a torque such as", "[control] kp"),
           (edit(LEO, 'omega = ["0 rad/s", "0 rad/s", "0 rad/s"]', 'omega = ["1 m", "0 rad/s", "0 rad/s"]'),
            "expected an angular frequency such as", "[initial] omega[0]")]
    bdot = (SCEN / "cubesat-bdot-detumble.toml").read_text()
    bad.append((edit(bdot, 'gain = "4e4 A m2 s / T"', 'gain = "4e4 A m2"'), "expected a quantity in m2 A s / T such as",
                "[control] gain"))
    for text, fragment, key in bad:
        with pytest.raises(ScenarioError) as info:
            parse(text, "s.toml")
        assert key in str(info.value) and fragment in str(info.value), str(info.value)
        assert "a unknown" not in str(info.value) and "a angular" not in str(info.value)


def test_rpm_is_the_unit_of_scenario_files_in_python_too():
    assert (2000 * orbatt.rpm).to_value(u.rad / u.s) == pytest.approx(2000 * 2 * np.pi / 60)
    assert u.Quantity("2000 rpm") == 2000 * orbatt.rpm
    wheel = orbatt.ReactionWheel([0.0, 0.0, 1.0], "4e-4 kg m2", 2000 * orbatt.rpm)
    assert wheel.speed_rad_s == pytest.approx(209.43951023931953)


def test_orbatt_scenarios_indents_wrapped_descriptions():
    r = subprocess.run([sys.executable, "-m", "orbatt.cli", "scenarios"], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "COLUMNS": "100"})
    assert r.returncode == 0
    names = {name for name, _, _ in orbatt.scenario.shipped_scenarios()}
    lines = r.stdout.splitlines()
    width = max(map(len, names)) + 2
    assert len(lines) > len(names)  # some descriptions wrap
    for line in lines:
        assert line.split(" ", 1)[0] in names or line.startswith(" " * width), line
        assert len(line) <= 100

"""Sweep parameters addressed by their scenario path (issue 23 item 2): any numeric leaf
varies in its key's unit; each case is the single run of its own scenario (the file with the
leaves replaced, :meth:`orbatt.sweep.Sweep.case_text`), bit for bit; coordinates named for
the path; bad paths and invalid cases named."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from orbatt.errors import InputError
from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.scenario.paths import coordinate_name, resolve, substitute, toml_text
from orbatt.sweep import Sweep

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")


def _short(name, t_end='"300 s"'):
    return re.sub(r"^t_end = .*$", f"t_end = {t_end}", (SCEN / f"{name}.toml").read_text(), flags=re.M)


def _sweep(text, table):
    return Sweep(Scenario(parse(text + "\n[sweep]\n" + table, "paths.toml")), seed=7)


def _each_case_is_its_single_run(sw, ds):
    for k in range(sw.cases):
        one = Scenario(parse(sw.case_text(k), "case.toml")).run()
        assert np.array_equal(ds["q_final"].values[k], one["q"].values[-1]), k
        assert np.array_equal(ds["Q_final"].values[k], one["Q"].values[-1]), k


@pytest.mark.parametrize("name", [p.stem for p in sorted(SCEN.glob("*.toml"))])
def test_scenario_data_round_trips_through_toml_text(name):
    data = tomllib.loads((SCEN / f"{name}.toml").read_text())
    assert tomllib.loads(toml_text(data)) == data


def test_paths_resolve_and_substitute():
    data = {"body": {"inertia": ["1 kg m2", "2 kg m2", "3 kg m2"], "facets": [{"area": "1 m2"}, {"area": "2 m2"}]}}
    assert resolve(data, "body.facets[1].area") == "2 m2"
    new = substitute(data, {"body.inertia[2]": "4 kg m2", "body.facets[0].area": 0.5})
    assert new["body"]["inertia"][2] == "4 kg m2" and new["body"]["facets"][0]["area"] == 0.5
    assert data["body"]["inertia"][2] == "3 kg m2"  # the nominal data untouched
    with pytest.raises(LookupError, match=r"\[9\] is past its end"):
        resolve(data, "body.facets[9].area")
    assert coordinate_name("body.facets[0].drag_coefficient") == "body_facets_0_drag_coefficient"
    assert coordinate_name("control.gain") == "control_gain"


def test_bdot_gain_rate_and_inertia_by_path():
    table = ('samples = 3\noutputs = ["final_state", "detumble_time"]\ndetumble_rate = "2 deg/s"\n'
             '[sweep.parameters]\n'
             '"initial.omega[0]" = { distribution = "uniform", low = "-0.08 rad/s", high = "0.08 rad/s" }\n'
             '"control.gain" = { distribution = "normal", std = "5e3 A m2 s / T" }\n'
             '"body.inertia[2]" = { distribution = "uniform", low = "0.006 kg m2", high = "0.008 kg m2" }\n')
    sw = _sweep(_short("cubesat-bdot-detumble", '"600 s"'), table)
    ds = sw.compute()
    _each_case_is_its_single_run(sw, ds)
    c = ds["control_gain"]
    assert c.attrs["scenario_key"] == "control.gain" and c.attrs["units"] == "m^2 A s T^-1"
    assert "control.gain" in c.attrs["long_name"]
    assert np.all(np.abs(c.values - 4e4) < 5e4)  # the nominal gain is the mean
    assert ds["initial_omega_0"].attrs["units"] == "degree s^-1"  # the key's unit (deg/s), in the CF spelling
    assert np.all(np.abs(ds["initial_omega_0"].values) <= np.degrees(0.08))


def test_facet_coefficient_and_wheel_speed_by_path():
    sw = _sweep(_short("cubesat-3u-disturbances"),
                '[sweep.parameters]\n"body.facets[0].drag_coefficient" = { values = [1.8, 2.6] }\n')
    ds = sw.compute()
    _each_case_is_its_single_run(sw, ds)
    assert not np.array_equal(ds["q_final"].values[0], ds["q_final"].values[1])
    assert ds["body_facets_0_drag_coefficient"].attrs["units"] == "1"
    sw = _sweep(_short("lvlh-hold-wheels"), '[sweep.parameters]\n"body.wheels[2].speed" = { values = ["0 rpm", '
                                            '"2000 rpm"] }\n"initial.omega[1]" = { values = ["-0.3 deg/s", "0.1 deg/s"] }\n')
    ds = sw.compute()
    assert ds.sizes["case"] == 4
    _each_case_is_its_single_run(sw, ds)


@pytest.mark.parametrize("base, key, match", [
    ("cubesat-3u-disturbances", '"body.facets[9].area"', r'body\.facets\[9\].*past its end'),
    ("cubesat-bdot-detumble", '"body.facets[0].area"', r'body\.facets is not in the scenario'),
    ("cubesat-bdot-detumble", '"control.law"', r'control\.law.*only numeric keys'),
    ("cubesat-bdot-detumble", '"orbit.epoch"', r'orbit\.epoch.*epoch'),
    ("cubesat-bdot-detumble", '"integration.rtol"', r'integration\.rtol.*shared by all cases'),
    ("cubesat-bdot-detumble", '"body.nothing"', r'body\.nothing is not in the scenario'),
    ("cubesat-bdot-detumble", '"initial.omega"', r'holds a list'),
    ("cubesat-bdot-detumble", 'nonsense', r'unknown parameter'),
])
def test_bad_paths_are_named(base, key, match):
    text = _short(base) + f'\n[sweep]\n[sweep.parameters]\n{key} = {{ values = [1.0] }}\n'
    with pytest.raises(ScenarioError, match=match):
        parse(text, "bad.toml")


def test_a_case_that_makes_the_scenario_invalid_is_named_or_resampled():
    base = _short("cubesat-3u-disturbances")
    table = ('samples = 40\n[sweep.parameters]\n'
             '"body.facets[0].drag_coefficient" = { distribution = "normal", mean = 0.1, std = 0.3 }\n')
    with pytest.raises(InputError, match=r"body\.facets\[0\]\.drag_coefficient = -.*drag_coefficient"):
        _sweep(base, table)
    sw = Sweep(Scenario(parse(base + "\n[sweep]\n" + table.replace("samples = 40", "samples = 40\non_invalid = "
                                                                   '"resample"'), "r.toml")), seed=7)
    v = sw.values["body.facets[0].drag_coefficient"]
    assert sw.resampled > 0 and np.all(v >= 0)


def test_a_key_that_takes_its_default_varies_about_the_default():
    """A path naming a key the scenario does not write (issue 34 item 2): its nominal value is
    the default, and every case is the single run of the scenario that writes it."""
    base = re.sub(r"^drag_coefficient = .*\n", "", _short("cubesat-3u-disturbances"), flags=re.M)
    assert "drag_coefficient" not in base
    sw = _sweep(base, 'samples = 2\n[sweep.parameters]\n"body.facets[0].drag_coefficient" = '
                      '{ distribution = "normal", std = 0.1 }\n')
    ds = sw.compute()
    _each_case_is_its_single_run(sw, ds)
    c = ds["body_facets_0_drag_coefficient"]
    assert c.attrs["units"] == "1" and np.all(np.abs(c.values - 2.2) < 1.0)  # the default 2.2 is the mean
    sw = _sweep(base, '[sweep.parameters]\n"body.facets[0].drag_coefficient" = { values = [2.2, 2.6] }\n')
    ds = sw.compute()
    nominal = Scenario(parse(base, "nominal.toml")).run()  # the default written nowhere
    assert np.array_equal(ds["q_final"].values[0], nominal["q"].values[-1])
    assert not np.array_equal(ds["q_final"].values[1], nominal["q"].values[-1])
    # a wheel's speed (default 0) with a unit
    wheels = _short("lvlh-hold-wheels").replace('speed = "0 rpm"\n', "", 1)
    sw = _sweep(wheels, '[sweep.parameters]\n"body.wheels[0].speed" = { values = ["0 rpm", "100 rpm"] }\n')
    ds = sw.compute()
    _each_case_is_its_single_run(sw, ds)
    assert sw.nominal["body.wheels[0].speed"] == 0.0
    np.testing.assert_allclose(ds["body_wheels_0_speed"].values, [0.0, 100 * 2 * np.pi / 60], rtol=1e-12)
    # a key the table cannot have, or a table the scenario lacks, is still refused
    for key, match in (('"body.facets[0].nothing"', r"body\.facets\[0\]\.nothing is not in the scenario"),
                       ('"body.facets[9].drag_coefficient"', r"past its end")):
        with pytest.raises(ScenarioError, match=match):
            parse(base + f"\n[sweep]\n[sweep.parameters]\n{key} = {{ values = [1.0] }}\n", "bad.toml")
    with pytest.raises(ScenarioError, match=r"body\.facets is not in the scenario"):
        parse(_short("cubesat-bdot-detumble") + '\n[sweep]\n[sweep.parameters]\n"body.facets[0].drag_coefficient" = '
                                                '{ values = [1.0] }\n', "bad.toml")


def test_default_leaves_are_the_documented_defaults():
    from orbatt.scenario.paths import leaf_quantity
    from orbatt.scenario.schema import KEY_DOCS
    from orbatt.scenario.sweep_schema import DEFAULT_LEAVES

    numeric = {}
    for table, keys in KEY_DOCS.items():
        for key, (_, default, _) in keys.items():
            try:
                numeric[table, key] = float(default)
            except ValueError:
                pass
    assert {k: leaf_quantity(v)[0] for k, v in DEFAULT_LEAVES.items()} == numeric

"""Scenario files: every shipped scenario validates; malformed ones are refused with the field."""
from pathlib import Path

import numpy as np
import pytest

from orbatt.scenario import ScenarioError, parse

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
GOOD = (SCEN / "paper-keplerian.toml").read_text()


@pytest.mark.parametrize("path", sorted(SCEN.glob("*.toml")), ids=lambda p: p.stem)
def test_shipped_scenarios_validate(path):
    spec = parse(path.read_text(), str(path))
    assert spec.name == path.stem
    assert spec.description


def test_paper_keplerian_values():
    spec = parse(GOOD)
    assert np.allclose(spec.inertia, [400, 500, 600])
    assert spec.orbit["a"] == 7000.0 and spec.orbit["e"] == 0.2
    assert np.isclose(spec.orbit["i"], np.pi / 6) and np.isclose(spec.orbit["argp"], np.pi / 12)
    assert spec.integration["t_end"] == ("orbits", 2.0)
    assert spec.integration["output_step"] == ("time", 10.0)


def edit(text, old, new):
    assert text.count(old) == 1, old
    return text.replace(old, new)


BAD = [
    ("missing table", lambda t: edit(t, "[potential]\nkind = \"gravity-gradient\"\n", ""), r"\[potential\].*missing"),
    ("unknown key", lambda t: edit(t, "\ne = 0.2\n", "\ne = 0.2\necc = 0.3\n"), r"\[orbit\] ecc: unknown key"),
    ("unknown table", lambda t: t + "\n[outputs]\nx = 1\n", r"outputs: unknown table"),
    ("a in degrees", lambda t: edit(t, 'a = "7000 km"', 'a = "30 deg"'), r"\[orbit\] a: '30 deg' has the wrong dimension"),
    ("non-unit q", lambda t: edit(t, "q = [0.5, -0.7071067811865476, 0.0, 0.5]", "q = [0.5, -0.7, 0.0, 0.5]"),
     r"\[initial\] q: .*\|q\| = "),
    ("negative inertia", lambda t: edit(t, '"400 kg km2"', '"-400 kg km2"'), r"\[body\] inertia.*positive"),
    ("triangle", lambda t: edit(t, '"600 kg km2"', '"1600 kg km2"'), r"\[body\] inertia.*triangle"),
    ("t_end <= 0", lambda t: edit(t, 't_end = "2 orbits"', 't_end = "-5 s"'), r"\[integration\] t_end.*positive"),
    ("hyperbolic", lambda t: edit(t, "\ne = 0.2\n", "\ne = 1.2\n"), r"\[orbit\] e: 1.2 is outside"),
    ("unit-less a", lambda t: edit(t, 'a = "7000 km"', "a = 7000"), r"\[orbit\] a: 7000 has no unit"),
    ("bad method", lambda t: edit(t, 'method = "dop853"', 'method = "euler"'), r"\[integration\] method: 'euler'"),
    ("bad kind", lambda t: edit(t, 'kind = "gravity-gradient"', 'kind = "magnetic"'), r"\[potential\] kind: 'magnetic'"),
    ("two anomalies", lambda t: edit(t, 'true_anomaly = "0 deg"', 'true_anomaly = "0 deg"\nmean_anomaly = "0 deg"'),
     r"exactly one of"),
    ("initial combo", lambda t: edit(t, "Q = [0.3, -0.848528, 0.141421, -1.5]", 'omega = ["1 rad/s", "0 rad/s", "0 rad/s"]\nQ = [0, 0, 0, 0]'),
     r"\[initial\]: got keys"),
    ("bad toml", lambda t: t + "\n[[[", r"TOML"),
    ("rebound key on kepler", lambda t: edit(t, 'provider = "kepler"', 'provider = "kepler"\nperturbations = ["j2"]'),
     r"\[orbit\] perturbations: only used by provider = 'rebound'"),
    ("orbits without orbit", lambda t: edit(edit(t, 'kind = "gravity-gradient"', 'kind = "torque-free"'),
                                           t[t.index("[orbit]"):t.index("[integration]")], ""),
     r"t_end: '2 orbits' needs an \[orbit\]"),
]


@pytest.mark.parametrize("name,mutate,pattern", BAD, ids=[b[0] for b in BAD])
def test_malformed_scenarios_are_refused(name, mutate, pattern):
    with pytest.raises(ScenarioError, match=pattern):
        parse(mutate(GOOD), "x.toml")


def test_unknown_perturbation_named():
    t = (SCEN / "sso-j2-rebound.toml").read_text()
    with pytest.raises(ScenarioError, match=r"perturbations: 'j3'"):
        parse(t.replace('["j2"]', '["j3"]'))


def test_dimensionless_scenario_refuses_units_on_omega():
    t = (SCEN / "paper-torque-free.toml").read_text()
    t = t.replace("Q = [0.3, -0.848528, 0.141421, -1.5]", 'omega = ["1 rad/s", 0, 0]')
    with pytest.raises(ScenarioError, match=r"omega\[0\].*has a unit but \[body\] inertia is plain"):
        parse(t)


def test_quantity_strings_parsed_again_give_the_same_values_and_errors():
    """Parsed quantity strings are remembered (issue 15): a second parse gives the same
    values, a per-key range still applies, and a bad string is refused every time."""
    from astropy import units as u

    from orbatt.scenario.fields import FieldContext, parse_quantity

    ctx = FieldContext("f.toml")
    first = parse_quantity(ctx, "[orbit] a", "7000 km", u.km, dimensionless=False)
    again = parse_quantity(ctx, "[orbit] a", "7000 km", u.km, dimensionless=False)
    assert first == again == 7000.0
    assert parse_quantity(ctx, "[orbit] i", "30 deg", u.rad, dimensionless=False) == (30 * u.deg).to_value(u.rad)
    with pytest.raises(ScenarioError, match="outside the range"):
        parse_quantity(ctx, "[orbit] a", "7000 km", u.km, dimensionless=False, bounds=(7100.0, None))
    for _ in range(2):
        with pytest.raises(ScenarioError, match=r"f\.toml: \[orbit\] a: '7000 s' has the wrong dimension"):
            parse_quantity(ctx, "[orbit] a", "7000 s", u.km, dimensionless=False)


def test_load_scenario_by_name_and_a_missing_path(tmp_path):
    """A shipped scenario by its name (any letter case, with or without ``.toml``); a path that
    does not exist is refused, even when its last part is a shipped name (it is never taken for
    the shipped file)."""
    import orbatt

    for name in ("paper-keplerian", "paper-keplerian.toml", "Paper-Keplerian"):
        sc = orbatt.load_scenario(name)
        assert sc.name == "paper-keplerian" and sc.text == GOOD
    with pytest.raises(ScenarioError, match=r"no-such-folder/paper-keplerian.toml: no such scenario file; give a path "
                                            r"to a TOML file or one of: .*paper-keplerian"):
        orbatt.load_scenario(tmp_path / "no-such-folder" / "paper-keplerian.toml")

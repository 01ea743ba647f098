"""The scenario tables of the environment torques: [[body.facets]], [torques], [environment]
(issue 11): the shipped CubeSat runs and records every torque; bad input is refused in one
line naming the key."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from orbatt.errors import ScenarioError
from orbatt.scenario import load_scenario, parse

SCEN = Path(__file__).resolve().parents[2] / "scenarios" / "cubesat-3u-disturbances.toml"
TEXT = SCEN.read_text()


def _short(text, t_end='"900 s"'):
    return re.sub(r'(?m)^t_end = .*$', f"t_end = {t_end}", text)


def test_shipped_cubesat_records_every_torque(tmp_path):
    p = tmp_path / "cubesat.toml"
    p.write_text(_short(TEXT))
    ds = load_scenario(p).run()
    names = ["gravity_gradient", "drag", "srp", "magnetic"]
    total = ds[f"torque_{names[0]}"].values.copy()
    for n in names[1:]:
        total += ds[f"torque_{n}"].values
    np.testing.assert_array_equal(ds.torque.values, total)
    for n in names:
        assert ds[f"torque_{n}"].attrs["units"] == "N m"
        assert np.all(np.isfinite(ds[f"torque_{n}"].values)) and np.abs(ds[f"torque_{n}"].values).max() > 0
    # orders of magnitude of a 3U CubeSat at 400 km (N m)
    assert 1e-9 < np.abs(ds.torque_drag).max() < 1e-6
    assert 1e-10 < np.abs(ds.torque_srp).max() < 1e-7
    assert 1e-9 < np.abs(ds.torque_magnetic).max() < 1e-6
    assert 1e-13 < float(ds.density.min()) and float(ds.density.max()) < 1e-10
    np.testing.assert_allclose(np.linalg.norm(ds.sun_direction.values, axis=1), 1.0, rtol=1e-12)
    assert 1e-5 < np.linalg.norm(ds.magnetic_field.values, axis=1).min() < 7e-5
    assert set(np.unique(ds.shadow.values)) <= {0.0, 1.0} or (0 <= ds.shadow.values).all()


BAD = [
    ("normal = [1.0, 0.0, 0.0]", "normal = [1.0, 0.1, 0.0]", "[[body.facets]] 1"),
    ('area = "0.034 m2"', 'area = "-0.034 m2"', "[[body.facets]] 1"),
    ('area = "0.034 m2"', 'area = "0 m2"', "[[body.facets]] 1"),
    ("specular = 0.1", "specular = 1.5", "[[body.facets]] 1 specular"),
    ("diffuse = 0.3", "diffuse = 0.95", "[[body.facets]] 1"),
    ('epoch = "2025-03-20T00:00:00"', "", "[orbit] epoch"),
    ("f107 = 150\n", "", "[environment] f107"),
    ("drag = true", "drag = 1", "[torques] drag"),
    ('atmosphere = "nrlmsis"', 'atmosphere = "jacchia"', "[environment] atmosphere"),
    ('shadow = "conical"', 'shadow = "soft"', "[environment] shadow"),
    ('magnetic_field = "igrf"', 'magnetic_field = "none"', "[environment] magnetic_field"),
    ('residual_dipole = ["0.005 A m2", "0 A m2", "0.002 A m2"]', 'residual_dipole = ["0.005 A", "0 A m2", "0 A m2"]',
     "[torques] residual_dipole[0]"),
]


@pytest.mark.parametrize("old,new,key", BAD)
def test_bad_torque_input_names_the_key(old, new, key):
    assert old in TEXT
    with pytest.raises(ScenarioError) as err:
        parse(TEXT.replace(old, new, 1), "s.toml")
    msg = str(err.value)
    assert key in msg and "\n" not in msg


def test_torques_need_a_potential_with_an_orbit():
    no_orbit = re.sub(r"(?s)\n\[orbit\].*?(?=\n\[integration\])", "", TEXT).replace(
        'kind = "gravity-gradient"', 'kind = "torque-free"').replace('frame = "orbital"', 'frame = "inertial"')
    assert "[orbit]" not in no_orbit
    with pytest.raises(ScenarioError, match=r"\[torques\]: the torques need an orbit"):
        parse(no_orbit, "s.toml")


def test_drag_or_srp_without_facets_is_refused():
    no_facets = re.sub(r"(?s)\[\[body\.facets\]\].*?(?=\n\[\[body\.facets\]\]|\n\[torques\])", "", TEXT)
    assert "[[body.facets]]" not in no_facets
    with pytest.raises(ScenarioError, match=r"\[torques\] drag.*facets"):
        parse(no_facets, "s.toml")


def test_space_weather_only_for_nrlmsis_and_exponential_keys_together():
    exp = TEXT.replace('atmosphere = "nrlmsis"', 'atmosphere = "exponential"')
    with pytest.raises(ScenarioError, match=r"\[environment\] f107.*nrlmsis"):
        parse(exp, "s.toml")
    exp = exp.replace("f107 = 150\nf107a = 150\nap = 4\n", 'density0 = "3e-12 kg/m3"\n')
    with pytest.raises(ScenarioError, match=r"\[environment\] altitude0"):
        parse(exp, "s.toml")
    spec = parse(exp.replace('density0 = "3e-12 kg/m3"\n', 'density0 = "3e-12 kg/m3"\naltitude0 = "400 km"\n'
                                                            'scale_height = "60 km"\n'), "s.toml")
    assert spec.torques["environment"]["density0"] == pytest.approx(3e-12)

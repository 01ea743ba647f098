"""Sweeps of every kind of scenario ``orbatt run`` accepts (issues 22 and 23): reaction wheels
with a PD law, B-dot control in IGRF, environment torques on facets, a TLE orbit. The case's
model is assembled by the single run's builders, so **every case equals the single run of
that case's scenario, bit for bit** (the scenario file with the swept keys replaced)."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.sweep import Sweep, run_sweep

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")

#: name: (t_end, the [initial] omega line, the [body] inertia line)
CASES = {
    "lvlh-hold-wheels": ('"600 s"', 'omega = ["0.5 deg/s", "-0.3 deg/s", "0.2 deg/s"]',
                         'inertia = ["1.8 kg m2", "2.2 kg m2", "1.2 kg m2"]'),
    "cubesat-bdot-detumble": ('"600 s"', 'omega = ["4 deg/s", "-3 deg/s", "3 deg/s"]',
                              'inertia = ["0.0387 kg m2", "0.0387 kg m2", "0.0067 kg m2"]'),
    "cubesat-3u-disturbances": ('"900 s"', 'omega = ["0 deg/s", "0 deg/s", "0 deg/s"]',
                                'inertia = ["0.0387 kg m2", "0.0387 kg m2", "0.0067 kg m2"]'),
    "iss-tle-gravity-gradient": ('"900 s"', 'omega = ["0 rad/s", "0 rad/s", "0 rad/s"]',
                                 'inertia = ["2.5e7 kg m2", "1.0e8 kg m2", "1.15e8 kg m2"]'),
}
OMEGA1 = ("-0.7 deg/s", "0.2 deg/s")  # ascending, as INERTIA2
INERTIA2 = {"lvlh-hold-wheels": ("2.0 kg m2", "2.4 kg m2"), "cubesat-bdot-detumble": ("0.036 kg m2", "0.04 kg m2"),
            "cubesat-3u-disturbances": ("0.036 kg m2", "0.04 kg m2"), "iss-tle-gravity-gradient": ("9e7 kg m2", "1.1e8 kg m2")}


def _base(name):
    t_end, omega, inertia = CASES[name]
    text = (SCEN / f"{name}.toml").read_text()
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    assert omega in text and text.count(inertia) == 1
    return text


def _case_text(name, text, w1, i2):
    """The scenario file of one case: the swept keys replaced."""
    _, omega, inertia = CASES[name]
    w = re.findall(r'"([^"]+)"', omega)
    ii = re.findall(r'"([^"]+)"', inertia)
    text = text.replace(omega, f'omega = ["{w1}", "{w[1]}", "{w[2]}"]')
    return text.replace(inertia, f'inertia = ["{ii[0]}", "{i2}", "{ii[2]}"]')


@pytest.mark.parametrize("name", list(CASES))
def test_every_case_is_the_single_run_of_its_scenario(name):
    _check_every_case(name, _base(name))


@pytest.mark.parametrize("name,period", [("lvlh-hold-wheels", "0.5 s"), ("cubesat-bdot-detumble", "1 s")])
def test_every_case_with_a_flight_software_is_its_single_run(name, period):
    """A law with a period (issue 32): each case, ticks and held commands included, is the
    single run of its scenario bit for bit, in any chunking."""
    text = _base(name).replace("[control]\n", f'[control]\nperiod = "{period}"\n', 1)
    assert "period" in text
    _check_every_case(name, text)


def _check_every_case(name, text):
    i2 = INERTIA2[name]
    table = (f'\n[sweep]\noutputs = ["final_state", "max_pointing_error"]\n[sweep.parameters]\n'
             f'omega1 = {{ values = ["{OMEGA1[0]}", "{OMEGA1[1]}"] }}\n'
             f'inertia2 = {{ values = ["{i2[0]}", "{i2[1]}"] }}\n')
    sw = Sweep(Scenario(parse(text + table, f"{name}-sweep.toml")), seed=1)
    ds = sw.compute()
    assert ds.sizes["case"] == 4 and not ds["integration_failed"].any()
    finals = []
    for k in range(4):
        w1 = OMEGA1[0] if ds["omega1"].values[k] == sw.values["omega1"].min() else OMEGA1[1]  # grid values
        inertia2 = i2[0] if ds["inertia2"].values[k] == ds["inertia2"].values.min() else i2[1]  # (kg m^2 there)
        sc = Scenario(parse(_case_text(name, text, w1, inertia2), f"{name}-case.toml"))
        ref = sc.run()
        assert np.array_equal(ds["q_final"].values[k], ref["q"].values[-1]), (name, k)
        assert np.array_equal(ds["Q_final"].values[k], ref["Q"].values[-1]), (name, k)
        finals.append(ds["q_final"].values[k])
    assert len({f.tobytes() for f in finals}) == 4  # the parameters act
    # chunking changes no bit
    again = run_sweep(sw, scheduler="synchronous", chunk_size=1)
    assert np.array_equal(again["q_final"].values, ds["q_final"].values)


def test_a_tle_orbit_is_shared_its_elements_do_not_vary():
    text = _base("iss-tle-gravity-gradient") + '\n[sweep]\n[sweep.parameters]\norbit_a = { values = ["6800 km"] }\n'
    with pytest.raises(ScenarioError, match=r"orbit_a.*TLE"):
        parse(text, "tle.toml")


def test_no_energy_error_without_a_conserved_energy():
    text = _base("cubesat-bdot-detumble") + ('\n[sweep]\noutputs = ["final_energy_error"]\n[sweep.parameters]\n'
                                             'omega1 = { values = ["0.1 deg/s"] }\n')
    with pytest.raises(ScenarioError, match=r"\[sweep\] outputs.*conserved energy"):
        parse(text, "bdot.toml")


def test_trajectories_of_a_wheeled_sweep_keep_the_wheels():
    text = _base("lvlh-hold-wheels") + ('\n[sweep]\noutputs = ["trajectory"]\n[sweep.parameters]\n'
                                        'omega1 = { values = ["0.1 deg/s", "0.3 deg/s"] }\n')
    sw = Sweep(Scenario(parse(text, "w.toml")), seed=1)
    ds = sw.compute()
    assert "wheel_momentum" in ds or "wheel_speed" in ds
    ref = sw.scenario.run()
    name = "wheel_momentum" if "wheel_momentum" in ds else "wheel_speed"
    assert ds[name].dims[0] == "case" and ds[name].shape[1:] == ref[name].shape

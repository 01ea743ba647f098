"""Every sweep output alone and every pair of outputs (issue 34 item 2): each subset runs, on
a scenario that has what its outputs read, writes exactly the variables of the outputs asked
(none of those computed alongside, such as the wheels' saturation with their speeds) and the
same values as the run that asks for every output. Short runs, two cases each.

The scenarios: a PD law with reaction wheels (``lvlh-hold-wheels``), B-dot control
(``cubesat-bdot-detumble``, for ``max_dipole``) and the torque-free body (``paper-torque-free``,
for ``final_energy_error``); a pair no scenario can have (the conserved energy with a control
law, the dipole with wheels) is refused by the schema and not listed."""
from __future__ import annotations

import functools
import itertools
import re
from pathlib import Path

import numpy as np
import pytest

from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.scenario.sweep_schema import OUTPUTS
from orbatt.sweep import Sweep
from orbatt.sweep_outputs import OUTPUTS as SWEEP_OUTPUTS

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")


def _short(name, t_end):
    return re.sub(r"^t_end = .*$", f"t_end = {t_end}", (SCEN / f"{name}.toml").read_text(), flags=re.M)


def _modes(t_end):
    """B-dot detumbling, left at a tick once |omega| has stayed below 7 deg/s for 10 s, then the
    orbital frame held by the PD law (a mode sequence)."""
    modes = ('[control]\nperiod = "1 s"\n\n[[control.modes]]\nname = "detumble"\nlaw = "bdot"\n'
             'gain = "4e4 A m2 s / T"\nmax_dipole = "0.2 A m2"\nuntil_rate = "7 deg/s"\nhold = "10 s"\n\n'
             '[[control.modes]]\nname = "nadir"\nlaw = "pd"\ntarget = "orbital"\nkp = "2e-5 N m"\n'
             'kd = "5e-4 N m s"\nmax_torque = "1e-4 N m"\n\n')
    return re.sub(r'\[control\]\nlaw = "bdot"\n[^\[]*', lambda m: modes, _short("cubesat-bdot-detumble", t_end))


def _estimator(t_end):
    """The PD law on wheels at 10 Hz on the estimate of a gyro, a star tracker and the MEKF
    (the knowledge indices read the filter's estimate)."""
    text = _short("lvlh-hold-wheels", t_end).replace("[control]\n", '[control]\nperiod = "0.1 s"\n', 1)
    return text + ('\n[sensors]\nseed = 5\n\n[sensors.gyro]\nrate = "10 Hz"\narw = "0.15 deg/sqrt(h)"\n\n'
                   '[sensors.star_tracker]\nrate = "1 Hz"\nnoise = "10 arcsec"\n\n[estimator]\nkind = "mekf"\n'
                   'attitude_sigma = "0.1 deg"\nbias_sigma = "10 deg/h"\n')


#: name: (scenario text, the swept parameter, the keys an output needs)
SCENARIOS = {
    "wheels": (_short("lvlh-hold-wheels", '"200 s"'), 'omega1 = { values = ["0.5 deg/s", "0.1 deg/s"] }',
               {"detumble_time": 'detumble_rate = "0.5 deg/s"', "settling_time": 'settling_angle = "25 deg"'}),
    "bdot": (_short("cubesat-bdot-detumble", '"300 s"'), 'omega1 = { values = ["4 deg/s", "-2 deg/s"] }',
             {"detumble_time": 'detumble_rate = "5 deg/s"', "settling_time": 'settling_angle = "25 deg"'}),
    "torque-free": (_short("paper-torque-free", "1"), "inertia1 = { values = [1.25, 1.3] }",
                    {"detumble_time": "detumble_rate = 1.0", "settling_time": 'settling_angle = "25 deg"'}),
    "modes": (_modes('"300 s"'), 'omega1 = { values = ["4 deg/s", "-2 deg/s"] }',
              {"detumble_time": 'detumble_rate = "5 deg/s"', "settling_time": 'settling_angle = "25 deg"'}),
    "estimator": (_estimator('"200 s"'), 'omega1 = { values = ["0.5 deg/s", "0.1 deg/s"] }',
                  {"detumble_time": 'detumble_rate = "0.5 deg/s"', "settling_time": 'settling_angle = "25 deg"'}),
}
for _name, (_, _, _keys) in SCENARIOS.items():  # slew_time reads settling_time's threshold
    _keys["slew_time"] = _keys["settling_time"]
    # the mean and relative pointing indices read the stability window (a plain number: normalized time)
    _keys["rpe"] = _keys["mpe"] = "stability_window = 0.2" if _name == "torque-free" else 'stability_window = "100 s"'
    _keys["rke"] = _keys["mke"] = _keys["rpe"]
#: the variables each output writes (its descriptor's)
VARIABLES = {k: o.names for k, o in SWEEP_OUTPUTS.items()}


def _text(name, outs):
    base, parameter, keys = SCENARIOS[name]
    table = "\n[sweep]\noutputs = [" + ", ".join(f'"{o}"' for o in outs) + "]\n"
    table += "".join(dict.fromkeys(keys[o] + "\n" for o in outs if o in keys))
    return base + table + "[sweep.parameters]\n" + parameter + "\n"


def _valid_on(name, outs):
    try:
        parse(_text(name, outs), "subset.toml")
    except ScenarioError:
        return False
    return True


def _scenario_for(outs):
    """The first scenario on which the outputs ``outs`` are valid, or None."""
    return next((name for name in SCENARIOS if _valid_on(name, outs)), None)


def _subsets():
    out = []
    for outs in [(o,) for o in OUTPUTS] + list(itertools.combinations(OUTPUTS, 2)):
        name = _scenario_for(outs)
        if name is not None:
            out.append(pytest.param(name, outs, id=f"{name}:{'+'.join(outs)}"))
    return out


SUBSETS = _subsets()


@functools.lru_cache(maxsize=None)
def _every_output(name):
    """The run of scenario ``name`` with every output it can have."""
    outs = [o for o in OUTPUTS if _valid_on(name, (o,))]
    return Sweep(Scenario(parse(_text(name, outs), "all.toml")), seed=1).compute(), tuple(outs)


def test_every_output_is_covered_alone_and_every_pair_some_scenario_has():
    alone = {outs[0] for _, outs in (p.values for p in SUBSETS) if len(outs) == 1}
    assert alone == set(OUTPUTS)
    assert sum(len(p.values[1]) == 2 for p in SUBSETS) >= 55
    # the request: PD + wheels, four outputs of which only one of the two wheel outputs
    assert _scenario_for(("final_state", "settling_time", "pointing_error", "max_wheel_speed")) == "wheels"


@pytest.mark.parametrize("name, outs", SUBSETS)
def test_a_subset_of_outputs_writes_exactly_its_variables(name, outs):
    ds = Sweep(Scenario(parse(_text(name, outs), "subset.toml")), seed=1).compute()
    ref, every = _every_output(name)
    assert set(outs) <= set(every)
    assert not ds["integration_failed"].values.any()
    for o in OUTPUTS:
        for var in VARIABLES[o]:
            if o in outs:
                assert var in ds, (o, var)
                np.testing.assert_array_equal(ds[var].values, ref[var].values, err_msg=f"{o}: {var}")
            elif not any(var in VARIABLES[a] for a in outs):
                assert var not in ds.data_vars, (o, var)

"""Drag in an exponential atmosphere needs no epoch (issue 25): altitude over the sphere, the
atmosphere turning about the inertial axis 3 at the Earth's rate; the run is bit for bit the
run of the same scenario with an epoch (the exponential atmospheres read no date)."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from orbatt.scenario import Scenario, ScenarioError, parse

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


def _scenario(atmosphere_keys, epoch):
    text = (SCEN / "cubesat-3u-disturbances.toml").read_text()
    text = re.sub(r"^t_end = .*$", 't_end = "600 s"', text, flags=re.M)
    text = text.replace("srp = true\n", "").replace('residual_dipole = ["0.005 A m2", "0 A m2", "0.002 A m2"]\n', "")
    env = text[text.index("[environment]"):text.index("[initial]")]
    text = text.replace(env, "[environment]\n" + atmosphere_keys + "\n\n")
    if not epoch:
        text = re.sub(r"^epoch = .*\n", "", text, flags=re.M)
    return text


@pytest.mark.parametrize("keys", ['atmosphere = "exponential"',
                                  'density0 = "3e-12 kg/m3"\naltitude0 = "400 km"\nscale_height = "60 km"'])
def test_exponential_drag_runs_without_an_epoch(keys):
    without = Scenario(parse(_scenario(keys, epoch=False), "no-epoch.toml")).run()
    with_epoch = Scenario(parse(_scenario(keys, epoch=True), "epoch.toml")).run()
    assert np.abs(without["torque_drag"].values).max() > 0
    for name in ("q", "Q", "torque_drag", "density"):
        assert np.array_equal(without[name].values, with_epoch[name].values), name


def test_nrlmsis_still_needs_an_epoch():
    text = _scenario('atmosphere = "nrlmsis"\nf107 = 150\nf107a = 150\nap = 4', epoch=False)
    with pytest.raises(ScenarioError, match=r"\[orbit\] epoch"):
        parse(text, "msis.toml")


def test_closed_form_density_interpreted_gives_the_compiled_bits(tmp_path):
    """The exponential density is evaluated in the kernel (math.exp): an interpreted first run
    (orbatt.coldstart) gives the compiled run's bits."""
    import os
    import subprocess

    from orbatt.dataset import open_dataset

    path = tmp_path / "exp.toml"
    path.write_text(_scenario('atmosphere = "exponential"', epoch=False))
    base = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", "ORBATT_COLD_START")}
    outs = {}
    for mode, extra in (("interpreted", {"NUMBA_DISABLE_JIT": "1"}), ("compiled", {"ORBATT_COLD_START": "compile"})):
        outs[mode] = tmp_path / f"{mode}.nc"
        r = subprocess.run(["orbatt", "run", str(path), "-o", str(outs[mode]), "--quiet"], capture_output=True,
                           text=True, env={**base, **extra}, timeout=600)
        assert r.returncode == 0, r.stderr
    with open_dataset(outs["interpreted"]) as a, open_dataset(outs["compiled"]) as b:
        for name in ("q", "Q", "torque_drag", "density"):
            assert np.array_equal(a[name].values, b[name].values), name

"""The interpreted kernels (``NUMBA_DISABLE_JIT=1``: what a first ``orbatt run`` of a kind of
scenario runs while the kernels compile, :mod:`orbatt.coldstart`) give the compiled kernels'
bits on **every** shipped scenario (issue 22): each run over three output steps, interpreted in a
fresh process, against the compiled run of the same file here."""
from __future__ import annotations

import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.scenario import Scenario, parse

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


def _short(text):
    """The scenario over three output steps (its own step, in its own unit)."""
    m = re.search(r"^output_step = ([^#\n]*)", text, flags=re.M)
    step = m.group(1).strip()
    if step.startswith('"'):
        value, unit = step.strip('"').split(None, 1)
        t_end = f'"{3 * float(value)!r} {unit}"'
    else:
        t_end = repr(3 * float(step))
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    # impulses (a binary's) move to the first output step, inside the short run
    return re.sub(r'(\[\[orbit\.impulses\]\][^\[]*?\btime = )"[^"]*"', lambda m: m.group(1) + step, text)


@pytest.mark.parametrize("name", sorted(p.stem for p in SCEN.glob("*.toml")))
def test_interpreted_run_gives_the_compiled_bits(name, tmp_path):
    path = tmp_path / f"{name}.toml"
    path.write_text(_short((SCEN / f"{name}.toml").read_text()))
    out = tmp_path / "interpreted.nc"
    env = {k: v for k, v in os.environ.items() if k != "ORBATT_COLD_START"}
    env["NUMBA_DISABLE_JIT"] = "1"
    r = subprocess.run([sys.executable, "-m", "orbatt.cli", "run", str(path), "-o", str(out), "--quiet"],
                       capture_output=True, text=True, env=env, timeout=600, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        compiled = Scenario(parse(path.read_text(), str(path)), path=path).run()
    with orbatt.open_dataset(out) as interpreted:
        assert sorted(interpreted.data_vars) == sorted(compiled.data_vars)
        for v in compiled.data_vars:
            a, b = np.asarray(interpreted[v].values), np.asarray(compiled[v].values)
            if a.dtype.kind in "fc":
                assert np.array_equal(a, b, equal_nan=True), f"{name}: {v} differs"

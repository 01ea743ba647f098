"""orbatt's B-dot Monte Carlo case against the Basilisk B-dot set-up of
``benchmarks/montecarlo.py`` (``magneticFieldCenteredDipole``, ``MtbEffector``, the law as a Python
module, gravity gradient; skipped without ``bsk``): the detumble time and the final rate of one
case of ``cubesat-detumble-montecarlo`` with the centred dipole. Measured numbers:
``benchmarks/README.md`` (section "Monte Carlo")."""
from __future__ import annotations

import math

import numpy as np
import pytest


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("montecarlo")


@pytest.fixture(scope="module")
def basilisk():
    pytest.importorskip("Basilisk", reason="Basilisk is not installed (pip install bsk, the bench extra)")


@pytest.fixture(scope="module")
def one_case(bench, tmp_path_factory):
    from orbatt.sweep import load_sweep

    path = tmp_path_factory.mktemp("bdot") / "bdot-dipole.toml"
    path.write_text(bench.bdot_dipole_text(2))
    sweep = load_sweep(path)
    return sweep, sweep.compute()


def test_the_dipole_scenario_is_the_shipped_study_with_the_dipole(bench):
    text = bench.bdot_dipole_text(7)
    assert 'magnetic_field = "dipole"' in text and "samples = 7" in text and '"igrf"' not in text


def test_basilisk_bdot_detumbles_like_orbatt(bench, basilisk, one_case):
    """Case 0 at a 0.5 s task step: the detumble time within 1.5 % (measured 0.08 % here, 0.1-1.4 %
    on three other cases: Basilisk holds the law over the task step and converges to orbatt as it
    shrinks) and the final rate (the residual turning with the field, ~2n) within 15 % (measured
    0.5 % here, up to 6.5 %)."""
    sweep, ds = one_case
    case = bench.bdot_cases(sweep, [0])[0]
    r = bench.basilisk_case(case, 0.5)
    t_orbatt = float(ds["detumble_time"].values[0])
    assert math.isfinite(t_orbatt) and 0 < t_orbatt < case["t_end"]
    assert abs(r["detumble_time"] - t_orbatt) < 0.015 * t_orbatt
    w_orbatt = np.linalg.norm(bench.final_rate(ds, 0))
    assert abs(np.linalg.norm(r["final_rate"]) - w_orbatt) < 0.15 * w_orbatt

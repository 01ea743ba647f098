"""Smoke test of ``benchmarks/basilisk_day.py`` (issue 25): the scenario file it writes for
``orbatt run`` is the case it propagates in-process, and Basilisk's Sun table looks up the
midpoints it was made at. No Basilisk needed, no timing; the measured table is in
``benchmarks/README.md``."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("basilisk_day")


def test_scenario_file_is_the_case(bench, tmp_path):
    from orbatt.scenario import load_scenario

    t_end = 1200.0
    path = tmp_path / "case.toml"
    path.write_text(bench.scenario_toml(1e-10, t_end=t_end))
    ds = load_scenario(path).run()
    t = np.arange(0.0, t_end + 1.0, bench.OUT_STEP)
    q, _ = bench.orbatt_propagate(bench.be.orbatt_case(t_end, bench.TERMS), t, 1e-10)
    qs = np.asarray(ds["q"].values, dtype=float)
    assert qs.shape == q.shape
    assert bench.be._angle(qs * np.sign(qs[:, :1]), q) < 1e-12   # the same model, the same steps


def test_sun_table(bench):
    table = bench.SunTable.of(lambda t: np.stack([t, 2 * t, 3 * t], axis=-1), 200.0)
    assert len(table.positions) == 4
    mid = (np.arange(4) + 0.5) * bench.SUN_EVERY
    for k, t in enumerate(mid):
        assert np.array_equal(table(t), [t, 2 * t, 3 * t])
    assert np.array_equal(table(1e6), table.positions[-1])

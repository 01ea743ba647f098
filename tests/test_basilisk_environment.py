"""orbatt's environment torques against an independent classical model (Euler's equations and
quaternion kinematics in scipy, the flat-plate formulas written again) and against Basilisk 2.12
(optional: skipped without ``bsk``). The models and the case are those of
``benchmarks/basilisk_environment.py``; the measured numbers are in ``benchmarks/README.md``."""
from __future__ import annotations

import math

import numpy as np
import pytest


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("basilisk_environment")


@pytest.fixture(scope="module")
def orbit_run(bench):
    t_end = math.ceil(bench.PERIOD / 60.0) * 60.0
    t = np.arange(0.0, t_end + 1.0, 60.0)
    return t, bench.sun_spline(t_end)


@pytest.mark.parametrize("terms, bound, rtol", [
    # the exponential atmosphere in closed form in the kernel (issue 25): measured 3.7e-11
    # against the reference at rtol 1e-13 (whose own error is ~8e-12; at rtol 1e-12 it is
    # 5e-10 off); with the density's 30 s spline table it was 7.4e-9
    (("gravity_gradient", "drag"), 1e-10, 1e-13),
    (("srp",), 5e-9, 1e-12),                # measured 9.6e-10
])
def test_orbatt_matches_the_classical_model_over_one_orbit(bench, orbit_run, terms, bound, rtol):
    t, sun = orbit_run
    qc = bench.classical_run(t, terms, sun=sun, rtol=rtol)
    qo, ds = bench.orbatt_run(t, terms)
    assert bench._angle(qo, qc) < bound
    # the torques of the Dataset at single instants against the formulas written in the script
    for k in (0, len(t) // 2, len(t) - 1):
        ref = bench.reference_torques(t[k], qo[k], sun)
        for name in terms:
            np.testing.assert_allclose(ds[f"torque_{name}"].values[k], ref[name], rtol=1e-11,
                                       atol=1e-12 * np.linalg.norm(ref[name]))


def test_the_classical_model_converges(bench, orbit_run):
    """The reference itself: rtol 1e-12 against 1e-13 (measured 5e-10 over the orbit with drag)."""
    t, sun = orbit_run
    terms = ("gravity_gradient", "drag")
    assert bench._angle(bench.classical_run(t, terms), bench.classical_run(t, terms, rtol=1e-13)) < 2e-9


@pytest.fixture(scope="module")
def basilisk(bench):
    pytest.importorskip("Basilisk", reason="Basilisk is not installed (pip install bsk, the bench extra)")
    t = np.arange(0.0, 1201.0, 60.0)   # a fifth of an orbit
    return t, bench.sun_spline(t[-1])


@pytest.mark.parametrize("terms", [("gravity_gradient", "drag"), ("srp",)])
def test_basilisk_torques_at_single_instants(bench, basilisk, terms):
    t, sun = basilisk
    qo, ds = bench.orbatt_run(t, terms)
    for k in (0, 7, 20):
        ref = bench.reference_torques(t[k], qo[k], sun)
        tb = bench.basilisk_torques(t[k], qo[k], ds.omega.values[k], terms, sun=sun)
        for name in terms:   # measured <= 1e-13 relative (Basilisk's SRP areas scaled to orbatt's flux)
            np.testing.assert_allclose(tb[name], ref[name], rtol=1e-11, atol=1e-12 * np.linalg.norm(ref[name]))


def test_basilisk_drag_is_the_classical_model_with_the_density_held_per_step(bench, basilisk):
    """Basilisk holds the density over each task step: it then follows the classical model with
    the same hold (4e-14 rad over 1200 s, no facet switch), and differs from the exact model by
    an error proportional to the step (4.1e-4 rad at 10 s, 8.1e-5 at 2 s)."""
    t, sun = basilisk
    terms = ("gravity_gradient", "drag")
    fine = np.arange(0.0, t[-1] + 5.0, 10.0)
    qb10, _ = bench.basilisk_run(fine, terms, 10.0)
    assert bench._angle(qb10, bench.classical_run(fine, terms, hold=10.0)) < 1e-12
    qo, _ = bench.orbatt_run(t, terms)
    qc = bench.classical_run(t, terms)
    assert bench._angle(qo, qc) < 1e-9                                     # measured 1.6e-10
    err10 = bench._angle(bench.basilisk_run(t, terms, 10.0)[0], qc)
    err2 = bench._angle(bench.basilisk_run(t, terms, 2.0)[0], qc)
    assert 1e-4 < err10 < 1e-3 and 3.5 < err10 / err2 < 6.5              # first order in the step
    assert bench._angle(bench.basilisk_run(t, terms, 2.0)[0], qo) < 2e-4  # measured 8.1e-5


def test_basilisk_srp_follows_the_classical_model_until_a_facet_switch(bench, basilisk):
    """With the Sun held per step (at its midpoint) Basilisk is the classical model to 1e-15 rad
    until a facet turns to or away from the Sun (cos = 0, first at 140 s): its fixed RKF78 steps
    then straddle the kink of max(0, cos) (5e-9 rad at 2 s over 1200 s, 9.7e-8 at 10 s)."""
    t, sun = basilisk
    terms = ("srp",)
    fine = np.arange(0.0, 130.0, 10.0)
    qb, _ = bench.basilisk_run(fine, terms, 10.0, sun=sun)
    assert bench._angle(qb, bench.classical_run(fine, terms, sun=sun, hold=10.0)) < 1e-13
    qo, _ = bench.orbatt_run(t, terms)
    assert bench._angle(bench.basilisk_run(t, terms, 2.0, sun=sun)[0], qo) < 2e-8

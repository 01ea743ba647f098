"""Issue 14 §4: every per-case quantity of a sweep chunk is computed per case, so a case's
result is bitwise the same whether it is computed alone or inside a batch of any size, at
any position (a BLAS product or a reduction across cases would pick its kernel, and its
rounding, by size and CPU)."""
from pathlib import Path

import numpy as np
import pytest

from orbatt import quaternion as qt
from orbatt.scenario import Scenario, parse
from orbatt.sweep import Sweep
from orbatt.sweep.chunk import conserved_energy, initial_states, pointing_error

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")
SIZES = (1, 7, 33, 101)
POOL = 160  # members to draw batches from
N = 37      # output times


def sweep_of(text):
    return Sweep(Scenario(parse(text, "test.toml")), seed=7)


@pytest.fixture(scope="module")
def gg():
    """The shipped dispersion (circular orbit: Jacobi integral; orbital reference; inertia,
    rate and attitude dispersions), shortened."""
    text = (SCEN / "gg-leo-dispersion.toml").read_text()
    text = text.replace('t_end = "300 orbits"', 't_end = "0.05 orbits"').replace("samples = 2000", f"samples = {POOL}")
    return sweep_of(text)


@pytest.fixture(scope="module")
def heavy_top():
    """A heavy top (H = T + U) with a rate dispersion."""
    text = (SCEN / "paper-heavy-top.toml").read_text() + (
        '\n[sweep]\nsamples = 3\nseed = 1\noutputs = ["final_energy_error", "max_pointing_error"]\n'
        'pointing_axis = [1, 2, 2]\n[sweep.parameters]\nomega1 = { distribution = "normal", std = 0.1 }\n')
    return sweep_of(text)


def members(rng, m, inertia, times=None):
    """Random unit attitudes ``q`` and tangent momenta ``Q = 2 q (0, I w)`` of ``m`` members
    (shape (m, 4), or (m, N, 4) with ``times``)."""
    shape = (m,) if times is None else (m, times)
    q = qt.normalize(rng.normal(size=shape + (4,)))
    w = rng.normal(scale=1e-3, size=shape + (3,))
    I = inertia if times is None else inertia[:, None, :]
    return q, 2.0 * qt.mul(q, qt.pure(I * w))


def batches(rng):
    """``(k, batch, pos)``: member ``k`` of the pool at position ``pos`` of a batch of pool
    indices, for every size and for the first, a middle and the last position."""
    for n in SIZES:
        for pos in sorted({0, n // 2, n - 1}):
            k = int(rng.integers(POOL))
            batch = rng.choice(np.delete(np.arange(POOL), k), size=n, replace=False)
            batch[pos] = k
            yield k, batch, pos


def assert_batch_invariant(fn, rng):
    """``fn(idx)`` returns per-member results (first axis along ``idx``)."""
    alone = {}
    for k, batch, pos in batches(rng):
        if k not in alone:
            alone[k] = np.asarray(fn(np.array([k])))[0]
        got = np.asarray(fn(batch))[pos]
        assert got.tobytes() == alone[k].tobytes(), (k, batch.size, pos, got, alone[k])


def test_jacobi_integral_per_member(gg):
    rng = np.random.default_rng(1)
    sc, spec = gg.scenario, gg.spec
    assert spec.energy == "jacobi"
    inertia = sc.spec.inertia * (1 + 0.05 * rng.random((POOL, 3)))
    q, Q = members(rng, POOL, inertia)
    for t in (0.0, float(sc.times[-1])):
        assert_batch_invariant(lambda i: conserved_energy(spec, sc.potential, sc.orbit, inertia[i], q[i], Q[i], t), rng)


def test_hamiltonian_per_member(heavy_top):
    rng = np.random.default_rng(2)
    sc, spec = heavy_top.scenario, heavy_top.spec
    assert spec.energy == "hamiltonian"
    inertia = sc.spec.inertia * (1 + 0.05 * rng.random((POOL, 3)))
    q, Q = members(rng, POOL, inertia)
    assert_batch_invariant(lambda i: conserved_energy(spec, sc.potential, None, inertia[i], q[i], Q[i], 0.3), rng)


def test_energy_error_per_member(gg):
    rng = np.random.default_rng(3)
    sc, spec = gg.scenario, gg.spec
    inertia = sc.spec.inertia * (1 + 0.05 * rng.random((POOL, 3)))
    q0, Q0 = members(rng, POOL, inertia)
    q1, Q1 = members(rng, POOL, inertia)

    def err(i):
        E0 = conserved_energy(spec, sc.potential, sc.orbit, inertia[i], q0[i], Q0[i], 0.0)
        E1 = conserved_energy(spec, sc.potential, sc.orbit, inertia[i], q1[i], Q1[i], float(sc.times[-1]))
        return (E1 - E0) / np.abs(E0)

    assert_batch_invariant(err, rng)


@pytest.mark.parametrize("axis", [None, [1.0, 2.0, 2.0]])
@pytest.mark.parametrize("reference", ["orbital", "inertial"])
def test_pointing_error_per_member(gg, axis, reference):
    rng = np.random.default_rng(4)
    sc, spec = gg.scenario, gg.spec
    spec = type(spec)(**{**spec.__dict__, "pointing_axis": None if axis is None else np.array(axis) / 3.0,
                         "pointing_reference": reference})
    times = np.linspace(0.0, 600.0, N)
    p = sc.orbit.orbital_quaternion(times) if reference == "orbital" else None
    q, _ = members(rng, POOL, np.broadcast_to(sc.spec.inertia, (POOL, 3)), times=N)
    assert_batch_invariant(lambda i: pointing_error(spec, q[i], p), rng)
    assert_batch_invariant(lambda i: np.max(pointing_error(spec, q[i], p), axis=-1), rng)


def test_initial_states_per_member(gg):
    """Each case's (q, Q) from its own inertia, rates and attitude perturbation."""
    rng = np.random.default_rng(5)
    sc, spec = gg.scenario, gg.spec
    inertia = np.array(np.broadcast_to(sc.spec.inertia, (POOL, 3)))
    for k, name in enumerate(("inertia1", "inertia2", "inertia3")):
        if name in gg.values:
            inertia[:, k] = gg.values[name]
    assert {"attitude_angle", "omega1", "inertia1"} <= set(spec.parameters)
    for out in (0, 1):
        assert_batch_invariant(lambda i: initial_states(sc, spec, gg.values, gg.attitude_axis, inertia, sc.orbit,
                                                        i)[out], rng)

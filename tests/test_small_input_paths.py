"""The small-input forms of quaternion.mul and to_euler321 (Python floats) give the values of
the whole-array forms bitwise; check_work's spin bound never lets through what the exact rate
refuses."""

import numpy as np
import pytest

from orbatt import quaternion as qt
from orbatt.body import RigidBody
from orbatt.errors import ScenarioError
from orbatt.scenario.build import MAX_ANGLE_PER_STEP, MAX_WORK_STEPS, check_work
from orbatt.scenario.fields import FieldContext
from orbatt.state import State


def _mul_components(a, b):
    """:func:`qt.mul` of ``a``, ``b`` through its whole-array form (copies stacked past the
    small-input sizes), the first copy."""
    big = 1000  # 4000+ components: past every small-input form
    shape = (big,) + np.broadcast_shapes(np.shape(a), np.shape(b))
    a2 = np.broadcast_to(a, shape).copy()
    b2 = np.broadcast_to(b, shape).copy()
    return qt.mul(a2, b2)[0]


@pytest.mark.parametrize("sa, sb", [((4,), (4,)), ((2, 4), (2, 4)), ((4,), (2, 4)), ((2, 4), (4,)),
                                    ((1, 2, 4), (1, 2, 4)), ((1, 4), (4,))])
def test_mul_of_few_quaternions_is_the_component_form(sa, sb):
    rng = np.random.default_rng(5)
    special = np.array([0.0, -0.0, 1e-310, 1e308, -1e308, 1.0, -0.5])
    for k in range(500):
        a = rng.standard_normal(sa) * 10.0 ** rng.integers(-6, 6, sa) if k % 2 else rng.choice(special, sa)
        b = rng.standard_normal(sb) if k % 3 else rng.choice(special, sb)
        with np.errstate(over="ignore", invalid="ignore"):
            ours, ref = qt.mul(a, b), _mul_components(a, b)
        assert ours.shape == ref.shape
        np.testing.assert_array_equal(ours.view(np.int64), ref.view(np.int64))


def test_euler321_of_few_quaternions_is_the_array_form():
    rng = np.random.default_rng(6)
    for shape in [(1, 4), (2, 4), (1, 2, 4)]:
        for _ in range(300):
            q = rng.standard_normal(shape)
            small = qt.to_euler321(q)
            big = qt.to_euler321(np.concatenate([q.reshape(-1, 4)] * 5))  # above the small-input size
            for s, b in zip(small, big):
                np.testing.assert_array_equal(np.asarray(s).reshape(-1), b[:np.asarray(s).size])


def test_check_work_bound_agrees_with_the_exact_rate():
    ctx = FieldContext("case.toml")
    body = RigidBody([1.0, 2.0, 2.5])
    state = State.from_omega(body, [1.0, 0.0, 0.0, 0.0], [3.0, -1.0, 2.0])
    spin = float(np.linalg.norm(state.omega))
    limit = MAX_WORK_STEPS * MAX_ANGLE_PER_STEP / spin  # t_end at which the spin alone reaches the limit
    check_work(ctx, limit * (1 - 1e-6), None, state)
    with pytest.raises(ScenarioError, match="the body turns"):
        check_work(ctx, limit * (1 + 1e-6), None, state)


def test_empty_inputs_keep_their_shapes():
    empty = np.zeros((0, 4))
    assert qt.mul(empty, [1.0, 0.0, 0.0, 0.0]).shape == (0, 4)
    assert qt.mul([1.0, 0.0, 0.0, 0.0], empty).shape == (0, 4)
    assert [np.shape(x) for x in qt.to_euler321(empty)] == [(0,), (0,), (0,)]


def test_a_body_leaves_the_callers_inertia_array_alone():
    """RigidBody keeps a frozen copy: the caller's array stays writeable (it froze the caller's
    own array, which then reached the compiled kernels as another numba type)."""
    inertia = np.array([400.0, 500.0, 600.0])
    body = RigidBody(inertia)
    assert inertia.flags.writeable
    inertia[0] = 450.0
    assert body.inertia_value.tolist() == [400.0, 500.0, 600.0]

"""Quaternion algebra: identities by property tests, conversions by round trips."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from orbatt import quaternion as qt
from orbatt.core import qalg
from orbatt.errors import InputError

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)
quats = arrays(np.float64, 4, elements=finite)
vecs = arrays(np.float64, 3, elements=finite)


def unit(q):
    n = np.linalg.norm(q)
    return q / n if n > 1e-3 else np.array([1.0, 0.0, 0.0, 0.0])


unit_quats = quats.map(unit)
TOL = 1e-12


def close(a, b, scale=1.0, tol=TOL):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) <= tol * max(1.0, scale)


@given(quats, quats, quats)
def test_associativity(a, b, c):
    s = np.linalg.norm(a) * np.linalg.norm(b) * np.linalg.norm(c)
    assert close(qt.mul(qt.mul(a, b), c), qt.mul(a, qt.mul(b, c)), s)


@given(quats, quats)
def test_norm_is_multiplicative(a, b):
    assert abs(qt.norm(qt.mul(a, b)) - qt.norm(a) * qt.norm(b)) <= TOL * max(1.0, qt.norm(a) * qt.norm(b))


@given(quats, quats)
def test_conjugate_is_anti_automorphism(a, b):
    s = np.linalg.norm(a) * np.linalg.norm(b)
    assert close(qt.conj(qt.mul(a, b)), qt.mul(qt.conj(b), qt.conj(a)), s)


@given(quats, quats)
def test_dot_is_real_part_of_p_conj_q(a, b):
    # docs/design.md §3a item 1: p.q = Re(p q~), not Re(p q)
    s = np.linalg.norm(a) * np.linalg.norm(b)
    assert abs(qt.dot(a, b) - qt.mul(a, qt.conj(b))[0]) <= TOL * max(1.0, s)


def test_dot_is_not_re_pq():
    p = np.array([0.0, 1.0, 0.0, 0.0])
    assert qt.dot(p, p) == 1.0
    assert qt.mul(p, p)[0] == -1.0  # the paper's printed Re(pq) would give -1


@given(quats, quats)
def test_scalar_kernel_matches_numpy(a, b):
    assert close(qalg.qmul(tuple(a), tuple(b)), qt.mul(a, b), np.linalg.norm(a) * np.linalg.norm(b))


wide = st.floats(-1e150, 1e150, allow_nan=False, allow_infinity=False, allow_subnormal=True)


@given(arrays(np.float64, 4, elements=wide), arrays(np.float64, 3, elements=wide))
def test_products_with_a_pure_quaternion_are_qmul_exactly(a, v):
    """qmul_pure / pure_qmul leave out the zero scalar part's products: the same numbers as
    qmul (compared as values: an exact zero's sign may differ), also the compiled kernels."""
    a, v = tuple(map(float, a)), tuple(map(float, v))
    pure = (0.0,) + v
    assert np.array_equal(qalg.qmul_pure.py_func(a, v), qalg.qmul.py_func(a, pure))
    assert np.array_equal(qalg.pure_qmul.py_func(v, a), qalg.qmul.py_func(pure, a))
    assert np.array_equal(qalg.qmul_pure(a, v), qalg.qmul(a, pure))
    assert np.array_equal(qalg.pure_qmul(v, a), qalg.qmul(pure, a))


def test_hamilton_convention_ijk():
    i, j, k = np.eye(4)[1:]
    assert np.array_equal(qt.mul(i, j), k)
    assert np.array_equal(qt.mul(j, k), i)
    assert np.array_equal(qt.mul(k, i), j)
    assert np.array_equal(qt.mul(i, i), -np.eye(4)[0])


def test_rotation_convention_90_degrees():
    # q rotates S axes into B axes: a body x axis, after +90 deg about s3, points along s2
    q = qt.from_axis_angle([0, 0, 1], np.pi / 2)
    assert np.allclose(qt.rotate(q, [1, 0, 0]), [0, 1, 0], atol=1e-15)
    assert np.allclose(qt.rotate_inv(q, [0, 1, 0]), [1, 0, 0], atol=1e-15)
    assert np.allclose(qt.to_matrix(q) @ [1, 0, 0], [0, 1, 0], atol=1e-15)


@given(unit_quats, vecs)
def test_rotate_matches_matrix_and_inverse(q, v):
    s = np.linalg.norm(v)
    assert close(qt.rotate(q, v), qt.to_matrix(q) @ v, s)
    assert close(qt.rotate_inv(q, qt.rotate(q, v)), v, s)
    assert close(qt.rotate(q, v), qalg.rotate(tuple(q), tuple(v)), s)


@given(unit_quats)
def test_matrix_round_trip(q):
    R = qt.to_matrix(q)
    assert close(R @ R.T, np.eye(3))
    assert abs(np.linalg.det(R) - 1) < TOL
    assert qt.angle_between(qt.from_matrix(R), q) < 1e-12
    assert close(qt.to_matrix(qt.from_matrix(R)), R)


@pytest.mark.parametrize("angle", [0.0, 1e-9, np.pi / 2, np.pi - 1e-9, np.pi])
@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, -2, 3]])
def test_shepperd_is_accurate_for_every_angle(axis, angle):
    q = qt.from_axis_angle(axis, angle)
    back = qt.from_matrix(qt.to_matrix(q))
    assert np.max(np.abs(qt.canonical(back) - qt.canonical(q))) < 1e-15 * 8


@given(unit_quats)
def test_axis_angle_and_rotvec_round_trip(q):
    axis, angle = qt.to_axis_angle(q)
    assert 0 <= angle <= np.pi
    assert qt.angle_between(qt.from_axis_angle(axis, angle), q) < 1e-12
    assert qt.angle_between(qt.from_rotvec(qt.to_rotvec(q)), q) < 1e-12


@given(arrays(np.float64, 4, elements=st.floats(-3, 3)))
def test_exp_log_round_trip(x):
    if np.linalg.norm(x[1:]) >= np.pi - 1e-6:
        x = x.copy()
        x[1:] *= 0.5
    assert close(qt.log(qt.exp(x)), x, 1.0, 1e-12)


@given(unit_quats)
def test_euler313_round_trip(q):
    phi, theta, psi = qt.to_euler313(q)
    assert 0 <= theta <= np.pi
    assert qt.angle_between(qt.from_euler313(phi, theta, psi), q) < 1e-12


@pytest.mark.parametrize("theta", [0.0, 1e-12, 1e-8, np.pi - 1e-8, np.pi - 1e-12, np.pi])
def test_euler313_near_singularities(theta):
    rng = np.random.default_rng(1)
    for phi, psi in rng.uniform(-np.pi, np.pi, size=(20, 2)):
        q = qt.from_euler313(phi, theta, psi)
        a = qt.to_euler313(q)
        assert np.all(np.isfinite(a))
        assert qt.angle_between(qt.from_euler313(*a), q) < 1e-12


def test_euler313_matches_scipy():
    rng = np.random.default_rng(2)
    ang = np.column_stack([rng.uniform(-np.pi, np.pi, 50), rng.uniform(0.01, np.pi - 0.01, 50),
                           rng.uniform(-np.pi, np.pi, 50)])
    q = qt.from_euler313(*ang.T)
    # intrinsic z-x'-z'' in scipy = rotation q_z(phi) q_x(theta) q_z(psi)
    R = Rotation.from_euler("ZXZ", ang)
    assert np.max(qt.angle_between(qt.from_scipy(R), q)) < 1e-12
    back = qt.to_scipy(q).as_euler("ZXZ")
    assert np.max(qt.angle_between(qt.from_euler313(*back.T), q)) < 1e-12


@given(unit_quats)
def test_scipy_round_trip_is_scalar_last_at_the_border(q):
    r = qt.to_scipy(q)
    assert close(r.as_quat(), np.r_[q[1:], q[0]]) or close(r.as_quat(), -np.r_[q[1:], q[0]])
    assert close(r.as_matrix(), qt.to_matrix(q))
    assert qt.angle_between(qt.from_scipy(r), q) < 1e-12


def test_broadcasting():
    a = np.random.default_rng(3).normal(size=(5, 1, 4))
    b = np.random.default_rng(4).normal(size=(1, 7, 4))
    assert qt.mul(a, b).shape == (5, 7, 4)
    assert np.allclose(qt.mul(a, b)[2, 3], qt.mul(a[2, 0], b[0, 3]))


def test_bad_input():
    with pytest.raises(InputError, match="shape"):
        qt.as_quaternion([1, 0, 0])
    with pytest.raises(InputError, match="non-finite"):
        qt.as_quaternion([np.nan, 0, 0, 0])
    with pytest.raises(InputError, match="zero quaternion"):
        qt.normalize([0, 0, 0, 0])
    with pytest.raises(InputError, match="zero vector"):
        qt.from_axis_angle([0, 0, 0], 1.0)


# ------------------------------------------------------------------------------------------
# 3-2-1 angles (moved from tests/test_dataset.py; also reachable as orbatt.dataset.to_euler321)
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("axis,which", [((1, 0, 0), 0), ((0, 1, 0), 1), ((0, 0, 1), 2)])
def test_euler321_ninety_degrees(axis, which):
    q = qt.from_axis_angle(np.array(axis, float), np.pi / 2 if which != 1 else np.pi / 3)
    angles = np.array(qt.to_euler321(q))
    expect = np.zeros(3)
    expect[which] = np.pi / 2 if which != 1 else np.pi / 3
    assert np.allclose(angles, expect, atol=1e-15)


def test_euler321_sequence_and_scipy():
    rng = np.random.default_rng(5)
    q = qt.normalize(rng.normal(size=(500, 4)))
    roll, pitch, yaw = qt.to_euler321(q)
    # q = q_z(yaw) q_y(pitch) q_x(roll)
    rebuilt = qt.mul(qt.mul(qt.from_axis_angle([0, 0, 1.0], yaw), qt.from_axis_angle([0, 1.0, 0], pitch)),
                     qt.from_axis_angle([1.0, 0, 0], roll))
    assert np.all(qt.angle_between(rebuilt, q) < 1e-14)
    ypr = qt.to_scipy(q).as_euler("ZYX")
    assert np.allclose(np.stack([roll, pitch, yaw], -1), ypr[:, ::-1], atol=1e-13)
    assert np.all(np.abs(pitch) <= np.pi / 2)


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2])
def test_euler321_gimbal_lock(pitch):
    q = qt.from_scipy(Rotation.from_euler("ZYX", [0.7, pitch, 0.2]))
    roll, p, yaw = qt.to_euler321(q)
    assert np.isfinite([roll, p, yaw]).all() and roll == 0.0
    assert abs(p - pitch) < 1e-7
    rebuilt = qt.from_scipy(Rotation.from_euler("ZYX", [yaw, p, roll]))
    assert qt.angle_between(rebuilt, q) < 1e-7


def test_euler321_still_reachable_from_dataset():
    from orbatt import dataset as D

    assert D.to_euler321 is qt.to_euler321


def test_euler_angles_of_a_row_do_not_depend_on_singular_rows_beside_it():
    """The generic rows come out bitwise the same whether or not a singular row (theta = 0 or
    pi; gimbal lock) in the same array takes the singular branch."""
    q = qt.normalize(np.random.default_rng(6).normal(size=(9, 4)))
    cases = [(qt.to_euler313, [qt.from_euler313(0.3, 0.0, 0.2), qt.from_euler313(0.3, np.pi, 0.2)]),
             (qt.to_euler321, [qt.from_scipy(Rotation.from_euler("ZYX", [0.7, p, 0.2])) for p in (np.pi / 2, -np.pi / 2)])]
    for f, singular in cases:
        alone = f(q)
        for s in singular:
            mixed = f(np.vstack([q, s]))
            for a, m in zip(alone, mixed):
                assert np.array_equal(a.view(np.int64), m[:-1].view(np.int64))
            assert np.isfinite(np.array(mixed)).all()


def test_mul_of_few_quaternions_is_bitwise_the_product_of_many():
    """mul computes a few quaternions as whole arrays and many component by component: the
    same terms in the same order, so the same bits (signed zeros, overflow and NaN included)."""
    rng = np.random.default_rng(7)
    special = np.array([0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, -1e300, np.inf, np.nan])
    many_a = np.concatenate([rng.standard_normal((200, 4)), rng.choice(special, (200, 4))])
    many_b = np.concatenate([rng.standard_normal((200, 4)), rng.choice(special, (200, 4))])
    with np.errstate(all="ignore"):
        many = qt.mul(many_a, many_b)
        for k in range(0, 400, 2):
            few = qt.mul(many_a[k:k + 2], many_b[k:k + 2])
            assert few.tobytes() == many[k:k + 2].tobytes()
        # broadcasting: one quaternion against a few
        assert qt.mul(many_a[0], many_b[:3]).tobytes() == qt.mul(np.tile(many_a[0], (400, 1)), many_b)[:3].tobytes()


@pytest.mark.parametrize("deg", [1e-6, 0.5, 30.0, 90.0, 179.0, 180.0])
def test_angle_between_is_the_rotation_angle(deg):
    """A rotation of ``deg`` about any axis is ``deg`` away (it returned half of it)."""
    a = qt.from_axis_angle([0.3, -0.5, 0.8], 0.4)
    b = qt.mul(a, qt.from_axis_angle([1.0, 2.0, -0.5], np.radians(deg)))
    assert np.degrees(qt.angle_between(a, b)) == pytest.approx(deg, rel=1e-12, abs=1e-12)
    assert np.degrees(qt.angle_between(a, -b)) == pytest.approx(deg, rel=1e-12, abs=1e-12)  # q and -q alike

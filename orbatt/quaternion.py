"""Quaternion algebra on float64 arrays of shape ``(..., 4)``: orbatt's conventions.

Conventions (stated here once; ``docs/design.md`` §1 is the reference)
----------------------------------------------------------------------
* **Scalar first**: ``q = (q0, q1, q2, q3)`` = ``q0 + q1 i + q2 j + q3 k``, stored in the
  last axis. Every function broadcasts over the leading axes.
* Product ``q p = (q0 p0 - q.p, q0 p + p0 q + q x p)`` (Hamilton, ``i j = k``).
  Conjugate ``q~ = (q0, -q)``. Dot product ``p.q = Re(p q~)`` (the R^4 dot product).
  A 3-vector ``x`` is the pure quaternion ``(0, x)``.
* ``(x)`` is the componentwise product in R^4 (:func:`hadamard`).
* **Frames**: ``S`` inertial (space), ``B`` body (principal axes), ``O`` orbital (``o1``
  radial outwards, ``o3`` along ``r x v``, ``o2 = o3 x o1``). The attitude ``q`` maps body
  components to space components: ``x_S = q x_B q~`` (:func:`rotate`), ``x_B = q~ x_S q``
  (:func:`rotate_inv`). This is the rotation that turns the ``S`` axes into the ``B`` axes;
  Basilisk-style, it is the attitude of ``B`` relative to ``S`` (``q_BS``). The orbital
  quaternion ``p`` maps ``O`` to ``S`` the same way; the attitude relative to the orbital
  frame is ``p~ q``. ``q`` and ``-q`` are the same rotation.
* Rotation matrices act on column vectors: ``R(q) x = q x q~`` (:func:`to_matrix`).
* Euler angles: the paper's 3-1-3 sequence ``(phi, theta, psi)`` (eq. 12),
  ``q = q_z(phi) q_x(theta) q_z(psi)``; ``0 <= theta <= pi``. The aerospace 3-2-1 sequence
  ``q = q_z(yaw) q_y(pitch) q_x(roll)`` (:func:`to_euler321`).
* scipy's :class:`~scipy.spatial.transform.Rotation` is **scalar last**; use
  :func:`to_scipy` / :func:`from_scipy`, which reorder explicitly.
* Angles are in radians, plain floats (units are stripped at the API boundary).

The scalar, allocation-free kernels used by the compiled integrators are in
:mod:`orbatt.core.qalg`; they follow the same conventions and are tested against the
functions below. This module does not import numba.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import InputError

__all__ = [
    "as_quaternion", "mul", "conj", "norm", "dot", "normalize", "hadamard", "inv",
    "exp", "log", "rotate", "rotate_inv", "to_matrix", "from_matrix", "to_axis_angle",
    "from_axis_angle", "to_rotvec", "from_rotvec", "to_euler313", "from_euler313",
    "to_euler321", "to_scipy", "from_scipy", "pure", "vector", "angle_between", "canonical",
]


def as_quaternion(q, name="q"):
    """Return ``q`` as a float64 array of shape ``(..., 4)``; raise :class:`InputError` on a
    wrong last axis or non-finite entries."""
    a = np.asarray(q, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != 4:
        raise InputError(f"{name}: expected an array of shape (..., 4) (scalar first "
                         f"q0, q1, q2, q3), got shape {a.shape}")
    if not (all(map(math.isfinite, a.ravel().tolist())) if a.size <= _TINY else np.isfinite(a).all()):
        raise InputError(f"{name}: contains non-finite values ({a!r}); give finite numbers")
    return a


def _as_vector(v, name="v"):
    a = np.asarray(v, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InputError(f"{name}: expected an array of shape (..., 3), got shape {a.shape}")
    return a


def mul(a, b):
    """Quaternion product ``a b`` (Hamilton convention), broadcasting over leading axes."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.ndim == 0 or b.ndim == 0 or a.shape[-1] != 4 or b.shape[-1] != 4:
        raise ValueError(f"mul: expected quaternions of shape (..., 4), got {a.shape} and {b.shape}")
    if a.size <= _TINY and b.size <= _TINY and (a.shape == b.shape or a.ndim == 1 or b.ndim == 1):
        return _mul_tiny(a, b)
    a0, a1, a2, a3 = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    b0, b1, b2, b3 = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    # written into one array (no stack of temporaries): the same operations in the same order
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    out[..., 1] = a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2
    out[..., 2] = a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1
    out[..., 3] = a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0
    return out


def _mul_tiny(a, b):
    """:func:`mul` of a few quaternions (``a``, ``b`` of one shape, or one of them a single
    quaternion) in Python floats: the per-component form's operations in its order (IEEE
    double arithmetic, as numpy's), so the same values, without numpy's ~0.5 us per call."""
    shape = a.shape if a.ndim >= b.ndim else b.shape
    A = a.reshape(-1, 4).tolist()
    B = b.reshape(-1, 4).tolist()
    if len(A) != len(B):  # one of them a single quaternion
        A, B = (A * len(B), B) if len(A) == 1 else (A, B * len(A))
    out = [(a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)
           for (a0, a1, a2, a3), (b0, b1, b2, b3) in zip(A, B)]
    return np.array(out, dtype=np.float64).reshape(shape)


#: most elements of the factors for :func:`mul`'s Python-float form
_TINY = 8

#: componentwise factor of the conjugate
_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


def conj(q):
    """Conjugate ``q~ = (q0, -q1, -q2, -q3)``."""
    return np.asarray(q, dtype=np.float64) * _CONJ


def dot(a, b):
    """R^4 dot product ``a.b = Re(a b~)``; shape ``(...)``."""
    # np.add.reduce: what np.sum calls, without its argument handling
    return np.add.reduce(np.asarray(a, dtype=np.float64) * np.asarray(b, dtype=np.float64), axis=-1)


def norm(q):
    """Euclidean norm ``|q|``; shape ``(...)``."""
    q = np.asarray(q, dtype=np.float64)
    # what np.linalg.norm(q, axis=-1) computes (the same sum, in the same order) without its
    # argument handling
    return np.sqrt(np.add.reduce(q * q, axis=-1))


def normalize(q):
    """``q / |q|``; raises :class:`InputError` for a zero or non-finite quaternion."""
    q = as_quaternion(q)
    n = norm(q)
    if (0.0 in n.ravel().tolist()) if q.size <= _TINY else (n == 0.0).any():
        raise InputError("q: the zero quaternion has no direction; give a nonzero quaternion")
    return q / n[..., None]


def inv(q):
    """Inverse ``q~ / |q|^2``."""
    q = np.asarray(q, dtype=np.float64)
    return conj(q) / dot(q, q)[..., None]


def hadamard(a, b):
    """Componentwise product in R^4 (the paper's ``(x)``)."""
    return np.asarray(a, dtype=np.float64) * np.asarray(b, dtype=np.float64)


def pure(v):
    """The pure quaternion ``(0, v)`` of 3-vectors ``v`` (shape ``(..., 3)``)."""
    v = _as_vector(v)
    return np.concatenate([np.zeros(v.shape[:-1] + (1,)), v], axis=-1)


def vector(q):
    """The vector part ``(q1, q2, q3)``."""
    return np.asarray(q, dtype=np.float64)[..., 1:]


def exp(q):
    """Quaternion exponential ``exp(a + v) = e^a (cos|v|, sin|v| v/|v|)`` (exact at v = 0)."""
    q = np.asarray(q, dtype=np.float64)
    v = q[..., 1:]
    n = np.linalg.norm(v, axis=-1)
    sinc = np.sinc(n / np.pi)  # sin(n)/n, 1 at n = 0
    ea = np.exp(q[..., 0])
    return np.concatenate([(ea * np.cos(n))[..., None], (ea * sinc)[..., None] * v], axis=-1)


def log(q):
    """Principal logarithm ``log q = (ln|q|, atan2(|v|, q0) v/|v|)``; ``log(exp(x)) = x`` for
    ``|Im x| < pi``."""
    q = as_quaternion(q)
    v = q[..., 1:]
    nv = np.linalg.norm(v, axis=-1)
    nq = np.linalg.norm(q, axis=-1)
    if np.any(nq == 0.0):
        raise InputError("q: the logarithm of the zero quaternion is undefined")
    ang = np.arctan2(nv, q[..., 0])
    # the vector part is ang * v/|v|; at v = 0 it is 0 whatever the factor
    f = np.where(nv > 0.0, ang / np.where(nv > 0.0, nv, 1.0), 0.0)
    return np.concatenate([np.log(nq)[..., None], f[..., None] * v], axis=-1)


def rotate(q, v):
    """``q (0, v) q~``: body -> space components when ``q`` is the attitude.

    ``q`` need not be normalized; it is normalized here (a rotation is a unit quaternion).
    """
    q = np.asarray(q, dtype=np.float64)
    v = _as_vector(v)
    q = q / norm(q)[..., None]
    return vector(mul(mul(q, pure(v)), conj(q)))


def rotate_inv(q, v):
    """``q~ (0, v) q``: space -> body components when ``q`` is the attitude."""
    q = np.asarray(q, dtype=np.float64)
    v = _as_vector(v)
    q = q / norm(q)[..., None]
    return vector(mul(mul(conj(q), pure(v)), q))


def to_matrix(q):
    """Rotation matrix ``R`` with ``R x = q x q~`` (shape ``(..., 3, 3)``; ``q`` normalized).

    Note: the matrix printed in the paper's Sect. 2 is the transpose of this one
    (``docs/design.md`` §3a item 2).
    """
    q = normalize(q)
    w, x, y, z = np.moveaxis(q, -1, 0)
    R = np.stack(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
        ],
        axis=-1,
    )
    return R.reshape(q.shape[:-1] + (3, 3))


def from_matrix(R):
    """Unit quaternion (``q0 >= 0``) of a rotation matrix, by Shepperd's method.

    Shepperd picks, per matrix, the largest of ``4 q0^2, 4 q1^2, 4 q2^2, 4 q3^2`` (from the
    trace and the diagonal) to divide by, so it is accurate for every rotation (the
    square-root-of-trace formula alone fails near 180 degrees).
    """
    R = np.asarray(R, dtype=np.float64)
    if R.shape[-2:] != (3, 3):
        raise InputError(f"R: expected shape (..., 3, 3), got {R.shape}")
    r = R.reshape(-1, 3, 3)
    tr = r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2]
    cand = np.stack([tr, r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]], axis=-1)
    k = np.argmax(cand, axis=-1)
    out = np.empty((r.shape[0], 4))
    # case 0: q0 largest
    s = np.sqrt(1.0 + 2.0 * cand[np.arange(len(k)), k] - tr)  # = 2 |q_k| (times 1)
    for idx in range(4):
        m = k == idx
        if not np.any(m):
            continue
        rr = r[m]
        ss = s[m]
        if idx == 0:
            q = [0.5 * ss, (rr[:, 2, 1] - rr[:, 1, 2]) / (2 * ss), (rr[:, 0, 2] - rr[:, 2, 0]) / (2 * ss),
                 (rr[:, 1, 0] - rr[:, 0, 1]) / (2 * ss)]
        elif idx == 1:
            q = [(rr[:, 2, 1] - rr[:, 1, 2]) / (2 * ss), 0.5 * ss, (rr[:, 0, 1] + rr[:, 1, 0]) / (2 * ss),
                 (rr[:, 0, 2] + rr[:, 2, 0]) / (2 * ss)]
        elif idx == 2:
            q = [(rr[:, 0, 2] - rr[:, 2, 0]) / (2 * ss), (rr[:, 0, 1] + rr[:, 1, 0]) / (2 * ss), 0.5 * ss,
                 (rr[:, 1, 2] + rr[:, 2, 1]) / (2 * ss)]
        else:
            q = [(rr[:, 1, 0] - rr[:, 0, 1]) / (2 * ss), (rr[:, 0, 2] + rr[:, 2, 0]) / (2 * ss),
                 (rr[:, 1, 2] + rr[:, 2, 1]) / (2 * ss), 0.5 * ss]
        out[m] = np.stack(q, axis=-1)
    out /= np.linalg.norm(out, axis=-1, keepdims=True)
    return canonical(out).reshape(R.shape[:-2] + (4,))


def canonical(q):
    """The representative of ``+-q`` with ``q0 > 0`` (ties broken on the first nonzero
    component), for comparing rotations."""
    q = np.asarray(q, dtype=np.float64)
    flat = q.reshape(-1, 4)
    nz = flat != 0.0
    first = np.where(nz.any(axis=1), np.argmax(nz, axis=1), 0)
    sign = np.sign(flat[np.arange(len(flat)), first])
    sign[sign == 0] = 1.0
    return (flat * sign[:, None]).reshape(q.shape)


def angle_between(a, b):
    """Rotation angle (rad, in ``[0, pi]``) of ``a~ b``: the attitude distance, blind to the
    sign of either quaternion."""
    a = normalize(a)
    b = normalize(b)
    # the angle phi between the unit 4-vectors is half the rotation angle, and
    # phi = 2 atan2(|a - b|, |a + b|) is accurate for small angles where acos|a.b| is not
    s = np.where(dot(a, b) < 0, -1.0, 1.0)[..., None]
    return 4.0 * np.arctan2(norm(a - s * b), norm(a + s * b))


def from_axis_angle(axis, angle):
    """``(cos(angle/2), sin(angle/2) n)`` for the unit vector ``n`` along ``axis``."""
    axis = _as_vector(axis, "axis")
    n = np.linalg.norm(axis, axis=-1)
    if np.any(n == 0.0):
        raise InputError("axis: the zero vector has no direction; give a nonzero rotation axis")
    angle = np.asarray(angle, dtype=np.float64)
    h = 0.5 * angle
    return np.concatenate([np.cos(h)[..., None], (np.sin(h) / n)[..., None] * axis], axis=-1)


def to_axis_angle(q):
    """``(axis, angle)`` with ``angle`` in ``[0, pi]``; the axis is ``(1, 0, 0)`` for the
    identity."""
    q = canonical(normalize(q))
    v = q[..., 1:]
    nv = np.linalg.norm(v, axis=-1)
    angle = 2.0 * np.arctan2(nv, q[..., 0])
    safe = np.where(nv > 0, nv, 1.0)
    axis = np.where((nv > 0)[..., None], v / safe[..., None], np.array([1.0, 0.0, 0.0]))
    return axis, angle


def from_rotvec(rv):
    """Quaternion of the rotation vector ``rv`` (axis times angle, rad): ``exp((0, rv/2))``."""
    rv = _as_vector(rv, "rotvec")
    return exp(pure(0.5 * rv))


def to_rotvec(q):
    """Rotation vector (axis times angle in ``[0, pi]``)."""
    axis, angle = to_axis_angle(q)
    return axis * angle[..., None]


def from_euler313(phi, theta, psi):
    """Quaternion of the paper's 3-1-3 Euler angles (eq. 12): ``q_z(phi) q_x(theta) q_z(psi)``.

    ``q0 = cos(theta/2) cos((phi+psi)/2)``, ``q1 = sin(theta/2) cos((phi-psi)/2)``,
    ``q2 = sin(theta/2) sin((phi-psi)/2)``, ``q3 = cos(theta/2) sin((phi+psi)/2)``.
    """
    phi, theta, psi = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (phi, theta, psi)))
    ct = np.cos(0.5 * theta)
    st = np.sin(0.5 * theta)
    sp = 0.5 * (phi + psi)
    sm = 0.5 * (phi - psi)
    return np.stack([ct * np.cos(sp), st * np.cos(sm), st * np.sin(sm), ct * np.sin(sp)], axis=-1)


def to_euler313(q):
    """3-1-3 Euler angles ``(phi, theta, psi)`` of ``q`` (eq. 13), each of shape ``(...)``.

    ``theta = 2 atan2(sqrt(q1^2 + q2^2), sqrt(q0^2 + q3^2))`` in ``[0, pi]``,
    ``phi + psi = 2 atan2(q3, q0)``, ``phi - psi = 2 atan2(q2, q1)``; angles wrapped to
    ``(-pi, pi]``. At the singular ``theta = 0`` (resp. ``pi``) only ``phi + psi``
    (resp. ``phi - psi``) is defined: ``psi = 0`` is returned there, never NaN.
    """
    q = normalize(q)
    q0, q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    a = np.hypot(q0, q3)
    b = np.hypot(q1, q2)
    theta = 2.0 * np.arctan2(b, a)
    sp = np.arctan2(q3, q0)
    sm = np.arctan2(q2, q1)
    za = a == 0.0
    zb = b == 0.0
    # phi and psi side by side: one wrap for both (elementwise, the same values)
    both = np.empty((2,) + sp.shape)
    if za.any() or zb.any():
        sp = np.where(za, 0.0, sp)
        sm = np.where(zb, 0.0, sm)
        # at theta = pi (a = 0), phi - psi = 2 sm alone is defined; psi := 0
        both[0] = np.where(za, 2.0 * sm, np.where(zb, 2.0 * sp, sp + sm))
        both[1] = np.where(za | zb, 0.0, sp - sm)
    else:  # the generic case: what the np.where above select
        np.add(sp, sm, out=both[0, ...])
        np.subtract(sp, sm, out=both[1, ...])
    wrapped = _wrap(both)
    return wrapped[0], theta, wrapped[1]


def _wrap(x):
    """``x`` wrapped to ``(-pi, pi]``: the argument of ``exp(i x)`` (``np.angle``)."""
    z = np.exp(1j * x)
    return np.arctan2(z.imag, z.real)


def to_euler321(q):
    """3-2-1 (yaw, pitch, roll) angles of ``q``, returned in the order ``(roll, pitch, yaw)``.

    The sequence: ``q = q_z(yaw) q_y(pitch) q_x(roll)`` with ``q_k(a) = (cos a/2, sin a/2 e_k)``.
    For the attitude of ``B`` relative to a frame ``F`` (``x_F = q x_B q~``; ``F = O`` for
    ``q_orbital``): turn the ``F`` axes by ``yaw`` about axis 3, then by ``pitch`` about the new
    axis 2, then by ``roll`` about the new axis 1; the result is the ``B`` axes (intrinsic
    z-y'-x'', the aerospace convention; scipy's ``Rotation.as_euler("ZYX")`` gives
    ``(yaw, pitch, roll)``).

    Parameters
    ----------
    q : array-like (..., 4)
        Quaternions, scalar first (normalized here).

    Returns
    -------
    roll, pitch, yaw : ndarray (...)
        rad; ``roll, yaw`` in ``(-pi, pi]``, ``pitch`` in ``[-pi/2, pi/2]``. At the singular
        ``pitch = +-pi/2`` only ``yaw -+ roll`` is defined: ``roll = 0`` is returned there
        (when ``cos(pitch) < sqrt(eps)``), never NaN.
    """
    q = normalize(q)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    if q.ndim >= 2 and 0 < q.size <= _TINY:  # a few quaternions: the terms below in Python floats
        r21, r22, r20, yn, yd = _euler321_terms(q)
    else:
        r21 = 2.0 * (w * x + y * z)  # sin(roll) cos(pitch)
        r22 = 1.0 - 2.0 * (x * x + y * y)  # cos(roll) cos(pitch)
        r20 = 2.0 * (w * y - x * z)  # sin(pitch)
        yn, yd = 2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)
    cp = np.hypot(r21, r22)
    pitch = np.arctan2(r20, cp)
    lock = cp < _SQRT_EPS
    roll = np.arctan2(r21, r22)
    yaw_generic = np.arctan2(yn, yd)
    if not lock.any():  # no gimbal lock: what the np.where below select (arrays, as there)
        return np.asarray(roll), pitch, np.asarray(yaw_generic)
    roll = np.where(lock, 0.0, roll)
    # with roll = 0: R = Rz(yaw) Ry(pitch), R01 = -sin(yaw), R11 = cos(yaw)
    yaw_lock = np.arctan2(-2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z))
    yaw = np.where(lock, yaw_lock, yaw_generic)
    return roll, pitch, yaw


def _euler321_terms(q):
    """The arguments of :func:`to_euler321`'s ``arctan2`` calls (``r21, r22, r20`` and yaw's
    two) of the quaternions ``q (..., 4)``, computed in Python floats with the same operations
    in the same order (the same values), as new float64 arrays of shape ``q.shape[:-1]``."""
    terms = [(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y), 2.0 * (w * y - x * z),
              2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)) for w, x, y, z in q.reshape(-1, 4).tolist()]
    rows = np.array(list(zip(*terms)), dtype=np.float64)  # (5, n): each row contiguous
    return tuple(row.reshape(q.shape[:-1]) for row in rows)


#: the gimbal-lock threshold of :func:`to_euler321` on ``cos(pitch)``
_SQRT_EPS = float(np.sqrt(np.finfo(np.float64).eps))


def to_scipy(q):
    """:class:`scipy.spatial.transform.Rotation` of ``q`` (reordered to scalar last)."""
    from scipy.spatial.transform import Rotation

    q = normalize(q)
    return Rotation.from_quat(np.concatenate([q[..., 1:], q[..., :1]], axis=-1))


def from_scipy(rotation):
    """Scalar-first quaternion(s) of a scipy ``Rotation`` (which stores scalar last)."""
    x = np.asarray(rotation.as_quat(), dtype=np.float64)
    return np.concatenate([x[..., 3:], x[..., :3]], axis=-1)

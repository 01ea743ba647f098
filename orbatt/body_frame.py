"""The body (mechanical) frame ``B`` of a full inertia tensor and its principal frame ``P``.

An ADCS engineer gives the inertia tensor about the centre of mass in the spacecraft's body
frame ``B``, as CAD gives it; orbatt's kernels integrate the body in principal axes (the
moments ``(I1, I2, I3)`` of eq. 7). :func:`principal_axes` finds the principal frame ``P`` of a
tensor once, and :class:`BodyFrame` holds the change of frame,

    ``x_B = R x_P``,  ``I_B = R diag(I1, I2, I3) R^T``,  ``r`` the unit quaternion of ``R``
    (``R x = r x r~``, :func:`orbatt.quaternion.to_matrix`),

so that an attitude ``q`` (body -> space, ``x_S = q x q~``, ``docs/design.md`` §1) and its
momentum transform as ``q_P = q_B r``, ``Q_P = Q_B r`` (quaternion products): ``x_S = q_B x_B
q_B~ = q_B r x_P r~ q_B~``, and ``Q_P = 2 q_P g_P = 2 q_B r (r~ g_B r) = Q_B r``. Body vectors
(rates, torques, facet normals, wheel axes, dipoles) transform as ``v_P = R^T v_B``.

The tensor's convention: its off-diagonal entries are the matrix's, ``I_xy = -∫ x y dm`` (the
products of inertia with their minus sign). Six values ``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` are
those entries.

The principal frame, deterministically (:func:`principal_axes`):

* a **diagonal** tensor (every off-diagonal entry exactly 0) has ``P = B``: the moments are its
  diagonal in the given order and there is no :class:`BodyFrame` (``None``) - the run is the
  principal-axes run of today, bit for bit;
* otherwise ``numpy.linalg.eigh``; a degenerate pair of moments (equal to 1e-10 relative: an
  axisymmetric body) gets the basis of its plane made from the body axes (the body axis with
  the largest projection on the plane, then the cross product), not LAPACK's arbitrary one;
  principal axis ``k`` is the eigenvector closest to body axis ``k`` (the permutation with the
  largest sum of squared cosines ``sum_k R_kk^2``, ties to 1e-9 going to the first in
  :func:`itertools.permutations` order), signed so that ``R_kk >= 0`` for ``k = 1, 2`` and
  ``P`` right-handed (``det R = +1``: the third axis is the cross product of the first two).
  So a nearly diagonal tensor keeps its moments in the order of its body axes, and ``R`` is
  near the identity. LAPACK may differ in the last bits between CPUs; outputs in ``B`` agree to
  round-off, and nothing is rounded.

The boundary (:mod:`orbatt.frame_boundary`) rotates every body-frame input into ``P`` where it
enters the kernel model and every body-axes output back to ``B``.
"""
from __future__ import annotations

import copy
import itertools

import numpy as np

from . import quaternion as qt
from .errors import InputError

__all__ = ["BodyFrame", "principal_axes", "inertia_tensor", "is_diagonal", "SYMMETRY_TOLERANCE",
           "DEGENERATE_TOLERANCE", "SIX_VALUES"]

#: a tensor whose ``|I - I^T|`` exceeds this times ``max |I|`` is refused (not symmetric)
SYMMETRY_TOLERANCE = 1e-12
#: two principal moments closer than this (relative to the largest) are one degenerate pair
DEGENERATE_TOLERANCE = 1e-10
#: the order of the six-value form: the matrix entries (row, column)
SIX_VALUES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
#: near-ties of the axis assignment (sums of squared cosines) go to the first permutation
_TIE = 1e-9


def is_diagonal(tensor):
    """Whether every off-diagonal entry of the ``(3, 3)`` ``tensor`` is exactly 0."""
    t = np.asarray(tensor, dtype=np.float64)
    return not np.any(t[~np.eye(3, dtype=bool)])


def inertia_tensor(values, name="inertia", unit="kg km^2"):
    """The ``(3, 3)`` tensor of ``values`` (a ``(3, 3)`` matrix or the six values
    :data:`SIX_VALUES` ``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]``, floats), checked finite and symmetric
    (to :data:`SYMMETRY_TOLERANCE` relative; the mean of ``I`` and ``I^T`` is kept).

    Raises
    ------
    InputError
        Another shape, a non-finite value, or an asymmetric matrix (naming ``name``, the
        values in ``unit`` and the fix).
    """
    v = np.asarray(values, dtype=np.float64)
    if v.shape == (6,):
        t = np.empty((3, 3))
        for k, (i, j) in enumerate(SIX_VALUES):
            t[i, j] = t[j, i] = v[k]
    elif v.shape == (3, 3):
        t = v.copy()
    else:
        raise InputError(f"{name}: expected the principal moments [I1, I2, I3], a 3x3 tensor [[Ixx, Ixy, Ixz], "
                         f"[Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] or six values [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], got shape "
                         f"{v.shape}")
    if not np.all(np.isfinite(t)):
        raise InputError(f"{name}: {t.tolist()} has non-finite entries; give finite values")
    scale = float(np.max(np.abs(t)))
    asym = float(np.max(np.abs(t - t.T)))
    if asym > SYMMETRY_TOLERANCE * scale:
        raise InputError(f"{name}: the tensor {t.tolist()} ({unit}) is not symmetric (|I - I^T| = {asym:.3g}); an "
                         "inertia tensor has I_ij = I_ji: give the same product of inertia above and below the "
                         "diagonal")
    if asym:
        t = 0.5 * (t + t.T)
    return t


def _unit_columns(v):
    return v / np.linalg.norm(v, axis=0, keepdims=True)


def _degenerate_basis(w, V):
    """Eigenvalues and vectors with the plane of a degenerate pair spanned by a basis made
    from the body axes (module docstring); unchanged without such a pair."""
    top = float(np.max(np.abs(w)))
    for a, b in ((0, 1), (1, 2)):
        if abs(w[b] - w[a]) <= DEGENERATE_TOLERANCE * top:
            c = 3 - a - b  # the distinct moment
            u_ = V[:, c]
            proj = np.eye(3) - np.outer(u_, u_)
            lengths = np.linalg.norm(proj, axis=0)
            k = int(np.flatnonzero(lengths >= lengths.max() - _TIE)[0])
            e1 = proj[:, k] / lengths[k]
            e2 = np.cross(u_, e1)
            m = 0.5 * (w[a] + w[b])
            return np.array([w[c], m, m]), np.column_stack([u_, e1, e2])
    return w, V


def principal_axes(tensor):
    """``(moments (3,), R (3, 3) or None)``: the principal moments of the symmetric ``tensor``
    and the matrix ``R`` whose columns are the principal axes in body components (``x_B = R
    x_P``; a proper rotation), in the order and with the signs of the module docstring; a
    diagonal tensor gives its diagonal and ``None`` (``P = B``)."""
    t = np.asarray(tensor, dtype=np.float64)
    if is_diagonal(t):
        return t.diagonal().copy(), None
    w, V = np.linalg.eigh(t)
    w, V = _degenerate_basis(w, V)
    V = _unit_columns(V)
    best, order = -1.0, None
    for p in itertools.permutations(range(3)):
        score = sum(V[k, p[k]] ** 2 for k in range(3))
        if score > best + _TIE:
            best, order = score, p
    w, V = w[list(order)], V[:, list(order)]
    for k in range(2):
        col = V[:, k]
        lead = col[k] if abs(col[k]) > _TIE else col[np.flatnonzero(np.abs(col) > _TIE)[0]]
        if lead < 0:
            V[:, k] = -col
    V[:, 2] = np.cross(V[:, 0], V[:, 1])
    return np.array(w, dtype=np.float64), V


class BodyFrame:
    """The change of frame between the user's body frame ``B`` and the principal frame ``P``
    of an inertia tensor (module docstring): ``x_B = R x_P``, ``q_P = q_B r``.

    Parameters
    ----------
    tensor : ndarray (3, 3)
        The inertia tensor in ``B`` (internal unit), symmetric and not diagonal.
    moments : ndarray (3,)
        Its principal moments (:func:`principal_axes`).
    axes : ndarray (3, 3)
        The principal axes as columns in body components (:func:`principal_axes`).

    Attributes
    ----------
    r : ndarray (4,)
        The unit quaternion of the rotation (scalar first, ``r0 >= 0``).
    R : ndarray (3, 3)
        Its matrix ``R x = r x r~`` (made from ``r``, so that vectors and attitudes turn by the
        same rotation to the last bits).
    """

    def __init__(self, tensor, moments, axes):
        self.tensor = np.array(tensor, dtype=np.float64)
        self.moments = np.array(moments, dtype=np.float64)
        self.r = qt.from_matrix(axes)
        self.R = qt.to_matrix(self.r)
        for a in (self.tensor, self.moments, self.r, self.R):
            a.flags.writeable = False

    # vectors: v_P = R^T v_B, v_B = R v_P (the last axis holds the components)
    def to_principal(self, v):
        """Body-frame vectors ``v (..., 3)`` in principal components: ``R^T v``."""
        return np.asarray(v, dtype=np.float64) @ self.R

    def to_body(self, v):
        """Principal-frame vectors ``v (..., 3)`` in body components: ``R v``."""
        return np.asarray(v, dtype=np.float64) @ self.R.T

    # attitudes and momenta (body -> space): q_P = q_B r, q_B = q_P r~
    def attitude_to_principal(self, q):
        """``q_B r`` of attitudes (or conjugate momenta ``Q``) ``(..., 4)`` of ``B``."""
        return qt.mul(np.asarray(q, dtype=np.float64), self.r)

    def attitude_to_body(self, q):
        """``q_P r~`` of attitudes (or conjugate momenta ``Q``) ``(..., 4)`` of ``P``."""
        return qt.mul(np.asarray(q, dtype=np.float64), qt.conj(self.r))

    def times_tensor(self, omega):
        """``I_B omega`` (body components) of body rates ``omega (..., 3)``, through ``P``."""
        return self.to_body(self.to_principal(omega) * self.moments)

    def solve_tensor(self, g):
        """``I_B^-1 g`` (body components) of body momenta ``g (..., 3)``, through ``P``."""
        return self.to_body(self.to_principal(g) / self.moments)

    def principal_state(self, state):
        """A copy of the :class:`~orbatt.State` ``state`` of a body with this frame in ``P``: the
        body's :attr:`~orbatt.RigidBody.principal` body, ``q_B r``, ``Q_B r``; what else it
        carries (a continued run's time, wheels' momenta, commands) as it is."""
        out = copy.copy(state)
        out.body = state.body.principal
        out.q, out.Q = self.attitude_to_principal(state.q), self.attitude_to_principal(state.Q)
        return out

    def key(self):
        """Bytes that identify the frame (two bodies share a kernel model only if equal)."""
        return self.r.tobytes()

    def __eq__(self, other):
        return isinstance(other, BodyFrame) and np.array_equal(self.tensor, other.tensor) and np.array_equal(
            self.r, other.r)

    def __hash__(self):
        return hash((self.tensor.tobytes(), self.r.tobytes()))

    def __repr__(self):
        return f"BodyFrame(r={self.r.tolist()}, moments={self.moments.tolist()})"

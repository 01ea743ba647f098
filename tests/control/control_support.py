"""Helpers shared by the control tests: the outputs of the extended right-hand side along a
trajectory, and attitude errors."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from orbatt import quaternion as qt
from orbatt.core.gyrostat import evaluate_extended
from orbatt.core.potentials import WORK_SIZE
from orbatt.methods.problem import kernel_spec

#: N m per internal torque unit (kg km^2 s^-2); A m^2 per internal dipole unit
N_M = 1e6
A_M2 = 1e6


class Outputs(NamedTuple):
    omega: np.ndarray   # (N, 3) body rate, rad/s, body axes
    h: np.ndarray       # (N, 3) wheels' momentum, N m s, body axes
    tau: np.ndarray     # (N, 3) torque the control applies to the body, N m, body axes
    m: np.ndarray       # (N, 3) B-dot dipole, A m^2, body axes
    u: np.ndarray       # (N, n) motor torques, N m


def outputs(tr, env):
    """:func:`orbatt.core.gyrostat.evaluate_extended` on a trajectory of ``env`` (SI units)."""
    k = kernel_spec(env, [tr.body])
    Y = np.hstack([tr.q, tr.Q] + ([tr.wheel_momenta] if tr.wheel_momenta is not None else []))
    omega, h, tau, m, u = evaluate_extended(tr.t, np.ascontiguousarray(Y), tr.body.inertia_value, k.terms,
                                            k.params, k.table, np.zeros(WORK_SIZE))
    return Outputs(omega, h * 1e6, tau * N_M, m * A_M2, u * N_M)


def angle(qa, qb):
    """Rotation angle (rad) between attitudes, precise for small angles."""
    d = qt.mul(qt.conj(qa), qb)
    return 2.0 * np.arcsin(np.minimum(1.0, np.linalg.norm(d[..., 1:], axis=-1)))


def rotation(axis, angle_rad):
    """The unit quaternion of a rotation by ``angle_rad`` about ``axis``."""
    return qt.from_axis_angle(np.asarray(axis, dtype=float), angle_rad)

"""Conservative terms: potentials ``U(q, t)`` and their tangential gradients (compiled, no
units), and the body torque of a gradient.

Every potential is extended off the unit sphere as a function of ``q/|q|`` (``docs/design.md``
§2): for a raw formula ``U_raw`` homogeneous of degree ``k`` in ``q``,
``U(q) = U_raw(q) / |q|^k`` and ``dU/dq = (grad U_raw - (q.grad U_raw) q / |q|^2) / |q|^k``.
With this gradient ``|q| = 1`` and ``q.Q = 0`` are invariants of Hamilton's equations.

The kernels here are the terms of the model (:mod:`orbatt.core.model`, which dispatches on
kinds and supplies the orbit); they are inlined into the step loops.

Kernel specification of a potential (the older, one-potential form that the API objects
``orbatt.TorqueFree``, ``HeavyTop``, ``GravityGradient`` still expose as ``kind``, ``params``,
``table``; :func:`orbatt.core.model.from_spec` converts it to a model):

==================  ====  =====================================================================
kind                code  params
==================  ====  =====================================================================
torque-free         0     (unused)
heavy top (eq. 18)  1     ``[s Mg, xc1, xc2, xc3]``; ``U = s Mg (q x_c q~)_3``, ``s = +1``
                          physical (gravity along ``-s3``), ``s = -1`` the paper's printed sign
gravity gradient,   2     ``[GM, a, e, inc, raan, argp, M0, n, ...]``: ``GM`` then the
Keplerian orbit           ``orb`` vector of ``orbatt.core.kepler`` (derived entries appended by
                          ``orbit_vector``); ``U = (3 GM / 2 r^3) x_B.(I x_B)``, eq. 20
gravity gradient,   3     ``[GM, t_first, t_last]``; ``table`` = the samples
sampled orbit             ``[t, x, y, z, vx, vy, vz, ax, ay, az]`` of ``orbatt.core.sampled``
                          (quintic Hermite in time; REBOUND orbits)
==================  ====  =====================================================================

Orbit-driven kernels take ``work``, a per-trajectory float64 scratch array of length
:data:`WORK_SIZE` filled with NaN at the start of a run (warm starts of Kepler's equation
and of the sampled orbit's interval search; see :func:`new_work`).
"""
from __future__ import annotations

import numpy as np

from ._jit import jit_inline
from .qalg import pure_qmul, qconj, qdot, qmul, qmul_pure, qscale

TORQUE_FREE = 0
HEAVY_TOP = 1
GRAVITY_GRADIENT_KEPLER = 2
GRAVITY_GRADIENT_SAMPLED = 3

EMPTY_TABLE = np.zeros((0, 0), dtype=np.float64)
#: most terms of one model that own a sampled table (an environment field, a control law's
#: field or Sun): each keeps its interval in a slot of ``work``
MAX_TABLE_TERMS = 28
#: most switching functions of one model the step loops locate (:mod:`orbatt.core.switches`)
MAX_SWITCHES = 40
#: the first scratch slot of the switching functions' references
SWITCH_SLOT = 4 + MAX_TABLE_TERMS
#: scratch slots: 0..2 Kepler's warm start, 3 the sampled orbit, 4.. the tables of the terms,
#: then the switching functions' references (:mod:`orbatt.core.switches`)
WORK_SIZE = SWITCH_SLOT + MAX_SWITCHES


def new_work(*batch):
    """Fresh scratch array(s) of shape ``batch + (WORK_SIZE,)``, all NaN."""
    return np.full(batch + (WORK_SIZE,), np.nan)


@jit_inline
def _tangential(q, graw, degree):
    """Gradient of ``U_raw(q/|q|)`` from the raw gradient of a degree-``degree`` form."""
    n2 = qdot(q, q)
    c = qdot(q, graw) / n2
    s = 1.0 / n2 ** (0.5 * degree)
    return (
        s * (graw[0] - c * q[0]),
        s * (graw[1] - c * q[1]),
        s * (graw[2] - c * q[2]),
        s * (graw[3] - c * q[3]),
    )


@jit_inline
def heavy_top(q, params):
    """Heavy top, eq. (18) with the sign chosen in ``params[0]``. Returns ``(U, dU/dq)``."""
    smg = params[0]
    X = (params[1], params[2], params[3])  # the pure quaternion (0, X)
    # U_raw = s Mg (q X q~)_3 ; grad U_raw = -2 s Mg s3 q X (pure quaternions s3, X)
    qX = qmul_pure(q, X)
    w = qmul(qX, qconj(q))
    graw = qscale(-2.0 * smg, pure_qmul((0.0, 0.0, 1.0), qX))
    n2 = qdot(q, q)
    return smg * w[3] / n2, _tangential(q, graw, 2)


@jit_inline
def gravity_gradient(q, inertia, k, xhat):
    """MacCullagh potential, eq. (20), for ``k = GM / r^3`` and radial unit vector ``xhat``
    (inertial components). Returns ``(U, dU/dq)``."""
    xb = qmul(qmul_pure(qconj(q), xhat), q)
    Y = (inertia[0] * xb[1], inertia[1] * xb[2], inertia[2] * xb[3])  # the pure quaternion (0, I xb)
    uraw = 1.5 * k * (xb[1] * Y[0] + xb[2] * Y[1] + xb[3] * Y[2])
    graw = qscale(-6.0 * k, qmul_pure(pure_qmul(xhat, q), Y))
    n2 = qdot(q, q)
    return uraw / (n2 * n2), _tangential(q, graw, 4)


@jit_inline
def torque_from_gradient(q, grad):
    """Body-frame torque ``tau = -1/2 Im(q~ dU/dq)`` for a unit ``q``."""
    w = qmul(qconj(q), grad)
    return (-0.5 * w[1], -0.5 * w[2], -0.5 * w[3])

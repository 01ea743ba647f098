"""The full two-body problem to second order (a binary asteroid): the relative orbit and the
attitudes of both bodies integrated together (``docs/design.md`` §12).

Bodies: the primary (mass ``M1``, principal moments ``I1``, attitude ``q1``) and the secondary
(``M2``, ``I2``, attitude ``q``); ``r`` the relative position primary -> secondary in the
inertial frame ``S``, ``mu = M1 M2 / (M1 + M2)`` the reduced mass, ``p = mu dr/dt``. The
attitudes are the canonical pairs of ``docs/design.md`` §2 (``q`` body -> inertial, scalar first,
``Q = 2 q g``, ``g`` the body-axes angular momentum).

Mutual potential (MacCullagh on both bodies; the secondary's term is eq. 20)::

    U = -G M1 M2 / r - G M1 / (2 r^3) (tr I2 - 3 rhat.I2^S rhat)
                     - G M2 / (2 r^3) (tr I1 - 3 rhat.I1^S rhat),   Ik^S = R(qk) diag(Ik) R(qk)^T

Hamiltonian ``H = |p|^2 / (2 mu) + T(q, Q) + T1(q1, Q1) + U`` and its equations::

    dr/dt = p / mu,    dp/dt = -dU/dr,
    dU/dr = G M1 M2 r / r^3 + 3 G M1 / (2 r^5) [tr I2 r + 2 I2^S r - 5 (rhat.I2^S rhat) r]
                            + 3 G M2 / (2 r^5) [tr I1 r + 2 I1^S r - 5 (rhat.I1^S rhat) r]
    dq/dt = 1/4 q (0, 2 omega),  dQ/dt = 1/4 Q (0, 2 omega) + 2 q (0, tau_B)       (eq. 7, §10)

with ``omega = g / I`` and the gravity-gradient torque on each body in its own axes,
``tau_B = 3 G M_other / r^5 (r_B x I r_B)``, ``r_B = q~ r q`` (the torque's generalized force
``-2 q (0, tau_B)``, :func:`orbatt.core.torques.gradient_of_torque`, keeps ``q.Q = 0`` exactly).
The invariants: ``H`` (:func:`energy`) and the total angular momentum about the barycentre
``L = r x p + q g q~ + q1 g1 q1~`` (:func:`angular_momentum`; the orbital part ``mu r x dr/dt``).

State ``y`` (float64), in the caller's consistent units (the API uses kg, km, s):

==========  ========  ===========================================================
slice       length    content
==========  ========  ===========================================================
``0:3``     3         ``r`` (inertial)
``3:6``     3         ``p = mu dr/dt`` (inertial)
``6:10``    4         ``q`` of the secondary
``10:14``   4         ``Q`` of the secondary
``14:18``   4         ``q1`` of the primary (only with a rigid primary)
``18:22``   4         ``Q1`` of the primary (only with a rigid primary)
==========  ========  ===========================================================

A point-mass primary (no ``[primary]``) has the 14-component state: ``q1, Q1`` are not
integrated, and its term of ``U`` is zero. The constants ``c`` (:func:`constants`) hold ``G``,
the masses, ``mu``, the moments and the per-component scale of the absolute tolerance that
the step loop of :mod:`orbatt.core.dop853` reads (:data:`C_ATOL`).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline
from .qalg import qconj, qmul, qmul_pure, rotate, rotate_inv
from .torques import gradient_of_torque

__all__ = ["C_G", "C_M1", "C_M2", "C_MU", "C_FULL", "C_CONTACT2", "C_I2", "C_I1", "C_ATOL", "C_SIZE", "N_POINT", "N_RIGID", "constants",
           "rhs_coupled", "hinit_norms_vec", "hinit_der2_vec", "potential", "potential_gradient", "torques", "energy", "angular_momentum", "evaluate"]

#: slots of the constants ``c``: ``G``, ``M1``, ``M2``, the reduced mass, the model (1: the
#: full mutual potential; 0: the secondary's torque only, :func:`constants`), the square of the
#: contact distance, the secondary's and the primary's principal moments (zeros for a point-mass
#: primary), and from ``C_ATOL`` the scale of each state component's absolute tolerance
#: (``atol * c[C_ATOL + i]``)
C_G, C_M1, C_M2, C_MU, C_FULL, C_CONTACT2, C_I2, C_I1, C_ATOL = 0, 1, 2, 3, 4, 5, 6, 9, 12
#: state lengths: point-mass primary, rigid primary
N_POINT, N_RIGID = 14, 22
C_SIZE = C_ATOL + N_RIGID


def constants(G, M1, M2, I2, I1=None, length_scale=1.0, momentum_scale=1.0, full=True, contact=0.0):
    """The constants array ``c`` of the kernels (plain floats, the caller's units).

    Parameters
    ----------
    G : float
        Gravitational constant (e.g. km^3 kg^-1 s^-2).
    M1, M2 : float
        Masses of the primary and the secondary.
    I2, I1 : (3,) float
        Principal moments of the secondary and of the primary (None: a point-mass primary).
    length_scale, momentum_scale : float
        The absolute tolerance of ``r`` is ``atol * length_scale`` and that of ``p``
        ``atol * momentum_scale`` (the driver gives the initial separation and ``mu`` times
        the circular speed there); ``q``, ``q1``: ``atol``; ``Q``: ``atol * max(I2)``, ``Q1``:
        ``atol * max(I1)`` (a body rate, as for the single body).
    full : bool
        True: the mutual potential of the module docstring. False (``[potential] kind =
        "gravity-gradient"`` with a coupled orbit): the orbit feels the point masses only
        (Keplerian about ``G (M1 + M2)``), the secondary the torque of eq. 20, the primary no
        torque; ``U`` keeps the secondary's term, so the energy is not an invariant then.
    contact : float
        The separation at which the bodies touch: :func:`rhs_coupled` returns NaN at or below it,
        so that the step loop cannot step past a contact (it stops with its non-finite status).
    """
    c = np.zeros(C_SIZE)
    c[C_G], c[C_M1], c[C_M2] = G, M1, M2
    c[C_MU] = M1 * M2 / (M1 + M2)
    c[C_FULL] = 1.0 if full else 0.0
    c[C_CONTACT2] = contact * contact
    c[C_I2:C_I2 + 3] = I2
    if I1 is not None:
        c[C_I1:C_I1 + 3] = I1
    scale = np.ones(N_RIGID)
    scale[0:3] = length_scale
    scale[3:6] = momentum_scale
    scale[10:14] = max(I2)
    scale[18:22] = max(I1) if I1 is not None else 1.0
    c[C_ATOL:] = scale
    return c


@jit_inline
def _inertia_term(rb, I):
    """``(tr I, rhat.I rhat r^2 = r_B.I r_B, I r_B)`` for ``r_B`` in body axes."""
    Ir = (I[0] * rb[0], I[1] * rb[1], I[2] * rb[2])
    return I[0] + I[1] + I[2], rb[0] * Ir[0] + rb[1] * Ir[1] + rb[2] * Ir[2], Ir


@jit_inline
def _body(y, k, c, ci):
    """``(q, Q)`` of the body whose quaternion starts at ``y[k]`` and its moments ``c[ci:ci+3]``."""
    return ((y[k], y[k + 1], y[k + 2], y[k + 3]), (y[k + 4], y[k + 5], y[k + 6], y[k + 7]),
            (c[ci], c[ci + 1], c[ci + 2]))


@jit_inline
def potential_gradient(y, c):
    """``(U, dU/dr, tau2_B, tau1_B)``: the mutual potential, its gradient in ``r`` (inertial)
    and the torques on the secondary and on the primary in their own body axes (zero torque
    on a point-mass primary, ``len(y) == 14``). With ``c[C_FULL] == 0`` (:func:`constants`'s
    ``full``) the gradient is the point masses' and the primary has no term."""
    G, M1, M2 = c[C_G], c[C_M1], c[C_M2]
    r = (y[0], y[1], y[2])
    r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    rn = math.sqrt(r2)
    ir2 = 1.0 / r2
    ir3 = ir2 / rn
    ir5 = ir3 * ir2
    U = -G * M1 * M2 / rn
    gk = G * M1 * M2 * ir3
    d = (gk * r[0], gk * r[1], gk * r[2])
    # the secondary's term (eq. 20), with M1
    q, _, I2 = _body(y, 6, c, C_I2)
    rb = rotate_inv(q, r)
    tr, rIr, Ir = _inertia_term(rb, I2)
    U -= 0.5 * G * M1 * ir3 * (tr - 3.0 * rIr * ir2)
    IrS = rotate(q, Ir)  # I2^S r
    a = 1.5 * G * M1 * ir5
    b = tr - 5.0 * rIr * ir2
    full = c[C_FULL] != 0.0
    if full:
        d = (d[0] + a * (b * r[0] + 2.0 * IrS[0]), d[1] + a * (b * r[1] + 2.0 * IrS[1]),
             d[2] + a * (b * r[2] + 2.0 * IrS[2]))
    s = 3.0 * G * M1 * ir5
    tau2 = (s * (rb[1] * Ir[2] - rb[2] * Ir[1]), s * (rb[2] * Ir[0] - rb[0] * Ir[2]),
            s * (rb[0] * Ir[1] - rb[1] * Ir[0]))
    tau1 = (0.0, 0.0, 0.0)
    if full and y.shape[0] > N_POINT:  # the primary's term, with M2
        q1, _, I1 = _body(y, 14, c, C_I1)
        rb = rotate_inv(q1, r)
        tr, rIr, Ir = _inertia_term(rb, I1)
        U -= 0.5 * G * M2 * ir3 * (tr - 3.0 * rIr * ir2)
        IrS = rotate(q1, Ir)
        a = 1.5 * G * M2 * ir5
        b = tr - 5.0 * rIr * ir2
        d = (d[0] + a * (b * r[0] + 2.0 * IrS[0]), d[1] + a * (b * r[1] + 2.0 * IrS[1]),
             d[2] + a * (b * r[2] + 2.0 * IrS[2]))
        s = 3.0 * G * M2 * ir5
        tau1 = (s * (rb[1] * Ir[2] - rb[2] * Ir[1]), s * (rb[2] * Ir[0] - rb[0] * Ir[2]),
                s * (rb[0] * Ir[1] - rb[1] * Ir[0]))
    return U, d, tau2, tau1


@jit
def potential(y, c):
    """The mutual potential ``U(r, q, q1)`` (module docstring)."""
    return potential_gradient(y, c)[0]


@jit
def torques(y, c):
    """``(dU/dr, tau2_B, tau1_B)`` as arrays (for tests and outputs)."""
    _, d, t2, t1 = potential_gradient(y, c)
    return np.array(d), np.array(t2), np.array(t1)


@jit_inline
def _rate(q, Q, I):
    """``(g, omega)``: the body momentum ``1/2 Im(q~ Q)`` and rate ``g / I`` (body axes)."""
    w = qmul(qconj(q), Q)
    g = (0.5 * w[1], 0.5 * w[2], 0.5 * w[3])
    return g, (g[0] / I[0], g[1] / I[1], g[2] / I[2])


@jit_inline
def _attitude_rates(y, k, c, ci, tau, dy):
    """``dq/dt, dQ/dt`` of the body at ``y[k:k+8]`` (eq. 7 with the torque ``tau``, body axes)."""
    q, Q, I = _body(y, k, c, ci)
    _, om = _rate(q, Q, I)
    a = (2.0 * om[0], 2.0 * om[1], 2.0 * om[2])
    qd = qmul_pure(q, a)
    Qd = qmul_pure(Q, a)
    Gt = gradient_of_torque(q, tau)
    for j in range(4):
        dy[k + j] = 0.25 * qd[j]
        dy[k + 4 + j] = 0.25 * Qd[j] - Gt[j]


@jit
def rhs_coupled(t, y, c, terms, params, table, work, dy):
    """``dy/dt`` of the coupled system (module docstring) into ``dy``; ``t`` is not used (the
    system is autonomous), nor are ``terms, params, table, work`` (the step loop's model
    arguments, kept for its one calling convention). NaN at or inside the contact distance."""
    if y[0] * y[0] + y[1] * y[1] + y[2] * y[2] <= c[C_CONTACT2]:
        for j in range(y.shape[0]):
            dy[j] = np.nan
        return
    _, d, tau2, tau1 = potential_gradient(y, c)
    imu = 1.0 / c[C_MU]
    for j in range(3):
        dy[j] = y[3 + j] * imu
        dy[3 + j] = -d[j]
    _attitude_rates(y, 6, c, C_I2, tau2, dy)
    if y.shape[0] > N_POINT:
        _attitude_rates(y, 14, c, C_I1, tau1, dy)


@jit_inline
def hinit_norms_vec(y, f, atol, c, rtol):
    """:func:`orbatt.core.step_control.hinit_norms` with the absolute tolerance ``atol * c[C_ATOL + i]``
    of each component (:func:`constants`)."""
    dnf = 0.0
    dny = 0.0
    for i in range(y.shape[0]):
        sk = atol * c[C_ATOL + i] + rtol * abs(y[i])
        a = f[i] / sk
        b = y[i] / sk
        dnf += a * a
        dny += b * b
    return dnf, dny


@jit_inline
def hinit_der2_vec(y, f0, f1, atol, c, rtol):
    """:func:`orbatt.core.step_control.hinit_der2` with the absolute tolerances of :func:`hinit_norms_vec`."""
    der2 = 0.0
    for i in range(y.shape[0]):
        d = (f1[i] - f0[i]) / (atol * c[C_ATOL + i] + rtol * abs(y[i]))
        der2 += d * d
    return der2


@jit
def energy(y, c):
    """The total energy ``H = |p|^2 / (2 mu) + T + T1 + U`` (conserved)."""
    H = (y[3] * y[3] + y[4] * y[4] + y[5] * y[5]) / (2.0 * c[C_MU]) + potential_gradient(y, c)[0]
    g, om = _rate((y[6], y[7], y[8], y[9]), (y[10], y[11], y[12], y[13]), (c[C_I2], c[C_I2 + 1], c[C_I2 + 2]))
    H += 0.5 * (g[0] * om[0] + g[1] * om[1] + g[2] * om[2])
    if y.shape[0] > N_POINT:
        g, om = _rate((y[14], y[15], y[16], y[17]), (y[18], y[19], y[20], y[21]),
                      (c[C_I1], c[C_I1 + 1], c[C_I1 + 2]))
        H += 0.5 * (g[0] * om[0] + g[1] * om[1] + g[2] * om[2])
    return H


@jit
def angular_momentum(y, c):
    """The total angular momentum about the barycentre, inertial: ``r x p + q g q~ (+ q1 g1
    q1~)`` (conserved), a (3,) array."""
    L = np.empty(3)
    L[0] = y[1] * y[5] - y[2] * y[4]
    L[1] = y[2] * y[3] - y[0] * y[5]
    L[2] = y[0] * y[4] - y[1] * y[3]
    n = 2 if y.shape[0] > N_POINT else 1
    for b in range(n):
        k = 6 + 8 * b
        q, Q = (y[k], y[k + 1], y[k + 2], y[k + 3]), (y[k + 4], y[k + 5], y[k + 6], y[k + 7])
        w = qmul(Q, qconj(q))  # G = 1/2 Im(Q q~)
        for j in range(3):
            L[j] += 0.5 * w[j + 1]
    return L


@jit
def evaluate(Y, c):
    """At the states ``Y (N, 14 | 22)``: ``energy (N,)``, ``L (N, 3)`` (:func:`angular_momentum`),
    the body rates ``omega (N, 3)`` of the secondary and ``omega1 (N, 3)`` of the primary
    (zeros for a point mass), body axes."""
    N = Y.shape[0]
    E = np.empty(N)
    L = np.empty((N, 3))
    om2 = np.zeros((N, 3))
    om1 = np.zeros((N, 3))
    I2 = (c[C_I2], c[C_I2 + 1], c[C_I2 + 2])
    I1 = (c[C_I1], c[C_I1 + 1], c[C_I1 + 2])
    for i in range(N):
        y = Y[i]
        E[i] = energy(y, c)
        L[i] = angular_momentum(y, c)
        _, om = _rate((y[6], y[7], y[8], y[9]), (y[10], y[11], y[12], y[13]), I2)
        for j in range(3):
            om2[i, j] = om[j]
        if y.shape[0] > N_POINT:
            _, om = _rate((y[14], y[15], y[16], y[17]), (y[18], y[19], y[20], y[21]), I1)
            for j in range(3):
                om1[i, j] = om[j]
    return E, L, om2, om1

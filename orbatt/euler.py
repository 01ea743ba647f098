"""The paper's 3-1-3 Euler angles and their conjugate momenta (eqs. 10, 12-15).

Angles ``(phi, theta, psi)`` (rad) of ``q = q_z(phi) q_x(theta) q_z(psi)``; conjugate
momenta ``(Phi, Theta, Psi)``: ``Phi = G.s3`` (space-vertical angular momentum),
``Psi = g.b3 = g3`` (body), ``Theta = G.n`` along the line of nodes ``n``. In body
components, with ``A = (Phi - Psi cos theta) / sin theta``::

    g1 = A sin psi + Theta cos psi,   g2 = A cos psi - Theta sin psi,   g3 = Psi     (eq. 14)

Euler angles are singular at ``theta = 0, pi``: they are an input/output convenience and an
independent formulation for tests, never what orbatt integrates. Plain floats, no units.

Paper errata handled here (``docs/design.md`` §3a): eq. (10)'s last term is ``Psi^2 / (2 I3)``;
the paper's initial ``theta = 3 pi/2`` lies outside ``(0, pi)`` - eqs. (12) and (14) accept
it, eqs. (13) and (15) return the equivalent ``(5 pi/4, pi/2, 5 pi/4)`` with ``Theta`` of
opposite sign.
"""
from __future__ import annotations

import numpy as np

from . import canonical as cn
from . import quaternion as qt


def body_momentum_from_euler(angles, momenta):
    """Body angular momentum ``g`` (body components) from ``(phi, theta, psi)`` and
    ``(Phi, Theta, Psi)`` (each of shape ``(..., 3)``); eq. (14) without the quaternion."""
    angles = np.asarray(angles, dtype=np.float64)
    momenta = np.asarray(momenta, dtype=np.float64)
    _, th, ps = np.moveaxis(angles, -1, 0)
    P, T, S = np.moveaxis(momenta, -1, 0)
    A = (P - S * np.cos(th)) / np.sin(th)
    return np.stack([A * np.sin(ps) + T * np.cos(ps), A * np.cos(ps) - T * np.sin(ps), S], axis=-1)


def to_canonical(angles, momenta):
    """``(q, Q)`` from the 3-1-3 angles and their momenta (eqs. 12 and 14)."""
    angles = np.asarray(angles, dtype=np.float64)
    q = qt.from_euler313(*np.moveaxis(angles, -1, 0))
    return q, cn.momentum_from_body_momentum(q, body_momentum_from_euler(angles, momenta))


def from_canonical(q, Q):
    """``((phi, theta, psi), (Phi, Theta, Psi))`` from ``(q, Q)`` (eqs. 13 and 15), each of
    shape ``(..., 3)``. At ``theta = 0, pi`` the angles follow :func:`orbatt.quaternion.to_euler313`."""
    phi, th, ps = qt.to_euler313(q)
    g = cn.body_momentum(q, Q)
    G = cn.space_momentum(q, Q)
    Theta = g[..., 0] * np.cos(ps) - g[..., 1] * np.sin(ps)
    return np.stack([phi, th, ps], axis=-1), np.stack([G[..., 2], Theta, g[..., 2]], axis=-1)


def hamiltonian(angles, momenta, inertia):
    """Kinetic energy in Euler variables, eq. (10) with the ``Psi^2 / (2 I3)`` term."""
    g = body_momentum_from_euler(angles, momenta)
    return 0.5 * np.sum(g * g / np.asarray(inertia, dtype=np.float64), axis=-1)


def equations_of_motion(y, inertia, mass_g=0.0, center_of_mass=(0.0, 0.0, 0.0), sign=1.0):
    """Hamilton's equations in Euler variables for ``y = (phi, theta, psi, Phi, Theta, Psi)``
    (torque-free, or the heavy top when ``mass_g != 0``). Singular at ``sin theta = 0``.

    Derived from eq. (10) independently of the quaternion form; used to cross-check it.
    """
    y = np.asarray(y, dtype=np.float64)
    I1, I2, I3 = inertia
    _, th, ps, P, T, S = y
    s, c = np.sin(th), np.cos(th)
    sp, cp = np.sin(ps), np.cos(ps)
    A = (P - S * c) / s
    g1 = A * sp + T * cp
    g2 = A * cp - T * sp
    w1, w2, w3 = g1 / I1, g2 / I2, S / I3
    u = w1 * sp + w2 * cp
    dphi = u / s
    dtheta = w1 * cp - w2 * sp
    dpsi = w3 - u * c / s
    dA = (S - P * c) / (s * s)
    dH_dtheta = u * dA
    dH_dpsi = w1 * g2 - w2 * g1
    x1, x2, x3 = center_of_mass
    k = sign * mass_g
    dU_dtheta = k * (x1 * c * sp + x2 * c * cp - x3 * s)
    dU_dpsi = k * (x1 * s * cp - x2 * s * sp)
    return np.array([dphi, dtheta, dpsi, 0.0, -dH_dtheta - dU_dtheta, -dH_dpsi - dU_dpsi])

"""The canonical pair ``(q, Q)`` and the physical quantities it encodes (paper Sects. 3, 5).

Plain float arrays, no units (the caller's consistent unit system). Shapes broadcast:
``q, Q`` are ``(..., 4)``, 3-vectors ``(..., 3)``, ``inertia`` is ``(I1, I2, I3)`` (the
principal moments; ``I0^-1 = 0``). Frames (``docs/design.md`` §1-2):

* ``omega`` - body angular velocity ``2 q~ dq/dt``, **body** components;
* ``g = I omega`` - angular momentum, **body** components;
* ``G = q g q~`` - angular momentum, **space** (inertial) components;
* ``Q = 2 q g`` (eq. 5, ``Q = 4 q (I (x) q~ dq/dt)``), inversely ``g = 1/2 Im(q~ Q)`` and
  ``G = 1/2 Im(Q q~)`` (order matters).
"""
from __future__ import annotations

import numpy as np

from . import quaternion as qt


def _inertia(inertia):
    return np.asarray(inertia, dtype=np.float64)


def momentum_from_body_momentum(q, g):
    """``Q = 2 q (0, g)`` from the attitude and the body angular momentum ``g`` (body)."""
    return 2.0 * qt.mul(q, qt.pure(g))


def momentum_from_omega(q, omega, inertia):
    """``Q = 2 q (0, I omega)`` from the body angular velocity ``omega`` (body, rad/time)."""
    return momentum_from_body_momentum(q, _inertia(inertia) * np.asarray(omega, dtype=np.float64))


def body_momentum(q, Q):
    """Body angular momentum ``g = 1/2 Im(q~ Q)`` (body components)."""
    return 0.5 * qt.vector(qt.mul(qt.conj(q), Q))


def body_rate(q, Q, inertia):
    """Body angular velocity ``omega = I^-1 g`` (body components, rad per time unit)."""
    return body_momentum(q, Q) / _inertia(inertia)


def space_momentum(q, Q):
    """Space angular momentum ``G = 1/2 Im(Q q~)`` (inertial components)."""
    return 0.5 * qt.vector(qt.mul(Q, qt.conj(q)))


def kinetic_energy(q, Q, inertia):
    """``T = 1/8 (I^-1 (x) q~Q).(q~Q) = 1/2 g.I^-1 g`` (eq. 6)."""
    return _kinetic_energy(body_momentum(q, Q), _inertia(inertia))


def _kinetic_energy(g, inertia):
    return 0.5 * np.add.reduce(g * g / inertia, axis=-1)  # np.sum without its argument handling


def body_quantities(q, Q, inertia):
    """``(g, omega, T)``: :func:`body_momentum`, :func:`body_rate` and
    :func:`kinetic_energy` (the same values) from one evaluation of ``g``."""
    inertia = _inertia(inertia)
    g = body_momentum(q, Q)
    return g, g / inertia, _kinetic_energy(g, inertia)


def hamilton_rhs(q, Q, inertia, dUdq=None):
    """Eq. (7): ``(dq/dt, dQ/dt)`` for the gradient ``dU/dq`` (zero if None). Vectorized
    numpy reference for the compiled kernel :func:`orbatt.core.hamiltonian.rhs`."""
    q = np.asarray(q, dtype=np.float64)
    Q = np.asarray(Q, dtype=np.float64)
    inv = np.concatenate([[0.0], 1.0 / _inertia(inertia)])
    qd = 0.25 * qt.mul(q, qt.hadamard(inv, qt.mul(qt.conj(q), Q)))
    Qd = -0.25 * qt.mul(Q, qt.hadamard(inv, qt.mul(qt.conj(Q), q)))
    if dUdq is not None:
        Qd = Qd - dUdq
    return qd, Qd


def constraint_residuals(q, Q):
    """``(|q| - 1, q.Q)``: both vanish on the constraint manifold."""
    return qt.norm(q) - 1.0, qt.dot(q, Q)

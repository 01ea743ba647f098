"""The canonical state ``(q, Q)`` of a rigid body, validated, built from what users know.

Frames and units: ``q`` maps body to space components (:mod:`orbatt.quaternion`); ``Q`` is
in the body's momentum unit, the kernels' (kg km^2 s^-1, or plain numbers for a
dimensionless body); a State prints ``Q`` in SI (kg m^2 s^-1), as every output gives it.
A state may hold a batch: ``q`` and ``Q`` of shape ``(..., 4)``.
"""
from __future__ import annotations

import numpy as np

from . import canonical as cn
from . import euler as eu
from . import quaternion as qt
from . import units as U
from .body import RigidBody
from .errors import InputError

#: ``| |q| - 1 |`` above this is refused (a 6-digit printed unit quaternion passes).
UNIT_TOLERANCE = 1e-6
#: ``|q.Q| / |Q|`` above this is refused as "clearly not tangent" (the paper's printed
#: ``Q(t0)`` has 5e-8).
TANGENT_TOLERANCE = 1e-6


def unit_quaternion(q, name="q"):
    q = qt.as_quaternion(q, name)
    n = qt.norm(q)
    if q.ndim == 1:  # one quaternion: the checks on a float (numpy's calls cost ~1 us each)
        nf = float(n)
        zero, off = nf == 0.0, abs(nf - 1.0) > UNIT_TOLERANCE
    else:
        bad = np.abs(n - 1.0) > UNIT_TOLERANCE
        zero, off = (n == 0.0).any(), bad.any()
    if zero:
        raise InputError(f"{name}: the zero quaternion is not an attitude; give a unit quaternion")
    if off:
        first = nf if q.ndim == 1 else float(np.asarray(n)[bad].ravel()[0])
        raise InputError(f"{name}: |q| = {first:.10g} is not 1 (tolerance "
                         f"{UNIT_TOLERANCE:g}); give a unit quaternion (scalar first)")
    return q / n[..., None]


class State:
    """Canonical state ``(q, Q)`` (paper Sect. 3), validated.

    Parameters
    ----------
    body : RigidBody
    q : array-like (..., 4)
        Attitude, body -> space, scalar first. Must be a unit quaternion to 1e-6; it is
        normalized exactly.
    Q : array-like or Quantity (..., 4)
        Conjugate momentum in the body's momentum unit. A small component along ``q``
        (``|q.Q| <= 1e-6 |Q|``, as in the paper's 6-digit data) is accepted and reported in
        :attr:`radial_residual`; a larger one is refused with the measured ``q.Q``.
    """

    def __init__(self, body: RigidBody, q, Q):
        if not isinstance(body, RigidBody):
            raise InputError(f"body: expected a RigidBody, got {type(body).__name__}")
        self.body = body
        self.q = unit_quaternion(q)
        Qv = U.strip(Q, body.momentum_unit, "Q", allow_plain=True)
        Qv = qt.as_quaternion(Qv, "Q")
        if Qv.shape != self.q.shape:
            try:
                np.broadcast_shapes(self.q.shape, Qv.shape)
            except ValueError:
                raise InputError(f"Q: shape {Qv.shape} does not match q's {self.q.shape}") from None
        qQ = qt.dot(self.q, Qv)
        scale = qt.norm(Qv)
        if Qv.ndim == 1 and self.q.ndim == 1:  # one state: the comparison on floats
            refused = abs(float(qQ)) > TANGENT_TOLERANCE * float(scale)
        else:
            refused = (np.abs(qQ) > TANGENT_TOLERANCE * scale).any()
        if refused:
            bad = np.abs(qQ) > TANGENT_TOLERANCE * scale
            raise InputError(f"Q: q.Q = {float(np.asarray(qQ)[bad].ravel()[0]):.6g} is not ~0 (|Q| = "
                             f"{float(np.asarray(scale)[bad].ravel()[0]):.6g}); Q must be tangent to the unit sphere "
                             "at q (Q = 2 q g): build it with State.from_omega or State.from_momentum")
        self.Q = Qv
        #: ``q.Q`` of the given data (0 for states built from rates or momenta)
        self.radial_residual = qQ

    # ---- constructors -------------------------------------------------------------------
    @classmethod
    def from_omega(cls, body: RigidBody, q, omega):
        """From the attitude and the body angular velocity ``omega`` (body components;
        rad/s Quantity, or plain numbers for a dimensionless body). For a body with reaction
        wheels, ``Q`` holds the total momentum ``g = I omega + sum Iw speed a`` (the wheels'
        initial speeds)."""
        q = unit_quaternion(q)
        w = U.strip(omega, body.rate_unit, "omega", allow_plain=body.dimensionless)
        if w.shape[-1:] != (3,):
            raise InputError(f"omega: expected 3 body-axis components, got shape {w.shape}")
        if body.wheels:  # a gyrostat: g = I omega + the rotors' relative momentum
            return cls(body, q, cn.momentum_from_body_momentum(q, body.inertia_value * w + body.rotor_momentum))
        return cls(body, q, cn.momentum_from_omega(q, w, body.inertia_value))

    @classmethod
    def from_momentum(cls, body: RigidBody, q, g):
        """From the attitude and the body angular momentum ``g`` (body components)."""
        q = unit_quaternion(q)
        gv = U.strip(g, body.momentum_unit, "g", allow_plain=True)
        if gv.shape[-1:] != (3,):
            raise InputError(f"g: expected 3 body-axis components, got shape {gv.shape}")
        return cls(body, q, cn.momentum_from_body_momentum(q, gv))

    @classmethod
    def from_euler(cls, body: RigidBody, angles, momenta):
        """From the 3-1-3 Euler angles ``(phi, theta, psi)`` (rad) and their conjugate momenta
        ``(Phi, Theta, Psi)`` (momentum unit); eqs. (12) and (14). ``sin(theta) = 0`` is
        refused (the Euler momenta do not determine the state there)."""
        ang = U.strip(angles, U.ANGLE, "euler_313")
        mom = U.strip(momenta, body.momentum_unit, "euler_momenta", allow_plain=True)
        if ang.shape[-1:] != (3,) or mom.shape[-1:] != (3,):
            raise InputError("euler_313/euler_momenta: expected 3 values each")
        if np.any(np.abs(np.sin(ang[..., 1])) < 1e-12):
            raise InputError(f"euler_313: theta = {ang[..., 1]!r} is singular (sin theta = 0); "
                             "give q and omega instead")
        q, Q = eu.to_canonical(ang, mom)
        return cls(body, q, Q)

    # ---- derived quantities -------------------------------------------------------------
    @property
    def g(self):
        """Body angular momentum (body components, momentum unit)."""
        return cn.body_momentum(self.q, self.Q)

    @property
    def omega(self):
        """Body angular velocity (body components, rad per time unit); for a body with
        reaction wheels ``I^-1 (g - sum Iw speed a)`` with the wheels' initial speeds."""
        if self.body.wheels:
            return (self.g - self.body.rotor_momentum) / self.body.inertia_value
        return cn.body_rate(self.q, self.Q, self.body.inertia_value)

    @property
    def G(self):
        """Space angular momentum (inertial components, momentum unit)."""
        return cn.space_momentum(self.q, self.Q)

    @property
    def kinetic_energy(self):
        return cn.kinetic_energy(self.q, self.Q, self.body.inertia_value)

    def euler(self):
        """``((phi, theta, psi), (Phi, Theta, Psi))`` (eqs. 13, 15)."""
        return eu.from_canonical(self.q, self.Q)

    @property
    def y(self):
        """The kernels' state vector(s) ``(q0..q3, Q0..Q3)``, shape ``(..., 8)``."""
        q, Q = self.q, self.Q
        if q.shape != Q.shape:
            q, Q = np.broadcast_arrays(q, Q)
        return np.concatenate([q, Q], axis=-1)

    def __repr__(self):
        """``State(q=[...], Q=[...] kg m^2 s^-1)``: ``Q`` printed in SI (the unit every
        output uses, :data:`orbatt.units.DIMENSIONAL_UNITS`), or as plain numbers for a
        dimensionless body; :attr:`Q` itself stays in the kernels' unit."""
        if self.body.dimensionless:
            return f"State(q={self.q.tolist()}, Q={self.Q.tolist()})"
        Q = U.to_output(self.Q, "momentum")
        return f"State(q={self.q.tolist()}, Q={Q.tolist()} {U.DIMENSIONAL_UNITS['momentum']})"

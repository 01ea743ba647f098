"""Attitude and rates relative to the orbital frame ``O`` (LVLH-type), ``docs/design.md`` §1.

Frames and names (Basilisk style: ``q_BO`` is ``B`` relative to ``O``, ``omega_BO_B`` the
angular velocity of ``B`` relative to ``O`` in ``B`` components):

* ``O``: ``o1`` radial (from the central body towards the satellite), ``o3`` along the
  orbit normal ``r x v``, ``o2 = o3 x o1`` (along-track for a circular orbit). The orbital
  quaternion ``p = q_OS`` maps ``O`` components to ``S`` components (``x_S = p x_O p~``).
* ``q_BO = p~ q`` maps body components to orbital components (``x_O = q_BO x_B q_BO~``);
  ``q = p q_BO``. ``q_BO = (1, 0, 0, 0)`` is a body whose axes coincide with the orbital
  axes: body axis 1 points to the zenith (so ``-b1`` is nadir-pointing), axis 3 along the
  orbit normal - the gravity-gradient-stable orientation when ``I1 < I2 < I3``.
* ``omega_OS_O``: angular velocity of ``O`` relative to ``S`` in ``O`` components,
  ``(r a_n / h, 0, h / r^2)`` (:meth:`orbatt.orbits.OrbitProvider.orbital_rate`; for a
  Keplerian orbit ``(0, 0, df/dt)``).
* Body rates: ``omega_BS_B = omega_BO_B + q_BO~ omega_OS_O q_BO``.

Times are seconds since the orbit's epoch; rates in rad/s (internal units, plain floats
on output).
"""
from __future__ import annotations

import numpy as np

from . import canonical as cn
from . import quaternion as qt
from . import units as U
from .body import RigidBody
from .errors import InputError
from .orbits.base import OrbitProvider, as_times
from .state import State

__all__ = ["orbital_attitude", "inertial_attitude", "orbital_rate", "relative_rate", "body_rate_from_orbital",
           "state_from_orbital", "to_orbital", "lvlh_angles", "LVLH_RELABEL"]


def _check_orbit(orbit):
    if not isinstance(orbit, OrbitProvider):
        raise InputError(f"orbit: expected an orbit provider (KeplerOrbit, ReboundOrbit), got {type(orbit).__name__}")


def orbital_attitude(orbit, t, q):
    """Attitude relative to the orbital frame, ``q_BO = p~ q``.

    Parameters
    ----------
    orbit : OrbitProvider
    t : array-like (N,) or float
        Seconds since the orbit's epoch.
    q : array-like (..., 4)
        Attitude (body -> space ``S``), broadcast against ``t``'s shape + (4,).

    Returns
    -------
    ndarray (..., 4)
        ``q_BO`` (body -> orbital components).
    """
    _check_orbit(orbit)
    p = orbit.orbital_quaternion(as_times(t))
    return qt.mul(qt.conj(p), qt.as_quaternion(q))


def inertial_attitude(orbit, t, q_BO):
    """Inertial attitude ``q = p q_BO`` from the attitude relative to the orbital frame."""
    _check_orbit(orbit)
    p = orbit.orbital_quaternion(as_times(t))
    return qt.mul(p, qt.as_quaternion(q_BO, "q_BO"))


def orbital_rate(orbit, t):
    """``omega_OS_O``: angular velocity of the orbital frame relative to ``S``, ``O``
    components (rad/s), shape ``t.shape + (3,)``."""
    _check_orbit(orbit)
    return orbit.orbital_rate(as_times(t))


def relative_rate(orbit, t, q, omega_B):
    """``omega_BO_B = omega_B - q_BO~ omega_OS_O q_BO``: body rate relative to the rotating
    orbital frame (body components, rad/s) from the inertial body rate ``omega_B``
    (body components, rad/s) and the attitude ``q`` (body -> ``S``)."""
    q_BO = orbital_attitude(orbit, t, q)
    w_O = orbital_rate(orbit, t)
    return np.asarray(omega_B, dtype=np.float64) - qt.rotate_inv(q_BO, w_O)


def body_rate_from_orbital(orbit, t, q_BO, omega_BO_B):
    """Inertial body rate ``omega_BS_B = omega_BO_B + q_BO~ omega_OS_O q_BO`` (body
    components, rad/s)."""
    w_O = orbital_rate(orbit, t)
    return np.asarray(omega_BO_B, dtype=np.float64) + qt.rotate_inv(qt.normalize(q_BO), w_O)


def state_from_orbital(body, orbit, q_BO=(1.0, 0.0, 0.0, 0.0), omega_BO_B=(0.0, 0.0, 0.0), t0=0.0):
    """Canonical state ``(q, Q)`` from an attitude and rates given relative to the orbital
    frame.

    Parameters
    ----------
    body : RigidBody
        A dimensional body (inertia in kg km^2) with a dimensional orbit, or a dimensionless
        one with a dimensionless orbit (normalized units; rates in its time unit).
    orbit : OrbitProvider
    q_BO : array-like (..., 4)
        Attitude of the body relative to the orbital frame (body -> ``O`` components, scalar
        first, unit to 1e-6). Default identity: body axes along ``o1`` (zenith), ``o2``,
        ``o3`` (orbit normal).
    omega_BO_B : Quantity (rad/s) or array-like (..., 3)
        Body angular velocity relative to the rotating orbital frame, body components
        (plain numbers are rad/s). Default zero: the body turns with the orbital frame
        (once per orbit about ``o3`` for a Keplerian orbit).
    t0 : Quantity (time) or float
        Time of the state, seconds since the orbit's epoch (default 0).

    Returns
    -------
    State
        ``q = p(t0) q_BO``, ``Q = 2 q (0, I omega_BS_B)`` with
        ``omega_BS_B = omega_BO_B + q_BO~ omega_OS_O q_BO``.
    """
    if not isinstance(body, RigidBody):
        raise InputError(f"body: expected a RigidBody, got {type(body).__name__}")
    _check_orbit(orbit)
    if bool(body.dimensionless) != bool(getattr(orbit, "dimensionless", False)):
        raise InputError("body: the body and the orbit must be both dimensional (inertia and a as Quantities) or "
                         "both in normalized units (plain numbers)")
    t0v = as_times(t0, "t0")
    if t0v.shape != ():
        raise InputError(f"t0: expected one time, got shape {t0v.shape}")
    qbo = qt.as_quaternion(q_BO, "q_BO")
    n = qt.norm(qbo)
    if np.any(np.abs(n - 1.0) > 1e-6):
        raise InputError(f"q_BO: |q_BO| = {np.asarray(n).ravel()[0]!r} is not 1; give a unit quaternion "
                         "(scalar first)")
    qbo = qbo / n[..., None]
    w = U.strip(omega_BO_B, U.RATE, "omega_BO_B", allow_plain=True)
    if w.shape[-1:] != (3,):
        raise InputError(f"omega_BO_B: expected 3 body-axis components, got shape {w.shape}")
    p = orbit.orbital_quaternion(t0v)
    q = qt.mul(p, qbo)
    omega = body_rate_from_orbital(orbit, t0v, qbo, w)
    return State.from_omega(body, q, omega if body.dimensionless else omega * U.RATE)


def to_orbital(orbit, t, q, Q=None, inertia=None):
    """Outputs relative to the orbital frame.

    Parameters
    ----------
    orbit : OrbitProvider
    t : array-like (N,)
        Seconds since the orbit's epoch.
    q : array-like (N, 4) or (E, N, 4)
        Attitude (body -> ``S``).
    Q : array-like like ``q``, optional
        Conjugate momentum (kg km^2 s^-1); with ``inertia`` gives the relative rates.
    inertia : array-like (3,), RigidBody, optional
        Principal moments (kg km^2).

    Returns
    -------
    q_BO : ndarray like ``q``
        ``p~ q``.
    omega_BO_B : ndarray (..., 3)
        Body rate relative to the orbital frame (body components, rad/s); only when ``Q``
        and ``inertia`` are given (otherwise only ``q_BO`` is returned).
    """
    q_BO = orbital_attitude(orbit, t, q)
    if Q is None:
        return q_BO
    if inertia is None:
        raise InputError("inertia: needed with Q to compute the body rates; pass the RigidBody or (I1, I2, I3)")
    I = inertia.inertia_value if isinstance(inertia, RigidBody) else np.asarray(inertia, dtype=np.float64)
    omega = cn.body_rate(np.asarray(q, dtype=np.float64), np.asarray(Q, dtype=np.float64), I)
    w_O = orbital_rate(orbit, t)
    return q_BO, omega - qt.rotate_inv(q_BO, w_O)


#: rotation of 120 deg about (1, 1, 1): relabels the axes (x, y, z) -> (y, z, x)
LVLH_RELABEL = np.array([0.5, 0.5, 0.5, 0.5])


def lvlh_angles(q_orbital):
    """Roll, pitch, yaw of an attitude relative to the orbital frame, as spacecraft practice
    names them.

    orbatt's orbital frame has ``o1`` radial (zenith), ``o2`` along-track, ``o3`` the orbit
    normal (``docs/design.md`` §1). **Roll** is the rotation about the along-track axis ``o2``,
    **pitch** about the orbit normal ``o3`` (the in-plane libration of a gravity-gradient
    satellite), **yaw** about the radial axis ``o1``, in the aerospace 3-2-1 sequence taken in
    the relabelled axes ``(x', y', z') = (o2, o3, o1)``: first yaw about ``o1``, then pitch
    about the new ``o3``, then roll about the new ``o2``. The body axes are relabelled the same
    way, so body axes 1, 2, 3 along ``o1, o2, o3`` is zero roll, pitch and yaw. Positive
    pitch turns about ``+o3`` (many LVLH conventions use ``-o3``: flip its sign to compare).

    Parameters
    ----------
    q_orbital : array-like (..., 4)
        Attitude of ``B`` relative to ``O`` (``x_O = q x_B q~``), scalar first.

    Returns
    -------
    roll, pitch, yaw : ndarray (...)
        rad; ranges and the singular ``pitch = +-pi/2`` as in
        :func:`orbatt.quaternion.to_euler321`.
    """
    m = LVLH_RELABEL
    return qt.to_euler321(qt.mul(qt.mul(qt.conj(m), q_orbital), m))

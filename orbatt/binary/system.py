"""A binary asteroid's two bodies and their initial state, with units (``docs/design.md`` §12).

:class:`BinarySystem` holds the masses and principal moments of the secondary (the body whose
attitude ``(q, Q)`` orbatt always integrates) and of the primary (a point mass, or a rigid body
with its own ``(q1, Q1)``), validated once; :meth:`BinarySystem.state` builds the flat state
of :mod:`orbatt.core.mutual` from the relative position and velocity (primary -> secondary,
inertial ``S``) and the attitudes; :meth:`BinarySystem.state_from_elements` from osculating
elements about ``G (M1 + M2)``. Internal units: kg, km, s, rad (inertia kg km^2, momenta
kg km^2 s^-1), as everywhere in orbatt.
"""
from __future__ import annotations

import math

import numpy as np
from astropy import constants as const
from astropy import units as u

from .. import quaternion as qt
from .. import units as U
from ..body import check_triangle
from ..core import mutual as km
from ..errors import InputError

__all__ = ["BinarySystem", "G_KM", "POTENTIALS", "body_radius", "rtn_basis", "osculating_elements", "mean_longitude",
           "mean_period", "MEAN_PERIOD_METHOD"]

#: the gravitational constant in km^3 kg^-1 s^-2 (astropy's CODATA value)
G_KM = float(const.G.to_value(u.km**3 / u.kg / u.s**2))
#: the models of the mutual potential (:func:`orbatt.core.mutual.constants`'s ``full``)
POTENTIALS = ("coupled", "gravity-gradient")


def body_radius(mass, inertia):
    """``sqrt(tr I / M)`` (km): the radius used for contact, ~1.095 times a homogeneous sphere's
    (``tr I = 6/5 M R^2``); 0 for a point mass (``inertia`` None)."""
    if inertia is None:
        return 0.0
    return math.sqrt(float(np.sum(inertia)) / mass)


def rtn_basis(r, v):
    """The radial, along-track and normal unit vectors (rows of a (3, 3) array, inertial) of the
    relative position ``r`` and velocity ``v``: ``o1 = r / |r|``, ``o3 = r x v / |r x v|``,
    ``o2 = o3 x o1`` (the orbital frame of ``docs/design.md`` §1)."""
    o1 = r / np.linalg.norm(r)
    h = np.cross(r, v)
    o3 = h / np.linalg.norm(h)
    return np.array([o1, np.cross(o3, o1), o3])


def osculating_elements(r, v, gm):
    """``(a, e, i, period)`` of the osculating Keplerian orbit of ``r (N, 3)`` (km), ``v (N, 3)``
    (km/s) about ``gm`` (km^3 s^-2); ``a`` and ``period`` NaN for an unbound state; ``i`` from
    the inertial ``s3`` axis (rad)."""
    r = np.atleast_2d(r)
    v = np.atleast_2d(v)
    rn = np.linalg.norm(r, axis=-1)
    v2 = np.sum(v * v, axis=-1)
    eps = 0.5 * v2 - gm / rn
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(eps < 0, -gm / (2.0 * eps), np.nan)
        period = 2.0 * np.pi * np.sqrt(a ** 3 / gm)
    h = np.cross(r, v)
    hn = np.linalg.norm(h, axis=-1)
    evec = np.cross(v, h) / gm - r / rn[:, None]
    e = np.linalg.norm(evec, axis=-1)
    i = np.arccos(np.clip(h[:, 2] / hn, -1.0, 1.0))
    return a, e, i, period


def mean_longitude(r, v, gm):
    """The osculating mean longitude ``lambda = varpi + M`` (rad, unwrapped along the rows) of the
    relative orbit ``r (N, 3)`` (km), ``v (N, 3)`` (km/s) about ``gm`` (km^3 s^-2).

    Computed in the equinoctial frame of the orbit plane (no singularity at ``e = 0`` or
    ``i = 0``; a retrograde orbit is measured in the direction of its motion): ``L`` the true
    longitude, ``varpi`` that of the eccentricity vector, ``M`` the mean anomaly of the true
    anomaly ``L - varpi``. On a Keplerian orbit it grows exactly as ``n t``; NaN from the first
    unbound state on.
    """
    r = np.atleast_2d(np.asarray(r, dtype=np.float64))
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    h = np.cross(r, v)
    hh = h / np.linalg.norm(h, axis=-1)[:, None]
    hh = np.where(hh[:, 2:3] < 0, -hh, hh)  # a retrograde orbit: the plane's other normal
    p = hh[:, 0] / (1.0 + hh[:, 2])
    q = -hh[:, 1] / (1.0 + hh[:, 2])
    s = 1.0 + p * p + q * q
    f = np.stack([1.0 - p * p + q * q, 2.0 * p * q, -2.0 * p], axis=-1) / s[:, None]
    g = np.stack([2.0 * p * q, 1.0 + p * p - q * q, 2.0 * q], axis=-1) / s[:, None]
    rn = np.linalg.norm(r, axis=-1)
    evec = np.cross(v, h) / gm - r / rn[:, None]
    e = np.linalg.norm(evec, axis=-1)
    true_long = np.arctan2(np.sum(r * g, axis=-1), np.sum(r * f, axis=-1))
    varpi = np.arctan2(np.sum(evec * g, axis=-1), np.sum(evec * f, axis=-1))
    nu = true_long - varpi
    sign = np.sign(np.sum(h * hh, axis=-1))  # +1 prograde in (f, g), -1 retrograde
    nu = sign * nu
    with np.errstate(invalid="ignore"):
        ecc = np.arctan2(np.sqrt(1.0 - e * e) * np.sin(nu), e + np.cos(nu))
    mean_anom = ecc - e * np.sin(ecc)
    centre = np.angle(np.exp(1j * (nu - mean_anom)))  # nu - M in (-pi, pi]: 0 on a circle
    lam = true_long - sign * centre
    bad = ~np.isfinite(lam) | (e >= 1.0)
    if bad.any():
        lam = lam.copy()
        lam[int(np.argmax(bad)):] = np.nan
    ok = np.isfinite(lam)
    lam[ok] = np.unwrap(lam[ok])
    return lam


#: how :func:`mean_period` measures (the ``method`` attribute of ``mean_period``)
MEAN_PERIOD_METHOD = ("2 pi W / |lambda(t + W/2) - lambda(t - W/2)|: the advance of the unwrapped osculating mean "
                      "longitude lambda (about G (M1 + M2)) over a window W centred on t (lambda interpolated "
                      "linearly between outputs), W = one mean period of the whole run (2 pi (t_end - t_0) / "
                      "|lambda_end - lambda_0|); NaN where the window does not fit in the run. Periodic terms of "
                      "period W / k cancel; on a Keplerian orbit it equals the osculating period")


def mean_period(t, lam):
    """The mean period of the mutual orbit at each output time and the window (s).

    Parameters
    ----------
    t : ndarray (N,)
        Output times (s).
    lam : ndarray (N,)
        The unwrapped mean longitude (:func:`mean_longitude`, rad).

    Returns
    -------
    period : ndarray (N,)
        :data:`MEAN_PERIOD_METHOD`: ``2 pi W / |lambda(t + W/2) - lambda(t - W/2)|``; NaN where
        ``[t - W/2, t + W/2]`` leaves the run (or a state is unbound).
    window : float
        ``W`` (s): one mean period over the whole run (NaN without one whole window).
    """
    t = np.asarray(t, dtype=np.float64)
    lam = np.asarray(lam, dtype=np.float64)
    out = np.full(t.shape, np.nan)
    if t.size < 2 or not np.all(np.isfinite(lam)) or lam[-1] == lam[0]:
        return out, float("nan")
    span = t[-1] - t[0]
    window = 2.0 * np.pi * span / abs(lam[-1] - lam[0])
    inside = (t - 0.5 * window >= t[0]) & (t + 0.5 * window <= t[-1])
    if window > span or not inside.any():
        return out, float(window)
    tk = t[inside]
    d = np.interp(tk + 0.5 * window, t, lam) - np.interp(tk - 0.5 * window, t, lam)
    out[inside] = 2.0 * np.pi * window / np.abs(d)
    return out, float(window)


def _masses(value, name):
    m = float(U.strip(value, U.MASS, name))
    if not (m > 0 and math.isfinite(m)):
        raise InputError(f"{name}: {value!r} must be a positive mass; give e.g. '4.3e9 kg'")
    return m


def _moments(value, name):
    if value is None:
        return None
    m = np.asarray(U.strip(value, U.INERTIA, name), dtype=np.float64)
    if m.shape != (3,) or not np.all(np.isfinite(m)) or np.any(m <= 0):
        raise InputError(f"{name}: {value!r} must be three positive principal moments, e.g. "
                         "['8.6e12 kg m2', '1.17e13 kg m2', '1.41e13 kg m2']")
    try:
        check_triangle(m)
    except InputError as exc:
        raise InputError(f"{name}: {exc}".replace("inertia: ", "")) from None
    return m


class BinarySystem:
    """The two bodies of a binary asteroid.

    Parameters
    ----------
    mass : Quantity (mass)
        The secondary's mass ``M2``.
    inertia : Quantity (mass x length^2), (3,)
        The secondary's principal moments ``I2`` (body axes).
    primary_mass : Quantity (mass)
        The primary's mass ``M1``.
    primary_inertia : Quantity (mass x length^2), (3,), optional
        The primary's principal moments ``I1``; None: a point mass (its attitude is not
        integrated, the state has 14 components).
    potential : {"coupled", "gravity-gradient"}
        ``"coupled"``: the second-order mutual potential, the orbit and both bodies feel it.
        ``"gravity-gradient"``: the orbit is Keplerian about ``G (M1 + M2)`` and only the
        secondary feels a torque (eq. 20); the one-way model with an integrated orbit.

    Raises
    ------
    InputError
        A mass or moment not positive, moments violating the triangle inequality, an unknown
        potential; the message names the argument.
    """

    def __init__(self, mass, inertia, primary_mass, primary_inertia=None, *, potential="coupled"):
        self.mass = _masses(mass, "mass")
        self.primary_mass = _masses(primary_mass, "primary_mass")
        self.inertia = _moments(inertia, "inertia")
        self.primary_inertia = _moments(primary_inertia, "primary_inertia")
        if potential not in POTENTIALS:
            raise InputError(f"potential: {potential!r} is not one of {', '.join(map(repr, POTENTIALS))}")
        self.potential = potential
        self.G = G_KM

    @property
    def rigid_primary(self):
        """Whether the primary is a rigid body (its attitude integrated)."""
        return self.primary_inertia is not None

    @property
    def gm(self):
        """``G (M1 + M2)`` (km^3 s^-2): the Keplerian parameter of the relative orbit."""
        return self.G * (self.primary_mass + self.mass)

    @property
    def reduced_mass(self):
        """``mu = M1 M2 / (M1 + M2)`` (kg)."""
        return self.primary_mass * self.mass / (self.primary_mass + self.mass)

    @property
    def contact_distance(self):
        """The separation below which the bodies touch: the sum of :func:`body_radius` (km)."""
        return body_radius(self.mass, self.inertia) + body_radius(self.primary_mass, self.primary_inertia)

    def constants(self, r0, v0):
        """The kernel's constants (:func:`orbatt.core.mutual.constants`), the absolute
        tolerance of ``r`` scaled by ``|r0|`` and that of ``p`` by ``mu`` times the circular
        speed at ``|r0|``."""
        rn = float(np.linalg.norm(r0))
        vc = math.sqrt(self.gm / rn)
        return km.constants(self.G, self.primary_mass, self.mass, self.inertia, self.primary_inertia,
                            length_scale=rn, momentum_scale=self.reduced_mass * vc,
                            full=self.potential == "coupled", contact=self.contact_distance)

    def state(self, position, velocity, q, omega, q_primary=(1.0, 0.0, 0.0, 0.0), omega_primary=(0.0, 0.0, 0.0)):
        """The flat state ``y`` (14 or 22 floats, :mod:`orbatt.core.mutual`).

        Parameters
        ----------
        position, velocity : Quantity (length, speed), (3,)
            The secondary relative to the primary, inertial components.
        q : array_like (4,)
            The secondary's attitude, body -> inertial, scalar first (normalized here).
        omega : Quantity (angular rate), (3,)
            The secondary's body rate, body axes.
        q_primary, omega_primary : as ``q``, ``omega``, for a rigid primary (ignored otherwise).
        """
        r = np.asarray(U.strip(position, U.LENGTH, "position"), dtype=np.float64)
        v = np.asarray(U.strip(velocity, U.LENGTH / U.TIME, "velocity"), dtype=np.float64)
        if r.shape != (3,) or v.shape != (3,):
            raise InputError("position, velocity: give three components each")
        n = km.N_RIGID if self.rigid_primary else km.N_POINT
        y = np.zeros(n)
        y[0:3] = r
        y[3:6] = self.reduced_mass * v
        y[6:14] = self._attitude(q, omega, self.inertia, "q", "omega")
        if self.rigid_primary:
            y[14:22] = self._attitude(q_primary, omega_primary, self.primary_inertia, "q_primary", "omega_primary")
        rn = float(np.linalg.norm(r))
        if not rn > self.contact_distance:
            raise InputError(f"position: the separation {rn:.6g} km is inside the bodies (contact at "
                             f"{self.contact_distance:.6g} km, the sum of the radii sqrt(tr I / M)); place the "
                             "secondary farther out")
        return y

    def state_from_elements(self, a, e, i, raan, argp, true_anomaly, q, omega, q_primary=(1.0, 0.0, 0.0, 0.0),
                            omega_primary=(0.0, 0.0, 0.0)):
        """:meth:`state` with the relative orbit from osculating elements about ``G (M1 + M2)``
        (angles from the inertial frame, i.e. the primary's axes at ``q1 = 1``)."""
        from ..orbits.kepler import KeplerOrbit

        orbit = KeplerOrbit(a, e, i, raan, argp, true_anomaly=true_anomaly, gm=self.gm * U.GM,
                            body_radius=None)
        r, v = orbit.state(0.0)  # plain km, km/s
        return self.state(r * U.LENGTH, v * (U.LENGTH / U.TIME), q, omega, q_primary, omega_primary)

    @staticmethod
    def _attitude(q, omega, inertia, qname, wname):
        q = np.asarray(q, dtype=np.float64)
        n = float(np.linalg.norm(q)) if q.shape == (4,) else 0.0
        if not (abs(n - 1.0) < 1e-6):
            raise InputError(f"{qname}: {q.tolist()} is not a unit quaternion (scalar first); give e.g. [1, 0, 0, 0]")
        q = q / n
        w = np.asarray(U.strip(omega, U.RATE, wname), dtype=np.float64)
        if w.shape != (3,):
            raise InputError(f"{wname}: give three body rates")
        g = inertia * w
        return np.concatenate([q, 2.0 * qt.mul(q, np.concatenate([[0.0], g]))])

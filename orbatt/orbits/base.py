"""The orbit-provider contract (``docs/design.md`` §5) and helpers shared by the providers."""
from __future__ import annotations

import warnings

import numpy as np
from astropy import constants as const
from astropy import units as u

from .. import quaternion as qt
from .. import units as U
from ..epoch import epoch_string, parse_epoch  # noqa: F401  (the old names: tests/test_epoch.py)
from ..errors import InputError

#: Earth's mass parameter (km^3 s^-2): astropy ``GM_earth`` (IAU 2015 nominal, 398600.4 km^3/s^2).
GM_EARTH = float(const.GM_earth.to_value(U.GM))
#: Earth's equatorial radius (km): astropy ``R_earth`` (IAU 2015 nominal, 6378.1 km); used only
#: for the periapsis check.
R_EARTH = float(const.R_earth.to_value(U.LENGTH))


class PeriapsisWarning(UserWarning):
    """The orbit's periapsis lies inside the central body (the point-mass model still
    integrates it; the paper's Sect. 6.2 orbit, ``a (1 - e) = 5600 km``, is such a case)."""


class OrbitProvider:
    """Base class of orbit providers: the contract the potentials, integrators and the
    Dataset builder rely on (``docs/design.md`` §1, §5).

    Times ``t`` are seconds since the orbit's epoch: float arrays of any shape (an astropy
    time Quantity is also accepted and converted); results have shape ``t.shape`` (+ the
    component axis). Inside, everything is in km, s, rad (:mod:`orbatt.units`).

    Methods
    -------
    radius(t)
        Orbit radius ``r`` (km), shape ``t.shape``.
    radial_direction(t)
        Unit vector ``r_vec / r`` in inertial ``S`` components, shape ``t.shape + (3,)``.
    orbital_quaternion(t)
        ``p``, shape ``t.shape + (4,)``: maps orbital ``O`` components to ``S``
        (``o1`` radial outwards, ``o3`` along ``r x v``, ``o2 = o3 x o1``); continuous in
        time along a 1-D ``t`` (``p`` and ``-p`` are the same frame).
    state(t)
        ``(position, velocity)`` in ``S``: km and km/s, each ``t.shape + (3,)``.
    true_anomaly(t)
        True anomaly (rad), continuous in time (not wrapped). Keplerian for
        :class:`~orbatt.orbits.KeplerOrbit`, osculating for
        :class:`~orbatt.orbits.ReboundOrbit`.
    orbital_rate(t)
        Angular velocity of ``O`` relative to ``S`` in ``O`` components (rad/s),
        ``(r a_n / h, 0, h / r^2)`` with ``h = |r x v|`` and ``a_n`` the acceleration
        along ``o3`` (zero for a Keplerian orbit).
    kernel()
        ``(kind, params, table)`` for the compiled gravity-gradient potential
        (:mod:`orbatt.core.potentials`): ``params = [GM, ...]`` (kind 2: the Keplerian
        ``orb`` vector of :mod:`orbatt.core.kepler`; kind 3: ``[GM, t_first, t_last]``
        with the samples in ``table``, :mod:`orbatt.core.sampled`).
    describe()
        ``dict`` of plain values (str, float, list) for Dataset attributes and scenario
        files; keys carry their units (``a_km``, ``inc_rad``, ...).

    Attributes
    ----------
    gm : float
        Central body's mass parameter (km^3 s^-2).
    period : Quantity
        Orbital period (s) (Keplerian; of the initial osculating orbit for REBOUND); the
        float is ``period_value``.
    epoch : astropy.time.Time or None
        The instant ``t = 0``.
    central_body : str
        ``"earth"`` or ``"custom"``.
    time_span : None or (float, float)
        ``(t_first, t_last)`` (s): the times the provider answers for (a sampled orbit);
        None: any time.
    """

    gm: float
    #: orbital period as a float in the orbit's time unit (s; normalized units for a
    #: dimensionless orbit); :attr:`period` is the same as a Quantity
    period_value: float
    #: True for an orbit in normalized units (plain numbers: lengths in the unit of ``a``,
    #: times in the unit ``gm`` implies); it acts only on dimensionless bodies
    dimensionless = False
    epoch = None
    central_body = "earth"
    name = "orbit"
    time_span = None

    @property
    def time_unit(self):
        """The unit of the orbit's times: ``s``, or dimensionless in normalized units."""
        return U.DIMENSIONLESS if self.dimensionless else U.TIME

    @property
    def period(self):
        """Orbital period as a Quantity (s, or dimensionless in normalized units); the float
        is :attr:`period_value`."""
        return self.period_value * self.time_unit

    # ---- contract (subclasses implement state(), kernel(), describe()) ------------------
    def state(self, t):  # pragma: no cover - abstract
        raise NotImplementedError

    def kernel(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def describe(self) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def radius(self, t):
        """Orbit radius (km) at ``t`` (s since epoch); shape ``t.shape``."""
        pos, _ = self.state(t)
        return np.linalg.norm(pos, axis=-1)

    def radial_direction(self, t):
        """Unit radial vector ``r_vec / r`` in ``S`` components; shape ``t.shape + (3,)``."""
        pos, _ = self.state(t)
        return pos / np.linalg.norm(pos, axis=-1)[..., None]

    def orbital_quaternion(self, t):
        """Orbital quaternion ``p`` (maps ``O`` to ``S``) from the position and velocity;
        shape ``t.shape + (4,)``, sign-continuous along a 1-D ``t``."""
        pos, vel = self.state(t)
        return frame_quaternion(pos, vel)

    def true_anomaly(self, t):
        """Osculating true anomaly (rad), unwrapped along a 1-D ``t``."""
        pos, vel = self.state(t)
        return _unwrapped_true_anomaly(pos, vel, self.gm)

    def quantities(self, t):
        """``(r, p, true_anomaly, position, velocity)`` at ``t``: what a result Dataset records
        (:meth:`radius`, :meth:`orbital_quaternion`, :meth:`true_anomaly`, :meth:`state`),
        in one call. Where a provider keeps this class's three methods, all come from one
        :meth:`state`; a provider may override it to evaluate its orbit once."""
        pos, vel = self.state(t)
        cls = type(self)
        if (cls.radius is OrbitProvider.radius and cls.orbital_quaternion is OrbitProvider.orbital_quaternion
                and cls.true_anomaly is OrbitProvider.true_anomaly):
            return (np.linalg.norm(pos, axis=-1), frame_quaternion(pos, vel),
                    _unwrapped_true_anomaly(pos, vel, self.gm), pos, vel)
        return self.radius(t), self.orbital_quaternion(t), self.true_anomaly(t), pos, vel

    def orbital_rate(self, t):
        """Angular velocity of ``O`` relative to ``S``, ``O`` components (rad/s):
        ``(r a_n / h, 0, h / r^2)``."""
        pos, vel = self.state(t)
        acc = self.acceleration(t)
        return _orbital_rate(pos, vel, acc)

    def acceleration(self, t):
        """Acceleration in ``S`` (km/s^2); default: the central point mass only."""
        pos, _ = self.state(t)
        r = np.linalg.norm(pos, axis=-1)[..., None]
        return -self.gm * pos / r**3

    def __repr__(self):
        d = self.describe()
        inner = ", ".join(f"{k}={v!r}" for k, v in d.items() if k != "type")
        return f"{type(self).__name__}({inner})"


# ---- helpers ------------------------------------------------------------------------------
def as_times(t, name="t"):
    """Times (s since the epoch) as a float64 array; a time Quantity is converted."""
    if isinstance(t, u.Quantity):
        out = U.strip(t, U.TIME, name)
    else:
        try:
            out = np.asarray(t, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"{name}: {t!r} is not an array of times (seconds since the epoch)") from None
        if not np.isfinite(out).all():
            raise InputError(f"{name}: contains non-finite times; give finite seconds since the epoch")
    return out


def frame_quaternion(pos, vel):
    """Orbital quaternion ``p`` (maps ``O`` to ``S``) of position/velocity arrays
    ``(..., 3)`` in ``S``: ``o1 = r / |r|``, ``o3 = (r x v) / |r x v|``, ``o2 = o3 x o1``.

    Shepperd's method (:func:`orbatt.quaternion.from_matrix`); along a 1-D time axis the
    sign is made continuous (``p_k . p_{k-1} >= 0``)."""
    pos = np.asarray(pos, dtype=np.float64)
    vel = np.asarray(vel, dtype=np.float64)
    o1 = pos / np.linalg.norm(pos, axis=-1)[..., None]
    h = np.cross(pos, vel)
    o3 = h / np.linalg.norm(h, axis=-1)[..., None]
    o2 = np.cross(o3, o1)
    R = np.stack([o1, o2, o3], axis=-1)  # columns: O axes in S components
    p = qt.from_matrix(R)
    if p.ndim == 2 and p.shape[0] > 1:
        p = sign_continuous(p)
    return p


def sign_continuous(p):
    """Flip signs along axis 0 so that consecutive quaternions have ``p_k . p_{k-1} >= 0``."""
    p = np.array(p, dtype=np.float64, copy=True)
    d = np.sum(p[1:] * p[:-1], axis=-1)
    flips = np.concatenate([[1.0], np.cumprod(np.where(d < 0.0, -1.0, 1.0))])
    return p * flips[:, None]


def _unwrapped_true_anomaly(pos, vel, gm):
    """:func:`osculating_true_anomaly`, unwrapped along a 1-D time axis."""
    f = osculating_true_anomaly(pos, vel, gm)
    return np.unwrap(f) if f.ndim == 1 and f.size > 1 else f


def osculating_true_anomaly(pos, vel, gm):
    """Osculating true anomaly (rad, in ``(-pi, pi]``) from position/velocity in ``S``;
    for a near-circular orbit (``e < 1e-12``) the argument of latitude from the node."""
    el = elements_from_state(pos, vel, gm)
    return el["f"]


def elements_from_state(pos, vel, gm):
    """Osculating classical elements of ``pos`` (km), ``vel`` (km/s) in ``S``, arrays of
    shape ``(..., 3)``, for ``gm`` (km^3 s^-2).

    Returns a dict of arrays: ``a`` (km; negative for hyperbolic), ``e``, ``inc``,
    ``raan``, ``argp``, ``f`` (rad). Conventions for the singular cases: an equatorial
    orbit (``sin i < 1e-14``) has ``raan = 0`` (node line along ``s1``); a circular one
    (``e < 1e-12``) has ``argp = 0`` (periapsis at the node), so ``f`` is the argument of
    latitude.
    """
    r = np.asarray(pos, dtype=np.float64)
    v = np.asarray(vel, dtype=np.float64)
    rn = np.linalg.norm(r, axis=-1)
    v2 = np.sum(v * v, axis=-1)
    h = np.cross(r, v)
    hn = np.linalg.norm(h, axis=-1)
    what = h / hn[..., None]
    inc = np.arctan2(np.hypot(h[..., 0], h[..., 1]), h[..., 2])
    # node direction N = s3 x h (normalized); equatorial: s1
    nvec = np.stack([-h[..., 1], h[..., 0], np.zeros_like(hn)], axis=-1)
    nn = np.linalg.norm(nvec, axis=-1)
    equatorial = nn < 1e-14 * hn
    N = np.where(equatorial[..., None], np.array([1.0, 0.0, 0.0]), nvec / np.where(nn > 0, nn, 1.0)[..., None])
    raan = np.where(equatorial, 0.0, np.arctan2(N[..., 1], N[..., 0]))
    W = np.cross(what, N)  # in-plane, 90 degrees ahead of the node
    evec = ((v2 - gm / rn)[..., None] * r - np.sum(r * v, axis=-1)[..., None] * v) / gm
    e = np.linalg.norm(evec, axis=-1)
    circular = e < 1e-12
    argp = np.where(circular, 0.0, np.arctan2(np.sum(evec * W, axis=-1), np.sum(evec * N, axis=-1)))
    ulat = np.arctan2(np.sum(r * W, axis=-1), np.sum(r * N, axis=-1))
    f = np.angle(np.exp(1j * (ulat - argp)))
    a = 1.0 / (2.0 / rn - v2 / gm)
    return {"a": a, "e": e, "inc": inc, "raan": raan, "argp": argp, "f": f}


def _orbital_rate(pos, vel, acc):
    r = np.linalg.norm(pos, axis=-1)
    h = np.cross(pos, vel)
    hn = np.linalg.norm(h, axis=-1)
    an = np.sum(acc * h, axis=-1) / hn
    return np.stack([r * an / hn, np.zeros_like(r), hn / r**2], axis=-1)


def resolve_gm(gm, central_body, dimensionless=False):
    """``(gm km^3/s^2, central_body)`` from the constructor arguments: ``gm=None`` means the
    Earth (astropy ``GM_earth``). A ``dimensionless`` orbit needs ``gm`` as a plain number
    (normalized units); a dimensional one needs a Quantity."""
    if dimensionless:
        if gm is None or isinstance(gm, (u.Quantity, str)):
            raise InputError(f"gm: {gm!r} with a plain-number a; a dimensionless orbit needs gm as a plain number "
                             "too (gm=1.0, a=1.0 make the mean motion 1), or give a as a Quantity")
    elif gm is not None and not isinstance(gm, (u.Quantity, str)):
        raise InputError(f"gm: {gm!r} has no unit but a is dimensional; give gm as a Quantity such as "
                         "'398600.4418 km3 / s2', or give a as a plain number too (normalized units)")
    if gm is None:
        if central_body not in (None, "earth"):
            raise InputError(f"central_body: {central_body!r} is not known; give gm (e.g. "
                             "'4902.8 km3 / s2') for a body other than 'earth'")
        return float(GM_EARTH), "earth"
    value = U.strip(gm, U.GM, "gm", allow_plain=dimensionless)
    if value.shape != ():
        raise InputError(f"gm: expected one mass parameter, got {gm!r}")
    value = float(value)
    if not value > 0.0:
        raise InputError(f"gm: {gm!r} must be positive (the central body's G M, e.g. "
                         "'398600.4418 km3 / s2')")
    return value, (central_body if central_body is not None else "custom")


def check_periapsis(a, e, body_radius, central_body, stacklevel=3):
    """Warn (:class:`PeriapsisWarning`) if ``a (1 - e)`` is inside ``body_radius`` (km)."""
    if body_radius is None:
        return
    rp = a * (1.0 - e)
    if rp < body_radius:
        warnings.warn(f"periapsis a (1 - e) = {rp:.6g} km is inside the central body ({central_body}, "
                      f"radius {body_radius:.6g} km); the point-mass orbit is still computed. Raise a or "
                      "lower e for a physical orbit, or pass body_radius=None to silence this check",
                      PeriapsisWarning, stacklevel=stacklevel)

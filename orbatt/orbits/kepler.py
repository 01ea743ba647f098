"""The Keplerian orbit provider: classical elements with units at the boundary, compiled
Kepler solve (:mod:`orbatt.core.kepler`) inside."""
from __future__ import annotations

import math

import numpy as np
from astropy import units as u

from .. import units as U
from ..core import kepler as kk
from ..core import potentials as kp
from ..epoch import epoch_string, parse_epoch
from ..errors import InputError
from .base import R_EARTH, OrbitProvider, as_times, check_periapsis, elements_from_state, resolve_gm


def _angle(value, name):
    out = U.strip(value, U.ANGLE, name)
    if out.shape != ():
        raise InputError(f"{name}: expected one angle, got {value!r}")
    return float(out)


def _mean_from_true(f, e):
    """Mean anomaly of the true anomaly ``f`` (same revolution)."""
    E = 2.0 * math.atan2(math.sqrt(1.0 - e) * math.sin(0.5 * f), math.sqrt(1.0 + e) * math.cos(0.5 * f))
    E += 2.0 * math.pi * round((f - E) / (2.0 * math.pi))
    return _mean_from_eccentric(E, e)


def _mean_from_eccentric(E, e):
    return E - e * math.sin(E)


class KeplerOrbit(OrbitProvider):
    """An elliptic Keplerian orbit about a point mass (``docs/design.md`` §1, §5).

    Parameters
    ----------
    a : Quantity (length), str, or float
        Semi-major axis, ``> 0``. A plain number makes a *dimensionless* orbit (normalized
        units, as in the spin-orbit literature): ``gm`` must then be a plain number too,
        lengths are in the unit of ``a`` and times in the unit ``gm`` implies (``gm = 1,
        a = 1`` make the mean motion 1); it acts on dimensionless bodies only.
    e : float or dimensionless Quantity
        Eccentricity, ``0 <= e < 1``. Parabolic and hyperbolic orbits (``e >= 1``) are
        refused with :class:`~orbatt.errors.InputError`.
    i, raan, argp : Quantity (angle) or str, or float (radians)
        Inclination (``0 <= i <= 180 deg``), right ascension of the ascending node and
        argument of periapsis, all relative to the inertial frame ``S`` (its ``s1-s2``
        plane is the reference plane, ``s1`` the reference direction).
    true_anomaly, mean_anomaly, eccentric_anomaly : Quantity (angle), str or float (rad)
        The anomaly at the epoch (``t = 0``): give at most one; default true anomaly 0.
    gm : Quantity (km^3/s^2), str, or float, optional
        The central body's ``G M``. Default: the Earth (astropy ``GM_earth``). A plain
        number with a plain ``a`` (required then).
    central_body : str, optional
        Name recorded in :meth:`describe`: ``"earth"`` (default when ``gm`` is not given)
        or any label (default ``"custom"`` with ``gm``).
    epoch : astropy.time.Time or str, optional
        The instant ``t = 0`` (a string is parsed as UTC).
    body_radius : Quantity (length), optional
        Radius of the central body for the periapsis check: a periapsis inside it
        **warns** (:class:`~orbatt.orbits.PeriapsisWarning`), it is not refused (the
        paper's Sect. 6.2 orbit has ``a (1 - e) = 5600 km``). Default: Earth's equatorial
        radius for the Earth, no check for a custom ``gm``; ``None`` disables it.

    Notes
    -----
    The mean anomaly is ``M(t) = M0 + n t``, ``n = sqrt(GM / a^3)``; Kepler's equation is
    solved for arrays of times by the compiled solver (ulp-level residual for every
    ``0 <= e < 1``, warm-started along the array). ``p(t)`` is the 3-1-3 Euler-parameter
    quaternion of ``(raan, i, u = argp + f)``.

    Examples
    --------
    The paper's Sect. 6.2 orbit:

    >>> import astropy.units as u
    >>> orbit = KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg,
    ...                     true_anomaly=0 * u.deg, body_radius=None)
    >>> orbit.period.round(1)
    <Quantity 5828.5 s>
    """

    name = "kepler"

    def __init__(self, a, e, i, raan, argp, *, true_anomaly=None, mean_anomaly=None, eccentric_anomaly=None,
                 gm=None, central_body=None, epoch=None, body_radius="default"):
        dimless = not isinstance(a, (u.Quantity, str))
        if dimless and gm is None:
            raise InputError(f"a: {a!r} has no unit; give a Quantity such as '{a} km', or give gm as a plain number "
                             "too (normalized units: gm=1.0, a=1.0 make the mean motion 1)")
        av = U.strip(a, U.LENGTH, "a", allow_plain=dimless)
        if av.shape != ():
            raise InputError(f"a: expected one semi-major axis, got {a!r}")
        av = float(av)
        ev = U.strip(e, U.DIMENSIONLESS, "e")
        if ev.shape != ():
            raise InputError(f"e: expected one eccentricity, got {e!r}")
        ev = float(ev)
        if ev < 0.0:
            raise InputError(f"e: {e!r} is negative; the eccentricity is 0 <= e < 1")
        if ev >= 1.0:
            raise InputError(f"e: {e!r} >= 1 (parabolic or hyperbolic orbit) is not supported; "
                             "give an elliptic orbit, 0 <= e < 1")
        if not av > 0.0:
            raise InputError(f"a: {a!r} must be positive (semi-major axis of an elliptic orbit); "
                             "give e.g. '7000 km'")
        inc = _angle(i, "i")
        if not 0.0 <= inc <= math.pi:
            raise InputError(f"i: {i!r} is outside [0, 180] deg; give the inclination in that range "
                             "(a retrograde orbit has i > 90 deg)")
        self.dimensionless = dimless
        self.gm, self.central_body = resolve_gm(gm, central_body, dimless)
        if dimless and epoch is not None:
            raise InputError(f"epoch: {epoch!r} given for a dimensionless orbit (plain a and gm), whose time unit "
                             "is not the second; leave the epoch out or give a and gm as Quantities")
        given = [(k, v) for k, v in (("true_anomaly", true_anomaly), ("mean_anomaly", mean_anomaly),
                                     ("eccentric_anomaly", eccentric_anomaly)) if v is not None]
        if len(given) > 1:
            raise InputError(f"{given[1][0]}: give only one of true_anomaly, mean_anomaly, eccentric_anomaly "
                             f"(got {', '.join(k for k, _ in given)})")
        kind, value = given[0] if given else ("true_anomaly", 0.0)
        anom = _angle(value, kind)
        if kind == "true_anomaly":
            M0 = _mean_from_true(anom, ev)
        elif kind == "eccentric_anomaly":
            M0 = _mean_from_eccentric(anom, ev)
        else:
            M0 = anom
        self.a_value = av
        self._a_unit = a.unit if isinstance(a, u.Quantity) else (u.Quantity(a).unit if isinstance(a, str) else None)
        self.e = ev
        self.inc = inc
        self.raan = _angle(raan, "raan")
        self.argp = _angle(argp, "argp")
        self.M0 = M0
        self.n_value = math.sqrt(self.gm / av**3)
        self.period_value = 2.0 * math.pi / self.n_value
        self.epoch = parse_epoch(epoch)
        if isinstance(body_radius, str) and body_radius == "default":
            self.body_radius = R_EARTH if self.central_body == "earth" else None
        elif body_radius is None:
            self.body_radius = None
        else:
            br = U.strip(body_radius, U.LENGTH, "body_radius", allow_plain=dimless)
            if br.shape != () or not br > 0:
                raise InputError(f"body_radius: {body_radius!r} must be one positive length, or None")
            self.body_radius = float(br)
        check_periapsis(av, ev, self.body_radius, self.central_body)
        self._orb = kk.orbit_vector(av, ev, inc, self.raan, self.argp, M0, self.n_value)

    # ---- in the user's units ----------------------------------------------------------
    @property
    def a(self):
        """Semi-major axis as a Quantity, in the unit it was given in (km for a string such
        as ``"7000 km"``; dimensionless in normalized units); the float in km is ``a_value``."""
        if self.dimensionless:
            return self.a_value * U.DIMENSIONLESS
        q = self.a_value * U.LENGTH
        return q.to(self._a_unit) if self._a_unit is not None else q

    @property
    def n(self):
        """Mean motion ``sqrt(GM / a^3)`` as a Quantity (rad/s; dimensionless in normalized
        units); the float is ``n_value``."""
        return self.n_value * (U.DIMENSIONLESS if self.dimensionless else U.RATE)

    def __repr__(self):
        if self.dimensionless:
            head = f"a={self.a_value:.10g}, gm={self.gm:.10g} (normalized units)"
            tail = f"period={self.period_value:.10g}"
        else:
            head = f"a={self.a:.10g}, central_body={self.central_body!r}, gm={self.gm:.10g} km^3 / s^2"
            tail = f"period={self.period_value:.10g} s"
        deg = 180.0 / math.pi
        ep = f", epoch={epoch_string(self.epoch)}" if self.epoch is not None else ""
        return (f"KeplerOrbit({head}, e={self.e:.10g}, i={self.inc * deg:.10g} deg, raan={self.raan * deg:.10g} deg, "
                f"argp={self.argp * deg:.10g} deg, mean_anomaly={self.M0 * deg:.10g} deg, {tail}{ep})")

    # ---- alternative constructor ------------------------------------------------------
    @classmethod
    def from_state(cls, position, velocity, *, gm=None, central_body=None, epoch=None, body_radius="default"):
        """The osculating Keplerian orbit of a state vector.

        Parameters
        ----------
        position : Quantity (length), shape (3,)
            Position relative to the central body in ``S`` components (3 plain numbers: a
            dimensionless orbit, then ``velocity`` and ``gm`` plain too).
        velocity : Quantity (speed), shape (3,)
            Velocity in ``S`` components.
        gm, central_body, epoch, body_radius
            As for :class:`KeplerOrbit`.

        Raises
        ------
        InputError
            A hyperbolic or parabolic state (``e >= 1``, or non-positive ``a``), a
            rectilinear one (``r x v = 0``), or malformed vectors.

        Notes
        -----
        Singular element sets follow :func:`orbatt.orbits.base.elements_from_state`:
        ``raan = 0`` for an equatorial orbit, ``argp = 0`` for a circular one; the state is
        reproduced whatever the convention.
        """
        dimless = not isinstance(position, (u.Quantity, str))
        r = U.strip(position, U.LENGTH, "position", allow_plain=dimless)
        v = U.strip(velocity, U.LENGTH / U.TIME, "velocity", allow_plain=dimless)
        if r.shape != (3,) or v.shape != (3,):
            raise InputError(f"position/velocity: expected 3 components each, got shapes {r.shape}, {v.shape}")
        gmv, _ = resolve_gm(gm, central_body, dimless)
        if np.linalg.norm(np.cross(r, v)) <= 1e-14 * np.linalg.norm(r) * max(np.linalg.norm(v), 1e-300):
            raise InputError(f"position/velocity: {r.tolist()} km, {v.tolist()} km/s is a rectilinear "
                             "(radial) motion with no orbit plane; give a state with angular momentum")
        el = elements_from_state(r, v, gmv)
        if not (el["a"] > 0 and el["e"] < 1.0):
            raise InputError(f"position/velocity: the state has e = {float(el['e']):.6g} (specific energy >= 0): "
                             "a parabolic or hyperbolic orbit is not supported; give an elliptic state")
        lu, gu = (1.0, 1.0) if dimless else (U.LENGTH, U.GM)
        return cls(float(el["a"]) * lu, float(el["e"]), float(el["inc"]), float(el["raan"]),
                   float(el["argp"]), true_anomaly=float(el["f"]), gm=gmv * gu if gm is not None else None,
                   central_body=central_body, epoch=epoch, body_radius=body_radius)

    # ---- evaluation -------------------------------------------------------------------
    def _many(self, t):
        t = as_times(t)
        flat = np.ascontiguousarray(t.reshape(-1))
        E, f, r, pos, vel = kk.kepler_many(flat, self._orb, self.gm)
        return t.shape, E, f, r, pos, vel

    def mean_anomaly(self, t):
        """Mean anomaly ``M0 + n t`` (rad, not wrapped); shape ``t.shape``."""
        t = as_times(t)
        return self.M0 + self.n_value * t

    def eccentric_anomaly(self, t):
        """Eccentric anomaly (rad, on the revolution of the mean anomaly)."""
        shape, E, *_ = self._many(t)
        return E.reshape(shape)

    def true_anomaly(self, t):
        """True anomaly (rad, on the revolution of the mean anomaly: continuous in time)."""
        shape, _, f, *_ = self._many(t)
        return f.reshape(shape)

    def radius(self, t):
        """Orbit radius (km); shape ``t.shape``."""
        shape, _, _, r, _, _ = self._many(t)
        return r.reshape(shape)

    def radial_direction(self, t):
        """Unit radial vector in ``S``; shape ``t.shape + (3,)``."""
        shape, _, _, r, pos, _ = self._many(t)
        return (pos / r[:, None]).reshape(shape + (3,))

    def state(self, t):
        """``(position km, velocity km/s)`` in ``S``; each ``t.shape + (3,)``."""
        shape, _, _, _, pos, vel = self._many(t)
        return pos.reshape(shape + (3,)), vel.reshape(shape + (3,))

    def orbital_quaternion(self, t):
        """``p``: the 3-1-3 quaternion of ``(raan, i, u = argp + f)`` (maps ``O`` to ``S``);
        continuous in time (``u`` is not wrapped); shape ``t.shape + (4,)``."""
        return self._frame(self.true_anomaly(t))

    def quantities(self, t):
        """``(r, p, true_anomaly, position, velocity)`` at ``t`` from one solution of
        Kepler's equation (the values of the separate methods)."""
        shape, _, f, r, pos, vel = self._many(t)
        f = f.reshape(shape)
        return r.reshape(shape), self._frame(f), f, pos.reshape(shape + (3,)), vel.reshape(shape + (3,))

    def _frame(self, f):
        """``p`` of the true anomalies ``f`` (:meth:`orbital_quaternion`)."""
        uu = self.argp + f
        ci = math.cos(0.5 * self.inc)
        si = math.sin(0.5 * self.inc)
        sp = 0.5 * (self.raan + uu)
        sm = 0.5 * (self.raan - uu)
        # np.stack([...], axis=-1) of the same values, written into one array (np.stack costs more)
        out = np.empty(sp.shape + (4,))
        out[..., 0] = ci * np.cos(sp)
        out[..., 1] = si * np.cos(sm)
        out[..., 2] = si * np.sin(sm)
        out[..., 3] = ci * np.sin(sp)
        return out

    def orbital_rate(self, t):
        """Angular velocity of ``O`` relative to ``S`` in ``O`` components (rad/s):
        ``(0, 0, df/dt)`` with ``df/dt = h / r^2``."""
        r = self.radius(t)
        h = math.sqrt(self.gm * self.a_value * (1.0 - self.e) * (1.0 + self.e))
        z = np.zeros_like(r)
        return np.stack([z, z, h / r**2], axis=-1)

    def acceleration(self, t):
        """Point-mass acceleration ``-GM r / r^3`` in ``S`` (km/s^2)."""
        pos, _ = self.state(t)
        r = np.linalg.norm(pos, axis=-1)[..., None]
        return -self.gm * pos / r**3

    # ---- kernel and description -------------------------------------------------------
    def kernel(self):
        """``(GRAVITY_GRADIENT_KEPLER, [GM, *orb], EMPTY_TABLE)`` for the compiled potential."""
        return kp.GRAVITY_GRADIENT_KEPLER, np.concatenate([[self.gm], self._orb]), kp.EMPTY_TABLE

    @property
    def elements(self):
        """``dict`` of the elements at the epoch: ``a`` (km), ``e``, ``i``, ``raan``,
        ``argp``, ``mean_anomaly``, ``true_anomaly`` (rad)."""
        return {"a": self.a_value, "e": self.e, "i": self.inc, "raan": self.raan, "argp": self.argp,
                "mean_anomaly": self.M0, "true_anomaly": float(self.true_anomaly(0.0))}

    def describe(self):
        """Plain description: ``type``, ``central_body``, ``gm_km3_s2``, ``a_km``, ``e``,
        ``i_rad``, ``raan_rad``, ``argp_rad``, ``mean_anomaly_rad`` (at the epoch),
        ``period_s``, and ``epoch`` (ISO UTC) when there is one; a dimensionless orbit has
        ``units = "normalized"`` and ``gm``, ``a``, ``period`` in its units instead."""
        if self.dimensionless:  # normalized units: the keys carry no unit
            d = {"type": "kepler", "units": "normalized", "central_body": self.central_body, "gm": self.gm,
                 "a": self.a_value}
        else:
            d = {"type": "kepler", "central_body": self.central_body, "gm_km3_s2": self.gm, "a_km": self.a_value}
        d.update({"e": self.e, "i_rad": self.inc, "raan_rad": self.raan, "argp_rad": self.argp,
                  "mean_anomaly_rad": self.M0, ("period" if self.dimensionless else "period_s"): self.period_value})
        if self.epoch is not None:
            d["epoch"] = epoch_string(self.epoch)
        return d

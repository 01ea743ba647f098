"""Attitude control and reaction wheels, with units at the boundary (kernels in
:mod:`orbatt.core.control` and :mod:`orbatt.core.gyrostat`; physics in ``docs/design.md`` §10).

* :class:`ReactionWheel`: a rotor of the body (``RigidBody(..., wheels=[...])``), which makes it
  a gyrostat: the state becomes ``(q, Q, h)`` with ``h`` the rotors' axial momenta, and
  ``g = 1/2 Im(q~ Q)`` is the **total** angular momentum. The body's ``inertia`` is that of
  the whole spacecraft with the rotors locked.
* :class:`PDControl`: quaternion feedback towards the orbital frame, an inertial attitude,
  the Sun, a ground target or the geodetic nadir, made by an ideal actuator, the wheels or
  magnetorquers.
* :class:`BDotControl`: B-dot detumbling with magnetorquers.

A control law is a peer of the potential: ``orbatt.propagate(..., control=law)`` (or carried
by :class:`orbatt.EnvironmentTorques`, ``control=``, which samples the fields the law reads:
the Sun, the magnetic field, :meth:`~orbatt.EnvironmentTorques.field_table`); the law gives its
own model row (``model_row``), which :func:`orbatt.model_assembly.assemble` packs after the
potential's terms and the wheels' row. Rate-dependent laws
need an adaptive method (``dop853`` or scipy's); wheels too (their state is integrated).
"""
from __future__ import annotations

import numpy as np
from astropy import units as u

from . import units as U
from .core import control as kc
from .core import model as km
from .errors import InputError

__all__ = ["ReactionWheel", "PDControl", "BDotControl", "AXIS_TOLERANCE", "MAX_WHEELS", "wheels_row",
           "wheel_axes_span", "reaction_wheel", "scalar_value", "flight_period", "PERIOD_RANGE", "command_slots",
           "limit_axes"]

#: a wheel axis or a Sun-pointing axis must have |a| = 1 within this
AXIS_TOLERANCE = 1e-6
#: most reaction wheels of a body
MAX_WHEELS = 16
#: PD targets and actuators by name
TARGETS = {"orbital": kc.TARGET_ORBITAL, "inertial": kc.TARGET_INERTIAL, "sun": kc.TARGET_SUN,
           "ground": kc.TARGET_GROUND, "nadir": kc.TARGET_NADIR}
#: the targets a body axis points at (``target_axis``), along the line of sight
POINTING_TARGETS = ("sun", "ground")
#: the frames a PD law holds the body axes on, turned by the optional offset ``target_q``
FRAME_TARGETS = ("orbital", "nadir")
ACTUATORS = ("ideal", "wheels", "magnetorquers")


def scalar_value(x, unit, name, *, positive=False, nonnegative=False, allow_none=False):
    """A float of ``x`` (Quantity or string, :func:`orbatt.units.strip`) in ``unit``, checked;
    None passes if allowed."""
    if x is None:
        if allow_none:
            return None
        raise InputError(f"{name}: required")
    v = U.strip(x, unit, name)
    if v.shape != ():
        raise InputError(f"{name}: expected one value, got {x}")
    v = float(v)
    if positive and not v > 0:
        raise InputError(f"{name}: {x} must be positive")
    if nonnegative and not v >= 0:
        raise InputError(f"{name}: {x} must not be negative")
    return v


def wheel_axes_span(wheels):
    """Whether the spin axes of ``wheels`` span three dimensions (else a wheel-actuated law
    leaves an axis uncontrollable)."""
    return bool(wheels) and np.linalg.matrix_rank(np.array([w.axis for w in wheels]), tol=1e-9) == 3


def _unit_vector(v, name):
    a = np.asarray(v, dtype=np.float64)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(f"{name}: expected 3 finite components, got {v!r}")
    n = float(np.linalg.norm(a))
    if abs(n - 1.0) > AXIS_TOLERANCE:
        raise InputError(f"{name}: {a.tolist()} is not a unit vector (|a| = {n:.9g}); give it normalized")
    return a / n


class ReactionWheel:
    """A reaction wheel: a symmetric rotor spinning about a body axis.

    Parameters
    ----------
    axis : 3 floats
        Unit spin axis (body axes).
    inertia : Quantity (mass x length^2)
        Axial moment of the rotor (e.g. ``4e-5 kg m^2``).
    speed : Quantity (angular velocity), optional
        Rotor speed relative to the body at the start (``"1000 rpm"``; default 0).
    max_torque : Quantity (N m), optional
        Motor torque limit (default: none).
    max_speed : Quantity (angular velocity), optional
        Speed limit: the motor does not push the rotor beyond it (default: none).
    friction_coulomb : Quantity (N m), optional
        Coulomb friction of the bearing: ``coulomb tanh(speed / friction_width)`` against the
        rotor's speed relative to the body (default: none).
    friction_viscous : Quantity (N m s), optional
        Viscous friction: ``viscous speed`` (default: none).
    friction_width : Quantity (angular velocity), optional
        The speed over which the Coulomb term turns (default 0.1 rad/s: smooth, so that the step
        loop does not chatter through zero speed; Basilisk's ``omegaLimitCycle`` is the same idea).
    """

    #: the plain settings (:meth:`settings`, :func:`reaction_wheel`): key -> SI unit
    UNITS = {"axis": None, "inertia": "kg m2", "speed": "rad / s", "max_torque": "N m", "max_speed": "rad / s",
             "friction_coulomb": "N m", "friction_viscous": "N m s", "friction_width": "rad / s"}
    #: the Coulomb friction's default width (rad/s)
    FRICTION_WIDTH = 0.1

    def __init__(self, axis, inertia, speed=0.0 * u.rad / u.s, *, max_torque=None, max_speed=None, name=None,
                 friction_coulomb=None, friction_viscous=None, friction_width=None):
        self.axis = _unit_vector(axis, "axis")
        self.inertia_kg_m2 = scalar_value(inertia, u.kg * u.m**2, "inertia", positive=True)
        self.speed_rad_s = scalar_value(speed, u.rad / u.s, "speed")
        self.max_torque_n_m = scalar_value(max_torque, u.N * u.m, "max_torque", positive=True, allow_none=True)
        self.max_speed_rad_s = scalar_value(max_speed, u.rad / u.s, "max_speed", positive=True, allow_none=True)
        if self.max_speed_rad_s is not None and abs(self.speed_rad_s) > self.max_speed_rad_s:
            raise InputError(f"speed: {self.speed_rad_s:.6g} rad/s is above max_speed = {self.max_speed_rad_s:.6g} "
                             "rad/s; lower the initial speed or raise max_speed")
        self.friction_coulomb = scalar_value(friction_coulomb, u.N * u.m, "friction_coulomb", nonnegative=True,
                                       allow_none=True)
        self.friction_viscous = scalar_value(friction_viscous, u.N * u.m * u.s, "friction_viscous", nonnegative=True,
                                       allow_none=True)
        self.friction_width = scalar_value(friction_width, u.rad / u.s, "friction_width", positive=True, allow_none=True)
        if self.friction_width is not None and self.friction_coulomb is None:
            raise InputError("friction_width: only with friction_coulomb (the speed over which it turns)")
        self.name = name

    def settings(self):
        """The plain settings (SI floats, :data:`UNITS`) that :func:`reaction_wheel` makes this
        wheel of again."""
        return {"axis": self.axis.tolist(), "inertia": self.inertia_kg_m2, "speed": self.speed_rad_s,
                "max_torque": self.max_torque_n_m, "max_speed": self.max_speed_rad_s,
                "friction_coulomb": self.friction_coulomb, "friction_viscous": self.friction_viscous,
                "friction_width": self.friction_width}

    @property
    def inertia(self):
        """Axial moment of the rotor (kg km^2, the internal unit)."""
        return U.to_kernel(self.inertia_kg_m2, "inertia")

    def describe(self):
        d = {"axis": self.axis.tolist(), "inertia_kg_m2": self.inertia_kg_m2, "speed_rad_s": self.speed_rad_s,
             "max_torque_N_m": self.max_torque_n_m, "max_speed_rad_s": self.max_speed_rad_s}
        for key, unit in (("friction_coulomb", "N_m"), ("friction_viscous", "N_m_s"), ("friction_width", "rad_s")):
            if getattr(self, key) is not None:
                d[f"{key}_{unit}"] = getattr(self, key)
        return d

    def _key(self):
        return (tuple(self.axis), self.inertia_kg_m2, self.speed_rad_s, self.max_torque_n_m, self.max_speed_rad_s,
                self.friction_coulomb, self.friction_viscous, self.friction_width)

    def __eq__(self, other):
        return isinstance(other, ReactionWheel) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        return (f"ReactionWheel(axis={self.axis.tolist()}, inertia={self.inertia_kg_m2:.4g} kg m^2, "
                f"speed={self.speed_rad_s:.6g} rad/s)")


#: the shortest flight-software period (s) and the longest: a law at more than a MHz, or held
#: for more than a year, describes no flight software
PERIOD_RANGE = (1e-6, 3.2e7)


def flight_period(period):
    """The flight-software period in s (None: a continuous law), checked."""
    v = scalar_value(period, u.s, "period", positive=True, allow_none=True)
    if v is not None and not PERIOD_RANGE[0] <= v <= PERIOD_RANGE[1]:
        raise InputError(f"period: {v:.6g} s is outside [{PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}] s; give the flight "
                         "software's rate as its period (e.g. '0.1 s' for 10 Hz), or leave it out for a continuous law")
    return v


def _location(loc):
    """``(latitude rad, longitude rad, height m)`` of a ground target (Quantities or plain rad,
    rad, m), checked."""
    if loc is None:
        raise InputError("target_location: target = 'ground' needs [latitude, longitude, height], e.g. "
                         "['43.6 deg', '1.44 deg', '150 m']")
    if isinstance(loc, u.Quantity) or not hasattr(loc, "__len__") or len(loc) != 3:
        raise InputError(f"target_location: expected [latitude, longitude, height], got {loc!r}")
    lat = scalar_value(loc[0], u.rad, "target_location latitude") if isinstance(loc[0], (u.Quantity, str)) else float(loc[0])
    lon = scalar_value(loc[1], u.rad, "target_location longitude") if isinstance(loc[1], (u.Quantity, str)) else float(loc[1])
    h = scalar_value(loc[2], u.m, "target_location height") if isinstance(loc[2], (u.Quantity, str)) else float(loc[2])
    if not (abs(lat) <= np.pi / 2 and np.isfinite(lon) and abs(lon) <= 4 * np.pi and -1.2e4 <= h <= 1e5):
        raise InputError(f"target_location: latitude {np.degrees(lat):.6g} deg (within +-90), longitude "
                         f"{np.degrees(lon):.6g} deg (within +-720), height {h:.6g} m (within -12 km .. 100 km)")
    return (lat, lon, h)


def limit_axes(law):
    """The principal axes ``R`` (``x_B = R x_P``) of a full inertia tensor along whose body axes
    the per-axis limits of ``law`` clip, or None (the law's axes are the body axes): the
    attribute ``limit_axes`` that :func:`orbatt.frame_boundary.principal_control` gives the law's
    copy in the principal frame."""
    return getattr(law, "limit_axes", None)


def _axes_key(law):
    axes = limit_axes(law)
    return None if axes is None else np.asarray(axes, dtype=np.float64).tobytes()


def command_slots(period, wheels):
    """The flight-software slots of a law's kernel row (:func:`orbatt.core.control.flight_software`):
    its ``period`` in s (None: continuous, 0), ticks from ``t = 0``, and its held command after
    the ``wheels``' momenta in the state."""
    return {"period": 0.0 if period is None else period, "phase": 0.0, "z0": 8 + len(wheels)}


def wheels_row(wheels):
    """The :data:`~orbatt.core.model.WHEELS` row ``(kind, params, None)`` of a list of wheels
    (internal units)."""
    inf = np.inf
    return (km.WHEELS, kc.wheel_params(
        [w.axis for w in wheels], [w.inertia for w in wheels],
        [inf if w.max_torque_n_m is None else U.to_kernel(w.max_torque_n_m, "torque") for w in wheels],
        [inf if w.max_speed_rad_s is None else w.max_speed_rad_s for w in wheels],
        [0.0 if w.friction_coulomb is None else U.to_kernel(w.friction_coulomb, "torque") for w in wheels],
        [0.0 if w.friction_viscous is None else U.to_kernel(w.friction_viscous, "torque_time") for w in wheels],
        [ReactionWheel.FRICTION_WIDTH if w.friction_width is None else w.friction_width for w in wheels]), None)


class PDControl:
    """Quaternion PD feedback: ``tau = -kp sgn(q_e0) Im(q_e) - kd (omega - omega_t)``, each axis
    clipped to ``max_torque`` (``q_e = q_t~ q``; targets and actuators in
    :mod:`orbatt.core.control`).

    Parameters
    ----------
    target : {"orbital", "inertial", "sun", "ground", "nadir"}
        Hold the body axes on the orbital frame O (``q_orbital`` -> identity, or -> ``target_q``
        when given), on the attitude ``target_q`` (inertial, scalar first), point the body
        axis ``target_axis`` at the Sun or at a ground target (both need the orbit's epoch), or
        hold the body axes on the geodetic nadir frame N (``"nadir"``: O with the geocentric
        radial ``o1`` replaced by the WGS84 ellipsoid's normal through the spacecraft, so that
        ``-n1`` points at the point of the ellipsoid below it; ``n3`` along ``n1 x v``, ``n2 =
        n3 x n1`` the velocity's projection; turned by ``target_q`` when given, as O is; needs
        the orbit's epoch: the Earth's rotation, ITRS -> GCRS through ERFA).
    kp : Quantity (N m)
        Torque per unit quaternion error.
    kd : Quantity (N m s)
        Torque per unit rate error (rad/s).
    max_torque : Quantity (N m), optional
        Per-axis saturation of the commanded torque (each body axis; with a full inertia tensor
        the axes of its body frame, not its principal axes: :mod:`orbatt.frame_boundary`; so
        are ``max_dipole`` and ``dump_max_dipole``).
    actuator : {"ideal", "wheels", "magnetorquers"}
        An ideal external torque, the body's reaction wheels (their axes must span three
        dimensions; their limits apply), or magnetorquers: the dipole ``m = (B x tau) / |B|^2``
        (body axes), each axis clipped to ``max_dipole``, so that the external torque ``m x B``
        is the commanded torque's part normal to the field (its part along ``B`` cannot be made:
        an underactuated law); reads the potential's magnetic field along the orbit. With a
        ``period`` the dipole is computed at the ticks and held (``m x B(t)`` follows the
        field). The dipole is the Dataset's ``dipole_control``.
    max_dipole : Quantity (A m^2), optional
        The magnetorquers' per-axis limit (required with ``actuator = "magnetorquers"``).
    target_q : 4 floats, optional
        The target attitude, scalar first: target -> inertial S (``target = "inertial"``,
        required), or target -> orbital O (``target = "orbital"``, optional: a constant offset
        from the orbital frame such as a roll, default identity), or target -> N (``target =
        "nadir"``, the same offset from the geodetic nadir frame).
    target_location : 3 values, optional
        ``target = "ground"``: the point on the rotating Earth to track, geodetic WGS84 latitude,
        longitude (angles; plain numbers are rad) and height (length; plain: m). The law points
        ``target_axis`` along the line of sight and feeds its rate forward (ITRS -> GCRS through
        ERFA, as the environment; needs the orbit's epoch).
    target_axis : 3 floats, optional
        The unit body axis to point at the Sun (``target = "sun"``, required).
    max_rate : Quantity (angular rate), optional
        A rate-limited eigenaxis slew (Wie, Weiss & Arapostathis 1989): the rate the law asks
        for, ``-(kp / kd) e``, is scaled down to ``|omega_c| <= max_rate`` (``max_torque``
        then acts as the acceleration limit); needs ``kd > 0``. Default: none.
    dump_gain : Quantity (1/s), optional
        Momentum management (``actuator = "wheels"``): magnetorquers dump the wheels' momentum
        ``h`` (body axes) with the cross-product law ``m = dump_gain (h x B) / |B|^2``, each
        axis clipped to ``dump_max_dipole``, so that ``m x B = -dump_gain h_perp`` (the part of
        ``h`` normal to the field) while unclipped; the torque ``m x B`` is external and the
        dipole the Dataset's ``dipole_control``. Reads the potential's magnetic field along the
        orbit. With a ``period`` the dipole is computed at the ticks and held (``m x B(t)``
        follows the field). Default: no dumping.
    dump_max_dipole : Quantity (A m^2), optional
        The magnetorquers' per-axis limit (required with ``dump_gain``).
    ki : Quantity (N m / s), optional
        Integral gain: ``- ki s``, ``s`` the integral of the attitude error (conditional
        integration stops an axis while its command is saturated and the error would drive it
        further: anti-windup). Default: 0.
    period : Quantity (time), optional
        The flight software's period: the law is evaluated at the ticks ``t_k = k period`` (time
        since the epoch: the time axis of the run) on the state at ``t_k``, and its command (the
        torque, or the wheels' motor torques) is held until the next tick (zero-order hold).
        Default: a continuous law, evaluated at every instant.
    """

    #: the law's name; its ``[control]`` keys are described once in :data:`orbatt.laws.LAWS`
    law = "pd"

    def __init__(self, target="orbital", *, kp, kd, max_torque=None, actuator="ideal", target_q=None,
                 target_axis=None, max_rate=None, ki=None, period=None, dump_gain=None, dump_max_dipole=None,
                 target_location=None, max_dipole=None):
        if target not in TARGETS:
            raise InputError(f"target: {target!r} is not one of {', '.join(map(repr, TARGETS))}")
        if actuator not in ACTUATORS:
            raise InputError(f"actuator: {actuator!r} is not one of {', '.join(map(repr, ACTUATORS))}")
        self.target, self.actuator = target, actuator
        self.kp = scalar_value(kp, u.N * u.m, "kp", nonnegative=True)
        self.kd = scalar_value(kd, u.N * u.m * u.s, "kd", nonnegative=True)
        self.max_torque = scalar_value(max_torque, u.N * u.m, "max_torque", positive=True, allow_none=True)
        self.period = flight_period(period)
        self.max_rate = scalar_value(max_rate, u.rad / u.s, "max_rate", positive=True, allow_none=True)
        if self.max_rate is not None and not self.kd > 0:
            raise InputError("max_rate: the rate-limited slew needs kd > 0 (the rate loop's gain)")
        self.ki = scalar_value(ki, u.N * u.m / u.s, "ki", nonnegative=True, allow_none=True)
        self.dump_gain, self.dump_max_dipole = _dumping(actuator, dump_gain, dump_max_dipole)
        self.max_dipole = scalar_value(max_dipole, u.A * u.m**2, "max_dipole", positive=True, allow_none=True)
        if actuator == "magnetorquers" and self.max_dipole is None:
            raise InputError("max_dipole: actuator = 'magnetorquers' needs the magnetorquers' per-axis limit, e.g. "
                             "max_dipole = '0.2 A m2'")
        if actuator != "magnetorquers" and self.max_dipole is not None:
            raise InputError(f"max_dipole: only read with actuator = 'magnetorquers' (actuator is {actuator!r}); "
                             "remove it")
        self.target_q = self.target_axis = None
        if target == "inertial" and target_q is None:
            raise InputError("target_q: target = 'inertial' needs the target attitude target_q = [w, x, y, z]")
        if target_q is not None:
            if target in POINTING_TARGETS:
                raise InputError(f"target_q: only for target = 'inertial', 'orbital' or 'nadir' (target is {target!r}; "
                                 "give target_axis)")
            tq = np.asarray(target_q, dtype=np.float64)
            if tq.shape != (4,) or not np.all(np.isfinite(tq)) or abs(np.linalg.norm(tq) - 1) > AXIS_TOLERANCE:
                raise InputError(f"target_q: {target_q!r} is not a unit quaternion [w, x, y, z]")
            self.target_q = tq / np.linalg.norm(tq)
        if target in POINTING_TARGETS:
            if target_axis is None:
                raise InputError(f"target_axis: target = {target!r} needs the body axis to point at it, e.g. [0, 0, 1]")
            self.target_axis = _unit_vector(target_axis, "target_axis")
        elif target_axis is not None:
            raise InputError(f"target_axis: only for target = 'sun' or 'ground' (target is {target!r})")
        self.target_location = None
        if target == "ground":
            self.target_location = _location(target_location)
        elif target_location is not None:
            raise InputError(f"target_location: only for target = 'ground' (target is {target!r})")

    def row(self, wheels, sun_table=None):
        """The :data:`~orbatt.core.model.PD_CONTROL` row for a body with ``wheels`` (internal
        units); ``sun_table``: its target's table along the orbit (the Sun's position for
        ``target = sun``, the ground point's for ``ground``, the geodetic vertical for ``nadir``)."""
        tmax = np.inf if self.max_torque is None else U.to_kernel(self.max_torque, "torque")
        values = (self.target_axis if self.target in POINTING_TARGETS else
                  self.target_q if self.target_q is not None else (1.0, 0.0, 0.0, 0.0))
        self.check_wheels(wheels)
        axes = np.array([w.axis for w in wheels]) if self.actuator == "wheels" else None
        params = kc.pd_params(TARGETS[self.target], U.to_kernel(self.kp, "torque"),
                              U.to_kernel(self.kd, "torque_time"), tmax, values, axes,
                              max_rate=np.inf if self.max_rate is None else self.max_rate,
                              ki=0.0 if self.ki is None else U.to_kernel(self.ki, "torque"),
                              magnetorquers=self.actuator == "magnetorquers",
                              axes=limit_axes(self) if tmax < np.inf or self.actuator == "magnetorquers" else None,
                              **command_slots(self.period, wheels))
        return (km.PD_CONTROL, params, sun_table)

    def check_wheels(self, wheels):
        """Refuse ``wheels`` (a list of :class:`ReactionWheel`) as the actuator of a law with
        ``actuator = "wheels"``: none, or axes that do not span three dimensions."""
        if self.actuator != "wheels":
            return
        if not wheels:
            raise InputError("actuator: 'wheels' needs the body's reaction wheels ([[body.wheels]])")
        if not wheel_axes_span(wheels):
            axes = np.array([w.axis for w in wheels])
            raise InputError(f"[[body.wheels]] axis: the {len(wheels)} wheel axes {axes.tolist()} do not span "
                             "three dimensions, which leaves an axis uncontrollable; add or tilt a wheel")

    def settings(self):
        """The plain settings (``law`` and its keys, SI floats) that
        :func:`orbatt.laws.control_law` makes this law of again."""
        return {"law": self.law, "target": self.target, "kp": self.kp, "kd": self.kd, "max_torque": self.max_torque,
                "actuator": self.actuator, "target_q": None if self.target_q is None else self.target_q.tolist(),
                "target_axis": None if self.target_axis is None else self.target_axis.tolist(),
                "target_location": None if self.target_location is None else list(self.target_location),
                "max_rate": self.max_rate, "ki": self.ki, "period": self.period, "dump_gain": self.dump_gain,
                "dump_max_dipole": self.dump_max_dipole, "max_dipole": self.max_dipole}

    @property
    def reads_orbit(self):
        """Whether the law reads the orbit: the orbital frame or the Sun as its target, or the
        magnetic field along it (momentum dumping, magnetorquers)."""
        return self.target != "inertial" or self.dump_gain is not None or self.actuator == "magnetorquers"

    def model_row(self, wheels, tables):
        """The law's model row (:meth:`row`) for a body with ``wheels``; ``tables(name)``
        gives the fields along the orbit (:meth:`orbatt.EnvironmentTorques.field_table`): the
        Sun's position (``"sun"``) for ``target = "sun"``, a ground point's (``("ground", lat,
        lon, h)``), the geodetic vertical (``"nadir"``)."""
        sun = (tables("sun") if self.target == "sun" else
               tables(("ground", *self.target_location)) if self.target == "ground" else
               tables("nadir") if self.target == "nadir" else None)
        # made once per set of wheels, settings and Sun table (~60 us): the settings are in the
        # key, so that a law changed after a run (law.kp = ...) is not run with its old row
        key = (tuple(wheels), repr(sorted(self.settings().items())), _axes_key(self))
        rows = self.__dict__.setdefault("_rows", {})
        hit = rows.get(key)
        if hit is None or hit[0] is not sun:
            hit = rows[key] = (sun, self.row(wheels, sun))
        return hit[1]

    def model_rows(self, wheels, tables):
        """The law's model rows: its :meth:`model_row`, then with ``dump_gain`` the
        :data:`~orbatt.core.model.MOMENTUM_DUMP` row of its magnetorquers, which reads the
        magnetic field along the orbit (``tables("field")``) and holds its dipole (with a
        ``period``) after the PD law's state; with ``actuator = "magnetorquers"`` the
        :data:`~orbatt.core.model.MAGNETORQUERS` row right after the PD row, which holds the
        field along the orbit (the PD row's own table slot is its target's) and the dipole limit
        (the PD row holds the dipole with a ``period``)."""
        rows = [self.model_row(wheels, tables)]
        if self.actuator == "magnetorquers":
            rows.append((km.MAGNETORQUERS, kc.magnetorquer_params(U.to_kernel(self.max_dipole, "dipole")),
                         tables("field")))
        if self.dump_gain is not None:
            pd = rows[0][1]
            slots = dict(command_slots(self.period, wheels), z0=pd[kc.CTL_Z0] + pd[kc.CTL_NZ])
            rows.append((km.MOMENTUM_DUMP, kc.dump_params(self.dump_gain, U.to_kernel(self.dump_max_dipole, "dipole"),
                                                          axes=limit_axes(self), **slots), tables("field")))
        return rows

    def describe(self):
        d = {"law": "pd", "target": self.target, "kp_N_m": self.kp, "kd_N_m_s": self.kd,
             "max_torque_N_m": self.max_torque, "actuator": self.actuator}
        if self.period is not None:
            d["period_s"] = self.period
        if self.max_rate is not None:
            d["max_rate_rad_s"] = self.max_rate
        if self.ki is not None:
            d["ki_N_m_per_s"] = self.ki
        if self.dump_gain is not None:
            d["dump_gain_per_s"] = self.dump_gain
            d["dump_max_dipole_A_m2"] = self.dump_max_dipole
        if self.max_dipole is not None:
            d["max_dipole_A_m2"] = self.max_dipole
        if self.target_q is not None:
            d["target_q"] = self.target_q.tolist()
        if self.target_axis is not None:
            d["target_axis"] = self.target_axis.tolist()
        if self.target_location is not None:
            d["target_location_rad_rad_m"] = list(self.target_location)
        return d

    def __repr__(self):
        return (f"PDControl(target={self.target!r}, kp={self.kp:.4g} N m, kd={self.kd:.4g} N m s, "
                f"actuator={self.actuator!r})")


def _dumping(actuator, gain, max_dipole):
    """``(dump_gain 1/s, dump_max_dipole A m^2)`` of a PD law (None, None: no dumping), checked:
    both or neither, on wheels."""
    k = scalar_value(gain, 1 / u.s, "dump_gain", positive=True, allow_none=True)
    mmax = scalar_value(max_dipole, u.A * u.m**2, "dump_max_dipole", positive=True, allow_none=True)
    if k is None and mmax is None:
        return None, None
    if k is None:
        raise InputError("dump_max_dipole: only read with dump_gain (momentum dumping); give both or neither")
    if mmax is None:
        raise InputError("dump_max_dipole: momentum dumping (dump_gain) needs the magnetorquers' per-axis limit, "
                         "e.g. dump_max_dipole = '0.2 A m2'")
    if actuator != "wheels":
        raise InputError(f"dump_gain: momentum dumping unloads reaction wheels; it needs actuator = 'wheels' "
                         f"(actuator is {actuator!r})")
    return k, mmax


class BDotControl:
    """B-dot detumbling: ``m = -gain dB_B/dt`` (body axes, each axis clipped to
    ``max_dipole``), ``tau = m x B``.

    Parameters
    ----------
    gain : Quantity (A m^2 s / T)
    max_dipole : Quantity (A m^2)
        The magnetorquers' limit per body axis (with a full inertia tensor: its body frame's).
    period : Quantity (time), optional
        The flight software's period: the dipole is computed at the ticks ``k period`` and held
        until the next (zero-order hold; the torque ``m x B(t)`` follows the field). Default:
        continuous.
    """

    #: the law's name; its ``[control]`` keys are described once in :data:`orbatt.laws.LAWS`
    law = "bdot"

    def __init__(self, gain, max_dipole, *, period=None):
        self.gain = scalar_value(gain, u.A * u.m**2 * u.s / u.T, "gain", nonnegative=True)
        self.max_dipole = scalar_value(max_dipole, u.A * u.m**2, "max_dipole", positive=True)
        self.period = flight_period(period)

    def row(self, field_table, wheels=()):
        """The :data:`~orbatt.core.model.BDOT_CONTROL` row with the field along the orbit
        (T, inertial; a piece table of :mod:`orbatt.core.environment`) for a body with
        ``wheels`` (its held dipole follows their momenta in the state)."""
        return (km.BDOT_CONTROL, kc.bdot_params(U.to_kernel(self.gain, "dipole_gain"),
                                                U.to_kernel(self.max_dipole, "dipole"),
                                                **command_slots(self.period, wheels), axes=limit_axes(self)), field_table)

    def check_wheels(self, wheels):
        """Nothing to refuse: the magnetorquers act whatever the wheels."""

    def settings(self):
        """The plain settings that :func:`orbatt.laws.control_law` makes this law of again."""
        return {"law": self.law, "gain": self.gain, "max_dipole": self.max_dipole, "period": self.period}

    #: B-dot reads the magnetic field along the orbit
    reads_orbit = True

    def model_row(self, wheels, tables):
        """The law's model row (:meth:`row`; ``wheels``: where its held command lies in the
        state); ``tables(name)`` gives the
        magnetic field along the orbit (``"field"``, :meth:`orbatt.EnvironmentTorques.field_table`)."""
        return self.row(tables("field"), wheels)

    def describe(self):
        d = {"law": "bdot", "gain_A_m2_s_per_T": self.gain, "max_dipole_A_m2": self.max_dipole}
        if self.period is not None:
            d["period_s"] = self.period
        return d

    def __repr__(self):
        return f"BDotControl(gain={self.gain:.4g} A m^2 s/T, max_dipole={self.max_dipole:.4g} A m^2)"


def _arguments(units, settings):
    """Keyword arguments of plain ``settings``: each value with a unit in ``units`` as a
    Quantity (None stays None)."""
    return {k: v if units[k] is None or v is None else v * u.Unit(units[k]) for k, v in settings.items()}


def reaction_wheel(settings, name=None):
    """The :class:`ReactionWheel` of plain ``settings`` (SI floats in
    :data:`ReactionWheel.UNITS`; :meth:`ReactionWheel.settings`)."""
    kw = _arguments(ReactionWheel.UNITS, settings)
    axis, inertia = kw.pop("axis"), kw.pop("inertia")
    return ReactionWheel(axis, inertia, kw.pop("speed", 0.0 * u.rad / u.s), name=name, **kw)

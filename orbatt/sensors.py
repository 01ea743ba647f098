"""Attitude sensors with noise and the attitude filter of the flight software (issue 33,
``docs/design.md`` §14): the public objects, with units at the boundary.

A :class:`Navigation` holds a :class:`Gyro`, a :class:`StarTracker` and an :class:`MEKF`, the
noise ``seed`` and the ``case`` (the key of every random number: :mod:`orbatt.core.noise`),
and whether the control law acts on the estimate (``feedback``). Attach it to a control law
with :func:`with_navigation`; :func:`orbatt.propagate` then runs the sensors and the filter at
their ticks, before the law (:func:`orbatt.core.gyrostat.tick`), and the Dataset gets the
estimate and its errors (:func:`navigation_variables`).

Frames and units: the body frame B of the attitude ``q`` (body -> inertial S); rates in rad/s
in body axes; angles in rad. The filter's error convention is ``q = q_hat (x) dq(dtheta)``:
``dtheta`` (body axes) turns the estimated body axes onto the true ones, and the Dataset's
``knowledge_error`` is that rotation vector.
"""
from __future__ import annotations

import math

import numpy as np
from astropy import units as u

from .control import scalar_value
from .core import estimator as ke
from .core import model as km
from .errors import InputError

__all__ = ["Gyro", "StarTracker", "Magnetometer", "SunSensor", "MEKF", "Navigation", "with_navigation", "FEEDBACKS",
           "PERIOD_TOLERANCE"]

#: the laws' inputs: the filter's estimate or the true state
FEEDBACKS = ("estimate", "truth")
#: how far a rate may be from an integer multiple of the base tick (relative)
PERIOD_TOLERANCE = 1e-9
#: the Earth's equatorial radius (km; WGS84), the star tracker's Earth exclusion
EARTH_RADIUS_KM = 6378.137


def _rate_period(rate, name):
    """The sample period (s) of a sampling ``rate`` (frequency, or a period as a time)."""
    if not isinstance(rate, u.Quantity):
        raise InputError(f"{name}: {rate!r} needs a unit, e.g. '10 Hz' (a sampling rate) or '0.1 s' (its period)")
    if rate.unit.physical_type == "time":
        p = rate.to_value(u.s)
    else:
        try:
            f = rate.to_value(u.Hz)
        except u.UnitConversionError:
            raise InputError(f"{name}: {rate!r} is not a frequency (Hz) or a period (s)") from None
        p = 1.0 / f if f > 0 else math.inf
    if not (p > 0.0 and math.isfinite(p)):
        raise InputError(f"{name}: {rate!r} must be a positive finite rate")
    return float(p)


def _vector(x, unit, name, n=3):
    q = u.Quantity(x)
    try:
        v = np.asarray(q.to_value(unit), dtype=np.float64).ravel()
    except u.UnitConversionError:
        raise InputError(f"{name}: {x!r} is not in {unit}") from None
    if v.size == 1:
        v = np.full(n, float(v[0]))
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise InputError(f"{name}: {x!r} must be {n} finite values in {unit}")
    return v


class Gyro:
    """A rate-integrating gyro (Farrenkopf's model): ``w_meas = omega + beta + eta_v``,
    ``d beta / dt = eta_u``, sampled at ``rate`` (Crassidis & Junkins 2012, §7.2).

    Parameters
    ----------
    rate : Quantity (frequency, or time: the period)
        The sampling rate; the base tick of the sensors and the filter.
    arw : Quantity (angle / time^(1/2)), e.g. ``0.15 deg / h**0.5``
        Angle random walk ``sigma_v`` (the rate noise over a sample is ``sigma_v / sqrt(dt)``).
    rrw : Quantity (angle / time^(3/2)), optional
        Rate random walk ``sigma_u`` of the bias. Default 0.
    bias : Quantity (angular rate), 3 values or one, optional
        The true bias at the start (body axes). Default 0.
    """

    def __init__(self, rate, arw, rrw=None, bias=None):
        self.period = _rate_period(rate, "gyro rate")
        self.arw = scalar_value(arw, u.rad / u.s ** 0.5, "gyro arw", nonnegative=True)
        self.rrw = 0.0 if rrw is None else scalar_value(rrw, u.rad / u.s ** 1.5, "gyro rrw", nonnegative=True)
        self.bias = np.zeros(3) if bias is None else _vector(bias, u.rad / u.s, "gyro bias")

    def __repr__(self):
        return (f"Gyro(period={self.period:g} s, arw={self.arw:.3g} rad/s^0.5, rrw={self.rrw:.3g} rad/s^1.5, "
                f"bias={self.bias.tolist()} rad/s)")


class StarTracker:
    """A star tracker: ``q_meas = q (x) [1, eta / 2]`` normalized, ``eta ~ N(0, diag(noise^2,
    noise^2, noise_roll^2))`` in body axes, sampled at ``rate``; no measurement while the Sun
    or the Earth's limb is within its exclusion angle of the boresight.

    Parameters
    ----------
    rate : Quantity (frequency, or time: the period)
        The sampling rate; an integer divisor of the gyro's rate when there is a gyro.
    noise : Quantity (angle)
        1-sigma noise about each cross-boresight axis (and about the boresight unless
        ``noise_roll``).
    noise_roll : Quantity (angle), optional
        1-sigma noise about the boresight.
    boresight : 3 floats, optional
        The unit boresight in body axes; default ``[0, 0, 1]``. The noise's axes are the body
        axes; ``noise_roll`` is about the body axis nearest the boresight. A body given by a full
        inertia tensor runs the sensors in its principal axes, where the noise is drawn per axis:
        a ``noise_roll`` other than ``noise`` needs that body axis to be a principal axis
        (:func:`orbatt.frame_boundary.principal_navigation`).
    sun_exclusion, earth_exclusion : Quantity (angle), optional
        Exclusion half-angles from the boresight to the Sun (needs the orbit's epoch) and to
        the Earth's limb. Default: none.
    misalignment : Quantity (angle), 3 values, optional
        The mounting error the flight software does not know: the rotation vector (body axes)
        of ``m`` in ``q_meas = q (x) m (x) [1, eta / 2]``, a bias of the knowledge error.
        Default: none.
    """

    def __init__(self, rate, noise, *, noise_roll=None, boresight=(0.0, 0.0, 1.0), sun_exclusion=None,
                 earth_exclusion=None, misalignment=None):
        self.period = _rate_period(rate, "star_tracker rate")
        self.noise = scalar_value(noise, u.rad, "star_tracker noise", nonnegative=True)
        self.noise_roll = (self.noise if noise_roll is None else
                           scalar_value(noise_roll, u.rad, "star_tracker noise_roll", nonnegative=True))
        b = np.asarray(boresight, dtype=np.float64).ravel()
        if b.shape != (3,) or not np.all(np.isfinite(b)) or not np.linalg.norm(b) > 0:
            raise InputError(f"star_tracker boresight: {boresight!r} must be a nonzero 3-vector (body axes)")
        self.boresight = b / np.linalg.norm(b)
        self.sun_exclusion = scalar_value(sun_exclusion, u.rad, "star_tracker sun_exclusion", nonnegative=True,
                                          allow_none=True)
        self.earth_exclusion = scalar_value(earth_exclusion, u.rad, "star_tracker earth_exclusion",
                                            nonnegative=True, allow_none=True)
        self.per_axis = None
        self.misalignment = np.zeros(3) if misalignment is None else _vector(misalignment, u.rad,
                                                                              "star_tracker misalignment")
        if np.linalg.norm(self.misalignment) > math.pi:
            raise InputError(f"star_tracker misalignment: {misalignment!r} is a rotation of more than 180 deg; give "
                             "the small rotation vector of the mounting error")

    def misalignment_quaternion(self):
        """``m = exp(misalignment / 2)``: the mounting error in ``q_meas = q (x) m (x) [1, eta / 2]``."""
        v = self.misalignment
        a = float(np.linalg.norm(v))
        if a == 0.0:
            return np.array([1.0, 0.0, 0.0, 0.0])
        return np.concatenate([[math.cos(0.5 * a)], math.sin(0.5 * a) * v / a])

    def sigma(self):
        """The 1-sigma noise per body axis (rad): ``noise`` across the boresight, ``noise_roll``
        about the body axis nearest it; per principal axis for the copy in the principal frame
        of a full inertia tensor (its ``per_axis``, :func:`orbatt.frame_boundary.principal_navigation`)."""
        if self.per_axis is not None:
            return np.array(self.per_axis, dtype=np.float64)
        s = np.full(3, self.noise)
        s[int(np.argmax(np.abs(self.boresight)))] = self.noise_roll
        return s

    def __repr__(self):
        return f"StarTracker(period={self.period:g} s, noise={self.noise:.3g} rad, boresight={self.boresight.tolist()})"


class Magnetometer:
    """A three-axis magnetometer for the filter's vector updates: ``B_meas = B_body + bias +
    eta``, ``eta ~ N(0, noise^2)`` per body axis; the filter predicts ``B`` from the run's field
    model (IGRF or the dipole) and does not estimate the bias.

    Parameters
    ----------
    rate : Quantity (frequency, or time: the period)
        An integer divisor of the gyro's rate.
    noise : Quantity (magnetic flux density)
        1-sigma noise per axis.
    bias : Quantity (magnetic flux density), 3 values or one, optional
        A constant bias (body axes), unknown to the filter. Default 0.
    """

    def __init__(self, rate, noise, bias=None):
        self.period = _rate_period(rate, "magnetometer rate")
        self.noise = scalar_value(noise, u.T, "magnetometer noise", positive=True)
        self.bias = np.zeros(3) if bias is None else _vector(bias, u.T, "magnetometer bias")

    def __repr__(self):
        return f"Magnetometer(period={self.period:g} s, noise={self.noise:.3g} T)"


class SunSensor:
    """A Sun sensor for the filter's vector updates: the unit vector to the Sun in body axes
    with ``noise`` per axis (then normalized); no measurement in the Earth's (cylindrical)
    shadow. Needs the orbit's epoch.

    Parameters
    ----------
    rate : Quantity (frequency, or time: the period)
        An integer divisor of the gyro's rate.
    noise : Quantity (angle)
        1-sigma noise per axis.
    """

    def __init__(self, rate, noise):
        self.period = _rate_period(rate, "sun_sensor rate")
        self.noise = scalar_value(noise, u.rad, "sun_sensor noise", positive=True)
        self.bias = np.zeros(3)

    def __repr__(self):
        return f"SunSensor(period={self.period:g} s, noise={self.noise:.3g} rad)"


class MEKF:
    """The multiplicative extended Kalman filter of the attitude and the gyro bias (Lefferts,
    Markley & Shuster 1982; :mod:`orbatt.core.estimator`).

    Parameters
    ----------
    attitude_sigma : Quantity (angle)
        The initial 1-sigma attitude error per axis; the initial estimate's error is drawn from
        it (the noise key's initial-estimate stream).
    bias_sigma : Quantity (angular rate)
        The initial 1-sigma bias error per axis (the bias estimate starts at 0).
    """

    kind = "mekf"

    def __init__(self, attitude_sigma, bias_sigma):
        self.attitude_sigma = scalar_value(attitude_sigma, u.rad, "estimator attitude_sigma", nonnegative=True)
        self.bias_sigma = scalar_value(bias_sigma, u.rad / u.s, "estimator bias_sigma", nonnegative=True)

    def __repr__(self):
        return f"MEKF(attitude_sigma={self.attitude_sigma:.3g} rad, bias_sigma={self.bias_sigma:.3g} rad/s)"


class Navigation:
    """The flight software's sensors and filter (module docstring).

    Parameters
    ----------
    seed : int
        The noise seed (recorded in the Dataset).
    case : int, optional
        The case's word of the noise key (a sweep gives each case its own). Default 0.
    gyro : Gyro, optional
    star_tracker : StarTracker, optional
    estimator : MEKF, optional
        Needs a gyro (its propagation) and a sensor to update with: the star tracker, and the
        vector sensors when the star tracker's last sample failed (or there is none).
    magnetometer : Magnetometer, optional
    sun_sensor : SunSensor, optional
    feedback : {"estimate", "truth"}, optional
        What the control law acts on; default the estimate with an estimator, else the truth.
    """

    def __init__(self, seed, *, case=0, gyro=None, star_tracker=None, estimator=None, feedback=None,
                 magnetometer=None, sun_sensor=None):
        for name, v in (("seed", seed), ("case", case)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 0 <= int(v) < 2 ** 53:
                raise InputError(f"sensors {name}: {v!r} must be an integer in [0, 2^53)")
        if gyro is None and star_tracker is None:
            raise InputError("sensors: no gyro and no star tracker; give [sensors.gyro] and/or [sensors.star_tracker] "
                             "(the magnetometer and the Sun sensor update the filter between them)")
        if magnetometer is not None and not isinstance(magnetometer, Magnetometer):
            raise InputError(f"magnetometer: expected orbatt.Magnetometer, got {type(magnetometer).__name__}")
        if sun_sensor is not None and not isinstance(sun_sensor, SunSensor):
            raise InputError(f"sun_sensor: expected orbatt.SunSensor, got {type(sun_sensor).__name__}")
        if (magnetometer is not None or sun_sensor is not None) and estimator is None:
            raise InputError("magnetometer / sun_sensor: they update the attitude filter; add [estimator] kind = 'mekf'")
        if gyro is not None and not isinstance(gyro, Gyro):
            raise InputError(f"gyro: expected orbatt.Gyro, got {type(gyro).__name__}")
        if star_tracker is not None and not isinstance(star_tracker, StarTracker):
            raise InputError(f"star_tracker: expected orbatt.StarTracker, got {type(star_tracker).__name__}")
        if estimator is not None:
            if not isinstance(estimator, MEKF):
                raise InputError(f"estimator: expected orbatt.MEKF, got {type(estimator).__name__}")
            if gyro is None:
                raise InputError("estimator: the MEKF propagates with a gyro; add [sensors.gyro]")
            if star_tracker is not None and not min(star_tracker.noise, star_tracker.noise_roll) > 0.0:
                raise InputError("star_tracker noise: the filter's update needs a positive measurement noise (a perfect "
                                 "attitude measurement leaves its covariance singular); give the tracker's 1-sigma "
                                 "noise, e.g. '10 arcsec'")
            if star_tracker is None and magnetometer is None and sun_sensor is None:
                raise InputError("estimator: the MEKF needs a sensor to update with; add [sensors.star_tracker], "
                                 "[sensors.magnetometer] or [sensors.sun_sensor]")
        if feedback is None:
            feedback = "estimate" if estimator is not None else "truth"
        if feedback not in FEEDBACKS:
            raise InputError(f"feedback: {feedback!r} is not one of 'estimate', 'truth'")
        if feedback == "estimate" and estimator is None:
            raise InputError("feedback: 'estimate' needs an estimator ([estimator] kind = 'mekf'); or use 'truth'")
        self.seed, self.case = int(seed), int(case)
        self.gyro, self.star_tracker, self.estimator, self.feedback = gyro, star_tracker, estimator, feedback
        self.magnetometer, self.sun_sensor = magnetometer, sun_sensor
        self.period = gyro.period if gyro is not None else star_tracker.period
        self.every = 0 if star_tracker is None else self._every(star_tracker, "star_tracker")

    def _ticks(self, period):
        """``period`` (s) in base ticks: a positive integer, or None when it is not one."""
        n = period / self.period
        return int(round(n)) if abs(n - round(n)) <= PERIOD_TOLERANCE * n and round(n) >= 1 else None

    def _every(self, sensor, name):
        """How many base ticks between ``sensor``'s samples (an integer, refused otherwise)."""
        n = self._ticks(sensor.period)
        if n is None:
            raise InputError(f"{name} rate: its period {sensor.period:g} s is not an integer multiple of the gyro's "
                             f"{self.period:g} s (the sensors share one base tick); choose rates such as 10 Hz and "
                             "1 Hz")
        return n

    def check_period(self, period):
        """Refuse a control law's ``period`` (s, None: a continuous law) whose ticks are not ticks
        of the sensors: a law on the estimate needs a period, an integer multiple of the base
        tick."""
        if period is None:
            if self.feedback == "estimate":
                raise InputError("[control] period: a law acting on the estimate runs at the flight software's rate; "
                                 f"give period (a multiple of the gyro's {self.period:g} s), or feedback = 'truth'")
            return
        if self._ticks(period) is None:
            raise InputError(f"[control] period: {period:g} s is not an integer multiple of the sensors' base tick "
                             f"{self.period:g} s (the gyro's period); the law reads the estimate at its ticks")

    def check_law(self, law):
        """:meth:`check_period` of ``law``'s period."""
        self.check_period(getattr(law, "period", None))

    @property
    def reads_sun(self):
        """Whether the star tracker's Sun exclusion reads the Sun's position."""
        return self.star_tracker is not None and self.star_tracker.sun_exclusion is not None

    @property
    def reads_field(self):
        """Whether a magnetometer reads the run's magnetic field model."""
        return self.magnetometer is not None

    def model_rows(self, z0, tables):
        """The kernel rows: :meth:`model_row`, then a :data:`~orbatt.core.model.VECTOR_SENSOR`
        row per vector sensor (its table: ``tables("field")`` or ``tables("sun")``)."""
        rows = [self.model_row(z0, tables)]
        if self.magnetometer is not None:
            m = self.magnetometer
            rows.append((km.VECTOR_SENSOR, ke.vector_params(ke.MAGNETOMETER, self._every(m, "magnetometer"), m.noise,
                                                            m.bias), tables("field")))
        if self.sun_sensor is not None:
            ss = self.sun_sensor
            rows.append((km.VECTOR_SENSOR, ke.vector_params(ke.SUN_SENSOR, self._every(ss, "sun_sensor"), ss.noise),
                         tables("sun")))
        return rows

    def model_row(self, z0, tables):
        """The :data:`~orbatt.core.model.NAVIGATION` row ``(kind, params, table)``: its state at
        ``y[z0:]``; ``tables("sun")`` the Sun's position along the orbit (Sun exclusion)."""
        g, st, f = self.gyro, self.star_tracker, self.estimator
        params = ke.nav_params(
            self.period, z0, seed=self.seed, case=self.case,
            gyro=None if g is None else (g.arw, g.rrw, g.bias),
            star_tracker=None if st is None else (
                self.every, st.sigma(), st.boresight,
                -1.0 if st.sun_exclusion is None else st.sun_exclusion,
                -1.0 if st.earth_exclusion is None else st.earth_exclusion, st.misalignment_quaternion()),
            filter=None if f is None else (f.attitude_sigma, f.bias_sigma),
            feedback=self.feedback == "estimate", earth_radius=EARTH_RADIUS_KM)
        return (km.NAVIGATION, params, tables("sun") if self.reads_sun else None)

    def describe(self):
        """Plain settings for the Dataset's attributes."""
        d = {"seed": self.seed, "case": self.case, "feedback": self.feedback, "base_period_s": self.period}
        if self.gyro is not None:
            d.update(gyro_period_s=self.gyro.period, gyro_arw_rad_per_sqrt_s=self.gyro.arw,
                     gyro_rrw_rad_per_s1_5=self.gyro.rrw, gyro_bias_rad_s=self.gyro.bias.tolist())
        if self.star_tracker is not None:
            st = self.star_tracker
            d.update(star_tracker_period_s=st.period, star_tracker_noise_rad=st.sigma().tolist(),
                     star_tracker_boresight=st.boresight.tolist())
        if self.estimator is not None:
            d.update(estimator="mekf", attitude_sigma_rad=self.estimator.attitude_sigma,
                     bias_sigma_rad_s=self.estimator.bias_sigma)
        return d

    def __repr__(self):
        parts = [f"seed={self.seed}", f"case={self.case}"]
        parts += [repr(x) for x in (self.gyro, self.star_tracker, self.magnetometer, self.sun_sensor, self.estimator)
                  if x is not None]
        return f"Navigation({', '.join(parts)}, feedback={self.feedback!r})"


def with_navigation(law, navigation):
    """``law`` (a control law of :mod:`orbatt.control` or :class:`orbatt.ModeSequence`) with its
    flight software's sensors and filter ``navigation`` (a :class:`Navigation`, or None to
    remove them); returns ``law``. Refuses a law whose ticks are not the sensors'."""
    if navigation is not None:
        if not isinstance(navigation, Navigation):
            raise InputError(f"navigation: expected orbatt.Navigation, got {type(navigation).__name__}")
        navigation.check_law(law)
    law.navigation = navigation
    return law

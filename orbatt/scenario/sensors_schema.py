"""The ``[sensors]`` and ``[estimator]`` tables of a scenario and ``[control] feedback``
(issue 33): the flight software's noisy sensors and attitude filter (:mod:`orbatt.sensors`),
parsed into plain settings that :func:`navigation_of` makes a :class:`~orbatt.sensors.Navigation`
of; every rule is the objects' own (a rejected value names its key).
"""
from __future__ import annotations

import numpy as np
from astropy import units as u

from ..errors import InputError
from ..sensors import FEEDBACKS, MEKF, Gyro, Magnetometer, Navigation, StarTracker, SunSensor, with_navigation
from .fields import parse_choice, parse_int, parse_plain_vector, parse_quantity, parse_vector
from .key_docs import parse_key_docs
from .torques_schema import check_field_epoch

__all__ = ["SENSOR_TABLES", "SENSOR_KEY_DOCS", "parse_navigation", "navigation_of", "attach_navigation",
           "ESTIMATOR_KINDS", "reads_magnetic_field"]

#: the keys of each table
SENSOR_TABLES = {
    "sensors": {"seed", "case", "gyro", "star_tracker", "magnetometer", "sun_sensor"},
    "sensors.magnetometer": {"rate", "noise", "bias"},
    "sensors.sun_sensor": {"rate", "noise"},
    "sensors.gyro": {"rate", "arw", "rrw", "bias"},
    "sensors.star_tracker": {"rate", "noise", "noise_roll", "boresight", "sun_exclusion", "earth_exclusion",
                             "misalignment"},
    "estimator": {"kind", "attitude_sigma", "bias_sigma"},
}
ESTIMATOR_KINDS = ("mekf",)
#: ``{table: {key: (dimension, default, meaning)}}`` (``docs/scenarios.md``)
SENSOR_KEY_DOCS = parse_key_docs("""
[sensors]
seed          integer in [0, 2^53)  required  the noise seed: every random number is a function of (seed, case,
                                              sensor, tick, axis) (a counter-based generator), so a case is bitwise
                                              the same alone, in any chunk, after a resume
case          integer in [0, 2^53)  0         the case's word of the noise key (a sweep gives case k the value k)
gyro          table                 none      [sensors.gyro]
star_tracker  table                 none      [sensors.star_tracker]
magnetometer  table                 none      [sensors.magnetometer]: updates the filter while the star tracker is
                                              out (or without one)
sun_sensor    table                 none      [sensors.sun_sensor]: updates the filter while the star tracker is out
                                              (or without one)

[sensors.gyro]
rate  frequency                   required  sampling rate: the base tick of the sensors and the filter
arw   noise density, angle / time^(1/2)  required  angle random walk sigma_v (e.g. '0.15 deg/sqrt(h)'): rate noise
                                            sigma_v / sqrt(dt) per sample
rrw   noise density, angle / time^(3/2)  0         rate random walk sigma_u of the bias (e.g. '0.3 deg / h(3/2)')
bias  angular rate, 3 values      zero      the true bias at the start (body axes)

[sensors.star_tracker]
rate             frequency        required  sampling rate: the gyro's rate divided by an integer
noise            angle            required  1-sigma noise about each cross-boresight body axis
noise_roll       angle            noise     1-sigma noise about the body axis nearest the boresight
boresight        3 plain values   [0, 0, 1]  the boresight, body axes
sun_exclusion    angle            none      no measurement while the Sun is within this angle of the boresight
                                            (needs [orbit] epoch)
earth_exclusion  angle            none      no measurement while the Earth's limb is within this angle of the
                                            boresight
misalignment     angle, 3 values  none      the mounting error unknown to the filter: the rotation vector m (body
                                            axes) of q_meas = q m [1, eta/2]; a bias of the knowledge error

[sensors.magnetometer]
rate   frequency                          required  sampling rate: the gyro's rate divided by an integer
noise  magnetic flux density              required  1-sigma noise per body axis (e.g. '100 nT'); reads [environment]
                                                    magnetic_field (the filter predicts B from the same model)
bias   magnetic flux density, 3 values    zero      a constant bias (body axes) the filter does not know

[sensors.sun_sensor]
rate   frequency  required  sampling rate: the gyro's rate divided by an integer
noise  angle      required  1-sigma noise per body axis of the unit vector to the Sun; no measurement in the Earth's
                            shadow (cylindrical); needs [orbit] epoch

[estimator]
kind            'mekf'        required  the multiplicative extended Kalman filter of the attitude and the gyro
                                        bias (needs [sensors.gyro] and [sensors.star_tracker]; the laws act on its
                                        estimate, see [control] feedback)
attitude_sigma  angle         required  initial 1-sigma attitude error per axis; the initial estimate's error is
                                        drawn from it
bias_sigma      angular rate  required  initial 1-sigma bias error per axis (the bias estimate starts at 0)
""")
#: ``[control] feedback``, described beside the laws' keys
FEEDBACK_DOC = ("'estimate' | 'truth'", "'estimate' with an [estimator], else 'truth'",
                "what the law acts on: the filter's estimate (q_hat, w_meas - b_hat) or the true state; with the "
                "estimate the law needs a period, an integer multiple of the gyro's")

_RATE = u.rad / u.s


def _table(ctx, data, name):
    t = data
    for part in name.split("."):
        t = t.get(part) if isinstance(t, dict) else None
    if t is None:
        return None
    if not isinstance(t, dict):
        raise ctx.error(f"[{name}]", f"must be a table, got {t!r}")
    for k in t:
        if k not in SENSOR_TABLES[name]:
            raise ctx.error(f"[{name}] {k}", f"unknown key; allowed: {', '.join(sorted(SENSOR_TABLES[name]))}")
    return t


def _required(ctx, t, name, key):
    if key not in t:
        raise ctx.error(f"[{name}] {key}", "missing; see docs/scenarios.md")
    return t[key]


def _q(ctx, t, name, key, unit, default=None):
    if key not in t:
        return default
    return parse_quantity(ctx, f"[{name}] {key}", t[key], unit, dimensionless=False)


def parse_navigation(ctx, data, control, orbit):
    """The plain settings of ``[sensors]``, ``[estimator]`` and ``[control] feedback``, or None
    without ``[sensors]``; checked by building the objects (:func:`navigation_of`) against the
    law's settings ``control`` (:meth:`~orbatt.PDControl.settings`)."""
    s = _table(ctx, data, "sensors")
    est = data.get("estimator")
    feedback = data.get("control", {}).get("feedback") if isinstance(data.get("control"), dict) else None
    if s is None:
        if est is not None:
            raise ctx.error("[estimator]", "needs [sensors] (a gyro and a star tracker) to estimate from")
        if feedback is not None:
            raise ctx.error("[control] feedback", "needs [sensors] and an [estimator]; remove it")
        return None
    if control is None:
        raise ctx.error("[sensors]", "the sensors feed the flight software: give a [control] law with a period")
    out = {"seed": parse_int(ctx, "[sensors] seed", _required(ctx, s, "sensors", "seed"), 0, 2 ** 53),
           "magnetometer": None, "sun_sensor": None, "magnetic_field": None,
           "case": parse_int(ctx, "[sensors] case", s.get("case", 0), 0, 2 ** 53),
           "gyro": None, "star_tracker": None, "estimator": None,
           "feedback": None if feedback is None else parse_choice(ctx, "[control] feedback", feedback, FEEDBACKS)}
    g = _table(ctx, data, "sensors.gyro")
    if g is not None:
        out["gyro"] = {"rate": parse_quantity(ctx, "[sensors.gyro] rate", _required(ctx, g, "sensors.gyro", "rate"),
                                              u.Hz, dimensionless=False),
                       "arw": parse_quantity(ctx, "[sensors.gyro] arw", _required(ctx, g, "sensors.gyro", "arw"),
                                             u.rad / u.s ** 0.5, dimensionless=False),
                       "rrw": _q(ctx, g, "sensors.gyro", "rrw", u.rad / u.s ** 1.5, 0.0),
                       "bias": (parse_vector(ctx, "[sensors.gyro] bias", g["bias"], 3, _RATE, dimensionless=False).tolist()
                                if "bias" in g else [0.0, 0.0, 0.0])}
    st = _table(ctx, data, "sensors.star_tracker")
    if st is not None:
        n = "sensors.star_tracker"
        out["star_tracker"] = {
            "rate": parse_quantity(ctx, f"[{n}] rate", _required(ctx, st, n, "rate"), u.Hz, dimensionless=False),
            "noise": parse_quantity(ctx, f"[{n}] noise", _required(ctx, st, n, "noise"), u.rad, dimensionless=False),
            "noise_roll": _q(ctx, st, n, "noise_roll", u.rad),
            "boresight": (parse_plain_vector(ctx, f"[{n}] boresight", st["boresight"], 3).tolist()
                          if "boresight" in st else [0.0, 0.0, 1.0]),
            "sun_exclusion": _q(ctx, st, n, "sun_exclusion", u.rad),
            "earth_exclusion": _q(ctx, st, n, "earth_exclusion", u.rad),
            "misalignment": (parse_vector(ctx, f"[{n}] misalignment", st["misalignment"], 3, u.rad,
                                          dimensionless=False).tolist() if "misalignment" in st else None)}
        if out["star_tracker"]["sun_exclusion"] is not None and (orbit is None or orbit.get("epoch") is None):
            raise ctx.error(f"[{n}] sun_exclusion", "needs the Sun's position: give [orbit] epoch")
    m = _table(ctx, data, "sensors.magnetometer")
    if m is not None:
        n = "sensors.magnetometer"
        out["magnetometer"] = {
            "rate": parse_quantity(ctx, f"[{n}] rate", _required(ctx, m, n, "rate"), u.Hz, dimensionless=False),
            "noise": parse_quantity(ctx, f"[{n}] noise", _required(ctx, m, n, "noise"), u.T, dimensionless=False),
            "bias": (parse_vector(ctx, f"[{n}] bias", m["bias"], 3, u.T, dimensionless=False).tolist()
                     if "bias" in m else [0.0, 0.0, 0.0])}
        out["magnetic_field"] = _field(ctx, data, orbit)
    ss = _table(ctx, data, "sensors.sun_sensor")
    if ss is not None:
        n = "sensors.sun_sensor"
        out["sun_sensor"] = {
            "rate": parse_quantity(ctx, f"[{n}] rate", _required(ctx, ss, n, "rate"), u.Hz, dimensionless=False),
            "noise": parse_quantity(ctx, f"[{n}] noise", _required(ctx, ss, n, "noise"), u.rad, dimensionless=False)}
        if orbit is None or orbit.get("epoch") is None:
            raise ctx.error(f"[{n}]", "needs the Sun's position: give [orbit] epoch")
    if est is not None:
        e = _table(ctx, data, "estimator")
        parse_choice(ctx, "[estimator] kind", _required(ctx, e, "estimator", "kind"), ESTIMATOR_KINDS)
        out["estimator"] = {
            "attitude_sigma": parse_quantity(ctx, "[estimator] attitude_sigma",
                                             _required(ctx, e, "estimator", "attitude_sigma"), u.rad,
                                             dimensionless=False),
            "bias_sigma": parse_quantity(ctx, "[estimator] bias_sigma", _required(ctx, e, "estimator", "bias_sigma"),
                                         _RATE, dimensionless=False)}
    try:
        navigation_of(out).check_period(control.get("period"))
    except InputError as exc:
        msg = str(exc)
        key, _, rest = msg.partition(": ")
        where = {"gyro rate": "[sensors.gyro] rate", "star_tracker rate": "[sensors.star_tracker] rate",
                 "magnetometer rate": "[sensors.magnetometer] rate", "sun_sensor rate": "[sensors.sun_sensor] rate",
                 "magnetometer / sun_sensor": "[estimator]", "star_tracker misalignment":
                 "[sensors.star_tracker] misalignment",
                 "estimator": "[estimator]", "feedback": "[control] feedback", "sensors": "[sensors]",
                 "[control] period": "[control] period"}.get(key, f"[sensors] {key}")
        raise ctx.error(where, rest or msg) from None
    return out


def _field(ctx, data, orbit):
    """The field model a magnetometer reads: ``[environment] magnetic_field`` ('igrf' or
    'dipole'), with the epoch it needs."""
    env = data.get("environment", {})
    field = env.get("magnetic_field") if isinstance(env, dict) else None
    if field is None or field == "none":
        raise ctx.error("[environment] magnetic_field", "missing; [sensors.magnetometer] needs a field model: add "
                                                        "[environment] magnetic_field = 'igrf' or 'dipole'")
    field = parse_choice(ctx, "[environment] magnetic_field", field, ("igrf", "dipole"))
    if orbit is None or orbit.get("epoch") is None:
        raise ctx.error("[orbit] epoch", f"missing; the {field} field of [sensors.magnetometer] needs the date")
    check_field_epoch(ctx, field, orbit["epoch"])
    return field


def reads_magnetic_field(data):
    """Whether the scenario's sensors read ``[environment] magnetic_field`` (a magnetometer)."""
    s = data.get("sensors")
    return isinstance(s, dict) and "magnetometer" in s


def navigation_of(settings):
    """The :class:`~orbatt.sensors.Navigation` of :func:`parse_navigation`'s settings (SI floats)."""
    g, st, e = settings["gyro"], settings["star_tracker"], settings["estimator"]
    gyro = None if g is None else Gyro(g["rate"] * u.Hz, g["arw"] * u.rad / u.s ** 0.5, g["rrw"] * u.rad / u.s ** 1.5,
                                       np.asarray(g["bias"]) * _RATE)
    tracker = None
    if st is not None:
        opt = {k: st[k] * u.rad for k in ("noise_roll", "sun_exclusion", "earth_exclusion") if st[k] is not None}
        if st.get("misalignment") is not None:
            opt["misalignment"] = np.asarray(st["misalignment"]) * u.rad
        tracker = StarTracker(st["rate"] * u.Hz, st["noise"] * u.rad, boresight=st["boresight"], **opt)
    mekf = None if e is None else MEKF(e["attitude_sigma"] * u.rad, e["bias_sigma"] * _RATE)
    m, ss = settings.get("magnetometer"), settings.get("sun_sensor")
    mag = None if m is None else Magnetometer(m["rate"] * u.Hz, m["noise"] * u.T, np.asarray(m["bias"]) * u.T)
    sun = None if ss is None else SunSensor(ss["rate"] * u.Hz, ss["noise"] * u.rad)
    return Navigation(settings["seed"], case=settings["case"], gyro=gyro, star_tracker=tracker, estimator=mekf,
                      feedback=settings["feedback"], magnetometer=mag, sun_sensor=sun)


def attach_navigation(law, settings):
    """``law`` with the sensors and filter of ``settings`` (None: as it is)."""
    if settings is None or law is None:
        return law
    return with_navigation(law, navigation_of(settings))

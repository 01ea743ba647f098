"""The ``[sensors]`` and ``[estimator]`` tables of a scenario and ``[control] feedback``
(issue 33): the flight software's noisy sensors and attitude filter (:mod:`orbatt.sensors`),
parsed into plain settings that :func:`navigation_of` makes a :class:`~orbatt.sensors.Navigation`
of; every rule is the objects' own (a rejected value names its key).
"""
from __future__ import annotations

import numpy as np
from astropy import units as u

from ..errors import InputError
from ..sensors import FEEDBACKS, MEKF, Gyro, Navigation, StarTracker, with_navigation
from .fields import parse_choice, parse_int, parse_plain_vector, parse_quantity, parse_vector
from .key_docs import parse_key_docs

__all__ = ["SENSOR_TABLES", "SENSOR_KEY_DOCS", "parse_navigation", "navigation_of", "attach_navigation",
           "ESTIMATOR_KINDS"]

#: the keys of each table
SENSOR_TABLES = {
    "sensors": {"seed", "case", "gyro", "star_tracker"},
    "sensors.gyro": {"rate", "arw", "rrw", "bias"},
    "sensors.star_tracker": {"rate", "noise", "noise_roll", "boresight", "sun_exclusion", "earth_exclusion"},
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
            "earth_exclusion": _q(ctx, st, n, "earth_exclusion", u.rad)}
        if out["star_tracker"]["sun_exclusion"] is not None and (orbit is None or orbit.get("epoch") is None):
            raise ctx.error(f"[{n}] sun_exclusion", "needs the Sun's position: give [orbit] epoch")
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
        nav = navigation_of(out)
        if control.get("period") is None and nav.feedback == "estimate":
            nav.check_law(type("Law", (), {"period": None})())
        elif control.get("period") is not None:
            nav.check_law(type("Law", (), {"period": control["period"]})())
    except InputError as exc:
        msg = str(exc)
        key, _, rest = msg.partition(": ")
        where = {"gyro rate": "[sensors.gyro] rate", "star_tracker rate": "[sensors.star_tracker] rate",
                 "estimator": "[estimator]", "feedback": "[control] feedback", "sensors": "[sensors]",
                 "[control] period": "[control] period"}.get(key, f"[sensors] {key}")
        raise ctx.error(where, rest or msg) from None
    return out


def navigation_of(settings):
    """The :class:`~orbatt.sensors.Navigation` of :func:`parse_navigation`'s settings (SI floats)."""
    g, st, e = settings["gyro"], settings["star_tracker"], settings["estimator"]
    gyro = None if g is None else Gyro(g["rate"] * u.Hz, g["arw"] * u.rad / u.s ** 0.5, g["rrw"] * u.rad / u.s ** 1.5,
                                       np.asarray(g["bias"]) * _RATE)
    tracker = None
    if st is not None:
        opt = {k: st[k] * u.rad for k in ("noise_roll", "sun_exclusion", "earth_exclusion") if st[k] is not None}
        tracker = StarTracker(st["rate"] * u.Hz, st["noise"] * u.rad, boresight=st["boresight"], **opt)
    mekf = None if e is None else MEKF(e["attitude_sigma"] * u.rad, e["bias_sigma"] * _RATE)
    return Navigation(settings["seed"], case=settings["case"], gyro=gyro, star_tracker=tracker, estimator=mekf,
                      feedback=settings["feedback"])


def attach_navigation(law, settings):
    """``law`` with the sensors and filter of ``settings`` (None: as it is)."""
    if settings is None or law is None:
        return law
    return with_navigation(law, navigation_of(settings))

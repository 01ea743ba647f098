"""What the engineering figures of a result draw (issue 26 §4): which figures a Dataset's
content calls for (:func:`choose_figures`), and the series behind them - the pointing error
to the control target or to the orbital frame (:func:`pointing_error`), the eclipses
(:func:`eclipse_intervals`), the limits of the reaction wheels (:func:`wheel_limits`), the
detumble threshold and B-dot steady-state rate (:func:`reference_rates`, :func:`thresholds`),
the rate relative to the orbital frame (:func:`rate_to_orbital_frame`) and values in the units
an attitude engineer reads (:func:`values_in`). No matplotlib here; :mod:`orbatt.dataset.figures` draws.

Every function takes a single run or an ensemble (a ``case`` dimension first): arrays keep
the Dataset's leading dimensions, ``(..., time)``.
"""
from __future__ import annotations

import json
from typing import NamedTuple

import numpy as np
from astropy import units as u

from .. import quaternion as qt
from ..orbital import lvlh_angles
from ..units import parse_unit, unit_string
from .plots import stored_scenario, value_in, drift_series, impulse_times, log_values
from .timeaxis import elapsed_values

__all__ = ["ModeInterval", "mode_intervals", "FIGURES", "LVLH_LABELS", "LVLH_DEFINITION", "Pointing", "choose_figures", "control_law",
           "pointing_error", "eclipse_intervals", "wheel_limits", "reference_rates", "thresholds",
           "rate_to_orbital_frame", "wheel_gyroscopic", "unit_factor", "values_in", "torque_terms", "conserved",
           "log_values", "impulse_times", "libration_angle"]

#: every figure orbatt draws, in the order they are written (``<name>-<figure>.png``)
FIGURES = ("pointing", "knowledge", "orbit", "rates", "wheels", "torques", "drift")


def _json_attr(ds, name):
    try:
        return json.loads(ds.attrs.get(name) or "{}")
    except (TypeError, ValueError):
        return {}


def control_law(ds):
    """The control law the run used (``potential`` attribute's ``control``, a dict with
    ``law`` ``"pd"`` or ``"bdot"`` and its settings), or None."""
    c = _json_attr(ds, "potential").get("control")
    return c if isinstance(c, dict) and c.get("law") else None


def torque_terms(ds):
    """Names of the torque variables a run records, in the order drawn: each external term
    (``torque_<term>``), the total ``torque``, then ``torque_control``."""
    terms = sorted(n for n in ds.data_vars if n.startswith("torque_") and n != "torque_control")
    return terms + [n for n in ("torque", "torque_control") if n in ds.data_vars]


def unit_factor(ds, name, unit):
    """``(factor, unit label)``: the factor from variable ``name``'s stored unit to ``unit``
    (e.g. ``"deg/s"``), or ``1`` and its own unit where it cannot be converted (a
    dimensionless problem's ``"1"``)."""
    src = ds[name].attrs.get("units", "1")
    try:
        target = parse_unit(unit) if isinstance(unit, str) else u.Unit(unit)
        factor = float(parse_unit(src).to(target))
    except (u.UnitConversionError, ValueError):
        return 1.0, ("dimensionless" if src in ("1", "") else unit_string(parse_unit(src)))
    return factor, unit if isinstance(unit, str) else unit_string(target)


def values_in(ds, name, unit):
    """``(values, unit label)``: variable ``name`` in ``unit`` (:func:`unit_factor`)."""
    factor, label = unit_factor(ds, name, unit)
    return np.asarray(ds[name].values, dtype=np.float64) * factor, label


#: the names of the 3-2-1 angles relative to the orbital frame, as the Dataset's ``euler_321``
#: defines them (:func:`orbatt.orbital.lvlh_angles`): the axis each one turns about
LVLH_LABELS = ("roll (about o2, along-track)", "pitch (about o3, orbit normal)", "yaw (about o1, radial)")
#: how they are defined, as the figures state it
LVLH_DEFINITION = ("the Dataset's euler_321: yaw about o1, then pitch about o3, then roll about o2 "
                   "(3-2-1 in the axes o2, o3, o1)")
#: the names of the 3-2-1 angles of an error to an inertial target (:func:`orbatt.quaternion.to_euler321`)
INERTIAL_LABELS = ("about target x", "about target y", "about target z")
INERTIAL_DEFINITION = "3-2-1 of target_q~ q: z, then the new y, then the new x (orbatt.quaternion.to_euler321)"


class Pointing(NamedTuple):
    """What the pointing figure draws (:func:`pointing_error`)."""

    #: the rotation angle of the error (rad, ``(..., time)``)
    angle: np.ndarray
    #: what the error is relative to
    title: str
    #: the error's three angles (rad, ``(..., time, 3)``), None for a Sun-pointing error (one angle)
    components: np.ndarray | None = None
    #: the names of the three angles, each with the axis it turns about
    labels: tuple = ()
    #: the sequence that defines them
    definition: str = ""


def pointing_error(ds):
    """The pointing error of a run, or None where it has no pointing reference.

    - PD control (``potential`` attribute): the angle to its target - the rotation angle of
      ``q_orbital`` relative to ``target_q`` (identity by default) for ``target = "orbital"``,
      of ``q`` relative to ``target_q`` for ``"inertial"``, and the angle between the body
      axis ``target_axis`` and ``sun_direction`` for ``"sun"`` (needs that variable);
    - B-dot control: None (the goal is the rate: see the ``rates`` figure);
    - no control, with an orbit (``q_orbital``): the rotation angle of the body axes relative
      to the orbital frame.

    Returns
    -------
    Pointing or None
        The angle, a title saying what it is relative to, and its components: relative to the
        orbital frame (or an offset target in it) roll, pitch and yaw exactly as the Dataset's
        ``euler_321`` defines them (:data:`LVLH_LABELS`, :func:`orbatt.orbital.lvlh_angles`; for
        an uncontrolled run they are ``euler_321`` itself); relative to an inertial target the
        3-2-1 angles about the target's axes (:data:`INERTIAL_LABELS`); none for the Sun.
    """
    ctrl = control_law(ds)
    if ctrl is not None and ctrl["law"] == "bdot":
        return None
    target = ctrl.get("target") if ctrl else None
    if target == "sun":
        if "sun_direction" not in ds:
            return None
        axis = np.asarray(ctrl.get("target_axis", (0.0, 0.0, 1.0)), dtype=np.float64)
        b = qt.rotate(np.asarray(ds["q"].values), np.broadcast_to(axis, ds["q"].shape[:-1] + (3,)))
        s = np.asarray(ds["sun_direction"].values)
        angle = np.arctan2(np.linalg.norm(np.cross(b, s), axis=-1), np.sum(b * s, axis=-1))
        return Pointing(angle, f"angle between body axis {axis.tolist()} and the Sun (PD target)")
    if target == "inertial":
        qe = qt.mul(qt.conj(np.asarray(ctrl["target_q"], dtype=np.float64)), np.asarray(ds["q"].values))
        title = f"attitude error to the inertial target {np.round(ctrl['target_q'], 4).tolist()} (PD)"
        labels, definition = INERTIAL_LABELS, INERTIAL_DEFINITION
        qe = qt.normalize(qe)
        components = np.stack(qt.to_euler321(qe), axis=-1)
    elif "q_orbital" in ds:
        q_orb = np.asarray(ds["q_orbital"].values)
        tq = ctrl.get("target_q") if target == "orbital" else None
        offset = tq is not None and not np.allclose(np.abs(np.asarray(tq, dtype=np.float64)[0]), 1.0)
        qe = q_orb if tq is None else qt.mul(qt.conj(np.asarray(tq, dtype=np.float64)), q_orb)
        title = ("attitude error to the orbital frame target (PD)" if target == "orbital" else
                 "attitude relative to the orbital frame (no control)" if ctrl is None else
                 "attitude relative to the orbital frame (a mode sequence: its modes' targets differ; see `mode`)"
                 if ctrl["law"] == "modes" else "attitude relative to the orbital frame")
        labels = LVLH_LABELS
        definition = LVLH_DEFINITION + ("; of the error to target_q, in the target's axes" if offset else "")
        qe = qt.normalize(qe)
        components = np.stack(lvlh_angles(qe), axis=-1)
    else:
        return None
    # the rotation angle of qe, accurate at small angles: 2 atan2(|vector part|, |scalar part|)
    angle = 2.0 * np.arctan2(np.linalg.norm(qe[..., 1:], axis=-1), np.abs(qe[..., 0]))
    return Pointing(angle, title, components, labels, definition)


def eclipse_intervals(ds, x):
    """``[(x_start, x_end, umbra)]``: the stretches of the time axis values ``x`` where the body
    is in the Earth's shadow (``shadow`` below 1; ``umbra``: it reaches 0). Empty without a
    ``shadow`` variable (a run without SRP has none)."""
    if "shadow" not in ds:
        return []
    s = np.asarray(ds["shadow"].values, dtype=np.float64)
    while s.ndim > 1:  # the shadow depends on the orbit only: any member's
        s = s[0]
    dark = s < 1.0
    out = []
    k, n = 0, dark.size
    while k < n:
        if not dark[k]:
            k += 1
            continue
        j = k
        while j + 1 < n and dark[j + 1]:
            j += 1
        out.append((x[max(k - 1, 0)] if k else x[k], x[j + 1] if j + 1 < n else x[j], bool(np.any(s[k:j + 1] <= 0.0))))
        k = j + 1
    return out


class ModeInterval(NamedTuple):
    """A stretch of the run in one mode of the flight software's sequence: ``start``, ``end``
    (the Dataset's ``elapsed`` unit), the mode's flag value ``mode`` and its ``name``."""

    start: float
    end: float
    mode: int
    name: str


def mode_intervals(ds):
    """The run's modes as :class:`ModeInterval` s, in order (empty without a ``mode`` variable;
    an ensemble: its first member's). Each begins when the mode was entered - its
    ``mode_entry_time`` (a tick between two outputs), else the first output in it - and ends
    where the next begins (the last at the last output); a mode entered and left between two
    outputs is one too (from its ``mode_entry_time`` to the next's); names from ``mode``'s CF
    ``flag_values`` / ``flag_meanings``."""
    if "mode" not in ds:
        return []
    mode = np.asarray(ds["mode"].values)
    entry = np.asarray(ds["mode_entry_time"].values, dtype=np.float64) if "mode_entry_time" in ds else None
    while mode.ndim > 1:
        mode = mode[0]
        entry = entry[0] if entry is not None and entry.ndim > 1 else entry
    t = np.asarray(elapsed_values(ds), dtype=np.float64)
    while t.ndim > 1:
        t = t[0]
    names = dict(zip(np.asarray(ds["mode"].attrs.get("flag_values", [])).ravel().tolist(),
                     str(ds["mode"].attrs.get("flag_meanings", "")).split()))
    starts = [i for i in range(mode.size) if mode[i] >= 0 and (i == 0 or mode[i] != mode[i - 1])]

    def entered(m, i):  # the entry time of mode m, where it lies between output i - 1 and i
        e = float(entry[m]) if entry is not None and m < entry.size else np.nan
        return e if i > 0 and t[i - 1] < e <= t[i] else None

    out = []  # [begin, end, mode, name, its first output (None: entered and left between two outputs)]
    for i in starts:
        m = int(mode[i])
        for p in range(out[-1][2] + 1 if out else m, m):  # modes passed between the outputs i - 1 and i
            e = entered(p, i)
            if e is not None:
                out.append([e, None, p, names.get(p, f"mode {p}"), None])
        e = entered(m, i)
        out.append([float(t[i]) if e is None else e, None, m, names.get(m, f"mode {m}"), i])
    firsts = [x[4] for x in out if x[4] is not None] + [None]
    for n, x in enumerate(out):
        x[1] = out[n + 1][0] if n + 1 < len(out) else float(t[-1])
        if x[4] is None:
            continue
        j = firsts[firsts.index(x[4]) + 1]
        if j is not None and np.any(mode[x[4]:j] < 0):  # (no mode: -1) the stretch ends at its last output
            x[1] = float(t[x[4] + int(np.argmax(mode[x[4]:j] < 0)) - 1])
    return [ModeInterval(*x[:4]) for x in out]


def wheel_limits(ds):
    """``(max_speed, max_torque)``: each wheel's limits (rad/s, N m; NaN for none), from the
    ``wheels`` attribute (JSON, :func:`orbatt.dataset.build.dataset_content` writes it), else
    (files of orbatt before it) the stored scenario's ``[[body.wheels]]``; None without either,
    or where their count is not the ``wheel`` dimension's."""
    if "wheel" not in ds.sizes:
        return None
    try:
        wheels = json.loads(ds.attrs["wheels"])
        speed = [value_in(w.get("max_speed_rad_s"), u.rad / u.s) for w in wheels]
        torque = [value_in(w.get("max_torque_N_m"), u.N * u.m) for w in wheels]
    except (KeyError, TypeError, ValueError, AttributeError):
        wheels = (stored_scenario(ds).get("body") or {}).get("wheels")
        if not isinstance(wheels, list) or not all(isinstance(w, dict) for w in wheels):
            return None
        speed = [value_in(w.get("max_speed"), u.rad / u.s) for w in wheels]
        torque = [value_in(w.get("max_torque"), u.N * u.m) for w in wheels]
    if not wheels or len(wheels) != ds.sizes["wheel"]:
        return None
    return (np.array([np.nan if v is None else v for v in speed], dtype=np.float64),
            np.array([np.nan if v is None else v for v in torque], dtype=np.float64))


def thresholds(ds):
    """The study thresholds of the stored scenario's ``[sweep]`` table: ``{"detumble_rate":
    rad/s (plain in normalized units) or None, "settling_angle": rad or None}``."""
    sweep = stored_scenario(ds).get("sweep")
    sweep = sweep if isinstance(sweep, dict) else {}
    return {"detumble_rate": value_in(sweep.get("detumble_rate"), u.rad / u.s),
            "settling_angle": value_in(sweep.get("settling_angle"), u.rad)}


def reference_rates(ds):
    """``[(rate, label)]``: the reference lines of the ``rates`` figure (rad/s, or the plain
    rate of a normalized scenario) - the detumble threshold (``[sweep] detumble_rate``) where
    the scenario has one and, for B-dot, twice the mean motion (the rate B-dot settles to in a
    polar orbit)."""
    out = []
    rate = thresholds(ds)["detumble_rate"]
    if rate is not None:
        out.append((float(rate), "detumble threshold ([sweep] detumble_rate)"))
    ctrl = control_law(ds)
    period = _json_attr(ds, "orbit").get("period_s")
    if ctrl is not None and ctrl["law"] == "bdot" and period:
        out.append((2.0 * 2.0 * np.pi / float(period), "2 n: B-dot's steady state (n: mean motion)"))
    return out


def rate_to_orbital_frame(ds):
    """The body rate relative to the orbital frame, ``omega - omega_O`` (body components, in
    the unit of ``omega``; ``(..., time, 3)``), for a run held on (or drifting about) the orbital
    frame: one whose pointing reference is that frame (:func:`pointing_error`). ``omega_O`` is
    the orbital frame's rate, the true anomaly's rate about the orbit normal ``o3``. None
    otherwise (no orbit, B-dot, an inertial or Sun target, fewer than 3 outputs)."""
    ctrl = control_law(ds)
    if ctrl is not None and (ctrl["law"] != "pd" or ctrl.get("target") != "orbital"):
        return None
    if not {"q_orbital", "true_anomaly", "omega"} <= set(ds.variables) or ds.sizes["time"] < 3:
        return None
    t = elapsed_values(ds)  # seconds (or the dimensionless time): time holds datetimes
    nu = np.unwrap(np.asarray(ds["true_anomaly"].values, dtype=np.float64), axis=-1)
    nu_dot = np.gradient(nu, t, axis=-1)
    q_orb = np.asarray(ds["q_orbital"].values, dtype=np.float64)
    w_orb = np.zeros(q_orb.shape[:-1] + (3,))
    w_orb[..., 2] = np.broadcast_to(nu_dot, q_orb.shape[:-1])
    return np.asarray(ds["omega"].values, dtype=np.float64) - qt.rotate_inv(q_orb, w_orb)


def conserved(ds):
    """True when the run has an invariant worth a drift figure: no control, no wheels, no
    torque but the gravity gradient, one run (not an ensemble: each case has its own
    invariant), and :func:`orbatt.dataset.plots.drift_series` finds the
    energy or the Jacobi integral conserved."""
    if control_law(ds) is not None or "wheel_speed" in ds or "case" in ds.dims:
        return False
    if any(n not in ("torque", "torque_gravity_gradient") for n in torque_terms(ds)):
        return False
    first = ds.isel(case=0) if "case" in ds.dims else ds
    return not drift_series(first)[1].startswith("energy change")


def choose_figures(ds):
    """The figures the content of ``ds`` calls for, in :data:`FIGURES` order.

    - ``pointing``: a pointing reference (:func:`pointing_error`: a PD target, or the orbital
      frame of an uncontrolled run with an orbit);
    - ``knowledge``: an attitude filter (``knowledge_error``): its error and 3 sigma;
    - ``orbit``: a binary (``separation``): the mutual orbit, its period and the libration;
    - ``rates``: always (``omega``);
    - ``wheels``: reaction wheels (``wheel_speed``);
    - ``torques``: any torque (``torque``, ``torque_<term>``, ``torque_control``);
    - ``drift``: an invariant to check the integration by (:func:`conserved`).
    """
    out = []
    if pointing_error(ds) is not None:
        out.append("pointing")
    if "knowledge_error" in ds:
        out.append("knowledge")
    if "separation" in ds:
        out.append("orbit")
    out.append("rates")
    if "wheel_speed" in ds:
        out.append("wheels")
    if torque_terms(ds):
        out.append("torques")
    if conserved(ds):
        out.append("drift")
    return tuple(out)


def wheel_gyroscopic(ds):
    """The reaction wheels' gyroscopic term ``omega x h`` (N m, body components, ``(..., time,
    3)``), ``h = sum_k h_k a_k`` the wheels' axial momenta along their axes: the torque the
    control balances when the body turns with the wheels spun up (Euler's equations of the
    gyrostat, ``J omega' = tau_ext + tau_control - omega x (J omega) - omega x h``). None
    without wheels (``wheel_momentum``, ``wheel_axis``) or where the units do not convert."""
    if not {"wheel_momentum", "wheel_axis", "omega"} <= set(ds.variables):
        return None
    w, wu = values_in(ds, "omega", "rad s^-1")
    h, hu = values_in(ds, "wheel_momentum", "N m s")
    if wu != "rad s^-1" or hu != "N m s":
        return None
    hvec = np.einsum("...k,ki->...i", h, np.asarray(ds["wheel_axis"].values, dtype=np.float64))
    return np.cross(w, hvec)


def libration_angle(ds):
    """The secondary's in-plane libration of a binary (rad, ``(time,)``, in ``[-pi/2, pi/2)``):
    the angle from the line of centres (``position``, primary to secondary) to the body axis 1
    of ``q``, about the orbit normal ``position x velocity``, the axis' sign not counted; 0 for a
    synchronous secondary with its long axis (axis 1) along that line. (The sweep output
    ``max_libration_angle`` is the unsigned angle in space, ``arccos |b1 . r| / |r|``: the same
    where axis 1 stays in the orbit plane.) None without ``position``, ``velocity`` and ``q``."""
    if not {"position", "velocity", "q"} <= set(ds.variables):
        return None
    r = np.asarray(ds["position"].values, dtype=np.float64)
    v = np.asarray(ds["velocity"].values, dtype=np.float64)
    n = np.cross(r, v)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    rhat = r / np.linalg.norm(r, axis=-1, keepdims=True)
    b1 = qt.rotate(np.asarray(ds["q"].values, dtype=np.float64), np.broadcast_to([1.0, 0.0, 0.0], r.shape))
    angle = np.arctan2(np.sum(n * np.cross(rhat, b1), axis=-1), np.sum(rhat * b1, axis=-1))
    return (angle + 0.5 * np.pi) % np.pi - 0.5 * np.pi  # the axis' sign does not count: (-pi/2, pi/2]

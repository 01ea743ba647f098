"""Building the result Dataset of a propagation: :func:`to_dataset` (layout in
:mod:`orbatt.dataset`), its global attributes (:func:`global_attrs`, shared with sweeps) and
the names and constants of the layout.

Every derived variable is computed here from the trajectory with :mod:`orbatt.canonical`,
:mod:`orbatt.quaternion`, :mod:`orbatt.orbital` and the potential's ``evaluate``; nothing is
integrated.

Units
-----
Variables are computed in the kernels' units (:data:`orbatt.units.INTERNAL_UNITS`: kg, km,
s, rad) and converted once, at the end (:func:`si_form`), to what is written
(:data:`orbatt.units.DIMENSIONAL_UNITS`): the attitude family in SI - ``inertia``,
``wheel_inertia`` in kg m^2; ``Q``, ``g``, ``G``, ``qQ``, ``wheel_momentum`` in kg m^2 s^-1;
``energy``, ``kinetic_energy``, ``potential_energy`` in J - each the kernel value times
``1e6``; torques in N m; orbit positions and velocities stay in km and km s^-1. A
dimensionless problem keeps plain numbers (:data:`orbatt.units.DIMENSIONLESS_UNITS`).

The time axis
-------------
Every dimensional result has one time representation, however it was obtained
(``Scenario.run()``, :func:`orbatt.to_dataset`, :func:`orbatt.open_dataset`, plain
:func:`xarray.open_dataset` of the file, a sweep's Dataset):

* ``time`` (dimension coordinate): ``datetime64[ns]`` UTC datetimes, the epoch plus the
  elapsed seconds as CF decoders compute it (leap seconds between the epoch and a sample are
  not counted by numpy's datetimes; :meth:`ds.orbatt.times() <orbatt.dataset.accessor.OrbattAccessor.times>`
  gives exact astropy Times). A run without an epoch is placed on the nominal epoch
  :data:`NOMINAL_EPOCH` (2000-01-01T00:00:00Z, no calendar meaning: the global ``epoch``
  attribute is absent and ``time``'s ``comment`` says so);
* ``elapsed`` (coordinate along ``time``): float64 seconds since the epoch (or the start),
  the integrator's output times bit for bit - use it for arithmetic and plots.

In the file ``time`` is CF's ``seconds since <epoch>`` with ``calendar = "standard"`` and the
same float64 values as ``elapsed`` (:func:`cf_time_attrs`); the in-memory Dataset is that
file form decoded by xarray (:meth:`orbatt.dataset.content.Content.to_dataset`), so the
three ways of getting a Dataset give equal ``time`` values and attributes, with no warning.

A dimensionless problem (normalized units) has no calendar: ``time`` and ``elapsed`` are
both float64 in the problem's time unit (``units = "1"``, the unit ``1/n`` of its rate scale).
"""
from __future__ import annotations

import json
import math
import threading
import time
from collections import OrderedDict
from datetime import datetime, timezone
from typing import TYPE_CHECKING

import numpy as np
from astropy import units as u

from .. import canonical as cn
from .. import quaternion as qt
from .control import control_variables, wheel_coordinates
from ..epoch import iso_epoch
from ..errors import InputError
from ..frame_boundary import body_variables, principal_trajectory
from ..orbital import lvlh_angles
from ..orbits.base import OrbitProvider
from ..potentials import energy_and_torques, evaluate_members
from ..state import continuation_text
from ..terms import FIELD_VARIABLES
from ..units import DIMENSIONLESS_UNITS, INTERNAL_UNITS, LEGACY_OUTPUT, from_kernel
from ..version import __version__
from .content import Content, Var
from .eclipses import eclipse_variables
from .timeaxis import (LEAP_SECONDS, NOMINAL_COMMENT, NOMINAL_EPOCH, cf_time_attrs, elapsed_attrs, elapsed_unit,
                       elapsed_values)

if TYPE_CHECKING:  # annotations only: the Dataset is made by Content.to_dataset
    import xarray

#: why ``q``/``Q`` and ``g``/``G`` differ only in case (CF §2.3 advises against it): the names
#: are the paper's notation, which every equation of the documentation uses
CASE_NOTE = ("q/Q and g/G differ only in case: the notation of Arribas, Elipe & Palacios (2006), "
             "kept so that names match the paper's equations (CF 2.3 advises distinct names)")

__all__ = [
    "CASE_NOTE", "to_dataset", "si_form", "cf_time_attrs", "elapsed_attrs", "NOMINAL_EPOCH", "NOMINAL_COMMENT",
    "LEAP_SECONDS", "UNIT_SYSTEM", "elapsed_values", "elapsed_unit", "dataset_content", "global_attrs", "cf_variable", "to_json", "utc_now", "orbatt_version",
    "QUATERNION_ORDER", "QUAT_INDEX", "QUAT_LABELS", "AXIS_INDEX", "AXIS_LABELS", "EULER_313_LABELS",
    "EULER_321_LABELS", "LABEL_COORDS", "CONVENTIONS", "REFERENCE", "FRAMES",
]

#: Order of the ``quat`` dimension, written on every quaternion variable.
QUATERNION_ORDER = "w x y z"
#: the index coordinates' values, shared by every result: read-only, so that editing a
#: result's coordinate in place cannot change the next run's
QUAT_INDEX = np.array([0, 1, 2, 3])
QUAT_INDEX.flags.writeable = False
QUAT_LABELS = ["w", "x", "y", "z"]
AXIS_INDEX = np.array([1, 2, 3])
AXIS_INDEX.flags.writeable = False
AXIS_LABELS = ["x", "y", "z"]
EULER_313_LABELS = ["phi", "theta", "psi"]
EULER_321_LABELS = ["roll", "pitch", "yaw"]
# the arrays of the label and position coordinates, copied into every Dataset (a copy costs
# less than making them from the lists)
_QUAT_LABELS, _AXIS_LABELS = np.array(QUAT_LABELS), np.array(AXIS_LABELS)
_EULER_313_LABELS, _EULER_321_LABELS = np.array(EULER_313_LABELS), np.array(EULER_321_LABELS)
_ARANGE3 = np.arange(3)
#: the string coordinates beside the numeric dimension coordinates
LABEL_COORDS = ("quat_label", "axis_label", "euler_313_label", "euler_321_label")

CONVENTIONS = "CF-1.11"
#: the ``unit_system`` attribute of a dimensional result
UNIT_SYSTEM = "SI: kg, m, s, rad, J, N m (orbit positions and velocities in km, km s^-1)"
REFERENCE = ("Arribas, M., Elipe, A., Palacios, M. (2006): Quaternions and the rotation of a "
             "rigid body. Celestial Mechanics and Dynamical Astronomy 96, 239-251")
FRAMES = ("S: inertial (space) frame; B: body principal axes; O: orbital frame (o1 radial "
          "outwards, o3 along r x v, o2 = o3 x o1). 'X relative to Y' quaternion p: x_Y = p x_X p~ "
          "(Hamilton product, scalar first).")


def _json_default(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, u.Quantity):
        return str(x)
    if hasattr(x, "isot"):
        return x.isot
    return str(x)


#: what ``json.dumps(obj, default=_json_default, sort_keys=True)`` makes for every call,
#: made once (an encoder keeps no state between calls)
_JSON = json.JSONEncoder(default=_json_default, sort_keys=True)


def to_json(obj) -> str:
    """JSON text of ``obj`` (keys sorted; numpy scalars and arrays, Quantities and Times
    written as numbers, lists and strings; ``None`` as ``{}``).

    The text of a dict of plain values (str keys; str, int, float, bool, None or such dicts
    as values: a run's orbit and potential descriptions, its settings) is remembered by those
    values, their types and the signs of the floats (what decides the text), so that a study
    running the same scenario again skips encoding the floats (~5 us a description).
    """
    if type(obj) is not dict:
        return _JSON.encode(obj if obj is not None else {})
    key = _json_key(obj, 0)
    if key is None:
        return _JSON.encode(obj)
    with _JSON_TEXTS_LOCK:
        text = _JSON_TEXTS.get(key)
        if text is not None:
            _JSON_TEXTS.move_to_end(key)
            return text
    text = _JSON.encode(obj)
    with _JSON_TEXTS_LOCK:
        _JSON_TEXTS[key] = text
        while len(_JSON_TEXTS) > JSON_CACHE_SIZE:
            _JSON_TEXTS.popitem(last=False)
    return text


#: JSON texts of plain dicts by :func:`_json_key`, most recently used last (:func:`to_json`)
_JSON_TEXTS: OrderedDict = OrderedDict()
_JSON_TEXTS_LOCK = threading.Lock()
#: most texts kept
JSON_CACHE_SIZE = 256
#: the value types whose equal values have one JSON text (float: nonzero ones)
_PLAIN = frozenset((str, int, bool, type(None)))


def _json_key(obj, depth):
    """A hashable key that decides :func:`to_json`'s text of the dict ``obj``: its items with
    each value's type (``1``, ``1.0`` and ``True`` are equal keys otherwise) and each float's
    sign (``0.0 == -0.0``); None for anything else (other types, non-str keys, deep nesting)."""
    items = []
    for k, v in obj.items():
        if k.__class__ is not str:
            return None
        t = v.__class__
        if t in _PLAIN or (t is float and v != 0.0):  # equal nonzero floats have one text
            items.append((k, t, v))
        elif t is float:
            items.append((k, t, v, math.copysign(1.0, v)))
        elif t is dict and depth < 2:
            sub = _json_key(v, depth + 1)
            if sub is None:
                return None
            items.append((k, t, sub))
        else:
            return None
    return tuple(items)


def utc_now() -> str:
    """The current time, ISO 8601 UTC to the second (``date_created``, ``history``)."""
    global _NOW
    second = math.floor(time.time())
    last = _NOW
    if last[0] != second:  # formatted once a second (strftime costs ~2 us a run)
        last = _NOW = (second, datetime.fromtimestamp(second, timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"))
    return last[1]


#: ``(second, its utc_now text)`` of the last call
_NOW = (None, "")


def orbatt_version() -> str:
    """orbatt's version string (the ``orbatt_version`` attribute)."""
    return __version__


def cf_variable(dims, data, units, long_name, **extra):
    """An :class:`xarray.Variable` with the CF ``units`` and ``long_name`` attributes (and any
    ``extra`` ones)."""
    from .assembly import variable

    return variable(dims, data, _cf_attrs(units, long_name, extra))


def _cf_attrs(units, long_name, extra):
    attrs = {"units": units, "long_name": long_name}
    attrs.update(extra)
    return attrs


def _var(dims, data, units, long_name, **extra):
    """:func:`cf_variable`'s variable as a plain :class:`~orbatt.dataset.content.Var`."""
    return Var(dims, data, _cf_attrs(units, long_name, extra))


def _quat_attrs(frames, maps):
    return {"quaternion_order": QUATERNION_ORDER, "frames": frames, "convention": maps}


_KM_PER_S = u.km / u.s


def _plain(x, unit):
    """Float64 array of ``x`` in ``unit`` (Quantities are converted, plain values kept)."""
    if isinstance(x, u.Quantity):
        return np.asarray(x.to_value(unit), dtype=np.float64)
    return np.asarray(x, dtype=np.float64)


def _columns(*arrays):
    """``np.stack(arrays, axis=-1)`` of float64 arrays of one shape (copied into one new
    array: a third of np.stack's cost on a few values)."""
    out = np.empty(arrays[0].shape + (len(arrays),))
    for k, a in enumerate(arrays):
        out[..., k] = a
    return out


def _describe(obj):
    """``obj.describe()``, or ``{"kind": <class name>}`` for an object without one."""
    return obj.describe() if hasattr(obj, "describe") else {"kind": type(obj).__name__}


def global_attrs(*, method, settings, stats, potential, dimensionless, complete=True, orbit=None,
                 epoch=None, scenario_text=None, title=None, action=None, **extra) -> dict:
    """The global attributes of an orbatt result (a run's or a sweep's Dataset).

    One place for what every result carries: :func:`to_dataset` and the sweep runner call it.

    Parameters
    ----------
    All keyword-only.

    method : str
        Integration method name (``method``).
    settings : dict
        Method settings, written as JSON text (``method_settings``).
    stats : dict or str
        Integration statistics (``integration_stats``): a dict is written as JSON text, a
        string is kept as is (already JSON).
    potential : Potential or dict
        The potential (its ``describe()`` is written as JSON text, ``potential``) or that
        description itself.
    dimensionless : bool
        The unit system (``unit_system``: :data:`UNIT_SYSTEM` or ``"dimensionless (angles in
        rad)"``).
    complete : bool
        The integration reached its end (``integration_complete``, int8 1 or 0).
    orbit : OrbitProvider or dict, optional
        Its ``describe()`` (or the dict) as JSON text (``orbit``); left out when None.
    epoch : astropy.time.Time or str, optional
        ``time = 0`` (``epoch``, ISO 8601 UTC with ns digits, :func:`orbatt.epoch.iso_epoch`);
        left out when None.
    scenario_text : str, optional
        The scenario's TOML text, verbatim (``scenario``); left out when None.
    title : str, optional
        Default: ``"orbatt attitude propagation (<potential kind>)"``.
    action : str, optional
        What made the result, for ``history`` (``"<now> orbatt <version>: <action>"``);
        default ``"propagated with <method>"``.
    **extra
        Further attributes (e.g. a sweep's ``sweep_*`` description), added after the ones
        above and before ``date_created`` and ``history``; they override a standard one of the
        same name.

    Returns
    -------
    dict
        ``Conventions``, ``title``, ``source``, ``references``, ``orbatt_version``, ``method``,
        ``method_settings``, ``integration_stats``, ``integration_complete``, ``potential``,
        ``unit_system``, ``frames``, ``quaternion_order``, then ``orbit``, ``epoch``,
        ``scenario`` where given, ``extra``, ``date_created`` and ``history``.
    """
    pot_desc = potential if isinstance(potential, dict) else _describe(potential)
    version = orbatt_version()
    attrs = {
        "Conventions": CONVENTIONS,
        "title": title or f"orbatt attitude propagation ({pot_desc.get('kind', 'unknown potential')})",
        "source": f"orbatt {version}",
        "references": REFERENCE,
        "orbatt_version": version,
        "method": str(method),
        "method_settings": to_json(settings),
        # (a run's statistics hold its wall time: encoded directly, never remembered)
        "integration_stats": stats if isinstance(stats, str) else _JSON.encode(stats if stats is not None else {}),
        "integration_complete": np.int8(1 if complete else 0),
        "potential": to_json(pot_desc),
        "unit_system": "dimensionless (angles in rad)" if dimensionless else UNIT_SYSTEM,
        "frames": FRAMES,
        "quaternion_order": QUATERNION_ORDER,
    }
    if orbit is not None:
        attrs["orbit"] = to_json(orbit if isinstance(orbit, dict) else _describe(orbit))
    epoch_s = iso_epoch(epoch)
    if epoch_s:
        attrs["epoch"] = epoch_s
    if scenario_text is not None:
        attrs["scenario"] = str(scenario_text)
    attrs.update(extra)
    now = utc_now()
    attrs["date_created"] = now
    attrs["history"] = f"{now} orbatt {version}: {action or f'propagated with {method}'}"
    return attrs


def to_dataset(trajectory, *, scenario_text=None, epoch=None, title=None) -> "xarray.Dataset":
    """The Dataset of a propagation (layout in :mod:`orbatt.dataset`).

    Parameters and values as :func:`dataset_content`, whose :class:`xarray.Dataset` this is.
    """
    return dataset_content(trajectory, scenario_text=scenario_text, epoch=epoch, title=title).to_dataset()


def dataset_content(trajectory, *, scenario_text=None, epoch=None, title=None) -> Content:
    """The variables of the Dataset of a propagation, as plain arrays (layout in
    :mod:`orbatt.dataset`; :meth:`~orbatt.dataset.content.Content.to_dataset` makes the
    Dataset, :func:`orbatt.dataset.write_netcdf` writes either).

    Parameters
    ----------
    trajectory : orbatt.trajectory.Trajectory
        What :func:`orbatt.propagate` returned: ``t (N,)`` and ``q, Q`` of shape ``(N, 4)`` (or
        ``(E, N, 4)`` for an ensemble) in the body's internal units.
    scenario_text : str, optional
        The scenario's TOML text; stored verbatim as the global attribute ``scenario``.
    epoch : astropy.time.Time or str, optional
        The instant ``time = 0``. Default: the orbit provider's ``epoch`` (if any). Stored as an
        ISO 8601 UTC string (global attribute ``epoch``); dimensionless problems have none.
    title : str, optional
        Global ``title`` attribute (default: a sentence naming the potential).

    Returns
    -------
    Content
        Every derived quantity is computed with :mod:`orbatt.canonical`,
        :mod:`orbatt.quaternion` and ``potential.evaluate``; nothing is integrated here.
    """
    tr = principal_trajectory(trajectory)  # a full inertia tensor: its principal frame (orbatt.frame_boundary)
    body = tr.body
    dimless = bool(body.dimensionless)
    U = DIMENSIONLESS_UNITS if dimless else INTERNAL_UNITS  # computed in these; SI at the end (si_form)
    t = np.ascontiguousarray(tr.t, dtype=np.float64)
    q = np.asarray(tr.q, dtype=np.float64)
    Q = np.asarray(tr.Q, dtype=np.float64)
    ens = q.ndim == 3
    if q.shape != Q.shape or q.shape[-1] != 4 or q.shape[-2] != t.shape[0] or q.ndim not in (2, 3):
        raise InputError(f"trajectory: q {q.shape}, Q {Q.shape} and t {t.shape} do not fit "
                         "(expected q, Q of shape (N, 4) or (E, N, 4) and t of shape (N,))")
    inertia = np.asarray(tr.inertia if tr.inertia is not None else body.inertia_value, dtype=np.float64)
    if ens:
        inertia = np.broadcast_to(inertia, (q.shape[0], 3)).copy()
    lead = ("case",) if ens else ()
    inert_b = inertia[:, None, :] if ens else inertia  # broadcast against (E, N, 3)

    if dimless and epoch is not None:
        raise InputError("epoch: a dimensionless problem has no calendar epoch; leave it out")
    if not callable(getattr(tr.potential, "evaluate", None)):
        raise InputError(f"potential: {type(tr.potential).__name__} has no evaluate(body, t, q), which the Dataset's "
                         "potential energy needs (orbatt.propagate takes any object with a kernel kind, params and "
                         "table); propagate with an orbatt Potential (e.g. orbatt.GravityGradient(orbit)) for a "
                         "Dataset, or use the Trajectory's t, q, Q")
    orbit = tr.orbit
    if epoch is None and orbit is not None and not dimless:
        epoch = getattr(orbit, "epoch", None)
    epoch_s = None if dimless else iso_epoch(epoch)

    # --- state and derived quantities (orbatt.canonical / quaternion / potential) ---
    g, omega, T = cn.body_quantities(q, Q, inert_b)
    G = cn.space_momentum(q, Q)
    norm_err, qQ = cn.constraint_residuals(q, Q)
    # U and the torque terms from one evaluation of the potential where it can give both
    want_tau = bool(getattr(tr.potential, "term_names", None)) and not dimless
    if ens:
        Upot, tau = evaluate_members(tr.potential, body, inertia, t, q, want_tau)
    else:
        Upot, tau = energy_and_torques(tr.potential, body, t, q, want_tau)
    phi, theta, psi = qt.to_euler313(q)
    e313 = _columns(phi, theta, psi)

    tdims = lead + ("time",)
    coords = {
        "time": Var(("time",), t, cf_time_attrs(epoch_s, dimless)),
        "elapsed": Var(("time",), t, elapsed_attrs(epoch_s, dimless)),
        "quat": _var(("quat",), QUAT_INDEX, "1", "quaternion component index (0 = scalar part)",
                     quaternion_order=QUATERNION_ORDER),
        "quat_label": Var(("quat",), _QUAT_LABELS.copy(), {"long_name": "quaternion component name"}),
        "axis": _var(("axis",), AXIS_INDEX, "1", "vector component index (axis 1, 2, 3 of the named frame)"),
        "axis_label": Var(("axis",), _AXIS_LABELS.copy(), {"long_name": "vector component name"}),
        "euler_313_angle": _var(("euler_313_angle",), _ARANGE3.copy(), "1", "position in (phi, theta, psi)"),
        "euler_313_label": Var(("euler_313_angle",), _EULER_313_LABELS.copy(),
                                       {"long_name": "3-1-3 Euler angle name"}),
    }
    if ens:
        coords["case"] = _var(("case",), np.arange(q.shape[0]), "1", "ensemble member")

    qv = tdims + ("quat",)
    vv = tdims + ("axis",)
    data = {
        "q": _var(qv, q, "1", "attitude quaternion of the body",
                  **_quat_attrs("B relative to S", "x_S = q x_B q~ (maps body to space components)")),
        "Q": _var(qv, Q, U["momentum"], "conjugate momentum of q (paper eq. 5: Q = 2 q g)",
                  quaternion_order=QUATERNION_ORDER, conjugate_to="q (B relative to S)",
                  convention="g = 1/2 Im(q~ Q) (body), G = 1/2 Im(Q q~) (space)", comment=CASE_NOTE),
        "omega": _var(vv, omega, U["rate"], "angular velocity of the body (body components)", frame="B"),
        "g": _var(vv, g, U["momentum"], "angular momentum (body components)", frame="B"),
        "G": _var(vv, G, U["momentum"], "angular momentum (space components)", frame="S", comment=CASE_NOTE),
        "energy": _var(tdims, T + Upot, U["energy"], "total energy H = T + U"),
        "kinetic_energy": _var(tdims, T, U["energy"], "kinetic energy T (paper eq. 6)"),
        "potential_energy": _var(tdims, Upot, U["energy"], "potential energy U"),
        "q_norm_error": _var(tdims, norm_err, "1", "constraint residual |q| - 1"),
        "qQ": _var(tdims, qQ, U["momentum"], "constraint residual q.Q (R4 dot product)"),
        "euler_313": _var(tdims + ("euler_313_angle",), e313, "rad",
                          "3-1-3 Euler angles (phi, theta, psi) of q (paper eq. 12): "
                          "q = q_z(phi) q_x(theta) q_z(psi)", frames="B relative to S"),
        "inertia": _var(lead + ("axis",), inertia, U["inertia"], "principal moments of inertia (I1, I2, I3)",
                        frame="B"),
    }

    if orbit is not None:
        # a provider without quantities() (any object with the contract's methods): one by one
        r, p, nu, pos, vel = (orbit.quantities(t) if hasattr(orbit, "quantities")
                              else OrbitProvider.quantities(orbit, t))
        r, p, nu = _plain(r, u.km), _plain(p, u.one), _plain(nu, u.rad)
        pos, vel = _plain(pos, u.km), _plain(vel, _KM_PER_S)
        q_orb = qt.mul(qt.conj(p), q)
        roll, pitch, yaw = lvlh_angles(q_orb)
        coords["euler_321_angle"] = _var(("euler_321_angle",), _ARANGE3.copy(), "1", "position in (roll, pitch, yaw)")
        coords["euler_321_label"] = Var(("euler_321_angle",), _EULER_321_LABELS.copy(),
                                                {"long_name": "3-2-1 Euler angle name"})
        data.update({
            "r": _var(("time",), r, U["length"], "orbit radius"),
            "p": _var(("time", "quat"), p, "1", "orbital quaternion",
                      **_quat_attrs("O relative to S", "x_S = p x_O p~ (maps orbital to space components)")),
            "true_anomaly": _var(("time",), nu, "rad", "true anomaly"),
            "position": _var(("time", "axis"), pos, U["length"], "position of the body's centre of mass", frame="S"),
            "velocity": _var(("time", "axis"), vel, U["speed"], "velocity of the body's centre of mass", frame="S"),
            "q_orbital": _var(qv, q_orb, "1", "attitude quaternion relative to the orbital frame (p~ q)",
                              **_quat_attrs("B relative to O", "x_O = q_orbital x_B q_orbital~")),
            "euler_321": _var(tdims + ("euler_321_angle",), _columns(roll, pitch, yaw), "rad",
                              "roll (about along-track o2), pitch (about orbit normal o3), yaw (about radial o1) "
                              "of q_orbital: q_orbital = m q_yaw,o1 q_pitch,o3 q_roll,o2 m~ (3-2-1 sequence in "
                              "the axes (o2, o3, o1))", frames="B relative to O",
                              body_axes="body axes 2, 3, 1 nominally along o2, o3, o1"),
        })

    data.update(_torque_variables(tr.potential, tau, t, tdims))
    if "sun_direction" not in data:  # a law pointing at the Sun without SRP: what it pointed at
        data.update(_sun_direction(tr.potential, tr.control or getattr(tr.potential, "control", None), t))
    if not dimless:
        data.update(eclipse_variables(tr.potential, t, epoch_s))
    extra = control_variables(tr, body, inertia, t, tdims, U)
    if "kinetic_energy" in extra:  # a gyrostat: its rate and energy replace the rigid body's
        extra["energy"] = _var(tdims, extra["kinetic_energy"].values + Upot, U["energy"], "total energy H = T + U")
    data.update(extra)
    coords.update(wheel_coordinates(body, U))

    pot_desc = _describe(trajectory.potential)
    if trajectory.control is not None and "control" not in pot_desc:  # a law given beside the potential
        pot_desc = {**pot_desc, "control": trajectory.control.describe()}
    # the wheels' settings and limits (what the wheels figure draws: figure_data.wheel_limits)
    wheels = {"wheels": to_json([w.describe() for w in trajectory.body.wheels])} if body.wheels else {}
    attrs = global_attrs(method=tr.method, settings=tr.settings, stats=tr.stats, potential=pot_desc,
                         dimensionless=dimless, complete=tr.complete, orbit=orbit, epoch=epoch_s,
                         scenario_text=scenario_text, title=title, **wheels)
    # back to the body frame of a tensor (q and Q: the trajectory's own, bit for bit)
    data, coords = body_variables(trajectory.body, data, coords, (trajectory.q, trajectory.Q))
    cont = continuation_text(trajectory)
    if cont is not None:  # where a run continued from this file starts (orbatt run --append)
        attrs["continuation"] = cont
    if not dimless:  # the Dataset boundary: the attitude family from kernel units to SI
        data, coords = si_form(data), si_form(coords)
    return Content(data, coords, attrs)


def si_form(variables):
    """``variables`` (name -> :class:`Var`) with the attitude family in SI: each variable whose
    ``units`` is a kernel spelling of :data:`orbatt.units.LEGACY_OUTPUT` (``"kg km^2"``,
    ``"kg km^2 s^-1"``, ``"kg km^2 s^-2"``, or orbatt 0.1's ``"kg km2 s-1"`` ...) is multiplied
    by its factor (``1e6``) and relabelled (``"kg m^2"``, ``"kg m^2 s^-1"``, ``"J"``); the
    others are kept as they are (a new dict)."""
    out = {}
    for name, var in variables.items():
        conv = LEGACY_OUTPUT.get(var.attrs.get("units"))
        if conv is not None:
            var = Var(var.dims, var.values * conv[1], dict(var.attrs, units=conv[0]))
        out[name] = var
    return out


def _sun_direction(potential, control, t):
    """``{"sun_direction": Var}`` for a control law with ``target = "sun"`` (the pointing figure
    measures the error to it; SRP, which writes it otherwise, may be off): from the Sun's table
    the law read (:meth:`orbatt.EnvironmentTorques.field_table`) inside the sampled span, else
    from the Sun's model; empty for any other law."""
    orbit = getattr(potential, "orbit", None)
    if getattr(control, "target", None) != "sun" or orbit is None or getattr(orbit, "epoch", None) is None:
        return {}
    from ..core import environment as kenv
    from ..core import kernel_floats
    from ..environment import sun as esun

    t = np.asarray(t, dtype=np.float64)
    pos = np.asarray(_plain(orbit.state(t)[0], u.km), dtype=np.float64)
    span = getattr(potential, "span", None)
    if span is not None and t.size and span[0] <= t.min() and t.max() <= span[1] and hasattr(potential, "field_table"):
        sun = kenv.piece_eval_many(potential.field_table("sun"), kernel_floats(t), 3)
    else:
        sun = np.asarray(esun.sun_position(orbit.epoch + t * u.s), dtype=np.float64)
    d = sun - pos
    dims, unit, long_name, extra = FIELD_VARIABLES["sun_direction"]
    return {"sun_direction": _var(("time",) + dims, d / np.linalg.norm(d, axis=-1, keepdims=True), unit, long_name,
                                  **extra)}


def _torque_variables(potential, tau, t, tdims):
    """``torque`` (the total) and ``torque_<term>`` of each torque term of ``potential``
    (body axes, N m) from its term torques ``tau`` (``(..., N, terms, 3)``, kg km^2 s^-2; None
    for none), and the environment fields it used along the orbit."""
    if tau is None:
        return {}
    names = list(potential.term_names)
    tau = from_kernel(tau, "torque")  # kg km^2 s^-2 -> N m
    vv = tdims + ("axis",)
    total = tau[..., 0, :].copy()
    for k in range(1, len(names)):
        total += tau[..., k, :]
    out = {"torque": _var(vv, total, "N m", "total external torque on the body (body components)",
                                 frame="B", terms=" + ".join(f"torque_{n}" for n in names))}
    for k, n in enumerate(names):
        out[f"torque_{n}"] = _var(vv, np.ascontiguousarray(tau[..., k, :]), "N m",
                                         f"{n.replace('_', ' ')} torque on the body (body components)", frame="B")
    for key, values in potential.fields(t).items():
        dims, unit, long_name, extra = FIELD_VARIABLES[key]
        out[key] = _var(("time",) + dims, values, unit, long_name, **extra)
    return out

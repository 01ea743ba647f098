"""Results as an :class:`xarray.Dataset`: building from a :class:`~orbatt.trajectory.Trajectory`,
the table of CF unit spellings, the ``ds.orbatt`` accessor, NetCDF export/import (whole or
appended as a run goes) and quick plots.

Layout (``DESIGN.md`` §6)
-------------------------
Dimensions and their coordinates (every coordinate is numeric, as CF requires of coordinate
variables; the names are in a label coordinate beside it):

* ``time`` - float64 time since the epoch: ``s`` (dimensional problems) or ``1``
  (dimensionless ones);
* ``quat`` - ``0 1 2 3``, labels ``w x y z`` (``quat_label``): quaternion component,
  **scalar first**, ``0`` is the paper's ``q0`` (the scalar ``w``);
* ``axis`` - ``1 2 3``, labels ``x y z`` (``axis_label``): component along axis 1, 2, 3 of
  the frame the variable names (the paper's ``b_i`` or ``s_i``);
* ``euler_313_angle`` - ``0 1 2``, labels ``phi theta psi``: the paper's 3-1-3 angles (eq. 12);
* ``euler_321_angle`` - ``0 1 2``, labels ``roll pitch yaw``: angles of ``q_orbital`` about
  the along-track, orbit-normal and radial axes (:func:`lvlh_angles`)
  (only with an orbit);
* ``case`` - ``0 .. E-1``: ensemble member (only for ensembles; the first dimension).

The quaternion index matches the paper's subscripts (``q.sel(quat=0)`` is ``q0``) and the axis
index matches ``I1, I2, I3`` and ``g1, g2, g3``: ``q.sel(quat=k)`` and ``g.sel(axis=k)`` refer
to the same body axis ``k``.

Frames (``DESIGN.md`` §1): ``S`` inertial (space), ``B`` body principal axes, ``O`` orbital
(``o1`` radial outwards, ``o3`` along ``r x v``, ``o2 = o3 x o1``). Quaternion variables carry
``quaternion_order = "w x y z"`` and ``frames = "B relative to S"`` (the rotation that turns the
``S`` axes into the ``B`` axes, ``x_S = q x_B q~``); vector variables carry ``frame``, the frame
of their components.

Variables: ``q``, ``Q`` (the canonical state), ``omega``, ``g`` (body), ``G`` (space),
``energy = kinetic_energy + potential_energy``, ``q_norm_error = |q| - 1``, ``qQ = q.Q``,
``euler_313``, ``inertia``; with an orbit also ``r``, ``p`` (``O`` relative to ``S``),
``true_anomaly``, ``position``, ``velocity`` (in ``S``), ``q_orbital = p~ q`` (``B`` relative to
``O``) and ``euler_321`` (its roll, pitch, yaw about ``o2, o3, o1``; :func:`lvlh_angles`).

Units: dimensional problems use orbatt's internal system (kg, km, s, rad; :mod:`orbatt.units`),
dimensionless ones ``"1"`` everywhere except angles (``"rad"``). Every ``units`` attribute is a
CF/UDUNITS spelling from :data:`CF_UNITS` that :class:`astropy.units.Unit` parses.

Global attributes: ``Conventions = "CF-1.11"``, ``title``, ``source``, ``references``,
``orbatt_version``, ``method``, ``method_settings`` and ``integration_stats`` (JSON text),
``integration_complete`` (1 or 0), ``potential`` and ``orbit`` (JSON text of their
``describe()``), ``unit_system``, ``epoch`` (ISO 8601 UTC, only when the problem has one),
``scenario`` (the scenario's TOML text, when given), ``date_created``, ``history``.

NetCDF (:func:`write_netcdf`, :func:`open_dataset`): float64 stored losslessly (zlib + shuffle),
chunked along an unlimited ``time`` dimension, so that :class:`NetCDFWriter` (or
``write_netcdf(..., append=True)``) can add samples as a long run goes. In the file the time
coordinate of a problem with an epoch has the CF encoding ``units = "seconds since <epoch>"``,
``calendar = "standard"`` (plain :func:`xarray.open_dataset` decodes it to datetimes);
:func:`open_dataset` gives back the in-memory form (``units = "s"``) bit for bit.
"""
from __future__ import annotations

import json
import os
from datetime import datetime, timezone

import numpy as np
import xarray as xr
from astropy import units as u

from . import canonical as cn
from . import quaternion as qt
from .errors import InputError

__all__ = [
    "CF_UNITS", "QUATERNION_ORDER", "unit_string", "parse_unit", "to_euler321", "lvlh_angles", "to_dataset",
    "write_netcdf", "open_dataset", "NetCDFWriter", "OrbattAccessor",
]

#: Order of the ``quat`` dimension, written on every quaternion variable.
QUATERNION_ORDER = "w x y z"
QUAT_INDEX = np.array([0, 1, 2, 3])
QUAT_LABELS = ["w", "x", "y", "z"]
AXIS_INDEX = np.array([1, 2, 3])
AXIS_LABELS = ["x", "y", "z"]
EULER_313_LABELS = ["phi", "theta", "psi"]
EULER_321_LABELS = ["roll", "pitch", "yaw"]

CONVENTIONS = "CF-1.11"
REFERENCE = ("Arribas, M., Elipe, A., Palacios, M. (2006): Quaternions and the rotation of a "
             "rigid body. Celestial Mechanics and Dynamical Astronomy 96, 239-251")
FRAMES = ("S: inertial (space) frame; B: body principal axes; O: orbital frame (o1 radial "
          "outwards, o3 along r x v, o2 = o3 x o1). 'X relative to Y' quaternion p: x_Y = p x_X p~ "
          "(Hamilton product, scalar first).")

#: CF/UDUNITS unit spellings orbatt writes, with the astropy unit each one parses to. Every
#: key round-trips: ``astropy.units.Unit(key) == CF_UNITS[key]`` (tested), and UDUNITS-2
#: accepts it.
CF_UNITS = {
    "1": u.dimensionless_unscaled,
    "rad": u.rad,
    "degree": u.deg,
    "s": u.s,
    "km": u.km,
    "m": u.m,
    "km s-1": u.km / u.s,
    "m s-1": u.m / u.s,
    "rad s-1": u.rad / u.s,
    "degree s-1": u.deg / u.s,
    "kg km2": u.kg * u.km**2,
    "kg m2": u.kg * u.m**2,
    "kg km2 s-1": u.kg * u.km**2 / u.s,
    "kg m2 s-1": u.kg * u.m**2 / u.s,
    "kg km2 s-2": u.kg * u.km**2 / u.s**2,
    "J": u.J,
    "km3 s-2": u.km**3 / u.s**2,
}

# time units of a CF "<unit> since <date>" string
_CF_TIME_UNITS = {"seconds": u.s, "second": u.s, "secs": u.s, "sec": u.s, "s": u.s,
                  "minutes": u.min, "minute": u.min, "min": u.min, "hours": u.h, "hour": u.h,
                  "h": u.h, "days": u.day, "day": u.day, "d": u.day}

# internal unit system (orbatt.units) by quantity kind, and its dimensionless counterpart
DIMENSIONAL_UNITS = {"time": "s", "angle": "rad", "rate": "rad s-1", "inertia": "kg km2",
                "momentum": "kg km2 s-1", "energy": "kg km2 s-2", "length": "km",
                "speed": "km s-1", "one": "1"}
DIMENSIONLESS_UNITS = {k: ("rad" if k == "angle" else "1") for k in DIMENSIONAL_UNITS}

DEFAULT_CHUNK_TIME = 16384
_LABEL_COORDS = ("quat_label", "axis_label", "euler_313_label", "euler_321_label")


# --------------------------------------------------------------------------------------------
# units
# --------------------------------------------------------------------------------------------
def unit_string(unit) -> str:
    """CF/UDUNITS spelling of an astropy unit.

    Parameters
    ----------
    unit : astropy Unit or str
        A unit (a string is parsed first, :func:`parse_unit`).

    Returns
    -------
    str
        The :data:`CF_UNITS` key whose unit is written the same way (``"kg km2 s-1"``), or
        else the FITS spelling astropy gives (``"km2 kg s-3"``, also CF-compatible), or the
        generic one. The result always parses back to an equal unit with
        :func:`astropy.units.Unit`.
    """
    unit = parse_unit(unit) if isinstance(unit, str) else u.Unit(unit)
    if unit == u.dimensionless_unscaled:
        return "1"
    rep = unit.to_string()
    for key, val in CF_UNITS.items():
        if val.to_string() == rep:
            return key
    for fmt in ("fits", "generic"):
        try:
            s = unit.to_string(fmt)
        except (ValueError, u.UnitsError):
            continue
        try:
            if u.Unit(s) == unit:
                return s
        except ValueError:
            continue
    return unit.to_string()


def parse_unit(s):
    """astropy unit of a ``units`` attribute.

    Parameters
    ----------
    s : str
        A :data:`CF_UNITS` key, any string :class:`astropy.units.Unit` parses, or a CF time
        reference ``"seconds since 2024-01-01T00:00:00Z"`` (then the unit before ``since``).

    Raises
    ------
    InputError
        The string is not a unit.
    """
    if isinstance(s, u.UnitBase):
        return s
    s = str(s).strip()
    if s in CF_UNITS:
        return CF_UNITS[s]
    if " since " in s:
        head = s.split(" since ", 1)[0].strip().lower()
        if head in _CF_TIME_UNITS:
            return _CF_TIME_UNITS[head]
    try:
        return u.Unit(s)
    except ValueError:
        raise InputError(f"units: {s!r} is not a unit astropy parses; use a CF spelling such as "
                         f"'rad s-1' or 'kg km2'") from None


# --------------------------------------------------------------------------------------------
# angles
# --------------------------------------------------------------------------------------------
def to_euler321(q):
    """3-2-1 (yaw, pitch, roll) angles of ``q``, returned in the order ``(roll, pitch, yaw)``.

    The sequence: ``q = q_z(yaw) q_y(pitch) q_x(roll)`` with ``q_k(a) = (cos a/2, sin a/2 e_k)``.
    For the attitude of ``B`` relative to a frame ``F`` (``x_F = q x_B q~``; ``F = O`` for
    ``q_orbital``): turn the ``F`` axes by ``yaw`` about axis 3, then by ``pitch`` about the new
    axis 2, then by ``roll`` about the new axis 1; the result is the ``B`` axes (intrinsic
    z-y'-x'', the aerospace convention; scipy's ``Rotation.as_euler("ZYX")`` gives
    ``(yaw, pitch, roll)``).

    Parameters
    ----------
    q : array-like (..., 4)
        Quaternions, scalar first (normalized here).

    Returns
    -------
    roll, pitch, yaw : ndarray (...)
        rad; ``roll, yaw`` in ``(-pi, pi]``, ``pitch`` in ``[-pi/2, pi/2]``. At the singular
        ``pitch = +-pi/2`` only ``yaw -+ roll`` is defined: ``roll = 0`` is returned there
        (when ``cos(pitch) < sqrt(eps)``), never NaN.
    """
    q = qt.normalize(q)
    w, x, y, z = np.moveaxis(q, -1, 0)
    r21 = 2.0 * (w * x + y * z)  # sin(roll) cos(pitch)
    r22 = 1.0 - 2.0 * (x * x + y * y)  # cos(roll) cos(pitch)
    r20 = 2.0 * (w * y - x * z)  # sin(pitch)
    cp = np.hypot(r21, r22)
    pitch = np.arctan2(r20, cp)
    lock = cp < np.sqrt(np.finfo(np.float64).eps)
    roll = np.where(lock, 0.0, np.arctan2(r21, r22))
    yaw_generic = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    # with roll = 0: R = Rz(yaw) Ry(pitch), R01 = -sin(yaw), R11 = cos(yaw)
    yaw_lock = np.arctan2(-2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z))
    yaw = np.where(lock, yaw_lock, yaw_generic)
    return roll, pitch, yaw


#: rotation of 120 deg about (1, 1, 1): relabels the axes (x, y, z) -> (y, z, x)
_LVLH_RELABEL = np.array([0.5, 0.5, 0.5, 0.5])


def lvlh_angles(q_orbital):
    """Roll, pitch, yaw of an attitude relative to the orbital frame, as spacecraft practice
    names them.

    orbatt's orbital frame has ``o1`` radial (zenith), ``o2`` along-track, ``o3`` the orbit
    normal (``DESIGN.md`` §1). **Roll** is the rotation about the along-track axis ``o2``,
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
        rad; ranges and the singular ``pitch = +-pi/2`` as in :func:`to_euler321`.
    """
    m = _LVLH_RELABEL
    return to_euler321(qt.mul(qt.mul(qt.conj(m), q_orbital), m))


# --------------------------------------------------------------------------------------------
# building
# --------------------------------------------------------------------------------------------
def to_json(obj) -> str:
    def default(x):
        if isinstance(x, np.generic):
            return x.item()
        if isinstance(x, np.ndarray):
            return x.tolist()
        if isinstance(x, u.Quantity):
            return str(x)
        if hasattr(x, "isot"):
            return x.isot
        return str(x)

    return json.dumps(obj if obj is not None else {}, default=default, sort_keys=True)


def _plain(x, unit):
    """Float64 array of ``x`` in ``unit`` (Quantities are converted, plain values kept)."""
    if isinstance(x, u.Quantity):
        return np.asarray(x.to_value(unit), dtype=np.float64)
    return np.asarray(x, dtype=np.float64)


def utc_now() -> str:
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def iso_epoch(epoch) -> str | None:
    """ISO 8601 UTC string (``...T..:..:..fffffffffZ``, ns digits) of an epoch, or None."""
    if epoch is None:
        return None
    from astropy.time import Time

    if isinstance(epoch, str):
        s = epoch.strip()
        try:
            t = Time(s[:-1] if s.endswith("Z") else s, scale="utc")
        except ValueError:
            raise InputError(f"epoch: cannot parse {epoch!r} as a date; write e.g. "
                             f"'2024-01-01T00:00:00Z'") from None
    elif isinstance(epoch, Time):
        t = epoch
    else:
        raise InputError(f"epoch: expected an astropy Time or an ISO string, got {epoch!r}")
    t = t.utc
    t.precision = 9
    return t.isot + "Z"


def orbatt_version() -> str:
    from . import __version__

    return __version__


def cf_variable(dims, data, units, long_name, **extra):
    attrs = {"units": units, "long_name": long_name}
    attrs.update(extra)
    return xr.Variable(dims, data, attrs)


def _quat_attrs(frames, maps):
    return {"quaternion_order": QUATERNION_ORDER, "frames": frames, "convention": maps}


def to_dataset(trajectory, *, scenario_text=None, epoch=None, title=None) -> xr.Dataset:
    """The Dataset of a propagation (layout in the module docstring).

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
    xarray.Dataset
        Every derived quantity is computed with :mod:`orbatt.canonical`,
        :mod:`orbatt.quaternion` and ``potential.evaluate``; nothing is integrated here.
    """
    tr = trajectory
    body = tr.body
    dimless = bool(body.dimensionless)
    U = DIMENSIONLESS_UNITS if dimless else DIMENSIONAL_UNITS
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
    orbit = tr.orbit
    if epoch is None and orbit is not None and not dimless:
        epoch = getattr(orbit, "epoch", None)
    epoch_s = None if dimless else iso_epoch(epoch)

    # --- state and derived quantities (orbatt.canonical / quaternion / potential) ---
    g = cn.body_momentum(q, Q)
    omega = cn.body_rate(q, Q, inert_b)
    G = cn.space_momentum(q, Q)
    T = cn.kinetic_energy(q, Q, inert_b)
    norm_err, qQ = cn.constraint_residuals(q, Q)
    if ens:
        Upot = np.stack([_potential_energy(tr.potential, _member_body(body, inertia[e]), t, q[e])
                         for e in range(q.shape[0])])
    else:
        Upot = _potential_energy(tr.potential, body, t, q)
    phi, theta, psi = qt.to_euler313(q)
    e313 = np.stack([phi, theta, psi], axis=-1)

    tdims = lead + ("time",)
    time_attrs = {"units": U["time"], "long_name": ("time since the epoch" if epoch_s else
                                                      "dimensionless time" if dimless else
                                                      "time since the start")}
    if epoch_s:
        time_attrs.update(standard_name="time", axis="T")
    coords = {
        "time": xr.Variable(("time",), t, time_attrs),
        "quat": cf_variable(("quat",), QUAT_INDEX, "1", "quaternion component index (0 = scalar part)",
                     quaternion_order=QUATERNION_ORDER),
        "quat_label": xr.Variable(("quat",), np.array(QUAT_LABELS), {"long_name": "quaternion component name"}),
        "axis": cf_variable(("axis",), AXIS_INDEX, "1", "vector component index (axis 1, 2, 3 of the named frame)"),
        "axis_label": xr.Variable(("axis",), np.array(AXIS_LABELS), {"long_name": "vector component name"}),
        "euler_313_angle": cf_variable(("euler_313_angle",), np.arange(3), "1", "position in (phi, theta, psi)"),
        "euler_313_label": xr.Variable(("euler_313_angle",), np.array(EULER_313_LABELS),
                                       {"long_name": "3-1-3 Euler angle name"}),
    }
    if ens:
        coords["case"] = cf_variable(("case",), np.arange(q.shape[0]), "1", "ensemble member")

    qv = tdims + ("quat",)
    vv = tdims + ("axis",)
    data = {
        "q": cf_variable(qv, q, "1", "attitude quaternion of the body",
                  **_quat_attrs("B relative to S", "x_S = q x_B q~ (maps body to space components)")),
        "Q": cf_variable(qv, Q, U["momentum"], "conjugate momentum of q (paper eq. 5: Q = 2 q g)",
                  quaternion_order=QUATERNION_ORDER, conjugate_to="q (B relative to S)",
                  convention="g = 1/2 Im(q~ Q) (body), G = 1/2 Im(Q q~) (space)"),
        "omega": cf_variable(vv, omega, U["rate"], "angular velocity of the body (body components)", frame="B"),
        "g": cf_variable(vv, g, U["momentum"], "angular momentum (body components)", frame="B"),
        "G": cf_variable(vv, G, U["momentum"], "angular momentum (space components)", frame="S"),
        "energy": cf_variable(tdims, T + Upot, U["energy"], "total energy H = T + U"),
        "kinetic_energy": cf_variable(tdims, T, U["energy"], "kinetic energy T (paper eq. 6)"),
        "potential_energy": cf_variable(tdims, Upot, U["energy"], "potential energy U"),
        "q_norm_error": cf_variable(tdims, norm_err, "1", "constraint residual |q| - 1"),
        "qQ": cf_variable(tdims, qQ, U["momentum"], "constraint residual q.Q (R4 dot product)"),
        "euler_313": cf_variable(tdims + ("euler_313_angle",), e313, "rad",
                          "3-1-3 Euler angles (phi, theta, psi) of q (paper eq. 12): "
                          "q = q_z(phi) q_x(theta) q_z(psi)", frames="B relative to S"),
        "inertia": cf_variable(lead + ("axis",), inertia, U["inertia"], "principal moments of inertia (I1, I2, I3)",
                        frame="B"),
    }

    if orbit is not None:
        r = _plain(orbit.radius(t), u.km)
        p = _plain(orbit.orbital_quaternion(t), u.one)
        nu = _plain(orbit.true_anomaly(t), u.rad)
        pos, vel = orbit.state(t)
        pos = _plain(pos, u.km)
        vel = _plain(vel, u.km / u.s)
        q_orb = qt.mul(qt.conj(p), q)
        roll, pitch, yaw = lvlh_angles(q_orb)
        coords["euler_321_angle"] = cf_variable(("euler_321_angle",), np.arange(3), "1", "position in (roll, pitch, yaw)")
        coords["euler_321_label"] = xr.Variable(("euler_321_angle",), np.array(EULER_321_LABELS),
                                                {"long_name": "3-2-1 Euler angle name"})
        data.update({
            "r": cf_variable(("time",), r, "km", "orbit radius"),
            "p": cf_variable(("time", "quat"), p, "1", "orbital quaternion",
                      **_quat_attrs("O relative to S", "x_S = p x_O p~ (maps orbital to space components)")),
            "true_anomaly": cf_variable(("time",), nu, "rad", "true anomaly"),
            "position": cf_variable(("time", "axis"), pos, "km", "position of the body's centre of mass", frame="S"),
            "velocity": cf_variable(("time", "axis"), vel, "km s-1", "velocity of the body's centre of mass", frame="S"),
            "q_orbital": cf_variable(qv, q_orb, "1", "attitude quaternion relative to the orbital frame (p~ q)",
                              **_quat_attrs("B relative to O", "x_O = q_orbital x_B q_orbital~")),
            "euler_321": cf_variable(tdims + ("euler_321_angle",), np.stack([roll, pitch, yaw], axis=-1), "rad",
                              "roll (about along-track o2), pitch (about orbit normal o3), yaw (about radial o1) "
                              "of q_orbital: q_orbital = m q_yaw,o1 q_pitch,o3 q_roll,o2 m~ (3-2-1 sequence in "
                              "the axes (o2, o3, o1))", frames="B relative to O",
                              body_axes="body axes 2, 3, 1 nominally along o2, o3, o1"),
        })

    pot_desc = tr.potential.describe() if hasattr(tr.potential, "describe") else {"kind": type(tr.potential).__name__}
    attrs = {
        "Conventions": CONVENTIONS,
        "title": title or f"orbatt attitude propagation ({pot_desc.get('kind', 'unknown potential')})",
        "source": f"orbatt {orbatt_version()}",
        "references": REFERENCE,
        "orbatt_version": orbatt_version(),
        "method": str(tr.method),
        "method_settings": to_json(tr.settings),
        "integration_stats": to_json(tr.stats),
        "integration_complete": np.int8(1 if tr.complete else 0),
        "potential": to_json(pot_desc),
        "unit_system": "dimensionless (angles in rad)" if dimless else "kg km s rad",
        "frames": FRAMES,
        "quaternion_order": QUATERNION_ORDER,
    }
    if orbit is not None:
        attrs["orbit"] = to_json(orbit.describe() if hasattr(orbit, "describe") else {"kind": type(orbit).__name__})
    if epoch_s:
        attrs["epoch"] = epoch_s
    if scenario_text is not None:
        attrs["scenario"] = str(scenario_text)
    now = utc_now()
    attrs["date_created"] = now
    attrs["history"] = f"{now} orbatt {orbatt_version()}: propagated with {tr.method}"
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _member_body(body, inertia):
    """The body of an ensemble member with principal moments ``inertia`` (internal unit)."""
    if np.array_equal(inertia, body.inertia_value):
        return body
    from .body import RigidBody

    return RigidBody(inertia.tolist() if body.dimensionless else inertia * body.inertia_unit)


def _potential_energy(potential, body, t, q):
    U, _, _ = potential.evaluate(body, t, q)
    return np.asarray(U, dtype=np.float64).reshape(t.shape)


# --------------------------------------------------------------------------------------------
# NetCDF
# --------------------------------------------------------------------------------------------
def _default_engine():
    try:
        import netCDF4  # noqa: F401

        return "netcdf4"
    except ImportError:
        pass
    try:
        import h5netcdf  # noqa: F401
        import h5py  # noqa: F401

        return "h5netcdf"
    except ImportError:
        raise InputError("NetCDF: neither netCDF4 nor h5netcdf (with h5py) is installed; "
                         "pip install 'orbatt[io]'") from None


def check_engine(engine):
    engine = _default_engine() if engine is None else str(engine).lower()
    if engine not in ("netcdf4", "h5netcdf"):
        raise InputError(f"engine: {engine!r} is not 'netcdf4' or 'h5netcdf' (orbatt files are "
                         "netCDF-4/HDF5: chunked, compressed and appendable)")
    return engine


def encode(ds: xr.Dataset) -> xr.Dataset:
    """The file form: CF time reference where there is an epoch, no stale encodings."""
    out = ds.drop_encoding()
    epoch = ds.attrs.get("epoch")
    if epoch and "time" in ds.coords and ds["time"].attrs.get("units") == "s":
        attrs = dict(ds["time"].attrs)
        attrs["units"] = f"seconds since {epoch}"
        attrs["calendar"] = "standard"
        out = out.assign_coords(time=xr.Variable(("time",), ds["time"].values, attrs))
    return out


def decode(ds: xr.Dataset) -> xr.Dataset:
    """Inverse of :func:`encode` on a dataset opened with ``decode_times=False``."""
    if "time" in ds.coords:
        units = str(ds["time"].attrs.get("units", ""))
        if " since " in units:
            head, ref = (s.strip() for s in units.split(" since ", 1))
            if head.lower() not in ("seconds", "second", "secs", "sec", "s"):
                raise InputError(f"time: units {units!r}; orbatt files use 'seconds since <epoch>'")
            attrs = dict(ds["time"].attrs)
            attrs["units"] = "s"
            attrs.pop("calendar", None)
            ds = ds.assign_coords(time=xr.Variable(("time",), ds["time"].values, attrs,
                                                   encoding=ds["time"].encoding))
            if "epoch" not in ds.attrs:
                ds.attrs["epoch"] = ref
    for name in _LABEL_COORDS:
        if name in ds.coords and ds[name].dtype.kind in "OS":
            vals = np.array([v.decode() if isinstance(v, bytes) else str(v) for v in ds[name].values])
            ds = ds.assign_coords({name: xr.Variable(ds[name].dims, vals, ds[name].attrs)})
    return ds


def encoding(ds: xr.Dataset, complevel: int, chunk_time: int) -> dict:
    enc = {}
    for name, var in ds.variables.items():
        e = {}
        if var.dtype.kind in "fiu":
            e["_FillValue"] = None
        if var.dtype.kind in "US":
            e["dtype"] = "S1"
        if "time" in var.dims:
            e["chunksizes"] = tuple(chunk_time if d == "time" else (1 if d == "case" else n)
                                    for d, n in zip(var.dims, var.shape))
            if var.dtype.kind == "f" and complevel > 0:
                e.update(zlib=True, complevel=int(complevel), shuffle=True)
        enc[name] = e
    return enc


def write_netcdf(ds: xr.Dataset, path, *, engine=None, append=False, complevel=1,
                 chunk_time=DEFAULT_CHUNK_TIME):
    """Write an orbatt Dataset to a netCDF-4 file, or append its samples to one.

    Parameters
    ----------
    ds : xarray.Dataset
        An orbatt Dataset (:func:`to_dataset`) or a slice of one along ``time``.
    path : str or os.PathLike
    engine : {"netcdf4", "h5netcdf"}, optional
        Library used; default netCDF4 if installed, else h5netcdf (needs h5py). Both write the
        same netCDF-4/HDF5 layout and can append to each other's files.
    append : bool
        False (default): create or overwrite ``path``. True: add the samples of ``ds`` after
        those in ``path`` (created if missing). The variables and their non-time coordinates
        must match; a first sample at the file's last time (as when a run is propagated
        segment by segment) is dropped; an earlier one is refused. ``integration_stats``
        numbers are summed, ``integration_complete`` is the AND of both, and ``history`` and
        ``date_modified`` record the append.
    complevel : int
        zlib level (0 = no compression, 1 default: fast, lossless; shuffle filter on).
    chunk_time : int
        Samples per chunk along ``time`` (HDF5 chunk shapes are ``(chunk_time, 4)`` etc.).

    Notes
    -----
    ``time`` is an unlimited dimension. Values are stored as float64 without fill values:
    reading gives them back bit for bit.
    """
    engine = check_engine(engine)
    path = os.fspath(path)
    if append and os.path.exists(path):
        _append(ds, path, engine)
        return
    enc_ds = encode(ds)
    enc_ds.to_netcdf(path, engine=engine, format="NETCDF4", unlimited_dims=["time"],
                     encoding=encoding(enc_ds, complevel, chunk_time))


def _append(ds: xr.Dataset, path, engine):
    piece = encode(ds)
    t_new = piece["time"].values
    if engine == "netcdf4":
        import netCDF4

        f = netCDF4.Dataset(path, "a")
        f.set_auto_maskandscale(False)
    else:
        import h5netcdf

        f = h5netcdf.File(path, "a")
    try:
        names_file = set(f.variables)
        names_piece = set(piece.variables)
        if names_file != names_piece:
            raise InputError(f"append: {path} has variables {sorted(names_file - names_piece)} the new "
                             f"samples lack, and they have {sorted(names_piece - names_file)} it lacks")
        tvar = f.variables["time"]
        units_file = tvar.attrs["units"] if engine == "h5netcdf" else tvar.getncattr("units")
        if units_file != piece["time"].attrs["units"]:
            raise InputError(f"append: time units differ ({units_file!r} in {path}, "
                             f"{piece['time'].attrs['units']!r} new); different epochs cannot be appended")
        n0 = f.dimensions["time"].size if engine == "h5netcdf" else len(f.dimensions["time"])
        start = 0
        if n0 > 0:
            last = float(np.asarray(tvar[n0 - 1]))
            if t_new.size and t_new[0] == last:
                start = 1
            if t_new.size > start and t_new[start] <= last:
                raise InputError(f"append: new samples start at time {t_new[start]!r}, not after the "
                                 f"file's last time {last!r}")
        n = t_new.size - start
        if n <= 0:
            return
        if engine == "h5netcdf":
            f.resize_dimension("time", n0 + n)
        for name, var in piece.variables.items():
            if "time" not in var.dims:
                continue
            ax = var.dims.index("time")
            idx_new = [slice(None)] * var.ndim
            idx_new[ax] = slice(start, None)
            idx_file = [slice(None)] * var.ndim
            idx_file[ax] = slice(n0, n0 + n)
            f.variables[name][tuple(idx_file)] = np.asarray(var.values)[tuple(idx_new)]
        # global attributes
        get = (lambda k: f.attrs.get(k)) if engine == "h5netcdf" else (
            lambda k: f.getncattr(k) if k in f.ncattrs() else None)

        def put(k, v):
            if engine == "h5netcdf":
                f.attrs[k] = v
            else:
                f.setncattr(k, v)

        stats = _sum_stats(get("integration_stats"), ds.attrs.get("integration_stats"))
        if stats is not None:
            put("integration_stats", stats)
        comp = get("integration_complete")
        if comp is not None:
            put("integration_complete", np.int8(int(np.asarray(comp)) and int(ds.attrs.get("integration_complete", 1))))
        now = utc_now()
        put("date_modified", now)
        hist = get("history") or ""
        put("history", f"{hist}\n{now} orbatt {orbatt_version()}: appended {n} samples".lstrip("\n"))
    finally:
        f.close()


def _sum_stats(a, b):
    """Sum the numbers of two JSON stats texts (keys of either kept)."""
    if a is None or b is None:
        return a
    try:
        da, db = json.loads(str(a)), json.loads(str(b))
    except ValueError:
        return a
    out = dict(da)
    for k, v in db.items():
        if k in out and isinstance(out[k], (int, float)) and isinstance(v, (int, float)) \
                and not isinstance(v, bool):
            out[k] = out[k] + v
        elif k not in out:
            out[k] = v
    return json.dumps(out, sort_keys=True)


class NetCDFWriter:
    """Write a long run to a netCDF file piece by piece, as it goes.

    Each :meth:`append` leaves a complete, readable file behind (the file is opened and closed
    per piece), so an interrupted run keeps what was written.

    Parameters
    ----------
    path : str or os.PathLike
        Created (or overwritten) by the first :meth:`append`.
    engine, complevel, chunk_time
        As in :func:`write_netcdf`.

    Examples
    --------
    >>> with NetCDFWriter("run.nc") as w:                     # doctest: +SKIP
    ...     for piece in segments:                            # Trajectory pieces
    ...         w.append(to_dataset(piece, scenario_text=text))
    """

    def __init__(self, path, *, engine=None, complevel=1, chunk_time=DEFAULT_CHUNK_TIME):
        self.path = os.fspath(path)
        self.engine = check_engine(engine)
        self.complevel = complevel
        self.chunk_time = chunk_time
        self._started = False
        self.samples = 0

    def append(self, ds: xr.Dataset):
        """Add the samples of ``ds`` (an orbatt Dataset) at the end of the file."""
        if not self._started:
            write_netcdf(ds, self.path, engine=self.engine, complevel=self.complevel,
                         chunk_time=self.chunk_time)
            self._started = True
        else:
            write_netcdf(ds, self.path, engine=self.engine, append=True)
        self.samples = _time_length(self.path, self.engine)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def _time_length(path, engine):
    if engine == "netcdf4":
        import netCDF4

        with netCDF4.Dataset(path) as f:
            return len(f.dimensions["time"])
    import h5netcdf

    with h5netcdf.File(path, "r") as f:
        return f.dimensions["time"].size


def open_dataset(path, *, engine=None, load=False, **kwargs) -> xr.Dataset:
    """Open an orbatt NetCDF file, giving back the Dataset :func:`to_dataset` built.

    Parameters
    ----------
    path : str or os.PathLike
    engine : {"netcdf4", "h5netcdf"}, optional
        Default as in :func:`write_netcdf`.
    load : bool
        Read all values into memory now (default: lazily, as :func:`xarray.open_dataset`).
    **kwargs
        Passed to :func:`xarray.open_dataset` (e.g. ``chunks`` for dask).

    Returns
    -------
    xarray.Dataset
        ``time`` as float seconds since the epoch (``units = "s"``; the CF ``"seconds since"``
        of the file is undone), label coordinates as strings, every value bit for bit as
        written.
    """
    engine = check_engine(engine)
    kwargs.setdefault("decode_times", False)
    kwargs.setdefault("decode_timedelta", False)
    ds = xr.open_dataset(os.fspath(path), engine=engine, **kwargs)
    ds = decode(ds)
    return ds.load() if load else ds


# --------------------------------------------------------------------------------------------
# accessor
# --------------------------------------------------------------------------------------------
@xr.register_dataset_accessor("orbatt")
class OrbattAccessor:
    """``ds.orbatt``: units, time, I/O and plots for an orbatt Dataset (stateless)."""

    def __init__(self, ds: xr.Dataset):
        self._ds = ds

    # units ------------------------------------------------------------------------------
    def unit(self, name):
        """astropy unit of variable ``name`` (from its ``units`` attribute)."""
        if name not in self._ds.variables:
            raise InputError(f"name: {name!r} is not a variable of this dataset; have "
                             f"{sorted(self._ds.variables)}")
        units = self._ds[name].attrs.get("units")
        if units is None:
            raise InputError(f"{name}: has no 'units' attribute")
        return parse_unit(units)

    def quantity(self, name):
        """Values of variable ``name`` as an :class:`astropy.units.Quantity`.

        Parameters
        ----------
        name : str
            A data variable or numeric coordinate (``"omega"``, ``"time"``, ...).
        """
        unit = self.unit(name)
        return np.asarray(self._ds[name].values) * unit

    def to(self, name, unit) -> xr.DataArray:
        """Variable ``name`` converted to ``unit``, as a DataArray with updated ``units``.

        Parameters
        ----------
        name : str
        unit : str or astropy Unit
            E.g. ``"degree s-1"``, ``"deg/s"`` or ``u.deg / u.s`` for ``omega``.

        Raises
        ------
        InputError
            The units are not convertible (e.g. a dimensionless problem's ``"1"`` to
            ``"deg/s"``).
        """
        target = parse_unit(unit) if isinstance(unit, str) else u.Unit(unit)
        src = self.unit(name)
        try:
            factor = src.to(target)
        except u.UnitConversionError:
            raise InputError(f"{name}: cannot convert {self._ds[name].attrs['units']!r} to "
                             f"{unit_string(target)!r}") from None
        da = self._ds[name]
        out = da.copy(data=np.asarray(da.values) * factor)
        out.attrs["units"] = unit_string(target)
        return out

    def convert(self, **units) -> xr.Dataset:
        """A copy of the Dataset with the named variables converted, e.g.
        ``ds.orbatt.convert(omega="degree s-1", euler_313="degree")``."""
        ds = self._ds.copy()
        for name, unit in units.items():
            ds[name] = self.to(name, unit)
        return ds

    # metadata ---------------------------------------------------------------------------
    @property
    def dimensionless(self) -> bool:
        """True for a dimensionless problem (``time`` in units ``"1"``)."""
        return self._ds["time"].attrs.get("units") == "1"

    @property
    def epoch(self):
        """The epoch (``time = 0``) as an :class:`astropy.time.Time` (UTC), or None."""
        s = self._ds.attrs.get("epoch")
        if not s:
            return None
        from astropy.time import Time

        s = str(s)
        return Time(s[:-1] if s.endswith("Z") else s, scale="utc")

    def times(self):
        """Absolute times (:class:`astropy.time.Time`) if there is an epoch, else the ``time``
        Quantity."""
        ep = self.epoch
        tq = self.quantity("time")
        return tq if ep is None else ep + tq

    @property
    def scenario(self):
        """The scenario's TOML text, or None."""
        return self._ds.attrs.get("scenario")

    @property
    def settings(self) -> dict:
        """The integration method's settings (parsed from ``method_settings``)."""
        return json.loads(self._ds.attrs.get("method_settings", "{}"))

    @property
    def stats(self) -> dict:
        """Integration statistics (parsed from ``integration_stats``)."""
        return json.loads(self._ds.attrs.get("integration_stats", "{}"))

    # I/O --------------------------------------------------------------------------------
    def to_netcdf(self, path, **kwargs):
        """Write to NetCDF (:func:`write_netcdf`; ``append=True`` adds samples)."""
        write_netcdf(self._ds, path, **kwargs)

    def to_aem(self, path, **kwargs):
        """Write ``q`` as a CCSDS AEM (:func:`orbatt.aem.write_aem`)."""
        from .aem import write_aem

        return write_aem(self._ds, path, **kwargs)

    # plots ------------------------------------------------------------------------------
    def _member(self, case):
        ds = self._ds
        if "case" in ds.dims:
            ds = ds.isel(case=0) if case is None else ds.sel(case=case)
        return ds

    def _time_label(self):
        units = self._ds["time"].attrs.get("units", "")
        return "t" if units == "1" else f"t [{units}]"

    def plot_state(self, case=None, fig=None):
        """The paper's figure layout: the four components of ``q`` (left) and of ``Q``
        (right) against time. Returns the matplotlib Figure."""
        import matplotlib.pyplot as plt

        ds = self._member(case)
        if fig is None:
            fig = plt.figure(figsize=(11, 4))
        axl, axr = fig.subplots(1, 2, sharex=True)
        t = ds["time"].values
        for k in range(4):
            axl.plot(t, ds["q"].values[:, k], label=f"q{k}")
            axr.plot(t, ds["Q"].values[:, k], label=f"Q{k}")
        qu = ds["Q"].attrs.get("units", "")
        axl.set_title("q (B relative to S)")
        axr.set_title("Q" + ("" if qu == "1" else f" [{qu}]"))
        for ax in (axl, axr):
            ax.set_xlabel(self._time_label())
            ax.legend(loc="best", fontsize="small")
            ax.grid(alpha=0.3)
        fig.tight_layout()
        return fig

    def plot_attitude(self, case=None, unit="degree", fig=None):
        """Euler angles against time: the 3-1-3 angles of ``q`` and, with an orbit, roll,
        pitch and yaw relative to the orbital frame. Returns the Figure."""
        import matplotlib.pyplot as plt

        ds = self._member(case)
        acc = ds.orbatt
        panels = [("euler_313", EULER_313_LABELS, "3-1-3 angles (B relative to S)")]
        if "euler_321" in ds:
            panels.append(("euler_321", EULER_321_LABELS, "roll, pitch, yaw (B relative to O)"))
        if fig is None:
            fig = plt.figure(figsize=(6 * len(panels), 4))
        axes = np.atleast_1d(fig.subplots(1, len(panels), sharex=True))
        t = ds["time"].values
        for ax, (name, labels, title) in zip(axes, panels):
            vals = acc.to(name, unit).values
            for k, lab in enumerate(labels):
                ax.plot(t, vals[:, k], label=lab)
            ax.set_title(title)
            ax.set_xlabel(self._time_label())
            ax.set_ylabel(f"[{unit_string(parse_unit(unit))}]")
            ax.legend(loc="best", fontsize="small")
            ax.grid(alpha=0.3)
        fig.tight_layout()
        return fig

    def plot_drift(self, case=None, fig=None):
        """Energy and constraint drift on log axes: ``|H - H0| / |H0|`` (or ``|H - H0|`` when
        ``H0 = 0``), ``| |q| - 1 |`` and the drift of ``q.Q`` from its initial value (the paper's
        printed data start at -9.7e-8; exact zeros are not drawn). For a time-dependent
        potential ``H`` is not an invariant. Returns the Figure."""
        import matplotlib.pyplot as plt

        ds = self._member(case)
        if fig is None:
            fig = plt.figure(figsize=(13, 3.6))
        axes = fig.subplots(1, 3, sharex=True)
        t = ds["time"].values
        H = ds["energy"].values
        dH = np.abs(H - H[0])
        rel = abs(H[0]) > 0
        series = [(dH / abs(H[0]) if rel else dH, "|H - H0| / |H0|" if rel else "|H - H0|"),
                  (np.abs(ds["q_norm_error"].values), "| |q| - 1 |"),
                  (np.abs(ds["qQ"].values - ds["qQ"].values[0]), "|q.Q - (q.Q)0|")]
        for ax, (y, title) in zip(axes, series):
            ax.semilogy(t, np.where(y > 0, y, np.nan))  # exact zeros left out of the log axis
            ax.set_title(title)
            ax.set_xlabel(self._time_label())
            ax.grid(alpha=0.3, which="both")
        fig.tight_layout()
        return fig

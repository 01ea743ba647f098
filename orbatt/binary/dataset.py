"""The result Dataset of a binary run (:func:`binary_content`): the relative orbit, both
attitudes, the invariants and the osculating elements, with CF units and ``long_name`` on
every variable: computed in the kernels' kg km s rad, written as every result is
(:mod:`orbatt.dataset.build`): momenta in kg m^2 s^-1, energies in J, orbits in km.

Variables (``time``: datetimes on the nominal epoch 2000-01-01T00:00:00Z, ``elapsed`` in s
since the start; ``axis`` 1..3 of the frame named by ``frame``)::

    position, velocity          relative orbit primary -> secondary, inertial (km, km s^-1)
    separation                  |position| (km)
    q, Q, omega                 the secondary's attitude (B -> S), momentum, body rate
    q_primary, Q_primary,       the rigid primary's (absent for a point-mass primary)
    omega_primary
    energy                      total H (J), conserved with the coupled potential
    angular_momentum_total      r x p + both spins, inertial (kg m^2 s^-1), conserved
    orbit_a, orbit_e, orbit_i,  osculating elements of the relative orbit about G (M1 + M2)
    orbit_period
    mean_period                 the mean period of the mutual orbit (s): the unwrapped osculating
                                mean longitude's advance over a window of one mean period
                                (attributes ``method``, ``window_s``; NaN within half a window
                                of either end)
    q_norm_error, qQ            the secondary's constraint residuals |q| - 1 and q.Q
    euler_313                   the secondary's 3-1-3 Euler angles (for ``orbatt plot``)
"""
from __future__ import annotations

import json

import numpy as np

from .. import canonical as cn
from ..core import mutual as km
from .. import quaternion as qt
from ..dataset.build import (AXIS_INDEX, AXIS_LABELS, EULER_313_LABELS, QUAT_INDEX, QUAT_LABELS, QUATERNION_ORDER,
                             global_attrs, si_form)
from ..dataset.content import Content, Var
from ..dataset.timeaxis import cf_time_attrs, elapsed_attrs
from ..units import INTERNAL_UNITS as UN
from .system import MEAN_PERIOD_METHOD, mean_longitude, mean_period, osculating_elements

__all__ = ["binary_content", "binary_dataset", "describe", "potential_attr"]

_MAPS = "x_S = q x_B q~ (maps body to space components)"


def _var(dims, values, units, long_name, **extra):
    attrs = {"units": units, "long_name": long_name}
    attrs.update(extra)
    return Var(dims, values, attrs)


def describe(system):
    """The bodies and the model, as a dict (the global attribute ``binary``)."""
    return {"kind": "binary (full two-body problem to second order)", "potential": system.potential,
            "mass_kg": system.mass, "inertia_kg_km2": system.inertia.tolist(),
            "primary_mass_kg": system.primary_mass,
            "primary_inertia_kg_km2": None if system.primary_inertia is None else system.primary_inertia.tolist(),
            "G_km3_kg-1_s-2": system.G}


def potential_attr(system):
    """The ``potential`` global attribute of a binary's results (a run's, a sweep's)."""
    return {"kind": f"mutual potential to second order ({system.potential})"}


def binary_content(traj, *, scenario_text=None, title=None) -> Content:
    """The variables of a binary run's Dataset (module docstring) as a :class:`Content`.

    Parameters
    ----------
    traj : BinaryTrajectory
        What :func:`orbatt.binary.propagate_binary` returned.
    scenario_text : str, optional
        The scenario's TOML text (global attribute ``scenario``).
    title : str, optional
    """
    s = traj.system
    t = np.ascontiguousarray(traj.t)
    Y = np.ascontiguousarray(traj.y)
    c = traj.c
    mu = s.reduced_mass
    pos = Y[:, 0:3].copy()
    vel = Y[:, 3:6] / mu
    q = Y[:, 6:10].copy()
    Q = Y[:, 10:14].copy()
    E, L, om2, om1 = km.evaluate(Y, c)
    a, e, inc, period = osculating_elements(pos, vel, s.gm)
    mean_p, window = mean_period(t, mean_longitude(pos, vel, s.gm))
    norm_err, qQ = cn.constraint_residuals(q, Q)
    td, vd, qd = ("time",), ("time", "axis"), ("time", "quat")
    coords = {
        # the one time axis of every result (orbatt.dataset.build): on the nominal epoch
        "time": Var(td, t, cf_time_attrs(None, False)),
        "elapsed": Var(td, t, elapsed_attrs(None, False)),
        "quat": _var(("quat",), QUAT_INDEX, "1", "quaternion component index (0 = scalar part)",
                     quaternion_order=QUATERNION_ORDER),
        "quat_label": Var(("quat",), np.array(QUAT_LABELS), {"long_name": "quaternion component name"}),
        "axis": _var(("axis",), AXIS_INDEX, "1", "vector component index (axis 1, 2, 3 of the named frame)"),
        "axis_label": Var(("axis",), np.array(AXIS_LABELS), {"long_name": "vector component name"}),
        "euler_313_angle": _var(("euler_313_angle",), np.arange(3), "1", "position in (phi, theta, psi)"),
        "euler_313_label": Var(("euler_313_angle",), np.array(EULER_313_LABELS), {"long_name": "3-1-3 Euler angle name"}),
    }
    data = {
        "position": _var(vd, pos, UN["length"], "position of the secondary relative to the primary", frame="S"),
        "velocity": _var(vd, vel, UN["speed"], "velocity of the secondary relative to the primary", frame="S"),
        "separation": _var(td, np.linalg.norm(pos, axis=1), UN["length"], "distance between the centres of mass"),
        "q": _var(qd, q, "1", "attitude quaternion of the secondary", quaternion_order=QUATERNION_ORDER,
                  frames="B relative to S", convention=_MAPS),
        "Q": _var(qd, Q, UN["momentum"], "conjugate momentum of q (Q = 2 q g)", quaternion_order=QUATERNION_ORDER),
        "omega": _var(vd, om2, UN["rate"], "angular velocity of the secondary (body components)", frame="B"),
        "euler_313": _var(td + ("euler_313_angle",), np.stack(qt.to_euler313(q), axis=-1), "rad",
                          "3-1-3 Euler angles (phi, theta, psi) of q (paper eq. 12)", frames="B relative to S"),
    }
    if s.rigid_primary:
        data.update({
            "q_primary": _var(qd, Y[:, 14:18].copy(), "1", "attitude quaternion of the primary",
                              quaternion_order=QUATERNION_ORDER, frames="B1 relative to S", convention=_MAPS),
            "Q_primary": _var(qd, Y[:, 18:22].copy(), UN["momentum"], "conjugate momentum of q_primary",
                              quaternion_order=QUATERNION_ORDER),
            "omega_primary": _var(vd, om1, UN["rate"], "angular velocity of the primary (body components)", frame="B1"),
        })
    conserved = "conserved" if s.potential == "coupled" else "not conserved: the orbit does not feel the torque"
    data.update({
        "energy": _var(td, E, UN["energy"], f"total energy H = |p|^2/(2 mu) + T + T1 + U ({conserved})"),
        "angular_momentum_total": _var(vd, L, UN["momentum"],
                                       f"total angular momentum about the barycentre, orbit and spins ({conserved})",
                                       frame="S"),
        "orbit_a": _var(td, a, UN["length"], "osculating semi-major axis of the relative orbit about G (M1 + M2)"),
        "orbit_e": _var(td, e, "1", "osculating eccentricity of the relative orbit"),
        "orbit_i": _var(td, inc, "rad", "osculating inclination of the relative orbit to the inertial s1-s2 plane"),
        "orbit_period": _var(td, period, "s", "osculating Keplerian period 2 pi sqrt(a^3 / (G (M1 + M2))) (point masses: "
                              "the mean period differs by the bodies' oblateness)"),
        "mean_period": _var(td, mean_p, "s", "mean period of the mutual orbit, from the unwrapped mean longitude over a "
                            "window of one mean period (the period an observer measures, e.g. DART's -33 min; the "
                            "osculating orbit_period differs)", method=MEAN_PERIOD_METHOD, window_s=window),
        "q_norm_error": _var(td, norm_err, "1", "constraint residual |q| - 1 (secondary)"),
        "qQ": _var(td, qQ, UN["momentum"], "constraint residual q.Q (secondary)"),
    })
    attrs = global_attrs(method=traj.method, settings=traj.settings, stats=traj.stats,
                         potential=potential_attr(s),
                         dimensionless=False, complete=traj.complete, scenario_text=scenario_text,
                         title=title or "orbatt: binary asteroid (coupled orbit and attitudes)",
                         binary=json.dumps(describe(s)))
    return Content(si_form(data), coords, attrs)  # computed in kernel units, written in SI


def binary_dataset(traj, **kw):
    """:func:`binary_content` as an :class:`xarray.Dataset`."""
    return binary_content(traj, **kw).to_dataset()

"""One chunk of a binary-asteroid sweep (``[orbit] provider = "coupled"``; ``docs/sweeps.md``:
Binary asteroids): each case's scenario written out (:func:`~orbatt.sweep.case_groups.case_text`'s
text), validated, built and run as ``orbatt run`` runs it, and summarized into the per-case
outputs of :data:`~orbatt.scenario.binary_sweep_schema.BINARY_OUTPUTS`.

A binary case is one run of its own scenario (the coupled problem has no ensemble kernel): a
case's outputs are its single run's arrays, bit for bit, on any chunking. The summaries are
reductions over one case's output times only (never across cases).
"""
from __future__ import annotations

import json
import tomllib
import warnings

import numpy as np

from ..dataset import AXIS_INDEX, AXIS_LABELS, QUAT_INDEX, QUAT_LABELS, cf_variable
from ..errors import IntegrationError
from ..scenario import Scenario, parse
from ..scenario.paths import toml_text
from .case_coords import parameter_coordinates
from .case_groups import case_data
from .stats import add_stats

__all__ = ["compute_binary_chunk", "libration_angle", "relative_drift"]

#: per-case variables: (dims after ``case``, the run's variable, the summary, long_name)
_FINAL = {
    "position_final": (("axis",), "position", "relative position primary -> secondary at the last output (inertial)"),
    "velocity_final": (("axis",), "velocity", "relative velocity at the last output (inertial)"),
    "q_final": (("quat",), "q", "attitude quaternion of the secondary at the last output (B relative to S)"),
    "omega_final": (("axis",), "omega", "angular velocity of the secondary at the last output (body components)"),
    "q_primary_final": (("quat",), "q_primary", "attitude quaternion of the primary at the last output"),
    "omega_primary_final": (("axis",), "omega_primary", "angular velocity of the primary at the last output "
                                                        "(body components)"),
    "orbit_a_final": ((), "orbit_a", "osculating semi-major axis of the relative orbit at the last output"),
    "orbit_e_final": ((), "orbit_e", "osculating eccentricity of the relative orbit at the last output"),
    "orbit_i_final": ((), "orbit_i", "osculating inclination of the relative orbit at the last output"),
    "orbit_period_final": ((), "orbit_period", "osculating Keplerian period of the relative orbit at the last output"),
}


def libration_angle(q, position):
    """The angle (rad, in [0, pi/2]) between the secondary's body axis 1 and the line of centres.

    Parameters
    ----------
    q : ndarray (n, 4)
        The secondary's attitude, B -> inertial (scalar first).
    position : ndarray (n, 3)
        The relative position primary -> secondary (inertial; any length unit).

    Returns
    -------
    ndarray (n,)
        ``arccos |b1 . r / |r||`` with ``b1 = q e1 q~`` (the axis's sign does not count: a
        synchronous secondary with its long axis on the line of centres has 0).
    """
    q0, q1, q2, q3 = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    b1 = (q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2.0 * (q1 * q2 + q0 * q3), 2.0 * (q1 * q3 - q0 * q2))
    x, y, z = position[:, 0], position[:, 1], position[:, 2]
    r = np.sqrt(x * x + y * y + z * z)
    nb = np.sqrt(b1[0] * b1[0] + b1[1] * b1[1] + b1[2] * b1[2])
    c = np.abs(b1[0] * x + b1[1] * y + b1[2] * z) / (r * nb)
    return np.arccos(np.minimum(c, 1.0))


def relative_drift(x, start):
    """``max_k |x_k - x_start| / |x_start|`` over the outputs ``k >= start`` of one case
    (``x``: (n,) or (n, 3), a vector's norm taken per output)."""
    x = np.asarray(x, dtype=np.float64)[start:]
    d = x - x[0]
    if x.ndim == 1:
        return float(np.max(np.abs(d)) / abs(x[0]))
    dn = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
    x0 = x[0]
    return float(np.max(dn) / np.sqrt(x0[0] * x0[0] + x0[1] * x0[1] + x0[2] * x0[2]))


def _case_outputs(sc, ds, outs):
    """The per-case outputs of one binary run's Dataset ``ds`` (``{name: (value, units)}``)."""
    out = {}
    last = {"final_state": ("position_final", "velocity_final", "q_final", "omega_final", "q_primary_final",
                            "omega_primary_final"),
            "final_orbit": ("orbit_a_final", "orbit_e_final", "orbit_i_final", "orbit_period_final")}
    for o, names in last.items():
        if o in outs:
            for name in names:
                src = _FINAL[name][1]
                if src in ds:
                    out[name] = (np.asarray(ds[src].values[-1]), ds[src].attrs.get("units", "1"))
    if "final_orbit" in outs:
        out["min_separation"] = (float(np.min(ds["separation"].values)), ds["separation"].attrs["units"])
    if "conservation" in outs:
        t = np.asarray(ds["elapsed"].values)
        t_kick = max((k.time for k in sc.impulses), default=None)
        start = 0 if t_kick is None else int(np.searchsorted(t, t_kick, side="right"))
        if start < t.size:
            out["max_energy_error"] = (relative_drift(ds["energy"].values, start), "1")
            out["max_angular_momentum_error"] = (relative_drift(ds["angular_momentum_total"].values, start), "1")
    if "max_libration" in outs:
        ang = libration_angle(np.asarray(ds["q"].values), np.asarray(ds["position"].values))
        out["max_libration_angle"] = (float(np.max(ang)), "rad")
    if "mean_period" in outs:
        p = np.asarray(ds["mean_period"].values)
        ok = np.flatnonzero(np.isfinite(p))
        first, last = (float(p[ok[0]]), float(p[ok[-1]])) if ok.size else (np.nan, np.nan)
        out["mean_period_initial"] = (first, ds["mean_period"].attrs["units"])
        out["mean_period_final"] = (last, ds["mean_period"].attrs["units"])
    return out


def _variables(sc, outs):
    """``{name: (dims after case, long_name)}`` of the chunk's output variables."""
    v = {}
    rigid = sc.system.rigid_primary
    if "final_state" in outs:
        for name in ("position_final", "velocity_final", "q_final", "omega_final") + (
                ("q_primary_final", "omega_primary_final") if rigid else ()):
            v[name] = _FINAL[name][0], _FINAL[name][2]
    if "final_orbit" in outs:
        for name in ("orbit_a_final", "orbit_e_final", "orbit_i_final", "orbit_period_final"):
            v[name] = _FINAL[name][0], _FINAL[name][2]
        v["min_separation"] = (), "smallest distance between the centres of mass over the output times"
    if "conservation" in outs:
        after = " after the last impulse" if sc.impulses else ""
        v["max_energy_error"] = (), (f"largest relative change of the total energy H over the output times{after}, "
                                     "max |H - H0| / |H0|")
        v["max_angular_momentum_error"] = (), (f"largest relative change of the total angular momentum over the "
                                               f"output times{after}, max |L - L0| / |L0|")
    if "max_libration" in outs:
        v["max_libration_angle"] = (), ("largest angle between the secondary's body axis 1 and the line of centres "
                                        "over the output times")
    if "mean_period" in outs:
        for name, which in (("mean_period_initial", "first (its window starting at the first output)"),
                            ("mean_period_final", "last (its window ending at the last output)")):
            v[name] = (), (f"mean period of the mutual orbit, the {which} value of the run's mean_period (unwrapped "
                           "mean longitude over one mean period; NaN for a run shorter than that); final - initial is "
                           "the change an impulse between the windows makes")
    return v


def compute_binary_chunk(sc, spec, job, units):
    """Compute the binary cases of a task's payload ``job`` (:meth:`orbatt.sweep.Sweep.job`).

    Parameters
    ----------
    sc : BinaryScenario
        The nominal scenario (its text, with ``[sweep]``).
    spec : SweepSpec
    job : dict
        ``start``, ``stop``, ``values`` (the chunk's parameter values).
    units : dict
        CF unit string of every parameter.

    Returns
    -------
    xarray.Dataset
        The cases' outputs along ``case`` (``docs/sweeps.md``: Binary asteroids);
        ``integration_stats`` (JSON) summed over the cases.
    """
    import xarray as xr

    start, stop = job["start"], job["stop"]
    n = stop - start
    values = job["values"]
    outs = set(spec.outputs)
    base = tomllib.loads(sc.text)
    source = str(sc.path) if sc.path is not None else sc.name
    shapes = {"axis": 3, "quat": 4}
    wanted = _variables(sc, outs)
    res = {name: np.full((n,) + tuple(shapes[d] for d in dims), np.nan) for name, (dims, _) in wanted.items()}
    res_units = {}
    failed = np.zeros(n, dtype=bool)
    stats = {}
    for j in range(n):
        text = toml_text(case_data(base, spec, values, j))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the nominal scenario warned
            case = Scenario(parse(text, source), path=sc.path)
        try:
            ds = case.run()
        except IntegrationError:
            failed[j] = True
            continue
        if not int(ds.attrs.get("integration_complete", 1)):  # the run kept what it had at a Ctrl-C: the sweep stops
            raise KeyboardInterrupt
        add_stats(stats, ds.attrs.get("integration_stats"))
        for name, (val, unit) in _case_outputs(case, ds, outs).items():
            if name in res:
                res[name][j] = val
                res_units[name] = unit
    coords = {"case": cf_variable(("case",), start + np.arange(n), "1", "sweep case (index into the sampled "
                                                                        "parameters)"),
              "axis": cf_variable(("axis",), AXIS_INDEX, "1", "vector component index (axis 1, 2, 3 of the named "
                                                              "frame)"),
              "axis_label": xr.Variable(("axis",), np.array(AXIS_LABELS), {"long_name": "vector component name"}),
              "quat": cf_variable(("quat",), QUAT_INDEX, "1", "quaternion component index (0 = scalar part)",
                                  quaternion_order="w x y z"),
              "quat_label": xr.Variable(("quat",), np.array(QUAT_LABELS), {"long_name": "quaternion component name"})}
    coords.update(parameter_coordinates(spec, values, units))
    data = {name: cf_variable(("case",) + dims, res[name], res_units.get(name, _default_unit(name)), long_name)
            for name, (dims, long_name) in wanted.items()}
    data["integration_failed"] = cf_variable(("case",), failed.astype(np.int8), "1",
                                             "1 where the integration of the case stopped (its values are NaN)",
                                             flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="ok failed")
    ds = xr.Dataset(data, coords=coords)
    ds.attrs["integration_stats"] = json.dumps(stats, sort_keys=True)
    return ds


def _default_unit(name):
    """The unit of an output no case of the chunk computed (all failed): as a run writes it."""
    return {"position_final": "km", "velocity_final": "km s^-1", "omega_final": "rad s^-1",
            "omega_primary_final": "rad s^-1", "orbit_a_final": "km", "orbit_i_final": "rad", "orbit_period_final": "s",
            "min_separation": "km", "max_libration_angle": "rad", "mean_period_initial": "s",
            "mean_period_final": "s"}.get(name, "1")

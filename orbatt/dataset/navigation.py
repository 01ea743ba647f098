"""The variables of the flight software's sensors and filter (issue 33; :mod:`orbatt.sensors`):
the estimate, its error and covariance, the gyro's bias and measurements, the star tracker's
validity. Read from the navigation row's discrete state (:data:`orbatt.core.estimator.STATE`)
along the outputs; nothing is integrated here.

The estimate at an output time ``t`` is the filter's as the flight software holds it: the
estimate of its last tick ``t_k`` propagated to ``t`` with the rate it holds (``w_meas - b_hat``,
:func:`orbatt.core.estimator.propagate_estimate`), the prediction it would compute at ``t``.
``knowledge_error`` is the rotation vector of ``q_hat~ q`` (body axes: the rotation that turns
the estimated body axes onto the true ones), ``knowledge_sigma`` the square root of the
covariance's attitude diagonal held since ``t_k``.

A body given by a full inertia tensor runs its filter in the principal frame ``P``
(:func:`orbatt.frame_boundary.principal_navigation`): ``navigation.axes`` is then ``R``, and
``knowledge_sigma`` is the square root of the diagonal of ``R P_att R^T`` (body axes; the
other body-axes variables are turned by ``R`` at the boundary,
:func:`orbatt.frame_boundary.body_variables`).
"""
from __future__ import annotations

import numpy as np

from .. import quaternion as qt
from ..core import control as kc
from ..core import estimator as ke
from ..core import model as km
from .content import Var

__all__ = ["navigation_column", "navigation_variables", "knowledge_error"]


def navigation_column(model, nwheels):
    """``(column, p0)``: where the navigation row's state starts in a trajectory's ``command``
    and its parameters' offset, or None without sensors."""
    terms, params, _ = model
    for j in range(1, terms.shape[0]):
        if int(terms[j, km.KIND]) == km.NAVIGATION:
            p0 = int(terms[j, km.P0])
            return int(params[p0 + kc.CTL_Z0]) - 8 - nwheels, p0
    return None


def _slot(z, col, name):
    off = col + getattr(ke.STATE, name)
    return z[..., off:off + ke.STATE._sizes[name]]


def estimate_at(t, z, col):
    """The filter's estimate ``(..., N, 4)`` (estimated body -> S) at the times ``t (N,)`` from
    the states ``z (..., N, nz)`` of the navigation row at column ``col`` (module docstring)."""
    qh = _slot(z, col, "q_hat")
    w = _slot(z, col, "w_meas") - _slot(z, col, "b_hat")
    dt = t - _slot(z, col, "t_last")[..., 0]
    return qt.normalize(qt.mul(qh, qt.from_rotvec(w * dt[..., None])))


def knowledge_error(q, q_hat):
    """The rotation vector (rad, body axes) of ``q_hat~ q``: the rotation that turns the
    estimated body axes onto the true ones (``q = q_hat (x) dq``), ``(..., 3)``."""
    return qt.to_rotvec(qt.mul(qt.conj(q_hat), q))


def _var(dims, data, units, long_name, **extra):
    attrs = {"units": units, "long_name": long_name}
    attrs.update(extra)
    return Var(tuple(dims), np.asarray(data), attrs)


def navigation_variables(model, q, z, t, tdims, nwheels, navigation):
    """The Dataset variables of the sensors and the filter (module docstring), or ``{}``.

    Parameters
    ----------
    model : KernelSpec
        The run's model (its navigation row).
    q : ndarray (..., N, 4)
        The true attitude (body -> S) at the outputs.
    z : ndarray (..., N, nz)
        The controllers' states (a trajectory's ``command``).
    t : ndarray (N,)
        Output times (s).
    tdims : tuple
        ``("time",)`` or ``("case", "time")``.
    nwheels : int
        The number of reaction wheels (the state's offset).
    navigation : Navigation
        The sensors and filter (what exists).
    """
    found = navigation_column(model, nwheels)
    if found is None:
        return {}
    col, _ = found
    vv, qv = tdims + ("axis",), tdims + ("quat",)
    data = {}
    if navigation.gyro is not None:
        data["gyro_bias"] = _var(vv, _slot(z, col, "beta"), "rad s^-1", "true bias of the gyro at its last sample",
                                 frame="B", comment="Farrenkopf's model: w_meas = omega + bias + noise")
        data["gyro_measurement"] = _var(vv, _slot(z, col, "w_meas"), "rad s^-1",
                                        "the gyro's last measurement of the body rate", frame="B")
    if navigation.star_tracker is not None:
        valid = _slot(z, col, "st_ok")[..., 0]
        data["star_tracker_valid"] = _var(tdims, valid.astype(np.int8), "1",
                                          "whether the star tracker measured at its last due sample",
                                          flag_values=np.array([0, 1], dtype=np.int8),
                                          flag_meanings="outage measured",
                                          comment="0 from a due sample where the Sun or the Earth's limb was within its "
                                                  "exclusion angle until the next that measures (between its samples it "
                                                  "keeps the last one's value)")
    if navigation.magnetometer is not None or navigation.sun_sensor is not None:
        data["vector_updates"] = _var(tdims, _slot(z, col, "vector")[..., 0].astype(np.int8), "1",
                                      "filter updates by the magnetometer and the Sun sensor at the last tick",
                                      comment="they update the filter while the star tracker is out (or without one)")
    if navigation.estimator is not None:
        qh = estimate_at(t, z, col)
        P = _slot(z, col, "P")
        data["q_estimate"] = _var(qv, qh, "1", "the attitude filter's estimate (estimated body relative to S)",
                                  frame="B", comment="the last tick's estimate propagated to the output time with "
                                                     "the rate the flight software holds (w_meas - b_hat)")
        data["knowledge_error"] = _var(vv, knowledge_error(q, qh), "rad",
                                       "rotation vector from the estimate to the truth (q = q_estimate dq)",
                                       frame="B")
        axes = getattr(navigation, "axes", None)  # a full inertia tensor's principal axes: P in B is R P R^T
        diag = np.stack([P[..., 0], P[..., 7], P[..., 14]], axis=-1) if axes is None else np.einsum(
            "ij,...jk,ik->...i", axes, P.reshape(P.shape[:-1] + (6, 6))[..., :3, :3], axes)
        data["knowledge_sigma"] = _var(vv, np.sqrt(np.maximum(diag, 0.0)), "rad",
                                       "filter's 1-sigma attitude uncertainty per axis", frame="B",
                                       comment="square root of the covariance's attitude diagonal, as held since "
                                               "the last tick")
        data["bias_estimate"] = _var(vv, _slot(z, col, "b_hat"), "rad s^-1", "the filter's estimate of the gyro bias",
                                     frame="B")
    key = f"seed {navigation.seed}, case {navigation.case}"  # the noise's key (orbatt.core.noise)
    for v in data.values():
        v.attrs["noise_key"] = key
    return data

"""``[body] inertia``: principal moments, or the inertia tensor in the body frame as CAD gives it.

Three forms (quantities as everywhere, :func:`orbatt.scenario.fields.parse_quantity`)::

    inertia = ["0.10 kg m2", "0.12 kg m2", "0.05 kg m2"]            # principal moments [I1, I2, I3]
    inertia = [["0.10 kg m2", "0.002 kg m2", "-0.001 kg m2"],        # 3x3 tensor, body (mechanical)
               ["0.002 kg m2", "0.12 kg m2", "0.0005 kg m2"],        # frame, about the centre of mass
               ["-0.001 kg m2", "0.0005 kg m2", "0.05 kg m2"]]
    inertia = ["0.10 kg m2", "0.12 kg m2", "0.05 kg m2",             # six values [Ixx, Iyy, Izz,
               "0.002 kg m2", "-0.001 kg m2", "0.0005 kg m2"]        #             Ixy, Ixz, Iyz]

The off-diagonal entries are the matrix's: ``I_xy = -∫ x y dm`` (products of inertia with their
minus sign). A tensor that is not diagonal makes orbatt integrate in its principal frame while
every body-fixed key (facets, wheels, dipole, constant torque, control axes and per-axis limits,
``[sensors]``, ``[initial]``) and
every body-axes output stays in the body frame (:mod:`orbatt.body_frame`,
:mod:`orbatt.frame_boundary`), in a sweep's cases as well; a sweep may not vary the inertia of a
tensor (:func:`check_sweep`).
"""
from __future__ import annotations

import numpy as np

from .. import units as U
from ..body import RigidBody
from ..body_frame import SIX_VALUES, inertia_tensor, is_diagonal
from ..errors import InputError
from .fields import parse_quantity

__all__ = ["parse_inertia", "check_sweep", "FORMS"]

#: what ``[body] inertia`` may be (the messages' list of forms)
FORMS = ("[I1, I2, I3] (principal moments), a 3x3 tensor [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] "
         "or six values [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (off-diagonal entries I_xy = -integral of x y dm)")
_WHERE = "[body] inertia"


def _plain(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _entries(ctx, raw):
    """``(form, [(row, column, value)])`` of a tensor's TOML value: ``"matrix"`` or ``"six"``."""
    if len(raw) == 3 and all(isinstance(row, list) for row in raw):
        if not all(len(row) == 3 for row in raw):
            raise ctx.error(_WHERE, f"a tensor has 3 rows of 3 values, got {raw!r}; give {FORMS}")
        return "matrix", [(i, j, raw[i][j]) for i in range(3) for j in range(3)]
    if len(raw) == 6 and not any(isinstance(v, list) for v in raw):
        return "six", [(i, j, raw[k]) for k, (i, j) in enumerate(SIX_VALUES)]
    raise ctx.error(_WHERE, f"expected {FORMS}, got {raw!r}")


def parse_inertia(ctx, raw, bounds):
    """``(dimensionless, moments (3,), tensor (3, 3) or None)`` of ``[body] inertia`` (internal
    unit): the principal moments as given, or those of the tensor (its principal frame's,
    :func:`orbatt.body_frame.principal_axes`) and the tensor; ``bounds`` (kg km^2): the range of
    a moment, applied to the diagonal entries of a dimensional tensor. Refusals name ``[body]
    inertia``, the value and the fix."""
    if not isinstance(raw, list) or len(raw) not in (3, 6):
        raise ctx.error(_WHERE, f"expected {FORMS}, got {raw!r}")
    if len(raw) == 3 and all(_plain(v) or isinstance(v, str) for v in raw):  # principal moments
        dimless = all(_plain(v) for v in raw)
        moments = np.array([parse_quantity(ctx, f"{_WHERE}[{k}]", v, U.INERTIA, dimensionless=dimless,
                                           bounds=None if dimless else bounds) for k, v in enumerate(raw)])
        tensor = None
        body_value = moments
    else:
        form, entries = _entries(ctx, raw)
        dimless = all(_plain(v) for _, _, v in entries)
        values = np.empty((3, 3))
        for i, j, v in entries:
            where = f"{_WHERE}[{i}][{j}]" if form == "matrix" else f"{_WHERE}[{SIX_VALUES.index((i, j))}]"
            # a moment's range on the diagonal; products of inertia take either sign
            value = parse_quantity(ctx, where, v, U.INERTIA, dimensionless=dimless,
                                   bounds=None if dimless or i != j else bounds)
            values[i, j] = value
            if form == "six":
                values[j, i] = value
        try:
            tensor = inertia_tensor(values, "inertia", "plain" if dimless else "kg km^2")
        except InputError as exc:
            raise ctx.error(_WHERE, f"{raw!r}: {exc}") from None
        body_value = tensor
    try:  # the body's own validation (positive, triangle inequality), reported with the file
        body = RigidBody(body_value if dimless else body_value * U.INERTIA)
    except InputError as exc:
        raise ctx.error(_WHERE, f"{raw!r}: {exc}") from None
    return dimless, (moments if tensor is None else body.inertia_value), tensor


def check_sweep(ctx, sweep, tensor):
    """Refuse a ``[sweep]`` of a scenario whose ``[body] inertia`` is a tensor (``tensor`` not
    None) that varies the inertia: its parameters or paths (``inertia1``..``inertia3``,
    ``body.inertia[i]``, a tensor's entries) name principal moments, not the tensor's entries,
    and the cases of a full tensor would have different principal frames (the members of one
    ensemble share one, :func:`orbatt.frame_boundary.frame_of`). Any other sweep of a tensor
    runs: each case through the single run's boundary (:mod:`orbatt.frame_boundary`)."""
    if tensor is None or sweep is None:
        return
    swept = [k for k in list(sweep.parameters) + list(sweep.paths)
             if k.startswith("inertia") or k.startswith("body.inertia")]
    if swept:
        why = "" if is_diagonal(tensor) else (" (its cases would have different principal frames, and orbatt "
                                              "integrates the members of a sweep in one)")
        raise ctx.error(f"[sweep] {swept[0]}", f"varies [body] inertia, which is given as a tensor{why}; give "
                                               "[body] inertia as principal moments [I1, I2, I3] (every body-fixed "
                                               "key in principal axes) to sweep them")

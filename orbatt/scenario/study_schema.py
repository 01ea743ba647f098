"""The study outputs of a ``[sweep]`` table (issue 23; computed by :mod:`orbatt.sweep.study`):
which need which scenario content, and their thresholds ``detumble_rate``, ``settling_angle``
and ``window``. Called by :func:`orbatt.scenario.sweep_schema.parse_sweep_table`."""
from __future__ import annotations

import math

from .. import units as U
from ..laws import LAWS, law_of
from .fields import parse_quantity

__all__ = ["parse_study_keys"]


def parse_study_keys(ctx, table, spec, *, dimensionless, control=None, wheels=0):
    """Check the study outputs in ``spec.outputs`` against the scenario and read their keys
    into ``spec`` (``detumble_rate`` rad/s, ``settling_angle`` rad, ``window`` s; plain
    numbers in normalized units); raise :class:`~orbatt.scenario.ScenarioError` naming
    ``[sweep] key``."""
    outs = set(spec.outputs)
    law = law_of(control)
    dipole_laws = " or ".join(f"{x.title}, law = {x.name!r}" for x in LAWS.values() if x.writes("dipole_control"))
    needs = {"max_wheel_speed": (wheels > 0, "reaction wheels ([[body.wheels]])"),
             "wheel_saturated": (wheels > 0, "reaction wheels ([[body.wheels]])"),
             "max_control_torque": (control is not None, "a [control] law"),
             "max_dipole": (law is not None and law.writes("dipole_control"),
                            f"a [control] law with magnetorquers ({dipole_laws})")}
    for name, (ok, what) in needs.items():
        if name in outs and not ok:
            raise ctx.error("[sweep] outputs", f"{name!r} needs {what}; remove it")
    for key, output in (("detumble_rate", "detumble_time"), ("settling_angle", "settling_time")):
        if output in outs and key not in table:
            raise ctx.error(f"[sweep] {key}", f"missing; '{output}' needs it")
        if key in table and output not in outs:
            raise ctx.error(f"[sweep] {key}", f"only used with '{output}' in outputs; remove it or add the output")
    if "detumble_rate" in table:
        spec.detumble_rate = parse_quantity(ctx, "[sweep] detumble_rate", table["detumble_rate"], U.RATE,
                                            dimensionless=dimensionless)
        if not spec.detumble_rate > 0:
            raise ctx.error("[sweep] detumble_rate", f"{table['detumble_rate']!r} must be positive")
    if "settling_angle" in table:
        spec.settling_angle = parse_quantity(ctx, "[sweep] settling_angle", table["settling_angle"], U.ANGLE,
                                             dimensionless=True)
        if not 0 < spec.settling_angle <= math.pi:
            raise ctx.error("[sweep] settling_angle", f"{table['settling_angle']!r} is outside (0, 180] deg")
    if "settling_time" in outs and law is not None and "sun" in law.fields(control):
        raise ctx.error("[sweep] outputs", "'settling_time' of a Sun-pointing law is not available yet; use "
                                           "pointing_axis / pointing_reference without the law, or remove it")
    if "window" in table:
        if "pointing_error" not in outs:
            raise ctx.error("[sweep] window", "only used with 'pointing_error' in outputs; remove it or add the output")
        spec.window = parse_quantity(ctx, "[sweep] window", table["window"], U.TIME, dimensionless=dimensionless)
        if not spec.window > 0:
            raise ctx.error("[sweep] window", f"{table['window']!r} must be positive")

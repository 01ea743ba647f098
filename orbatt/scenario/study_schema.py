"""The study outputs of a ``[sweep]`` table (issue 23): the checks of what each output needs
of the scenario and the ``[sweep]`` keys it reads (thresholds), generated from the outputs'
descriptors (:data:`orbatt.sweep_outputs.OUTPUTS`, :data:`~orbatt.sweep_outputs.NEEDS`,
:data:`~orbatt.sweep_outputs.THRESHOLDS`). Called by
:func:`orbatt.scenario.sweep_schema.parse_sweep_table`."""
from __future__ import annotations

from ..sweep_outputs import NEEDS, OUTPUTS, THRESHOLDS, users_of
from .fields import parse_quantity

__all__ = ["parse_study_keys"]


def _either(names):
    return " or ".join(f"'{n}'" for n in names)


def parse_study_keys(ctx, table, spec, *, dimensionless, control=None, wheels=0):
    """Check the outputs in ``spec.outputs`` against the scenario and read their keys into
    ``spec`` (:data:`~orbatt.sweep_outputs.THRESHOLDS`: ``detumble_rate`` rad/s,
    ``settling_angle`` rad, ``window`` s; plain numbers in normalized units); raise
    :class:`~orbatt.scenario.ScenarioError` naming ``[sweep] key``."""
    outs = [OUTPUTS[o] for o in spec.outputs]
    for o in outs:
        for need in o.needs:
            ok, what = NEEDS[need]
            if not ok(control, wheels):
                raise ctx.error("[sweep] outputs", f"{o.key!r} needs {what}; remove it")
    for key, th in THRESHOLDS.items():
        users = users_of(key)
        asked = [o.key for o in outs if key in o.keys]
        if th.required and asked and key not in table:
            raise ctx.error(f"[sweep] {key}", f"missing; {_either(asked)} needs it")
        if key in table and not asked:
            raise ctx.error(f"[sweep] {key}", f"only used with {_either(users)} in outputs; remove it or add the output")
        if key in table:
            value = parse_quantity(ctx, f"[sweep] {key}", table[key], th.unit, dimensionless=th.angle or dimensionless)
            if not 0 < value <= th.high:
                raise ctx.error(f"[sweep] {key}", f"{table[key]!r} {th.outside}")
            setattr(spec, key, value)
    for o in outs:
        why = None if control is None else o.refuse(control)
        if why:
            raise ctx.error("[sweep] outputs", why)

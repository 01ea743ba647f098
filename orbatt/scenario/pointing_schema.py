"""``[sweep] requirement``: the pointing requirement of each ECSS index a sweep computes
(``requirement = { ape = "0.1 deg", rpe = "10 arcsec" }``; ``docs/pointing-budgets.md``),
checked against the outputs that are pointing indices
(:data:`orbatt.sweep_outputs.POINTING_INDICES`). Called by
:func:`orbatt.scenario.sweep_schema.parse_sweep_table`."""
from __future__ import annotations

from .. import units as U
from ..sweep_outputs import POINTING_INDICES
from .fields import parse_quantity

__all__ = ["parse_requirement"]


def parse_requirement(ctx, table, spec):
    """Read ``[sweep] requirement`` into ``spec.requirement`` (``{index: rad}``); raise
    :class:`~orbatt.scenario.ScenarioError` naming ``[sweep] requirement.INDEX`` for an index
    that is not a pointing index among ``spec.outputs``, or a value that is not a positive
    angle."""
    if "requirement" not in table:
        return
    req = table["requirement"]
    names = ", ".join(f"'{k}'" for k in POINTING_INDICES)
    if not isinstance(req, dict) or not req:
        raise ctx.error("[sweep] requirement", f"expected an inline table of index -> angle such as "
                                               f"{{ ape = \"0.1 deg\" }} (indices: {names}), got {req!r}")
    out = {}
    for name, value in req.items():
        where = f"[sweep] requirement.{name}"
        if name not in POINTING_INDICES:
            raise ctx.error(where, f"{name!r} is not a pointing index; give one of {names}")
        if name not in spec.outputs:
            raise ctx.error(where, f"the sweep does not compute {name!r}; add it to [sweep] outputs or remove it")
        x = parse_quantity(ctx, where, value, U.ANGLE, dimensionless=True)
        if not x > 0:
            raise ctx.error(where, f"{value!r} must be a positive angle, e.g. \"10 arcsec\"")
        out[name] = x
    spec.requirement = out

"""What a person reads of a sweep result: each scalar output's percentiles over the cases
and how many cases have none (``orbatt info SWEEP.nc``; issue 23)."""
from __future__ import annotations

import numpy as np

from ..dataset.sweep_figures import sweep_outputs
from ..sweep_outputs import per_component_outputs

__all__ = ["PERCENTILES", "scalar_outputs", "percentile_table"]

#: the percentiles ``orbatt info`` prints (0 and 100: min and max)
PERCENTILES = (0, 50, 95, 99, 100)
#: display units for the Dataset's units (a factor and a label)
_DISPLAY = {"rad": (np.degrees(1.0), "deg"), "rad s^-1": (np.degrees(1.0), "deg/s")}


def scalar_outputs(ds):
    """The names of the per-case scalar outputs of a sweep Dataset (float variables along
    ``case`` only, flags left out), in the Dataset's order
    (:func:`orbatt.dataset.sweep_figures.sweep_outputs`)."""
    return sweep_outputs(ds)


def percentile_table(ds) -> list[str]:
    """Lines of a table: each scalar output's min, median, 95th, 99th percentile and max over
    the cases with a value, and the count of cases without one (NaN: never reached, or failed);
    angles in degrees. Outputs with a dimension beyond ``case`` get a row per wheel, axis or mode
    (:func:`orbatt.sweep_outputs.per_component_outputs`), and the saturation flags a count."""
    rows = []
    names = scalar_outputs(ds)
    names += per_component_outputs(ds)  # a row per wheel, axis, mode
    for name in names:
        v = ds[name]
        units = v.attrs.get("units", "")
        factor, label = _DISPLAY.get(units, (1.0, units))
        if name == "max_wheel_speed" and units == "rad s^-1":  # wheels: revolutions per minute
            factor, label = 60.0 / (2.0 * np.pi), "rpm"
        cols = [(name, np.asarray(v.values, dtype=float))] if v.dims == ("case",) else \
            [(f"{name}[{k}]", np.asarray(v.values[:, k], dtype=float)) for k in range(v.shape[1])]
        for label_k, x in cols:
            ok = x[np.isfinite(x)] * factor
            nan = x.size - ok.size
            if ok.size:
                p = np.percentile(ok, PERCENTILES)
                vals = "  ".join(f"{y:>10.4g}" for y in p)
            else:
                vals = "  ".join(f"{'-':>10}" for _ in PERCENTILES)
            rows.append(f"  {label_k:<22} {vals}  {nan:>6}  {label}")
    if not rows:
        return []
    head = "  ".join(f"{('min' if p == 0 else 'max' if p == 100 else f'p{p}'):>10}" for p in PERCENTILES)
    out = [f"  {'output':<22} {head}  {'NaN':>6}  units", *rows]
    if "wheel_saturated" in ds:
        sat = np.asarray(ds["wheel_saturated"].values)
        out.append(f"  wheel_saturated        {int((sat == 1).any(axis=1).sum())} of {sat.shape[0]} cases saturated a "
                   "wheel")
    return out

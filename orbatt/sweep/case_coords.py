"""The coordinates along ``case`` of a sweep's Dataset that record each case's sampled
parameter values (``docs/sweeps.md``: Outputs): a named parameter under its name, a scenario
path under :func:`~orbatt.scenario.paths.coordinate_name` of it, with ``units``,
``long_name`` and (paths) ``scenario_key``."""
from __future__ import annotations

import numpy as np

from ..dataset import cf_variable
from ..scenario.paths import coordinate_name
from ..scenario.sweep_schema import PARAMETERS
from ..units import LEGACY_OUTPUT

__all__ = ["parameter_coordinates"]


def parameter_coordinates(spec, values, units):
    """``{coordinate name: variable}`` of every swept parameter.

    Parameters
    ----------
    spec : SweepSpec
    values : dict of str to ndarray (n,)
        The cases' values (internal units, or a path's own unit).
    units : dict
        CF unit string of every parameter (:func:`~orbatt.scenario.sweep_schema.sweep_units`).
    """
    coords = {}
    for name in spec.parameters:
        # sampled in internal units (or a path's own unit); a kernel unit of the attitude family
        # (the inertia parameters' kg km^2) is written in SI, as every output
        vals, unit = values[name], units[name]
        conv = LEGACY_OUTPUT.get(unit)
        if conv is not None:
            vals, unit = np.multiply(vals, conv[1]), conv[0]
        if name in spec.paths:  # by its path: the coordinate named for it, the path as written
            coords[coordinate_name(name)] = cf_variable(("case",), vals, unit,
                                                        f"sampled parameter: scenario key {name}", scenario_key=name)
        else:
            coords[name] = cf_variable(("case",), vals, unit, f"sampled parameter: {PARAMETERS[name].long_name}")
    return coords

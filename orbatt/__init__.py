"""orbatt: satellite attitude coupled to the orbit, in the canonical quaternion variables of
Arribas, Elipe & Palacios (2006). Conventions: :mod:`orbatt.quaternion`.

``import orbatt`` is light (no numpy, numba or astropy): every public name below is loaded from
its module on first use (PEP 562). ``orbatt run`` relies on that to choose, before numba is
imported, whether a first run on an empty compile cache runs its kernels interpreted
(:mod:`orbatt.coldstart`).
"""
from __future__ import annotations

from .errors import InputError, IntegrationError, OrbattError, ScenarioError, SweepError
from .version import __version__
from .xarray_hook import install_accessor_hook

install_accessor_hook()  # ``ds.orbatt`` on every Dataset once xarray is imported, by whom and when it may be

#: ``{public name: the module that defines it}`` (submodules map to themselves)
_WHERE = {
    "canonical": ".canonical", "euler": ".euler", "quaternion": ".quaternion", "orbital": ".orbital",
    "methods": ".methods",
    "read_aem": ".dataset.aem", "write_aem": ".dataset.aem",
    "open_dataset": ".dataset", "to_dataset": ".dataset",
    "RigidBody": ".body",
    "HeavyTop": ".potentials", "Potential": ".potentials", "TorqueFree": ".potentials", "GravityGradient": ".potentials",
    "METHODS": ".methods", "Method": ".methods", "Problem": ".methods", "register": ".methods",
    "ProgressInfo": ".progress",
    "propagate": ".propagation",
    "Scenario": ".scenario", "load_scenario": ".scenario",
    "State": ".state",
    "inertial_attitude": ".orbital", "orbital_attitude": ".orbital", "state_from_orbital": ".orbital",
    "to_orbital": ".orbital",
    "KeplerOrbit": ".orbits", "ReboundOrbit": ".orbits", "TleOrbit": ".orbits",
    "EnvironmentTorques": ".torques", "Facet": ".torques",
    "BDotControl": ".control", "PDControl": ".control", "ReactionWheel": ".control",
    "LAWS": ".laws", "control_law": ".laws",
    "rpm": ".units",
    "Sweep": ".sweep", "load_sweep": ".sweep", "run_sweep": ".sweep",
    "pointing": ".pointing", "index_series": ".pointing", "window_means": ".pointing",
    "temporal_quantile": ".pointing", "ensemble_quantile": ".pointing", "mixed_quantile": ".pointing",
    "interpreted_quantile": ".pointing",
    "Gyro": ".sensors", "StarTracker": ".sensors", "MEKF": ".sensors", "Navigation": ".sensors",
    "Magnetometer": ".sensors", "SunSensor": ".sensors",
    "with_navigation": ".sensors",
}
_SUBMODULES = {"canonical", "euler", "quaternion", "orbital", "methods", "pointing"}

__all__ = [
    "RigidBody", "State", "Potential", "TorqueFree", "HeavyTop", "propagate", "load_scenario", "Scenario",
    "Method", "METHODS", "methods", "register", "Problem", "ProgressInfo",
    "OrbattError", "InputError", "IntegrationError", "ScenarioError",
    "quaternion", "canonical", "euler", "__version__",
    "KeplerOrbit", "ReboundOrbit", "TleOrbit", "GravityGradient", "EnvironmentTorques", "Facet", "ReactionWheel", "PDControl", "BDotControl", "LAWS",
    "control_law", "orbital",
    "state_from_orbital", "to_orbital", "orbital_attitude", "inertial_attitude",
    "to_dataset", "open_dataset", "write_aem", "read_aem",
    "Sweep", "SweepError", "load_sweep", "run_sweep", "rpm",
    "pointing", "index_series", "window_means", "temporal_quantile", "ensemble_quantile", "mixed_quantile",
    "interpreted_quantile",
    "Gyro", "StarTracker", "Magnetometer", "SunSensor", "MEKF", "Navigation", "with_navigation",
]


def __getattr__(name):
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    module = importlib.import_module(where, __name__)
    value = module if name in _SUBMODULES else getattr(module, name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_WHERE))

"""orbatt: satellite attitude coupled to the orbit, in the canonical quaternion variables of
Arribas, Elipe & Palacios (2006). Conventions: :mod:`orbatt.quaternion`."""
from __future__ import annotations

from . import canonical, euler, quaternion
from .dataset.aem import read_aem, write_aem
from .body import RigidBody
from .dataset import open_dataset, to_dataset
from .errors import InputError, IntegrationError, OrbattError, ScenarioError, SweepError
from .potentials import HeavyTop, Potential, TorqueFree
from . import methods  # the subpackage; its function methods() is orbatt.methods.methods
from .methods import METHODS, Method, Problem, register
from .progress import ProgressInfo
from .propagation import propagate
from .scenario import Scenario, load_scenario
from .state import State
from . import orbital
from .orbital import inertial_attitude, orbital_attitude, state_from_orbital, to_orbital
from .orbits import KeplerOrbit, ReboundOrbit, TleOrbit
from .potentials import GravityGradient
from .torques import EnvironmentTorques, Facet
from .control import BDotControl, PDControl, ReactionWheel
from .version import __version__

__all__ = [
    "RigidBody", "State", "Potential", "TorqueFree", "HeavyTop", "propagate", "load_scenario", "Scenario",
    "Method", "METHODS", "methods", "register", "Problem", "ProgressInfo",
    "OrbattError", "InputError", "IntegrationError", "ScenarioError",
    "quaternion", "canonical", "euler", "__version__",
    "KeplerOrbit", "ReboundOrbit", "TleOrbit", "GravityGradient", "EnvironmentTorques", "Facet", "ReactionWheel", "PDControl", "BDotControl", "orbital",
    "state_from_orbital", "to_orbital", "orbital_attitude", "inertial_attitude",
    "to_dataset", "open_dataset", "write_aem", "read_aem",
    "Sweep", "SweepError", "load_sweep", "run_sweep",
]

#: names loaded on first use (``orbatt.Sweep`` ...): a run does not need the sweep machinery
_LAZY = {"Sweep": "sweep", "load_sweep": "sweep", "run_sweep": "sweep"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))

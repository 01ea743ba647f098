"""orbatt: satellite attitude coupled to the orbit, in the canonical quaternion variables of
Arribas, Elipe & Palacios (2006). Conventions: :mod:`orbatt.quaternion`."""
from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version as _version

from . import canonical, euler, quaternion
from .aem import read_aem, write_aem
from .body import RigidBody
from .dataset import open_dataset, to_dataset
from .errors import InputError, IntegrationError, OrbattError, ScenarioError, SweepError
from .potentials import HeavyTop, Potential, TorqueFree
from .propagate import propagate
from .scenario import Scenario, load_scenario
from .state import State
from . import orbital
from .orbital import inertial_attitude, orbital_attitude, state_from_orbital, to_orbital
from .orbits import KeplerOrbit, ReboundOrbit
from .potentials import GravityGradient
from .sweep import Sweep, load_sweep, run_sweep

try:
    __version__ = _version("orbatt")
except PackageNotFoundError:  # pragma: no cover - source tree without install
    __version__ = "0+unknown"

__all__ = [
    "RigidBody", "State", "Potential", "TorqueFree", "HeavyTop", "propagate", "load_scenario", "Scenario",
    "OrbattError", "InputError", "IntegrationError", "ScenarioError", "SweepError",
    "quaternion", "canonical", "euler", "__version__",
    "KeplerOrbit", "ReboundOrbit", "GravityGradient", "orbital",
    "state_from_orbital", "to_orbital", "orbital_attitude", "inertial_attitude",
    "to_dataset", "open_dataset", "write_aem", "read_aem",
    "Sweep", "SweepError", "load_sweep", "run_sweep",
]

"""orbatt: satellite attitude coupled to the orbit, in the canonical quaternion variables of
Arribas, Elipe & Palacios (2006). Conventions: :mod:`orbatt.quaternion`."""
from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version as _version

from . import canonical, euler, quaternion
from .body import RigidBody
from .errors import InputError, IntegrationError, OrbattError
from .potentials import HeavyTop, Potential, TorqueFree
from .state import State

try:
    __version__ = _version("orbatt")
except PackageNotFoundError:  # pragma: no cover - source tree without install
    __version__ = "0+unknown"

__all__ = [
    "RigidBody", "State", "Potential", "TorqueFree", "HeavyTop",
    "OrbattError", "InputError", "IntegrationError",
    "quaternion", "canonical", "euler", "__version__",
]

"""Orbit providers (``docs/design.md`` §5): the orbit that drives the gravity-gradient torque.

* :class:`KeplerOrbit` - an elliptic Keplerian orbit (compiled Kepler solve);
* :class:`ReboundOrbit` - the orbit integrated by REBOUND (optionally J2, Moon, Sun),
  sampled and interpolated;
* :class:`TleOrbit` - a satellite's two-line elements propagated by SGP4 (GCRS), sampled and
  interpolated;
* :class:`OrbitProvider` - the contract both follow (read its docstring).
"""
from .base import GM_EARTH, R_EARTH, OrbitProvider, PeriapsisWarning, elements_from_state, frame_quaternion
from .kepler import KeplerOrbit
from .rebound import GM_MOON, GM_SUN, J2_EARTH, R_J2_EARTH, ReboundOrbit
from .sampled import SampledOrbit
from .tle import TleOrbit

__all__ = ["OrbitProvider", "KeplerOrbit", "ReboundOrbit", "TleOrbit", "SampledOrbit", "PeriapsisWarning", "elements_from_state",
           "frame_quaternion", "GM_EARTH", "R_EARTH", "GM_MOON", "GM_SUN", "J2_EARTH", "R_J2_EARTH"]

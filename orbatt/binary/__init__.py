"""Binary asteroids: the relative orbit and the attitudes of both bodies integrated together
(the full two-body problem to second order, ``docs/design.md`` §12).

:class:`BinarySystem` (the bodies, validated), :func:`propagate_binary` (the coupled DOP853 or
Verner 9(8) run, impulses, contact), :func:`binary_content` / :func:`binary_dataset` (the result
Dataset). The kernels are in :mod:`orbatt.core.mutual`; the scenario form (``[orbit] provider =
"coupled"``) in :mod:`orbatt.scenario.binary_schema`.
"""
from .dataset import binary_content, binary_dataset
from .propagate import METHODS, BinaryTrajectory, Impulse, propagate_binary
from .system import BinarySystem, osculating_elements

__all__ = ["BinarySystem", "BinaryTrajectory", "Impulse", "propagate_binary", "binary_content", "binary_dataset",
           "osculating_elements", "METHODS"]

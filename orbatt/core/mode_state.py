"""The state of a mode sequence in the flight software's state (issue 32, item 4): where each
part of it lies in ``y[z0:z0 + nz]`` and the one kernel that changes the mode.

A sequence of ``count`` modes holds ``nz = 4 + count`` components at ``z0`` (its row's
:data:`~orbatt.core.control.CTL_Z0`):

========================  ===================================================================
``y[z0 + MODE]``          the current mode, ``0 .. count - 1``
``y[z0 + ENTRY]``         the time the current mode began (s)
``y[z0 + HOLD_BEGAN]``    the time its conditions began to hold (s)
``y[z0 + HOLDS]``         1.0 while they hold, else 0.0
``y[z0 + ENTRIES + k]``   the time mode ``k`` began (s), for every ``k <= mode`` (0.0 for the
                          modes not yet entered: the step loop's error norm reads every
                          component, so no NaN); a mode entered and left between two outputs
                          keeps its entry time here
========================  ===================================================================

Modes run in order and are never entered twice, so the entries are written once each, by
:func:`enter_mode`, at a tick (:func:`orbatt.core.gyrostat.mode_transition`) or at a located
instant (:func:`orbatt.core.mode_events.advance`). Times are seconds from the epoch of the run's
``t`` (the kernels' time).
"""
from __future__ import annotations

from ._jit import jit_inline

__all__ = ["MODE", "ENTRY", "HOLD_BEGAN", "HOLDS", "ENTRIES", "state_size", "enter_mode"]

MODE, ENTRY, HOLD_BEGAN, HOLDS, ENTRIES = 0, 1, 2, 3, 4


def state_size(count):
    """The number of state components of a sequence of ``count`` modes."""
    return ENTRIES + int(count)


@jit_inline
def enter_mode(y, z, m, t):
    """Begin mode ``m`` at time ``t`` (s) in the sequence whose state is ``y[z:]``: its entry
    time, its conditions not holding yet."""
    y[z + MODE] = float(m)
    y[z + ENTRY] = t
    y[z + HOLD_BEGAN] = t
    y[z + HOLDS] = 0.0
    y[z + ENTRIES + m] = t

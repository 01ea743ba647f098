"""orbatt's exceptions. Each also inherits the built-in a caller would catch otherwise."""
from __future__ import annotations


class OrbattError(Exception):
    """Base class of every orbatt error."""


class InputError(OrbattError, ValueError):
    """Bad input: the message names the field, the value and the fix."""


class IntegrationError(OrbattError, RuntimeError):
    """An integration could not continue (non-finite state, step size underflow, ...);
    ``t`` is the time at which it stopped."""

    def __init__(self, message, t=None):
        super().__init__(message)
        self.t = t


class ScenarioError(InputError):
    """A scenario file is malformed; the message names the file, table, key, value and fix."""


class SweepError(OrbattError, RuntimeError):
    """A sweep could not finish (a task failed for good, e.g. its workers kept dying); the
    chunks written so far are kept for ``resume``."""

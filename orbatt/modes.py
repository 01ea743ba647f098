"""Mode sequences of the flight software (issue 32, item 4): detumble -> Sun -> target, each
mode a control law, left for the next at a flight-software tick when its condition holds.

The sequence is a control law of its own (:class:`ModeSequence`, ``[[control.modes]]`` in a
scenario): its kernel rows are those of its modes' laws, each marked with its mode (a row acts
only while the sequence is in its mode: :func:`orbatt.core.gyrostat.row_active`), then the
sequence's row (:data:`orbatt.core.control.MODES`) whose state ``(mode, entry time, time the
condition began to hold)`` follows the laws' held commands in the state. Transitions are
decided at the flight software's ticks (:func:`orbatt.core.gyrostat.mode_transition`), or,
for a sequence without a ``period`` (continuous laws), located on the continuous solution at
the instant a condition is met (:mod:`orbatt.core.mode_events`); the Dataset gets ``mode`` along ``time`` (CF ``flag_values`` /
``flag_meanings`` naming the modes) and ``mode_entry_time``.
"""
from __future__ import annotations

import copy

import numpy as np
from astropy import units as u

from .control import BDotControl, PDControl, flight_period, scalar_value
from .core import control as kc
from .core import model as km
from .errors import InputError

__all__ = ["Mode", "ModeSequence", "MAX_MODES"]

#: most modes of a sequence
MAX_MODES = 16


class Mode:
    """One mode of a :class:`ModeSequence`.

    Parameters
    ----------
    name : str
        A name (an identifier: it becomes a CF flag meaning).
    law : PDControl or BDotControl
        The law that acts in the mode.
    until_time : Quantity (time), optional
        Leave after this time in the mode.
    until_rate : Quantity (angular rate), optional
        Leave once ``|omega|`` has stayed below it for ``hold``.
    until_settled : Quantity (angle), optional
        Leave once the attitude error of the mode's PD law has stayed below it for ``hold``.
    hold : Quantity (time), optional
        How long ``until_rate`` / ``until_settled`` must hold (default 0: at the first tick).

    Conditions given together: ``until_time`` or (all of the others, for ``hold``).
    """

    def __init__(self, name, law, *, until_time=None, until_rate=None, until_settled=None, hold=None):
        if not isinstance(name, str) or not name.isidentifier():
            raise InputError(f"name: {name!r} is not a name (letters, digits and _, e.g. 'detumble')")
        if not isinstance(law, (PDControl, BDotControl)):
            raise InputError(f"law: expected a PDControl or BDotControl, got {type(law).__name__}")
        self.name, self.law = name, law
        self.until_time = scalar_value(until_time, u.s, "until_time", positive=True, allow_none=True)
        self.until_rate = scalar_value(until_rate, u.rad / u.s, "until_rate", positive=True, allow_none=True)
        self.until_settled = scalar_value(until_settled, u.rad, "until_settled", positive=True, allow_none=True)
        self.hold = scalar_value(hold, u.s, "hold", nonnegative=True, allow_none=True)
        if self.until_settled is not None and law.law != "pd":
            raise InputError(f"until_settled: the attitude error is the PD law's (mode {name!r} runs {law.law!r})")
        if self.hold is not None and self.until_rate is None and self.until_settled is None:
            raise InputError("hold: only with until_rate or until_settled (how long they must hold)")

    @property
    def has_exit(self):
        return any(x is not None for x in (self.until_time, self.until_rate, self.until_settled))

    def conditions(self):
        """The kernel's condition row (:data:`orbatt.core.control.MODE_FIELDS`; ``inf``: none)."""
        inf = np.inf
        return [inf if self.until_time is None else self.until_time, inf if self.until_rate is None else self.until_rate,
                inf if self.until_settled is None else self.until_settled, 0.0 if self.hold is None else self.hold]

    def settings(self):
        """Plain settings: ``name``, the conditions (SI floats or None) and the law's own."""
        return {"name": self.name, "until_time": self.until_time, "until_rate": self.until_rate,
                "until_settled": self.until_settled, "hold": self.hold, **self.law.settings()}

    def __repr__(self):
        return f"Mode({self.name!r}, {self.law!r})"


def _shifted(row, z0, mode):
    """A law's kernel row with its controller state moved to ``y[z0:]`` and marked ``mode``."""
    kind, params, table = row
    p = np.array(params, dtype=np.float64)
    old = p[kc.CTL_Z0]
    p[kc.CTL_Z0] = z0
    p[kc.CTL_MODE] = mode
    if int(kind) == km.PD_CONTROL and p[kc.PD.zi] >= 0:
        p[kc.PD.zi] += z0 - old
    return (kind, p, table), int(p[kc.CTL_NZ])


class ModeSequence:
    """A sequence of control laws run by the flight software (module docstring).

    Parameters
    ----------
    modes : list of Mode
        In order; every mode but the last needs a condition to leave it.
    period : Quantity (time) or None
        The flight software's period: the laws' ticks and the transitions' (every mode's law
        runs at it). None: the laws are continuous and each transition is located on the
        continuous solution, at the instant its condition is met
        (:mod:`orbatt.core.mode_events`; ensembles member by member, not in lockstep lanes).
    """

    law = "modes"

    def __init__(self, modes, *, period):
        modes = list(modes)
        if not modes or not all(isinstance(m, Mode) for m in modes):
            raise InputError("modes: expected a non-empty list of orbatt.modes.Mode")
        if len(modes) > MAX_MODES:
            raise InputError(f"modes: {len(modes)} modes, more than {MAX_MODES}")
        names = [m.name for m in modes]
        if len(set(names)) != len(names):
            raise InputError(f"modes: the names {names} repeat one; give each mode its own name")
        for m in modes[:-1]:
            if not m.has_exit:
                raise InputError(f"modes: mode {m.name!r} has no condition to leave it (until_time, until_rate or "
                                 "until_settled), so the modes after it never run")
        self.period = flight_period(period)
        for m in modes:
            if m.law.period is not None and self.period is None:
                raise InputError(f"period: mode {m.name!r}'s law runs at {m.law.period:g} s and the sequence has no "
                                 "period (continuous laws); give the sequence the period (ModeSequence(..., "
                                 "period=...), [control] period) so that every mode runs at it")
            if m.law.period is not None and m.law.period != self.period:
                raise InputError(f"period: mode {m.name!r}'s law runs at {m.law.period:g} s, the sequence at "
                                 f"{self.period:g} s; the flight software has one rate")
            m.law = copy.copy(m.law)  # the sequence's own: its laws run at its period
            m.law.__dict__.pop("_rows", None)
            m.law.period = self.period
        self.modes = modes

    @property
    def names(self):
        return [m.name for m in self.modes]

    @property
    def reads_orbit(self):
        return any(m.law.reads_orbit for m in self.modes)

    def check_wheels(self, wheels):
        for m in self.modes:
            m.law.check_wheels(wheels)

    def settings(self):
        return {"law": self.law, "period": self.period, "modes": [m.settings() for m in self.modes]}

    def model_rows(self, wheels, tables):
        """The kernel rows: each mode's law's, marked with its mode and given its state after
        the previous ones' (from ``8 + len(wheels)``), then the sequence's row."""
        z = 8 + len(wheels)
        rows = []
        for i, m in enumerate(self.modes):
            own = m.law.model_rows(wheels, tables) if hasattr(m.law, "model_rows") else [m.law.model_row(wheels, tables)]
            for row in own:
                row, nz = _shifted(row, z, i)
                rows.append(row)
                z += nz
        rows.append((km.MODES, kc.modes_params(0.0 if self.period is None else self.period, z,
                                               [m.conditions() for m in self.modes]), None))
        return rows

    def describe(self):
        return {"law": "modes", "period_s": self.period,
                "modes": [{"name": m.name, **m.law.describe(), **{k: v for k, v in m.settings().items()
                                                                  if k.startswith("until_") or k == "hold"}}
                          for m in self.modes]}

    def __repr__(self):
        rate = "continuous" if self.period is None else f"period={self.period:g} s"
        return f"ModeSequence({' -> '.join(self.names)}, {rate})"

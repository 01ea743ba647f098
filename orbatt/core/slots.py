"""Named parameter slots of a kernel row (issue 32): one layout, shared by the packer that
writes a row's ``params`` and the kernel that reads them.

A row's parameters are a flat float64 slice ``params[p0:p1]`` (:mod:`orbatt.core.model`).
Instead of hand-numbered offsets (``params[p0 + 5]``) each row kind declares its layout once::

    PD = Slots(("target", 1), ("kp", 1), ("kd", 1), ..., ("c", 4))

The kernel takes the offsets as module constants (``_KP = PD.kp``), which numba folds into the
compiled code exactly as a literal; the packer fills the row by name (:meth:`Slots.pack`),
which refuses a missing or extra name and a value of the wrong size. A layout may end with a
variable-length tail (``tail=True``: the wheels' pseudo-inverse of the PD law), packed after
the fixed slots.
"""
from __future__ import annotations

import numpy as np

__all__ = ["Slots"]


class Slots:
    """The named slots of a kernel row's parameters (module docstring).

    Parameters
    ----------
    *fields : (name, size) pairs
        In the row's order; ``size`` floats each.
    tail : str, optional
        The name of a variable-length tail after the fixed slots (its offset is :attr:`size`).
    """

    def __init__(self, *fields, tail=None):
        offsets, sizes = {}, {}
        at = 0
        for name, size in fields:
            if name in offsets or not name.isidentifier() or int(size) < 1:
                raise ValueError(f"Slots: bad or repeated slot {name!r} of size {size!r}")
            offsets[name], sizes[name] = at, int(size)
            at += int(size)
        self._offsets, self._sizes, self.tail = offsets, sizes, tail
        #: the number of fixed floats (the tail's offset)
        self.size = at
        if tail is not None:
            offsets[tail] = at

    def __getattr__(self, name):
        try:
            return self.__dict__["_offsets"][name]
        except KeyError:
            raise AttributeError(f"no slot {name!r}") from None

    @property
    def names(self):
        """The fixed slots' names, in order."""
        return tuple(self._sizes)

    def pack(self, tail=None, **values):
        """The row's parameters: every fixed slot by name (a float, or ``size`` floats), then
        the ``tail`` values (flattened), as one float64 array."""
        missing = [n for n in self._sizes if n not in values]
        extra = [n for n in values if n not in self._sizes]
        if missing or extra:
            raise ValueError(f"Slots.pack: missing {missing}, unknown {extra}")
        out = np.empty(self.size, dtype=np.float64)
        for name, size in self._sizes.items():
            v = np.asarray(values[name], dtype=np.float64).ravel()
            if v.size != size:
                raise ValueError(f"Slots.pack: {name!r} takes {size} value(s), got {v.size}")
            out[self._offsets[name]:self._offsets[name] + size] = v
        if tail is None:
            return out
        if self.tail is None:
            raise ValueError("Slots.pack: this layout has no tail")
        return np.concatenate([out, np.asarray(tail, dtype=np.float64).ravel()])

    def __repr__(self):
        inner = ", ".join(f"{n}@{self._offsets[n]}" + (f"[{s}]" if s > 1 else "") for n, s in self._sizes.items())
        return f"Slots({inner}" + (f", tail {self.tail}@{self.size}" if self.tail else "") + ")"

"""The fast paths that lean on other libraries' internals, fenced in one place, with one switch
(``docs/design.md`` §8).

orbatt is faster in a few places because it uses what numba and xarray do not promise. Each
such path lives beside the code it speeds up, is **guarded by behaviour** (on first use it
checks that the library does what the path was written for, comparing with the public way, and
falls back to the public way otherwise, silently and for the rest of the process), and is
listed here:

======================  =============================  ==========================================
name                    where                          the public way it replaces
======================  =============================  ==========================================
``numba-cache-loads``   ``orbatt.core._jit``           numba's own ``load_overload`` (which
                        (``_CheckedCache``)            first imports every lowering registry:
                                                       ~0.4 s a process)
``borrowed-arrays``     ``orbatt.core._jit.borrow``    arrays passed to compiled calls as they are
                                                       (reference-counted: ~3x the cost of a
                                                       right-hand side call)
``xarray-direct``       ``orbatt.dataset.assembly``    ``xr.Variable`` / ``xr.Dataset`` and
                                                       xarray's CF time decoder
``accessor-hook``       ``orbatt.xarray_hook``         ``import orbatt`` imports xarray (and
                                                       pandas, ~0.3 s) to register ``ds.orbatt``
``interpreted-first``   ``orbatt.coldstart``           every ``orbatt run`` compiles (a first run
                                                       of a kind waits for numba)
``rebound-particles``   ``orbatt.orbits.rebound``      each particle's ``x`` .. ``az`` read as
                        (``_RAW_READS``)               attributes (ctypes, one field at a time)
======================  =============================  ==========================================

**The switch.** ``ORBATT_FAST_PATHS=0`` in the environment (read once, when orbatt is
imported) turns every one of them off: the results are the same, bit for bit (tested), only
slower to start. The older ``ORBATT_FAST_LOADS=0`` still turns off the cache loads alone.
The compiled kernels' cache stamp includes the switch, so kernels compiled with borrowed
arrays are never loaded without them, and the other way round.
"""
from __future__ import annotations

import os
import sys

__all__ = ["SWITCH", "ENABLED", "PATHS", "report", "active"]

#: the environment variable that turns every fast path off (``0``)
SWITCH = "ORBATT_FAST_PATHS"
#: the fast paths are allowed in this process (they still check the libraries' behaviour)
ENABLED = os.environ.get(SWITCH, "1").strip() != "0"
#: name -> (module, what it does)
PATHS = {
    "numba-cache-loads": ("orbatt.core._jit", "kernels load from numba's cache without its compiler"),
    "borrowed-arrays": ("orbatt.core._jit", "arrays without reference counts inside the compiled loops"),
    "xarray-direct": ("orbatt.dataset.assembly", "Datasets and time axes built without xarray's checks"),
    "accessor-hook": ("orbatt.xarray_hook", "ds.orbatt registered when xarray is imported, not before"),
    "interpreted-first": ("orbatt.coldstart", "a first run interprets while a warm-up compiles"),
    "rebound-particles": ("orbatt.orbits.rebound", "REBOUND's particle states read from its memory in one view"),
}


#: name -> a function of no argument: whether that path is in use now (:func:`report`)
_IN_USE: dict = {}


def report(name: str, in_use) -> None:
    """Called by the module that owns the fast path ``name`` (a key of :data:`PATHS`) when it
    is imported: ``in_use``, a function of no argument, tells :func:`active` whether the path
    is in use now (its library check passed, and has not failed since). The owners import
    this module, never the other way round."""
    if name not in PATHS:
        raise KeyError(f"{name!r} is not a fast path of orbatt.fast_paths.PATHS")
    _IN_USE[name] = in_use


def active() -> dict:
    """``{name: bool}``: which fast paths this process uses (a library check that fails
    later turns its path off then). A path whose module has not been imported yet (it has
    neither been used nor failed yet) is :data:`ENABLED`; imports nothing."""
    rebound = sys.modules.get("orbatt.orbits.rebound")  # not imported: not used, nor failed, yet
    return {**{name: ENABLED for name in PATHS}, **{name: bool(in_use()) for name, in_use in _IN_USE.items()},
            "rebound-particles": ENABLED if rebound is None else rebound.raw_reads_in_use()}

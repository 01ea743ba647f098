"""The one switch point of the compiled kernels: numba presets, intrinsics, status codes and
the named bits and slots of the resumable integrator state.

Every kernel of :mod:`orbatt.core` is compiled through one of the presets below, so changing
how the package compiles (caching, the error model, inlining) is a change here only.

Numerics: every kernel runs with ``error_model="numpy"`` (a division by zero gives inf/NaN,
which the step loops catch and reject, instead of raising).
"""
from __future__ import annotations

import contextlib
import hashlib
import itertools
import os
import warnings
from pathlib import Path

import numba as nb
import numpy as np
from numba.core import cgutils, types
from numba.core.caching import FunctionCache
from numba.core.runtime import rtsys
from numba.core.serialize import dumps
from numba.extending import intrinsic

from .. import fast_paths
from ..fast_paths import ENABLED as _FAST_PATHS

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: numba's own unlocked saves
    fcntl = None

#: the lock file of a cache folder (:func:`cache_lock`)
LOCK_NAME = "orbatt-numba-cache.lock"


@contextlib.contextmanager
def cache_lock(folder, exclusive):
    """Hold the lock of the numba cache folder ``folder``: ``exclusive`` to change an index
    (:meth:`_CheckedCache.save_overload`), shared to read an index and the entry it names.

    numba's own save reads a kernel's index, takes the first unused data-file number and
    writes the index and then the data, unlocked. Two processes compiling kernels that share an
    index (two signatures of one function, or the variants of one closure, such as the
    DOP853 and Verner loops of :func:`orbatt.core.rk_loop.loop_of`) at once, as the background
    warm-up beside a first run, Dask's workers or pytest's do, both take the same number:
    one index entry then names the other's machine code, and every later process loads it
    silently for the wrong kernel (seen: ensemble runs failing with a step-size underflow
    after a cold parallel test run). Without ``fcntl`` (Windows), or where the folder cannot
    hold the lock file, nothing is locked (numba's own behaviour)."""
    fd = None
    if fcntl is not None:
        path = os.path.join(folder, LOCK_NAME)
        for flags in (os.O_RDWR | os.O_CREAT, os.O_RDONLY):
            try:
                fd = os.open(path, flags, 0o666)
                break
            except OSError:
                continue
    if fd is None:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        yield
    finally:
        os.close(fd)  # releases the lock


class _CheckedCache(FunctionCache):
    """numba's disk cache of a kernel that survives an unreadable entry, and (where numba's
    internals are the ones checked) loads without initializing the compiler.

    **Concurrent processes.** Saves hold the cache folder's exclusive lock and loads its shared
    lock (:func:`cache_lock`): processes compiling at once no longer give two kernels the same
    data file.

    **Unreadable entries.** numba unpickles the index (``.nbi``) and data (``.nbc``) files as
    they are: a truncated or corrupted file (a full disk, a killed writer, a copied cache)
    raises in every later process, before and after compiling (saving reads the index again),
    until the user deletes it. Here a failed load removes the kernel's index file, warns (once
    per process, :class:`CacheWarning`, naming the first file) and returns None: numba compiles the kernel and
    writes a fresh index (its data files are numbered anew).

    **Fast loads.** numba's ``FunctionCache.load_overload`` first calls
    ``target_context.refresh()``, which imports every lowering registry numba has (numpy,
    linalg, random, typed containers ...): ~0.4 s of imports in each new process, needed to
    *compile* but not to *load* machine code from the cache. Loading needs only the runtime
    (``rtsys.initialize``, for allocations). A kernel that has to be compiled still gets the
    full initialization (numba's compiler calls ``refresh()`` itself). Measured on a warm
    ``orbatt run``: 0.48 -> 0.07 s to the first result of the compiled loop, bitwise the same
    results. Used only where :data:`FAST_LOADS` holds.
    """

    def __init__(self, py_func):
        super().__init__(py_func)
        cache_file = getattr(self, "_cache_file", None)
        if cache_file is not None and hasattr(cache_file, "_source_stamp"):
            cache_file._source_stamp = (cache_file._source_stamp, core_stamp())

    def load_overload(self, sig, target_context):
        with cache_lock(self._cache_path, False):
            return self._locked_load(sig, target_context)

    def _locked_load(self, sig, target_context):
        global FAST_LOADS
        if FAST_LOADS:
            try:
                rtsys.initialize(target_context)
                with self._guard_against_spurious_io_errors():
                    return self._load_overload(sig, target_context)
            except (AttributeError, TypeError, NameError):
                # numba's internals are not the ones the fast load was written for (guarded by
                # what they do, not by their names): numba's own load from now on
                FAST_LOADS = False
            except Exception:  # noqa: BLE001 - an unreadable entry: numba's own load below says so
                pass
        try:
            return super().load_overload(sig, target_context)
        except Exception as exc:  # noqa: BLE001 - any unreadable entry: recompile instead of failing
            self._discard(exc)
            return None

    def save_overload(self, sig, data):
        """numba's save, under the folder's exclusive lock (:func:`cache_lock`), and writing
        the data file before the index entry that names it (numba writes the index first: a
        process loading in between would read a missing or stale data file)."""
        cache_file = getattr(self, "_cache_file", None)
        if not (all(hasattr(cache_file, name) for name in ("_load_index", "_save_index", "_save_data", "_data_name"))
                and all(hasattr(self, name) for name in ("_guard_against_spurious_io_errors", "_impl", "_index_key",
                                                         "_enabled"))):
            with cache_lock(self._cache_path, True):  # numba's internals differ: its own save, serialized
                return super().save_overload(sig, data)
        with self._guard_against_spurious_io_errors():
            if not self._enabled or not self._impl.check_cachable(data):
                return None
            self._impl.locator.ensure_cache_path()
            key = self._index_key(sig, data.codegen)
            data = self._impl.reduce(data)
            with cache_lock(self._cache_path, True):
                try:
                    overloads = cache_file._load_index()
                except Exception:  # noqa: BLE001 - an unreadable index: start a new one
                    overloads = {}
                name = overloads.get(key)
                if name is None:
                    used = set(overloads.values())
                    name = next(n for n in map(cache_file._data_name, itertools.count(1)) if n not in used)
                cache_file._save_data(name, data)
                overloads[key] = name
                cache_file._save_index(overloads)
        return None

    def _discard(self, exc):
        index = getattr(getattr(self, "_cache_file", None), "_index_path", None)
        if index is None:  # numba's internals differ: no file to name; disable this kernel's cache
            self._enabled = False
            index = "(unknown file)"
        else:
            try:
                os.unlink(index)
            except OSError:
                self._enabled = False  # cannot remove it: compile without the cache
        if not _DISCARDED:  # one warning per process, naming the first entry
            warnings.warn(f"numba's compile cache entry {index} is unreadable ({type(exc).__name__}: {exc}); "
                          "removed it (and any other unreadable entry) and compiling again", CacheWarning, stacklevel=2)
        _DISCARDED.append(index)


#: the unreadable cache entries this process removed
_DISCARDED: list = []


def fast_paths_in_use() -> dict:
    """``{"numba-cache-loads": bool, "borrowed-arrays": bool}``: the compiled kernels' fast
    paths (:mod:`orbatt.fast_paths`) this process uses now (a cache load that found numba's
    internals changed has turned its path off); re-exported by :mod:`orbatt.core`, and what
    this module reports to :func:`orbatt.fast_paths.active`."""
    return {"numba-cache-loads": bool(FAST_LOADS), "borrowed-arrays": bool(BORROWED)}


fast_paths.report("numba-cache-loads", lambda: fast_paths_in_use()["numba-cache-loads"])
fast_paths.report("borrowed-arrays", lambda: fast_paths_in_use()["borrowed-arrays"])


def core_stamp() -> str:
    """A digest of every source file of :mod:`orbatt.core` (name, modification time, size),
    folded into each kernel's cache stamp by :class:`_CheckedCache`.

    numba keys a kernel's cache entry on its own file's stamp only, but the kernels inline
    helpers from other files (the step loops of ``dop853.py`` inline ``model.term_value``): a
    change to ``model.py`` alone left the loops' cached machine code in place, running the old
    right-hand side (seen: a new term kind integrated with the old dispatch, wrong results and
    ~10^7 tiny steps, until the cache was deleted). With the digest, a change to any file of
    the package's kernels recompiles them all."""
    global _CORE_STAMP
    if _CORE_STAMP is None:
        h = hashlib.sha1()
        for f in sorted(Path(__file__).resolve().parent.glob("*.py")):
            st = f.stat()
            h.update(f"{f.name}:{st.st_mtime_ns}:{st.st_size};".encode())
        h.update(f"fast_paths={_FAST_PATHS}".encode())  # borrowed arrays or not: other machine code
        _CORE_STAMP = h.hexdigest()
    return _CORE_STAMP


_CORE_STAMP = None


class CacheWarning(RuntimeWarning):
    """An unreadable entry of numba's disk cache was removed and its kernel recompiled."""


def variant_name(func) -> str | None:
    """Give a closure ``func`` a qualified name of its own variant, ``<qualname>[<digest>]``
    (the digest of its cells' contents, as numba's cache keys them), before it is compiled;
    the new name, or None where ``func`` is no closure or its cells cannot be digested (it
    keeps its name).

    numba names a kernel's machine code by its qualified name, its argument types and a count
    of the functions the process has compiled so far, and a caller's machine code holds a
    copy of each callee's under that name (a weak symbol: a process binds it to the first code
    it loaded under the name). The variants of one closure (the DOP853 and Verner, rigid and
    extended loops of :func:`orbatt.core.rk_loop.loop_of`, the ensemble drivers of
    :mod:`orbatt.core.dop853`) share a qualified name and their types, and two processes that
    compile the same kernels in the same order (a cold parallel start: pytest's or Dask's
    workers, the warm-up beside a run) give two variants the same count. A process that then
    loaded both ran one's callers on the other's code, silently (seen: an ensemble of DOP853
    runs integrated with the Verner loop, sweeps of wheel models failing every case). With a
    name per variant, two codes never share a name; the variants also get index files of
    their own in the cache."""
    cells = func.__closure__
    if not cells:
        return None
    try:
        digest = hashlib.sha256(dumps(tuple(c.cell_contents for c in cells))).hexdigest()[:12]
    except Exception:  # noqa: BLE001 - an empty cell, or contents numba cannot pickle either
        return None
    func.__qualname__ = f"{func.__qualname__}[{digest}]"
    return func.__qualname__


def _preset(**options):
    """An ``njit`` decorator with ``options`` whose dispatchers cache on disk through
    :class:`_CheckedCache` (numba's own cache where its cache class is not the one checked);
    closures are named by their variant first (:func:`variant_name`)."""
    decorate = nb.njit(cache=True, error_model="numpy", **options)

    def apply(func):
        if not nb.config.DISABLE_JIT:
            variant_name(func)
        dispatcher = decorate(func)
        if type(getattr(dispatcher, "_cache", None)) is FunctionCache:
            dispatcher._cache = _CheckedCache(dispatcher.py_func)
        return dispatcher

    return apply


#: the numba internals the fast loads of :class:`_CheckedCache` rely on are there (checked
#: with numba 0.68); ``ORBATT_FAST_LOADS=0`` or ``ORBATT_FAST_PATHS=0`` (:mod:`orbatt.fast_paths`)
#: turns them off
FAST_LOADS = (_FAST_PATHS and all(hasattr(FunctionCache, name)
                                  for name in ("_load_overload", "_guard_against_spurious_io_errors"))
              and os.environ.get("ORBATT_FAST_LOADS", "1") != "0")

#: a compiled kernel (cached on disk)
jit = _preset()
#: a kernel inlined into its callers at numba-IR level (small helpers of the hot loops)
jit_inline = _preset(inline="always")
#: a kernel with ``prange`` loops over ensemble members or groups
jit_parallel = _preset(parallel=True)

#: dimension of the state ``y = (q, Q)``
NDIM = 8
#: the smallest step / time ratio: steps below ``10 EPS max(|t|)`` end a run
EPS = float(np.finfo(np.float64).eps)

# ---------------------------------------------------------------------------------------
# Status codes returned by every step loop (adaptive and fixed-step)
DONE = 0            #: every output time reached
PAUSED = 1          #: step budget of this call used up; call again to continue
BUFFER_FULL = 2     #: record buffer full; grow it and call again
NONFINITE = 3       #: non-finite state/derivative that step reduction could not cure
STEP_TOO_SMALL = 4  #: step size underflow
MAX_STEPS = 5       #: ``max_steps`` step attempts used up

# ---------------------------------------------------------------------------------------
# Bits of the ``flags`` counter of the adaptive loops (``cnt[CNT_FLAGS]``)
FLAG_F0_VALID = 1      #: ``f0`` holds ``f(t, y)`` (FSAL derivative ready)
FLAG_REJECTED = 2      #: the last step attempt was rejected
FLAG_NONFINITE = 4     #: the last failure was a non-finite error estimate or derivative
FLAG_BITS = 0xFF       #: the flag bits proper
BAD_LANE_SHIFT = 8     #: lockstep groups: ``(flags >> BAD_LANE_SHIFT) - 1`` is the first failing lane


#: the kernels run as plain Python (``NUMBA_DISABLE_JIT=1``, set by :mod:`orbatt.coldstart`
#: for a first run on an empty compile cache): the same source, the same IEEE arithmetic and
#: libm calls, so the same bits (tested on the shipped scenarios), ~1000x slower per step.
#: Kernels keep that true by writing integer powers as products (numba multiplies, Python
#: calls pow) and by not calling ``math.hypot`` (CPython has its own, which differs from
#: numba's in the last bit for ~1 % of arguments)
INTERPRETED = bool(nb.config.DISABLE_JIT)
#: compiled loops pass borrowed views (:func:`borrow`; a fast path of :mod:`orbatt.fast_paths`)
BORROWED = _FAST_PATHS and not INTERPRETED

if INTERPRETED:
    def borrow(arr):
        """:func:`borrow` of the compiled kernels: in Python, the array itself."""
        return arr

    def keepalive(arr):
        """:func:`keepalive` of the compiled kernels: nothing to do in Python."""
        return None
elif not BORROWED:  # ORBATT_FAST_PATHS=0: reference-counted arrays, as numba passes them
    @jit_inline
    def borrow(arr):
        """:func:`borrow` with the fast paths off: the array itself."""
        return arr

    @jit_inline
    def keepalive(arr):
        """:func:`keepalive` with the fast paths off: nothing to do."""
        return None
else:
    @intrinsic
    def borrow(typingctx, arr):
        """A view of ``arr`` without a reference-counted owner (``meminfo = NULL``).

        numba increments and decrements the reference count of every array passed into a
        compiled call (an atomic operation, ~5-10 ns each, and a contended cache line when
        several threads share the array). Kernels here call the right-hand side 10^4-10^8 times
        with the same arrays; passing borrowed views makes those updates no-ops
        (``NRT_incref(NULL)`` returns at once): measured on the RHS of the torque-free case,
        105 ns -> 30 ns per call. Safe only while the caller keeps the owner alive, i.e. inside
        one kernel call on its own arguments; a borrowed view must never be returned or stored.
        """
        def codegen(context, builder, signature, args):
            src = context.make_array(arr)(context, builder, value=args[0])
            dst = context.make_array(arr)(context, builder)
            dst.meminfo = cgutils.get_null_value(dst.meminfo.type)
            dst.parent = cgutils.get_null_value(dst.parent.type)
            for name in ("nitems", "itemsize", "data", "shape", "strides"):
                setattr(dst, name, getattr(src, name))
            return dst._getvalue()

        return arr(arr), codegen

    @intrinsic
    def keepalive(typingctx, arr):
        """A use of ``arr`` that generates no code: numba frees a local array right after its last
        use, so an owner whose memory is used through :func:`borrow` views must be "used" again
        where those views die (the end of the kernel)."""
        def codegen(context, builder, signature, args):
            return context.get_dummy_value()

        return types.none(arr), codegen


@jit_inline
def borrow_model(terms, params, table, work):
    """:func:`borrow` views of the model ``terms, params, table`` and the scratch ``work``
    (what every step loop hands on to the right-hand side)."""
    return borrow(terms), borrow(params), borrow(table), borrow(work)

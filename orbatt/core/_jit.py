"""The one switch point of the compiled kernels: numba presets, intrinsics, status codes and
the named bits and slots of the resumable integrator state.

Every kernel of :mod:`orbatt.core` is compiled through one of the presets below, so changing
how the package compiles (caching, the error model, inlining) is a change here only.

Numerics: every kernel runs with ``error_model="numpy"`` (a division by zero gives inf/NaN,
which the step loops catch and reject, instead of raising).
"""
from __future__ import annotations

import numba as nb
import numpy as np
from numba.core import cgutils, types
from numba.extending import intrinsic

#: a compiled kernel (cached on disk)
jit = nb.njit(cache=True, error_model="numpy")
#: a kernel inlined into its callers at numba-IR level (small helpers of the hot loops)
jit_inline = nb.njit(cache=True, inline="always", error_model="numpy")
#: a kernel with ``prange`` loops over ensemble members or groups
jit_parallel = nb.njit(cache=True, parallel=True, error_model="numpy")

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


@jit_inline
def borrow_model(terms, params, table, work):
    """:func:`borrow` views of the model ``terms, params, table`` and the scratch ``work``
    (what every step loop hands on to the right-hand side)."""
    return borrow(terms), borrow(params), borrow(table), borrow(work)


@intrinsic
def keepalive(typingctx, arr):
    """A use of ``arr`` that generates no code: numba frees a local array right after its last
    use, so an owner whose memory is used through :func:`borrow` views must be "used" again
    where those views die (the end of the kernel)."""
    def codegen(context, builder, signature, args):
        return context.get_dummy_value()

    return types.none(arr), codegen

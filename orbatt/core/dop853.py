"""Compiled adaptive Runge-Kutta DOP853 on Hamilton's equations (eq. 7), whole step loop in
numba; one trajectory (:func:`advance`), an ensemble of independent members in parallel
(:func:`advance_batch`, each member bitwise as alone), or an ensemble in lockstep groups
(:func:`advance_lanes`, vectorized over the members of a group, see below).

Method: the explicit embedded Runge-Kutta pair of order 8(5,3) of Dormand & Prince, with the
error estimate and step-size control of Hairer's ``dop853.f`` (Hairer, Norsett & Wanner,
*Solving ODEs I*, 2nd ed., Sect. II.10): 12 stages, the last derivative reused as the first of
the next step (FSAL), error norm

    err = |h| e5 / sqrt(n (e5 + 0.01 e3)),  e5 = sum(((E5 . K)_i / sk_i)^2), e3 likewise,
    sk_i = atol_i + rtol max(|y_i|, |y_new_i|),   atol_i = atol (q), atol * max(I) (Q)

(scipy's ``DOP853`` norm, with the absolute tolerance of the momentum block scaled by the
largest moment of inertia: ``atol`` bounds the absolute error of ``q`` and of ``Q / max(I)``, a
body rate in rad per time unit, whatever the unit of ``Q`` - kg km^2 s^-1 makes ``Q`` ~1e-7 for
a small satellite and ~1e17 for a moon), new step
``h / clip(err^(1/8) / facold^0.04 / 0.9, 1/6, 1/0.333)`` (Hairer's PI control with
``beta = 0.04``: measured 2x fewer rejected steps than ``beta = 0``, same work-precision), no
increase right after a rejection. A non-finite error estimate rejects the step with
``h / 10``; a step size below 10 ulps of the time span ends the run (:data:`NONFINITE` if the
last failure was non-finite, else :data:`STEP_TOO_SMALL`).

Numerics notes: every kernel runs with ``error_model="numpy"`` (a division by zero gives
inf/NaN, caught as above, instead of raising); the arrays handed to the right-hand side are
:func:`borrow`-ed views (no reference-count traffic in the hot loop).

Output: the integrator lands exactly on every requested output time (the step before it is
shortened, the step size proposed before shortening is kept for the step after), so outputs
carry the full accuracy of step-end values - no interpolation (``DESIGN.md`` §4).
Alternatively every accepted step is recorded (``record_all``).

Resumable: the whole integrator state lives in small per-trajectory arrays (``y``, ``st``,
``cnt``, ``f0`` and the potential's ``work``), and :func:`advance` returns after ``budget``
step attempts; calling it again continues exactly as if it had not stopped (the Python
driver uses this for progress reports and for a clean stop on KeyboardInterrupt).

The coefficients below are module-level data (from Hairer's ``dop853.f``, 30 digits, as in
scipy's ``dop853_coefficients.py``).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np
from numba.core import cgutils
from numba.extending import intrinsic

from . import hamiltonian
from . import potentials as _pot
from .kepler import kepler_radial
from .qalg import qmul

#: :func:`orbatt.core.hamiltonian.rhs` (eq. 7), the same source compiled to be inlined into
#: the step loop (saves the call with ~45 argument words: 50 -> 41 ns per torque-free RHS)
rhs = nb.njit(inline="always")(hamiltonian.rhs.py_func)
#: :func:`orbatt.core.potentials.potential` and two of its kernels, compiled to be inlined
potential = nb.njit(inline="always")(_pot.potential.py_func)
_gravity_gradient = nb.njit(inline="always")(_pot.gravity_gradient.py_func)
_heavy_top = nb.njit(inline="always")(_pot.heavy_top.py_func)
_kinetic_rates = hamiltonian._a


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

    from numba.core import types

    return types.none(arr), codegen

# ---------------------------------------------------------------------------------------
# Coefficients (Butcher tableau). Stage s uses K[0..s-1]; K[12] is f(t + h, y_new) (FSAL).
N_STAGES = 12
ORDER = 8
ERROR_ORDER = 7  # the error estimate is O(h^8), exponent 1/8 in the controller

C = np.array([
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
])

A = np.zeros((N_STAGES, N_STAGES))
A[1, 0] = 5.26001519587677318785587544488e-2
A[2, 0] = 1.97250569845378994544595329183e-2
A[2, 1] = 5.91751709536136983633785987549e-2
A[3, 0] = 2.95875854768068491816892993775e-2
A[3, 2] = 8.87627564304205475450678981324e-2
A[4, 0] = 2.41365134159266685502369798665e-1
A[4, 2] = -8.84549479328286085344864962717e-1
A[4, 3] = 9.24834003261792003115737966543e-1
A[5, 0] = 3.7037037037037037037037037037e-2
A[5, 3] = 1.70828608729473871279604482173e-1
A[5, 4] = 1.25467687566822425016691814123e-1
A[6, 0] = 3.7109375e-2
A[6, 3] = 1.70252211019544039314978060272e-1
A[6, 4] = 6.02165389804559606850219397283e-2
A[6, 5] = -1.7578125e-2
A[7, 0] = 3.70920001185047927108779319836e-2
A[7, 3] = 1.70383925712239993810214054705e-1
A[7, 4] = 1.07262030446373284651809199168e-1
A[7, 5] = -1.53194377486244017527936158236e-2
A[7, 6] = 8.27378916381402288758473766002e-3
A[8, 0] = 6.24110958716075717114429577812e-1
A[8, 3] = -3.36089262944694129406857109825
A[8, 4] = -8.68219346841726006818189891453e-1
A[8, 5] = 2.75920996994467083049415600797e1
A[8, 6] = 2.01540675504778934086186788979e1
A[8, 7] = -4.34898841810699588477366255144e1
A[9, 0] = 4.77662536438264365890433908527e-1
A[9, 3] = -2.48811461997166764192642586468
A[9, 4] = -5.90290826836842996371446475743e-1
A[9, 5] = 2.12300514481811942347288949897e1
A[9, 6] = 1.52792336328824235832596922938e1
A[9, 7] = -3.32882109689848629194453265587e1
A[9, 8] = -2.03312017085086261358222928593e-2
A[10, 0] = -9.3714243008598732571704021658e-1
A[10, 3] = 5.18637242884406370830023853209
A[10, 4] = 1.09143734899672957818500254654
A[10, 5] = -8.14978701074692612513997267357
A[10, 6] = -1.85200656599969598641566180701e1
A[10, 7] = 2.27394870993505042818970056734e1
A[10, 8] = 2.49360555267965238987089396762
A[10, 9] = -3.0467644718982195003823669022
A[11, 0] = 2.27331014751653820792359768449
A[11, 3] = -1.05344954667372501984066689879e1
A[11, 4] = -2.00087205822486249909675718444
A[11, 5] = -1.79589318631187989172765950534e1
A[11, 6] = 2.79488845294199600508499808837e1
A[11, 7] = -2.85899827713502369474065508674
A[11, 8] = -8.87285693353062954433549289258
A[11, 9] = 1.23605671757943030647266201528e1
A[11, 10] = 6.43392746015763530355970484046e-1

#: weights of the 8th-order solution ``y_new = y + h sum(B_i K_i)``
B = np.zeros(N_STAGES)
B[0] = 5.42937341165687622380535766363e-2
B[5] = 4.45031289275240888144113950566
B[6] = 1.89151789931450038304281599044
B[7] = -5.8012039600105847814672114227
B[8] = 3.1116436695781989440891606237e-1
B[9] = -1.52160949662516078556178806805e-1
B[10] = 2.01365400804030348374776537501e-1
B[11] = 4.47106157277725905176885569043e-2

#: 3rd-order error estimate ``B - bhh`` (Hairer's ``bhh1, bhh2, bhh3`` on stages 1, 9, 12)
E3 = B.copy()
E3[0] -= 0.244094488188976377952755905512
E3[8] -= 0.733846688281611857341361741547
E3[11] -= 0.220588235294117647058823529412e-1

#: 5th-order error estimate (Hairer's ``er1, er6..er12``)
E5 = np.zeros(N_STAGES)
E5[0] = 0.1312004499419488073250102996e-1
E5[5] = -0.1225156446376204440720569753e+1
E5[6] = -0.4957589496572501915214079952
E5[7] = 0.1664377182454986536961530415e+1
E5[8] = -0.3503288487499736816886487290
E5[9] = 0.3341791187130174790297318841
E5[10] = 0.8192320648511571246570742613e-1
E5[11] = -0.2235530786388629525884427845e-1

# The nonzero entries of A, row by row (stage s uses A_VAL[A_PTR[s]:A_PTR[s+1]] on the
# stages A_COL[...]): the stage loop skips the zeros of the tableau.
A_PTR = np.zeros(N_STAGES + 1, dtype=np.int64)
A_COL = np.array([j for s in range(N_STAGES) for j in range(s) if A[s, j] != 0.0], dtype=np.int64)
A_VAL = np.array([A[s, j] for s in range(N_STAGES) for j in range(s) if A[s, j] != 0.0])
for _s in range(N_STAGES):
    A_PTR[_s + 1] = A_PTR[_s] + np.count_nonzero(A[_s, :_s])
del _s

# Step-size controller (Hairer's defaults for dop853): safety, bounds on h_new / h, exponent
SAFETY = 0.9
FAC_MIN = 0.333  # h_new >= FAC_MIN h   (Hairer's fac1)
FAC_MAX = 6.0    # h_new <= FAC_MAX h   (Hairer's fac2)
EXPONENT = 1.0 / 8.0
#: PI control: ``h_new = h / (err^EXPONENT / facold^BETA / SAFETY)`` (Hairer's ``beta``)
BETA = 0.04
#: a step lands on the next output time when it would otherwise stop within 1 % of it
LAND_MARGIN = 1.01

NDIM = 8

# ---------------------------------------------------------------------------------------
# Per-trajectory state arrays (resumable integrator). ``st`` (float64):
ST_T = 0          # current time
ST_H = 1          # step size to try next (0: choose one, Hairer's hinit)
ST_FACOLD = 2     # previous error (kept for a PI controller; beta = 0 in dop853)
ST_SIZE = 3
# ``cnt`` (int64):
CNT_STEPS = 0     # accepted steps
CNT_REJECTED = 1  # rejected steps (error too large or non-finite)
CNT_NFEV = 2      # right-hand-side evaluations
CNT_IOUT = 3      # index of the next output time
CNT_NREC = 4      # rows written to the record buffer (record_all mode)
CNT_FLAGS = 5     # bit 0: f0 holds f(t, y); bit 1: last attempt rejected; bit 2: last
#                   failure was a non-finite error estimate
CNT_SIZE = 6

# Status codes returned by the kernels
DONE = 0            # every output time reached
PAUSED = 1          # step budget of this call used up; call again to continue
BUFFER_FULL = 2     # record buffer full; grow it and call again
NONFINITE = 3       # non-finite state/derivative that step reduction could not cure
STEP_TOO_SMALL = 4  # step size underflow
MAX_STEPS = 5       # max_steps step attempts used up

_EPS = np.finfo(np.float64).eps


def new_state(batch=None):
    """Fresh ``(st, cnt, f0)`` arrays, for one trajectory or a ``batch`` of them."""
    shape = () if batch is None else (batch,)
    return (np.zeros(shape + (ST_SIZE,)), np.zeros(shape + (CNT_SIZE,), dtype=np.int64),
            np.zeros(shape + (NDIM,)))


@nb.njit(cache=True, inline="always")
def momentum_scale(inertia):
    """``max(I1, I2, I3)``: the absolute tolerance of ``Q`` is ``atol`` times this."""
    return max(inertia[0], max(inertia[1], inertia[2]))


@nb.njit(cache=True, error_model="numpy")
def _initial_step(t, y, f0, f1, ytmp, inertia, kind, params, table, work, rtol, atol, hmax):
    """Hairer's ``hinit`` (order 8): a first step from the sizes of ``y``, ``f`` and an
    estimate of the second derivative (one extra RHS evaluation)."""
    dnf = 0.0
    dny = 0.0
    aQ = atol * momentum_scale(inertia)
    for i in range(NDIM):
        sk = (atol if i < 4 else aQ) + rtol * abs(y[i])
        dnf += (f0[i] / sk) ** 2
        dny += (y[i] / sk) ** 2
    if dnf <= 1e-10 or dny <= 1e-10:
        h = 1.0e-6
    else:
        h = math.sqrt(dny / dnf) * 0.01
    h = min(h, hmax)
    if not (h > 0.0 and h < np.inf):
        return h
    for i in range(NDIM):
        ytmp[i] = y[i] + h * f0[i]
    rhs(t + h, ytmp, inertia, kind, params, table, work, f1)
    der2 = 0.0
    for i in range(NDIM):
        sk = (atol if i < 4 else aQ) + rtol * abs(y[i])
        der2 += ((f1[i] - f0[i]) / sk) ** 2
    der2 = math.sqrt(der2) / h
    der12 = max(abs(der2), math.sqrt(dnf))
    if der12 <= 1e-15:
        h1 = max(1.0e-6, abs(h) * 1.0e-3)
    else:
        h1 = (0.01 / der12) ** (1.0 / ORDER)
    return min(100.0 * abs(h), h1, hmax)


@nb.njit(cache=True, error_model="numpy")
def advance(y, st, cnt, f0, t_out, rec_t, out_y, record_all, inertia, kind, params, table,
            work, rtol, atol, max_step, max_steps, budget):
    """Advance one trajectory towards the output times ``t_out[cnt[CNT_IOUT]:]``.

    Parameters
    ----------
    y : (8,) state ``(q, Q)`` at ``st[ST_T]``; updated in place.
    st, cnt, f0 : per-trajectory integrator state (:func:`new_state`); updated in place.
    t_out : (N,) increasing output times, all after ``st[ST_T]``.
    rec_t, out_y : outputs. Default mode: ``out_y[i]`` (N, 8) receives ``y(t_out[i])``
        (``rec_t`` unused). ``record_all``: every accepted step appends its time to
        ``rec_t`` and its state to ``out_y`` (capacity ``len(rec_t)``; returns
        :data:`BUFFER_FULL` when full); integration stops at ``t_out[-1]``.
    inertia, kind, params, table, work : the problem (:mod:`orbatt.core.hamiltonian`).
    rtol, atol, max_step : tolerances (scipy's meaning) and the largest step allowed.
    max_steps : limit on step attempts (accepted + rejected) over the whole run.
    budget : step attempts allowed in this call.

    Returns a status code (:data:`DONE`, :data:`PAUSED`, ...).
    """
    nout = t_out.shape[0]
    Kown = np.empty((N_STAGES + 1, NDIM))
    tmpown = np.empty((2, NDIM))
    K = borrow(Kown)
    ytmp = borrow(tmpown[0])
    ynew = borrow(tmpown[1])
    y = borrow(y)
    f0 = borrow(f0)
    inertia = borrow(inertia)
    params = borrow(params)
    table = borrow(table)
    work = borrow(work)
    t = st[ST_T]
    h = st[ST_H]
    facold = st[ST_FACOLD]
    if facold <= 0.0:
        facold = 1.0e-4
    i_out = cnt[CNT_IOUT]
    flags = cnt[CNT_FLAGS]
    status = DONE
    if i_out >= nout:
        return DONE
    if (flags & 1) == 0:
        rhs(t, y, inertia, kind, params, table, work, f0)
        cnt[CNT_NFEV] += 1
        flags |= 1
    for i in range(NDIM):
        K[0, i] = f0[i]
    if h <= 0.0:
        h = _initial_step(t, y, f0, K[1], ytmp, inertia, kind, params, table, work, rtol, atol,
                          min(max_step, t_out[nout - 1] - t))
        cnt[CNT_NFEV] += 1
        if not (h > 0.0 and h < np.inf):
            h = 1e-6 * max(1.0, abs(t_out[nout - 1] - t))
    reject = (flags & 2) != 0
    attempts = 0
    # step-size floor: 10 ulps of the largest time involved (Hairer's test uses |t| only,
    # which lets a run starting at t = 0 crawl with steps of 1e-300)
    hmin = 10.0 * _EPS * max(abs(t), abs(t_out[nout - 1]))
    aQ = atol * momentum_scale(inertia)
    cap = rec_t.shape[0]
    while i_out < nout:
        if attempts >= budget:
            status = PAUSED
            break
        if cnt[CNT_STEPS] + cnt[CNT_REJECTED] >= max_steps:
            status = MAX_STEPS
            break
        if record_all and cnt[CNT_NREC] >= cap:
            status = BUFFER_FULL
            break
        t_next = t_out[i_out]
        hh = min(h, max_step)
        landing = False
        if t + LAND_MARGIN * hh >= t_next:
            hh = t_next - t
            landing = True
        if hh <= 0.0 or (hh <= hmin and not landing):
            status = NONFINITE if (flags & 4) != 0 else STEP_TOO_SMALL
            break
        # --- the 12 stages
        for s in range(1, N_STAGES):
            for i in range(NDIM):
                ytmp[i] = 0.0
            for jj in range(A_PTR[s], A_PTR[s + 1]):
                a = A_VAL[jj]
                j = A_COL[jj]
                for i in range(NDIM):
                    ytmp[i] += a * K[j, i]
            for i in range(NDIM):
                ytmp[i] = y[i] + hh * ytmp[i]
            rhs(t + C[s] * hh, ytmp, inertia, kind, params, table, work, K[s])
        cnt[CNT_NFEV] += N_STAGES - 1
        # --- 8th-order solution and error estimate
        e5 = 0.0
        e3 = 0.0
        for i in range(NDIM):
            acc = 0.0
            a5 = 0.0
            a3 = 0.0
            for j in range(N_STAGES):
                kji = K[j, i]
                acc += B[j] * kji
                a5 += E5[j] * kji
                a3 += E3[j] * kji
            ynew[i] = y[i] + hh * acc
            isk = 1.0 / ((atol if i < 4 else aQ) + rtol * max(abs(y[i]), abs(ynew[i])))
            a5 *= isk
            a3 *= isk
            e5 += a5 * a5
            e3 += a3 * a3
        deno = e5 + 0.01 * e3
        if deno <= 0.0:
            deno = 1.0
        err = abs(hh) * e5 * math.sqrt(1.0 / (NDIM * deno))
        attempts += 1
        if not (err < np.inf):  # NaN or inf: shrink hard and retry
            cnt[CNT_REJECTED] += 1
            flags |= 4
            reject = True
            h = 0.1 * hh
            continue
        fac11 = math.sqrt(math.sqrt(math.sqrt(err)))  # err ** EXPONENT (= 1/8)
        fac = fac11 / facold ** BETA if BETA != 0.0 else fac11
        fac = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, fac / SAFETY))
        hnew = hh / fac
        if err <= 1.0:
            # accepted: FSAL derivative at the new point
            if landing:
                t_new = t_next
            else:
                t_new = t + hh
            rhs(t_new, ynew, inertia, kind, params, table, work, K[N_STAGES])
            cnt[CNT_NFEV] += 1
            ok = True
            for i in range(NDIM):
                if not (abs(K[N_STAGES, i]) < np.inf):
                    ok = False
            if not ok:
                cnt[CNT_REJECTED] += 1
                flags |= 4
                reject = True
                h = 0.1 * hh
                continue
            flags &= ~4
            facold = max(err, 1.0e-4)
            cnt[CNT_STEPS] += 1
            t = t_new
            for i in range(NDIM):
                y[i] = ynew[i]
                K[0, i] = K[N_STAGES, i]
            hnew = min(hnew, max_step)
            if reject:
                hnew = min(hnew, hh)
            reject = False
            if landing:
                # the shortened step says little about the next one: keep the earlier proposal
                hnew = max(hnew, h)
                if not record_all:
                    for i in range(NDIM):
                        out_y[i_out, i] = y[i]
                i_out += 1
            if record_all:
                n = cnt[CNT_NREC]
                rec_t[n] = t
                for i in range(NDIM):
                    out_y[n, i] = y[i]
                cnt[CNT_NREC] = n + 1
            h = hnew
        else:
            cnt[CNT_REJECTED] += 1
            flags &= ~4
            reject = True
            h = hh / min(1.0 / FAC_MIN, fac11 / SAFETY)
    st[ST_T] = t
    st[ST_H] = h
    st[ST_FACOLD] = facold
    for i in range(NDIM):
        f0[i] = K[0, i]
    flags = (flags & ~2) | (2 if reject else 0)
    cnt[CNT_FLAGS] = flags
    cnt[CNT_IOUT] = i_out
    keepalive(Kown)
    keepalive(tmpown)
    return status


@nb.njit(cache=True, parallel=True, error_model="numpy")
def advance_batch(Y, ST, CNT, F0, t_out, out_y, status, inertia, kind, params, table, WORK,
                  rtol, atol, max_step, max_steps, budget):
    """:func:`advance` for an ensemble, in parallel over members (numba ``prange``).

    ``Y (E, 8)``, ``ST (E, ST_SIZE)``, ``CNT (E, CNT_SIZE)``, ``F0 (E, 8)``, ``WORK (E, w)``
    and ``inertia (E, 3)`` are per member; ``out_y (E, N, 8)``; ``status (E,)`` receives each
    member's status (members already :data:`DONE` are skipped). Every member runs exactly the
    code of :func:`advance`, so its result is identical to a one-by-one propagation.
    """
    E = Y.shape[0]
    rec_t = np.empty(0)
    for e in nb.prange(E):
        if CNT[e, CNT_IOUT] >= t_out.shape[0]:
            status[e] = DONE
            continue
        status[e] = advance(Y[e], ST[e], CNT[e], F0[e], t_out, rec_t, out_y[e], False, inertia[e],
                            kind, params, table, WORK[e], rtol, atol, max_step, max_steps, budget)


# ---------------------------------------------------------------------------------------
# Lockstep lanes: a group of L members advanced with one step size (ensembles)
#
# The members of a group share the time grid, so the orbit of an orbit-driven potential is
# evaluated once per stage for the whole group, and the per-member arithmetic (eq. 7 and the
# gradient) runs in loops over the lanes that LLVM vectorizes (structure-of-arrays layout
# ``(component, lane)``). The error of a step is the largest of the members' Hairer norms, so
# every member meets the tolerance it would meet alone; results agree with one-by-one runs
# to that tolerance, not bitwise (the step sizes differ). Measured RHS cost per member on
# the Keplerian case: 150 ns alone, 11 ns in a group of 16.


@nb.njit(cache=True, inline="always", error_model="numpy")
def _lane_store(dY, l, qd, Qd, g):
    dY[0, l] = 0.25 * qd[0]
    dY[1, l] = 0.25 * qd[1]
    dY[2, l] = 0.25 * qd[2]
    dY[3, l] = 0.25 * qd[3]
    dY[4, l] = 0.25 * Qd[0] - g[0]
    dY[5, l] = 0.25 * Qd[1] - g[1]
    dY[6, l] = 0.25 * Qd[2] - g[2]
    dY[7, l] = 0.25 * Qd[3] - g[3]


@nb.njit(cache=True, error_model="numpy")
def rhs_lanes(t, Y, nl, I, kind, params, table, work, dY):
    """Eq. (7) for lanes ``0..nl-1`` of ``Y (8, L)`` at the common time ``t`` (inertia
    ``I (3, L)``), into ``dY (8, L)``: the terms of :func:`orbatt.core.hamiltonian.rhs`,
    one loop per potential kind so that each loop vectorizes. Not inlined (one call serves a
    whole group; inlining it at every call site made the group kernels take 20-45 s to
    compile). Pass borrowed arrays (:func:`borrow`)."""
    if kind == _pot.GRAVITY_GRADIENT_KEPLER:
        r, xhat = kepler_radial(t, params[1:], work)
        k = params[0] / (r * r * r)
        for l in range(nl):
            q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
            Q = (Y[4, l], Y[5, l], Y[6, l], Y[7, l])
            inertia = (I[0, l], I[1, l], I[2, l])
            _, a = _kinetic_rates(q, Q, inertia)
            _, g = _gravity_gradient(q, inertia, k, xhat)
            _lane_store(dY, l, qmul(q, a), qmul(Q, a), g)
    elif kind == _pot.TORQUE_FREE:
        for l in range(nl):
            q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
            Q = (Y[4, l], Y[5, l], Y[6, l], Y[7, l])
            _, a = _kinetic_rates(q, Q, (I[0, l], I[1, l], I[2, l]))
            _lane_store(dY, l, qmul(q, a), qmul(Q, a), (0.0, 0.0, 0.0, 0.0))
    elif kind == _pot.HEAVY_TOP:
        for l in range(nl):
            q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
            Q = (Y[4, l], Y[5, l], Y[6, l], Y[7, l])
            _, a = _kinetic_rates(q, Q, (I[0, l], I[1, l], I[2, l]))
            _, g = _heavy_top(q, params)
            _lane_store(dY, l, qmul(q, a), qmul(Q, a), g)
    else:  # any other kind: the generic potential, member by member (orbit warm-started)
        for l in range(nl):
            q = (Y[0, l], Y[1, l], Y[2, l], Y[3, l])
            Q = (Y[4, l], Y[5, l], Y[6, l], Y[7, l])
            inertia = (I[0, l], I[1, l], I[2, l])
            _, a = _kinetic_rates(q, Q, inertia)
            _, g = potential(t, q, inertia, kind, params, table, work)
            _lane_store(dY, l, qmul(q, a), qmul(Q, a), g)


@nb.njit(cache=True, error_model="numpy")
def advance_group(Y, st, cnt, F0, t_out, out_y, inertia, kind, params, table, work, rtol, atol, max_step,
                  max_steps, budget):
    """:func:`advance` for a group of ``nl = Y.shape[0]`` members in lockstep.

    ``Y (nl, 8)``, ``F0 (nl, 8)``, ``inertia (nl, 3)``, ``out_y (nl, N, 8)`` are the group's
    members; ``st``, ``cnt``, ``work`` the group's (one time, one step size, one orbit). The
    counters count group steps and group RHS evaluations (multiply by ``nl`` for members).
    Returns a status code; on a failure ``cnt[CNT_FLAGS] >> 8`` is the first failing lane.
    """
    nl = Y.shape[0]
    nout = t_out.shape[0]
    i_out = cnt[CNT_IOUT]
    if i_out >= nout:
        return DONE
    params = borrow(params)
    table = borrow(table)
    work = borrow(work)
    # structure-of-arrays copies (lane index last)
    Kown = np.empty((N_STAGES + 1, NDIM, nl))
    tmpown = np.empty((3, NDIM, nl))
    Iown = np.empty((3, nl))
    K = borrow(Kown)
    yg = borrow(tmpown[0])
    ytmp = borrow(tmpown[1])
    ynew = borrow(tmpown[2])
    I = borrow(Iown)
    eown = np.empty((2, nl))
    e5 = borrow(eown[0])
    e3 = borrow(eown[1])
    for l in range(nl):
        for i in range(NDIM):
            yg[i, l] = Y[l, i]
            K[0, i, l] = F0[l, i]
        for i in range(3):
            I[i, l] = inertia[l, i]
    aQown = np.empty(nl)
    aQ = borrow(aQown)
    for l in range(nl):
        aQ[l] = atol * momentum_scale(inertia[l])
    t = st[ST_T]
    h = st[ST_H]
    facold = st[ST_FACOLD]
    if facold <= 0.0:
        facold = 1.0e-4
    flags = cnt[CNT_FLAGS] & 0xFF
    status = DONE
    if (flags & 1) == 0:
        rhs_lanes(t, yg, nl, I, kind, params, table, work, K[0])
        cnt[CNT_NFEV] += 1
        flags |= 1
    if h <= 0.0:
        # Hairer's hinit for each member; the smallest first step
        hmax = min(max_step, t_out[nout - 1] - t)
        h = hmax
        for l in range(nl):
            dnf = 0.0
            dny = 0.0
            for i in range(NDIM):
                sk = (atol if i < 4 else aQ[l]) + rtol * abs(yg[i, l])
                dnf += (K[0, i, l] / sk) ** 2
                dny += (yg[i, l] / sk) ** 2
            hl = 1.0e-6 if (dnf <= 1e-10 or dny <= 1e-10) else math.sqrt(dny / dnf) * 0.01
            h = min(h, hl)
        if h > 0.0 and h < np.inf:
            for l in range(nl):
                for i in range(NDIM):
                    ytmp[i, l] = yg[i, l] + h * K[0, i, l]
            rhs_lanes(t + h, ytmp, nl, I, kind, params, table, work, K[1])
            cnt[CNT_NFEV] += 1
            h0 = h
            h = hmax
            for l in range(nl):
                der2 = 0.0
                dnf = 0.0
                for i in range(NDIM):
                    sk = (atol if i < 4 else aQ[l]) + rtol * abs(yg[i, l])
                    der2 += ((K[1, i, l] - K[0, i, l]) / sk) ** 2
                    dnf += (K[0, i, l] / sk) ** 2
                der12 = max(math.sqrt(der2) / h0, math.sqrt(dnf))
                h1 = max(1.0e-6, h0 * 1.0e-3) if der12 <= 1e-15 else (0.01 / der12) ** (1.0 / ORDER)
                h = min(h, 100.0 * h0, h1)
        if not (h > 0.0 and h < np.inf):
            h = 1e-6 * max(1.0, abs(t_out[nout - 1] - t))
    reject = (flags & 2) != 0
    attempts = 0
    hmin = 10.0 * _EPS * max(abs(t), abs(t_out[nout - 1]))
    bad_lane = -1
    while i_out < nout:
        if attempts >= budget:
            status = PAUSED
            break
        if cnt[CNT_STEPS] + cnt[CNT_REJECTED] >= max_steps:
            status = MAX_STEPS
            break
        t_next = t_out[i_out]
        hh = min(h, max_step)
        landing = False
        if t + LAND_MARGIN * hh >= t_next:
            hh = t_next - t
            landing = True
        if hh <= 0.0 or (hh <= hmin and not landing):
            status = NONFINITE if (flags & 4) != 0 else STEP_TOO_SMALL
            break
        for s in range(1, N_STAGES):
            for i in range(NDIM):
                for l in range(nl):
                    ytmp[i, l] = 0.0
            for jj in range(A_PTR[s], A_PTR[s + 1]):
                a = A_VAL[jj]
                j = A_COL[jj]
                for i in range(NDIM):
                    for l in range(nl):
                        ytmp[i, l] += a * K[j, i, l]
            for i in range(NDIM):
                for l in range(nl):
                    ytmp[i, l] = yg[i, l] + hh * ytmp[i, l]
            rhs_lanes(t + C[s] * hh, ytmp, nl, I, kind, params, table, work, K[s])
        cnt[CNT_NFEV] += N_STAGES - 1
        for l in range(nl):
            e5[l] = 0.0
            e3[l] = 0.0
        for i in range(NDIM):
            for l in range(nl):
                acc = 0.0
                a5 = 0.0
                a3 = 0.0
                for j in range(N_STAGES):
                    kji = K[j, i, l]
                    acc += B[j] * kji
                    a5 += E5[j] * kji
                    a3 += E3[j] * kji
                ynew[i, l] = yg[i, l] + hh * acc
                isk = 1.0 / ((atol if i < 4 else aQ[l]) + rtol * max(abs(yg[i, l]), abs(ynew[i, l])))
                a5 *= isk
                a3 *= isk
                e5[l] += a5 * a5
                e3[l] += a3 * a3
        err = 0.0
        for l in range(nl):
            deno = e5[l] + 0.01 * e3[l]
            if deno <= 0.0:
                deno = 1.0
            el = abs(hh) * e5[l] * math.sqrt(1.0 / (NDIM * deno))
            if not (el < np.inf):
                err = np.inf
                bad_lane = l
                break
            err = max(err, el)
        attempts += 1
        if not (err < np.inf):
            cnt[CNT_REJECTED] += 1
            flags |= 4
            reject = True
            h = 0.1 * hh
            continue
        fac11 = math.sqrt(math.sqrt(math.sqrt(err)))
        fac = fac11 / facold ** BETA if BETA != 0.0 else fac11
        fac = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, fac / SAFETY))
        hnew = hh / fac
        if err <= 1.0:
            t_new = t_next if landing else t + hh
            rhs_lanes(t_new, ynew, nl, I, kind, params, table, work, K[N_STAGES])
            cnt[CNT_NFEV] += 1
            ok = True
            for l in range(nl):
                for i in range(NDIM):
                    if not (abs(K[N_STAGES, i, l]) < np.inf):
                        ok = False
                        bad_lane = l
            if not ok:
                cnt[CNT_REJECTED] += 1
                flags |= 4
                reject = True
                h = 0.1 * hh
                continue
            flags &= ~4
            facold = max(err, 1.0e-4)
            cnt[CNT_STEPS] += 1
            t = t_new
            for i in range(NDIM):
                for l in range(nl):
                    yg[i, l] = ynew[i, l]
                    K[0, i, l] = K[N_STAGES, i, l]
            hnew = min(hnew, max_step)
            if reject:
                hnew = min(hnew, hh)
            reject = False
            if landing:
                hnew = max(hnew, h)
                for l in range(nl):
                    for i in range(NDIM):
                        out_y[l, i_out, i] = yg[i, l]
                i_out += 1
            h = hnew
        else:
            cnt[CNT_REJECTED] += 1
            flags &= ~4
            reject = True
            h = hh / min(1.0 / FAC_MIN, fac11 / SAFETY)
    for l in range(nl):
        for i in range(NDIM):
            Y[l, i] = yg[i, l]
            F0[l, i] = K[0, i, l]
    st[ST_T] = t
    st[ST_H] = h
    st[ST_FACOLD] = facold
    flags = (flags & ~2) | (2 if reject else 0)
    cnt[CNT_FLAGS] = flags | ((bad_lane + 1) << 8)
    cnt[CNT_IOUT] = i_out
    keepalive(Kown)
    keepalive(tmpown)
    keepalive(Iown)
    keepalive(eown)
    keepalive(aQown)
    return status


@nb.njit(cache=True, parallel=True, error_model="numpy")
def advance_lanes(Y, ST, CNT, F0, t_out, out_y, status, inertia, kind, params, table, WORK, lanes, rtol, atol,
                  max_step, max_steps, budget):
    """:func:`advance_group` over the groups ``[g lanes, (g + 1) lanes)`` of an ensemble, in
    parallel over groups. ``ST, CNT, WORK, status`` have one row per group."""
    E = Y.shape[0]
    G = (E + lanes - 1) // lanes
    for gi in nb.prange(G):
        if CNT[gi, CNT_IOUT] >= t_out.shape[0]:
            status[gi] = DONE
            continue
        a = gi * lanes
        b = min(E, a + lanes)
        status[gi] = advance_group(Y[a:b], ST[gi], CNT[gi], F0[a:b], t_out, out_y[a:b], inertia[a:b], kind, params,
                                   table, WORK[gi], rtol, atol, max_step, max_steps, budget)

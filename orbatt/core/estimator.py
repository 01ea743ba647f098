"""Attitude sensors and the multiplicative extended Kalman filter on plain floats
(``docs/design.md`` §14, issue 33).

One kernel row of kind :data:`~orbatt.core.model.NAVIGATION` (:data:`NAV`) holds the sensors
and the filter of the flight software. It ticks at the gyro's period (the base tick of the
sensors; the star tracker samples every ``st_every`` ticks) with the flight software's slots
(:data:`orbatt.core.control.FLIGHT_SOFTWARE`), before the mode logic and the laws of the same
tick (:func:`orbatt.core.gyrostat.tick`). Its discrete state ``y[z0:z0 + NZ]`` (constant between
ticks) is :data:`STATE`:

* ``q_hat`` (4): the estimate, estimated body -> S (scalar first); ``b_hat`` (3): the gyro
  bias estimate (rad/s, body axes);
* ``P`` (36): the error covariance, row-major 6 x 6, of the error state ``x = (dtheta, dbeta)``
  with the **body-frame** convention ``q = q_hat (x) dq(dtheta)``, ``dq ~ (1, dtheta / 2)``
  (``dtheta`` rotates the estimated body axes onto the true ones; rad, body axes);
* ``beta`` (3): the gyro's true bias (rad/s), ``w_meas`` (3): the last gyro measurement
  (rad/s), ``q_meas`` (4): the last star tracker measurement (zeros before the first),
  ``valid``: 1 when the star tracker measured at the last tick, ``t_last``: that tick's time.

Models (Crassidis & Junkins, *Optimal Estimation of Dynamic Systems*, 2nd ed., §7.2;
Markley & Crassidis, *Fundamentals of Spacecraft Attitude Determination and Control*, 2014,
§6.2; Lefferts, Markley & Shuster 1982):

* gyro (Farrenkopf): ``beta_k+1 = beta_k + su sqrt(dt) N_u``, ``w_meas_k+1 = omega_k+1 +
  (beta_k+1 + beta_k) / 2 + sqrt(sv^2 / dt + su^2 dt / 12) N_v``; at the first tick
  ``w_meas_0 = omega_0 + beta_0 + sv / sqrt(dt) N_v``;
* star tracker: ``q_meas = q (x) [1, eta / 2]`` normalized, ``eta ~ N(0, diag(sx^2, sy^2,
  sroll^2))`` in body axes; no measurement when the Sun is within ``sun_exclusion`` of the
  boresight or the Earth's limb within ``earth_exclusion`` (a negative angle: no such check);
* MEKF: ``q_hat`` propagated with the rate ``w_hat = w_meas - b_hat`` held over the tick
  (``q_hat (x) exp(w_hat dt / 2)``, exact for a constant rate), ``P <- Phi P Phi^T + Qd`` with
  ``F = [[-[w_hat x], -I], [0, 0]]`` (``Phi`` in closed form) and ``Qd = [[sv^2 dt + su^2
  dt^3 / 3, -su^2 dt^2 / 2], [-su^2 dt^2 / 2, su^2 dt]] (x) I3``; the update with ``H = [I 0]``,
  ``R = diag(sx^2, sy^2, sroll^2)``, the residual ``2 sgn(d0) Im(d)``, ``d = q_hat~ q_meas``,
  the Joseph form for ``P`` and the multiplicative reset.

Noise comes from :mod:`orbatt.core.noise`, keyed on ``(seed, case, sensor, tick, axis)``: the
tick index ``k = round((t - phase) / period)``. Units: the caller's consistent system with time
in s and angles in rad (the densities ``sv`` in rad/s^(1/2), ``su`` in rad/s^(3/2)).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit, jit_inline
from . import noise
from .control import FLIGHT_SOFTWARE
from .qalg import qconj, qmul, rotate_inv
from .slots import Slots

__all__ = ["NAV", "STATE", "NZ", "VEC", "MAGNETOMETER", "SUN_SENSOR", "nav_params", "vector_params",
           "propagate_estimate", "covariance_step", "kalman_update", "attitude_update", "vector_update",
           "navigation_tick",
           "vector_tick", "estimate_feedback"]

#: the parameter layout of a navigation row (module docstring): the flight-software slots, the
#: noise key (``seed``, ``case``), the gyro (``gyro`` 1/0, ``arw`` sv, ``rrw`` su, the initial true
#: ``bias``), the star tracker (``st_every`` ticks, 0: none; ``st_noise`` per axis; ``boresight``
#: and the exclusion angles, rad, negative: none; the Earth's radius, km), the filter (``filter``
#: 1/0; initial 1-sigma ``attitude_sigma``, rad, and ``bias_sigma``, rad/s) and ``feedback`` (1:
#: the laws act on the estimate)
NAV = Slots(*FLIGHT_SOFTWARE, ("seed", 1), ("case", 1), ("gyro", 1), ("arw", 1), ("rrw", 1), ("bias", 3),
            ("st_every", 1), ("st_noise", 3), ("boresight", 3), ("sun_exclusion", 1), ("earth_exclusion", 1),
            ("earth_radius", 1), ("filter", 1), ("attitude_sigma", 1), ("bias_sigma", 1), ("feedback", 1),
            ("st_mis", 4))
#: the discrete state's layout (offsets from ``z0``; module docstring)
STATE = Slots(("q_hat", 4), ("b_hat", 3), ("P", 36), ("beta", 3), ("w_meas", 3), ("q_meas", 4), ("valid", 1),
              ("t_last", 1), ("st_ok", 1), ("vector", 1))
#: a vector sensor's row (:data:`~orbatt.core.model.VECTOR_SENSOR`, after the navigation row):
#: ``which`` (:data:`MAGNETOMETER` or :data:`SUN_SENSOR`), sampled every ``every`` base ticks,
#: 1-sigma ``noise`` per axis (T, or rad for the Sun sensor's unit vector) and the magnetometer's
#: ``bias`` (T, body axes: not estimated); its table: the field ``B`` or the Sun's position
VEC = Slots(("which", 1), ("every", 1), ("noise", 1), ("bias", 3))
MAGNETOMETER, SUN_SENSOR = 1, 2
#: the size of the state
NZ = STATE.size

_PERIOD, _PHASE, _Z0 = NAV.period, NAV.phase, NAV.z0
_SEED, _CASE, _GYRO, _ARW, _RRW, _BIAS = NAV.seed, NAV.case, NAV.gyro, NAV.arw, NAV.rrw, NAV.bias
_ST_EVERY, _ST_NOISE, _BORE, _SUN_EX, _EARTH_EX, _RE = (NAV.st_every, NAV.st_noise, NAV.boresight, NAV.sun_exclusion,
                                                         NAV.earth_exclusion, NAV.earth_radius)
_FILTER, _SIG_A, _SIG_B, _FEEDBACK = NAV.filter, NAV.attitude_sigma, NAV.bias_sigma, NAV.feedback
_ZQ, _ZB, _ZP, _ZBETA, _ZW, _ZQM, _ZVALID, _ZT = (STATE.q_hat, STATE.b_hat, STATE.P, STATE.beta, STATE.w_meas,
                                                  STATE.q_meas, STATE.valid, STATE.t_last)
_ZOK, _ZVEC = STATE.st_ok, STATE.vector
_ST_MIS = NAV.st_mis
_V_WHICH, _V_EVERY, _V_NOISE, _V_BIAS = VEC.which, VEC.every, VEC.noise, VEC.bias


def nav_params(period, z0, *, seed, case=0, gyro=None, star_tracker=None, filter=None, feedback=False,
               earth_radius=6378.137, phase=0.0):
    """The parameters of a navigation row (:data:`NAV`), internal units (s, rad, km).

    Parameters
    ----------
    period : float
        The base tick (s): the gyro's sample period, else the star tracker's.
    z0 : int
        Where the row's state (:data:`STATE`) lies in ``y``.
    seed, case : int
        The noise key (:mod:`orbatt.core.noise`).
    gyro : (arw, rrw, bias (3,)) or None
        ``sv`` (rad/s^(1/2)), ``su`` (rad/s^(3/2)), the initial true bias (rad/s).
    star_tracker : (every, noise (3,), boresight (3,), sun_exclusion, earth_exclusion, mis (4,)) or None
        Sample every ``every`` ticks; 1-sigma noise per body axis (rad); the unit boresight
        (body); exclusion half-angles (rad; negative: none); its mounting's misalignment, the
        quaternion ``m`` of ``q_meas = q (x) m (x) [1, eta / 2]`` (unknown to the filter).
    filter : (attitude_sigma, bias_sigma) or None
        The MEKF's initial 1-sigma errors (rad, rad/s); the initial estimate's error is drawn
        from ``attitude_sigma``.
    feedback : bool
        The laws act on the estimate (``q_hat``, ``w_meas - b_hat``) instead of the truth.
    """
    if not period > 0.0:
        raise ValueError("navigation: the base tick must be > 0")
    g = (0.0, 0.0, (0.0, 0.0, 0.0)) if gyro is None else gyro
    st = (0, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), -1.0, -1.0, (1.0, 0.0, 0.0, 0.0)) if star_tracker is None else \
        star_tracker
    f = (0.0, 0.0) if filter is None else filter
    return NAV.pack(period=period, phase=phase, z0=float(z0), nz=float(NZ), mode=-1.0, seed=float(seed),
                    case=float(case), gyro=0.0 if gyro is None else 1.0, arw=g[0], rrw=g[1], bias=g[2],
                    st_every=float(st[0]), st_noise=st[1], boresight=st[2], sun_exclusion=st[3],
                    earth_exclusion=st[4], earth_radius=earth_radius, filter=0.0 if filter is None else 1.0,
                    attitude_sigma=f[0], bias_sigma=f[1], feedback=1.0 if feedback else 0.0, st_mis=st[5])


def vector_params(which, every, noise, bias=(0.0, 0.0, 0.0)):
    """The parameters of a vector sensor's row (:data:`VEC`)."""
    return VEC.pack(which=float(which), every=float(every), noise=float(noise), bias=bias)


@jit_inline
def _small_rotation(v):
    """The unit quaternion ``[1, v / 2]`` normalized (a small rotation by the vector ``v``, rad)."""
    n = math.sqrt(1.0 + 0.25 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
    return (1.0 / n, 0.5 * v[0] / n, 0.5 * v[1] / n, 0.5 * v[2] / n)


@jit_inline
def _normalized(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


@jit_inline
def propagate_estimate(q, w, dt):
    """``q (x) exp(w dt / 2)``: the attitude ``q`` (body -> S) turned by the constant body rate
    ``w`` (rad/s) for ``dt`` (s), normalized."""
    n = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    half = 0.5 * n * dt
    if n > 0.0:
        s = math.sin(half) / n
    else:
        s = 0.5 * dt
    return _normalized(qmul(q, (math.cos(half), s * w[0], s * w[1], s * w[2])))


@jit_inline
def _mm(A, B):
    """The product ``A B`` written out (no BLAS: the same bits on any CPU)."""
    n, m, p = A.shape[0], A.shape[1], B.shape[1]
    C = np.zeros((n, p))
    for i in range(n):
        for k in range(p):
            acc = 0.0
            for j in range(m):
                acc += A[i, j] * B[j, k]
            C[i, k] = acc
    return C


@jit
def covariance_step(P, w, dt, sv, su):
    """``P <- Phi P Phi^T + Qd`` in place (``P``: the covariance, 36 floats row-major, a view
    into the state; module docstring) for the estimated rate ``w`` (rad/s) held over ``dt`` (s)
    and the gyro's densities ``sv``, ``su``. ``Phi = [[A, B], [0, I]]`` is formed in closed form and
    the products are written out on its blocks (two scratch arrays; no BLAS)."""
    n = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    x = n * dt
    if x > 1e-4:
        a = math.sin(x) / n
        b = (1.0 - math.cos(x)) / (n * n)
        c = (x - math.sin(x)) / (n * n * n)
    else:  # the series (relative error below 1e-13 there)
        a = dt * (1.0 - x * x / 6.0)
        b = dt * dt * (0.5 - x * x / 24.0)
        c = dt * dt * dt * (1.0 / 6.0 - x * x / 120.0)
    # W = [w x], W2 = W W = w w^T - |w|^2 I
    W = ((0.0, -w[2], w[1]), (w[2], 0.0, -w[0]), (-w[1], w[0], 0.0))
    n2 = n * n
    Phi = np.zeros(36)  # row-major 6 x 6
    for i in range(3):
        for k in range(3):
            eye = 1.0 if i == k else 0.0
            w2 = w[i] * w[k] - n2 * eye
            Phi[6 * i + k] = eye - a * W[i][k] + b * w2
            Phi[6 * i + 3 + k] = b * W[i][k] - dt * eye - c * w2
        Phi[6 * (3 + i) + 3 + i] = 1.0
    M = np.empty(36)  # Phi P
    for i in range(6):
        for k in range(6):
            acc = 0.0
            for j in range(6):
                acc += Phi[6 * i + j] * P[6 * j + k]
            M[6 * i + k] = acc
    for i in range(6):  # (Phi P) Phi^T, the lower triangle
        for k in range(i + 1):
            acc = 0.0
            for j in range(6):
                acc += M[6 * i + j] * Phi[6 * k + j]
            P[6 * i + k] = acc
    q11 = sv * sv * dt + su * su * dt * dt * dt / 3.0
    q12 = -0.5 * su * su * dt * dt
    q22 = su * su * dt
    for i in range(3):
        P[6 * i + i] += q11
        P[6 * (3 + i) + i] += q12
        P[6 * (3 + i) + 3 + i] += q22
    for i in range(6):  # symmetric by construction
        for k in range(i):
            P[6 * k + i] = P[6 * i + k]


@jit
def kalman_update(q, b, P, H, res, var):
    """The MEKF's update with three measurements: ``H (3, 6)``, the residual ``res (3)`` and
    their noise variances ``var (3)`` (``R = diag(var)``): ``(q, b)`` reset multiplicatively and
    returned, ``P (6, 6)`` in place (the Joseph form; ``S^-1`` by cofactors: no BLAS or LAPACK,
    the same bits on any CPU)."""
    PHt = _mm(P, H.T.copy())
    S = _mm(H, PHt)
    for i in range(3):
        S[i, i] += var[i]
    c00 = S[1, 1] * S[2, 2] - S[1, 2] * S[2, 1]
    c01 = S[0, 2] * S[2, 1] - S[0, 1] * S[2, 2]
    c02 = S[0, 1] * S[1, 2] - S[0, 2] * S[1, 1]
    c11 = S[0, 0] * S[2, 2] - S[0, 2] * S[2, 0]
    c12 = S[0, 2] * S[1, 0] - S[0, 0] * S[1, 2]
    c22 = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
    det = S[0, 0] * c00 + S[1, 0] * c01 + S[2, 0] * c02
    Si = np.empty((3, 3))
    Si[0, 0], Si[0, 1], Si[0, 2] = c00 / det, c01 / det, c02 / det
    Si[1, 0], Si[1, 1], Si[1, 2] = c01 / det, c11 / det, c12 / det
    Si[2, 0], Si[2, 1], Si[2, 2] = c02 / det, c12 / det, c22 / det
    K = _mm(PHt, Si)
    dx = np.zeros(6)
    for i in range(6):
        dx[i] = K[i, 0] * res[0] + K[i, 1] * res[1] + K[i, 2] * res[2]
    IKH = np.eye(6) - _mm(K, H)
    KR = K.copy()
    for i in range(6):
        for k in range(3):
            KR[i, k] *= var[k]
    new = _mm(_mm(IKH, P), IKH.T.copy()) + _mm(KR, K.T.copy())
    for i in range(6):
        for k in range(6):
            P[i, k] = 0.5 * (new[i, k] + new[k, i])
    qn = _normalized(qmul(q, _small_rotation((dx[0], dx[1], dx[2]))))
    return qn, (b[0] + dx[3], b[1] + dx[4], b[2] + dx[5])


@jit
def attitude_update(q, b, P, q_meas, sigma):
    """The MEKF's update with an attitude measurement ``q_meas`` (body -> S) of 1-sigma
    ``sigma (3)`` (rad, body axes): ``H = [I 0]``, the residual ``2 sgn(d0) Im(d)``, ``d = q~
    q_meas`` (:func:`kalman_update`)."""
    d = qmul(qconj(q), q_meas)
    sg = 2.0 if d[0] >= 0.0 else -2.0
    H = np.zeros((3, 6))
    for i in range(3):
        H[i, i] = 1.0
    return kalman_update(q, b, P, H, (sg * d[1], sg * d[2], sg * d[3]),
                         (sigma[0] * sigma[0], sigma[1] * sigma[1], sigma[2] * sigma[2]))


@jit_inline
def _angle(a, b):
    """The angle (rad) between the unit vectors ``a`` and ``b``."""
    c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    return math.acos(max(-1.0, min(1.0, c)))


@jit_inline
def _unit(v):
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] / n, v[1] / n, v[2] / n)


@jit_inline
def _star_tracker_sees(q, params, p0, r, xhat, sun):
    """Whether the star tracker measures at the attitude ``q``: the Sun (inertial position
    ``sun``, km; zeros: unknown) and the Earth's limb (the orbit's ``r xhat``) outside their
    exclusion angles from the boresight."""
    bore = (params[p0 + _BORE], params[p0 + _BORE + 1], params[p0 + _BORE + 2])
    sun_ex = params[p0 + _SUN_EX]
    if sun_ex >= 0.0 and (sun[0] != 0.0 or sun[1] != 0.0 or sun[2] != 0.0):
        s = rotate_inv(q, _unit((sun[0] - r * xhat[0], sun[1] - r * xhat[1], sun[2] - r * xhat[2])))
        if _angle(bore, s) < sun_ex:
            return False
    earth_ex = params[p0 + _EARTH_EX]
    if earth_ex >= 0.0 and r > 0.0:
        e = rotate_inv(q, (-xhat[0], -xhat[1], -xhat[2]))
        radius = math.asin(min(1.0, params[p0 + _RE] / r))
        if _angle(bore, e) - radius < earth_ex:
            return False
    return True


@jit
def navigation_tick(t, y, q, omega, r, xhat, sun, params, p0, start):
    """The sensors and the filter of the navigation row at ``params[p0]`` at its tick ``t`` on
    the true attitude ``q`` and body rate ``omega`` (module docstring), the orbit's ``r xhat``
    and the Sun's position ``sun`` (km; zeros: none): sample the gyro, propagate the filter from
    its last tick, sample the star tracker when due and visible and update; the state
    ``y[z0:z0 + NZ]`` written. ``start``: the first tick of a run (the true bias, the estimate
    drawn about the truth, the covariance)."""
    z = int(params[p0 + _Z0])
    dt = params[p0 + _PERIOD]
    k = math.floor((t - params[p0 + _PHASE]) / dt + 0.5)
    seed, case = params[p0 + _SEED], params[p0 + _CASE]
    sv, su = params[p0 + _ARW], params[p0 + _RRW]
    has_filter = params[p0 + _FILTER] > 0.0
    if params[p0 + _GYRO] > 0.0:
        if start:
            nv = sv / math.sqrt(dt)
            for i in range(3):
                b = params[p0 + _BIAS + i]
                y[z + _ZBETA + i] = b
                y[z + _ZW + i] = omega[i] + b + nv * noise.normal(seed, case, noise.GYRO_RATE, k, i)
        else:
            nv = math.sqrt(sv * sv / dt + su * su * dt / 12.0)
            nu = su * math.sqrt(dt)
            # the filter propagates over [t_last, t] with the measurement of t_last
            if has_filter:
                w_hat = (y[z + _ZW] - y[z + _ZB], y[z + _ZW + 1] - y[z + _ZB + 1], y[z + _ZW + 2] - y[z + _ZB + 2])
                h = t - y[z + _ZT]
                qh = propagate_estimate((y[z + _ZQ], y[z + _ZQ + 1], y[z + _ZQ + 2], y[z + _ZQ + 3]), w_hat, h)
                for i in range(4):
                    y[z + _ZQ + i] = qh[i]
                covariance_step(y[z + _ZP:z + _ZP + 36], w_hat, h, sv, su)
            for i in range(3):
                old = y[z + _ZBETA + i]
                new = old + nu * noise.normal(seed, case, noise.GYRO_BIAS, k, i)
                y[z + _ZBETA + i] = new
                y[z + _ZW + i] = omega[i] + 0.5 * (new + old) + nv * noise.normal(seed, case, noise.GYRO_RATE, k, i)
    if has_filter and start:
        sa, sb = params[p0 + _SIG_A], params[p0 + _SIG_B]
        e = (sa * noise.normal(seed, case, noise.INITIAL_ESTIMATE, k, 0.0),
             sa * noise.normal(seed, case, noise.INITIAL_ESTIMATE, k, 1.0),
             sa * noise.normal(seed, case, noise.INITIAL_ESTIMATE, k, 2.0))
        qh = _normalized(qmul(q, _small_rotation(e)))  # q_hat = q (x) dq(e): e is -dtheta
        for i in range(4):
            y[z + _ZQ + i] = qh[i]
        for i in range(36):
            y[z + _ZP + i] = 0.0
        for i in range(3):
            y[z + _ZB + i] = 0.0
            y[z + _ZP + 7 * i] = sa * sa
            y[z + _ZP + 7 * (3 + i)] = sb * sb
    y[z + _ZVALID] = 0.0
    y[z + _ZVEC] = 0.0
    every = params[p0 + _ST_EVERY]
    due = every > 0.0 and k - every * math.floor(k / every) == 0.0
    if due:
        y[z + _ZOK] = 0.0
    if due and _star_tracker_sees(q, params, p0, r, xhat, sun):
        y[z + _ZOK] = 1.0
        sig = (params[p0 + _ST_NOISE], params[p0 + _ST_NOISE + 1], params[p0 + _ST_NOISE + 2])
        eta = (sig[0] * noise.normal(seed, case, noise.STAR_TRACKER, k, 0.0),
               sig[1] * noise.normal(seed, case, noise.STAR_TRACKER, k, 1.0),
               sig[2] * noise.normal(seed, case, noise.STAR_TRACKER, k, 2.0))
        mis = (params[p0 + _ST_MIS], params[p0 + _ST_MIS + 1], params[p0 + _ST_MIS + 2], params[p0 + _ST_MIS + 3])
        qm = _normalized(qmul(qmul(q, mis), _small_rotation(eta)))
        if qm[0] < 0.0:
            qm = (-qm[0], -qm[1], -qm[2], -qm[3])
        for i in range(4):
            y[z + _ZQM + i] = qm[i]
        y[z + _ZVALID] = 1.0
        if has_filter:
            P = y[z + _ZP:z + _ZP + 36].copy().reshape(6, 6)
            qh, bh = attitude_update((y[z + _ZQ], y[z + _ZQ + 1], y[z + _ZQ + 2], y[z + _ZQ + 3]),
                                     (y[z + _ZB], y[z + _ZB + 1], y[z + _ZB + 2]), P, qm, sig)
            y[z + _ZP:z + _ZP + 36] = P.ravel()
            for i in range(4):
                y[z + _ZQ + i] = qh[i]
            for i in range(3):
                y[z + _ZB + i] = bh[i]
    y[z + _ZT] = t


@jit_inline
def estimate_feedback(y, params, p0, q, omega):
    """``(q, omega)`` the laws act on: the estimate ``q_hat`` and ``w_meas - b_hat`` when the
    navigation row at ``p0`` feeds back its estimate (``p0 < 0``: none), else the truth."""
    if p0 < 0 or params[p0 + _FEEDBACK] == 0.0:
        return q, omega
    z = int(params[p0 + _Z0])
    return ((y[z + _ZQ], y[z + _ZQ + 1], y[z + _ZQ + 2], y[z + _ZQ + 3]),
            (y[z + _ZW] - y[z + _ZB], y[z + _ZW + 1] - y[z + _ZB + 1], y[z + _ZW + 2] - y[z + _ZB + 2]))


@jit
def vector_update(q, b, P, pred, meas, sigma):
    """The MEKF's update with a vector measurement ``meas`` (body axes) of the predicted
    ``pred`` (the reference vector in the estimated body axes), 1-sigma ``sigma`` per axis:
    ``H = [[pred x] 0]`` (``b_true = pred + pred x dtheta``; :func:`kalman_update`)."""
    H = np.zeros((3, 6))
    H[0, 1], H[0, 2], H[1, 2] = -pred[2], pred[1], -pred[0]
    H[1, 0], H[2, 0], H[2, 1] = pred[2], -pred[1], pred[0]
    v = sigma * sigma
    return kalman_update(q, b, P, H, (meas[0] - pred[0], meas[1] - pred[1], meas[2] - pred[2]), (v, v, v))


@jit_inline
def _sunlit(r, xhat, sun, earth_radius):
    """Whether the spacecraft at ``r xhat`` sees the Sun at ``sun`` (km, inertial): outside the
    Earth's cylindrical shadow."""
    s = _unit(sun)
    along = r * (xhat[0] * s[0] + xhat[1] * s[1] + xhat[2] * s[2])
    if along >= 0.0:
        return True
    px, py, pz = r * xhat[0] - along * s[0], r * xhat[1] - along * s[1], r * xhat[2] - along * s[2]
    return px * px + py * py + pz * pz >= earth_radius * earth_radius


@jit
def vector_tick(t, y, q, r, xhat, ref, params, p0, pv):
    """A vector sensor's sample at the navigation row's tick ``t`` (row ``params[p0]``; the
    sensor's row at ``pv``) on the true attitude ``q`` and its reference ``ref`` (inertial: the
    field ``B``, T, or the Sun's position, km): when due, measured (the Sun sensor: not in the
    Earth's shadow) and, when the filter runs and the star tracker's last sample failed (or
    there is none), the filter updated; ``y[z0 + vector]`` counts the updates of this tick."""
    z = int(params[p0 + _Z0])
    if params[p0 + _FILTER] == 0.0:
        return
    dt = params[p0 + _PERIOD]
    k = math.floor((t - params[p0 + _PHASE]) / dt + 0.5)
    every = params[pv + _V_EVERY]
    if k - every * math.floor(k / every) != 0.0:
        return
    if params[p0 + _ST_EVERY] > 0.0 and y[z + _ZOK] > 0.0:  # the star tracker measures: no vector update
        return
    which = params[pv + _V_WHICH]
    sensor = noise.MAGNETOMETER if which == MAGNETOMETER else noise.SUN_SENSOR
    if which == SUN_SENSOR:
        if not _sunlit(r, xhat, ref, params[p0 + _RE]):
            return
        ref = _unit((ref[0] - r * xhat[0], ref[1] - r * xhat[1], ref[2] - r * xhat[2]))
    seed, case = params[p0 + _SEED], params[p0 + _CASE]
    sig = params[pv + _V_NOISE]
    truth = rotate_inv(q, ref)
    meas = (truth[0] + params[pv + _V_BIAS] + sig * noise.normal(seed, case, sensor, k, 0.0),
            truth[1] + params[pv + _V_BIAS + 1] + sig * noise.normal(seed, case, sensor, k, 1.0),
            truth[2] + params[pv + _V_BIAS + 2] + sig * noise.normal(seed, case, sensor, k, 2.0))
    if which == SUN_SENSOR:
        meas = _unit(meas)
    qh = (y[z + _ZQ], y[z + _ZQ + 1], y[z + _ZQ + 2], y[z + _ZQ + 3])
    pred = rotate_inv(qh, ref)
    P = y[z + _ZP:z + _ZP + 36].copy().reshape(6, 6)
    qn, bn = vector_update(qh, (y[z + _ZB], y[z + _ZB + 1], y[z + _ZB + 2]), P, pred, meas, sig)
    y[z + _ZP:z + _ZP + 36] = P.ravel()
    for i in range(4):
        y[z + _ZQ + i] = qn[i]
    for i in range(3):
        y[z + _ZB + i] = bn[i]
    y[z + _ZVEC] += 1.0

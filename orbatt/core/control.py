"""Attitude control laws and reaction wheels on plain floats (``docs/design.md`` §10).

Units are the caller's consistent system (orbatt's internal kg, km, s, rad: torques in
kg km^2 s^-2 = 1e6 N m, dipoles in 1e-6 A m^2 so that ``m x B`` with ``B`` in T is such a
torque). Vectors are 3-tuples in **body axes** unless named ``_s`` (inertial): the principal
axes ``P`` of a full inertia tensor, whose per-axis limits clip along the user's axes ``B``
(the rows' :data:`LIMIT_FRAME`, :func:`clip_in_body_axes`).

Parameter layouts (rows of the term list, :mod:`orbatt.core.model`)
----------------------------------------------------------------
Each layout is named once (:class:`~orbatt.core.slots.Slots`), shared by the packer and the
kernels (which take the offsets as folded constants):

* reaction wheels (:data:`~orbatt.core.model.WHEELS`): :func:`wheel_params`: ``[n]`` then
  :data:`WHEEL` per wheel: unit spin ``axis``, axial moment of the rotor ``iw``, motor torque
  limit ``u_max`` and speed limit ``speed_max`` (relative to the body; ``inf``: none).
* PD control (:data:`~orbatt.core.model.PD_CONTROL`): :func:`pd_params`, :data:`PD`:
  ``target, kp, kd, max_torque, actuator, c (4)``, then for wheels the tail ``pinv``: the
  ``(n, 3)`` pseudo-inverse of the ``(3, n)`` matrix of spin axes; ``c`` is the target
  quaternion (``target = inertial``: target -> S; ``target = orbital`` / ``nadir``: target -> O
  / N, identity by default) or the body axis to point at the Sun or a ground point.
* magnetorquers making the PD law's torque (:data:`~orbatt.core.model.MAGNETORQUERS`, the
  companion row after it): :func:`magnetorquer_params`, :data:`MAGNETORQUER`: ``max_dipole``.
* B-dot (:data:`~orbatt.core.model.BDOT_CONTROL`): :func:`bdot_params`, :data:`BDOT`:
  ``gain, max_dipole``.

The PD law (``q_e = q_t~ q``, ``tau = -kp sgn(q_e0) Im(q_e) - kd (omega - omega_t)``, each
axis clipped to ``tau_max``) with the targets:

* ``orbital``: ``q_t = p c``, the orbital frame O of the orbit's ``(r, v)`` (``docs/design.md`` §1)
  turned by the constant offset ``c`` (identity: hold O itself), and ``omega_t = (r x v) / r^2``
  in body axes: O's rate about its normal, which the offset frame shares (exact for a Keplerian
  orbit; its component along ``o1``, from an acceleration off the orbit plane, is left out:
  below 2e-6 rad/s for J2 in LEO).
* ``inertial``: a constant ``q_t``, ``omega_t = 0``.
* ``sun``: ``q_e`` the shortest rotation taking the Sun's direction (body axes) onto the body
  axis ``b``, ``omega_t = 0`` (the Sun's apparent motion, ~2e-7 rad/s, is left out).
* ``ground``: the same toward a point on the rotating Earth, the line of sight's rate fed forward.
* ``nadir``: ``q_t = p_N c``, the geodetic nadir frame N (:func:`nadir_target`: O with ``o1``
  replaced by the WGS84 ellipsoid's normal through the spacecraft, from the row's table).

With ``actuator = wheels`` the commanded torque is made by the wheels: motor torques
``u = -A+ tau`` (each clipped to ``u_max``, and to zero when it would push a wheel past
``speed_max``); the body feels ``-A u``, an internal torque: the total angular momentum
does not change. With ``actuator = magnetorquers``: ``m = (B_B x tau) / |B_B|^2`` (each axis
clipped to ``m_max``), the external torque ``m x B_B``: the command's part normal to the field
(:func:`torque_dipole`). B-dot: ``m = -k dB_B/dt`` (each axis clipped to ``m_max``) with
``dB_B/dt = q~ dB_S/dt q - omega x B_B``; ``tau = m x B_B``.
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit_inline
from .qalg import cross, mat_t_vec, mat_vec, qconj, qmul, rotate_inv
from . import mode_state
from .slots import Slots

#: PD targets
TARGET_ORBITAL, TARGET_INERTIAL, TARGET_SUN, TARGET_GROUND, TARGET_NADIR = 0, 1, 2, 3, 4
#: actuators of the PD law
ACTUATOR_IDEAL, ACTUATOR_WHEELS, ACTUATOR_MAGNETORQUERS = 0, 1, 2
#: the slots every control law's row starts with (the flight software, issue 32): its
#: ``period`` (s; 0: a continuous law), the origin ``phase`` of its tick grid (``t_k = phase +
#: k period``), where its held command lies in the state (``z0``: ``y[z0:z0 + nz]``, after the
#: wheels' momenta) and its size ``nz`` (0 for a continuous law)
FLIGHT_SOFTWARE = (("period", 1), ("phase", 1), ("z0", 1), ("nz", 1), ("mode", 1))
#: the slots of a law that clips per axis (issue 32 item 6): ``framed`` (1: the body frame ``B`` of a
#: full inertia tensor differs from the principal frame ``P`` the kernels integrate in; 0: it does
#: not: the arithmetic it always took) and ``axes``, the matrix ``R`` (row-major, ``x_B = R x_P``)
#: along whose ``B`` axes the limits clip (:func:`clip_in_body_axes`)
LIMIT_FRAME = (("framed", 1), ("axes", 9))
#: the parameter layouts (module docstring): one wheel, the PD law, B-dot
WHEEL = Slots(("axis", 3), ("iw", 1), ("u_max", 1), ("speed_max", 1), ("coulomb", 1), ("viscous", 1), ("width", 1))
PD = Slots(*FLIGHT_SOFTWARE, ("target", 1), ("kp", 1), ("kd", 1), ("max_torque", 1), ("actuator", 1), ("c", 4),
           ("max_rate", 1), ("ki", 1), ("zi", 1), *LIMIT_FRAME, tail="pinv")
BDOT = Slots(*FLIGHT_SOFTWARE, ("gain", 1), ("max_dipole", 1), *LIMIT_FRAME)
#: a mode sequence (:data:`~orbatt.core.model.MODES`, issue 32 item 4): its state ``y[z0:z0 + 4 + count]``
#: is laid out in :mod:`orbatt.core.mode_state`; ``count`` modes, then per mode the
#: tail :data:`MODE_FIELDS`: leave after ``until_time`` in the mode, or once ``|omega| <
#: until_rate`` or the attitude error ``< until_settled`` (rad) has held for ``hold`` (``inf``:
#: no such condition; any condition met leaves; the last mode stays)
MODES = Slots(*FLIGHT_SOFTWARE, ("count", 1), tail="conditions")
MODE_FIELDS = 4
MODE_UNTIL_TIME, MODE_UNTIL_RATE, MODE_UNTIL_SETTLED, MODE_HOLD = 0, 1, 2, 3
#: the flight-software slots, the same in every law's row (``mode``: the row acts in that
#: mode of the sequence only; -1: always)
CTL_PERIOD, CTL_PHASE, CTL_Z0, CTL_NZ, CTL_MODE = PD.period, PD.phase, PD.z0, PD.nz, PD.mode
assert (BDOT.period, BDOT.phase, BDOT.z0, BDOT.nz, BDOT.mode) == (CTL_PERIOD, CTL_PHASE, CTL_Z0, CTL_NZ, CTL_MODE)
assert (MODES.period, MODES.phase, MODES.z0, MODES.nz, MODES.mode) == (CTL_PERIOD, CTL_PHASE, CTL_Z0, CTL_NZ,
                                                                       CTL_MODE)
#: the floats of one wheel, and of the PD law before the wheels' pseudo-inverse
WHEEL_SIZE = WHEEL.size
PD_HEADER = PD.size
# the slot offsets as module constants: numba folds them into the kernels as literals
_W_AXIS, _W_IW, _W_UMAX, _W_SMAX = WHEEL.axis, WHEEL.iw, WHEEL.u_max, WHEEL.speed_max
_W_COULOMB, _W_VISCOUS, _W_WIDTH = WHEEL.coulomb, WHEEL.viscous, WHEEL.width
_PD_TARGET, _PD_KP, _PD_KD, _PD_TMAX, _PD_C, _PD_PINV = PD.target, PD.kp, PD.kd, PD.max_torque, PD.c, PD.pinv
_PD_MAXRATE, _PD_KI, _PD_ZI = PD.max_rate, PD.ki, PD.zi
_PD_FRAMED, _PD_AXES = PD.framed, PD.axes
#: the slot of the PD law's actuator (``params[p0 + PD_ACTUATOR]``)
PD_ACTUATOR = PD.actuator
_BD_GAIN, _BD_MMAX = BDOT.gain, BDOT.max_dipole
_BD_FRAMED, _BD_AXES = BDOT.framed, BDOT.axes


def limit_frame(axes):
    """The :data:`LIMIT_FRAME` slots: ``axes`` the ``(3, 3)`` matrix ``R`` of a full inertia
    tensor's principal axes (``x_B = R x_P``), or None (``P = B``: ``framed = 0``)."""
    if axes is None:
        return dict(framed=0.0, axes=np.eye(3))
    R = np.asarray(axes, dtype=np.float64)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)) or np.abs(R @ R.T - np.eye(3)).max() > 1e-12:
        raise ValueError(f"axes: {R.tolist()} is not a rotation matrix")
    return dict(framed=1.0, axes=R)


def wheel_params(axes, inertia, max_torque, max_speed, coulomb=0.0, viscous=0.0, width=1.0):
    """The parameters of a :data:`~orbatt.core.model.WHEELS` row: unit spin axes ``(n, 3)``
    (body), axial moments ``(n,)``, motor torque limits and speed limits ``(n,)`` (``inf``:
    none)."""
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 3)
    n = axes.shape[0]
    iw, um, sm, fc, fv, fw = (np.broadcast_to(np.asarray(x, dtype=np.float64).ravel(), (n,))
                              for x in (inertia, max_torque, max_speed, coulomb, viscous, width))
    rows = [WHEEL.pack(axis=axes[k], iw=iw[k], u_max=um[k], speed_max=sm[k], coulomb=fc[k], viscous=fv[k],
                       width=fw[k]) for k in range(n)]
    return np.concatenate([[float(n)], *rows])


def modes_params(period, z0, conditions, phase=0.0):
    """The parameters of a :data:`~orbatt.core.model.MODES` row: the flight software's
    ``period`` (0: continuous laws, the transitions located on the solution:
    :mod:`orbatt.core.mode_events`), its state at ``y[z0:]`` (:mod:`orbatt.core.mode_state`),
    and ``conditions (n, MODE_FIELDS)``."""
    c = np.asarray(conditions, dtype=np.float64).reshape(-1, MODE_FIELDS)
    return MODES.pack(tail=c, count=float(c.shape[0]), nz=float(mode_state.state_size(c.shape[0])), mode=-1.0,
                      **flight_software(period, phase, z0))


def flight_software(period=0.0, phase=0.0, z0=8):
    """The flight-software slots of a law's row (:data:`FLIGHT_SOFTWARE`) but ``nz``: a
    continuous law (``period = 0``) or one evaluated at the ticks ``phase + k period`` whose
    command is held in ``y[z0:]``."""
    if not (period >= 0.0 and np.isfinite(period)):
        raise ValueError(f"period: {period!r} must be finite and >= 0")
    return dict(period=float(period), phase=float(phase), z0=float(z0))


def law_slots(nz, mode=-1):
    """The rest of a law's flight-software slots: its state's size ``nz`` and its ``mode``."""
    return dict(nz=float(nz), mode=float(mode))


def pd_params(target, kp, kd, max_torque, target_values=(1.0, 0.0, 0.0, 0.0), wheel_axes=None, period=0.0,
              phase=0.0, z0=8, max_rate=np.inf, ki=0.0, magnetorquers=False, axes=None):
    """The parameters of a :data:`~orbatt.core.model.PD_CONTROL` row. ``target``: one of
    the ``TARGET_*`` constants; ``target_values``:
    the target quaternion (relative to the orbital frame for ``TARGET_ORBITAL``; default
    identity) or the body axis (padded to 4); ``wheel_axes (n, 3)``: actuate with
    these wheels (their axes must span the three dimensions), else an ideal torque;
    ``period, phase, z0``: :func:`flight_software` (the held command: the torque, 3, or the
    wheels' motor torques, n); ``max_rate``: the rate limit of the eigenaxis slew (``inf``:
    none; needs ``kd > 0``); ``ki``: the integral gain (0: none), whose integral of the
    error (3) follows the held command in the state (``zi``); ``magnetorquers``: the torque is
    made by magnetorquers (:data:`ACTUATOR_MAGNETORQUERS`; the row is followed by its
    :data:`MAGNETORQUER` row, :func:`magnetorquer_params`; the held command is the dipole, 3);
    ``axes``: the principal axes ``R`` of a full inertia tensor, along whose body axes
    ``max_torque`` and the magnetorquers' limit clip (:data:`LIMIT_FRAME`; None: the row's axes
    are the body axes)."""
    c = np.zeros(4)
    tv = np.asarray(target_values, dtype=np.float64).ravel()
    c[:tv.size] = tv
    if magnetorquers and wheel_axes is not None:
        raise ValueError("one actuator: wheels or magnetorquers")
    if target not in (TARGET_SUN, TARGET_GROUND) and not abs(np.linalg.norm(c) - 1.0) < 1e-9:
        raise ValueError(f"the target quaternion {c.tolist()} is not a unit quaternion")
    fs = flight_software(period, phase, z0)
    if not (max_rate > 0.0) or (max_rate < np.inf and not kd > 0.0):
        raise ValueError(f"max_rate: {max_rate!r} must be positive, with kd > 0")
    if not (ki >= 0.0 and np.isfinite(ki)):
        raise ValueError(f"ki: {ki!r} must be finite and >= 0")
    ncmd = (3 if wheel_axes is None else np.asarray(wheel_axes).reshape(-1, 3).shape[0]) if fs["period"] > 0 else 0
    nint = 3 if ki > 0.0 else 0
    head = dict(target=float(target), kp=kp, kd=kd, max_torque=max_torque,
                actuator=(ACTUATOR_MAGNETORQUERS if magnetorquers else ACTUATOR_IDEAL if wheel_axes is None else
                          ACTUATOR_WHEELS), c=c,
                max_rate=float(max_rate), ki=float(ki), **law_slots(ncmd + nint),
                zi=fs["z0"] + ncmd if nint else -1.0, **limit_frame(axes), **fs)
    if wheel_axes is None:
        return PD.pack(**head)
    A = np.asarray(wheel_axes, dtype=np.float64).reshape(-1, 3).T  # (3, n)
    if np.linalg.matrix_rank(A) < 3:
        raise ValueError("the wheels' spin axes do not span three dimensions")
    return PD.pack(tail=np.linalg.pinv(A), **head)


def bdot_params(gain, max_dipole, period=0.0, phase=0.0, z0=8, axes=None):
    """The parameters of a :data:`~orbatt.core.model.BDOT_CONTROL` row (:data:`BDOT`;
    ``period, phase, z0``: :func:`flight_software`, the held command: the dipole, 3; ``axes``:
    :func:`limit_frame`)."""
    fs = flight_software(period, phase, z0)
    return BDOT.pack(gain=gain, max_dipole=max_dipole, **law_slots(3 if fs["period"] > 0 else 0),
                     **limit_frame(axes), **fs)


@jit_inline
def clip(x, limit):
    """``x`` limited to ``[-limit, limit]``."""
    return min(max(x, -limit), limit)


@jit_inline
def clip_in_body_axes(v, limit, params, a):
    """The vector ``v`` (``P`` components) with each of its ``B`` components clipped to
    ``limit``, in ``P`` components: ``R^T clip(R v)`` (a full inertia tensor's per-body-axis
    limit; ``R`` at ``params[a]``)."""
    b = mat_vec(params, a, v)
    return mat_t_vec(params, a, (clip(b[0], limit), clip(b[1], limit), clip(b[2], limit)))


@jit_inline
def frame_quaternion(o1, o2, o3):
    """The quaternion mapping frame components to inertial ones for the frame whose axes have
    the inertial components ``o1, o2, o3`` (Shepperd's method, scalar part >= 0)."""
    m00, m11, m22 = o1[0], o2[1], o3[2]
    tr = m00 + m11 + m22
    if tr >= m00 and tr >= m11 and tr >= m22:
        w = 0.5 * math.sqrt(1.0 + tr)
        f = 0.25 / w
        return (w, (o2[2] - o3[1]) * f, (o3[0] - o1[2]) * f, (o1[1] - o2[0]) * f)
    if m00 >= m11 and m00 >= m22:
        x = 0.5 * math.sqrt(1.0 + 2.0 * m00 - tr)
        f = 0.25 / x
        q = ((o2[2] - o3[1]) * f, x, (o2[0] + o1[1]) * f, (o3[0] + o1[2]) * f)
    elif m11 >= m22:
        y = 0.5 * math.sqrt(1.0 + 2.0 * m11 - tr)
        f = 0.25 / y
        q = ((o3[0] - o1[2]) * f, (o2[0] + o1[1]) * f, y, (o3[1] + o2[2]) * f)
    else:
        z = 0.5 * math.sqrt(1.0 + 2.0 * m22 - tr)
        f = 0.25 / z
        q = ((o1[1] - o2[0]) * f, (o3[0] + o1[2]) * f, (o3[1] + o2[2]) * f, z)
    if q[0] < 0.0:
        return (-q[0], -q[1], -q[2], -q[3])
    return q


@jit_inline
def orbital_target(r, xhat, v):
    """``(p, omega_s)``: the orbital frame's quaternion (O -> S) and its rate (inertial) at the
    position ``r xhat`` and velocity ``v``."""
    hx = r * (xhat[1] * v[2] - xhat[2] * v[1])
    hy = r * (xhat[2] * v[0] - xhat[0] * v[2])
    hz = r * (xhat[0] * v[1] - xhat[1] * v[0])
    hn = math.sqrt(hx * hx + hy * hy + hz * hz)
    o3 = (hx / hn, hy / hn, hz / hn)
    o2 = cross(o3, xhat)
    r2 = r * r
    return frame_quaternion(xhat, o2, o3), (hx / r2, hy / r2, hz / r2)


@jit_inline
def nadir_target(r, xhat, v, up, up_rate):
    """``(p, omega_s)``: the geodetic nadir frame N (N -> S) and its rate (inertial) at the
    position ``r xhat``, velocity ``v``, for the geodetic vertical ``up`` (the WGS84 ellipsoid's
    outward normal through the spacecraft, inertial; normalized here) and its rate ``up_rate``.

    N is the orbital frame with the geocentric radial replaced by the geodetic vertical:
    ``n1 = up`` (so ``-n1`` points at the geodetic nadir), ``n3 = (n1 x v) / |n1 x v|`` (the
    orbit normal tilted with ``n1``), ``n2 = n3 x n1`` (the velocity's projection normal to
    ``n1``). Where ``up`` is radial, N is O. Its rate: the part normal to ``n1`` exactly,
    ``n1 x dn1/dt``, from the table's rate of ``up``; the part about ``n1`` is the orbital
    frame's ``(r x v) / r^2`` projected on ``n1`` (N turns about ``n1`` as O does to first order;
    the remainder ~ flattening x orbit rate x its rate of change, below 1e-8 rad/s in LEO)."""
    un = math.sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2])
    n1 = (up[0] / un, up[1] / un, up[2] / un)
    c3 = cross(n1, v)
    cn = math.sqrt(c3[0] * c3[0] + c3[1] * c3[1] + c3[2] * c3[2])
    n3 = (c3[0] / cn, c3[1] / cn, c3[2] / cn)
    n2 = cross(n3, n1)
    d = cross(n1, up_rate)
    hx = r * (xhat[1] * v[2] - xhat[2] * v[1])
    hy = r * (xhat[2] * v[0] - xhat[0] * v[2])
    hz = r * (xhat[0] * v[1] - xhat[1] * v[0])
    r2 = r * r
    a = (hx * n1[0] + hy * n1[1] + hz * n1[2]) / r2
    return frame_quaternion(n1, n2, n3), (d[0] / un + a * n1[0], d[1] / un + a * n1[1], d[2] / un + a * n1[2])


@jit_inline
def pointing_error(s_b, b):
    """The shortest rotation taking the unit vector ``s_b`` onto ``b`` (both body axes), as a
    unit quaternion; about any axis normal to ``b`` when they are opposite."""
    c = s_b[0] * b[0] + s_b[1] * b[1] + s_b[2] * b[2]
    x = cross(s_b, b)
    w = 1.0 + c
    n = math.sqrt(w * w + x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    if n < 1e-12:  # opposite: half a turn about an axis normal to b
        k = (1.0, 0.0, 0.0) if abs(b[0]) < 0.9 else (0.0, 1.0, 0.0)
        x = cross(b, k)
        m = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        return (0.0, x[0] / m, x[1] / m, x[2] / m)
    return (w / n, x[0] / n, x[1] / n, x[2] / n)


@jit_inline
def pd_error(q, params, p0, r, xhat, v, aux, aux_rate):
    """``(e, omega_t)``: the PD law's attitude error ``sgn(q_e0) Im(q_e)`` and the target's rate
    (body axes) for the attitude ``q``; the orbit's ``r, xhat, v`` serve the orbital target,
    ``aux`` (inertial, km) the Sun's position or a ground target's, ``aux_rate`` (km/s) the
    ground target's velocity: the body axis ``c`` is pointed along the line of sight ``d = aux -
    r xhat``, and for a ground target ``omega_t`` is the line of sight's rate ``d x d' / |d|^2``
    (the feed-forward; the Sun's apparent rate, ~2e-7 rad/s, is left out). For the geodetic
    nadir ``aux`` is the geodetic vertical (a unit vector, inertial) and ``aux_rate`` its rate
    (:func:`nadir_target`)."""
    target = params[p0 + _PD_TARGET]
    c = p0 + _PD_C
    wt = (0.0, 0.0, 0.0)
    if target == TARGET_GROUND:
        dx = aux[0] - r * xhat[0]
        dy = aux[1] - r * xhat[1]
        dz = aux[2] - r * xhat[2]
        d2 = dx * dx + dy * dy + dz * dz
        d = math.sqrt(d2)
        s_b = rotate_inv(q, (dx / d, dy / d, dz / d))
        qe = pointing_error(s_b, (params[c], params[c + 1], params[c + 2]))
        ex, ey, ez = aux_rate[0] - v[0], aux_rate[1] - v[1], aux_rate[2] - v[2]
        wt = rotate_inv(q, ((dy * ez - dz * ey) / d2, (dz * ex - dx * ez) / d2, (dx * ey - dy * ex) / d2))
    elif target == TARGET_SUN:
        dx = aux[0] - r * xhat[0]
        dy = aux[1] - r * xhat[1]
        dz = aux[2] - r * xhat[2]
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        s_b = rotate_inv(q, (dx / d, dy / d, dz / d))
        qe = pointing_error(s_b, (params[c], params[c + 1], params[c + 2]))
    else:
        if target == TARGET_ORBITAL:  # the frame O turned by the constant offset c (O -> target)
            p, wt_s = orbital_target(r, xhat, v)
            qt = qmul(p, (params[c], params[c + 1], params[c + 2], params[c + 3]))
            wt = rotate_inv(q, wt_s)
        elif target == TARGET_NADIR:  # the geodetic nadir frame N turned by the offset c (N -> target)
            p, wt_s = nadir_target(r, xhat, v, aux, aux_rate)
            qt = qmul(p, (params[c], params[c + 1], params[c + 2], params[c + 3]))
            wt = rotate_inv(q, wt_s)
        else:
            qt = (params[c], params[c + 1], params[c + 2], params[c + 3])
        qe = qmul(qconj(qt), q)
    sg = 1.0 if qe[0] >= 0.0 else -1.0
    return (sg * qe[1], sg * qe[2], sg * qe[3]), wt


@jit_inline
def pd_torque(q, omega, params, p0, r, xhat, v, aux, aux_rate, y):
    """``(tau, raw, e)``: the PD law's commanded torque (body axes, each axis clipped to
    ``max_torque``), the same before the clip, and its attitude error (:func:`pd_error`), for
    the attitude ``q`` and body rate ``omega``. A row with a limit frame (:data:`LIMIT_FRAME`,
    ``framed``, and a finite ``max_torque``) clips along the body axes of ``B`` and returns
    ``raw`` and ``e`` in ``B`` components, in which its integral ``y[zi:zi + 3]`` is held (the
    anti-windup gate of each body axis then reads them as it reads a principal row's):

    * ``tau = -kp e - kd (omega - omega_t)`` (quaternion feedback);
    * with ``max_rate``: the rate-limited eigenaxis slew of Wie, Weiss & Arapostathis (1989),
      ``tau = -kd (omega - omega_t - omega_c)``, ``omega_c = -(kp / kd) e`` scaled down to
      ``|omega_c| <= max_rate`` (the same law where the limit is not reached);
    * with ``ki``: ``- ki s``, ``s = y[zi:zi + 3]`` the integral of ``e`` (:func:`pd_integral_rate`).
    """
    kp = params[p0 + _PD_KP]
    kd = params[p0 + _PD_KD]
    tmax = params[p0 + _PD_TMAX]
    e, wt = pd_error(q, params, p0, r, xhat, v, aux, aux_rate)
    mr = params[p0 + _PD_MAXRATE]
    if mr < np.inf:
        g = kp / kd
        c0, c1, c2 = -g * e[0], -g * e[1], -g * e[2]
        n = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        if n > mr:
            f = mr / n
            c0, c1, c2 = c0 * f, c1 * f, c2 * f
        t0 = -kd * (omega[0] - wt[0] - c0)
        t1 = -kd * (omega[1] - wt[1] - c1)
        t2 = -kd * (omega[2] - wt[2] - c2)
    else:
        t0 = -kp * e[0] - kd * (omega[0] - wt[0])
        t1 = -kp * e[1] - kd * (omega[1] - wt[1])
        t2 = -kp * e[2] - kd * (omega[2] - wt[2])
    ki = params[p0 + _PD_KI]
    if params[p0 + _PD_FRAMED] != 0.0 and tmax < np.inf:  # the limit along the body axes B of a tensor
        a = p0 + _PD_AXES
        if ki > 0.0:  # the integral is held in B components (its anti-windup gate acts per body axis)
            zi = int(params[p0 + _PD_ZI])
            s = mat_t_vec(params, a, (y[zi], y[zi + 1], y[zi + 2]))
            t0 -= ki * s[0]
            t1 -= ki * s[1]
            t2 -= ki * s[2]
        raw = (t0, t1, t2)
        return clip_in_body_axes(raw, tmax, params, a), mat_vec(params, a, raw), mat_vec(params, a, e)
    if ki > 0.0:
        zi = int(params[p0 + _PD_ZI])
        t0 -= ki * y[zi]
        t1 -= ki * y[zi + 1]
        t2 -= ki * y[zi + 2]
    return (clip(t0, tmax), clip(t1, tmax), clip(t2, tmax)), (t0, t1, t2), e


@jit_inline
def windup_gate(raw, e, ki, tmax):
    """The rate of the integral of one axis's error ``e`` under conditional integration (anti-
    windup): ``e``, or 0 while the command ``raw`` is beyond ``tmax`` and ``e`` would drive it
    further (``d raw = -ki e dt``)."""
    if (raw > tmax and e < 0.0) or (raw < -tmax and e > 0.0):
        return 0.0
    return e


@jit_inline
def wheel_friction(omega, y, params, wheels0, k):
    """The friction torque on wheel ``k``'s rotor (opposing its speed relative to the body):
    ``coulomb tanh(speed / width) + viscous speed`` (Basilisk's ``reactionWheelStateEffector``
    model, its Coulomb sign smoothed over ``width`` so that the step loop does not chatter near
    zero speed); an internal torque: ``dh_k/dt -= f``, the total momentum unchanged."""
    w = wheels0 + 1 + WHEEL_SIZE * k
    c = params[w + _W_COULOMB]
    b = params[w + _W_VISCOUS]
    if c == 0.0 and b == 0.0:
        return 0.0
    speed = y[8 + k] / params[w + _W_IW] - (params[w + _W_AXIS] * omega[0] + params[w + _W_AXIS + 1] * omega[1]
                                            + params[w + _W_AXIS + 2] * omega[2])
    return c * math.tanh(speed / params[w + _W_WIDTH]) + b * speed


@jit_inline
def wheel_commands(tau, params, pd0, wheels0, u):
    """The wheels' motor torques ``u`` (written, one per wheel) that make the body torque
    ``tau``: ``-A+ tau``, each clipped to its motor's limit (the PD row's tail, :data:`PD`
    ``pinv``; the wheels from ``params[wheels0]``)."""
    for k in range(u.shape[0]):
        pk = pd0 + _PD_PINV + 3 * k
        uk = -(params[pk] * tau[0] + params[pk + 1] * tau[1] + params[pk + 2] * tau[2])
        u[k] = clip(uk, params[wheels0 + 1 + WHEEL_SIZE * k + _W_UMAX])


@jit_inline
def wheel_reaction(omega, y, params, wheels0, u):
    """The torque the body feels from the motor torques ``u`` (a command, held or not):
    ``-A u``, after zeroing (in ``u``) a torque that would push a wheel past its speed limit.
    ``y[8 + k]`` is wheel ``k``'s axial momentum."""
    tb = (0.0, 0.0, 0.0)
    for k in range(u.shape[0]):
        w = wheels0 + 1 + WHEEL_SIZE * k
        a = (params[w + _W_AXIS], params[w + _W_AXIS + 1], params[w + _W_AXIS + 2])
        uk = u[k]
        speed = y[8 + k] / params[w + _W_IW] - (a[0] * omega[0] + a[1] * omega[1] + a[2] * omega[2])
        smax = params[w + _W_SMAX]
        if (speed >= smax and uk > 0.0) or (speed <= -smax and uk < 0.0):
            uk = 0.0
        u[k] = uk
        tb = (tb[0] - uk * a[0], tb[1] - uk * a[1], tb[2] - uk * a[2])
    return tb


@jit_inline
def wheel_torques(tau, omega, y, params, pd0, wheels0, u):
    """Make the body torque ``tau`` with the wheels: the motor torques ``u`` (written; one per
    wheel, clipped to the motor and speed limits: :func:`wheel_commands`, then
    :func:`wheel_reaction`) and the torque the body feels, ``-A u`` (returned)."""
    wheel_commands(tau, params, pd0, wheels0, u)
    return wheel_reaction(omega, y, params, wheels0, u)


@jit_inline
def bdot_dipole(q, omega, b_s, bdot_s, params, p0):
    """``(m, B_B)``: the B-dot dipole (body axes, each axis clipped to the row's
    ``max_dipole``; along ``B``'s axes with a limit frame, :data:`LIMIT_FRAME`) and the field in body axes, from the field ``b_s`` and its rate ``bdot_s``
    along the orbit (inertial); the row's parameters at ``params[p0]`` (:data:`BDOT`)."""
    gain = params[p0 + _BD_GAIN]
    mmax = params[p0 + _BD_MMAX]
    b = rotate_inv(q, b_s)
    db = rotate_inv(q, bdot_s)
    wb = cross(omega, b)
    if params[p0 + _BD_FRAMED] != 0.0:  # the limit along the body axes B of a tensor
        m = (-gain * (db[0] - wb[0]), -gain * (db[1] - wb[1]), -gain * (db[2] - wb[2]))
        return clip_in_body_axes(m, mmax, params, p0 + _BD_AXES), b
    return (clip(-gain * (db[0] - wb[0]), mmax), clip(-gain * (db[1] - wb[1]), mmax),
            clip(-gain * (db[2] - wb[2]), mmax)), b


# ---------------------------------------------------------------------------------------
# Momentum management (issue 32 item 5): magnetorquers dump the wheels' momentum

#: the layout of a :data:`~orbatt.core.model.MOMENTUM_DUMP` row (it follows the PD law's row
#: on wheels): the flight-software slots (the law's period; its held dipole, 3, after the PD
#: law's state), the gain ``k`` (1/s) and the magnetorquers' per-axis limit
DUMP = Slots(*FLIGHT_SOFTWARE, ("gain", 1), ("max_dipole", 1), *LIMIT_FRAME)
assert (DUMP.period, DUMP.phase, DUMP.z0, DUMP.nz) == (CTL_PERIOD, CTL_PHASE, CTL_Z0, CTL_NZ)
_DU_GAIN, _DU_MMAX, _DU_FRAMED, _DU_AXES = DUMP.gain, DUMP.max_dipole, DUMP.framed, DUMP.axes


def dump_params(gain, max_dipole, period=0.0, phase=0.0, z0=8, axes=None):
    """The parameters of a :data:`~orbatt.core.model.MOMENTUM_DUMP` row (:data:`DUMP`): the
    gain ``k`` (1/s), the per-axis dipole limit (internal units), ``period, phase, z0``:
    :func:`flight_software` (the held command: the dipole, 3); ``axes``: :func:`limit_frame`."""
    if not (gain > 0.0 and np.isfinite(gain)):
        raise ValueError(f"gain: {gain!r} must be finite and positive")
    if not max_dipole > 0.0:
        raise ValueError(f"max_dipole: {max_dipole!r} must be positive")
    fs = flight_software(period, phase, z0)
    return DUMP.pack(gain=float(gain), max_dipole=float(max_dipole), **law_slots(3 if fs["period"] > 0 else 0),
                     **limit_frame(axes), **fs)


@jit_inline
def wheels_momentum(y, params, w0):
    """The wheels' momentum ``h = sum h_k a_k`` (body axes; ``y[8 + k]`` the axial momenta,
    the wheels' parameters from ``params[w0]``; zero without wheels), summed as
    :func:`orbatt.core.gyrostat.body_rate` sums it."""
    h0 = h1 = h2 = 0.0
    if w0 < 0:
        return (h0, h1, h2)
    for k in range(int(params[w0])):
        w = w0 + 1 + WHEEL_SIZE * k
        hk = y[8 + k]
        h0 += hk * params[w + _W_AXIS]
        h1 += hk * params[w + _W_AXIS + 1]
        h2 += hk * params[w + _W_AXIS + 2]
    return (h0, h1, h2)


@jit_inline
def dump_dipole(h, b, params, p0):
    """The dumping dipole ``m = k (h x B) / |B|^2`` (body axes, each axis clipped to the row's
    ``max_dipole``, along ``B``'s axes with a limit frame; :data:`DUMP` at ``params[p0]``) for the wheels' momentum ``h`` and the field
    ``b`` (body axes): unclipped, ``m x B = -k h_perp``, ``h_perp`` the part of ``h`` normal to
    ``B``. Zero in a zero field."""
    b2 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    if not b2 > 0.0:
        return (0.0, 0.0, 0.0)
    f = params[p0 + _DU_GAIN] / b2
    mmax = params[p0 + _DU_MMAX]
    c = cross(h, b)
    if params[p0 + _DU_FRAMED] != 0.0:  # the limit along the body axes B of a tensor
        return clip_in_body_axes((f * c[0], f * c[1], f * c[2]), mmax, params, p0 + _DU_AXES)
    return (clip(f * c[0], mmax), clip(f * c[1], mmax), clip(f * c[2], mmax))


# ---------------------------------------------------------------------------------------
# Magnetorquers as the PD law's actuator (issue 32 item 5)

#: the layout of a :data:`~orbatt.core.model.MAGNETORQUERS` row, the companion that follows a PD
#: law's row with ``actuator = magnetorquers`` and holds what the PD row's own table slot
#: cannot (that slot is its target's: the Sun, a ground point, the geodetic vertical): the
#: magnetic field along the orbit (its table) and the magnetorquers' per-axis limit. It
#: carries the flight-software slots (a mode sequence marks and shifts every row of a law)
#: with no state of its own (``nz = 0``): the PD row holds the dipole.
MAGNETORQUER = Slots(*FLIGHT_SOFTWARE, ("max_dipole", 1))
assert (MAGNETORQUER.period, MAGNETORQUER.phase, MAGNETORQUER.z0, MAGNETORQUER.nz, MAGNETORQUER.mode) == (
    CTL_PERIOD, CTL_PHASE, CTL_Z0, CTL_NZ, CTL_MODE)
#: the slot of the magnetorquers' limit (``params[p0 + MTQ_MAX_DIPOLE]`` of the companion row)
MTQ_MAX_DIPOLE = MAGNETORQUER.max_dipole


def magnetorquer_params(max_dipole):
    """The parameters of a :data:`~orbatt.core.model.MAGNETORQUERS` row (:data:`MAGNETORQUER`):
    the per-axis dipole limit (internal units, 1e-6 A m^2); no state, no period of its own."""
    if not max_dipole > 0.0:
        raise ValueError(f"max_dipole: {max_dipole!r} must be positive")
    return MAGNETORQUER.pack(max_dipole=float(max_dipole), **law_slots(0), **flight_software())


@jit_inline
def torque_dipole(tau, b, mmax):
    """The dipole that makes the commanded torque ``tau`` in the field ``b`` (both body axes):
    ``m = (B x tau) / |B|^2``, each axis clipped to ``mmax``. Unclipped, ``m x B = tau_perp``,
    the part of ``tau`` normal to ``B`` (magnetorquers cannot make the part along ``B``), and
    ``m . B = 0``. Zero in a zero field."""
    b2 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    if not b2 > 0.0:
        return (0.0, 0.0, 0.0)
    c = cross(b, tau)
    return (clip(c[0] / b2, mmax), clip(c[1] / b2, mmax), clip(c[2] / b2, mmax))


@jit_inline
def pd_dipole(tau, b, mmax, params, p0):
    """:func:`torque_dipole` for the PD row at ``params[p0]``: its dipole clipped along the body
    axes ``B`` of a tensor when the row has a limit frame (:data:`LIMIT_FRAME`), else exactly
    :func:`torque_dipole`."""
    if params[p0 + _PD_FRAMED] == 0.0:
        return torque_dipole(tau, b, mmax)
    b2 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    if not b2 > 0.0:
        return (0.0, 0.0, 0.0)
    c = cross(b, tau)
    return clip_in_body_axes((c[0] / b2, c[1] / b2, c[2] / b2), mmax, params, p0 + _PD_AXES)

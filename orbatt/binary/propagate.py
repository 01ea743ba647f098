"""Propagating a binary: the coupled orbit and attitudes (:mod:`orbatt.core.mutual`) with the
one adaptive step loop of :mod:`orbatt.core.dop853` (its coupled form), impulses applied
between segments, and a stop at contact.

Output times are landed on exactly (step-end values, no interpolation). An impulse at time
``t_k`` changes the secondary's velocity relative to the primary by ``delta_v`` (radial,
along-track, normal components in the orbital frame of the state at ``t_k``): ``p += mu
delta_v``; an output at ``t_k`` holds the state **before** the impulse. After an impulse the
step loop restarts (new derivative, Hairer's initial step), as the right-hand side jumps there.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..core import kernel_floats
from ..core import dop853 as kd
from ..core import model as kmod
from ..core import mutual_splitting as ks
from ..core.mutual import C_MU
from ..core.splitting import COMPOSITIONS
from ..errors import InputError, IntegrationError
from .system import BinarySystem, rtn_basis

__all__ = ["BinaryTrajectory", "propagate_binary", "apply_impulse", "METHODS", "LOOPS", "Impulse"]

#: the methods of a coupled binary: the adaptive step loops of :mod:`orbatt.core.dop853`
#: (:data:`LOOPS`), and the symplectic splitting of :mod:`orbatt.core.mutual_splitting` (fixed
#: step, a composition of :data:`orbatt.core.splitting.COMPOSITIONS`)
METHODS = ("dop853", "vern98", "splitting")
#: the coupled forms of the one adaptive step loop, by method
LOOPS = {"dop853": kd.advance_coupled, "vern98": kd.advance_coupled_verner98}
#: outputs per call of the step loop: the separation is checked between calls
_CHUNK = 512


@dataclass(frozen=True)
class Impulse:
    """A velocity change of the secondary at ``time`` (s): ``delta_v`` (km/s) in the radial,
    along-track and normal directions of the relative orbit at that instant."""

    time: float
    delta_v: tuple


@dataclass
class BinaryTrajectory:
    """What :func:`propagate_binary` returns (plain floats, kg km s).

    Attributes
    ----------
    system : BinarySystem
    t : ndarray (N,)
        Output times (s).
    y : ndarray (N, 14 | 22)
        States (:mod:`orbatt.core.mutual`) at ``t``.
    c : ndarray
        The kernel constants used.
    method : str
    settings : dict
        ``rtol``, ``atol``, ``impulses``.
    stats : dict
        ``steps``, ``rejected_steps``, ``rhs_evaluations``, ``wall_time_s``.
    complete : bool
        False when the run stopped early (contact, failure): ``t, y`` hold what was computed.
    """

    system: BinarySystem
    t: np.ndarray
    y: np.ndarray
    c: np.ndarray
    method: str
    settings: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    complete: bool = True


def apply_impulse(y, c, delta_v):
    """``y`` after the secondary's velocity change ``delta_v`` (radial, along-track, normal,
    km/s): ``p += mu delta_v`` (inertial)."""
    y = y.copy()
    mu = c[C_MU]
    basis = rtn_basis(y[0:3], y[3:6] / mu)
    y[3:6] += mu * (np.asarray(delta_v, dtype=np.float64) @ basis)
    return y


def propagate_binary(system, y0, times, *, method="dop853", rtol=1e-10, atol=1e-12, impulses=(), max_steps=10**8,
                     step=None, composition="yoshida4"):
    """Integrate the coupled binary from ``y0`` at ``times[0]`` to every time of ``times``.

    Parameters
    ----------
    system : BinarySystem
    y0 : ndarray (14 | 22,)
        :meth:`BinarySystem.state`.
    times : array_like (N,)
        Increasing output times (s); ``times[0]`` is the time of ``y0``.
    method : {"dop853", "vern98", "splitting"}
    rtol, atol : float
        Tolerances: ``atol`` bounds the error of ``q``, ``q1``, of ``Q / max(I)``, of ``r`` in
        units of the initial separation and of ``p`` in units of ``mu`` times the circular speed.
    impulses : sequence of Impulse
    max_steps : int
    step, composition : float, str
        ``"splitting"`` only: the fixed step (s; every output and impulse time must be a
        multiple of it from ``times[0]``) and a key of :data:`orbatt.core.splitting.COMPOSITIONS`.

    Returns
    -------
    BinaryTrajectory

    Raises
    ------
    IntegrationError
        The bodies touched (separation below :attr:`BinarySystem.contact_distance` at an output
        time) or the step loop failed; ``exc.trajectory`` holds the outputs computed until then.
    """
    if method not in METHODS:
        raise InputError(f"method: {method!r} is not one of {', '.join(map(repr, METHODS))} for a coupled binary")
    if method == "splitting":
        return _propagate_split(system, y0, times, step, composition, impulses)
    loop = LOOPS[method]
    times = np.asarray(times, dtype=np.float64)
    if times.ndim != 1 or times.size < 1 or np.any(np.diff(times) <= 0):
        raise InputError("times: give increasing output times")
    imps = sorted(impulses, key=lambda k: k.time)
    for k in imps:
        if not times[0] < k.time <= times[-1]:
            raise InputError(f"impulses: time {k.time!r} s is outside the run ({times[0]:g} .. {times[-1]:g} s]")
    y = np.array(y0, dtype=np.float64)
    c = system.constants(y[0:3], y[3:6] / system.reduced_mass)
    terms = np.zeros((1, kmod.TERM_FIELDS), dtype=np.int64)  # no model terms: no breakpoints
    params = np.zeros(1)
    table = np.zeros((1, 1))
    work = np.zeros(1)
    st, cnt, f0 = kd.new_state(width=y.size)
    st[kd.ST_T] = times[0]
    out = np.empty((times.size, y.size))
    out[0] = y
    done = 1
    contact = system.contact_distance
    wall = time.perf_counter()
    stops = [k.time for k in imps] + [None]
    status = kd.DONE
    stop_reason = None
    for k_imp, t_stop in enumerate(stops):
        # the output times of this segment, plus the impulse time if it is not one of them
        hi = times.size if t_stop is None else int(np.searchsorted(times, t_stop, side="right"))
        seg = times[done:hi]
        extra = t_stop is not None and (seg.size == 0 or seg[-1] != t_stop)
        t_seg = np.concatenate([seg, [t_stop]]) if extra else seg
        for j0 in range(0, t_seg.size, _CHUNK):
            t_out = np.ascontiguousarray(t_seg[j0:j0 + _CHUNK])
            buf = np.empty((t_out.size, y.size))
            cnt[kd.CNT_IOUT] = 0
            status = loop(y, st, cnt, f0, t_out, np.empty(0), buf, False, c, terms, params, table, work,
                          rtol, atol, np.inf, max_steps, 2**62)
            n_ok = int(cnt[kd.CNT_IOUT])
            n_rec = min(n_ok, seg.size - j0) if extra else n_ok
            n_rec = max(n_rec, 0)
            sep = np.linalg.norm(buf[:n_rec, 0:3], axis=1)
            hit = np.nonzero(sep <= contact)[0]
            if hit.size:
                n_rec = int(hit[0]) + 1
                stop_reason = (f"contact at t = {t_out[hit[0]]:.9g} s: separation {sep[hit[0]]:.6g} km <= "
                               f"{contact:.6g} km (the sum of the radii sqrt(tr I / M))")
            out[done:done + n_rec] = buf[:n_rec]
            done += n_rec
            if stop_reason is None and status != kd.DONE:
                sep_now = float(np.linalg.norm(y[0:3]))
                if status in (kd.NONFINITE, kd.STEP_TOO_SMALL) and sep_now <= contact * (1 + 1e-3):
                    stop_reason = (f"contact at t = {st[kd.ST_T]:.9g} s: separation {sep_now:.6g} km, the bodies "
                                   f"touch at {contact:.6g} km (the sum of the radii sqrt(tr I / M))")
                else:
                    stop_reason = f"the step loop stopped at t = {st[kd.ST_T]:.9g} s (status {status})"
            if stop_reason is not None:
                break
        if stop_reason is not None:
            break
        if t_stop is not None:
            y[:] = apply_impulse(y, c, imps[k_imp].delta_v)
            cnt[kd.CNT_FLAGS] &= ~kd.FLAG_F0_VALID  # the derivative jumps: evaluate it again
            st[kd.ST_H] = 0.0  # and choose a new first step
            st[kd.ST_FACOLD] = 0.0
    wall = time.perf_counter() - wall
    stats = {"steps": int(cnt[kd.CNT_STEPS]), "rejected_steps": int(cnt[kd.CNT_REJECTED]),
             "rhs_evaluations": int(cnt[kd.CNT_NFEV]), "wall_time_s": wall}
    settings = {"rtol": rtol, "atol": atol,
                "impulses": [{"time": k.time, "delta_v": list(map(float, k.delta_v))} for k in imps]}
    traj = BinaryTrajectory(system, times[:done].copy(), out[:done].copy(), c, method, settings, stats,
                            complete=stop_reason is None)
    if stop_reason is not None:
        exc = IntegrationError(f"binary: {stop_reason}", t=float(traj.t[-1]))
        exc.trajectory = traj
        raise exc
    return traj


def _grid_steps(times, t0, step, what):
    """The numbers of steps of size ``step`` between ``t0`` and each of ``times``; refuse a
    time off the grid ``t0 + k step`` (relative 1e-9 of a step)."""
    k = np.rint((np.asarray(times) - t0) / step)
    if np.any(np.abs(t0 + k * step - times) > 1e-9 * step):
        raise InputError(f"step: {step!r} s does not divide the {what} (from the start); give a step that does, "
                         "e.g. the output step over an integer")
    return k.astype(np.int64)


def _propagate_split(system, y0, times, step, composition, impulses):
    """:func:`propagate_binary` with the symplectic splitting (fixed ``step``)."""
    if composition not in COMPOSITIONS:
        raise InputError(f"composition: {composition!r} is not one of {', '.join(map(repr, COMPOSITIONS))}")
    if step is None or not float(step) > 0:
        raise InputError(f"step: {step!r}; the splitting method needs a positive fixed step (s)")
    step = float(step)
    times = np.asarray(times, dtype=np.float64)
    if times.ndim != 1 or times.size < 1 or np.any(np.diff(times) <= 0):
        raise InputError("times: give increasing output times")
    imps = sorted(impulses, key=lambda k: k.time)
    k_out = _grid_steps(times, times[0], step, "output times")
    k_imp = _grid_steps([k.time for k in imps], times[0], step, "impulse times") if imps else np.zeros(0, np.int64)
    y = np.array(y0, dtype=np.float64)
    c = system.constants(y[0:3], y[3:6] / system.reduced_mass)
    gammas = np.array(COMPOSITIONS[composition][1])
    i2 = kernel_floats(system.inertia)
    i1 = kernel_floats(system.primary_inertia if system.rigid_primary else np.ones(3))
    out = np.empty((times.size, y.size))
    out[0] = y
    # segments: outputs up to and including each impulse's grid point, the impulse, and on
    wall = time.perf_counter()
    evals = 0
    done, k_now = 1, 0
    for j, k_stop in enumerate(list(k_imp) + [None]):
        hi = times.size if k_stop is None else int(np.searchsorted(k_out, k_stop, side="right"))
        ks_seg = k_out[done:hi]
        extra = k_stop is not None and (ks_seg.size == 0 or ks_seg[-1] != k_stop)
        targets = np.concatenate([ks_seg, [k_stop]]) if extra else ks_seg
        n_steps = np.diff(np.concatenate([[k_now], targets])).astype(np.int64)
        buf = np.empty((targets.size, y.size))
        evals += ks.advance_split(y, c, i2, i1, gammas, step, n_steps, buf)
        out[done:done + ks_seg.size] = buf[:ks_seg.size]
        done += ks_seg.size
        k_now = int(targets[-1]) if targets.size else k_now
        if k_stop is not None:
            y[:] = apply_impulse(y, c, imps[j].delta_v)
    wall = time.perf_counter() - wall
    stats = {"steps": int(k_out[-1]), "gradient_evaluations": int(evals), "wall_time_s": wall}
    settings = {"step": step, "composition": composition,
                "impulses": [{"time": k.time, "delta_v": list(map(float, k.delta_v))} for k in imps]}
    sep = np.linalg.norm(out[:, 0:3], axis=1)
    hit = np.nonzero(sep <= system.contact_distance)[0]
    n = int(hit[0]) + 1 if hit.size else times.size
    traj = BinaryTrajectory(system, times[:n].copy(), out[:n].copy(), c, "splitting", settings, stats,
                            complete=not hit.size)
    if hit.size:
        exc = IntegrationError(f"binary: contact at t = {times[hit[0]]:.9g} s: separation {sep[hit[0]]:.6g} km <= "
                               f"{system.contact_distance:.6g} km (the sum of the radii sqrt(tr I / M))",
                               t=float(times[hit[0]]))
        exc.trajectory = traj
        raise exc
    return traj

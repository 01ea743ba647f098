"""Propagating a binary: the coupled orbit and attitudes (:mod:`orbatt.core.mutual`) with the
one adaptive step loop of :mod:`orbatt.core.dop853` (its coupled form), impulses applied
between segments, and a stop at contact.

Output times are landed on exactly (step-end values, no interpolation). An impulse at time
``t_k`` changes the secondary's velocity relative to the primary by ``delta_v`` (radial,
along-track, normal components in the orbital frame of the state at ``t_k``): ``p += mu
delta_v``; an output at ``t_k`` holds the state **before** the impulse; impulses at the same
time are applied one after the other, in their order. After an impulse the step loop restarts
(new derivative, Hairer's initial step), as the right-hand side jumps there.

The compiled loops run in calls of about :data:`CHUNK_SECONDS`: between them ``progress`` is
called and a KeyboardInterrupt (Ctrl-C) is honoured, as in :func:`orbatt.propagate` (the
result then holds the outputs computed so far, ``complete=False``; results do not depend on
the calls' lengths). Contact is checked on every step: the adaptive loops stop where the
right-hand side is undefined (:func:`orbatt.core.mutual.rhs_coupled`), the splitting at the end
of the first step whose path (its drifts' straight lines) comes within the contact distance.
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

__all__ = ["BinaryTrajectory", "propagate_binary", "apply_impulse", "METHODS", "LOOPS", "Impulse", "CHUNK_SECONDS"]

#: the methods of a coupled binary: the adaptive step loops of :mod:`orbatt.core.dop853`
#: (:data:`LOOPS`), and the symplectic splitting of :mod:`orbatt.core.mutual_splitting` (fixed
#: step, a composition of :data:`orbatt.core.splitting.COMPOSITIONS`)
METHODS = ("dop853", "vern98", "splitting")
#: the coupled forms of the one adaptive step loop, by method
LOOPS = {"dop853": kd.advance_coupled, "vern98": kd.advance_coupled_verner98}

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
    km/s): ``p += mu delta_v`` (inertial). IntegrationError where the relative position and
    velocity are parallel (a radial orbit has no along-track or normal direction)."""
    y = y.copy()
    mu = c[C_MU]
    r, v = y[0:3], y[3:6] / mu
    if not np.linalg.norm(np.cross(r, v)) > 1e-12 * np.linalg.norm(r) * np.linalg.norm(v):
        raise IntegrationError("binary: an impulse on a radial orbit (the relative position and velocity are "
                               "parallel): its radial, along-track and normal directions are undefined")
    basis = rtn_basis(r, v)
    y[3:6] += mu * (np.asarray(delta_v, dtype=np.float64) @ basis)
    return y


def propagate_binary(system, y0, times, *, method="dop853", rtol=1e-10, atol=1e-12, impulses=(), max_steps=10**8,
                     step=None, composition="yoshida4", progress=None):
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
        Impulses at the same time are applied one after the other, in the order given.
    max_steps : int
    step, composition : float, str
        ``"splitting"`` only: the fixed step (s; every output and impulse time must be a
        multiple of it from ``times[0]``) and a key of :data:`orbatt.core.splitting.COMPOSITIONS`.
    progress : None, True or callable
        As for :func:`orbatt.propagate`: called with a :class:`~orbatt.progress.ProgressInfo`
        after each compiled call (about :data:`CHUNK_SECONDS` each); returning False stops the
        run (``complete=False``). A KeyboardInterrupt (Ctrl-C) stops it too, within about
        :data:`CHUNK_SECONDS`: the result then holds the outputs computed so far.

    Returns
    -------
    BinaryTrajectory

    Raises
    ------
    IntegrationError
        The bodies touched (separation below :attr:`BinarySystem.contact_distance`: the
        adaptive loops stop where the right-hand side is undefined, the splitting at the end of
        the step whose path comes within the contact distance) or the step loop failed; ``exc.trajectory``
        holds the outputs computed until then.
    """
    from ..progress import progress_callback

    if method not in METHODS:
        raise InputError(f"method: {method!r} is not one of {', '.join(map(repr, METHODS))} for a coupled binary")
    progress = progress_callback(progress)
    times = np.asarray(times, dtype=np.float64)
    if times.ndim != 1 or times.size < 1 or np.any(np.diff(times) <= 0):
        raise InputError("times: give increasing output times")
    imps = sorted(impulses, key=lambda k: k.time)  # stable: impulses at one time keep their order
    for k in imps:
        if not times[0] < k.time <= times[-1]:
            raise InputError(f"impulses: time {k.time!r} s is outside the run ({times[0]:g} .. {times[-1]:g} s]")
    if method == "splitting":
        return _propagate_split(system, y0, times, step, composition, imps, progress)
    loop = LOOPS[method]
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
    contact = system.contact_distance
    pace = _Pacer(progress, times[0], times[-1])
    # what is recorded: out[:done]; the current segment's buffer, its output count, and how many
    # of its outputs are copied (``collect`` is idempotent: also called after a Ctrl-C)
    rec = {"done": 1, "buf": None, "n_seg": 0, "copied": 0, "stop": None}

    def collect():
        buf = rec["buf"]
        if buf is None:
            return
        j0 = rec["copied"]
        j1 = min(int(cnt[kd.CNT_IOUT]), rec["n_seg"])
        if j1 <= j0:
            return
        sep = np.linalg.norm(buf[j0:j1, 0:3], axis=1)
        hit = np.nonzero(sep <= contact)[0]
        if hit.size:
            j1 = j0 + int(hit[0]) + 1
            rec["stop"] = (f"contact at t = {times[rec['done'] + hit[0]]:.9g} s: separation {sep[hit[0]]:.6g} km <= "
                           f"{contact:.6g} km (the sum of the radii sqrt(tr I / M))")
        d = rec["done"]
        out[d:d + j1 - j0] = buf[j0:j1]
        rec["done"] = d + j1 - j0
        rec["copied"] = j1

    try:
        for t_stop, group in _segments(imps):
            # the output times of this segment, plus the impulse time if it is not one of them
            done = rec["done"]
            hi = times.size if t_stop is None else int(np.searchsorted(times, t_stop, side="right"))
            seg = times[done:hi]
            extra = t_stop is not None and (seg.size == 0 or seg[-1] != t_stop)
            t_seg = np.ascontiguousarray(np.concatenate([seg, [t_stop]]) if extra else seg)
            if t_seg.size and t_seg[-1] > st[kd.ST_T]:
                rec.update(buf=np.empty((t_seg.size, y.size)), n_seg=seg.size, copied=0)
                cnt[kd.CNT_IOUT] = 0
                while True:
                    c0 = time.perf_counter()
                    status = loop(y, st, cnt, f0, t_seg, np.empty(0), rec["buf"], False, c, terms, params, table,
                                  work, rtol, atol, np.inf, max_steps, pace.budget)
                    collect()
                    if rec["stop"] is not None:
                        break
                    if status == kd.PAUSED:
                        if not pace.report(time.perf_counter() - c0, float(st[kd.ST_T]), int(cnt[kd.CNT_STEPS])):
                            break
                        continue
                    if status != kd.DONE:
                        sep_now = float(np.linalg.norm(y[0:3]))
                        if status in (kd.NONFINITE, kd.STEP_TOO_SMALL) and sep_now <= contact * (1 + 1e-3):
                            rec["stop"] = (f"contact at t = {st[kd.ST_T]:.9g} s: separation {sep_now:.6g} km, the "
                                           f"bodies touch at {contact:.6g} km (the sum of the radii sqrt(tr I / M))")
                        else:
                            rec["stop"] = f"the step loop stopped at t = {st[kd.ST_T]:.9g} s (status {status})"
                    break
                rec["buf"] = None
            if rec["stop"] is not None or pace.stopped:
                break
            rec["stop"] = _apply(y, c, group, t_stop)  # the impulses at t_stop, in order
            if rec["stop"] is not None:
                break
            if group:
                cnt[kd.CNT_FLAGS] &= ~kd.FLAG_F0_VALID  # the derivative jumps: evaluate it again
                st[kd.ST_H] = 0.0  # and choose a new first step
                st[kd.ST_FACOLD] = 0.0
    except KeyboardInterrupt:
        collect()
        pace.interrupted()
    pace.finish(float(st[kd.ST_T]), int(cnt[kd.CNT_STEPS]), rec["stop"] is None and not pace.stopped)
    stats = {"steps": int(cnt[kd.CNT_STEPS]), "rejected_steps": int(cnt[kd.CNT_REJECTED]),
             "rhs_evaluations": int(cnt[kd.CNT_NFEV]), "wall_time_s": pace.wall()}
    settings = {"rtol": rtol, "atol": atol, "impulses": _impulse_settings(imps)}
    done = rec["done"]
    return _result(BinaryTrajectory(system, times[:done].copy(), out[:done].copy(), c, method, settings, stats,
                                    complete=rec["stop"] is None and not pace.stopped), rec["stop"], pace)


#: target wall time of one compiled call between progress reports and Ctrl-C checks (as
#: :data:`orbatt.propagation.CHUNK_SECONDS`)
CHUNK_SECONDS = 0.25


class _Pacer:
    """The step budget of each compiled call (aimed at :data:`CHUNK_SECONDS`), the progress
    reports between calls, and why the run stopped early (a progress callback's False, Ctrl-C)."""

    def __init__(self, progress, t0, t_end):
        self.progress, self.t0, self.t_end = progress, float(t0), float(t_end)
        self.budget = 64
        self.start = time.perf_counter()
        self.stopped = None  # "progress callback" | "KeyboardInterrupt"

    def wall(self):
        return time.perf_counter() - self.start

    def _info(self, t, steps, frac=None):
        from ..progress import ProgressInfo

        span = self.t_end - self.t0
        if frac is None:
            frac = min(1.0, max(0.0, (t - self.t0) / span)) if span > 0 else 1.0
        return ProgressInfo(frac, t, self.t_end, steps, self.wall())

    def report(self, dt, t, steps):
        """After a call that used its budget (``dt`` s): report, adapt the budget; False: stop."""
        if self.progress is not None and self.progress(self._info(t, steps)) is False:
            self.stopped = "progress callback"
            return False
        self.budget = int(min(max(self.budget * min(4.0, CHUNK_SECONDS / dt), 1), 2**40)) if dt > 0 else self.budget * 4
        return True

    def interrupted(self):
        self.stopped = "KeyboardInterrupt"

    def finish(self, t, steps, complete):
        """The last report (fraction 1 when the run completed)."""
        if self.progress is not None and self.stopped is None:
            self.progress(self._info(t, steps, 1.0 if complete else None))


def _apply(y, c, group, t):
    """Apply the impulses ``group`` to ``y`` in place, in order; why not (a message), or None."""
    for k in group:
        try:
            y[:] = apply_impulse(y, c, k.delta_v)
        except IntegrationError as exc:
            return f"{str(exc).removeprefix('binary: ')} (at t = {t:.9g} s)"
    return None


def _segments(imps):
    """``(t_stop, impulses at t_stop)`` for each distinct impulse time, then ``(None, [])``."""
    groups = {}
    for k in imps:
        groups.setdefault(k.time, []).append(k)
    return list(groups.items()) + [(None, [])]


def _impulse_settings(imps):
    return [{"time": k.time, "delta_v": list(map(float, k.delta_v))} for k in imps]


def _result(traj, stop_reason, pace):
    """``traj``, or the IntegrationError of ``stop_reason`` holding it."""
    if pace.stopped is not None:
        traj.settings["stopped"] = pace.stopped
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


def _propagate_split(system, y0, times, step, composition, imps, progress):
    """:func:`propagate_binary` with the symplectic splitting (fixed ``step``)."""
    if composition not in COMPOSITIONS:
        raise InputError(f"composition: {composition!r} is not one of {', '.join(map(repr, COMPOSITIONS))}")
    if step is None or not float(step) > 0:
        raise InputError(f"step: {step!r}; the splitting method needs a positive fixed step (s)")
    step = float(step)
    k_out = _grid_steps(times, times[0], step, "output times")
    segments = _segments(imps)
    k_stops = _grid_steps([t for t, _ in segments[:-1]], times[0], step, "impulse times") if imps else []
    y = np.array(y0, dtype=np.float64)
    c = system.constants(y[0:3], y[3:6] / system.reduced_mass)
    gammas = np.array(COMPOSITIONS[composition][1])
    i2 = kernel_floats(system.inertia)
    i1 = kernel_floats(system.primary_inertia if system.rigid_primary else np.ones(3))
    out = np.empty((times.size, y.size))
    out[0] = y
    pace = _Pacer(progress, times[0], times[-1])
    # segments: outputs up to and including each impulse's grid point, the impulses, and on
    rec = {"done": 1, "buf": None, "n_seg": 0, "cnt": np.zeros(ks.CNT_SIZE, np.int64), "copied": 0,
           "k_now": 0, "steps": 0, "evals": 0, "stop": None}

    def collect():
        buf, cnt = rec["buf"], rec["cnt"]
        if buf is None:
            return
        j0, j1 = rec["copied"], min(int(cnt[ks.CNT_K]), rec["n_seg"])
        if j1 > j0:
            out[rec["done"]:rec["done"] + j1 - j0] = buf[j0:j1]
            rec["done"] += j1 - j0
            rec["copied"] = j1

    def steps_now():
        return rec["steps"] + int(rec["cnt"][ks.CNT_STEPS])

    try:
        for j, (t_stop, group) in enumerate(segments):
            k_stop = None if t_stop is None else int(k_stops[j])
            done = rec["done"]
            hi = times.size if k_stop is None else int(np.searchsorted(k_out, k_stop, side="right"))
            ks_seg = k_out[done:hi]
            extra = k_stop is not None and (ks_seg.size == 0 or ks_seg[-1] != k_stop)
            targets = np.concatenate([ks_seg, [k_stop]]) if extra else ks_seg
            n_steps = np.diff(np.concatenate([[rec["k_now"]], targets])).astype(np.int64)
            rec.update(buf=np.empty((targets.size, y.size)), n_seg=ks_seg.size, copied=0,
                       cnt=np.zeros(ks.CNT_SIZE, np.int64))
            sp = np.zeros(ks.SP_SIZE)
            while targets.size:
                c0 = time.perf_counter()
                status = ks.advance_split(y, c, i2, i1, gammas, step, n_steps, rec["buf"], sp, rec["cnt"],
                                          pace.budget)
                collect()
                if status == ks.CONTACT:
                    k_hit = rec["k_now"] + int(rec["cnt"][ks.CNT_STEPS])
                    rec["stop"] = (f"contact in the step ending at t = {times[0] + k_hit * step:.9g} s: the separation "
                                   f"comes within {system.contact_distance:.6g} km (the sum of the radii "
                                   "sqrt(tr I / M))")
                    break
                if status == ks.PAUSED:
                    if not pace.report(time.perf_counter() - c0, times[0] + steps_now() * step, steps_now()):
                        break
                    continue
                break
            rec["steps"] += int(rec["cnt"][ks.CNT_STEPS])
            rec["evals"] += int(rec["cnt"][ks.CNT_EVALS])
            rec["cnt"] = np.zeros(ks.CNT_SIZE, np.int64)
            rec["buf"] = None
            if rec["stop"] is not None or pace.stopped:
                break
            rec["k_now"] = int(targets[-1]) if targets.size else rec["k_now"]
            rec["stop"] = _apply(y, c, group, t_stop)  # the impulses at t_stop, in order
            if rec["stop"] is not None:
                break
    except KeyboardInterrupt:
        collect()
        rec["steps"] += int(rec["cnt"][ks.CNT_STEPS])
        rec["evals"] += int(rec["cnt"][ks.CNT_EVALS])
        pace.interrupted()
    complete = rec["stop"] is None and not pace.stopped
    pace.finish(times[0] + rec["steps"] * step, rec["steps"], complete)
    stats = {"steps": rec["steps"], "gradient_evaluations": rec["evals"], "wall_time_s": pace.wall()}
    settings = {"step": step, "composition": composition, "impulses": _impulse_settings(imps)}
    done = rec["done"]
    return _result(BinaryTrajectory(system, times[:done].copy(), out[:done].copy(), c, "splitting", settings, stats,
                                    complete=complete), rec["stop"], pace)

"""The canonical state ``(q, Q)`` of a rigid body, validated, built from what users know.

Frames and units: ``q`` maps body to space components (:mod:`orbatt.quaternion`); ``Q`` is
in the body's momentum unit, the kernels' (kg km^2 s^-1, or plain numbers for a
dimensionless body); a State prints ``Q`` in SI (kg m^2 s^-1), as every output gives it.
A state may hold a batch: ``q`` and ``Q`` of shape ``(..., 4)``.
"""
from __future__ import annotations

import json
import math

import numpy as np

from . import canonical as cn
from . import euler as eu
from . import quaternion as qt
from . import units as U
from .body import RigidBody
from .errors import InputError

#: ``| |q| - 1 |`` above this is refused (a 6-digit printed unit quaternion passes).
UNIT_TOLERANCE = 1e-6
#: ``|q.Q| / |Q|`` above this is refused as "clearly not tangent" (the paper's printed
#: ``Q(t0)`` has 5e-8).
TANGENT_TOLERANCE = 1e-6


def unit_quaternion(q, name="q"):
    q = qt.as_quaternion(q, name)
    n = qt.norm(q)
    if q.ndim == 1:  # one quaternion: the checks on a float (numpy's calls cost ~1 us each)
        nf = float(n)
        zero, off = nf == 0.0, abs(nf - 1.0) > UNIT_TOLERANCE
    else:
        bad = np.abs(n - 1.0) > UNIT_TOLERANCE
        zero, off = (n == 0.0).any(), bad.any()
    if zero:
        raise InputError(f"{name}: the zero quaternion is not an attitude; give a unit quaternion")
    if off:
        first = nf if q.ndim == 1 else float(np.asarray(n)[bad].ravel()[0])
        raise InputError(f"{name}: |q| = {first:.10g} is not 1 (tolerance "
                         f"{UNIT_TOLERANCE:g}); give a unit quaternion (scalar first)")
    return q / n[..., None]


def _finite(value, name):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: {value!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{name}: {value!r} is not finite")
    return v


#: the step loop's memory a continued run takes over (:meth:`orbatt.methods.dop853.DOP853.stepper`)
STEPPER_KEYS = ("h", "facold", "switch", "flags", "f0", "work", "independent_variable", "method")


def _floats(v):
    """An array of floats from a record (None: NaN)."""
    return np.array(np.where(np.equal(np.array(v, dtype=object), None), np.nan, np.array(v, dtype=object)),
                    dtype=np.float64)


def _stepper(s):
    """The step loop's memory (:data:`STEPPER_KEYS`), checked: plain arrays."""
    if not isinstance(s, dict) or not set(STEPPER_KEYS) <= set(s):
        raise InputError(f"stepper: expected a dict with {', '.join(STEPPER_KEYS)}, got {str(s)[:80]!r}")
    try:
        out = {k: _floats(s[k]) for k in ("h", "facold", "switch", "f0", "work")}
        out["flags"] = np.array(s["flags"], dtype=np.int64)
    except (TypeError, ValueError):
        raise InputError(f"stepper: not arrays of numbers ({str(s)[:80]!r}); the record was edited or damaged") from None
    h, fac = out["h"], out["facold"]
    if not (np.isfinite(h).all() and (h > 0).all() and np.isfinite(fac).all() and (fac > 0).all()):
        raise InputError(f"stepper: h = {h!r} and facold = {fac!r} must be positive and finite")
    out["independent_variable"], out["method"] = str(s["independent_variable"]), str(s["method"])
    return out


def _plain(v):
    """A JSON form of an array (NaN: None)."""
    a = np.asarray(v)
    if a.dtype.kind == "f":
        return np.where(np.isnan(a), None, a.astype(object)).tolist()
    return a.tolist()


def continuation_text(trajectory):
    """The JSON text of the :class:`State` a run continues from after ``trajectory``'s last output
    (:meth:`State.record`; the NetCDF global attribute ``continuation``), or None where there is
    none to give: an ensemble, no output, a body given by a full inertia tensor (its Dataset is
    in the body frame, its run in the principal one)."""
    tr = trajectory
    if tr.q.ndim != 2 or tr.t.shape[0] == 0 or getattr(tr.body, "frame", None) is not None:
        return None
    return json.dumps(State.of_trajectory(tr).record(), allow_nan=False)


class State:
    """Canonical state ``(q, Q)`` (paper Sect. 3), validated.

    Parameters
    ----------
    body : RigidBody
    q : array-like (..., 4)
        Attitude, body -> space, scalar first. Must be a unit quaternion to 1e-6; it is
        normalized exactly.
    Q : array-like or Quantity (..., 4)
        Conjugate momentum in the body's momentum unit. A small component along ``q``
        (``|q.Q| <= 1e-6 |Q|``, as in the paper's 6-digit data) is accepted and reported in
        :attr:`radial_residual`; a larger one is refused with the measured ``q.Q``.
    """

    def __init__(self, body: RigidBody, q, Q):
        if not isinstance(body, RigidBody):
            raise InputError(f"body: expected a RigidBody, got {type(body).__name__}")
        self.body = body
        self.q = unit_quaternion(q)
        Qv = U.strip(Q, body.momentum_unit, "Q", allow_plain=True)
        Qv = qt.as_quaternion(Qv, "Q")
        if Qv.shape != self.q.shape:
            try:
                np.broadcast_shapes(self.q.shape, Qv.shape)
            except ValueError:
                raise InputError(f"Q: shape {Qv.shape} does not match q's {self.q.shape}") from None
        qQ = qt.dot(self.q, Qv)
        scale = qt.norm(Qv)
        if Qv.ndim == 1 and self.q.ndim == 1:  # one state: the comparison on floats
            refused = abs(float(qQ)) > TANGENT_TOLERANCE * float(scale)
        else:
            refused = (np.abs(qQ) > TANGENT_TOLERANCE * scale).any()
        if refused:
            bad = np.abs(qQ) > TANGENT_TOLERANCE * scale
            raise InputError(f"Q: q.Q = {float(np.asarray(qQ)[bad].ravel()[0]):.6g} is not ~0 (|Q| = "
                             f"{float(np.asarray(scale)[bad].ravel()[0]):.6g}); Q must be tangent to the unit sphere "
                             "at q (Q = 2 q g): build it with State.from_omega or State.from_momentum")
        self.Q = Qv
        #: ``q.Q`` of the given data (0 for states built from rates or momenta)
        self.radial_residual = qQ
        self._no_continuation()

    def _no_continuation(self):
        #: the time of the state (the body's time unit), for a state a run continues from; None
        self.t = None
        #: the reaction wheels' axial momenta ``(..., n)`` (kg km^2/s) a run continues from; None:
        #: from the body rate and the wheels' initial speeds (:func:`orbatt.methods.problem.initial_states`)
        self.wheel_momenta = None
        #: the flight software's discrete state ``z (..., nz)`` (held commands, a PD law's
        #: integral, a mode sequence's state: :attr:`orbatt.trajectory.Trajectory.command`), in
        #: kernel units, after the tick at :attr:`t` if ``t`` is a tick; None: a new run (its
        #: first tick issues the commands at its start)
        self.command = None
        #: the origin of the flight software's tick grid ``t_k = phase + k period`` (the body's
        #: time unit); None: the law's own (0, the time axis' origin)
        self.phase = None
        #: the flight software's period of the run the state comes from (information; None)
        self.period = None
        #: the step loop's memory at :attr:`t` (:data:`STEPPER_KEYS`): a run continued from it
        #: takes the steps the run it comes from would have taken, as after a pause (None: a
        #: fresh start, Hairer's initial step)
        self.stepper = None

    # ---- constructors -------------------------------------------------------------------
    @classmethod
    def from_omega(cls, body: RigidBody, q, omega):
        """From the attitude and the body angular velocity ``omega`` (body components;
        rad/s Quantity, or plain numbers for a dimensionless body). For a body with reaction
        wheels, ``Q`` holds the total momentum ``g = I omega + sum Iw speed a`` (the wheels'
        initial speeds)."""
        q = unit_quaternion(q)
        w = U.strip(omega, body.rate_unit, "omega", allow_plain=body.dimensionless)
        if w.shape[-1:] != (3,):
            raise InputError(f"omega: expected 3 body-axis components, got shape {w.shape}")
        if body.frame is not None:  # a full inertia tensor (orbatt.body_frame): g = I_B omega (+ the rotors')
            return cls(body, q, cn.momentum_from_body_momentum(q, body.momentum(w)))
        if body.wheels:  # a gyrostat: g = I omega + the rotors' relative momentum
            return cls(body, q, cn.momentum_from_body_momentum(q, body.inertia_value * w + body.rotor_momentum))
        return cls(body, q, cn.momentum_from_omega(q, w, body.inertia_value))

    @classmethod
    def from_momentum(cls, body: RigidBody, q, g):
        """From the attitude and the body angular momentum ``g`` (body components)."""
        q = unit_quaternion(q)
        gv = U.strip(g, body.momentum_unit, "g", allow_plain=True)
        if gv.shape[-1:] != (3,):
            raise InputError(f"g: expected 3 body-axis components, got shape {gv.shape}")
        return cls(body, q, cn.momentum_from_body_momentum(q, gv))

    @classmethod
    def from_euler(cls, body: RigidBody, angles, momenta):
        """From the 3-1-3 Euler angles ``(phi, theta, psi)`` (rad) and their conjugate momenta
        ``(Phi, Theta, Psi)`` (momentum unit); eqs. (12) and (14). ``sin(theta) = 0`` is
        refused (the Euler momenta do not determine the state there)."""
        ang = U.strip(angles, U.ANGLE, "euler_313")
        mom = U.strip(momenta, body.momentum_unit, "euler_momenta", allow_plain=True)
        if ang.shape[-1:] != (3,) or mom.shape[-1:] != (3,):
            raise InputError("euler_313/euler_momenta: expected 3 values each")
        if np.any(np.abs(np.sin(ang[..., 1])) < 1e-12):
            raise InputError(f"euler_313: theta = {ang[..., 1]!r} is singular (sin theta = 0); "
                             "give q and omega instead")
        q, Q = eu.to_canonical(ang, mom)
        return cls(body, q, Q)

    @classmethod
    def continuing(cls, body: RigidBody, t, y, *, phase=None, period=None, stepper=None):
        """The state a run continues from: the kernels' state vector ``y = (q, Q, h, z)`` at
        time ``t``, kept bit for bit (``q`` is checked, not normalized).

        A run of :func:`orbatt.propagate` from it starts at ``t`` with the wheels' momenta
        ``h`` and the flight software's state ``z`` it holds (no tick at its start: ``z`` is the
        state after the tick at ``t`` if ``t`` is one), on the tick grid ``phase + k period``,
        and, with a ``stepper``, with the step controller's memory: it then gives the outputs
        of the run it continues bit for bit (:meth:`orbatt.trajectory.Trajectory.state`).

        Parameters
        ----------
        body : RigidBody
            Its wheels say how many components of ``y`` after ``Q`` are their momenta.
        t : float
            Time (the body's time unit: s, or dimensionless).
        y : array-like (..., 8 + n + nz)
            ``q`` (4), ``Q`` (4, the body's momentum unit), the wheels' momenta (``n``,
            kg km^2/s), the flight software's state (``nz``, kernel units).
        phase, period : float, optional
            The tick grid of the run it continues (the body's time unit).
        stepper : dict, optional
            The step loop's memory at ``t`` (:data:`STEPPER_KEYS`: the next step ``h``, the
            controller's ``facold``, a located ``switch``, ``flags``, the derivative ``f0``, the
            scratch array ``work``, per member; the ``independent_variable`` and ``method``), as
            :meth:`orbatt.methods.dop853.DOP853.stepper` gives it.
        """
        if hasattr(y, "unit"):
            raise InputError("y: give plain floats in the kernels' units (as Trajectory.q, Q, wheel_momenta, command "
                             "hold them), not a Quantity")
        try:
            y = np.array(y, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(f"y: {str(y)[:80]!r} is not an array of numbers") from None
        n = len(body.wheels)
        if y.ndim not in (1, 2) or y.shape[-1] < 8 + n:
            raise InputError(f"y: expected (q, Q, the {n} wheels' momenta, the flight software's state) along the last "
                             f"axis, at least {8 + n} components, got shape {y.shape}")
        if not np.isfinite(y).all():
            raise InputError(f"y: holds non-finite values ({y!r}); continue only from a finite state")
        try:
            tv = float(t)
        except (TypeError, ValueError):
            raise InputError(f"t: {t!r} is not a time (a float in the body's time unit)") from None
        if not math.isfinite(tv):
            raise InputError(f"t: {t!r} is not finite")
        # the checks of q (a unit quaternion); Q is an integrated state carried as it is: its
        # tangency q.Q ~ 0 is the integration's (relative to |Q| it fails for a body near rest,
        # |Q| ~ 1e-22 and q.Q ~ 1e-25 after a slew on wheels), kept as radial_residual
        st = cls(body, y[..., :4], np.zeros_like(y[..., 4:8]))
        st.q = np.ascontiguousarray(y[..., :4])  # bit for bit (State() normalizes q)
        st.Q = np.ascontiguousarray(y[..., 4:8])
        st.radial_residual = qt.dot(st.q, st.Q)
        st.t = tv
        st.wheel_momenta = np.ascontiguousarray(y[..., 8:8 + n]) if n else None
        st.command = np.ascontiguousarray(y[..., 8 + n:])
        st.phase = None if phase is None else _finite(phase, "phase")
        st.period = None if period is None else _finite(period, "period")
        st.stepper = None if stepper is None else _stepper(stepper)
        return st

    @classmethod
    def of_trajectory(cls, trajectory, i=-1):
        """The state of a :class:`~orbatt.trajectory.Trajectory` at its output ``i`` (default
        the last), to continue the run from (:meth:`continuing`). The step controller's memory
        comes with the last output of a complete run of the compiled Runge-Kutta methods only
        (the loop keeps it there): continued from it, a run is bitwise the run it continues;
        from another output it starts with a fresh step (equal to the tolerances)."""
        tr = trajectory
        nt = tr.t.shape[0]
        if not -nt <= i < nt:
            raise InputError(f"i: output {i} does not exist (the trajectory has {nt}); give -{nt} .. {nt - 1}")
        k = i % nt
        parts = [tr.q[..., k, :], tr.Q[..., k, :]]
        parts += [x[..., k, :] for x in (tr.wheel_momenta, tr.command) if x is not None]
        info = getattr(tr, "continuation", None) or {}
        stepper = info.get("stepper") if k == nt - 1 and tr.complete else None
        return cls.continuing(tr.body, tr.t[k], np.concatenate(parts, axis=-1), phase=info.get("phase"),
                              period=info.get("period"), stepper=stepper)

    def record(self):
        """The state as plain JSON values (what a NetCDF file keeps to continue its run from:
        the global attribute ``continuation``); :meth:`from_record` reads it back bit for bit
        (Python's float ``repr`` round-trips)."""
        if self.t is None:
            raise InputError("state: it has no time; build it with State.continuing or Trajectory.state()")
        parts = [self.q, self.Q] + [x for x in (self.wheel_momenta, self.command) if x is not None]
        y = np.concatenate([np.broadcast_to(x, np.broadcast_shapes(self.q.shape[:-1], x.shape[:-1]) + x.shape[-1:])
                            for x in parts], axis=-1)
        rec = {"t": self.t, "y": y.tolist(), "wheels": len(self.body.wheels), "units": "kernel",
               "phase": self.phase, "period": self.period}
        if self.stepper is not None:
            rec["stepper"] = {k: (v if isinstance(v, str) else _plain(v)) for k, v in self.stepper.items()}
        return rec

    @classmethod
    def from_record(cls, body: RigidBody, record):
        """The state of a :meth:`record` (a dict, or its JSON text) for ``body``."""
        if isinstance(record, str):
            try:
                record = json.loads(record)
            except ValueError as exc:
                raise InputError(f"continuation: not JSON ({exc}); the file was edited or damaged") from None
        if not isinstance(record, dict) or not {"t", "y", "wheels"} <= set(record):
            raise InputError(f"continuation: expected a record with t, y and wheels, got {str(record)[:80]!r}")
        if int(record["wheels"]) != len(body.wheels):
            raise InputError(f"continuation: the state holds {record['wheels']} wheels' momenta and the body has "
                             f"{len(body.wheels)} wheels; continue a run with the body it was run with")
        return cls.continuing(body, record["t"], record["y"], phase=record.get("phase"), period=record.get("period"),
                              stepper=record.get("stepper"))

    # ---- derived quantities -------------------------------------------------------------
    @property
    def g(self):
        """Body angular momentum (body components, momentum unit)."""
        return cn.body_momentum(self.q, self.Q)

    @property
    def omega(self):
        """Body angular velocity (body components, rad per time unit); for a body with
        reaction wheels ``I^-1 (g - sum Iw speed a)`` with the wheels' initial speeds."""
        if self.body.frame is not None:  # a full inertia tensor: computed in its principal frame, turned back
            return self.body.frame.to_body(self.body.frame.principal_state(self).omega)
        if self.body.wheels and self.wheel_momenta is not None:  # J omega = g - sum h_k a_k, J = I - sum Iw a a^T
            axes = np.array([w.axis for w in self.body.wheels])
            J = np.diag(self.body.inertia_value) - sum(w.inertia * np.outer(w.axis, w.axis) for w in self.body.wheels)
            rhs = self.g - self.wheel_momenta @ axes
            return np.linalg.solve(J, rhs[..., None])[..., 0]
        if self.body.wheels:
            return (self.g - self.body.rotor_momentum) / self.body.inertia_value
        return cn.body_rate(self.q, self.Q, self.body.inertia_value)

    @property
    def G(self):
        """Space angular momentum (inertial components, momentum unit)."""
        return cn.space_momentum(self.q, self.Q)

    @property
    def kinetic_energy(self):
        if self.body.frame is not None:  # a full inertia tensor: 1/2 g.I_B^-1 g, in its principal frame
            return self.body.frame.principal_state(self).kinetic_energy
        return cn.kinetic_energy(self.q, self.Q, self.body.inertia_value)

    def euler(self):
        """``((phi, theta, psi), (Phi, Theta, Psi))`` (eqs. 13, 15)."""
        return eu.from_canonical(self.q, self.Q)

    @property
    def y(self):
        """The kernels' state vector(s) ``(q0..q3, Q0..Q3)``, shape ``(..., 8)``."""
        q, Q = self.q, self.Q
        if q.shape != Q.shape:
            q, Q = np.broadcast_arrays(q, Q)
        return np.concatenate([q, Q], axis=-1)

    def __repr__(self):
        """``State(q=[...], Q=[...] kg m^2 s^-1)``: ``Q`` printed in SI (the unit every
        output uses, :data:`orbatt.units.DIMENSIONAL_UNITS`), or as plain numbers for a
        dimensionless body; :attr:`Q` itself stays in the kernels' unit."""
        if self.body.dimensionless:
            return f"State(q={self.q.tolist()}, Q={self.Q.tolist()})"
        Q = U.to_output(self.Q, "momentum")
        return f"State(q={self.q.tolist()}, Q={Q.tolist()} {U.DIMENSIONAL_UNITS['momentum']})"

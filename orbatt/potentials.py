"""Potentials acting on the body, with units at the boundary (kernels in
:mod:`orbatt.core.potentials`).

A potential object knows its kernel ``kind``, ``params`` and ``table`` (what the compiled
integrators take) and the times it is defined at (``time_span``), and evaluates ``U``, the
tangential gradient ``dU/dq`` and the body-frame torque for arrays of times and attitudes.
"""
from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from . import units as U
from .body import RigidBody
from .core import kernel_floats
from .core import evaluation as kev
from .core import model as km
from .core import potentials as kp
from .errors import InputError
from .orbits.base import OrbitProvider


def kernel_backed(method):
    """Mark a :class:`Potential` method that computes from :meth:`Potential.kernel_model` alone
    (as the compiled kernels do, after checks that depend on the body and the times only):
    :func:`evaluate_members` then evaluates an ensemble in one compiled call. A subclass that
    overrides ``evaluate`` or ``term_torques`` without this mark gets a call per member; a marked
    ``term_torques`` other than the base one gives each kernel term's torque, as
    :func:`orbatt.core.evaluation.evaluate_terms`."""
    method.kernel_backed = True
    return method


def _read_only(a):
    """``a`` with its ``writeable`` flag cleared (a potential's parameters are fixed)."""
    a.flags.writeable = False
    return a


#: models of small kernel specifications by value, most recently used last
#: (:func:`_model_of`): a study building the same potential again (``load_scenario(path)``
#: in a loop) skips :func:`orbatt.core.model.from_spec` (~30 us)
_MODELS: OrderedDict = OrderedDict()
_MODELS_LOCK = threading.Lock()
#: most models kept; specifications with larger tables (sampled orbits) are not kept
MODEL_CACHE_SIZE = 64
_MODEL_CACHE_MAX_TABLE = 4096


def _model_of(kind, params, table):
    """``km.from_spec(kind, params, table)``, remembered by the values of small specifications;
    every call returns fresh arrays (the caller may change them)."""
    try:
        pv = np.asarray(params, dtype=np.float64)
        tv = np.asarray(table, dtype=np.float64)
        key = (int(kind), pv.shape, pv.tobytes(), tv.shape, tv.tobytes()) if tv.size <= _MODEL_CACHE_MAX_TABLE else None
    except (TypeError, ValueError):  # from_spec reports a bad specification
        key = None
    if key is None:
        return km.from_spec(kind, params, table)
    with _MODELS_LOCK:
        model = _MODELS.get(key)
        if model is not None:
            _MODELS.move_to_end(key)
    if model is None:
        model = km.from_spec(kind, params, table)
        with _MODELS_LOCK:
            _MODELS[key] = tuple(a.copy() for a in model)
            while len(_MODELS) > MODEL_CACHE_SIZE:
                _MODELS.popitem(last=False)
        return model
    return tuple(a.copy() for a in model)


class Potential:
    """Base class. Subclasses set ``kind``, ``params``, ``table`` and ``name``.

    ``params``/``table`` are in the internal unit system of the body they are used with
    (see :mod:`orbatt.units`).
    """

    kind: int
    name: str
    table = kp.EMPTY_TABLE
    #: ``None`` (defined at all times) or ``(t_first, t_last)``: the times the potential can
    #: be evaluated at (in the body's time unit); :func:`orbatt.propagate` refuses to leave it
    time_span = None

    def check_body(self, body: RigidBody):
        """Raise :class:`InputError` if this potential cannot act on ``body``."""

    @kernel_backed
    def evaluate(self, body: RigidBody, t, q):
        """``(U, dU/dq, torque)`` at times ``t (N,)`` and attitudes ``q (N, 4)``.

        ``U`` in the body's energy unit; ``dU/dq`` (tangential, ``(N, 4)``) in energy unit;
        torque in body components (``(N, 3)``, energy unit = kg km^2 s^-2 = 1e6 N m for
        dimensional bodies).
        """
        q = kernel_floats(np.atleast_2d(q))
        if type(t) is np.ndarray and t.dtype == np.float64 and t.shape == q.shape[:1]:
            t = kernel_floats(t)  # a run's outputs: as they are (np.broadcast_to costs ~3 us)
        else:
            t = kernel_floats(np.broadcast_to(np.asarray(t, dtype=np.float64), q.shape[:1]))
        return kev.evaluate_many(t, q, body.inertia_value, *self.kernel_model(), kp.new_work())

    def kernel_model(self):
        """The compiled model ``(terms, params, table)`` of this potential
        (:mod:`orbatt.core.model`): fresh writeable copies (the caller may change them) of
        the model :meth:`build_model` made on the first call. A potential does not change
        after construction (its ``params`` are read-only); assigning other ``params`` or
        ``table`` arrays makes the next call build the model again."""
        cache = self.__dict__.get("_kernel_cache")
        if cache is None or cache[0] is not self.params or cache[1] is not self.table:
            cache = (self.params, self.table, self.build_model())
            self._kernel_cache = cache
        terms, params, table = cache[2]
        return terms.copy(), params.copy(), table.copy()

    def build_model(self):
        """Build the compiled model ``(terms, params, table)`` from the kernel specification
        (:func:`orbatt.core.model.from_spec`); subclasses with more terms override it. Use
        :meth:`kernel_model`, which builds it once."""
        return _model_of(self.kind, self.params, self.table)

    def describe(self) -> dict:
        """Plain description (strings and numbers) for Dataset attributes and scenarios."""
        return {"kind": self.name}

    #: names of the torque terms of this potential (``torque_<name>`` in a Dataset; none
    #: for a potential that is not a torque of the environment)
    term_names: list = []

    @kernel_backed
    def term_torques(self, body, t, q):
        """Each term's body torque ``(N, len(term_names), 3)`` in the body's energy unit (kg
        km^2 s^-2 = 1e6 N m) at the times ``t`` and attitudes ``q (N, 4)``."""
        _, _, tau = self.evaluate(body, t, q)
        return np.asarray(tau, dtype=np.float64)[:, None, :]

    def fields(self, t):
        """The environment fields along the orbit a Dataset records (none here)."""
        return {}


class TorqueFree(Potential):
    """``U = 0``: the free rigid body (paper Sect. 6.1)."""

    kind = kp.TORQUE_FREE
    name = "torque-free"
    params = _read_only(np.zeros(1))


class HeavyTop(Potential):
    """Heavy top in uniform gravity along ``-s3`` (paper eq. 18; ``docs/design.md`` §3).

    Parameters
    ----------
    mass_g : Quantity (force) or float
        Weight ``M g`` (N, or plain for dimensionless bodies).
    center_of_mass : Quantity (length) or 3 floats
        Centre of mass ``x_c`` in body components, relative to the fixed point.
    sign : {"physical", "paper"}
        ``"physical"`` (default): ``U = M g z_c`` (the potential energy; torque
        ``x_c x F_B``). ``"paper"``: eq. (18) as printed, ``U = x_c . F_B = -M g z_c``, as if
        gravity pointed up - only for reproducing the paper's Fig. 2.
    """

    kind = kp.HEAVY_TOP
    name = "heavy-top"

    def __init__(self, mass_g, center_of_mass, sign="physical", *, dimensionless=None):
        if sign not in ("physical", "paper"):
            raise InputError(f"potential.sign: {sign!r} is not 'physical' or 'paper'")
        from astropy import units as u

        if dimensionless is None:
            dimensionless = not isinstance(mass_g, (u.Quantity, str))
        self.dimensionless = dimensionless
        mg = U.strip(mass_g, U.MASS * U.LENGTH / U.TIME**2, "mass_g", allow_plain=dimensionless)
        xc = U.strip(center_of_mass, U.LENGTH, "center_of_mass", allow_plain=dimensionless)
        if mg.shape != () or mg < 0:
            raise InputError(f"mass_g: expected one non-negative weight M g, got {mass_g!r}")
        if xc.shape != (3,):
            raise InputError(f"center_of_mass: expected [x, y, z] in body axes, got {center_of_mass!r}")
        self.sign = sign
        s = 1.0 if sign == "physical" else -1.0
        self.params = _read_only(np.array([s * float(mg), *xc], dtype=np.float64))

    def check_body(self, body):
        if body.dimensionless != self.dimensionless:
            raise InputError("potential: heavy-top weight/centre of mass and the body's inertia must be "
                             "both dimensional or both plain numbers")

    def describe(self):
        return {"kind": self.name, "mass_g": abs(self.params[0]), "center_of_mass": self.params[1:].tolist(),
                "sign": self.sign}


class GravityGradient(Potential):
    """Gravity-gradient (MacCullagh) potential of a point-mass central body, eq. (20)
    (``docs/design.md`` §3), driven by an orbit provider (:mod:`orbatt.orbits`).

    ``U = (3 GM / 2 r^3) x_B . (I x_B)`` with ``x_B = q~ X q`` the radial unit vector in
    body components (``X = p s1 p~``); tangential gradient (extension as a function of
    ``q/|q|``); body torque ``(3 GM / r^3) x_B x (I x_B)``. The kernel takes ``r`` and
    ``x_S`` from the orbit without returning to Python: Kepler's equation solved in the
    kernel (:class:`~orbatt.orbits.KeplerOrbit`, kind 2), or the REBOUND samples
    interpolated in the kernel (:class:`~orbatt.orbits.ReboundOrbit`, kind 3).

    Parameters
    ----------
    orbit : OrbitProvider
        The orbit (times in seconds since its epoch). A dimensional orbit acts on
        dimensional bodies (inertia in kg km^2; energies and torques in kg km^2 s^-2 = 1e6 N m),
        a dimensionless one (plain ``a`` and ``gm``, normalized units) on dimensionless
        bodies (plain numbers throughout).

    Attributes
    ----------
    orbit : OrbitProvider
    kind, params, table
        The provider's kernel specification (:meth:`OrbitProvider.kernel`).
    time_span : None or (float, float)
        The orbit's ``time_span``: seconds since its epoch the orbit is available at (a
        sampled orbit), None for all times.
    """

    name = "gravity-gradient"
    term_names = ["gravity_gradient"]

    def __init__(self, orbit):

        if not isinstance(orbit, OrbitProvider):
            raise InputError(f"orbit: expected an orbit provider (KeplerOrbit, ReboundOrbit), got "
                             f"{type(orbit).__name__}")
        self.orbit = orbit
        self.kind, params, self.table = orbit.kernel()
        self.params = _read_only(np.array(params, dtype=np.float64))

    @property
    def time_span(self):
        return self.orbit.time_span

    @property
    def dimensionless(self):
        """Whether the orbit (and so the body it acts on) is in normalized units."""
        return bool(self.orbit.dimensionless)

    def check_body(self, body):
        if body.dimensionless and not self.dimensionless:
            raise InputError("body: plain-number inertia with a dimensional orbit (GM in km^3/s^2); give the inertia "
                             "as a Quantity, e.g. [400, 500, 600] * u.kg * u.km**2, or the orbit's a and gm as plain "
                             "numbers (normalized units)")
        if self.dimensionless and not body.dimensionless:
            raise InputError("body: dimensional inertia with a dimensionless orbit (plain a and gm); give the "
                             "inertia as plain numbers too (normalized units), or a and gm as Quantities")

    @kernel_backed
    def evaluate(self, body, t, q):
        """``(U, dU/dq, torque)`` at times ``t`` (s since the orbit's epoch) and attitudes
        ``q (N, 4)``: ``U`` in kg km^2 s^-2, ``dU/dq`` ``(N, 4)``, body torque ``(N, 3)`` in
        kg km^2 s^-2 (1e6 N m)."""
        self.check_body(body)
        if self.time_span is not None:
            tt = np.asarray(t, dtype=np.float64)
            lo, hi = self.time_span
            if tt.size and (np.min(tt) < lo or np.max(tt) > hi):
                raise InputError(f"t: times outside the sampled span [{lo}, {hi}] s of the REBOUND orbit; "
                                 "build the orbit with a larger t_end")
        return super().evaluate(body, t, q)

    def describe(self):
        return {"kind": self.name, "orbit": self.orbit.describe()}

    def __repr__(self):
        return f"GravityGradient(orbit={self.orbit!r})"


def member_body(body, inertia):
    """The body of an ensemble member with principal moments ``inertia`` (the body's internal
    unit): ``body`` itself when they are its own."""
    if np.array_equal(inertia, body.inertia_value):
        return body
    return RigidBody(inertia.tolist() if body.dimensionless else inertia * body.inertia_unit)


def _total_torque_only(potential):
    """Whether ``potential``'s terms are its one total torque (the base ``term_torques``); else
    each term has its own (a kernel-backed ``term_torques``: ``orbatt.core.evaluation.evaluate_terms``)."""
    return getattr(type(potential), "term_torques", None) is Potential.term_torques


def energy_and_torques(potential, body, t, q, want_tau):
    """``(U (N,), tau)``: the potential energy at the times ``t (N,)`` and attitudes ``q (N,
    4)`` and, if ``want_tau``, each torque term (``(N, terms, 3)``,
    :meth:`Potential.term_torques`), else None (the body's energy unit). A potential whose
    terms are its own torque (the base ``term_torques``) is evaluated once."""
    if want_tau and _total_torque_only(potential):
        U, _, torque = potential.evaluate(body, t, q)
        tau = np.asarray(torque, dtype=np.float64)[:, None, :]
    else:
        U, _, _ = potential.evaluate(body, t, q)
        tau = potential.term_torques(body, t, q) if want_tau else None
    return np.asarray(U, dtype=np.float64).reshape(t.shape), tau


def evaluate_members(potential, body, inertia, t, q, want_tau):
    """:func:`energy_and_torques` of each member of an ensemble: ``(U (E, N), tau (E, N, terms,
    3) or None)`` at the times ``t (N,)`` and attitudes ``q (E, N, 4)`` of members of principal
    moments ``inertia (E, 3)`` (``body``'s internal unit; ``body``: the ensemble's body, for the
    checks). Each member's numbers are those of :func:`energy_and_torques` on its own body.

    A :class:`Potential` whose ``evaluate`` and ``term_torques`` are :func:`kernel_backed` is
    checked once (``evaluate`` of the first member) and evaluated in one compiled call
    (:func:`orbatt.core.evaluation.evaluate_members`, the orbit evaluated once for all members): 10^4
    members of the Keplerian case over 11 outputs in 4 ms instead of 147 ms of a call per member
    (``benchmarks/run.py``'s ensemble end-to-end rows). Any other potential: a call per member."""
    cls = type(potential)
    if isinstance(potential, Potential) and all(getattr(getattr(cls, name), "kernel_backed", False)
                                                for name in ("evaluate", "term_torques")):
        t = kernel_floats(t)
        q = kernel_floats(q)
        potential.evaluate(body, t, q[0])  # what evaluate checks (the body, the times), once
        U, tau = kev.evaluate_members(t, q, kernel_floats(inertia),
                                     *potential.kernel_model(), not _total_torque_only(potential), want_tau)
        return U, (tau if want_tau else None)
    members = [energy_and_torques(potential, member_body(body, inertia[e]), t, q[e], want_tau)
               for e in range(q.shape[0])]
    return np.stack([m[0] for m in members]), (np.stack([m[1] for m in members]) if want_tau else None)

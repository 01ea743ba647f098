"""Environment torques on a body of flat plates along a prescribed orbit, with units at the
boundary (``docs/design.md`` §10): aerodynamic drag, solar radiation pressure and a residual
magnetic dipole, with or without the gravity gradient.

The orbit is prescribed, so every field that depends on position and time alone - the
atmospheric density, the geomagnetic field, the Sun's position - is evaluated before the
integration by the models of :mod:`orbatt.environment`, at sample times along the orbit, and
interpolated in the compiled kernel (Chebyshev pieces; the tables' errors are stated in
:mod:`orbatt.environment.tables`). The kernel terms are in :mod:`orbatt.core.model` and
:mod:`orbatt.core.torques`.

Internal units: kg, km, s (torques in kg km^2 s^-2 = 1e6 N m); facet areas given in m^2,
densities in kg m^-3, dipoles in A m^2 and fields in T at the boundary.
"""
from __future__ import annotations

import math

import numpy as np
from astropy import units as u

from . import units as U
from .core import kernel_floats
from .core import evaluation as kev
from .core import model as km
from .core import potentials as kp
from .core.environment import PIECE_HEADER
from .core.kinds import BY_NAME
from .environment import sun as esun
from .environment.atmosphere import NRLMSIS, PiecewiseExponentialAtmosphere
from .environment.frames import geodetic_up_gcrs, ground_point_gcrs
from .environment.tables import (DENSITY_PIECES, LAYERED_DENSITY_PIECES, MAGNETIC_FIELD_PIECES, SUN_PIECES,
                                  TABLE_MARGIN, tabulate_along_orbit)
from .control import BDotControl, PDControl
from .modes import ModeSequence
from .errors import InputError
from .orbits.base import OrbitProvider
from .potentials import Potential, kernel_backed
from .terms import TERMS

__all__ = ["Facet", "facet", "EnvironmentTorques", "TERM_NAMES", "TERM_KEYWORDS", "FIELDS_SOURCE", "sample_margin"]

#: where the Dataset's environment fields come from (its variables' ``source`` attribute)
FIELDS_SOURCE = ("the kernel's piece tables (the integration's own samples along the orbit, "
                 "interpolated; docs/design.md §10), or the closed form the kernel evaluates (exponential atmosphere)")
#: names of the terms, as in the Dataset variables ``torque_<name>`` (:mod:`orbatt.core.kinds`)
TERM_NAMES = {k.code: k.name for k in BY_NAME.values()}
_AREA = u.m**2
_LENGTH_M = u.m


def _quantity(value, unit, name):
    """:func:`orbatt.units.strip` (a Quantity or a string astropy parses, with the dimension
    of ``unit``), element by element for a list such as ``["0 m", "0.1 m", "0.03 m"]``."""
    if isinstance(value, (list, tuple)) and any(isinstance(v, (str, u.Quantity)) for v in value):
        return np.array([U.strip(v, unit, f"{name}[{k}]") for k, v in enumerate(value)], dtype=np.float64)
    return U.strip(value, unit, name)


def sample_margin(*, drag=False, srp=False, magnetic=False, sun=False):
    """How far (s) before the start and after the end of a run :class:`EnvironmentTorques`
    samples the orbit: :data:`~orbatt.environment.tables.TABLE_MARGIN` when it builds a table.

    Parameters
    ----------
    drag, srp, magnetic, sun : bool
        The tables built: density (drag), Sun position (SRP or a PD law pointing at the Sun),
        magnetic field (a residual dipole or B-dot); their pieces:
        :mod:`orbatt.environment.tables`.

    Returns
    -------
    float
        The margin (s), 0 without tables. An orbit sampled over ``[t_start - margin, t_end +
        margin]`` (a TLE's, which SGP4 propagates either side of its epoch) keeps the tables
        a little beyond the run; a shorter one cuts the margin (the pieces' interpolation
        has no end effects).
    """
    return TABLE_MARGIN if (drag or srp or magnetic or sun) else 0.0


#: the keywords of :class:`EnvironmentTorques` its signature names (the terms' among them)
_NAMED = {"gravity_gradient", "drag", "srp", "residual_dipole", "constant_torque"}
#: the terms' keywords :class:`EnvironmentTorques` takes through ``**terms``: those of the
#: vector keys of :data:`orbatt.terms.TERMS` its signature does not name (a new term's)
TERM_KEYWORDS = {k.argument: k for t in TERMS for k in t.keys if k.kind == "vector" and k.argument not in _NAMED}
_TERM_OF = {k.argument: t for t in TERMS for k in t.keys}


def _vector_argument(spec, value):
    """The value (3 floats in the key's unit, or None) of a term's keyword ``spec.argument``."""
    if value is None:
        return None
    v = _quantity(value, u.Unit(spec.unit), spec.argument)
    if np.shape(v) != (3,) or not np.all(np.isfinite(v)):
        raise InputError(f"{spec.argument}: expected 3 finite values in {spec.unit}, got {value!r}")
    return np.asarray(v, dtype=np.float64)


def _check_pd_fields(law, epoch, magnetic_field):
    """Refuse a PD law whose target or actuator reads what the environment cannot give: the
    geodetic nadir needs the epoch (the Earth's rotation), magnetorquers a field model."""
    if law.target == "nadir" and epoch is None:
        raise InputError("epoch: a PD law holding the geodetic nadir needs the orbit's epoch (the Earth's rotation)")
    if law.actuator == "magnetorquers" and magnetic_field is None:
        raise InputError("magnetic_field: a PD law on magnetorquers needs a field model (igrf or dipole)")


class Facet:
    """A flat plate of the body (body axes), for drag and solar radiation pressure.

    Parameters
    ----------
    area : Quantity (area)
        Positive.
    normal : array_like (3,)
        Outward unit normal, body axes (unit length to 1e-9).
    position : Quantity (3,) (length)
        Centre of pressure from the centre of mass, body axes.
    drag_coefficient : float
        ``C_D`` (default 2.2), non-negative.
    specular, diffuse : float
        SRP reflectivities in ``[0, 1]`` with ``specular + diffuse <= 1`` (absorbed: the rest).
    """

    def __init__(self, area, normal, position, drag_coefficient=2.2, specular=0.0, diffuse=0.0, *, name="facet"):
        a = float(_quantity(area, _AREA, f"{name}.area"))
        if not a > 0.0:
            raise InputError(f"{name}.area: {area!r} must be positive")
        n = np.asarray(normal, dtype=np.float64)
        if n.shape != (3,) or not np.all(np.isfinite(n)) or abs(np.linalg.norm(n) - 1.0) > 1e-9:
            raise InputError(f"{name}.normal: {normal!r} is not a unit 3-vector (|n| = 1); normalize it")
        p = _quantity(position, _LENGTH_M, f"{name}.position")
        if p.shape != (3,):
            raise InputError(f"{name}.position: expected 3 lengths, got {position!r}")
        for key, v in (("drag_coefficient", drag_coefficient), ("specular", specular), ("diffuse", diffuse)):
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise InputError(f"{name}.{key}: {v!r} is not a number")
        if drag_coefficient < 0:
            raise InputError(f"{name}.drag_coefficient: {drag_coefficient!r} must be non-negative")
        for key, v in (("specular", specular), ("diffuse", diffuse)):
            if not 0.0 <= v <= 1.0:
                raise InputError(f"{name}.{key}: {v!r} must lie in [0, 1]")
        if specular + diffuse > 1.0 + 1e-12:
            raise InputError(f"{name}: specular + diffuse = {specular + diffuse!r} exceeds 1 (absorbed = 1 - both)")
        self.area = a * _AREA
        self.normal = n
        self.position = p * _LENGTH_M
        self.drag_coefficient = float(drag_coefficient)
        self.specular = float(specular)
        self.diffuse = float(diffuse)

    def settings(self):
        """The plain settings (SI floats: m^2, m) that :func:`facet` makes this plate of again."""
        return {"area": float(self.area.to_value(_AREA)), "normal": self.normal.tolist(),
                "position": self.position.to_value(_LENGTH_M).tolist(), "drag_coefficient": self.drag_coefficient,
                "specular": self.specular, "diffuse": self.diffuse}

    def row(self, coefficient_km2):
        """The kernel row ``[c, n, r (km), C_s, C_d]`` (:data:`orbatt.core.torques.FACET_SIZE`)."""
        return np.r_[coefficient_km2, self.normal, self.position.to_value(u.km), self.specular, self.diffuse]

    def describe(self):
        return {"area": str(self.area), "normal": self.normal.tolist(), "position": str(self.position),
                "drag_coefficient": self.drag_coefficient, "specular": self.specular, "diffuse": self.diffuse}

    def __repr__(self):
        return (f"Facet(area={self.area:.4g}, normal={self.normal.tolist()}, position={self.position}, "
                f"C_D={self.drag_coefficient}, specular={self.specular}, diffuse={self.diffuse})")


def facet(settings, name="facet"):
    """The :class:`Facet` of plain ``settings`` (:meth:`Facet.settings`: area in m^2, position in
    m), whose constructor checks every rule (:class:`~orbatt.errors.InputError` naming
    ``name.key``)."""
    return Facet(settings["area"] * _AREA, settings["normal"], np.asarray(settings["position"]) * _LENGTH_M,
                 settings["drag_coefficient"], settings["specular"], settings["diffuse"], name=name)


class EnvironmentTorques(Potential):
    """The gravity gradient (optional) plus environment torques along a prescribed orbit.

    Acts as the ``potential`` of :func:`orbatt.propagate` (its kernel model holds every term);
    the Dataset of a run gets ``torque`` and one ``torque_<term>`` per term (body axes) and
    the fields along the orbit (:meth:`output_variables`).

    Parameters
    ----------
    orbit : OrbitProvider or None
        The orbit (GCRS when it has an epoch). SRP, IGRF and NRLMSIS need ``orbit.epoch``.
        None: no term reads an orbit (a torque-free body with a ``constant_torque``).
    t_end : Quantity (time) or None
        The end of the runs (the environment is sampled over ``[t_start, t_end]`` and a
        margin either side, :func:`sample_margin`, cut to a sampled orbit's span, which must
        hold ``[t_start, t_end]``); None without an orbit (nothing is sampled: the terms are
        defined at all times).
    facets : sequence of Facet
        The plates of the body (drag and SRP need at least one).
    gravity_gradient : bool
        Include the gravity gradient (eq. 20).
    drag : bool
        Aerodynamic drag of the facets in ``atmosphere`` (an object with ``density(t, r)``,
        :mod:`orbatt.environment.atmosphere`), the atmosphere turning with the Earth when
        ``corotation``.
    srp : bool
        Solar radiation pressure (flux :data:`orbatt.environment.sun.SRP_FLUX` at 1 AU, the
        Sun from astropy), with the ``shadow`` model ``"conical"``, ``"cylindrical"`` or
        ``"none"``.
    residual_dipole : Quantity (3,) (A m^2), optional
        The body's magnetic dipole (body axes), in ``magnetic_field`` (an object with
        ``field(t, r)``, :mod:`orbatt.environment.magnetic`): ``tau = m x B``.
    t_start : Quantity (time)
        The start of the sampled span (default 0).
    control : PDControl or BDotControl, optional
        A control law in the loop (:mod:`orbatt.control`): B-dot reads ``magnetic_field``; a
        PD law pointing at the Sun needs the orbit's epoch. Its torque is not a term of
        ``torque``: a Dataset records it as ``torque_control`` (and ``dipole_control``).
    constant_torque : Quantity (3,) (torque), optional
        A constant body torque (body axes; thruster misalignment, outgassing): the term
        ``torque_constant``. It reads no orbit.
    **terms : Quantity (3,), optional
        The keyword of any other term of :data:`orbatt.terms.TERMS` (:data:`TERM_KEYWORDS`: its
        key's ``argument``, 3 values in the key's unit; an attribute of the same name).
    """

    name = "environment"
    dimensionless = False

    def __init__(self, orbit, t_end, *, facets=(), gravity_gradient=True, drag=False, srp=False,
                 residual_dipole=None, atmosphere=None, magnetic_field=None, shadow="conical", corotation=True,
                 t_start=0.0 * u.s, control=None, constant_torque=None, **terms):
        for name in terms:
            if name not in TERM_KEYWORDS:
                raise TypeError(f"EnvironmentTorques() got an unexpected keyword argument {name!r}; the terms' "
                                f"keywords: {', '.join(sorted(TERM_KEYWORDS)) or 'none besides the named ones'}")
        extra = {name: _vector_argument(spec, terms.get(name)) for name, spec in TERM_KEYWORDS.items()}
        self.__dict__.update(extra)
        const = None
        if constant_torque is not None:
            const = _quantity(constant_torque, u.N * u.m, "constant_torque")
            if np.shape(const) != (3,) or not np.all(np.isfinite(const)):
                raise InputError(f"constant_torque: expected 3 finite torques (body axes), got {constant_torque!r}")
        self.constant_torque = const
        if orbit is None:
            needs = [n for n, on in (("gravity_gradient", gravity_gradient), ("drag", drag), ("srp", srp),
                                     ("residual_dipole", residual_dipole is not None), ("control", control is not None))
                     if on] + [n for n, v in extra.items() if v is not None and _TERM_OF[n].kind.orbit]
            if needs:
                raise InputError(f"orbit: {needs[0]} needs an orbit provider (KeplerOrbit, ReboundOrbit, TleOrbit)")
            if const is None and not any(v is not None for v in extra.values()):
                raise InputError("constant_torque: without an orbit the torques need a constant_torque")
        elif not isinstance(orbit, OrbitProvider):
            raise InputError(f"orbit: expected an orbit provider (KeplerOrbit, ReboundOrbit), got {type(orbit).__name__}")
        self.orbit = orbit
        t0 = float(_quantity(t_start, u.s, "t_start"))
        t1 = None if orbit is None and t_end is None else float(_quantity(t_end, u.s, "t_end"))
        if t1 is not None and not t1 > t0:
            raise InputError(f"t_end: {t_end!r} must come after t_start = {t_start!r}")
        self.facets = list(facets)
        if not all(isinstance(f, Facet) for f in self.facets):
            raise InputError("facets: expected a list of orbatt.torques.Facet")
        if (drag or srp) and not self.facets:
            raise InputError(f"facets: {'drag' if drag else 'srp'} needs the body's facets ([[body.facets]])")
        if drag and atmosphere is None:
            raise InputError("atmosphere: drag needs an atmosphere (exponential or nrlmsis)")
        if shadow not in ("conical", "cylindrical", "none"):
            raise InputError(f"shadow: {shadow!r} is not one of 'conical', 'cylindrical', 'none'")
        epoch = getattr(orbit, "epoch", None)
        if srp and epoch is None:
            raise InputError("epoch: SRP needs the orbit's epoch (the Sun's position)")
        dip = None
        if residual_dipole is not None:
            dip = _quantity(residual_dipole, u.A * u.m**2, "residual_dipole")
            if dip.shape != (3,):
                raise InputError(f"residual_dipole: expected 3 components, got {residual_dipole!r}")
            if magnetic_field is None:
                raise InputError("magnetic_field: a residual dipole needs a field model (igrf or dipole)")
        if (atmosphere is not None and drag and not hasattr(atmosphere, "density")) or (
                magnetic_field is not None and not hasattr(magnetic_field, "field")):
            raise InputError("atmosphere/magnetic_field: expected models of orbatt.environment")
        self.gravity_gradient, self.drag, self.srp = bool(gravity_gradient), bool(drag), bool(srp)
        self.residual_dipole = dip
        self.atmosphere, self.magnetic_field = atmosphere, magnetic_field
        self.shadow, self.corotation = shadow, bool(corotation)
        if control is not None and not isinstance(control, (PDControl, BDotControl, ModeSequence)):
            raise InputError(f"control: expected orbatt.PDControl, orbatt.BDotControl or an orbatt.modes.ModeSequence, "
                             f"got {type(control).__name__}")
        if isinstance(control, ModeSequence):  # its modes' laws, checked one by one below
            for law in [m.law for m in control.modes]:
                if isinstance(law, BDotControl) and magnetic_field is None:
                    raise InputError("magnetic_field: a B-dot mode needs a field model (igrf or dipole)")
                if isinstance(law, PDControl) and law.target == "sun" and epoch is None:
                    raise InputError("epoch: a mode pointing at the Sun needs the orbit's epoch (the Sun's position)")
                if isinstance(law, PDControl):
                    _check_pd_fields(law, epoch, magnetic_field)
        if isinstance(control, BDotControl) and magnetic_field is None:
            raise InputError("magnetic_field: B-dot control needs a field model (igrf or dipole)")
        if getattr(control, "dump_gain", None) is not None and magnetic_field is None:
            raise InputError("magnetic_field: momentum dumping (dump_gain) needs a field model (igrf or dipole)")
        if isinstance(control, PDControl) and control.target == "sun" and epoch is None:
            raise InputError("epoch: a PD law pointing at the Sun needs the orbit's epoch (the Sun's position)")
        if isinstance(control, PDControl):
            _check_pd_fields(control, epoch, magnetic_field)
        self.control = control
        valid = None if orbit is None else orbit.time_span
        if valid is not None and (t0 < valid[0] or t1 > valid[1]):
            key, value = ("t_start", t0) if t0 < valid[0] else ("t_end", t1)
            hint = getattr(orbit, "span_hint", "build the orbit over a longer span")
            raise InputError(f"{key}: {value!r} s is outside the span [{valid[0]!r}, {valid[1]!r}] s the orbit "
                             f"was sampled over; {hint}")
        self.span = None if orbit is None else (t0, t1)
        if orbit is None:
            self.kind, self.params, self.table = kp.TORQUE_FREE, np.zeros(1), kp.EMPTY_TABLE
        else:
            self.kind, self.params, self.table = orbit.kernel()
        self._fields = {}
        self._field_tables = {}  # the piece tables of field_table: density, sun, field

    # --- the kernel model
    def _tabulate(self, pieces, evaluate, breaks=False):
        """The piece table (:func:`~orbatt.environment.tables.tabulate_along_orbit`) of
        ``evaluate`` over the run and a margin of :data:`~orbatt.environment.tables.TABLE_MARGIN`
        on each side, cut to the span of a sampled orbit (:func:`sample_margin` says how far to
        sample one, e.g. a TLE, to keep it whole); ``breaks``: knots at the UTC midnights
        (a model with daily inputs: NRLMSIS)."""
        t0, t1 = self.span
        valid = self.orbit.time_span
        lo, hi = t0 - TABLE_MARGIN, t1 + TABLE_MARGIN
        if valid is not None:
            lo, hi = max(lo, valid[0]), min(hi, valid[1])
        cuts = ()
        epoch = self.orbit.epoch
        if breaks and epoch is not None:
            from astropy.time import Time

            day0 = math.floor((epoch + lo * u.s).utc.mjd)
            days = Time(np.arange(day0 + 1, math.floor((epoch + hi * u.s).utc.mjd) + 1), format="mjd", scale="utc")
            cuts = (days - epoch).to_value(u.s) if days.size else ()
        # a sampled orbit (TLE, REBOUND) is a quintic between its samples, C2 across: the
        # field along it is smooth only between them, so they are the pieces' knots too (the
        # step loops land on them anyway); 600 s pieces across them were 5.7e-8 off IGRF
        knots = self.table[:, 0] if self.kind == kp.GRAVITY_GRADIENT_SAMPLED else ()
        return tabulate_along_orbit(self.orbit, lo, hi, pieces, evaluate, cuts, knots)

    def field_table(self, name):
        """The piece table (:mod:`orbatt.core.environment`) of an environment field along the
        orbit, sampled over the run and its margin (:meth:`_tabulate`) once and kept:
        ``"density"`` (kg km^-3, of ``atmosphere``; NRLMSIS's with knots at the UTC midnights,
        where its day of the year changes: a jump of 2.6e-3 at 400 km), ``"sun"`` (the Sun's position,
        km, inertial) or ``"field"`` (``B`` in T, inertial, of ``magnetic_field``), with the
        pieces of :mod:`orbatt.environment.tables`. The terms' rows (:mod:`orbatt.terms`) and
        the control laws' (:mod:`orbatt.control`) read them."""
        if name not in self._field_tables:
            if name == "density":
                layered = isinstance(self.atmosphere, PiecewiseExponentialAtmosphere)
                pieces = LAYERED_DENSITY_PIECES if layered else DENSITY_PIECES
                # NRLMSIS reads the date (its day of the year jumps at midnight); the exponential
                # atmospheres read none: their tables are the same with or without an epoch
                tab = self._tabulate(pieces, self.atmosphere.density, breaks=isinstance(self.atmosphere, NRLMSIS))
                tab[:, PIECE_HEADER:] *= 1e9  # kg m^-3 -> kg km^-3 (the coefficients; not the header)
            elif name == "sun":
                tab = self._tabulate(SUN_PIECES, lambda t, r: esun.sun_position(t))
            elif name == "field":
                tab = self._tabulate(MAGNETIC_FIELD_PIECES, self.magnetic_field.field)
            elif name == "nadir":  # a PD law's geodetic nadir: the ellipsoid's normal through the spacecraft
                if self.orbit.epoch is None:
                    raise InputError("epoch: the geodetic nadir needs the orbit's epoch (the Earth's rotation)")
                tab = self._tabulate(MAGNETIC_FIELD_PIECES, geodetic_up_gcrs)
            elif isinstance(name, tuple) and name[0] == "ground":  # a PD law's ground target
                lat, lon, h = name[1:]
                if self.orbit.epoch is None:
                    raise InputError("epoch: a ground target needs the orbit's epoch (the Earth's rotation)")
                tab = self._tabulate(MAGNETIC_FIELD_PIECES, lambda t, r: ground_point_gcrs(t, lat, lon, h))
            else:
                raise ValueError(f"field_table: unknown field {name!r}; one of 'density', 'sun', 'field'")
            self._field_tables[name] = tab
        return self._field_tables[name]

    def build_model(self):
        """The compiled model ``(terms, params, table)`` (:mod:`orbatt.core.model`): the orbit,
        then the enabled terms of :data:`orbatt.terms.TERMS` in that order (gravity gradient,
        drag, SRP, magnetic, constant torque), each row from its descriptor; built once, by
        :meth:`kernel_model` (:func:`orbatt.model_assembly.assemble` appends the wheels' and the
        control law's rows)."""
        orbit_row = None
        if self.orbit is not None:
            okind, oparams, otable = km.from_spec(self.kind, self.params, self.table)
            orbit_row = (int(okind[0, km.KIND]), oparams[okind[0, km.P0]:okind[0, km.P1]],
                         otable[okind[0, km.R0]:okind[0, km.R1]] if okind[0, km.R1] > okind[0, km.R0] else None)
        rows = [term.row(self) for term in TERMS if term.enabled(self)]
        self.term_kinds = [r[0] for r in rows]
        return km.build(orbit=orbit_row, terms=rows)

    @property
    def time_span(self):
        """``(t_start, t_end)`` (s): the span the environment was sampled over."""
        return self.span

    @property
    def term_names(self):
        """The names of the terms, in kernel order (``torque_<name>`` in a Dataset)."""
        self.kernel_model()
        return [TERM_NAMES[k] for k in self.term_kinds]

    def check_body(self, body):
        if body.dimensionless:
            raise InputError("body: environment torques need a dimensional body (inertia with units)")

    @kernel_backed
    def evaluate(self, body, t, q):
        self.check_body(body)
        return super().evaluate(body, t, q)

    @kernel_backed
    def term_torques(self, body, t, q):
        """Each term's body torque ``(N, n_terms, 3)`` (kg km^2 s^-2 = 1e6 N m) at the times ``t``
        (s) and attitudes ``q (N, 4)``."""
        q = kernel_floats(np.atleast_2d(q))
        t = kernel_floats(np.broadcast_to(np.asarray(t, dtype=np.float64), q.shape[:1]))
        _, tau = kev.evaluate_terms(t, q, body.inertia_value, *self.kernel_model(), kp.new_work())
        return tau

    def fields(self, t):
        """The environment along the orbit at the times ``t`` (s): a dict of ``density``
        (kg m^-3), ``magnetic_field`` (T, inertial), ``sun_direction`` (inertial unit vector)
        and ``shadow`` (0 umbra .. 1 full Sun), those the terms use: the kernel's own tables
        (:data:`FIELDS_SOURCE`: the tables the integration read, no second pass of the
        libraries) at times inside the sampled span, the models themselves elsewhere (or
        before the model is built)."""
        t = np.asarray(t, dtype=np.float64)
        out = {}
        terms = [term for term in TERMS if term.sample is not None and term.enabled(self)]
        if not terms:
            return out
        epoch = getattr(self.orbit, "epoch", None)
        pos, _ = self.orbit.state(t)
        pos = np.asarray(U.strip(pos, u.km, "position", allow_plain=True), dtype=np.float64)
        time = None if epoch is None else epoch + t * u.s
        tabs = self._field_tables if self.span is not None and t.size and self.span[0] <= t.min() \
            and t.max() <= self.span[1] else {}
        for term in terms:
            out.update(term.sample(self, t, pos, time, tabs))
        return out

    def describe(self):
        d = {"kind": self.name, "gravity_gradient": self.gravity_gradient, "drag": self.drag, "srp": self.srp,
             "orbit": None if self.orbit is None else self.orbit.describe(),
             "facets": [f.describe() for f in self.facets], "shadow": self.shadow, "corotation": self.corotation,
             "sampled_span_s": None if self.span is None else list(self.span)}
        if self.constant_torque is not None:
            d["constant_torque_N_m"] = self.constant_torque.tolist()
        for name, spec in TERM_KEYWORDS.items():
            if getattr(self, name) is not None:
                d[f"{name}_{spec.unit.replace(' ', '_')}"] = getattr(self, name).tolist()
        if self.residual_dipole is not None:
            d["residual_dipole_A_m2"] = self.residual_dipole.tolist()
        if self.atmosphere is not None:
            d["atmosphere"] = repr(self.atmosphere)
        if self.magnetic_field is not None:
            d["magnetic_field"] = repr(self.magnetic_field)
        if self.control is not None:
            d["control"] = self.control.describe()
        return d

    def __repr__(self):
        terms = ", ".join(self.term_names)
        return f"EnvironmentTorques({terms}; {len(self.facets)} facets; orbit {self.orbit!r})"

"""The cases of a sweep that varies scenario keys by their paths (issue 23; ``docs/sweeps.md``:
Parameters by path): each case's scenario written out, and the cases grouped so that each
group is one ensemble call.

A case's scenario is the nominal file with the swept leaves replaced (:func:`case_data`,
:func:`case_text`); its single run is the definition of the case. Cases whose scenarios
differ only in the initial state and the principal moments share the orbit, the environment
tables and the control law: they form one group (one ensemble call), whose members' bodies and
initial states are built from each case's own scenario by the single run's builders
(:func:`~orbatt.scenario.build.build_initial_state`).

Cases on one orbit share its **environment** whatever else varies (gains, facets, wheels,
dipoles; issue 35): the orbit (a TLE's SGP4 samples) and the field tables along it (density,
Sun, magnetic field) are built once per process - the nominal scenario's when the case's orbit
is the nominal one - and each group's potential (its terms, facets and control law, cheap) is
built by the single run's own builder (:func:`~orbatt.scenario.build.build_potential`) on that
orbit and reads those tables (:class:`Environment`). The orbit and the tables are functions of
the ``[orbit]``, ``[integration]`` and ``[environment]`` tables alone (:func:`environment_key`),
built by the same code from the same inputs as the case's single run builds them, so every case
still equals the single run of its scenario, bit for bit.
"""
from __future__ import annotations

import re
import threading
import tomllib
import warnings
from collections import OrderedDict

import numpy as np
from astropy import units as u

from .. import units as U
from ..body import RigidBody
from ..control import reaction_wheel
from ..scenario import FieldContext, Scenario, parse
from ..scenario.build import build_initial_state, build_potential, environment_margin
from ..scenario.paths import ALIAS_PATHS, substitute, toml_text

__all__ = ["ALIAS_PATHS", "case_data", "case_text", "state_only", "path_groups", "Environment", "environment_key",
           "environment_of", "clear_environments", "MAX_ENVIRONMENTS"]

#: environments (orbits with their field tables) a process keeps, least recently used dropped
MAX_ENVIRONMENTS = 4



def _alias_unit(name, dimensionless):
    """The unit text a named parameter's internal value is written with (None: plain)."""
    if name.startswith("inertia"):
        return None if dimensionless else U.INERTIA.to_string()
    if name.startswith("omega"):
        return None if dimensionless else U.RATE.to_string()
    if name == "orbit_a":
        return None if dimensionless else U.LENGTH.to_string()
    if name == "orbit_e":
        return None
    return U.ANGLE.to_string()


def case_data(base, spec, values, k, dimensionless=False):
    """The scenario (TOML data) of case ``k``: ``base`` (the nominal file's data) without its
    ``[sweep]`` table, with every swept leaf replaced by the case's value (``values[name][k]``:
    a path's value in its key's unit, a named parameter's in internal units)."""
    subs = {}
    for name in spec.parameters:
        v = float(values[name][k])
        if name in spec.paths:
            unit = spec.paths[name]
            path = name
        else:
            path, unit = ALIAS_PATHS[name], _alias_unit(name, dimensionless)
        subs[path] = v if unit is None else f"{v!r} {unit}"
    data = substitute({key: val for key, val in base.items() if key != "sweep"}, subs)
    return data


def case_text(scenario, spec, values, k):
    """The TOML text of case ``k``'s scenario (:func:`case_data` written out): ``orbatt run`` of
    it gives the case's results bit for bit."""
    base = tomllib.loads(scenario.text)
    data = case_data(base, spec, values, k, scenario.spec.dimensionless)
    if "sensors" in data and "sensors.case" not in spec.paths:  # each case draws its own noise
        data["sensors"] = {**data["sensors"], "case": int(k)}
    return toml_text(data)


def state_only(name):
    """Whether the swept ``name`` changes only the initial state or the principal moments (the
    cases then share one model)."""
    path = ALIAS_PATHS.get(name, name)
    return path.startswith("initial.") or re.fullmatch(r"body\.inertia\[\d\]", path) is not None


#: the tables of the environment (:data:`orbatt.scenario.schema` tables) that alone determine
#: a case's orbit and the fields sampled along it (with the margin, :func:`environment_key`)
ENVIRONMENT_TABLES = ("orbit", "integration", "environment")

_ENVIRONMENTS: OrderedDict = OrderedDict()
_LOCK = threading.Lock()


class Environment:
    """What every case on one orbit shares: the orbit provider, the output times and the
    integration settings (functions of ``[orbit]`` and ``[integration]``) and the field tables
    along the orbit (``tables``: :meth:`orbatt.EnvironmentTorques.field_table`'s, filled as the
    first potential on this orbit samples them, then read by every other)."""

    def __init__(self, sc):
        self.orbit, self.times, self.t_end = sc.orbit, sc.times, sc.t_end
        self.method, self.settings = sc.method, sc.settings
        # the tables' dict of the scenario's own potential, shared (None: a potential without)
        self.tables = getattr(sc.potential, "_field_tables", None)
        self.builds = 0  #: potentials built on it (for tests and benchmarks)


def environment_key(data, spec):
    """The key of a case's environment: the TOML text of its ``[orbit]``, ``[integration]`` and
    ``[environment]`` tables (``data``: the case's scenario, TOML data), whether it is normalized,
    and how far around the run a TLE and the tables are sampled (:func:`~orbatt.scenario.build.
    environment_margin`). Two cases with one key have the same orbit and the same tables."""
    part = {k: data[k] for k in ENVIRONMENT_TABLES if k in data}
    return toml_text(part), bool(spec.dimensionless), float(environment_margin(spec))


def clear_environments():
    """Forget every environment kept by this process (:func:`environment_of`)."""
    with _LOCK:
        _ENVIRONMENTS.clear()


def environment_of(sc, key, build):
    """The :class:`Environment` of ``key`` in this process: kept from an earlier chunk, the
    nominal scenario ``sc``'s own when ``key`` is its key, else that of the scenario ``build()``
    returns (the single run's :class:`~orbatt.scenario.Scenario` of the first case on this
    orbit), then kept (at most :data:`MAX_ENVIRONMENTS`). Returns ``(environment, scenario)``,
    the scenario when one was built (None otherwise)."""
    with _LOCK:
        env = _ENVIRONMENTS.get(key)
        if env is not None:
            _ENVIRONMENTS.move_to_end(key)
            return env, None
        built = None
        if key == _nominal_key(sc):
            env = Environment(sc)
        else:
            built = build()
            env = Environment(built)
        _ENVIRONMENTS[key] = env
        while len(_ENVIRONMENTS) > MAX_ENVIRONMENTS:
            _ENVIRONMENTS.popitem(last=False)
        return env, built


def _nominal_key(sc):
    key = getattr(sc, "_sweep_environment_key", None)
    if key is None:
        data = {k: v for k, v in tomllib.loads(sc.text).items() if k != "sweep"}
        key = environment_key(data, sc.spec)
        sc._sweep_environment_key = key
    return key


def _body(spec, wheels):
    """The :class:`~orbatt.RigidBody` of a case's ``spec`` with ``wheels``, as its single run's
    (:class:`~orbatt.scenario.Scenario`): the principal moments, or the full inertia tensor in
    the body frame (the run then goes through :mod:`orbatt.frame_boundary`)."""
    inertia = spec.inertia if spec.inertia_tensor is None else spec.inertia_tensor
    return RigidBody(inertia if spec.dimensionless else u.Quantity(inertia, U.INERTIA), wheels=wheels)


class CaseModel:
    """A group's model on a shared :class:`Environment`: what :func:`orbatt.sweep.chunk.
    propagate_group` reads of a :class:`~orbatt.scenario.Scenario` (``times``, ``settings``,
    ``method``, ``body``, ``orbit``, ``potential``), built as the single run of the case's
    ``spec`` builds them, the orbit and the field tables taken from ``env``."""

    def __init__(self, spec, env, path=None):
        self.spec, self.path, self.name, self.text = spec, path, spec.name, spec.text
        wheels = [reaction_wheel(w) for w in spec.control["wheels"]] if spec.control is not None else ()
        self.body = _body(spec, wheels)
        self.orbit, self.times, self.t_end = env.orbit, env.times, env.t_end
        self.method, self.settings = env.method, env.settings
        self.potential = build_potential(spec, env.orbit, float(env.times[-1]))
        if env.tables is not None and hasattr(self.potential, "_field_tables"):
            self.potential._field_tables = env.tables  # the fields along this orbit, sampled once
        env.builds += 1


def path_groups(sc, spec, values, n):
    """``[(scenario, idx, bodies, q0, Q0)]``: the ``n`` cases of a chunk (``values[name]`` of
    length ``n``) grouped by their model, in order of first appearance. ``scenario`` is the
    group's first case's :class:`~orbatt.scenario.Scenario` (its orbit, potential, output
    times and settings are every member's); ``bodies`` and the initial states ``q0, Q0 (m, 4)``
    are each case's own."""
    base = tomllib.loads(sc.text)
    dimless = sc.spec.dimensionless
    model = [name for name in spec.parameters if not state_only(name)]
    order, members = [], {}
    for k in range(n):
        key = tuple(float(values[name][k]) for name in model)
        if key not in members:
            order.append(key)
            members[key] = []
        members[key].append(k)
    source = str(sc.path) if sc.path is not None else sc.name
    out = []
    for key in order:
        idx = np.asarray(members[key], dtype=np.int64)
        specs = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the nominal scenario warned
            data0 = None
            for k in idx:
                data = case_data(base, spec, values, int(k), dimless)
                data0 = data if data0 is None else data0
                specs.append(parse(toml_text(data), source))
            env, built = environment_of(sc, environment_key(data0, specs[0]),
                                        lambda: Scenario(specs[0], path=sc.path))
            scenario = built if built is not None else CaseModel(specs[0], env, sc.path)
        ctx = FieldContext(source)
        wheels = scenario.body.wheels
        bodies, q0, Q0 = [], [], []
        for s in specs:
            body = _body(s, wheels)
            state = build_initial_state(ctx, s, body, scenario.orbit)
            bodies.append(body)
            q0.append(state.q)
            Q0.append(state.Q)
        out.append((scenario, idx, bodies, np.array(q0), np.array(Q0)))
    return out

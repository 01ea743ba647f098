"""The cases of a sweep that varies scenario keys by their paths (issue 23; ``docs/sweeps.md``:
Parameters by path): each case's scenario written out, and the cases grouped so that each
group is one ensemble call.

A case's scenario is the nominal file with the swept leaves replaced (:func:`case_data`,
:func:`case_text`); its single run is the definition of the case. Cases whose scenarios
differ only in the initial state and the principal moments share the orbit, the environment
tables and the control law: they form one group, whose model is built once by the single
run's own :class:`~orbatt.scenario.Scenario` (of the group's first case) and whose members'
bodies and initial states are built from each case's own scenario by the single run's
builders (:func:`~orbatt.scenario.build.build_initial_state`). So every case equals the
single run of its scenario, bit for bit.
"""
from __future__ import annotations

import re
import tomllib
import warnings

import numpy as np
from astropy import units as u

from .. import units as U
from ..body import RigidBody
from ..scenario import FieldContext, Scenario, parse
from ..scenario.build import build_initial_state
from ..scenario.paths import ALIAS_PATHS, substitute, toml_text

__all__ = ["ALIAS_PATHS", "case_data", "case_text", "state_only", "path_groups"]



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
    return toml_text(case_data(base, spec, values, k, scenario.spec.dimensionless))


def state_only(name):
    """Whether the swept ``name`` changes only the initial state or the principal moments (the
    cases then share one model)."""
    path = ALIAS_PATHS.get(name, name)
    return path.startswith("initial.") or re.fullmatch(r"body\.inertia\[\d\]", path) is not None


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
            for k in idx:
                specs.append(parse(toml_text(case_data(base, spec, values, int(k), dimless)), source))
            scenario = Scenario(specs[0], path=sc.path)
        ctx = FieldContext(source)
        wheels = scenario.body.wheels
        bodies, q0, Q0 = [], [], []
        for s in specs:
            body = RigidBody(s.inertia if s.dimensionless else u.Quantity(s.inertia, U.INERTIA), wheels=wheels)
            state = build_initial_state(ctx, s, body, scenario.orbit)
            bodies.append(body)
            q0.append(state.q)
            Q0.append(state.Q)
        out.append((scenario, idx, bodies, np.array(q0), np.array(Q0)))
    return out

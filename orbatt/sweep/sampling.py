"""Drawing a sweep's samples: the nominal values, grids, distributions, the seed's one
generator, and resampling outside the physical limits.

The order is part of the contract (``docs/sweeps.md``, Reproducibility): every case's values
are drawn once, before any chunking, from ``numpy.random.Generator(PCG64(seed))``: first
every random parameter (canonical order, one array over all cases), then the attitude axes,
then the resampling rounds. Values are in internal units (:mod:`orbatt.units`).
"""
from __future__ import annotations

import itertools

import numpy as np

from ..body import triangle_violation
from ..errors import InputError
from ..scenario.paths import leaf_quantity, resolve
from ..scenario.sweep_schema import (DEFAULT_LEAVES, INERTIA_PARAMETERS, SweepSpec, definition, in_limits,
                                     limits_text)

__all__ = ["nominal_values", "nominal_rates", "draw_samples", "MAX_RESAMPLE_ROUNDS", "SAMPLING_VERSION"]

MAX_RESAMPLE_ROUNDS = 1000
#: version of the drawing code: raise it whenever a seed would give other samples (it enters
#: every sweep's fingerprint, so parts drawn by other code are not merged)
SAMPLING_VERSION = 1


def nominal_values(scenario):
    """Nominal value of every parameter the scenario has (internal units)."""
    spec = scenario.spec
    out = {f"inertia{k + 1}": float(spec.inertia[k]) for k in range(3)}
    if spec.orbit is None or spec.orbit["provider"] != "coupled":  # a binary varies its keys by path only
        w = nominal_rates(scenario)
        out.update({f"omega{k + 1}": float(w[k]) for k in range(3)})
        out["attitude_angle"] = 0.0
    if spec.orbit is not None and spec.orbit["provider"] not in ("tle", "coupled"):  # a TLE's elements do not vary
        o = spec.orbit
        out.update(orbit_a=o["a"], orbit_e=o["e"], orbit_i=o["i"], orbit_raan=o["raan"], orbit_argp=o["argp"])
        out[f"orbit_{o['anomaly_kind']}"] = o["anomaly"]
    if spec.sweep is not None and spec.sweep.paths:  # a path's nominal value: the file's (else the key's
        import tomllib                                 # default), in the key's unit

        data = tomllib.loads(scenario.text)
        for path in spec.sweep.paths:
            out[path] = leaf_quantity(resolve(data, path, DEFAULT_LEAVES))[0]
    return out


def nominal_rates(scenario):
    """Nominal initial body rates (3,): ``[initial] omega`` as given (relative to the orbital
    frame when ``frame = "orbital"``), else the rates of the nominal state (rad/s or plain)."""
    ini = scenario.spec.initial
    if "omega" in ini:
        return np.asarray(ini["omega"], dtype=np.float64)
    return np.asarray(scenario.state0.omega, dtype=np.float64)


def draw_samples(spec: SweepSpec, seed, nominal, unit_text, check=None):
    """Every case's parameter values and attitude axes (``docs/sweeps.md``: Reproducibility).

    Parameters
    ----------
    spec : SweepSpec
    seed : int
        Seed of the one generator ``numpy.random.Generator(PCG64(seed))``.
    nominal : dict
        :func:`nominal_values` (internal units).
    unit_text : dict
        CF unit string of every parameter (for messages).
    check : callable, optional
        ``check(values, cases) -> (n,) bool``: the cases (indices) whose own scenario is
        invalid (a sweep of scenario paths); they count as outside the limits, in each path.

    Returns
    -------
    values : dict of str to ndarray (cases,)
        Every swept parameter's value per case (internal units).
    axis : ndarray (cases, 3) or None
        Unit axes of the attitude perturbation (body components).
    resampled : int
        Cases redrawn for the physical limits.

    Raises
    ------
    InputError
        A sample outside the physical limits with ``on_invalid = "error"`` (naming the case,
        the parameter and the value), or resampling that does not converge.
    """
    n = spec.cases
    values = {}
    grid = spec.grid
    if grid:
        idx = np.array(list(itertools.product(*[range(len(d.values)) for d in grid.values()])), dtype=np.int64)
        for j, (name, d) in enumerate(grid.items()):
            values[name] = np.repeat(np.asarray(d.values, dtype=np.float64)[idx[:, j]], spec.samples)
    rng = np.random.Generator(np.random.PCG64(seed))
    for name, d in spec.random.items():
        values[name] = np.asarray(d.draw(rng, n, nominal[name]), dtype=np.float64)
    axis = None
    if "attitude_angle" in spec.parameters:
        axis = rng.normal(size=(n, 3))
        # |axis| per case, written out (no reduction across cases)
        axis /= np.sqrt(axis[:, 0] * axis[:, 0] + axis[:, 1] * axis[:, 1] + axis[:, 2] * axis[:, 2])[:, None]
    # physical limits
    resampled = np.zeros(n, dtype=bool)
    unchecked = np.ones(n, dtype=bool)
    for _ in range(MAX_RESAMPLE_ROUNDS + 1):
        bad = {name: ~in_limits(definition(name), v) for name, v in values.items()}
        if check is not None:  # each case's own scenario must be valid (parameters given by path)
            invalid = check(values, np.flatnonzero(unchecked))
            unchecked[:] = False
            for name in spec.paths:
                bad[name] = bad[name] | invalid
        inertia = np.stack([values.get(k, np.full(n, nominal[k])) for k in INERTIA_PARAMETERS], axis=-1)
        tri = triangle_violation(inertia)
        if tri.any():
            for k in INERTIA_PARAMETERS:
                if k in values:
                    bad[k] = bad[k] | tri
        any_bad = np.zeros(n, dtype=bool)
        for b in bad.values():
            any_bad |= b
        any_bad |= tri
        if spec.min_apoapsis is not None and "orbit_a" in values:
            e = values.get("orbit_e", np.full(n, nominal["orbit_e"]))
            inside = values["orbit_a"] * (1.0 + e) < spec.min_apoapsis
            if inside.any() and spec.on_invalid == "error":
                case = int(np.flatnonzero(inside)[0])
                raise InputError(f"[sweep.parameters] orbit_a: case {case} drew a = {values['orbit_a'][case]:.6g} km "
                                 f"with e = {e[case]:.6g}: the whole orbit lies inside the Earth (radius "
                                 f"{spec.min_apoapsis:.6g} km); narrow the distribution (truncnormal with low) or set "
                                 "[sweep] on_invalid = \"resample\"")
            bad["orbit_a"] = bad["orbit_a"] | inside
            any_bad |= inside
        if not any_bad.any():
            break
        fixable = {k for k, d in spec.random.items() if bad[k].any()}
        case = int(np.flatnonzero(any_bad)[0])
        if spec.on_invalid == "error" or not fixable or (tri.any() and not (set(spec.random) & set(INERTIA_PARAMETERS))):
            raise InputError(_invalid_message(spec, values, bad, tri, case, nominal, unit_text, check))
        for k in spec.random:  # canonical order
            if k in fixable:
                m = bad[k]
                values[k][m] = spec.random[k].draw(rng, int(m.sum()), nominal[k])
                resampled |= m
                unchecked |= m
    else:
        raise InputError(f"[sweep] on_invalid: after {MAX_RESAMPLE_ROUNDS} rounds of resampling some samples are "
                         "still outside the physical limits; narrow the distributions (e.g. truncnormal)")
    return values, axis, int(resampled.sum())


def _invalid_message(spec, values, bad, tri, case, nominal, unit_text, check=None):
    where = f"{spec.source}: [sweep.parameters]" if getattr(spec, "source", None) else "[sweep.parameters]"
    reason = getattr(check, "messages", {}).get(case)
    if reason is not None:
        drew = ", ".join(f"{name} = {values[name][case]:.6g} {'' if unit_text[name] == '1' else unit_text[name]}".rstrip()
                         for name in spec.paths)
        return (f"{where}: case {case} ({drew}) makes the scenario invalid: {reason}; narrow the distributions or set "
                "[sweep] on_invalid = \"resample\"")
    for name, b in bad.items():
        if b[case] and not (tri[case] and name in INERTIA_PARAMETERS):
            p = definition(name)
            return (f"{where} {name}: case {case} drew {values[name][case]:.6g}, outside the physical range "
                    f"{limits_text(p, unit_text[name])}; narrow the distribution (truncnormal with low/high) or set "
                    "[sweep] on_invalid = \"resample\"")
    I = [values.get(k, np.full(case + 1, nominal[k]))[case] for k in INERTIA_PARAMETERS]
    return (f"{where} inertia: case {case} drew I = [{I[0]:.6g}, {I[1]:.6g}, {I[2]:.6g}] {unit_text['inertia1']}, "
            "which violates the triangle inequality Ii + Ij >= Ik (no rigid body has these moments); narrow the "
            "inertia distributions or set [sweep] on_invalid = \"resample\" to redraw such cases")

"""Parameter sweeps (dispersions, Monte Carlo, grids) run on Dask.

A scenario file with a ``[sweep]`` table describes many cases of one study: the nominal
scenario plus parameters that vary from case to case. :func:`load_sweep` validates it and
draws every sample; :func:`run_sweep` cuts the cases into chunks, runs each chunk as **one
ensemble call** of :func:`orbatt.propagate` inside a Dask task (not one task per case),
writes every chunk to disk as it finishes and merges them into one Dataset with a ``case``
dimension. ``orbatt sweep SCENARIO.toml -o OUT.nc`` is the command-line form.

Schema of ``[sweep]`` (quantities are strings astropy parses, in the dimension of the field
they replace; plain numbers for a dimensionless scenario)::

    [sweep]
    samples = 200                # random draws (per grid point); required with random parameters
    seed = 20260320              # optional, 0 <= seed < 2**63; drawn at random and recorded if absent
    chunk_size = 50              # optional: cases per Dask task (default: about 4 tasks per worker)
    outputs = ["final_state", "max_pointing_error", "tumbling"]   # (the default)
    pointing_axis = [1, 0, 0]    # optional body axis (plain numbers); default: the whole attitude
    pointing_reference = "orbital"  # or "inertial"; default "orbital" when [initial] frame = "orbital"
    tumbling_angle = "90 deg"    # tumbling = max pointing error above this (default 90 deg)
    on_invalid = "error"         # or "resample": what to do with samples outside physical limits

    [sweep.parameters]           # one entry per varied parameter (names below)
    inertia1 = { distribution = "normal", std = "0.5 kg m2" }          # mean defaults to the nominal value
    omega3 = { distribution = "uniform", low = "-1e-3 rad/s", high = "1e-3 rad/s" }
    attitude_angle = { distribution = "truncnormal", std = "2 deg", low = "0 deg", high = "10 deg" }
    orbit_a = { values = ["7000 km", "7100 km", "7200 km"] }            # a grid

Parameters (canonical order; the sampling order below follows it, never the file's order):

==================== ========================================================================
``inertia1..3``      principal moments ``I1, I2, I3`` (replace ``[body] inertia[k]``)
``omega1..3``        initial body rates (body components); relative to the orbital frame when
                     ``[initial] frame = "orbital"`` (as ``[initial] omega`` there), inertial
                     otherwise. Nominal value: ``[initial] omega``, or the rates of the nominal
                     state when it is given by ``Q`` or Euler momenta.
``attitude_angle``   a rotation of the nominal initial attitude by this angle about a random
                     body axis, uniform on the sphere (drawn from the same generator and stored
                     as the coordinate ``attitude_axis``): ``q = q_nominal (cos a/2, sin a/2 n)``
``orbit_a, orbit_e,  the Keplerian elements of ``[orbit]`` (``orbit_true_anomaly`` or
orbit_i, orbit_raan, ``orbit_mean_anomaly``: whichever ``[orbit]`` gives)
orbit_argp, ...``
==================== ========================================================================

Each parameter is either a grid ``{ values = [...] }`` or a distribution:
``uniform`` (``low``, ``high``), ``normal`` (``mean``, ``std``) or ``truncnormal``
(``mean``, ``std`` and at least one of ``low``, ``high``); ``mean`` defaults to the
nominal value of the scenario.

Cases
    The Cartesian product of the grids (the first grid parameter varies slowest) times
    ``samples`` random draws: case ``k = g * samples + s`` has grid point ``g`` and draw
    ``s``. Without random parameters ``samples`` is 1 and must be left out.
The initial state of a case
    Built from its attitude and **rates** (the rates are what a dispersion holds, so an
    inertia dispersion changes the angular momentum), with its own inertia and orbit. A case
    whose parameters touch nothing of the initial state uses the nominal ``(q, Q)`` as is.
Times
    The output times of the nominal scenario (``"N orbits"`` uses the nominal period, also
    when ``orbit_a`` varies).

Outputs (``outputs``)
    ``"trajectory"``: the full Dataset of :func:`orbatt.to_dataset` for every case;
    ``"final_state"``: ``q_initial, Q_initial, q_final, Q_final`` (case, quat);
    ``"max_pointing_error"``: the largest angle over the output times between the body and
    the reference frame (``pointing_reference``): the whole attitude's rotation angle, or,
    with ``pointing_axis = b``, the angle between the body axis ``b`` and the reference axis
    with the same components;
    ``"tumbling"``: 1 where the maximum pointing error exceeds ``tumbling_angle``;
    ``"final_energy_error"``: ``(E(t_end) - E(t0)) / |E(t0)|`` of the conserved energy:
    ``H = T + U`` (torque-free, heavy top) or the Jacobi integral ``H - n h.G`` (gravity
    gradient on a circular Keplerian orbit: ``n`` mean motion, ``h`` orbit normal, ``G`` space
    angular momentum). Refused where nothing is conserved (eccentric or REBOUND orbits).
    Always: ``inertia`` (case, axis), ``integration_failed`` (1 for a case whose integration
    stopped, e.g. a non-finite state: its values are NaN; the other cases are unaffected),
    and every swept parameter as a coordinate along ``case`` (internal units: kg km^2, rad,
    rad/s, km).

Physical limits
    Moments positive and obeying the triangle inequality ``Ii + Ij >= Ik``; ``0 <= e < 1``;
    ``a > 0``; ``0 <= i <= 180 deg``. A ``uniform``/``truncnormal`` range or a grid value
    outside them is refused when the file is read. A normal draw outside them is refused too
    (``on_invalid = "error"``, the default: the message names the case, the parameter and
    the value), or, with ``on_invalid = "resample"``, drawn again: the offending parameter
    (for the triangle inequality: every random moment of that case) is redrawn from the same
    generator, after all first draws, in canonical order, until every case is valid; the
    count is recorded (``sweep_resampled_cases``). Resampling truncates the distribution:
    prefer ``truncnormal`` when the truncation matters.

Reproducibility
    All samples are drawn once, before any chunking, from
    ``numpy.random.Generator(PCG64(seed))``: first every random parameter (canonical order,
    one array over all cases), then the attitude axes, then the resampling rounds. Every case
    is then integrated independently of the others (the ensemble kernels give each member
    its own step-size control), so the same seed gives bitwise the same samples and results
    for any number of workers, chunk size, scheduler, or resumption. A missing seed is drawn
    from the operating system's entropy and recorded (``sweep_seed``); ``--resume`` reuses
    the recorded one.

Storage and resumption (:func:`run_sweep`)
    Chunks are written, as they finish, to ``OUT.parts/`` beside the output, one netCDF file
    per chunk named by its case range (``cases-0000000-0000063.nc``). A part is written under
    a temporary name and renamed when complete, so a file with a final name is a complete
    chunk; a crash loses at most the chunks in flight. ``OUT.parts/sweep.json`` records the
    sweep's fingerprint (scenario text, seed, number of cases). When every chunk is there the
    parts are merged into ``OUT`` (reductions in memory; trajectories lazily, with dask, so
    they never have to fit in memory) - netCDF, or Zarr for an output named ``*.zarr``
    (needs the ``zarr`` package) - written under a temporary name, renamed, and the parts
    folder is removed. A rerun with ``resume=True`` (``--resume``) keeps the complete parts,
    checks the fingerprint, and computes only the missing cases (in chunks of the current
    ``chunk_size``). The driver (the process that calls :func:`run_sweep`) writes the parts:
    no shared file system is needed between it and the workers.

Execution
    The chunk function is sent to Dask with the scenario text and the chunk's samples (small;
    nothing is scattered, so a lost worker costs only a recomputation of its chunks: Dask
    retries them on the other workers). Default: a :class:`dask.distributed.LocalCluster` of
    ``workers`` processes (default: one per CPU) with one thread each, on 127.0.0.1; each task
    then runs numba with one thread, Dask giving the parallelism. ``scheduler="tcp://..."``
    uses a running ``dask.distributed`` scheduler (its workers need orbatt installed);
    ``scheduler="synchronous"`` runs the chunks one after the other in this process (numba
    uses every core). The results are the same in every case.
"""
from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
import os
import secrets
import shutil
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import canonical as cn
from . import quaternion as qt
from . import units as U
from .errors import InputError, IntegrationError, OrbattError

__all__ = ["SweepSpec", "Distribution", "Sweep", "SweepError", "ChunkInfo", "load_sweep", "run_sweep",
           "PARAMETERS", "OUTPUTS", "DISTRIBUTIONS"]

FORMAT = "orbatt-sweep-1"
#: keys of the [sweep] table
SWEEP_KEYS = ("parameters", "samples", "seed", "chunk_size", "outputs", "pointing_axis", "pointing_reference",
              "tumbling_angle", "on_invalid")
#: outputs that may be asked for
OUTPUTS = ("trajectory", "final_state", "max_pointing_error", "tumbling", "final_energy_error")
DEFAULT_OUTPUTS = ("final_state", "max_pointing_error", "tumbling")
DISTRIBUTIONS = ("uniform", "normal", "truncnormal")
_DIST_KEYS = {"uniform": ("low", "high"), "normal": ("mean", "std"), "truncnormal": ("mean", "std", "low", "high")}
MAX_CASES = 100_000_000
MAX_RESAMPLE_ROUNDS = 1000
#: largest chunk chosen automatically (cases per task)
MAX_AUTO_CHUNK = 1000


@dataclass(frozen=True)
class _Param:
    group: str                # "body", "initial", "orbit"
    kind: str                 # unit kind: inertia, rate, angle, length, one
    low: float = -math.inf    # physical limits
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    long_name: str = ""


_PI = math.pi
#: the parameters a sweep can vary, in canonical (sampling) order
PARAMETERS = {
    "inertia1": _Param("body", "inertia", 0.0, low_open=True, long_name="principal moment of inertia I1"),
    "inertia2": _Param("body", "inertia", 0.0, low_open=True, long_name="principal moment of inertia I2"),
    "inertia3": _Param("body", "inertia", 0.0, low_open=True, long_name="principal moment of inertia I3"),
    "omega1": _Param("initial", "rate", long_name="initial body rate, axis 1"),
    "omega2": _Param("initial", "rate", long_name="initial body rate, axis 2"),
    "omega3": _Param("initial", "rate", long_name="initial body rate, axis 3"),
    "attitude_angle": _Param("initial", "angle", long_name="initial attitude perturbation angle (about attitude_axis)"),
    "orbit_a": _Param("orbit", "length", 0.0, low_open=True, long_name="semi-major axis"),
    "orbit_e": _Param("orbit", "one", 0.0, 1.0, high_open=True, long_name="eccentricity"),
    "orbit_i": _Param("orbit", "angle", 0.0, _PI, long_name="inclination"),
    "orbit_raan": _Param("orbit", "angle", long_name="right ascension of the ascending node"),
    "orbit_argp": _Param("orbit", "angle", long_name="argument of periapsis"),
    "orbit_true_anomaly": _Param("orbit", "angle", long_name="true anomaly at the epoch"),
    "orbit_mean_anomaly": _Param("orbit", "angle", long_name="mean anomaly at the epoch"),
}
_INERTIA = ("inertia1", "inertia2", "inertia3")
_OMEGA = ("omega1", "omega2", "omega3")
_ORBIT = tuple(k for k, p in PARAMETERS.items() if p.group == "orbit")
_CF = {"inertia": ("kg km2", "1"), "rate": ("rad s-1", "1"), "angle": ("rad", "rad"), "length": ("km", "km"),
       "one": ("1", "1")}


def _unit(kind):
    return {"inertia": U.INERTIA, "rate": U.RATE, "angle": U.ANGLE, "length": U.LENGTH,
            "one": U.DIMENSIONLESS}[kind]


# ---------------------------------------------------------------------------------------
# the [sweep] table


@dataclass(frozen=True)
class Distribution:
    """How one parameter varies: a grid of ``values`` or a random ``kind``.

    Attributes
    ----------
    kind : {"grid", "uniform", "normal", "truncnormal"}
    values : tuple of float
        Grid values (internal units).
    low, high, mean, std : float or None
        Distribution parameters (internal units); ``mean = None`` means the nominal value.
    """

    kind: str
    values: tuple = ()
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = None

    @property
    def random(self) -> bool:
        return self.kind != "grid"

    def describe(self, nominal=None) -> dict:
        """Plain description (for the Dataset's ``sweep_parameters``)."""
        if self.kind == "grid":
            return {"kind": "grid", "values": list(self.values)}
        d = {"kind": self.kind}
        for k in ("mean", "std", "low", "high"):
            v = getattr(self, k)
            if k == "mean" and v is None and self.kind != "uniform":
                v = nominal
            if v is not None and not (k in ("low", "high") and math.isinf(v)):
                d[k] = v
        return d

    def draw(self, rng, n, nominal):
        """``n`` samples from ``rng`` (a :class:`numpy.random.Generator`)."""
        if self.kind == "uniform":
            return rng.uniform(self.low, self.high, n)
        mean = nominal if self.mean is None else self.mean
        if self.kind == "normal":
            return rng.normal(mean, self.std, n)
        from scipy.stats import truncnorm

        u = rng.random(n)
        lo = -math.inf if self.low is None else (self.low - mean) / self.std
        hi = math.inf if self.high is None else (self.high - mean) / self.std
        x = truncnorm.ppf(u, lo, hi, loc=mean, scale=self.std)
        return np.clip(x, -math.inf if self.low is None else self.low, math.inf if self.high is None else self.high)


@dataclass
class SweepSpec:
    """The validated ``[sweep]`` table (internal units; see the module docstring).

    Attributes
    ----------
    parameters : dict of str to Distribution
        In canonical order (:data:`PARAMETERS`).
    samples : int
    seed : int or None
    chunk_size : int or None
    outputs : tuple of str
    pointing_axis : ndarray (3,) or None
        Unit vector (body components).
    pointing_reference : {"orbital", "inertial"}
    tumbling_angle : float
        rad.
    on_invalid : {"error", "resample"}
    """

    parameters: dict
    samples: int = 1
    seed: int | None = None
    chunk_size: int | None = None
    outputs: tuple = DEFAULT_OUTPUTS
    pointing_axis: np.ndarray | None = None
    pointing_reference: str = "inertial"
    tumbling_angle: float = 0.5 * math.pi
    on_invalid: str = "error"
    energy: str | None = None   # "hamiltonian" or "jacobi": the conserved energy (when one exists)

    @property
    def grid(self) -> dict:
        return {k: d for k, d in self.parameters.items() if not d.random}

    @property
    def random(self) -> dict:
        return {k: d for k, d in self.parameters.items() if d.random}

    @property
    def grid_points(self) -> int:
        return math.prod(len(d.values) for d in self.grid.values())

    @property
    def cases(self) -> int:
        return self.grid_points * self.samples


def _int(ctx, where, v, lo, hi=None):
    if isinstance(v, bool) or not isinstance(v, int) or v < lo or (hi is not None and v >= hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi})"
        raise ctx.error(where, f"{v!r} must be an integer {rng}")
    return int(v)


def _in_limits(p: _Param, x):
    x = np.asarray(x, dtype=np.float64)
    ok = np.isfinite(x)
    ok &= (x > p.low) if p.low_open else (x >= p.low)
    ok &= (x < p.high) if p.high_open else (x <= p.high)
    return ok


def _limits_text(p: _Param, unit_text):
    lo = "-inf" if math.isinf(p.low) else f"{p.low:g}"
    hi = "inf" if math.isinf(p.high) else f"{p.high:g}"
    lb = "(" if p.low_open or math.isinf(p.low) else "["
    hb = ")" if p.high_open or math.isinf(p.high) else "]"
    return f"{lb}{lo}, {hi}{hb} {unit_text}".rstrip()


def parse_sweep_table(ctx, table, *, dimensionless, potential_kind, orbit, frame):
    """Validate a ``[sweep]`` table (called by :func:`orbatt.scenario.parse`).

    Parameters
    ----------
    ctx : orbatt.scenario._Ctx
        Error context (names the file).
    table : dict
        The TOML table.
    dimensionless : bool
        Whether the scenario's inertia is plain numbers.
    potential_kind : str
    orbit : dict or None
        The validated ``[orbit]`` table.
    frame : str
        ``[initial] frame``.

    Returns
    -------
    SweepSpec

    Raises
    ------
    ScenarioError
        Naming ``[sweep] key`` or ``[sweep.parameters.NAME] key``, the value and the fix.
    """
    from .scenario import parse_quantity

    for k in table:
        if k not in SWEEP_KEYS:
            raise ctx.error(f"[sweep] {k}", f"unknown key; allowed keys in [sweep]: {', '.join(sorted(SWEEP_KEYS))}")
    raw = table.get("parameters")
    if not isinstance(raw, dict) or not raw:
        raise ctx.error("[sweep] parameters", "missing or empty; give at least one parameter to vary, e.g. "
                                              "[sweep.parameters] inertia1 = { distribution = \"normal\", std = \"1 kg m2\" }")
    for name in raw:
        if name not in PARAMETERS:
            raise ctx.error(f"[sweep.parameters] {name}", f"unknown parameter; allowed: {', '.join(PARAMETERS)}")
    params = {}
    for name in PARAMETERS:  # canonical order
        if name not in raw:
            continue
        p = PARAMETERS[name]
        where = f"[sweep.parameters.{name}]"
        if p.group == "orbit":
            if orbit is None:
                raise ctx.error(where, "orbit elements vary only in a scenario with an [orbit]")
            if name in ("orbit_true_anomaly", "orbit_mean_anomaly") and name[6:] != orbit["anomaly_kind"]:
                raise ctx.error(where, f"the [orbit] gives {orbit['anomaly_kind']}; vary orbit_{orbit['anomaly_kind']}")
        unit = _unit(p.kind)
        dimless = dimensionless if p.kind in ("inertia", "rate") else p.kind in ("one", "angle")
        cf = _CF[p.kind][1 if dimensionless else 0]

        def q(key, value, _where=where, _unit=unit, _dimless=dimless):
            return parse_quantity(ctx, f"{_where} {key}", value, _unit, dimensionless=_dimless)

        d = raw[name]
        if not isinstance(d, dict):
            raise ctx.error(where, f"expected a table such as {{ values = [...] }} or {{ distribution = \"normal\", "
                                   f"std = ... }}, got {d!r}")
        if "values" in d:
            extra = sorted(set(d) - {"values"})
            if extra:
                raise ctx.error(f"{where} {extra[0]}", "a grid takes only 'values'; remove it or give a distribution")
            vals = d["values"]
            if not isinstance(vals, list) or not vals:
                raise ctx.error(f"{where} values", f"expected a non-empty list, got {vals!r}")
            v = tuple(q(f"values[{i}]", x) for i, x in enumerate(vals))
            bad = np.flatnonzero(~_in_limits(p, v))
            if bad.size:
                raise ctx.error(f"{where} values[{bad[0]}]", f"{vals[bad[0]]!r} is outside the physical range "
                                                            f"{_limits_text(p, cf)}")
            if len(set(v)) != len(v):
                raise ctx.error(f"{where} values", f"{vals!r} repeats a value; give distinct grid values")
            params[name] = Distribution("grid", values=v)
            continue
        kind = d.get("distribution")
        if kind in ("truncated-normal", "truncated_normal"):
            kind = "truncnormal"
        if kind not in DISTRIBUTIONS:
            raise ctx.error(f"{where} distribution", f"{kind!r} is not one of {', '.join(map(repr, DISTRIBUTIONS))} "
                                                     "(or give a grid: values = [...])")
        allowed = set(_DIST_KEYS[kind]) | {"distribution"}
        for k in d:
            if k not in allowed:
                raise ctx.error(f"{where} {k}", f"unknown key for a {kind} distribution; allowed: "
                                                f"{', '.join(sorted(allowed))}")
        vals = {k: q(k, d[k]) for k in _DIST_KEYS[kind] if k in d}
        if kind == "uniform":
            for k in ("low", "high"):
                if k not in vals:
                    raise ctx.error(f"{where} {k}", "missing; a uniform distribution needs low and high")
        else:
            if "std" not in vals:
                raise ctx.error(f"{where} std", f"missing; a {kind} distribution needs std (mean defaults to the "
                                                "nominal value)")
            if not vals["std"] > 0:
                raise ctx.error(f"{where} std", f"{d['std']!r} must be positive")
            if kind == "truncnormal" and "low" not in vals and "high" not in vals:
                raise ctx.error(f"{where} low", "a truncnormal distribution needs low and/or high (or use normal)")
        if "low" in vals and "high" in vals and not vals["low"] < vals["high"]:
            raise ctx.error(f"{where} high", f"{d['high']!r} is not above low = {d['low']!r}")
        for k in ("low", "high"):
            if k in vals:
                x = vals[k]
                edge_ok = (x >= p.low if k == "low" else x <= p.high)
                if not edge_ok or (k == "low" and x >= p.high) or (k == "high" and x <= p.low):
                    raise ctx.error(f"{where} {k}", f"{d[k]!r} leaves the physical range {_limits_text(p, cf)}; "
                                                    "no sample may fall outside it")
        if kind == "uniform" and p.low_open and vals["low"] == p.low:
            raise ctx.error(f"{where} low", f"{d['low']!r}: a sample may equal low, which is outside the physical "
                                            f"range {_limits_text(p, cf)}")
        if "mean" in vals and not np.isfinite(vals["mean"]):
            raise ctx.error(f"{where} mean", f"{d['mean']!r} is not finite")
        params[name] = Distribution(kind, low=vals.get("low"), high=vals.get("high"), mean=vals.get("mean"),
                                    std=vals.get("std"))

    spec = SweepSpec(parameters=params)
    n_random = sum(d.random for d in params.values())
    if "samples" in table:
        spec.samples = _int(ctx, "[sweep] samples", table["samples"], 1)
        if not n_random:
            raise ctx.error("[sweep] samples", "only random parameters are sampled; with grids only, remove samples")
    elif n_random:
        raise ctx.error("[sweep] samples", "missing; give the number of random draws, e.g. samples = 100")
    if spec.cases > MAX_CASES:
        raise ctx.error("[sweep] samples", f"{spec.cases} cases is more than {MAX_CASES}; split the study")
    if "seed" in table:
        spec.seed = _int(ctx, "[sweep] seed", table["seed"], 0, 2**63)
    if "chunk_size" in table:
        spec.chunk_size = _int(ctx, "[sweep] chunk_size", table["chunk_size"], 1)
    if "outputs" in table:
        outs = table["outputs"]
        if not isinstance(outs, list) or not outs:
            raise ctx.error("[sweep] outputs", f"expected a non-empty list such as {list(DEFAULT_OUTPUTS)}, got {outs!r}")
        for o in outs:
            if o not in OUTPUTS:
                raise ctx.error("[sweep] outputs", f"{o!r} is not one of {', '.join(map(repr, OUTPUTS))}")
        spec.outputs = tuple(o for o in OUTPUTS if o in outs)
    if "pointing_axis" in table:
        ax = table["pointing_axis"]
        if not (isinstance(ax, list) and len(ax) == 3 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                                for x in ax)):
            raise ctx.error("[sweep] pointing_axis", f"expected a body axis [x, y, z] of plain numbers, got {ax!r}")
        a = np.array(ax, dtype=float)
        n = float(np.linalg.norm(a))
        if not (np.all(np.isfinite(a)) and n > 0):
            raise ctx.error("[sweep] pointing_axis", f"{ax!r} has no direction; give a nonzero body axis")
        spec.pointing_axis = a / n
    spec.pointing_reference = "orbital" if frame == "orbital" else "inertial"
    if "pointing_reference" in table:
        ref = table["pointing_reference"]
        if ref not in ("orbital", "inertial"):
            raise ctx.error("[sweep] pointing_reference", f"{ref!r} is not 'orbital' or 'inertial'")
        if ref == "orbital" and orbit is None:
            raise ctx.error("[sweep] pointing_reference", "'orbital' needs an [orbit]; use 'inertial'")
        spec.pointing_reference = ref
    if "tumbling_angle" in table:
        if "tumbling" not in spec.outputs:
            raise ctx.error("[sweep] tumbling_angle", "only used with 'tumbling' in outputs; remove it or add the output")
        spec.tumbling_angle = parse_quantity(ctx, "[sweep] tumbling_angle", table["tumbling_angle"], U.ANGLE,
                                        dimensionless=True)
        if not 0 < spec.tumbling_angle <= math.pi:
            raise ctx.error("[sweep] tumbling_angle", f"{table['tumbling_angle']!r} is outside (0, 180] deg")
    for k in ("pointing_axis", "pointing_reference"):
        if k in table and not {"max_pointing_error", "tumbling"} & set(spec.outputs):
            raise ctx.error(f"[sweep] {k}", "only used with 'max_pointing_error' or 'tumbling' in outputs")
    if "on_invalid" in table:
        if table["on_invalid"] not in ("error", "resample"):
            raise ctx.error("[sweep] on_invalid", f"{table['on_invalid']!r} is not 'error' or 'resample'")
        spec.on_invalid = table["on_invalid"]
    # the conserved energy, if any
    if potential_kind in ("torque-free", "heavy-top"):
        spec.energy = "hamiltonian"
    elif orbit is not None and orbit["provider"] == "kepler" and orbit["e"] == 0.0 and "orbit_e" not in params:
        spec.energy = "jacobi"
    if "final_energy_error" in spec.outputs and spec.energy is None:
        why = ("the REBOUND orbit" if orbit["provider"] == "rebound" else
               "orbit_e varies" if "orbit_e" in params else f"the orbit is eccentric (e = {orbit['e']:g})")
        raise ctx.error("[sweep] outputs", f"'final_energy_error': nothing is conserved for a gravity-gradient "
                                           f"potential when {why}; it needs e = 0 on a Kepler orbit (Jacobi "
                                           "integral), or a torque-free or heavy-top scenario. Remove it")
    return spec


# ---------------------------------------------------------------------------------------
# samples


def _nominal(scenario):
    """Nominal value of every parameter the scenario has (internal units)."""
    spec = scenario.spec
    out = {f"inertia{k + 1}": float(spec.inertia[k]) for k in range(3)}
    w = _nominal_rates(scenario)
    out.update({f"omega{k + 1}": float(w[k]) for k in range(3)})
    out["attitude_angle"] = 0.0
    if spec.orbit is not None:
        o = spec.orbit
        out.update(orbit_a=o["a"], orbit_e=o["e"], orbit_i=o["i"], orbit_raan=o["raan"], orbit_argp=o["argp"])
        out[f"orbit_{o['anomaly_kind']}"] = o["anomaly"]
    return out


def _nominal_rates(scenario):
    ini = scenario.spec.initial
    if "omega" in ini:
        return np.asarray(ini["omega"], dtype=np.float64)
    return np.asarray(scenario.state0.omega, dtype=np.float64)


def _draw(spec: SweepSpec, seed, nominal, unit_text):
    """Every case's parameter values and attitude axes (module docstring: Reproducibility)."""
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
        axis /= np.linalg.norm(axis, axis=-1)[:, None]
    # physical limits
    resampled = np.zeros(n, dtype=bool)
    for _ in range(MAX_RESAMPLE_ROUNDS + 1):
        bad = {name: ~_in_limits(PARAMETERS[name], v) for name, v in values.items()}
        inertia = np.stack([values.get(k, np.full(n, nominal[k])) for k in _INERTIA], axis=-1)
        tri = _triangle_violation(inertia)
        if tri.any():
            for k in _INERTIA:
                if k in values:
                    bad[k] = bad[k] | tri
        any_bad = np.zeros(n, dtype=bool)
        for b in bad.values():
            any_bad |= b
        any_bad |= tri
        if not any_bad.any():
            break
        fixable = {k for k, d in spec.random.items() if bad[k].any()}
        case = int(np.flatnonzero(any_bad)[0])
        if spec.on_invalid == "error" or not fixable or (tri.any() and not (set(spec.random) & set(_INERTIA))):
            raise InputError(_invalid_message(spec, values, bad, tri, case, nominal, unit_text))
        for k in spec.random:  # canonical order
            if k in fixable:
                m = bad[k]
                values[k][m] = spec.random[k].draw(rng, int(m.sum()), nominal[k])
                resampled |= m
    else:
        raise InputError(f"[sweep] on_invalid: after {MAX_RESAMPLE_ROUNDS} rounds of resampling some samples are "
                         "still outside the physical limits; narrow the distributions (e.g. truncnormal)")
    return values, axis, int(resampled.sum())


def _triangle_violation(inertia):
    I1, I2, I3 = inertia[:, 0], inertia[:, 1], inertia[:, 2]
    tol = 1.0 - 1e-12  # as RigidBody
    return (I1 + I2 < I3 * tol) | (I2 + I3 < I1 * tol) | (I3 + I1 < I2 * tol)


def _invalid_message(spec, values, bad, tri, case, nominal, unit_text):
    where = "[sweep.parameters]"
    for name, b in bad.items():
        if b[case] and not (tri[case] and name in _INERTIA):
            p = PARAMETERS[name]
            return (f"{where} {name}: case {case} drew {values[name][case]:.6g}, outside the physical range "
                    f"{_limits_text(p, unit_text[name])}; narrow the distribution (truncnormal with low/high) or set "
                    "[sweep] on_invalid = \"resample\"")
    I = [values.get(k, np.full(case + 1, nominal[k]))[case] for k in _INERTIA]
    return (f"{where} inertia: case {case} drew I = [{I[0]:.6g}, {I[1]:.6g}, {I[2]:.6g}] {unit_text['inertia1']}, "
            "which violates the triangle inequality Ii + Ij >= Ik (no rigid body has these moments); narrow the "
            "inertia distributions or set [sweep] on_invalid = \"resample\" to redraw such cases")


# ---------------------------------------------------------------------------------------
# the Sweep object


class Sweep:
    """A validated sweep: the nominal :class:`~orbatt.scenario.Scenario`, its ``[sweep]``
    table, and every case's parameter values (drawn once, here).

    Build one with :func:`load_sweep`.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[sweep]`` table.
    seed : int, optional
        Overrides the table's seed (or fixes the one to use when the table has none).

    Attributes
    ----------
    scenario : Scenario
    spec : SweepSpec
    seed : int
    seed_source : str
        ``"scenario"``, ``"argument"`` or ``"default"`` (drawn from OS entropy).
    cases : int
    values : dict of str to ndarray (cases,)
        Every swept parameter's value per case (internal units).
    attitude_axis : ndarray (cases, 3) or None
    resampled : int
        Cases redrawn for physical limits (``on_invalid = "resample"``).
    nominal : dict
        Nominal value of every parameter (internal units).
    fingerprint : str
        Hash of the scenario text, seed and number of cases (checked on resume).
    """

    def __init__(self, scenario, seed=None):
        spec = scenario.spec.sweep
        if spec is None:
            raise InputError(f"{scenario.path or scenario.name}: [sweep]: missing table; a sweep scenario needs "
                             "[sweep] with samples and [sweep.parameters] (see orbatt.sweep)")
        self.scenario = scenario
        self.spec = spec
        if seed is not None:
            if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**63:
                raise InputError(f"seed: {seed!r} must be an integer in [0, 2**63)")
            self.seed, self.seed_source = int(seed), "argument"
        elif spec.seed is not None:
            self.seed, self.seed_source = spec.seed, "scenario"
        else:
            self.seed, self.seed_source = secrets.randbits(63), "default"
        self.cases = spec.cases
        self.nominal = _nominal(scenario)
        dimless = scenario.spec.dimensionless
        self.units = {k: _CF[p.kind][1 if dimless else 0] for k, p in PARAMETERS.items()}
        self.values, self.attitude_axis, self.resampled = _draw(spec, self.seed, self.nominal, self.units)
        h = hashlib.sha256(f"{FORMAT}\n{self.seed}\n{self.cases}\n".encode() + scenario.text.encode())
        self.fingerprint = h.hexdigest()[:32]

    @property
    def source(self) -> str:
        return str(self.scenario.path) if self.scenario.path is not None else self.scenario.name

    def job(self, start, stop, numba_threads=None) -> dict:
        """The payload of a task: the chunk of cases ``start .. stop - 1``.

        Parameters
        ----------
        start, stop : int
            Case range (``stop`` excluded).
        numba_threads : int, optional
            Threads numba may use inside the task (None: numba's default).

        Returns
        -------
        dict
            The scenario text and source, the range, the chunk's parameter values and
            attitude axes (plain data: cheap to send, nothing to scatter).
        """
        return {"text": self.scenario.text, "source": self.source, "start": int(start), "stop": int(stop),
                "values": {k: v[start:stop].copy() for k, v in self.values.items()},
                "axis": None if self.attitude_axis is None else self.attitude_axis[start:stop].copy(),
                "numba_threads": numba_threads}

    def compute(self, start=0, stop=None):
        """Compute a range of cases here, as one chunk: one ensemble call of
        :func:`orbatt.propagate` per distinct orbit.

        This is what every Dask task runs; ``sweep.compute()`` is the serial reference of a
        whole sweep (numba uses every core).

        Parameters
        ----------
        start, stop : int
            Case range (``stop`` excluded; default all cases).

        Returns
        -------
        xarray.Dataset
            The cases' outputs (dimension ``case``), without the sweep's global attributes
            (:func:`run_sweep` adds them).
        """
        stop = self.cases if stop is None else stop
        if not 0 <= start < stop <= self.cases:
            raise InputError(f"cases: [{start}, {stop}) is not a range within the {self.cases} cases")
        return _compute_chunk(self.scenario, self.spec, self.job(start, stop), self.units)

    def attrs(self) -> dict:
        """The sweep's global attributes (seed, parameters, cases, ...)."""
        desc = {k: dict(d.describe(self.nominal.get(k)), units=self.units[k]) for k, d in self.spec.parameters.items()}
        return {
            "sweep_format": FORMAT,
            "sweep_fingerprint": self.fingerprint,
            "sweep_seed": np.int64(self.seed),
            "sweep_seed_source": self.seed_source,
            "sweep_rng": "numpy.random.Generator(PCG64(sweep_seed))",
            "sweep_cases": np.int64(self.cases),
            "sweep_samples": np.int64(self.spec.samples),
            "sweep_grid_points": np.int64(self.spec.grid_points),
            "sweep_parameters": json.dumps(desc),  # canonical order
            "sweep_outputs": json.dumps(list(self.spec.outputs)),
            "sweep_on_invalid": self.spec.on_invalid,
            "sweep_resampled_cases": np.int64(self.resampled),
        }

    def __repr__(self):
        return (f"Sweep({self.scenario.name!r}, cases={self.cases}, parameters={list(self.spec.parameters)}, "
                f"seed={self.seed})")


def load_sweep(path, *, seed=None) -> Sweep:
    """Read a scenario file with a ``[sweep]`` table, validate it and draw the samples.

    Parameters
    ----------
    path : str or Path
        A TOML file, or the name of a shipped scenario.
    seed : int, optional
        Use this seed instead of the file's (or where the file has none).

    Returns
    -------
    Sweep

    Raises
    ------
    InputError
        A malformed file or ``[sweep]`` table, a missing ``[sweep]``, or (with
        ``on_invalid = "error"``) a sample outside the physical limits, named.
    """
    from .scenario import load_scenario

    return Sweep(load_scenario(path), seed=seed)


# ---------------------------------------------------------------------------------------
# one chunk (runs in the Dask task)


@functools.lru_cache(maxsize=4)
def _scenario_from_text(text, source):
    from .scenario import Scenario, parse

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Scenario(parse(text, source), path=source)


def _run_chunk(job):
    """Task function: compute one chunk from its payload (:meth:`Sweep.job`)."""
    t0 = time.perf_counter()
    threads = job.get("numba_threads")
    if threads:
        import numba

        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    sc = _scenario_from_text(job["text"], job["source"])
    dimless = sc.spec.dimensionless
    units = {k: _CF[p.kind][1 if dimless else 0] for k, p in PARAMETERS.items()}
    ds = _compute_chunk(sc, sc.spec.sweep, job, units)
    ds.attrs["sweep_chunk_seconds"] = time.perf_counter() - t0
    return ds


def _orbit_groups(sc, spec, values, n):
    """``[(orbit, potential, idx)]``: the chunk's cases grouped by identical orbit."""
    swept = [k for k in _ORBIT if k in spec.parameters]
    if not swept:
        return [(sc.orbit, sc.potential, np.arange(n))]
    from .potentials import GravityGradient
    from .scenario import FieldContext, build_kepler_orbit, build_rebound_orbit

    cols = np.stack([values[k] for k in swept], axis=-1)
    keys, first, inverse = np.unique(cols, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    ctx = FieldContext(sc.name)
    out = []
    for g in np.argsort(first):  # in order of first appearance
        o = dict(sc.spec.orbit)
        for k, v in zip(swept, keys[g]):
            if k in ("orbit_true_anomaly", "orbit_mean_anomaly"):
                o["anomaly"] = float(v)
            else:
                o[{"orbit_a": "a", "orbit_e": "e", "orbit_i": "i", "orbit_raan": "raan",
                   "orbit_argp": "argp"}[k]] = float(v)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # periapsis warnings: the nominal scenario already warned
            orbit = build_kepler_orbit(ctx, o)
            if o["provider"] == "rebound":
                orbit = build_rebound_orbit(ctx, o, orbit, float(sc.times[-1]))
        out.append((orbit, GravityGradient(orbit), np.flatnonzero(inverse == g)))
    return out


def _initial_state(sc, spec, values, axis, inertia, orbit, idx):
    """``(q, Q)`` of the cases ``idx`` (module docstring: the initial state of a case)."""
    from .state import State, unit_quaternion

    m = idx.size
    frame = sc.spec.frame
    touches = (any(k in spec.parameters for k in _INERTIA + _OMEGA + ("attitude_angle",))
               or (frame == "orbital" and any(k in spec.parameters for k in _ORBIT)))
    if not touches:
        st = sc.state0
        return np.broadcast_to(st.q, (m, 4)).copy(), np.broadcast_to(st.Q, (m, 4)).copy()
    ini = sc.spec.initial
    w = np.array(np.broadcast_to(_nominal_rates(sc), (m, 3)))
    for k, name in enumerate(_OMEGA):
        if name in values:
            w[:, k] = values[name][idx]
    if frame == "orbital":
        q_nom = ini["q"] if "q" in ini else qt.from_euler313(*ini["euler_313"])
        q_nom = q_nom / qt.norm(q_nom)
    else:
        q_nom = sc.state0.q
    q_c = np.array(np.broadcast_to(q_nom, (m, 4)))
    if "attitude_angle" in spec.parameters:
        q_c = qt.mul(q_c, qt.from_axis_angle(axis[idx], values["attitude_angle"][idx]))
    I = inertia[idx]
    if frame == "orbital":
        from .orbital import body_rate_from_orbital
        from .orbits.base import as_times

        t0 = as_times(float(sc.times[0]))
        q = qt.mul(orbit.orbital_quaternion(t0), q_c)
        w = body_rate_from_orbital(orbit, t0, q_c, w)
    else:
        q = q_c
    q = unit_quaternion(q)
    st = State(sc.body, q, cn.momentum_from_omega(q, w, I))
    return st.q, st.Q


def _propagate_group(sc, bodies, q0, Q0, potential):
    """Ensemble propagation of one group; a member that fails is rerun alone and left NaN
    (members are independent, so the others' results do not change)."""
    from .propagate import propagate
    from .state import State

    kw = dict(sc.settings)
    m = q0.shape[0]
    failed = np.zeros(m, dtype=bool)
    try:
        tr = propagate(bodies if len(bodies) > 1 else bodies[0], State(sc.body, q0, Q0), potential, sc.times,
                       method=sc.method, **kw)
        return tr, tr.q, tr.Q, failed, dict(tr.stats)
    except IntegrationError:
        pass
    N = sc.times.size
    q = np.full((m, N, 4), np.nan)
    Q = np.full((m, N, 4), np.nan)
    stats = {}
    tr = None
    for e in range(m):
        b = bodies[e] if len(bodies) > 1 else bodies[0]
        try:
            t1 = propagate([b], State(sc.body, q0[e:e + 1], Q0[e:e + 1]), potential, sc.times, method=sc.method, **kw)
        except IntegrationError:
            failed[e] = True
            continue
        tr = t1
        q[e], Q[e] = t1.q[0], t1.Q[0]
        for k, v in t1.stats.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                stats[k] = stats.get(k, 0) + v
    return tr, q, Q, failed, stats


def _pointing_error(spec, q, p):
    """Angle (rad) between the body and the reference frame at every output, ``q (m, N, 4)``;
    ``p (N, 4)`` the orbital quaternion (or None for the inertial reference)."""
    q_rel = q if p is None else qt.mul(qt.conj(p)[None], q)
    if spec.pointing_axis is None:
        v = np.linalg.norm(q_rel[..., 1:], axis=-1)
        return 2.0 * np.arctan2(v, np.abs(q_rel[..., 0]))
    b = spec.pointing_axis
    b_ref = qt.rotate(q_rel, b)  # the body axis in reference-frame components
    c = np.linalg.norm(np.cross(b_ref, b), axis=-1)
    return np.arctan2(c, np.sum(b_ref * b, axis=-1))


def _energy(spec, sc, potential, orbit, inertia, q, Q, t):
    """Conserved energy (H or the Jacobi integral) of members ``q, Q (m, 4)`` at time ``t``."""
    from .core import potentials as kp

    T = cn.kinetic_energy(q, Q, inertia)
    Upot = np.empty(q.shape[0])
    tt = np.array([t])
    for e in range(q.shape[0]):
        if not np.all(np.isfinite(q[e])):
            Upot[e] = np.nan
            continue
        Upot[e] = kp.evaluate_many(tt, np.ascontiguousarray(q[e:e + 1]), np.ascontiguousarray(inertia[e]),
                                   int(potential.kind), np.asarray(potential.params, dtype=np.float64),
                                   np.asarray(potential.table, dtype=np.float64), kp.new_work())[0][0]
    H = T + Upot
    if spec.energy == "jacobi":
        h = qt.rotate(orbit.orbital_quaternion(np.array(0.0)), np.array([0.0, 0.0, 1.0]))
        G = cn.space_momentum(q, Q)
        # h.G per member, written out: a BLAS product's kernel (and its rounding) depends on
        # how many members share the call and on the CPU (issue 14)
        H = H - orbit.n * (G[:, 0] * h[0] + G[:, 1] * h[1] + G[:, 2] * h[2])
    return H


def _compute_chunk(sc, spec, job, units):
    import xarray as xr

    from .dataset import QUAT_INDEX, QUAT_LABELS, AXIS_INDEX, AXIS_LABELS, DIMENSIONAL_UNITS, DIMENSIONLESS_UNITS, cf_variable
    from .dataset import to_dataset
    from .trajectory import Trajectory

    start, stop = job["start"], job["stop"]
    n = stop - start
    values = job["values"]
    axis = job["axis"]
    dimless = sc.spec.dimensionless
    UN = DIMENSIONLESS_UNITS if dimless else DIMENSIONAL_UNITS
    inertia = np.array(np.broadcast_to(sc.spec.inertia, (n, 3)), dtype=np.float64)
    for k, name in enumerate(_INERTIA):
        if name in values:
            inertia[:, k] = values[name]
    vary_inertia = any(k in spec.parameters for k in _INERTIA)
    if vary_inertia:
        from .body import RigidBody

        iu = sc.body.inertia_unit
        all_bodies = [RigidBody(inertia[e].tolist() if dimless else inertia[e] * iu) for e in range(n)]
    outs = set(spec.outputs)
    qi, Qi, qf, Qf = (np.empty((n, 4)) for _ in range(4))
    failed = np.zeros(n, dtype=bool)
    perr = np.full(n, np.nan)
    eerr = np.full(n, np.nan)
    stats = {}
    pieces = []
    for orbit, potential, idx in _orbit_groups(sc, spec, values, n):
        q0, Q0 = _initial_state(sc, spec, values, axis, inertia, orbit, idx)
        bodies = [all_bodies[e] for e in idx] if vary_inertia else [sc.body]
        tr, q, Q, bad, st = _propagate_group(sc, bodies, q0, Q0, potential)
        for k, v in st.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                stats[k] = stats.get(k, 0) + v
        failed[idx] = bad
        qi[idx], Qi[idx] = q0, Q0
        qf[idx], Qf[idx] = q[:, -1], Q[:, -1]
        if {"max_pointing_error", "tumbling"} & outs:
            p = orbit.orbital_quaternion(sc.times) if spec.pointing_reference == "orbital" else None
            perr[idx] = np.max(_pointing_error(spec, q, p), axis=-1)
        if "final_energy_error" in outs:
            E0 = _energy(spec, sc, potential, orbit, inertia[idx], q[:, 0], Q[:, 0], float(sc.times[0]))
            E1 = _energy(spec, sc, potential, orbit, inertia[idx], q[:, -1], Q[:, -1], float(sc.times[-1]))
            eerr[idx] = (E1 - E0) / np.abs(E0)
        if "trajectory" in outs:
            body0 = bodies[0]
            full = Trajectory(body=body0, potential=potential, t=sc.times, q=q, Q=Q,
                              inertia=inertia[idx], method=tr.method if tr is not None else sc.method,
                              settings=tr.settings if tr is not None else {}, stats=st, complete=True)
            with np.errstate(invalid="ignore"):
                piece = to_dataset(full, scenario_text=sc.text, title=f"orbatt sweep: {sc.name}")
            piece = piece.assign_coords(case=("case", start + idx, piece["case"].attrs))
            if any(k in spec.parameters for k in _ORBIT):
                for name in ("r", "p", "true_anomaly", "position", "velocity"):
                    if name in piece:
                        piece[name] = piece[name].expand_dims(case=piece["case"].size).copy()
            pieces.append(piece)

    case = start + np.arange(n)
    coords = {"case": cf_variable(("case",), case, "1", "sweep case (index into the sampled parameters)"),
              "axis": cf_variable(("axis",), AXIS_INDEX, "1", "vector component index (axis 1, 2, 3 of the named frame)"),
              "axis_label": xr.Variable(("axis",), np.array(AXIS_LABELS), {"long_name": "vector component name"})}
    if "final_state" in outs:
        coords["quat"] = cf_variable(("quat",), QUAT_INDEX, "1", "quaternion component index (0 = scalar part)",
                              quaternion_order="w x y z")
        coords["quat_label"] = xr.Variable(("quat",), np.array(QUAT_LABELS), {"long_name": "quaternion component name"})
    for name in spec.parameters:
        coords[name] = cf_variable(("case",), values[name], units[name], f"sampled parameter: {PARAMETERS[name].long_name}")
    if axis is not None:
        coords["attitude_axis"] = cf_variable(("case", "axis"), axis, "1",
                                       "axis of the initial attitude perturbation (unit vector)", frame="B")
    data = {}
    qattrs = {"quaternion_order": "w x y z", "frames": "B relative to S"}
    if "final_state" in outs:
        data["q_initial"] = cf_variable(("case", "quat"), qi, "1", "initial attitude quaternion", **qattrs)
        data["Q_initial"] = cf_variable(("case", "quat"), Qi, UN["momentum"], "initial conjugate momentum")
        data["q_final"] = cf_variable(("case", "quat"), qf, "1", "final attitude quaternion (at the last output time)",
                               **qattrs)
        data["Q_final"] = cf_variable(("case", "quat"), Qf, UN["momentum"], "final conjugate momentum")
    if "trajectory" not in outs:
        data["inertia"] = cf_variable(("case", "axis"), inertia, UN["inertia"], "principal moments of inertia (I1, I2, I3)",
                               frame="B")
    ref = (f"body axis {spec.pointing_axis.tolist()} vs the same axis of the {spec.pointing_reference} frame"
           if spec.pointing_axis is not None else f"rotation angle of the attitude relative to the "
                                                  f"{spec.pointing_reference} frame")
    if "max_pointing_error" in outs:
        data["max_pointing_error"] = cf_variable(("case",), perr, "rad", "maximum pointing error over the output times",
                                          definition=ref)
    if "tumbling" in outs:
        data["tumbling"] = cf_variable(("case",), np.where(np.isnan(perr), -1, perr > spec.tumbling_angle).astype(np.int8),
                                "1", "tumbling flag: maximum pointing error above tumbling_angle",
                                flag_values=np.array([-1, 0, 1], dtype=np.int8),
                                flag_meanings="failed not_tumbling tumbling", tumbling_angle_rad=spec.tumbling_angle,
                                definition=ref)
    if "final_energy_error" in outs:
        what = ("H = T + U" if spec.energy == "hamiltonian" else "the Jacobi integral H - n h.G")
        data["final_energy_error"] = cf_variable(("case",), eerr, "1", f"relative change of the conserved energy "
                                          f"(E(t_end) - E(t0)) / |E(t0)|, E = {what}")
    data["integration_failed"] = cf_variable(("case",), failed.astype(np.int8), "1",
                                      "1 where the integration of the case stopped (its values are NaN)",
                                      flag_values=np.array([0, 1], dtype=np.int8), flag_meanings="ok failed")
    if pieces:
        ds = pieces[0] if len(pieces) == 1 else xr.concat(pieces, dim="case", data_vars="minimal", coords="minimal",
                                                           compat="override", join="exact", combine_attrs="override")
        ds = ds.sortby("case").drop_attrs(deep=False)
        ds = ds.assign_coords(coords).assign(data)
    else:
        ds = xr.Dataset(data, coords=coords)
    ds.attrs["integration_stats"] = json.dumps(stats, sort_keys=True)
    return ds


# ---------------------------------------------------------------------------------------
# running and storage


class SweepError(OrbattError, RuntimeError):
    """A sweep could not finish (a task failed for good, e.g. its workers kept dying); the
    chunks written so far are kept for ``resume``."""


def _parts_dir(output: Path) -> Path:
    return output.with_name(output.name + ".parts")


def _part_name(start, stop):
    return f"cases-{start:09d}-{stop - 1:09d}.nc"


def _parse_part(name):
    if not (name.startswith("cases-") and name.endswith(".nc")):
        return None
    try:
        a, b = name[6:-3].split("-")
        return int(a), int(b) + 1
    except ValueError:
        return None


def _done_parts(parts: Path, n_cases):
    """``[(start, stop, path)]`` of the complete parts (a damaged one is removed)."""
    from .dataset import check_engine

    engine = check_engine(None)
    done = []
    for f in sorted(parts.iterdir()):
        if f.name.startswith(".tmp-"):
            f.unlink()  # a part whose writing was interrupted
            continue
        r = _parse_part(f.name)
        if r is None:
            continue
        ok = 0 <= r[0] < r[1] <= n_cases
        if ok:
            try:
                if engine == "netcdf4":
                    import netCDF4

                    with netCDF4.Dataset(f) as nc:
                        ok = len(nc.dimensions["case"]) == r[1] - r[0]
                else:
                    import h5netcdf

                    with h5netcdf.File(f, "r") as nc:
                        ok = nc.dimensions["case"].size == r[1] - r[0]
            except Exception:  # noqa: BLE001 - any unreadable part is recomputed
                ok = False
        if not ok:
            f.unlink()
            continue
        done.append((r[0], r[1], f))
    # overlapping parts cannot come from orbatt; keep the first of any overlap
    out, covered = [], np.zeros(n_cases, dtype=bool)
    for a, b, f in done:
        if covered[a:b].any():
            f.unlink()
            continue
        covered[a:b] = True
        out.append((a, b, f))
    return out, covered


def _chunks(missing, chunk_size):
    """Runs of consecutive missing cases, cut into chunks of at most ``chunk_size``."""
    idx = np.flatnonzero(missing)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) != 1) + 1
    out = []
    for run in np.split(idx, breaks):
        a, b = int(run[0]), int(run[-1]) + 1
        for s in range(a, b, chunk_size):
            out.append((s, min(s + chunk_size, b)))
    return out


def _write_netcdf(ds, path):
    """:func:`orbatt.dataset.write_netcdf`, also for a Dataset without ``time`` (reductions)."""
    from .dataset import check_engine, encode, encoding, write_netcdf

    if "time" in ds.dims:
        write_netcdf(ds, path)
        return
    enc = encode(ds)
    enc.to_netcdf(path, engine=check_engine(None), format="NETCDF4", encoding=encoding(enc, 1, 1))


def _write_part(ds, parts: Path, start, stop):
    final = parts / _part_name(start, stop)
    tmp = parts / f".tmp-{final.name}-{os.getpid()}"
    _write_netcdf(ds, tmp)
    os.replace(tmp, final)  # a part with its final name is complete
    return final


def _open_client(scheduler, workers):
    """``(client, cluster_or_None)``."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - dask is a dependency
        raise InputError("scheduler: dask.distributed is not installed; pip install 'dask[distributed]'") from None
    if scheduler in (None, "local"):
        import logging

        n = workers or os.cpu_count() or 1
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None, silence_logs=logging.ERROR)
        return Client(cluster), cluster
    try:
        client = Client(scheduler)  # waits up to dask's distributed.comm.timeouts.connect
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"scheduler: cannot connect to {scheduler!r} ({exc}); start one with 'dask scheduler' "
                         "and workers with 'dask worker ADDRESS', or leave --scheduler out for a local cluster") from None
    if workers:
        try:
            client.wait_for_workers(workers, timeout=120)
        except TimeoutError:
            client.close()
            raise InputError(f"workers: {workers} workers did not connect to {scheduler!r} within 120 s") from None
    return client, None


def _finish_attrs(ds, sweep, stats, run):
    from .dataset import CONVENTIONS, FRAMES, REFERENCE, iso_epoch, to_json, utc_now, orbatt_version

    sc = sweep.scenario
    trajectory = "trajectory" in sweep.spec.outputs
    attrs = {} if not trajectory else {k: v for k, v in ds.attrs.items()}
    attrs.pop("sweep_chunk_seconds", None)
    kw = dict(sc.settings)
    settings = {"method": sc.method, **kw}
    attrs.update({
        "Conventions": CONVENTIONS,
        "title": f"orbatt sweep: {sc.name} ({sweep.cases} cases)",
        "source": f"orbatt {orbatt_version()}",
        "references": REFERENCE,
        "orbatt_version": orbatt_version(),
        "method": str(sc.method),
        "method_settings": to_json(settings),
        "integration_stats": json.dumps(stats, sort_keys=True),
        "integration_complete": np.int8(1),
        "potential": to_json(sc.potential.describe()),
        "unit_system": "dimensionless (angles in rad)" if sc.spec.dimensionless else "kg km s rad",
        "frames": FRAMES,
        "quaternion_order": "w x y z",
        "scenario": sc.text,
        "sweep_output_times": np.int64(sc.times.size),
        "sweep_t_end": float(sc.times[-1]),
    })
    if sc.orbit is not None:
        attrs["orbit"] = to_json(sc.orbit.describe())
        ep = iso_epoch(sc.orbit.epoch)
        if ep:
            attrs["epoch"] = ep
    elif "epoch" in attrs:
        del attrs["epoch"]
    attrs.update(sweep.attrs())
    attrs["sweep_run"] = json.dumps(run, sort_keys=True)
    now = utc_now()
    attrs["date_created"] = now
    attrs["history"] = f"{now} orbatt {orbatt_version()}: sweep of {sweep.cases} cases ({run.get('scheduler')})"
    ds.attrs = attrs
    return ds


def _sum_into(total, stats_json):
    try:
        d = json.loads(stats_json)
    except (TypeError, ValueError):
        return
    for k, v in d.items():
        if isinstance(v, (int, float)) and not isinstance(v, bool) and k != "members":
            total[k] = total.get(k, 0) + v


@dataclass
class ChunkInfo:
    """What a :func:`run_sweep` progress callback receives after each chunk."""

    start: int             #: first case of the chunk
    stop: int              #: one past its last case
    chunks_done: int       #: chunks complete (this run and earlier ones)
    chunks_total: int
    cases_done: int
    cases_total: int
    wall_time_s: float     #: since the start of this run
    path: Path | None = None   #: the part file written (None without an output)
    extra: dict = field(default_factory=dict)


def run_sweep(sweep, output=None, *, scheduler=None, workers=None, chunk_size=None, resume=False,
              progress=None, client=None, keep_parts=False):
    """Run a sweep on Dask, chunk by chunk, and return its Dataset.

    Parameters
    ----------
    sweep : Sweep or str or Path
        A :class:`Sweep`, or a scenario file with ``[sweep]`` (:func:`load_sweep`).
    output : str or Path, optional
        The result file: netCDF, or Zarr if the name ends with ``.zarr``. Chunks are written
        to ``OUTPUT.parts/`` as they finish and merged at the end (module docstring). Without
        it nothing is written and the chunks are gathered in memory.
    scheduler : str, optional
        ``None`` (default): a local cluster of ``workers`` processes on 127.0.0.1, started
        and stopped here; ``"tcp://host:port"``: a running dask.distributed scheduler;
        ``"synchronous"``: no Dask, the chunks one after the other in this process.
    workers : int, optional
        Local cluster: its number of worker processes (default: the CPU count). With a
        scheduler address: wait until that many workers are connected.
    chunk_size : int, optional
        Cases per task. Default: the ``[sweep] chunk_size``, else a multiple of four tasks
        per worker, at most 1000 cases each. The results do not depend on it. Keep a task
        above ~0.1 s of work: each costs ~20-40 ms of Dask, netCDF and merge overhead.
    resume : bool
        Keep the complete parts of an interrupted run of the same sweep (same scenario text,
        seed and number of cases; the seed is read back when the file gives none) and
        compute only the missing cases. Without it, an existing ``OUTPUT.parts/`` is refused.
    progress : callable, optional
        Called with a :class:`ChunkInfo` after every chunk (and once at the start, with the
        chunks found on resume).
    client : dask.distributed.Client, optional
        Use this client (its cluster is left running); overrides ``scheduler``/``workers``.
    keep_parts : bool
        Keep ``OUTPUT.parts/`` after merging.

    Returns
    -------
    xarray.Dataset
        Dimension ``case`` (and ``time``, ``quat``, ``axis`` as the outputs need); the swept
        parameters as coordinates along ``case``; global attributes ``sweep_seed``,
        ``sweep_parameters``, ... and ``sweep_run`` (JSON: chunks computed and reused this
        run, wall time, scheduler). Opened from ``output`` when one is given (lazily for
        netCDF; load it or close it when done).

    Raises
    ------
    InputError
        Bad arguments, a parts folder without ``resume``, a parts folder of another sweep,
        an unreachable scheduler.
    """
    import xarray as xr

    if not isinstance(sweep, Sweep):
        sweep = load_sweep(sweep)
    n_cases = sweep.cases
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1):
        raise InputError(f"workers: {workers!r} must be a positive integer")
    if chunk_size is not None and (isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer))
                                   or chunk_size < 1):
        raise InputError(f"chunk_size: {chunk_size!r} must be a positive integer")
    if scheduler is not None and not isinstance(scheduler, str):
        raise InputError(f"scheduler: expected an address such as 'tcp://127.0.0.1:8786', 'synchronous' or None, "
                         f"got {scheduler!r}")
    synchronous = scheduler == "synchronous" and client is None
    scheduler_name = "synchronous" if synchronous else (scheduler or "local cluster") if client is None else \
        str(getattr(client, "scheduler", None) and client.scheduler.address)
    zarr_out = False
    out_path = parts = None
    if output is not None:
        out_path = Path(output)
        zarr_out = out_path.suffix == ".zarr"
        if zarr_out:
            try:
                import zarr  # noqa: F401
            except ImportError:
                raise InputError(f"output: {output!s} is a Zarr store but zarr is not installed; pip install zarr, "
                                 "or give a .nc file") from None
        if not out_path.parent.is_dir():
            raise InputError(f"output: the folder {str(out_path.parent)!r} does not exist")
        parts = _parts_dir(out_path)
    elif resume:
        raise InputError("resume: needs an output file (the parts of the interrupted run are beside it)")

    # --- parts folder, resume
    covered = np.zeros(n_cases, dtype=bool)
    reused = []
    if parts is not None:
        manifest = parts / "sweep.json"
        if parts.exists():
            if not resume:
                raise InputError(f"output: {str(parts)!r} holds the chunks of an interrupted sweep; pass --resume "
                                 "(resume=True) to finish it, or delete that folder to start again")
            try:
                man = json.loads(manifest.read_text())
            except (OSError, ValueError):
                raise InputError(f"resume: {str(parts)!r} has no readable sweep.json; it is not an orbatt sweep's "
                                 "parts folder (delete it to start again)") from None
            if sweep.seed_source == "default":  # the file gives no seed: reuse the interrupted run's
                sweep = Sweep(sweep.scenario, seed=int(man.get("seed", sweep.seed)))
                sweep.seed_source = "default"
            if man.get("fingerprint") != sweep.fingerprint:
                raise InputError(f"resume: {str(parts)!r} belongs to another sweep (the scenario text, seed or number "
                                 f"of cases changed: fingerprint {man.get('fingerprint')} != {sweep.fingerprint}); "
                                 "delete it or rerun without changes")
            reused, covered = _done_parts(parts, n_cases)
        else:
            if resume and out_path.exists() and not zarr_out:
                from .dataset import open_dataset

                try:
                    with open_dataset(out_path) as old:
                        fp = old.attrs.get("sweep_fingerprint")
                        old_seed = old.attrs.get("sweep_seed")
                except Exception:  # noqa: BLE001 - an unreadable file is simply recomputed
                    fp = old_seed = None
                if sweep.seed_source == "default" and old_seed is not None:
                    sweep = Sweep(sweep.scenario, seed=int(old_seed))
                    sweep.seed_source = "default"
                if fp == sweep.fingerprint:  # complete already
                    from .dataset import open_dataset

                    return open_dataset(out_path)
            parts.mkdir(parents=True)
            tmp = parts / ".tmp-sweep.json"
            tmp.write_text(json.dumps({"format": FORMAT, "fingerprint": sweep.fingerprint, "seed": sweep.seed,
                                       "cases": n_cases, "scenario": sweep.source}, indent=1))
            os.replace(tmp, manifest)

    # --- chunks and execution
    t_start = time.perf_counter()
    own = None
    numba_threads = None
    if covered.all():  # every chunk is on disk already: only the merge is left
        synchronous = True
    if not synchronous:
        if client is None:
            client, own = _open_client(scheduler, workers)
            owned_client = True
        else:
            owned_client = False
        n_workers = max(1, sum(client.nthreads().values()))  # worker threads: tasks that run at once
        numba_threads = 1
    else:
        owned_client = False
        n_workers = 1
    try:
        if chunk_size is None:  # a multiple of 4 tasks per worker, at most MAX_AUTO_CHUNK cases each
            rounds = math.ceil(n_cases / (4 * n_workers * MAX_AUTO_CHUNK))
            chunk_size = sweep.spec.chunk_size or max(1, math.ceil(n_cases / (4 * n_workers * rounds)))
        todo = _chunks(~covered, int(chunk_size))
        n_chunks = len(reused) + len(todo)
        done_cases = int(covered.sum())
        info = dict(chunks_total=n_chunks, cases_total=n_cases)
        if progress is not None:
            progress(ChunkInfo(0, 0, len(reused), cases_done=done_cases, wall_time_s=0.0, **info))
        results = []
        compute_s = 0.0
        stats = {}
        k_done = len(reused)

        def handle(a, b, ds):
            nonlocal compute_s, k_done, done_cases
            compute_s += float(ds.attrs.pop("sweep_chunk_seconds", 0.0))
            path = None
            if parts is not None:
                path = _write_part(ds, parts, a, b)
            else:
                results.append(ds)
            k_done += 1
            done_cases += b - a
            if progress is not None:
                progress(ChunkInfo(a, b, k_done, cases_done=done_cases, wall_time_s=time.perf_counter() - t_start,
                                   path=path, **info))

        if synchronous:
            for a, b in todo:
                handle(a, b, _run_chunk(sweep.job(a, b)))
        elif todo:
            from dask.distributed import as_completed

            futures = {}
            for a, b in todo:
                fut = client.submit(_run_chunk, sweep.job(a, b, numba_threads), pure=False,
                                    key=f"orbatt-sweep-{sweep.fingerprint[:12]}-{a}-{b}-{secrets.token_hex(4)}")
                futures[fut.key] = (fut, a, b)
            pending = iter(as_completed([f for f, _, _ in futures.values()], with_results=True))
            try:
                while True:
                    try:
                        fut, ds = next(pending)
                    except StopIteration:
                        break
                    except Exception as exc:  # a task failed for good (raised, or its workers kept dying)
                        left = sorted((a, b) for _, a, b in futures.values())
                        keep = f"; the finished chunks are kept in {str(parts)!r}: rerun with --resume" if parts else ""
                        raise SweepError(f"sweep: a task failed ({len(left)} chunks not finished, the first from case "
                                         f"{left[0][0]}): {type(exc).__name__}: {exc}{keep}") from exc
                    _, a, b = futures.pop(fut.key)
                    del fut  # let the scheduler forget the result
                    handle(a, b, ds)
            except BaseException:
                client.cancel([f for f, _, _ in futures.values()])
                raise
    finally:
        if owned_client:
            client.close()
            if own is not None:
                own.close()
    wall = time.perf_counter() - t_start
    run = {"chunks": n_chunks, "chunks_computed": len(todo), "chunks_reused": len(reused),
           "cases_computed": int(sum(b - a for a, b in todo)), "chunk_size": int(chunk_size),
           "wall_time_s": wall, "compute_time_s": compute_s,
           "scheduler": scheduler_name,
           "workers": int(n_workers)}

    # --- merge
    import dask

    with dask.config.set(scheduler="synchronous"):
        if parts is None:
            for ds in results:
                _sum_into(stats, ds.attrs.get("integration_stats"))
            ds = _concat(sorted(results, key=lambda d: int(d["case"].values[0])))
            return _finish_attrs(ds, sweep, stats, run)
        from .dataset import check_engine, decode

        files = sorted((p for p in parts.iterdir() if _parse_part(p.name)), key=lambda p: _parse_part(p.name)[0])
        ranges = [_parse_part(p.name) for p in files]
        if ranges[0][0] != 0 or ranges[-1][1] != n_cases or any(r[1] != s[0] for r, s in zip(ranges, ranges[1:])):
            raise InputError(f"output: the parts in {str(parts)!r} do not cover cases 0..{n_cases - 1}; rerun with "
                             "--resume")
        engine = check_engine(None)
        # reductions are small: read them now; trajectories stay on disk (dask) until written
        lazy = {"chunks": {}} if "trajectory" in sweep.spec.outputs else {}
        opened = [decode(xr.open_dataset(f, engine=engine, decode_times=False, decode_timedelta=False, **lazy))
                  for f in files]
        if not lazy:
            opened = [d.load() for d in opened]
        try:
            for d in opened:
                _sum_into(stats, d.attrs.get("integration_stats"))
            ds = _finish_attrs(_concat(opened), sweep, stats, run)
            tmp = out_path.with_name(f".tmp-{out_path.name}-{os.getpid()}")
            try:
                if zarr_out:
                    with warnings.catch_warnings():  # zarr 3 on the 1-character label coordinates
                        warnings.simplefilter("ignore")
                        ds.drop_encoding().to_zarr(tmp, mode="w")
                    if out_path.is_dir():
                        shutil.rmtree(out_path)
                else:
                    _write_netcdf(ds, tmp)
                os.replace(tmp, out_path)
            except BaseException:  # the parts stay: --resume merges again
                if tmp.is_dir():
                    shutil.rmtree(tmp, ignore_errors=True)
                elif tmp.exists():
                    tmp.unlink()
                raise
        finally:
            for d in opened:
                d.close()
    if not keep_parts:
        shutil.rmtree(parts)
    if zarr_out:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return xr.open_zarr(out_path)
    from .dataset import open_dataset

    return open_dataset(out_path)


def _concat(pieces):
    import xarray as xr

    if len(pieces) == 1:
        return pieces[0]
    return xr.concat(pieces, dim="case", data_vars="minimal", coords="minimal", compat="override", join="exact",
                     combine_attrs="override")

"""The ``[sweep]`` table of a scenario file: the parameters a sweep varies, their
distributions, and the table's validation (called by :func:`orbatt.scenario.parse`).

The manual (every key, the cases, reproducibility, outputs): ``docs/sweeps.md``. Values are
in internal units (:mod:`orbatt.units`): kg km^2, rad, rad/s, km; plain numbers for a
dimensionless scenario. Drawing the samples is :mod:`orbatt.sweep.sampling`'s job.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import units as U
from ..dataset import DIMENSIONLESS_UNITS
from ..units import INTERNAL_UNITS
from .paths import ALIAS_PATHS, DEFAULT_LEAVES, FIXED_TABLES, path_unit, split_path  # noqa: F401 - re-exported
from .study_schema import parse_study_keys
from .pointing_schema import parse_requirement
from ..sweep_outputs import DEFAULT_OUTPUTS, OUTPUTS as SWEEP_OUTPUTS, THRESHOLDS, users_of
from .fields import parse_int, parse_quantity
from ..orbits import R_EARTH
from .key_docs import parse_key_docs
from .ranges import RANGES

__all__ = ["SweepSpec", "Distribution", "Parameter", "PARAMETERS", "OUTPUTS", "DEFAULT_OUTPUTS", "DISTRIBUTIONS",
           "SWEEP_KEYS", "SWEEP_KEY_DOCS", "INERTIA_PARAMETERS", "RATE_PARAMETERS", "ORBIT_PARAMETERS", "parse_sweep_table",
           "parameter_unit", "parameter_units", "in_limits", "limits_text", "PATH_PARAMETER", "definition", "path_unit", "sweep_units",
           "FIXED_TABLES", "MAX_GRID_VALUES", "DEFAULT_LEAVES"]

#: keys of the [sweep] table
SWEEP_KEYS = ("parameters", "samples", "seed", "chunk_size", "outputs", "pointing_axis", "pointing_reference",
              "tumbling_angle", "on_invalid", "detumble_rate", "settling_angle", "window", "confidence",
              "stability_window", "requirement")
#: what each key of [sweep] is: ``(dimension, default, meaning)`` (``docs/scenarios.md``), written
#: as a table (:mod:`orbatt.scenario.key_docs`)
SWEEP_KEY_DOCS = parse_key_docs("""
[sweep]
parameters          table                   required                                           [sweep.parameters]: each varied
                                                                                               parameter, with `values = [...]` (a
                                                                                               grid) or a `distribution` ('uniform':
                                                                                               low, high; 'normal': mean, std;
                                                                                               'truncnormal': mean, std, low, high)
samples             plain integer           required with random parameters                    number of random draws
seed                plain integer           drawn and recorded                                 seed of the random draws (numpy PCG64)
chunk_size          plain integer           automatic                                          cases per task
outputs             list                    ['final_state', 'max_pointing_error', 'tumbling']  (below)
pointing_axis       plain, 3 values         none: the whole attitude                           body axis whose pointing error is
                                                                                               measured (without it: the rotation angle
                                                                                               of the attitude from the reference)
pointing_reference  'orbital' | 'inertial'  the [initial] frame                                frame the pointing is measured in
tumbling_angle      angle                   90 deg                                             pointing error beyond which a case
                                                                                               tumbles
on_invalid          'error' | 'resample'    'error'                                            what to do with a draw outside the
                                                                                               physical limits
detumble_rate       angular velocity        (below)                                            the earliest time after which |omega|
                                                                                               stays below it
settling_angle      angle                   (below)                                            the earliest time after which the
                                                                                               pointing error stays below it
window              time                    the last orbit, else the last 10 % of the run      span before t_end that
                                                                                               pointing_error_max/_rms summarize
confidence          plain number in (0, 1)  0.9973                                             the confidence level P_C of the
                                                                                               pointing indices: each case's
                                                                                               P_C-quantile over its output times
                                                                                               (docs/pointing-budgets.md)
stability_window    time                    (below)                                            the stability window of the mean and
                                                                                               relative indices: consecutive windows
                                                                                               from the first output
requirement         table of angles         none                                               each index's requirement (e.g. { ape =
                                                                                               "0.1 deg", rpe = "10 arcsec" }): drawn by
                                                                                               orbatt plot, checked by orbatt info
""")["sweep"]
#: outputs that may be asked for: their descriptors (:data:`orbatt.sweep_outputs.OUTPUTS`)
OUTPUTS = tuple(SWEEP_OUTPUTS)
SWEEP_KEY_DOCS["outputs"] = SWEEP_KEY_DOCS["outputs"][:2] + (
    "per-case outputs, of " + ", ".join(f"'{k}'" for k in OUTPUTS) + " (each in the outputs table below); a binary "
    "asteroid's: 'final_state', 'final_orbit', 'conservation', 'max_libration', 'mean_period' (all by default)",)
for _key in THRESHOLDS:  # what each threshold measures, and the outputs that read it
    _d, _default, _meaning = SWEEP_KEY_DOCS[_key]
    _users = " or ".join(f"'{o}'" for o in users_of(_key))
    SWEEP_KEY_DOCS[_key] = (_d, f"required with {_users}" if THRESHOLDS[_key].required else _default,
                            f"{_users}: {_meaning}")
del _key, _d, _default, _meaning, _users
DISTRIBUTIONS = ("uniform", "normal", "truncnormal")
DISTRIBUTION_KEYS = {"uniform": ("low", "high"), "normal": ("mean", "std"), "truncnormal": ("mean", "std", "low", "high")}
MAX_CASES = 100_000_000
#: the physical range of each kind of parameter: that of the key it replaces
#: (:data:`orbatt.scenario.ranges.RANGES`; angles are bounded by the field parser)
KIND_RANGES = {"inertia": RANGES["body", "inertia"], "rate": RANGES["initial", "omega"],
               "length": RANGES["orbit", "a"]}
#: central body radii (km): a sweep's orbit whose apoapsis lies below is refused
BODY_RADII = {"earth": R_EARTH}
#: most values of one grid: a longer list takes minutes to read before any limit on the cases
#: could refuse it (the cases of a sweep are bounded by its estimated work,
#: :func:`orbatt.sweep.Sweep`)
MAX_GRID_VALUES = 10_000


@dataclass(frozen=True)
class Parameter:
    """A parameter a sweep can vary: what it replaces, its unit kind and physical limits."""

    group: str                # "body", "initial", "orbit"
    kind: str                 # unit kind: inertia, rate, angle, length, one
    low: float = -math.inf    # physical limits
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    long_name: str = ""


#: the parameters a sweep can vary, in canonical (sampling) order
PARAMETERS = {
    "inertia1": Parameter("body", "inertia", 0.0, low_open=True, long_name="principal moment of inertia I1"),
    "inertia2": Parameter("body", "inertia", 0.0, low_open=True, long_name="principal moment of inertia I2"),
    "inertia3": Parameter("body", "inertia", 0.0, low_open=True, long_name="principal moment of inertia I3"),
    "omega1": Parameter("initial", "rate", long_name="initial body rate, axis 1"),
    "omega2": Parameter("initial", "rate", long_name="initial body rate, axis 2"),
    "omega3": Parameter("initial", "rate", long_name="initial body rate, axis 3"),
    "attitude_angle": Parameter("initial", "angle", long_name="initial attitude perturbation angle (about attitude_axis)"),
    "orbit_a": Parameter("orbit", "length", 0.0, low_open=True, long_name="semi-major axis"),
    "orbit_e": Parameter("orbit", "one", 0.0, 1.0, high_open=True, long_name="eccentricity"),
    "orbit_i": Parameter("orbit", "angle", 0.0, math.pi, long_name="inclination"),
    "orbit_raan": Parameter("orbit", "angle", long_name="right ascension of the ascending node"),
    "orbit_argp": Parameter("orbit", "angle", long_name="argument of periapsis"),
    "orbit_true_anomaly": Parameter("orbit", "angle", long_name="true anomaly at the epoch"),
    "orbit_mean_anomaly": Parameter("orbit", "angle", long_name="mean anomaly at the epoch"),
}
#: what a parameter given by its scenario path is (its unit: the key's, :attr:`SweepSpec.paths`)
PATH_PARAMETER = Parameter("path", "path", long_name="scenario key")


def definition(name) -> Parameter:
    """The :class:`Parameter` of a swept name: a named one, or :data:`PATH_PARAMETER`."""
    return PARAMETERS.get(name, PATH_PARAMETER)


INERTIA_PARAMETERS = ("inertia1", "inertia2", "inertia3")
RATE_PARAMETERS = ("omega1", "omega2", "omega3")
ORBIT_PARAMETERS = tuple(k for k, p in PARAMETERS.items() if p.group == "orbit")


def parameter_unit(kind):
    """The internal unit (:mod:`orbatt.units`) of a parameter kind (``Parameter.kind``)."""
    return {"inertia": U.INERTIA, "rate": U.RATE, "angle": U.ANGLE, "length": U.LENGTH,
            "one": U.DIMENSIONLESS}[kind]


def parameter_units(dimensionless):
    """CF unit string of every parameter in :data:`PARAMETERS` (internal units, those the
    values are sampled in: :data:`orbatt.units.INTERNAL_UNITS`; a dimensionless scenario's
    inertia and rates are plain numbers, ``"1"``). The sweep's Dataset writes the inertia
    parameters in kg m^2 (:func:`orbatt.sweep.chunk.chunk_dataset`)."""
    table = DIMENSIONLESS_UNITS if dimensionless else INTERNAL_UNITS
    return {name: table[p.kind] for name, p in PARAMETERS.items()}


def sweep_units(spec, dimensionless):
    """CF unit string of every parameter a sweep can vary (:func:`parameter_units`) and of each
    path it varies: the key's unit (the values are in it) in the CF spelling every other variable
    of the file has (:func:`orbatt.units.unit_string`: ``"kg m2"`` is written ``"kg m^2"``, which
    UDUNITS-2, astropy and pint all read); ``"1"`` for a plain number."""
    return {**parameter_units(dimensionless),
            **{k: ("1" if v is None else U.unit_string(v)) for k, v in spec.paths.items()}}


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
    """The validated ``[sweep]`` table (internal units; manual: ``docs/sweeps.md``).

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
    paths: dict = field(default_factory=dict)  # swept scenario path -> the key's unit text (None: plain)
    detumble_rate: float | None = None   # rad/s (or plain): detumble_time's threshold
    settling_angle: float | None = None  # rad: settling_time's threshold
    window: float | None = None          # s (or plain): pointing_error's window; None: the default
    confidence: float = 0.9973           # the pointing indices' confidence level (docs/pointing-budgets.md)
    stability_window: float | None = None  # s (or plain): the mean and relative indices' window
    requirement: dict = field(default_factory=dict)  # pointing index -> requirement, rad
    min_apoapsis: float | None = None  # km: a draw whose apoapsis a (1 + e) is lower is invalid (the Earth's radius)
    source: str | None = None  # the scenario file (or name) the table was read from: messages about draws name it

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


def in_limits(p: Parameter, x):
    """Mask: where the values ``x`` are finite and inside the physical limits of ``p``."""
    x = np.asarray(x, dtype=np.float64)
    ok = np.isfinite(x)
    ok &= (x > p.low) if p.low_open else (x >= p.low)
    ok &= (x < p.high) if p.high_open else (x <= p.high)
    return ok


def limits_text(p: Parameter, unit_text):
    """The physical range of ``p`` as text, e.g. ``"(0, inf) kg km2"``."""
    lo = "-inf" if math.isinf(p.low) else f"{p.low:g}"
    hi = "inf" if math.isinf(p.high) else f"{p.high:g}"
    lb = "(" if p.low_open or math.isinf(p.low) else "["
    hb = ")" if p.high_open or math.isinf(p.high) else "]"
    return f"{lb}{lo}, {hi}{hb} {unit_text}".rstrip()


def _check_apoapsis(ctx, params, orbit, radius):
    """Refuse a grid value or a distribution bound of ``orbit_a`` whose orbit lies inside the
    central body (apoapsis ``a (1 + e)`` below its ``radius`` km, with the smallest ``e`` the
    sweep gives), as ``[orbit] a`` is refused."""
    e = params.get("orbit_e")
    e_min = (orbit["e"] if e is None else min(e.values) if not e.random
             else e.low if e.low is not None else 0.0)
    d = params.get("orbit_a")
    if d is None:
        return
    where = "[sweep.parameters.orbit_a]"
    if not d.random:
        for k, a in enumerate(d.values):
            if a * (1.0 + e_min) < radius:
                raise ctx.error(f"{where} values[{k}]", f"{a:.6g} km with e = {e_min:g}: the whole orbit (apoapsis "
                                                        f"{a * (1 + e_min):.6g} km) lies inside the central body "
                                                        f"(radius {radius:.6g} km); raise a")
    elif d.low is not None and d.low * (1.0 + e_min) < radius:
        raise ctx.error(f"{where} low", f"{d.low:.6g} km with e = {e_min:g}: draws may put the whole orbit inside the "
                                        f"central body (radius {radius:.6g} km); raise low")


def _check_one_spelling(ctx, raw):
    """Refuse a key varied twice: under a parameter's name and its path (``inertia1`` and
    ``"body.inertia[0]"``), or under two spellings of one path (``"initial.omega[0]"`` and
    ``"initial.omega[00]"``), naming both."""
    seen = {}
    for name in raw:
        path = ALIAS_PATHS.get(name, name)
        try:
            key = tuple(split_path(path))
        except ValueError:
            continue  # not a path: refused by its own check
        if key in seen:
            raise ctx.error(f'[sweep.parameters] "{name}"', f'varies the same key as "{seen[key]}" ({path}); give '
                                                           "each key once")
        seen[key] = name


def parse_sweep_table(ctx, table, *, dimensionless, potential_kind, orbit, frame, conservative=True, control=None,
                      wheels=0, data=None):
    """Validate a ``[sweep]`` table (called by :func:`orbatt.scenario.schema.parse`).

    Parameters
    ----------
    ctx : FieldContext
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
    conservative : bool
        Whether the scenario has a conserved energy (no ``[torques]``, no ``[control]``):
        ``final_energy_error`` needs one.
    control : dict or None
        The scenario's control law, its plain settings (:meth:`orbatt.control.PDControl.settings`;
        the study outputs that need one).
    wheels : int
        The number of reaction wheels.
    data : dict
        The whole scenario (TOML): the parameters given by their path are looked up there.

    Returns
    -------
    SweepSpec

    Raises
    ------
    ScenarioError
        Naming ``[sweep] key`` or ``[sweep.parameters.NAME] key``, the value and the fix.
    """
    for k in table:
        if k not in SWEEP_KEYS:
            raise ctx.error(f"[sweep] {k}", f"unknown key; allowed keys in [sweep]: {', '.join(sorted(SWEEP_KEYS))}")
    raw = table.get("parameters")
    if not isinstance(raw, dict) or not raw:
        raise ctx.error("[sweep] parameters", "missing or empty; give at least one parameter to vary, e.g. "
                                              "[sweep.parameters] inertia1 = { distribution = \"normal\", std = \"1 kg m2\" }")
    paths = {}
    for name in raw:
        if name not in PARAMETERS:
            if "." not in name and "[" not in name:
                raise ctx.error(f"[sweep.parameters] {name}", f"unknown parameter; give a scenario path such as "
                                                              f"\"control.gain\" or \"initial.omega[0]\", or one of "
                                                              f"{', '.join(PARAMETERS)}")
            paths[name] = path_unit(ctx, name, data, raw[name])
    _check_one_spelling(ctx, raw)
    if paths and "attitude_angle" in raw:
        raise ctx.error("[sweep.parameters] attitude_angle", "combines with the named parameters only; vary "
                                                             "\"initial.q[k]\" or the Euler angles by their paths")
    units = sweep_units(SweepSpec(parameters={}, paths=paths), dimensionless)
    params = {}
    for name in [*(k for k in PARAMETERS if k in raw), *paths]:  # canonical order, then the paths as given
        p = definition(name)
        where = f"[sweep.parameters.{name}]" if name in PARAMETERS else f'[sweep.parameters."{name}"]'

        if p.group == "orbit":
            if orbit is None:
                raise ctx.error(where, "orbit elements vary only in a scenario with an [orbit]")
            if orbit["provider"] == "tle":
                raise ctx.error(where, "a TLE orbit (provider = 'tle') is shared by all cases: its elements do not "
                                       "vary; use a kepler or rebound orbit to vary them")
            if name in ("orbit_true_anomaly", "orbit_mean_anomaly") and name[6:] != orbit["anomaly_kind"]:
                raise ctx.error(where, f"the [orbit] gives {orbit['anomaly_kind']}; vary orbit_{orbit['anomaly_kind']}")
        if name in paths:
            unit = U.DIMENSIONLESS if paths[name] is None else U.parse_unit(paths[name])
            dimless = paths[name] is None
        else:
            unit = parameter_unit(p.kind)
            dimless = dimensionless if p.kind in ("inertia", "rate", "length") else p.kind in ("one", "angle")
        cf = units[name] if paths.get(name) is None else paths[name]  # messages: the unit as the file writes it

        # the physical range of the key the parameter replaces (dimensional scenarios; a std
        # is a spread of the same quantity, bounded alike)
        rng = None if dimensionless else KIND_RANGES.get(p.kind)
        if rng is not None and p.low == 0.0:  # a positive kind: its own limit names a value <= 0 first
            rng = (None, rng.bounds(unit)[1])

        def q(key, value, _where=where, _unit=unit, _dimless=dimless, _rng=rng):
            return parse_quantity(ctx, f"{_where} {key}", value, _unit, dimensionless=_dimless, bounds=_rng)

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
            if len(vals) > MAX_GRID_VALUES:
                raise ctx.error(f"{where} values", f"a grid of {len(vals)} values is more than {MAX_GRID_VALUES}; "
                                                   "give fewer values or a distribution with samples")
            v = tuple(q(f"values[{i}]", x) for i, x in enumerate(vals))
            bad = np.flatnonzero(~in_limits(p, v))
            if bad.size:
                raise ctx.error(f"{where} values[{bad[0]}]", f"{vals[bad[0]]!r} is outside the physical range "
                                                            f"{limits_text(p, cf)}")
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
        allowed = set(DISTRIBUTION_KEYS[kind]) | {"distribution"}
        for k in d:
            if k not in allowed:
                raise ctx.error(f"{where} {k}", f"unknown key for a {kind} distribution; allowed: "
                                                f"{', '.join(sorted(allowed))}")
        vals = {k: q(k, d[k]) for k in DISTRIBUTION_KEYS[kind] if k in d}
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
                    raise ctx.error(f"{where} {k}", f"{d[k]!r} leaves the physical range {limits_text(p, cf)}; "
                                                    "no sample may fall outside it")
        if kind == "uniform" and p.low_open and vals["low"] == p.low:
            raise ctx.error(f"{where} low", f"{d['low']!r}: a sample may equal low, which is outside the physical "
                                            f"range {limits_text(p, cf)}")
        if "mean" in vals and not np.isfinite(vals["mean"]):
            raise ctx.error(f"{where} mean", f"{d['mean']!r} is not finite")
        params[name] = Distribution(kind, low=vals.get("low"), high=vals.get("high"), mean=vals.get("mean"),
                                    std=vals.get("std"))

    radius = None if orbit is None or dimensionless or "a" not in orbit else BODY_RADII.get(orbit["central_body"])
    if radius is not None:  # a Keplerian or REBOUND orbit about the Earth: no orbit inside it
        _check_apoapsis(ctx, params, orbit, radius)
    spec = SweepSpec(parameters=params, paths=paths, min_apoapsis=radius, source=ctx.source)
    n_random = sum(d.random for d in params.values())
    if "samples" in table:
        spec.samples = parse_int(ctx, "[sweep] samples", table["samples"], 1)
        if not n_random:
            raise ctx.error("[sweep] samples", "only random parameters are sampled; with grids only, remove samples")
    elif n_random:
        raise ctx.error("[sweep] samples", "missing; give the number of random draws, e.g. samples = 100")
    if spec.cases > MAX_CASES:
        raise ctx.error("[sweep] samples", f"{spec.cases} cases is more than {MAX_CASES}; split the study")
    if "seed" in table:
        spec.seed = parse_int(ctx, "[sweep] seed", table["seed"], 0, 2**63)
    if "chunk_size" in table:
        spec.chunk_size = parse_int(ctx, "[sweep] chunk_size", table["chunk_size"], 1)
    if "outputs" in table:
        outs = table["outputs"]
        if not isinstance(outs, list) or not outs:
            raise ctx.error("[sweep] outputs", f"expected a non-empty list such as {list(DEFAULT_OUTPUTS)}, got {outs!r}")
        for o in outs:
            if not isinstance(o, str) or o not in OUTPUTS:
                raise ctx.error("[sweep] outputs", f"{o!r} is not one of {', '.join(map(repr, OUTPUTS))}")
        spec.outputs = tuple(o for o in OUTPUTS if o in outs)
        if "final_energy_error" in spec.outputs and not conservative:
            raise ctx.error("[sweep] outputs", "'final_energy_error' needs a conserved energy: this scenario has "
                                               "[torques] or [control] (non-conservative); remove the output")
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
        users = users_of(k)
        if k in table and not set(users) & set(spec.outputs):
            raise ctx.error(f"[sweep] {k}", "only used with " + ", ".join(f"'{o}'" for o in users[:-1])
                            + f" or '{users[-1]}' in outputs")
    parse_study_keys(ctx, table, spec, dimensionless=dimensionless, control=control, wheels=wheels)
    parse_requirement(ctx, table, spec)
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

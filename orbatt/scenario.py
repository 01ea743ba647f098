"""Scenario files (TOML): schema, validation, and the objects they build.

A scenario describes one study; :func:`load_scenario` validates it completely (unknown keys
and tables are refused, every quantity is checked for its dimension) and returns a
:class:`Scenario` whose :meth:`Scenario.run` returns the result Dataset.

Schema (the contract other tools read; quantities are strings astropy parses, e.g.
``"7000 km"``, ``"30 deg"``, ``"0.001 rad / s"``; plain numbers mean dimensionless)::

    name = "..."                  # optional; defaults to the file name
    description = "..."           # optional, one line
    [body]        inertia = [I1, I2, I3]; heavy top: mass_g, center_of_mass = [x, y, z]
    [initial]     q = [...] and Q = [...]
                  | q = [...] or euler_313 = [phi, theta, psi], with omega = [w1, w2, w3]
                  | euler_313 with euler_momenta = [Phi, Theta, Psi]
                  frame = "inertial" (default) | "orbital"
    [potential]   kind = "torque-free" | "heavy-top" | "gravity-gradient"
                  sign = "physical" (default) | "paper"        (heavy top)
    [orbit]       provider = "kepler" | "rebound"; central_body = "earth" | gm = "..."
                  a, e, i, raan, argp, and one of true_anomaly | mean_anomaly
                  epoch (ISO UTC); rebound: perturbations = ["j2", "moon", "sun"], integrator
    [integration] method, rtol, atol | step, t_end, output_step
                  (times: a time, a plain number if dimensionless, or "N orbits")
    [sweep]       optional: parameters varied over many cases, run by ``orbatt sweep``
                  (schema in :mod:`orbatt.sweep`); ``orbatt run`` runs the nominal case

Outputs fall exactly on ``k * output_step`` for ``k = 0 .. floor(t_end / output_step)``.
``Q`` is in the unit implied by the inertia and time units (kg km^2 s^-1 for a dimensional
body; plain numbers for a dimensionless one).
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from astropy import units as u

from . import units as U
from .body import RigidBody
from .errors import InputError

# ---- schema ------------------------------------------------------------------------------
TOP_KEYS = {"name", "description"}
TABLES = {
    "body": {"inertia", "mass_g", "center_of_mass"},
    "initial": {"q", "Q", "omega", "euler_313", "euler_momenta", "frame"},
    "potential": {"kind", "sign"},
    "orbit": {"provider", "central_body", "gm", "a", "e", "i", "raan", "argp", "true_anomaly",
              "mean_anomaly", "epoch", "perturbations", "integrator"},
    "integration": {"method", "rtol", "atol", "step", "t_end", "output_step"},
    "sweep": None,  # keys checked by orbatt.sweep.parse_sweep_table (see parse)
}
REQUIRED_TABLES = ("body", "initial", "potential", "integration")
POTENTIAL_KINDS = ("torque-free", "heavy-top", "gravity-gradient")
FRAMES = ("inertial", "orbital")
PROVIDERS = ("kepler", "rebound")


class ScenarioError(InputError):
    """A scenario file is malformed; the message names the file, table, key, value and fix."""


@dataclass
class FieldContext:
    source: str

    def error(self, where, msg):
        return ScenarioError(f"{self.source}: {where}: {msg}")


def parse_quantity(ctx, where, value, unit, *, dimensionless):
    """Parse one scalar: a Quantity string, or a plain number when ``dimensionless`` (or when
    ``unit`` is dimensionless)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise ctx.error(where, f"{value!r} is not a number or a quantity string")
    if isinstance(value, str):
        try:
            q = u.Quantity(value)
        except (TypeError, ValueError):
            raise ctx.error(where, f"cannot parse {value!r} as a quantity; write e.g. '1 {unit.to_string()}'") from None
        if dimensionless and unit not in (U.DIMENSIONLESS, U.ANGLE) and q.unit != U.DIMENSIONLESS:
            raise ctx.error(where, f"{value!r} has a unit but the scenario is dimensionless (plain-number "
                                  "inertia); give a plain number or give the inertia with units")
        try:
            eq = u.dimensionless_angles() if unit == U.ANGLE else []
            return float(q.to_value(unit, equivalencies=eq))
        except u.UnitConversionError:
            raise ctx.error(where, f"{value!r} has the wrong dimension; expected a {unit.physical_type} such "
                                  f"as '1 {unit.to_string()}'") from None
    x = float(value)
    if not math.isfinite(x):
        raise ctx.error(where, f"{value!r} is not finite")
    if unit in (U.DIMENSIONLESS, U.ANGLE) or dimensionless:
        return x
    raise ctx.error(where, f"{value!r} has no unit; write it as a quantity string such as '{value} {unit.to_string()}'")


def _vector(ctx, where, value, n, unit, *, dimensionless):
    if not isinstance(value, list) or len(value) != n:
        raise ctx.error(where, f"expected a list of {n} values, got {value!r}")
    return np.array([parse_quantity(ctx, f"{where}[{k}]", v, unit, dimensionless=dimensionless)
                     for k, v in enumerate(value)])


def _plain_vector(ctx, where, value, n):
    if not isinstance(value, list) or len(value) != n or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise ctx.error(where, f"expected a list of {n} plain numbers, got {value!r}")
    a = np.array(value, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ctx.error(where, f"{value!r} contains non-finite numbers")
    return a


def _check_keys(ctx, data):
    for key, val in data.items():
        if key in TABLES:
            if not isinstance(val, dict):
                raise ctx.error(key, f"must be a table [{key}], got {val!r}")
            allowed = TABLES[key]
            if allowed is None:
                continue
            for k in val:
                if k not in allowed:
                    raise ctx.error(f"[{key}] {k}", f"unknown key; allowed keys in [{key}]: {', '.join(sorted(allowed))}")
        elif key not in TOP_KEYS:
            raise ctx.error(key, f"unknown table or key; allowed: {', '.join(sorted(TOP_KEYS | set(TABLES)))}")
    for t in REQUIRED_TABLES:
        if t not in data:
            raise ctx.error(f"[{t}]", f"missing table; every scenario needs {', '.join('[' + x + ']' for x in REQUIRED_TABLES)}")


def _choice(ctx, where, value, choices):
    if value not in choices:
        raise ctx.error(where, f"{value!r} is not one of {', '.join(repr(c) for c in choices)}")
    return value


@dataclass
class Spec:
    """The validated content of a scenario file, in internal units (plain floats)."""

    name: str
    description: str
    text: str
    dimensionless: bool
    inertia: np.ndarray
    potential_kind: str
    heavy_top: dict = field(default_factory=dict)
    initial: dict = field(default_factory=dict)
    frame: str = "inertial"
    orbit: dict | None = None
    integration: dict = field(default_factory=dict)
    sweep: object = None  # orbatt.sweep.SweepSpec of a [sweep] table, or None


def parse(text: str, source: str = "<scenario>") -> Spec:
    """Validate scenario TOML ``text``; raise :class:`ScenarioError` naming the field."""
    ctx = FieldContext(source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ctx.error("TOML", f"{exc}; fix the syntax") from None
    _check_keys(ctx, data)
    body = data["body"]
    if "inertia" not in body:
        raise ctx.error("[body] inertia", "missing; give the principal moments [I1, I2, I3]")
    inertia_raw = body["inertia"]
    if not isinstance(inertia_raw, list) or len(inertia_raw) != 3:
        raise ctx.error("[body] inertia", f"expected [I1, I2, I3], got {inertia_raw!r}")
    dimless = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in inertia_raw)
    inertia = _vector(ctx, "[body] inertia", inertia_raw, 3, U.INERTIA, dimensionless=dimless)
    try:  # the body's own validation (positive, triangle inequality), reported with the file
        RigidBody(inertia if dimless else inertia * U.INERTIA)
    except InputError as exc:
        raise ctx.error("[body] inertia", f"{inertia_raw!r}: {exc}") from None

    pot = data["potential"]
    kind = _choice(ctx, "[potential] kind", pot.get("kind"), POTENTIAL_KINDS)
    heavy = {}
    if kind == "heavy-top":
        for k in ("mass_g", "center_of_mass"):
            if k not in body:
                raise ctx.error(f"[body] {k}", "missing; the heavy top needs mass_g (M g) and center_of_mass")
        force = U.MASS * U.LENGTH / U.TIME**2
        heavy["mass_g"] = parse_quantity(ctx, "[body] mass_g", body["mass_g"], force, dimensionless=dimless)
        if heavy["mass_g"] < 0:
            raise ctx.error("[body] mass_g", f"{body['mass_g']!r} must be non-negative")
        heavy["center_of_mass"] = _vector(ctx, "[body] center_of_mass", body["center_of_mass"], 3, U.LENGTH,
                                          dimensionless=dimless)
        heavy["sign"] = _choice(ctx, "[potential] sign", pot.get("sign", "physical"), ("physical", "paper"))
    else:
        for k in ("mass_g", "center_of_mass"):
            if k in body:
                raise ctx.error(f"[body] {k}", f"only used by kind = 'heavy-top' (this scenario is {kind!r}); remove it")
        if "sign" in pot:
            raise ctx.error("[potential] sign", "only used by kind = 'heavy-top'; remove it")

    orbit = None
    if kind == "gravity-gradient":
        if "orbit" not in data:
            raise ctx.error("[orbit]", "missing table; the gravity-gradient potential needs an orbit")
        if dimless:
            raise ctx.error("[body] inertia", "the gravity-gradient potential needs a dimensional inertia "
                                              "(e.g. '400 kg km2') to go with the orbit's units")
        orbit = _parse_orbit(ctx, data["orbit"])
    elif "orbit" in data:
        raise ctx.error("[orbit]", f"only used by kind = 'gravity-gradient' (this scenario is {kind!r}); remove it")

    init = data["initial"]
    frame = _choice(ctx, "[initial] frame", init.get("frame", "inertial"), FRAMES)
    if frame == "orbital" and orbit is None:
        raise ctx.error("[initial] frame", "'orbital' needs an [orbit]; use frame = 'inertial'")
    initial = _parse_initial(ctx, init, dimless)

    integ = _parse_integration(ctx, data["integration"], dimless, orbit)
    sweep = None
    if "sweep" in data:  # the [sweep] schema lives with the sweeps (orbatt.sweep)
        from .sweep import parse_sweep_table

        sweep = parse_sweep_table(ctx, data["sweep"], dimensionless=dimless, potential_kind=kind, orbit=orbit,
                                  frame=frame)
    name = data.get("name", Path(source).stem)
    desc = data.get("description", "")
    if not isinstance(name, str) or not isinstance(desc, str):
        raise ctx.error("name/description", "must be strings")
    return Spec(name=name, description=desc, text=text, dimensionless=dimless, inertia=inertia,
                potential_kind=kind, heavy_top=heavy, initial=initial, frame=frame, orbit=orbit,
                integration=integ, sweep=sweep)


def _parse_orbit(ctx, o):
    out = {}
    out["provider"] = _choice(ctx, "[orbit] provider", o.get("provider", "kepler"), PROVIDERS)
    if "gm" in o and "central_body" in o:
        raise ctx.error("[orbit] gm", "give either central_body or gm, not both")
    if "gm" in o:
        out["gm"] = parse_quantity(ctx, "[orbit] gm", o["gm"], U.GM, dimensionless=False)
        if out["gm"] <= 0:
            raise ctx.error("[orbit] gm", f"{o['gm']!r} must be positive")
        out["central_body"] = None
    else:
        out["central_body"] = _choice(ctx, "[orbit] central_body", o.get("central_body", "earth"), ("earth",))
    for k in ("a", "e", "i", "raan", "argp"):
        if k not in o:
            raise ctx.error(f"[orbit] {k}", "missing; the orbit needs a, e, i, raan, argp and an anomaly")
    out["a"] = parse_quantity(ctx, "[orbit] a", o["a"], U.LENGTH, dimensionless=False)
    if out["a"] <= 0:
        raise ctx.error("[orbit] a", f"{o['a']!r} must be positive (elliptic orbits only)")
    out["e"] = parse_quantity(ctx, "[orbit] e", o["e"], U.DIMENSIONLESS, dimensionless=True)
    if not 0 <= out["e"] < 1:
        raise ctx.error("[orbit] e", f"{o['e']!r} is outside [0, 1): only elliptic orbits are supported")
    for k in ("i", "raan", "argp"):
        out[k] = parse_quantity(ctx, f"[orbit] {k}", o[k], U.ANGLE, dimensionless=False)
    anomalies = [k for k in ("true_anomaly", "mean_anomaly") if k in o]
    if len(anomalies) != 1:
        raise ctx.error("[orbit] true_anomaly", "give exactly one of true_anomaly or mean_anomaly")
    out["anomaly_kind"] = anomalies[0]
    out["anomaly"] = parse_quantity(ctx, f"[orbit] {anomalies[0]}", o[anomalies[0]], U.ANGLE, dimensionless=False)
    if "epoch" in o:
        from astropy.time import Time

        try:
            out["epoch"] = Time(str(o["epoch"]), scale="utc")
        except ValueError:
            raise ctx.error("[orbit] epoch", f"{o['epoch']!r} is not an ISO UTC time such as '2026-03-20T00:00:00'") from None
    else:
        out["epoch"] = None
    if out["provider"] == "rebound":
        pert = o.get("perturbations", [])
        if not isinstance(pert, list):
            raise ctx.error("[orbit] perturbations", f"expected a list such as ['j2'], got {pert!r}")
        for p in pert:
            _choice(ctx, "[orbit] perturbations", p, ("j2", "moon", "sun"))
        if ("moon" in pert or "sun" in pert) and out["epoch"] is None:
            raise ctx.error("[orbit] epoch", "third bodies (moon, sun) need an epoch to place them")
        out["perturbations"] = list(pert)
        out["integrator"] = _choice(ctx, "[orbit] integrator", o.get("integrator", "ias15"), ("ias15", "whfast"))
    else:
        for k in ("perturbations", "integrator"):
            if k in o:
                raise ctx.error(f"[orbit] {k}", "only used by provider = 'rebound'; remove it or switch provider")
    return out


def _parse_initial(ctx, init, dimless):
    has = {k for k in ("q", "Q", "omega", "euler_313", "euler_momenta") if k in init}
    valid = ({"q", "Q"}, {"q", "omega"}, {"euler_313", "omega"}, {"euler_313", "euler_momenta"})
    if has not in valid:
        raise ctx.error("[initial]", f"got keys {sorted(has)}; give one of: q and Q | q and omega | "
                                     "euler_313 and omega | euler_313 and euler_momenta")
    out = {}
    if "q" in has:
        q = _plain_vector(ctx, "[initial] q", init["q"], 4)
        n = float(np.linalg.norm(q))
        if abs(n - 1) > 1e-6:
            raise ctx.error("[initial] q", f"{init['q']!r} has |q| = {n:.9g}, not 1; give a unit quaternion "
                                           "(scalar first q0, q1, q2, q3)")
        out["q"] = q / n
    else:
        out["euler_313"] = _vector(ctx, "[initial] euler_313", init["euler_313"], 3, U.ANGLE, dimensionless=True)
    if "Q" in has:
        out["Q"] = _plain_vector(ctx, "[initial] Q", init["Q"], 4)
    if "omega" in has:
        out["omega"] = _vector(ctx, "[initial] omega", init["omega"], 3, U.RATE, dimensionless=dimless)
    if "euler_momenta" in has:
        out["euler_momenta"] = _vector(ctx, "[initial] euler_momenta", init["euler_momenta"], 3, U.MOMENTUM,
                                       dimensionless=dimless)
    return out


def _time(ctx, where, value, dimless, orbit):
    if isinstance(value, str) and value.strip().endswith(("orbits", "orbit")):
        num = value.strip().split()[0]
        try:
            n = float(num)
        except ValueError:
            raise ctx.error(where, f"{value!r}: write 'N orbits' with a number N") from None
        if orbit is None:
            raise ctx.error(where, f"{value!r} needs an [orbit]; give a time such as '100 s'")
        return ("orbits", n)
    return ("time", parse_quantity(ctx, where, value, U.TIME, dimensionless=dimless))


def _parse_integration(ctx, g, dimless, orbit):
    from .propagation import METHODS

    out = {"method": g.get("method", "dop853")}
    if out["method"] not in METHODS:
        raise ctx.error("[integration] method", f"{out['method']!r} is not one of {', '.join(sorted(METHODS))}")
    for k in ("rtol", "atol"):
        if k in g:
            v = g[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (v > 0 and math.isfinite(v)):
                raise ctx.error(f"[integration] {k}", f"{v!r} must be a positive number")
            out[k] = float(v)
    if "step" in g:
        out["step"] = _time(ctx, "[integration] step", g["step"], dimless, orbit)
    for k in ("t_end", "output_step"):
        if k not in g:
            raise ctx.error(f"[integration] {k}", "missing; give the span t_end and the output_step")
        out[k] = _time(ctx, f"[integration] {k}", g[k], dimless, orbit)
        if out[k][1] <= 0:
            raise ctx.error(f"[integration] {k}", f"{g[k]!r} must be positive")
    return out


# ---- building and running ----------------------------------------------------------------
class Scenario:
    """A validated study: the body, potential, orbit, initial state and integration settings.

    Build one with :func:`load_scenario`. :meth:`run` returns the result Dataset; calling it
    again in the same process reuses everything built (the orbit, the compiled kernels).

    Attributes
    ----------
    name, description : str
    text : str
        The scenario file's TOML text (stored in the Dataset's ``scenario`` attribute).
    body : RigidBody
    potential : Potential
    orbit : OrbitProvider or None
    state0 : State
        Initial state in inertial components (converted from the orbital frame if the file
        says ``frame = "orbital"``).
    times : ndarray
        Output times (s, or dimensionless): exactly ``k * output_step``.
    method : str
    settings : dict
        ``rtol``, ``atol``, ``step`` as given (step in the time unit).
    """

    def __init__(self, spec: Spec, path=None):
        from .potentials import HeavyTop, TorqueFree

        self.spec = spec
        self.path = path
        self.name = spec.name
        self.description = spec.description
        self.text = spec.text
        ctx = FieldContext(str(path) if path else spec.name)
        dimless = spec.dimensionless
        self.body = RigidBody(spec.inertia if dimless else spec.inertia * U.INERTIA)
        self.orbit = None
        self._kepler = None
        if spec.orbit is not None:
            self._kepler = build_kepler_orbit(ctx, spec.orbit)
        t_end = self._time(spec.integration["t_end"])
        step_out = self._time(spec.integration["output_step"])
        if step_out > t_end:
            raise ctx.error("[integration] output_step", f"{step_out:g} is longer than t_end = {t_end:g}")
        n = int(math.floor(t_end / step_out * (1 + 1e-12)))
        self.times = np.arange(n + 1, dtype=np.float64) * step_out
        self.t_end = t_end
        if spec.orbit is not None:
            self.orbit = (self._kepler if spec.orbit["provider"] == "kepler"
                          else build_rebound_orbit(ctx, spec.orbit, self._kepler, float(self.times[-1])))
        if spec.potential_kind == "torque-free":
            self.potential = TorqueFree()
        elif spec.potential_kind == "heavy-top":
            h = spec.heavy_top
            if dimless:
                self.potential = HeavyTop(h["mass_g"], h["center_of_mass"], sign=h["sign"])
            else:
                self.potential = HeavyTop(h["mass_g"] * U.MASS * U.LENGTH / U.TIME**2, h["center_of_mass"] * U.LENGTH,
                                          sign=h["sign"])
        else:
            from .potentials import GravityGradient

            self.potential = GravityGradient(self.orbit)
        self.state0 = self._initial_state(ctx)
        self.method = spec.integration["method"]
        self.settings = {k: spec.integration[k] for k in ("rtol", "atol") if k in spec.integration}
        if "step" in spec.integration:
            self.settings["step"] = self._time(spec.integration["step"])

    def _time(self, t):
        kind, value = t
        return value * self._kepler.period if kind == "orbits" else value

    def _initial_state(self, ctx):
        from .state import State

        ini = self.spec.initial
        body = self.body
        try:
            if "euler_momenta" in ini:
                if self.spec.frame == "orbital":
                    raise ctx.error("[initial] frame", "euler_momenta are inertial; use omega with frame = 'orbital'")
                return State.from_euler(body, ini["euler_313"], ini["euler_momenta"])
            if "q" in ini:
                q = ini["q"]
            else:
                from . import quaternion as qt

                q = qt.from_euler313(*ini["euler_313"])
            if self.spec.frame == "orbital":
                from .orbital import state_from_orbital

                if "Q" in ini:
                    raise ctx.error("[initial] Q", "Q is inertial; with frame = 'orbital' give omega (relative rates)")
                return state_from_orbital(body, self.orbit, q, ini["omega"] * U.RATE)
            if "Q" in ini:
                return State(body, q, ini["Q"])
            w = ini["omega"] if body.dimensionless else ini["omega"] * U.RATE
            return State.from_omega(body, q, w)
        except ScenarioError:
            raise
        except InputError as exc:
            raise ctx.error("[initial]", str(exc)) from None

    def run(self, method=None, progress=False, **overrides):
        """Propagate and return the result :class:`xarray.Dataset` (see :mod:`orbatt.dataset`).

        Parameters
        ----------
        method : str, optional
            Override the file's ``[integration] method`` (its rtol/atol/step still apply
            where the method takes them).
        progress : bool or callable
            Progress bar (True) or callback; off by default.
        **overrides
            Further keyword arguments for :func:`orbatt.propagate` (e.g. ``rtol``).
        """
        from .dataset import to_dataset
        from .propagation import propagate

        kw = dict(self.settings)
        kw.update(overrides)
        m = method or self.method
        try:
            traj = propagate(self.body, self.state0, self.potential, self.times, method=m, progress=progress, **kw)
        except InputError as exc:  # e.g. a fixed-step method chosen without [integration] step
            raise ScenarioError(f"{self.path or self.name}: [integration] (method {m!r}): {exc}") from None
        epoch = self.orbit.epoch if self.orbit is not None else None
        return to_dataset(traj, scenario_text=self.text, epoch=epoch, title=f"orbatt: {self.name}")

    def __repr__(self):
        return f"Scenario({self.name!r}, method={self.method!r}, outputs={self.times.size})"


def build_kepler_orbit(ctx, o):
    from .orbits import KeplerOrbit

    kw = {o["anomaly_kind"]: o["anomaly"] * U.ANGLE}
    if o["central_body"] is None:
        kw["gm"] = o["gm"] * U.GM
    else:
        kw["central_body"] = o["central_body"]
    if o["epoch"] is not None:
        kw["epoch"] = o["epoch"]
    try:  # a periapsis inside the central body warns (PeriapsisWarning), as the paper's Sect. 6.2 orbit does
        return KeplerOrbit(o["a"] * U.LENGTH, o["e"], o["i"] * U.ANGLE, o["raan"] * U.ANGLE,
                           o["argp"] * U.ANGLE, **kw)
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def build_rebound_orbit(ctx, o, kepler, t_end):
    from .orbits import ReboundOrbit

    try:
        return ReboundOrbit(kepler, t_end * U.TIME, perturbations=o["perturbations"], integrator=o["integrator"])
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def shipped_scenarios():
    """``[(name, description, path)]`` of the scenarios shipped with orbatt."""
    from importlib.resources import files

    try:
        folder = files("orbatt.scenarios")
    except ModuleNotFoundError:  # a source checkout used without installing: scenarios/ beside orbatt/
        folder = Path(__file__).resolve().parent.parent / "scenarios"
    out = []
    for f in sorted(folder.iterdir(), key=lambda p: p.name):
        if f.name.endswith(".toml"):
            spec = parse(f.read_text(), f.name)
            out.append((spec.name, spec.description, f))
    return out


def load_scenario(path) -> Scenario:
    """Read and validate a scenario file; return a :class:`Scenario`.

    Parameters
    ----------
    path : str or Path
        A TOML file, or the name of a shipped scenario (``orbatt scenarios`` lists them).

    Raises
    ------
    ScenarioError
        (an :class:`~orbatt.errors.InputError`) naming the file, the field, the value and
        the fix.
    """
    p = Path(path)
    if not p.is_file():
        shipped = {name: f for name, _, f in shipped_scenarios()}
        key = p.name[:-5] if p.name.endswith(".toml") else p.name
        if key in shipped:
            return Scenario(parse(shipped[key].read_text(), key), path=key)
        raise ScenarioError(f"{path}: no such scenario file; give a path to a TOML file or one of: "
                            f"{', '.join(sorted(shipped))}")
    return Scenario(parse(p.read_text(), str(p)), path=p)

"""The scenario file schema (TOML) and its validation, ``[sweep]`` table included.

A scenario describes one study; :func:`load_scenario` validates it completely (unknown keys
and tables are refused, every quantity is checked for its dimension) and returns a
:class:`Scenario` whose :meth:`Scenario.run` returns the result Dataset.

Schema (the contract other tools read; quantities are strings astropy parses, e.g.
``"7000 km"``, ``"30 deg"``, ``"0.001 rad / s"``; plain numbers mean dimensionless: a
scenario written in plain numbers throughout, ``gm`` and ``a`` included, is in normalized
units, lengths in the unit of ``a`` and times in the unit ``gm`` implies; a mix of plain and
dimensional quantities is refused naming the first plain key)::

    name = "..."                  # optional; defaults to the file name
    description = "..."           # optional, one line
    [body]        inertia = [I1, I2, I3] | 3x3 tensor | [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (body frame);
                  heavy top: mass_g, center_of_mass = [x, y, z]
    [initial]     q = [...] and Q = [...]
                  | q = [...] or euler_313 = [phi, theta, psi], with omega = [w1, w2, w3]
                  | euler_313 with euler_momenta = [Phi, Theta, Psi]
                  frame = "inertial" (default) | "orbital"
    [potential]   kind = "torque-free" | "heavy-top" | "gravity-gradient"
                  sign = "physical" (default) | "paper"        (heavy top)
    [orbit]       provider = "kepler" | "rebound" | "tle" | "coupled" (a binary asteroid: its own
                  schema, :mod:`orbatt.scenario.binary_schema`); central_body = "earth" | gm = "..."
                  a, e, i, raan, argp, and one of true_anomaly | mean_anomaly
                  epoch (ISO UTC); rebound: perturbations = ["j2", "moon", "sun"], integrator
    [integration] method, rtol, atol | step, t_end, output_step, independent_variable
                  (times: a time, a plain number if dimensionless, or "N orbits")
    [sweep]       optional: parameters varied over many cases, run by ``orbatt sweep``
                  (schema: :mod:`orbatt.scenario.sweep_schema`); ``orbatt run`` runs the nominal case

Quantity rules (:func:`orbatt.scenario.fields.parse_quantity`): a string is one number and
one unit, parsed whole (``"1 2 orbits"``, ``"0.01 planet orbits"`` are refused); the unit has
the dimension of the key; **angles always carry an angle unit** (``"45 deg"``, ``"0.8 rad"``;
``"45"``, ``45`` and ``"98.2 deg deg"`` are refused; a plain ``0`` is accepted), in
dimensionless scenarios too; every value is finite. Every numeric key has a physical range
(:data:`orbatt.scenario.ranges.RANGES`, shown in ``docs/scenarios.md``; the ranges of
dimensional quantities apply to dimensional scenarios); an ``[orbit] a`` whose apoapsis
``a (1 + e)`` lies below the Earth's surface is refused (a periapsis below it only warns, as in
the paper's Sect. 6.2 orbit).

Work limits, checked before the run: at most :data:`~orbatt.scenario.build.MAX_OUTPUTS`
output times (``t_end / output_step``), and at most
:data:`~orbatt.scenario.build.MAX_WORK_STEPS` integration steps by a lower estimate (the
body's rotation angle ``|omega| t_end``, twice the orbital angle and the angles of the torques'
and control laws' time scales, :mod:`orbatt.scenario.work`, at most pi rad per step; a fixed
step's count): a run past them would take hours or fail at ``max_steps``.

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

from .. import units as U
from ..body import RigidBody
from ..control import reaction_wheel
from ..errors import InputError
from ..epoch import parse_epoch
from .inertia_schema import check_sweep, parse_inertia
from .key_docs import parse_key_docs
from .ranges import RANGES
from .fields import (FieldContext, check_integers, parse_choice, parse_int, parse_plain_vector, parse_quantity, parse_time,
                     parse_vector)
from .sweep_schema import SweepSpec, parse_sweep_table
from .binary_schema import BinarySpec, is_binary, parse_binary
from .control_schema import CONTROL_KEYS, parse_control
from .sensors_schema import FEEDBACK_DOC, SENSOR_KEY_DOCS, SENSOR_TABLES, parse_navigation, reads_magnetic_field
from .torques_schema import ENVIRONMENT_KEYS, TORQUE_KEYS, parse_torques
from ..methods import METHODS
from ..methods.dop853 import INDEPENDENT_VARIABLES
from ..methods.problem import MAX_ATOL, MAX_RTOL
from ..orbits import R_EARTH
from ..laws import control_key_docs, mode_key_docs
from ..laws import reads_field
from ..terms import torque_key_docs

__all__ = ["Spec", "parse", "RANGES", "TOP_KEYS", "TABLES", "KEY_DOCS", "REQUIRED_TABLES", "POTENTIAL_KINDS", "FRAMES",
           "PROVIDERS"]

TOP_KEYS = {"name", "description"}
TABLES = {
    "body": {"inertia", "mass_g", "center_of_mass", "facets", "wheels"},
    "initial": {"q", "Q", "omega", "euler_313", "euler_momenta", "frame"},
    "potential": {"kind", "sign"},
    "orbit": {"provider", "central_body", "gm", "a", "e", "i", "raan", "argp", "true_anomaly",
              "mean_anomaly", "epoch", "perturbations", "integrator", "tle", "tle_file"},
    "integration": {"method", "rtol", "atol", "step", "t_end", "output_step", "independent_variable", "max_steps"},
    "sweep": None,  # keys checked by parse_sweep_table (sweep_schema.py)
    "torques": TORQUE_KEYS,  # validated by parse_torques (torques_schema.py)
    "environment": ENVIRONMENT_KEYS,
    "control": CONTROL_KEYS | {"feedback"},  # validated by parse_control (control_schema.py); feedback below
    "sensors": SENSOR_TABLES["sensors"],  # validated by parse_navigation (sensors_schema.py)
    "estimator": SENSOR_TABLES["estimator"],
}
#: what each key of :data:`TABLES` is: ``(dimension, default, meaning)``, written as a table
#: (:mod:`orbatt.scenario.key_docs`); ``docs/scenarios.md`` is generated from it by
#: :mod:`orbatt.scenario.reference` (a test keeps the two equal and every key described).
#: "plain" dimensions are numbers without a unit; a quantity is a string astropy parses
#: ("7000 km"), or a plain number in a scenario in normalized units.
KEY_DOCS = parse_key_docs("""
[]
name         text  the file name  the scenario's name (Dataset title, `orbatt scenarios`)
description  text  ""             one line saying what the study is

[body]
inertia         mass x length^2, 3/6/3x3   required                principal moments [I1, I2, I3] about body axes 1,
                                                                   2, 3; or the inertia tensor about the centre of
                                                                   mass in the body (mechanical) frame, as CAD gives
                                                                   it: a 3x3 matrix [[Ixx, Ixy, Ixz], [Ixy, Iyy,
                                                                   Iyz], [Ixz, Iyz, Izz]] or six values [Ixx, Iyy,
                                                                   Izz, Ixy, Ixz, Iyz], the off-diagonal entries
                                                                   being the matrix's (I_xy = -∫ x y dm, products
                                                                   of inertia with their minus sign); a tensor that
                                                                   is not diagonal is integrated in its principal
                                                                   axes while every body-fixed key and every
                                                                   body-axes output stays in the body frame
                                                                   (docs/design.md §8, orbatt.body_frame); it has
                                                                   positive principal moments that satisfy the
                                                                   triangle inequality; a tensor cannot be swept
                                                                   (the scenario's other keys can: each case runs
                                                                   in the body frame); plain numbers make the
                                                                   scenario dimensionless (normalized units)
mass_g          force                      required for heavy-top  weight M g of the heavy top
center_of_mass  length, 3 values           required for heavy-top  centre of mass in body axes, relative to the
                                                                   fixed point
facets          array of tables            none                    [[body.facets]]: the flat plates of the body, for
                                                                   [torques] drag and srp (keys below)
wheels          array of tables            none                    [[body.wheels]]: reaction wheels (keys below);
                                                                   the body becomes a gyrostat and `inertia` is that
                                                                   of the whole spacecraft with the rotors locked

[body.wheels]
axis        plain, 3 values  required  unit spin axis, body axes
inertia     mass x length^2  required  axial moment of the rotor
speed       angular rate     0         rotor speed relative to the body at the start (`"1000 rpm"`)
max_torque  torque (N m)     none      motor torque limit
max_speed   angular rate     none      speed limit: the motor does not push the rotor beyond it
friction_coulomb  torque (N m)  none  bearing friction against the rotor's speed relative to the body:
                                      friction_coulomb tanh(speed / friction_width) (Basilisk's model, smoothed)
friction_viscous  torque x time (N m s)  none  viscous friction: friction_viscous speed
friction_width  angular rate  0.1 rad/s  the speed over which the Coulomb friction turns (with friction_coulomb)

[body.facets]
area              area              required  the plate's area (> 0)
normal            plain, 3 values   required  outward unit normal, body axes
position          length, 3 values  required  centre of pressure from the centre of mass, body axes
drag_coefficient  plain             2.2       C_D of the plate (drag)
specular          plain in [0, 1]   0         specular reflectivity (SRP); absorbed = 1 - specular - diffuse
diffuse           plain in [0, 1]   0         diffuse reflectivity (SRP)

[environment]
atmosphere      'exponential' | 'nrlmsis' | 'none'  'exponential' with drag        density model (NRLMSIS 2.1 through
                                                                                   pymsis needs the epoch and f107, f107a,
                                                                                   ap)
density0        density                             Vallado's table                exponential: density at altitude0 (with
                                                                                   altitude0, scale_height)
altitude0       length                              Vallado's table                exponential: reference altitude above
                                                                                   the equatorial radius
scale_height    length                              Vallado's table                exponential: scale height
corotation      true | false                        true                           the atmosphere turns with the Earth
                                                                                   (drag uses v - omega_E x r)
f107            plain                               required for nrlmsis           daily F10.7 solar flux (sfu); never
                                                                                   downloaded
f107a           plain                               required for nrlmsis           81-day mean F10.7 (sfu)
ap              plain                               required for nrlmsis           daily Ap geomagnetic index
magnetic_field  'igrf' | 'dipole' | 'none'          'igrf' with a residual dipole  IGRF-14 (ppigrf) or its tilted dipole at
                                                                                   the epoch
shadow          'conical' | 'cylindrical' | 'none'  'conical'                      the Earth's shadow for SRP (umbra and
                                                                                   penumbra)

[initial]
q              plain, 4 values         -           attitude quaternion (q0 scalar first), body -> `frame`
                                                   components; |q| = 1
Q              momentum, 4 values      -           conjugate momentum Q = 2 q (0, I omega) (inertial frame only)
omega          angular rate, 3 values  -           body angular velocity in body axes (relative to the orbital frame
                                                   when frame = 'orbital')
euler_313      angle, 3 values         -           3-1-3 Euler angles (phi, theta, psi) instead of q
euler_momenta  momentum, 3 values      -           momenta conjugate to the 3-1-3 angles (inertial frame only)
frame          'inertial' | 'orbital'  'inertial'  the frame q, euler_313 and omega are relative to

[potential]
kind  'torque-free' | 'heavy-top' | 'gravity-gradient'  required    the torque acting on the body
sign  'physical' | 'paper'                              'physical'  heavy top: U = M g z_c, or eq. (18) as printed
                                                                    (Fig. 2)

[orbit]
provider       'kepler' | 'rebound' | 'tle'   'kepler'              Keplerian elements, REBOUND integration, or SGP4
                                                                    from a TLE
central_body   'earth'                        'earth'               the central body (its GM from astropy); or give
                                                                    gm
gm             length^3 / time^2              the Earth's           central body's G M (a plain number in normalized
                                                                    units: gm = 1, a = 1 make the mean motion 1)
a              length                         required (not tle)    semi-major axis (> 0; the unit of length in
                                                                    normalized units)
e              plain                          required (not tle)    eccentricity, 0 <= e < 1
i              angle                          required (not tle)    inclination to the s1-s2 plane of the inertial
                                                                    frame
raan           angle                          required (not tle)    right ascension of the ascending node
argp           angle                          required (not tle)    argument of periapsis
true_anomaly   angle                          one of the two        true anomaly at t = 0
mean_anomaly   angle                          one of the two        mean anomaly at t = 0
epoch          ISO time (UTC)                 none; tle: the TLE's  the instant t = 0 (CF time axis, third bodies; the
                                                                    date of the Sun, NRLMSIS and the magnetic field)
perturbations  list of 'j2' | 'moon' | 'sun'  []                    rebound: forces besides the central point mass
integrator     'ias15' | 'whfast'             'ias15'               rebound: the REBOUND integrator
tle            2 text lines                   one of tle, tle_file  tle: the two-line element set
tle_file       path                           one of tle, tle_file  tle: a file with the two lines (a name line
                                                                    optional), relative to the scenario file

[integration]
method       text                'dop853'                        the integration method (listed by
                                                                 `orbatt.methods.methods()`)
rtol         plain               the method's                    relative tolerance (adaptive methods)
atol         plain               the method's                    absolute tolerance (adaptive methods)
step         time or 'N orbits'  required by fixed-step methods  the fixed step
t_end        time or 'N orbits'  required                        the span; outputs at k * output_step <= t_end
output_step  time or 'N orbits'  required                        spacing of the output times
independent_variable  text       'auto'                          DOP853's variable: 'auto' (the eccentric anomaly
                                                                 on a Keplerian orbit, no Kepler solve per stage:
                                                                 ~2x faster; else the time), 'eccentric-anomaly'
                                                                 or 'time' (orbatt 0.1's numbers)
max_steps    plain integer       1e8 (the bound)                 most step attempts; giving it agrees to a run the
                                                                 work estimate finds long (above 1e7 steps; else
                                                                 orbatt run --yes)

[sweep]
# described by orbatt.scenario.sweep_schema.SWEEP_KEY_DOCS
""")
#: the [torques] keys are described by their terms (orbatt.terms)
KEY_DOCS["torques"] = torque_key_docs()
KEY_DOCS["control"] = control_key_docs()
KEY_DOCS["control.modes"] = mode_key_docs()
KEY_DOCS["control"]["feedback"] = FEEDBACK_DOC
KEY_DOCS.update(SENSOR_KEY_DOCS)
REQUIRED_TABLES = ("body", "initial", "potential", "integration")
#: central body radii (km) below which an apoapsis is refused
BODY_RADII = {"earth": R_EARTH}
POTENTIAL_KINDS = ("torque-free", "heavy-top", "gravity-gradient")
FRAMES = ("inertial", "orbital")
PROVIDERS = ("kepler", "rebound", "tle")
#: the [orbit] keys of provider = "tle" (the elements come from the TLE)
TLE_KEYS = {"provider", "tle", "tle_file", "epoch", "central_body"}


def _check_keys(ctx, data):
    """Unknown tables and keys refused; the required tables present."""
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
    sweep: SweepSpec | None = None  # the [sweep] table, if any
    torques: dict | None = None  # [torques], [environment] and the facets (torques_schema.py)
    control: dict | None = None  # [control] and the wheels, plain settings (control_schema.py)
    inertia_tensor: np.ndarray | None = None  # [body] inertia given as a tensor (body frame; inertia: its moments)


def parse(text: str, source: str = "<scenario>") -> Spec | BinarySpec:
    """Validate scenario TOML ``text``; raise :class:`ScenarioError` naming the field. A binary
    asteroid (``[orbit] provider = "coupled"``) gives a :class:`~orbatt.scenario.binary_schema.BinarySpec`."""
    ctx = FieldContext(source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ctx.error("TOML", f"{exc}; fix the syntax") from None
    except RecursionError:
        raise ctx.error("TOML", "arrays or tables nested too deeply to parse; scenario values are at most "
                                "2 levels deep") from None
    check_integers(ctx, data)
    if is_binary(data):  # [orbit] provider = "coupled" or a [primary]: a binary asteroid
        return parse_binary(ctx, data, text, source)
    _check_keys(ctx, data)
    body = data["body"]
    if "inertia" not in body:
        raise ctx.error("[body] inertia", "missing; give the principal moments [I1, I2, I3] (or the tensor)")
    # principal moments, or a tensor in the body frame (scenario/inertia_schema.py), validated by RigidBody
    dimless, inertia, tensor = parse_inertia(ctx, body["inertia"], RANGES["body", "inertia"])

    pot = data["potential"]
    kind = parse_choice(ctx, "[potential] kind", pot.get("kind"), POTENTIAL_KINDS)
    heavy = {}
    if kind == "heavy-top":
        for k in ("mass_g", "center_of_mass"):
            if k not in body:
                raise ctx.error(f"[body] {k}", "missing; the heavy top needs mass_g (M g) and center_of_mass")
        force = U.MASS * U.LENGTH / U.TIME**2
        heavy["mass_g"] = parse_quantity(ctx, "[body] mass_g", body["mass_g"], force, dimensionless=dimless,
                                         bounds=None if dimless else RANGES["body", "mass_g"])
        if heavy["mass_g"] < 0:
            raise ctx.error("[body] mass_g", f"{body['mass_g']!r} must be non-negative")
        heavy["center_of_mass"] = parse_vector(ctx, "[body] center_of_mass", body["center_of_mass"], 3, U.LENGTH,
                                               dimensionless=dimless,
                                               bounds=None if dimless else RANGES["body", "center_of_mass"])
        heavy["sign"] = parse_choice(ctx, "[potential] sign", pot.get("sign", "physical"), ("physical", "paper"))
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
        orbit = _parse_orbit(ctx, data["orbit"], source, dimless)
    elif "orbit" in data:
        raise ctx.error("[orbit]", f"only used by kind = 'gravity-gradient' (this scenario is {kind!r}); remove it")

    ctl = data.get("control")
    torques = parse_torques(ctx, data, kind, orbit, bdot=reads_field(ctl) or reads_magnetic_field(data))
    if torques is not None and dimless:
        raise ctx.error("[torques]", "the environment torques need a dimensional scenario ([body] inertia with units)")
    init = data["initial"]
    frame = parse_choice(ctx, "[initial] frame", init.get("frame", "inertial"), FRAMES)
    if frame == "orbital" and orbit is None:
        raise ctx.error("[initial] frame", "'orbital' needs an [orbit]; use frame = 'inertial'")
    initial = _parse_initial(ctx, init, dimless)

    integ = _parse_integration(ctx, data["integration"], dimless, orbit)
    ctl_data = data  # [control] feedback belongs to the sensors (sensors_schema.py), not to a law
    if isinstance(ctl, dict) and "feedback" in ctl:
        ctl_data = {**data, "control": {k: v for k, v in ctl.items() if k != "feedback"}}
    control = parse_control(ctx, ctl_data, kind, orbit, dimless, integ["method"])
    navigation = parse_navigation(ctx, data, None if control is None else control["control"], orbit)
    if navigation is not None:
        control["navigation"] = navigation
        if control["magnetic_field"] is None:  # the field a magnetometer reads (and the filter predicts)
            control["magnetic_field"] = navigation["magnetic_field"]
    if control is not None and control["wheels"]:
        try:  # the gyrostat must keep inertia about every axis
            RigidBody((inertia if tensor is None else tensor) * U.INERTIA,
                      wheels=[reaction_wheel(w) for w in control["wheels"]])
        except InputError as exc:
            raise ctx.error("[[body.wheels]] inertia", str(exc).split(": ", 1)[-1]) from None
    sweep = None
    if "sweep" in data:
        sweep = parse_sweep_table(ctx, data["sweep"], dimensionless=dimless, potential_kind=kind, orbit=orbit,
                                  frame=frame, conservative=control is None and torques is None,
                                  control=_sweep_control(control),
                                  wheels=0 if control is None else len(control["wheels"]), data=data)
        check_sweep(ctx, sweep, tensor)
    name = data.get("name", Path(source).stem)
    desc = data.get("description", "")
    if not isinstance(name, str) or not isinstance(desc, str):
        raise ctx.error("name/description", "must be strings")
    return Spec(name=name, description=desc, text=text, dimensionless=dimless, inertia=inertia,
                potential_kind=kind, heavy_top=heavy, initial=initial, frame=frame, orbit=orbit,
                integration=integ, sweep=sweep, torques=torques, control=control, inertia_tensor=tensor)


def _sweep_control(control):
    """The law's settings the ``[sweep]`` table checks its outputs against, marked with whether
    an attitude filter runs (the knowledge indices need one)."""
    if control is None or control["control"] is None:
        return None
    nav = control.get("navigation")
    return {**control["control"], "estimator": nav is not None and nav["estimator"] is not None}


def _check_normalized_orbit(ctx, o):
    """A dimensionless scenario's orbit (normalized units): ``gm`` given as a plain number, no
    named central body, no calendar epoch, no TLE."""
    if o.get("provider") == "tle":
        raise ctx.error("[orbit] provider", "'tle' needs a dimensional scenario, but [body] inertia is plain numbers "
                                            "(normalized units); give the inertia with units, e.g. '400 kg m^2'")
    for k in ("central_body", "epoch"):
        if k in o:
            raise ctx.error(f"[orbit] {k}", "not used in normalized units ([body] inertia is plain numbers): remove "
                                            "it and give gm as a plain number (gm = 1.0 with a = 1.0: mean motion 1)")
    if "gm" not in o:
        raise ctx.error("[orbit] gm", "missing; in normalized units ([body] inertia is plain numbers) give gm as a "
                                      "plain number (gm = 1.0 with a = 1.0 makes the mean motion 1)")


def _parse_orbit(ctx, o, source="<scenario>", dimless=False):
    out = {}
    if dimless:
        _check_normalized_orbit(ctx, o)
    out["provider"] = parse_choice(ctx, "[orbit] provider", o.get("provider", "kepler"), PROVIDERS)
    if out["provider"] == "tle":
        return _parse_tle_orbit(ctx, o, source)
    for k in ("tle", "tle_file"):
        if k in o:
            raise ctx.error(f"[orbit] {k}", "only used by provider = 'tle'; remove it or set provider = 'tle'")
    if "gm" in o and "central_body" in o:
        raise ctx.error("[orbit] gm", "give either central_body or gm, not both")
    if "gm" in o:
        out["gm"] = parse_quantity(ctx, "[orbit] gm", o["gm"], U.GM, dimensionless=dimless,
                                   bounds=RANGES["orbit", "gm"])
        out["central_body"] = None
    else:
        out["central_body"] = parse_choice(ctx, "[orbit] central_body", o.get("central_body", "earth"), ("earth",))
    for k in ("a", "e", "i", "raan", "argp"):
        if k not in o:
            raise ctx.error(f"[orbit] {k}", "missing; the orbit needs a, e, i, raan, argp and an anomaly")
    out["a"] = parse_quantity(ctx, "[orbit] a", o["a"], U.LENGTH, dimensionless=dimless, bounds=RANGES["orbit", "a"])
    out["e"] = parse_quantity(ctx, "[orbit] e", o["e"], U.DIMENSIONLESS, dimensionless=True)
    if not 0 <= out["e"] < 1:
        raise ctx.error("[orbit] e", f"{o['e']!r} is outside [0, 1): only elliptic orbits are supported")
    radius = BODY_RADII.get(out["central_body"])
    if radius is not None and out["a"] * (1 + out["e"]) < radius:
        raise ctx.error("[orbit] a", f"{o['a']!r} with e = {out['e']:g}: the whole orbit (apoapsis "
                                     f"{out['a'] * (1 + out['e']):.6g} km) lies inside the central body "
                                     f"({out['central_body']}, radius {radius:.6g} km); raise a")
    for k in ("i", "raan", "argp"):
        out[k] = parse_quantity(ctx, f"[orbit] {k}", o[k], U.ANGLE, dimensionless=False)
    anomalies = [k for k in ("true_anomaly", "mean_anomaly") if k in o]
    if len(anomalies) != 1:
        raise ctx.error("[orbit] true_anomaly", "give exactly one of true_anomaly or mean_anomaly")
    out["anomaly_kind"] = anomalies[0]
    out["anomaly"] = parse_quantity(ctx, f"[orbit] {anomalies[0]}", o[anomalies[0]], U.ANGLE, dimensionless=False)
    out["dimensionless"] = dimless
    if "epoch" in o:
        try:  # the orbit providers' own parser: a string astropy parses, taken as UTC
            out["epoch"] = parse_epoch(str(o["epoch"]))
        except InputError as exc:
            raise ctx.error("[orbit] epoch", str(exc).split(": ", 1)[-1]) from None
    else:
        out["epoch"] = None
    if out["provider"] == "rebound":
        pert = o.get("perturbations", [])
        if not isinstance(pert, list):
            raise ctx.error("[orbit] perturbations", f"expected a list such as ['j2'], got {pert!r}")
        for p in pert:
            parse_choice(ctx, "[orbit] perturbations", p, ("j2", "moon", "sun"))
        if ("moon" in pert or "sun" in pert) and out["epoch"] is None:
            raise ctx.error("[orbit] epoch", "third bodies (moon, sun) need an epoch to place them")
        out["perturbations"] = list(pert)
        out["integrator"] = parse_choice(ctx, "[orbit] integrator", o.get("integrator", "ias15"), ("ias15", "whfast"))
    else:
        for k in ("perturbations", "integrator"):
            if k in o:
                raise ctx.error(f"[orbit] {k}", "only used by provider = 'rebound'; remove it or switch provider")
    return out


def _parse_tle_orbit(ctx, o, source):
    """``[orbit] provider = "tle"``: the two lines (``tle``) or a file (``tle_file``, relative
    to the scenario file), checked here (:func:`orbatt.orbits.tle.parse_tle`); an optional
    ``epoch`` (default: the TLE's, which ``epoch`` holds then)."""
    from ..orbits.tle import parse_tle, read_tle_file, tle_epoch

    extra = sorted(set(o) - TLE_KEYS)
    if extra:
        raise ctx.error(f"[orbit] {extra[0]}", "not used by provider = 'tle' (the elements come from the TLE); "
                                               "remove it")
    if ("tle" in o) == ("tle_file" in o):
        raise ctx.error("[orbit] tle", "give exactly one of tle = ['1 ...', '2 ...'] or tle_file = 'path'")
    parse_choice(ctx, "[orbit] central_body", o.get("central_body", "earth"), ("earth",))
    try:
        if "tle" in o:
            lines = list(parse_tle(o["tle"], "tle"))
        else:
            path = Path(str(o["tle_file"]))
            if not path.is_absolute() and Path(source).parent.is_dir():
                path = Path(source).parent / path
            lines = list(read_tle_file(path, "tle_file"))
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None
    out = {"provider": "tle", "tle": lines, "central_body": "earth", "gm": None}
    # the TLE's own epoch unless [orbit] epoch moves t = 0: what the environment and the
    # control laws read (NRLMSIS, IGRF, the Sun), like a Keplerian orbit's epoch
    out["epoch"] = tle_epoch(lines[-2], lines[-1])
    if "epoch" in o:
        try:
            out["epoch"] = parse_epoch(str(o["epoch"]))
        except InputError as exc:
            raise ctx.error("[orbit] epoch", str(exc).split(": ", 1)[-1]) from None
    return out


def _parse_initial(ctx, init, dimless):
    has = {k for k in ("q", "Q", "omega", "euler_313", "euler_momenta") if k in init}
    valid = ({"q", "Q"}, {"q", "omega"}, {"euler_313", "omega"}, {"euler_313", "euler_momenta"})
    if has not in valid:
        raise ctx.error("[initial]", f"got keys {sorted(has)}; give one of: q and Q | q and omega | "
                                     "euler_313 and omega | euler_313 and euler_momenta")
    out = {}
    if "q" in has:
        q = parse_plain_vector(ctx, "[initial] q", init["q"], 4)
        n = float(np.linalg.norm(q))
        if abs(n - 1) > 1e-6:
            raise ctx.error("[initial] q", f"{init['q']!r} has |q| = {n:.9g}, not 1; give a unit quaternion "
                                           "(scalar first q0, q1, q2, q3)")
        out["q"] = q / n
    else:
        out["euler_313"] = parse_vector(ctx, "[initial] euler_313", init["euler_313"], 3, U.ANGLE, dimensionless=True)
    if "Q" in has:
        out["Q"] = parse_plain_vector(ctx, "[initial] Q", init["Q"], 4)
    if "omega" in has:
        out["omega"] = parse_vector(ctx, "[initial] omega", init["omega"], 3, U.RATE, dimensionless=dimless,
                                    bounds=None if dimless else RANGES["initial", "omega"])
    if "euler_momenta" in has:
        out["euler_momenta"] = parse_vector(ctx, "[initial] euler_momenta", init["euler_momenta"], 3, U.MOMENTUM,
                                            dimensionless=dimless,
                                            bounds=None if dimless else RANGES["initial", "euler_momenta"])
    return out


def _parse_integration(ctx, g, dimless, orbit):
    out = {"method": g.get("method", "dop853")}
    if not isinstance(out["method"], str) or out["method"] not in METHODS:
        raise ctx.error("[integration] method", f"{out['method']!r} is not one of {', '.join(sorted(METHODS))}")
    for k, hi, why in (("rtol", MAX_RTOL, "a relative error above 10% gives no accuracy at all"),
                       ("atol", MAX_ATOL, "|q| = 1, so an absolute error above 1 leaves the attitude uncontrolled")):
        if k in g:
            v = g[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (v > 0 and math.isfinite(v)):
                raise ctx.error(f"[integration] {k}", f"{v!r} must be a positive number")
            if v > hi:
                raise ctx.error(f"[integration] {k}", f"{v!r} is above {hi:g}: {why}; give e.g. {k} = 1e-10")
            out[k] = float(v)
    if "step" in g:
        out["step"] = parse_time(ctx, "[integration] step", g["step"], dimless, orbit,
                                 bounds=None if dimless else RANGES["integration", "step"])
    if "independent_variable" in g:
        iv = parse_choice(ctx, "[integration] independent_variable", g["independent_variable"], INDEPENDENT_VARIABLES)
        provider = None if orbit is None else orbit["provider"]
        if iv == "eccentric-anomaly" and provider != "kepler":
            has = "has no orbit" if provider is None else f"has provider = {provider!r}"
            raise ctx.error("[integration] independent_variable",
                            f"'eccentric-anomaly' needs a Keplerian orbit ([orbit] provider = 'kepler'); this "
                            f"scenario {has}; give independent_variable = 'auto'")
        out["independent_variable"] = iv
    if "max_steps" in g:
        v = g["max_steps"]  # an integer, or an integral float (1e9)
        v = int(v) if isinstance(v, float) and v.is_integer() and 1 <= v < 1e12 else v
        out["max_steps"] = parse_int(ctx, "[integration] max_steps", v, 1, 10**12)
    for k in ("t_end", "output_step"):
        if k not in g:
            raise ctx.error(f"[integration] {k}", "missing; give the span t_end and the output_step")
        out[k] = parse_time(ctx, f"[integration] {k}", g[k], dimless, orbit,
                            bounds=None if dimless else RANGES["integration", k])
    return out

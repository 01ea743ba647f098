"""Building the objects of a study from a validated :class:`~orbatt.scenario.schema.Spec`:
the orbit, the potential, the initial state and the output times.

Every builder takes a :class:`~orbatt.scenario.fields.FieldContext` and reports an
:class:`~orbatt.errors.InputError` of the object it builds as a
:class:`~orbatt.errors.ScenarioError` naming the file and the table.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from astropy import units as u

from .. import quaternion as qt
from .. import units as U
from ..laws import control_law
from .sensors_schema import attach_navigation
from ..errors import InputError, IntegrationError, ScenarioError
from ..methods.problem import DEFAULT_MAX_STEPS
from ..orbits import KeplerOrbit, ReboundOrbit, TleOrbit
from ..potentials import GravityGradient, HeavyTop, TorqueFree
from ..environment.atmosphere import NRLMSIS, ExponentialAtmosphere, PiecewiseExponentialAtmosphere
from ..environment.magnetic import DipoleField, IGRFField
from ..state import State
from ..torques import EnvironmentTorques, facet, sample_margin
from ..orbital import state_from_orbital
from .torques_schema import torque_arguments
from .work import counted_work, torque_rates

__all__ = ["build_kepler_orbit", "build_rebound_orbit", "build_tle_orbit", "environment_margin", "tle_period",
           "build_potential",
           "build_environment_torques", "build_control", "build_initial_state",
           "build_output_times", "check_work", "run_to_content", "check_field_span", "estimate_steps", "MAX_OUTPUTS", "MAX_WORK_STEPS",
           "LONG_WORK_STEPS", "STEP_SECONDS"]

#: most output times a scenario may ask for: the Dataset holds about 360 bytes per output
#: time and the run needs working copies of it (2e6 outputs: 0.7 GB; a day every 0.05 s)
MAX_OUTPUTS = 2_000_000
#: most integration steps a scenario may need by the lower estimate of :func:`check_work`
#: (the default ``max_steps`` of :func:`orbatt.propagate`: a run needing more would stop
#: there after many minutes)
MAX_WORK_STEPS = DEFAULT_MAX_STEPS
#: most work (steps) a run may need without consent (``orbatt run --yes``,
#: ``load_scenario(..., yes=True)`` or ``[integration] max_steps``): at :data:`STEP_SECONDS` a
#: step, ten seconds at the least; a PD law with wheels at 4 us a step, 40 s
LONG_WORK_STEPS = 10_000_000
#: the least time (s) a compiled step takes, for the estimate's time in words (a torque-free
#: DOP853 step: ~0.5 us; the disturbed CubeSat or a PD law with wheels: 2-4 us)
STEP_SECONDS = 1e-6
#: most angle (rad) one step of any method covers, for :func:`check_work`'s lower estimate
#: (DOP853 at rtol 1e-3 takes about 1 rad per step of a rotation; at 1e-12, 0.1 rad)
MAX_ANGLE_PER_STEP = math.pi
#: smallest moment of inertia (kg m^2) blamed before the torque acting on it when the two make
#: a run too stiff: a body lighter than a 1 g, 3 cm chip
TINY_INERTIA = 1e-7


def build_kepler_orbit(ctx, o):
    """The :class:`~orbatt.orbits.KeplerOrbit` of a validated ``[orbit]`` table ``o``
    (internal units: km, rad; ``gm`` in km^3 s^-2; plain numbers in normalized units). For ``provider = "rebound"`` it is the
    initial osculating orbit (and gives the period for ``"N orbits"``)."""

    plain = o.get("dimensionless", False)  # normalized units: a and gm as plain numbers
    lu, gu = (1.0, 1.0) if plain else (U.LENGTH, U.GM)
    # angles as plain floats: KeplerOrbit takes a plain number as rad (the same value as a
    # Quantity in rad, without making and stripping four Quantities)
    kw = {o["anomaly_kind"]: float(o["anomaly"])}
    if o["central_body"] is None:
        kw["gm"] = o["gm"] * gu if plain else u.Quantity(o["gm"], gu)  # what o["gm"] * gu makes, faster
    else:
        kw["central_body"] = o["central_body"]
    if o["epoch"] is not None:
        kw["epoch"] = o["epoch"]
    try:  # a periapsis inside the central body warns (PeriapsisWarning), as the paper's Sect. 6.2 orbit does
        a = o["a"] * lu if plain else u.Quantity(o["a"], lu)
        return KeplerOrbit(a, o["e"], float(o["i"]), float(o["raan"]), float(o["argp"]), **kw)
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def build_rebound_orbit(ctx, o, kepler, t_end):
    """The :class:`~orbatt.orbits.ReboundOrbit` from ``kepler`` (its initial osculating
    orbit) over ``[0, t_end]`` (s), with the table's perturbations and integrator."""

    try:
        return ReboundOrbit(kepler, t_end if kepler.dimensionless else t_end * U.TIME,
                            perturbations=o["perturbations"], integrator=o["integrator"])
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def tle_period(o):
    """Orbital period (s) of the TLE of a validated ``[orbit]`` table (from its mean motion;
    converts ``"N orbits"`` before the orbit is sampled)."""
    from sgp4.api import Satrec

    sat = Satrec.twoline2rv(o["tle"][-2], o["tle"][-1])
    return 2.0 * math.pi / (sat.no_kozai / 60.0)


def build_tle_orbit(ctx, o, t_end, margin=0.0):
    """The :class:`~orbatt.orbits.TleOrbit` of a validated ``[orbit]`` table over
    ``[-margin, t_end + margin]`` (s): ``margin`` is :func:`environment_margin`'s, the span
    the environment tables sample beyond the run. An SGP4 failure along the span (a decayed
    orbit) names ``tle``."""
    try:
        return TleOrbit(o["tle"], (t_end + margin) * U.TIME, epoch=o["epoch"], t_start=-margin * U.TIME)
    except InputError as exc:
        raise ctx.error("[orbit]", str(exc)) from None


def environment_margin(spec):
    """How far (s) before ``t = 0`` and after ``t_end`` the environment tables of ``spec``'s
    ``[torques]`` and ``[control]`` sample the orbit (:func:`orbatt.torques.sample_margin`;
    0 without them): a TLE orbit is sampled over that margin too."""
    tq, c = spec.torques, spec.control
    if tq is None and (c is None or c["control"] is None):
        return 0.0
    law = (None if c is None else c["control"]) or {}
    return sample_margin(drag=tq is not None and tq["drag"], srp=tq is not None and tq["srp"],
                         magnetic=(tq is not None and tq["residual_dipole"] is not None)
                         or (c is not None and c["magnetic_field"] is not None),
                         sun=law.get("target") == "sun" or _reads_sun(c))


def _reads_sun(c):
    """Whether the star tracker of ``[sensors]`` reads the Sun (its exclusion angle)."""
    st = ((c or {}).get("navigation") or {}).get("star_tracker")
    return st is not None and st["sun_exclusion"] is not None


def check_field_span(ctx, spec, t_end):
    """Refuse, naming ``[integration] t_end``, a run whose IGRF field (``magnetic_field =
    "igrf"`` of ``[torques]`` or of a B-dot ``[control]``) would be sampled past IGRF-14's span
    (:data:`orbatt.environment.magnetic.IGRF_SPAN`): the epoch is checked when the file is read,
    the end of the run (with the tables' margin, :func:`environment_margin`) here, before
    anything is sampled."""
    fields = [] if spec.torques is None else [spec.torques["environment"]["magnetic_field"]]
    fields += [] if spec.control is None else [spec.control["magnetic_field"]]
    epoch = None if spec.orbit is None else spec.orbit.get("epoch")
    if "igrf" not in fields or epoch is None:
        return
    from astropy.time import TimeDelta

    from ..environment.magnetic import check_igrf_instants

    margin = environment_margin(spec)
    try:
        with warnings.catch_warnings():  # ERFA's "dubious year" past the leap-second table
            warnings.simplefilter("ignore")
            check_igrf_instants(epoch + TimeDelta([-margin, t_end + margin], format="sec"), "[integration] t_end")
    except InputError as exc:
        raise ctx.error("[integration] t_end", f"{t_end:.6g} s from the epoch: the IGRF field would be sampled "
                                               f"over {str(exc).split(': ', 1)[-1]}; shorten the run") from None


def build_output_times(ctx, integration, period):
    """``(times, t_end)``: the output times ``k * output_step``, ``k = 0 .. floor(t_end /
    output_step)`` (s, or dimensionless); ``period`` (s) converts ``"N orbits"``."""
    t_end = _duration(integration["t_end"], period)
    step_out = _duration(integration["output_step"], period)
    if step_out > t_end:
        raise ctx.error("[integration] output_step", f"{step_out:g} is longer than t_end = {t_end:g}")
    count = t_end / step_out
    if count + 1 > MAX_OUTPUTS:
        raise ctx.error("[integration] output_step", f"{step_out:g} over t_end = {t_end:g} gives {count:.3g} output "
                                                     f"times, more than {MAX_OUTPUTS:.0e} (about "
                                                     f"{count * 360 / 1e9:.3g} GB); give a longer output_step")
    n = int(math.floor(count * (1 + 1e-12)))
    return np.arange(n + 1, dtype=np.float64) * step_out, t_end


def _duration(t, period):
    kind, value = t
    return value * period if kind == "orbits" else value


def build_environment_torques(spec, orbit, t_end):
    """The :class:`~orbatt.torques.EnvironmentTorques` of ``spec.torques`` along ``orbit``,
    sampled over ``[0, t_end]`` (s)."""
    tq = spec.torques
    env = tq["environment"]
    atmosphere = field = None
    if tq["drag"]:
        if env["atmosphere"] == "nrlmsis":
            atmosphere = NRLMSIS(env["f107"], env["f107a"], env["ap"])
        elif "density0" in env:
            atmosphere = ExponentialAtmosphere(env["density0"] * u.kg / u.m**3, env["altitude0"] * u.km,
                                               env["scale_height"] * u.km)
        else:
            atmosphere = PiecewiseExponentialAtmosphere()
    if tq["residual_dipole"] is not None:
        field = IGRFField() if env["magnetic_field"] == "igrf" else DipoleField(orbit.epoch)
    law = None if spec.control is None else spec.control["control"]
    control = None if law is None else attach_navigation(control_law(law), spec.control.get("navigation"))
    if field is None and spec.control is not None and spec.control["magnetic_field"] is not None:
        field = IGRFField() if spec.control["magnetic_field"] == "igrf" else DipoleField(orbit.epoch)
    gg = spec.potential_kind == "gravity-gradient"
    return EnvironmentTorques(orbit if gg else None, t_end * u.s if gg else None,
                              facets=[facet(f) for f in tq["facets"]], gravity_gradient=gg, atmosphere=atmosphere,
                              magnetic_field=field, shadow=env["shadow"], corotation=env["corotation"], control=control,
                              **torque_arguments(tq))


def build_control(spec, orbit, t_end):
    """The gravity gradient along ``orbit`` with the control law of ``spec.control`` (an
    :class:`~orbatt.torques.EnvironmentTorques` without environment terms), up to ``t_end``
    (s)."""
    c = spec.control
    field = None
    if c["magnetic_field"] is not None:
        field = IGRFField() if c["magnetic_field"] == "igrf" else DipoleField(orbit.epoch)
    return EnvironmentTorques(orbit, t_end * u.s, gravity_gradient=True, magnetic_field=field,
                              control=attach_navigation(control_law(c["control"]), c.get("navigation")))


def build_potential(spec, orbit, t_end=None):
    """The potential of ``spec.potential_kind`` (a gravity gradient needs the ``orbit``; with
    ``[torques]`` or a ``[control]`` law, the environment torques sampled up to ``t_end``)."""
    if spec.torques is not None:
        return build_environment_torques(spec, orbit, t_end)
    if spec.control is not None and spec.control["control"] is not None:
        return build_control(spec, orbit, t_end)

    if spec.potential_kind == "torque-free":
        return TorqueFree()
    if spec.potential_kind == "heavy-top":
        h = spec.heavy_top
        if spec.dimensionless:
            return HeavyTop(h["mass_g"], h["center_of_mass"], sign=h["sign"])
        return HeavyTop(h["mass_g"] * U.MASS * U.LENGTH / U.TIME**2, h["center_of_mass"] * U.LENGTH,
                        sign=h["sign"])
    return GravityGradient(orbit)


def build_initial_state(ctx, spec, body, orbit):
    """The initial :class:`~orbatt.state.State` of ``[initial]``, in inertial components
    (converted from the orbital frame when ``frame = "orbital"``)."""

    ini = spec.initial
    try:
        if "euler_momenta" in ini:
            if spec.frame == "orbital":
                raise ctx.error("[initial] frame", "euler_momenta are inertial; use omega with frame = 'orbital'")
            return State.from_euler(body, ini["euler_313"], ini["euler_momenta"])
        q = ini["q"] if "q" in ini else qt.from_euler313(*ini["euler_313"])
        if spec.frame == "orbital":

            if "Q" in ini:
                raise ctx.error("[initial] Q", "Q is inertial; with frame = 'orbital' give omega (relative rates)")
            return state_from_orbital(body, orbit, q, ini["omega"] if body.dimensionless else ini["omega"] * U.RATE)
        if "Q" in ini:
            return State(body, q, ini["Q"])
        w = ini["omega"] if body.dimensionless else ini["omega"] * U.RATE
        return State.from_omega(body, q, w)
    except ScenarioError:
        raise
    except InputError as exc:
        raise ctx.error("[initial]", str(exc)) from None


def _work(t_end, period, state0, spec, step, outputs):
    """``[(steps, key, what)]``: every term of :func:`check_work`'s estimate (the key that sets
    it, a phrase saying what it is), and the rates of :func:`~orbatt.scenario.work.torque_rates`
    (for the time scale in the message)."""
    if step is not None:
        terms = [(t_end / step, "[integration] step", f"a fixed step of {step:.6g}")]
    else:
        terms = []
        if state0 is not None:
            spin = float(np.linalg.norm(state0.omega)) * t_end
            terms.append((spin / MAX_ANGLE_PER_STEP, "[initial]", f"the body turns {spin:.3g} rad"))
        if period:
            gm_given = spec is not None and spec.orbit is not None and spec.orbit.get("central_body") is None \
                and spec.orbit.get("gm") is not None and spec.orbit["provider"] != "tle"
            terms.append((4.0 * math.pi * t_end / period / MAX_ANGLE_PER_STEP, "[orbit] gm" if gm_given else "[orbit] a",
                          f"the orbit (period {period:.3g}) goes round {t_end / period:.3g} times"))
    rates = [] if spec is None else torque_rates(spec)
    if step is None:
        terms += [(r * t_end / MAX_ANGLE_PER_STEP, key, what) for r, key, what in rates]
    terms += counted_work(spec, t_end, outputs)
    return terms, rates


def estimate_steps(t_end, period, state0=None, spec=None, step=None, outputs=0):
    """:func:`check_work`'s lower estimate of the work of one run, in integration steps (a
    float)."""
    return sum(w for w, _, _ in _work(t_end, period, state0, spec, step, outputs)[0])


def _computing_time(steps):
    """A lower estimate of the time of ``steps`` (at :data:`STEP_SECONDS` each), in words."""
    s = steps * STEP_SECONDS
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.0f} min" if s < 7200 else f"{s / 3600:.1f} h"


def check_work(ctx, t_end, period, state0=None, spec=None, step=None, *, outputs=0, consent=True,
               max_steps=None):
    """Refuse a run that cannot end in reasonable time, or a long one not agreed to, before it
    starts.

    A lower estimate of the steps any method needs: the body turns by ``|omega0| t_end``
    (``omega0`` the initial body rate of ``state0``, if given) and the gravity-gradient
    potential, which depends on twice the orbital angle, by ``2 (2 pi) t_end / period``; the
    torques, control laws and wheels of ``spec`` (if given) turn it at their own rates
    (:func:`orbatt.scenario.work.torque_rates`: ``sqrt(tau / I)``, ``sqrt(kp / I)``, ``kd /
    I``, ``h / I``, ``sqrt(max_torque / I)``, ...); no method covers more than
    :data:`MAX_ANGLE_PER_STEP` per step. A fixed ``step`` (s) needs ``t_end / step`` steps.
    Counted beside them (:func:`orbatt.scenario.work.counted_work`): the control period's ticks,
    the environment tables' pieces and samples, and the ``outputs`` output times.

    Above ``max_steps`` (default :data:`MAX_WORK_STEPS`: the run would stop there) it is
    refused; above :data:`LONG_WORK_STEPS` (a minute or more) too unless ``consent`` (``orbatt
    run --yes``, ``load_scenario(..., yes=True)`` or ``[integration] max_steps`` in the file).
    The error names the key whose term dominates (``[initial]`` rates, ``[orbit] a`` or ``gm``,
    the torque's, the law's or the wheel's key, ``[control] period``, ``[integration] step``,
    ``t_end`` or ``output_step``), the estimated steps and time.
    """
    hard = MAX_WORK_STEPS if max_steps is None else max_steps
    limit = hard if consent else min(hard, LONG_WORK_STEPS)
    if step is not None and not t_end / step <= hard:
        raise ctx.error("[integration] step", f"{step:.6g} over t_end = {t_end:.6g} is {t_end / step:.3g} steps, more "
                                              f"than {hard:.0e} (hours of computing); give a longer step or "
                                              "shorten t_end")
    if state0 is not None and step is None and _spin_bound(state0) * t_end / MAX_ANGLE_PER_STEP \
            + estimate_steps(t_end, period, None, spec, None, outputs) <= limit * (1.0 - 1e-9):
        return  # far enough below the limit by an upper bound of the spin (no need of omega)
    terms, rates = _work(t_end, period, state0, spec, step, outputs)
    steps = sum(w for w, _, _ in terms)
    if steps <= limit:
        return
    work, key, what = max(terms, key=lambda term: term[0] if math.isfinite(term[0]) else math.inf)
    rate = next((r for r, k, _ in rates if k == key), None)
    if rate is not None:  # a time scale of a torque, a law or a wheel
        tiny = float(np.min(spec.inertia)) * 1e6 < TINY_INERTIA
        what = (f"{what} ({key})" if tiny else what) + f" sets a time scale of {1.0 / rate:.3g} s"
        key = "[body] inertia" if tiny else key
        fix = "give a physical value (or raise [body] inertia, shorten [integration] t_end)"
    else:
        fix = {"[initial]": "lower the rates (omega, Q) or shorten [integration] t_end",
               "[orbit] a": "raise a or shorten [integration] t_end",
               "[orbit] gm": "give a physical gm or shorten [integration] t_end",
               "[control] period": "give a longer period or shorten [integration] t_end",
               "[integration] output_step": "give a longer output_step or shorten t_end",
               "[integration] step": "give a longer step or shorten t_end"}.get(key, "shorten [integration] t_end")
    over = f"{what} over t_end = {t_end:.6g}: at least {steps:.3g} integration steps"
    if steps > hard or not math.isfinite(steps):
        where = "[integration] max_steps = " if max_steps is not None else ""
        raise ctx.error(key, f"{over}, more than {where}{hard:.0e} (hours of computing, a stiff problem or a "
                             f"meaningless magnitude); {fix}")
    raise ctx.error(key, f"{over}, more than {LONG_WORK_STEPS:.0e}: about {_computing_time(steps)} or more of computing; "
                         f"{fix}, or agree to a long run (orbatt run --yes, load_scenario(..., yes=True) or "
                         "[integration] max_steps)")


def _spin_bound(state0):
    """An upper bound of ``|omega|`` of ``state0`` (0 for None) from plain floats, for
    :func:`check_work`: ``|omega| <= |g| / min(I) <= |Q| / (2 min(I))`` for a unit ``q``
    (rounding covered by a factor ``1 + 1e-6``); ``inf`` where it does not apply (a batch, a
    body with wheels), which sends :func:`check_work` to the exact rate."""
    if state0 is None:
        return 0.0
    if state0.body.wheels or state0.Q.shape != (4,):
        return math.inf
    Q = state0.Q.tolist()
    return math.sqrt(sum(x * x for x in Q)) / (2.0 * min(state0.body.inertia_value.tolist())) * (1.0 + 1e-6)


def run_to_content(where, method, run, content):
    """``content(run())`` for a scenario's :meth:`run_content`: an
    :class:`~orbatt.errors.InputError` of the run (e.g. a fixed-step method without
    ``[integration] step``) becomes a :class:`~orbatt.errors.ScenarioError` naming ``where`` and
    the method; an :class:`~orbatt.errors.IntegrationError` keeps what was computed until then
    as its ``dataset`` (marked incomplete; None if nothing was) and is raised again."""
    try:
        traj = run()
    except InputError as exc:
        raise ScenarioError(f"{where}: [integration] (method {method!r}): {exc}") from None
    except IntegrationError as exc:
        partial = getattr(exc, "trajectory", None)
        exc.dataset = content(partial).to_dataset() if partial is not None and partial.t.size else None
        raise
    return content(traj)

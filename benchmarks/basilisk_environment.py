"""orbatt's environment torques against Basilisk 2.12 and against a classical model written here.

Run from a checkout: ``python benchmarks/basilisk_environment.py`` (about 20 s on 2 cores;
``--quick`` runs a fifth of an orbit). Basilisk (``pip install bsk``, the ``bench`` extra) is
optional: without it only orbatt and the classical model are compared.

The case: a 3U CubeSat (inertia diag(0.031, 0.030, 0.010) kg m^2; six facets of a
0.1 x 0.1 x 0.3 m box whose centre of mass is offset from the geometric centre, so that every
facet has a lever arm) tumbling slowly (|omega| ~ 4e-3 rad/s) on a 400 km dawn-dusk orbit
(a = 6778.137 km, e = 0.001, i = 97.03 deg, RAAN = 90 deg at the 2024-03-20 equinox: the Sun
is 83 deg off the orbit plane, so the orbit is in full sunlight throughout, which this script
checks with orbatt's conical shadow function), over one orbit (5553 s). Two runs:

a. drag + gravity gradient: exponential atmosphere rho = 3e-12 kg/m^3 exp(-(h - 400 km) / 60 km),
   h = |r| - 6378.137 km, no co-rotation (Basilisk's facet drag without a wind message uses the
   inertial velocity: orbatt's ``corotation=False``);
b. solar radiation pressure alone (docs/design.md §10's flat-plate law; the Sun from astropy).

Three models of each:

* orbatt: ``EnvironmentTorques`` as the potential of ``orbatt.propagate`` (dop853, rtol 1e-12);
* the classical model (:func:`classical_run`): Euler's equations ``I w' = tau - w x I w`` and the
  kinematics ``q' = q (0, w) / 2`` in numpy, Kepler's equation solved here, the torque formulas
  written again here, scipy ``solve_ivp`` (DOP853, rtol 1e-12): the tight reference;
* Basilisk: ``spacecraft.Spacecraft`` with the CubeSat's inertia and a 4e9 kg hub (so that drag
  cannot change the orbit, which orbatt prescribes), point-mass Earth with orbatt's GM,
  ``GravityGradientEffector``, ``facetDragDynamicEffector`` fed by ``exponentialAtmosphere``,
  ``facetSRPDynamicEffector`` fed by a Sun message written from astropy's Sun before every task
  step (at the step's midpoint), RKF78 at a fixed task step.

Basilisk's facet SRP force is docs/design.md §10's formula (same ``(1 - C_s) s + 2 (C_s cos t + C_d / 3) n``;
``addFacet(area, dcm_F0B, nHat_F, rotHat_F, r_CopB_B, diffuseCoeff, specularCoeff)``, diffuse
first) but with a flux of 1368 W/m^2 where orbatt uses 1361 W/m^2: the script gives Basilisk the
areas scaled by 1361/1368 (force and torque are linear in the area) and checks the instantaneous
torques. Basilisk's drag and Sun are held constant over each task step (the atmosphere module
runs at the task rate; ``facetDragDynamicEffector`` reads the density once per step), which the
classical model can reproduce (``hold=dt``) to show where the difference comes from.
"""
from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

# astropy and scipy are imported where used: benchmarks/basilisk_day.py times a fresh process
# that imports this module to build Basilisk's simulation, and that process needs numpy only

EPOCH = "2024-03-20T00:00:00Z"
GM = 398600.4418e9                  # m^3/s^2 (orbatt's KeplerOrbit is given the same value)
R_EARTH = 6378137.0                 # m, the exponential atmosphere's sphere
A, ECC, INC, RAAN, ARGP, NU0 = 6778137.0, 0.001, math.radians(97.03), math.radians(90.0), math.radians(30.0), 0.0
INERTIA = np.array([0.031, 0.030, 0.010])       # kg m^2, principal = body axes
Q0 = np.array([0.8, 0.3, -0.4, 0.331662479035540])  # body -> inertial (Basilisk's beta_BN)
Q0 = Q0 / np.linalg.norm(Q0)
OMEGA0 = np.array([2.0e-3, -1.5e-3, 3.0e-3])    # rad/s, body axes
DENSITY0, ALTITUDE0, SCALE_HEIGHT = 3e-12, 400e3, 60e3   # kg/m^3, m, m
FLUX, C_LIGHT, AU = 1361.0, 299792458.0, 149597870700.0  # W/m^2, m/s, m (orbatt's values)
BASILISK_FLUX = 1368.0              # W/m^2, hard-coded in Basilisk's facetSRPDynamicEffector
COM = np.array([0.004, -0.003, 0.012])          # m, centre of mass from the geometric centre
#: six facets: (area m^2, outward normal, face centre from the geometric centre m, C_D, C_s, C_d)
FACETS = [
    (0.03, (1, 0, 0), (0.05, 0, 0), 2.2, 0.10, 0.30), (0.03, (-1, 0, 0), (-0.05, 0, 0), 2.1, 0.20, 0.20),
    (0.03, (0, 1, 0), (0, 0.05, 0), 2.3, 0.05, 0.40), (0.03, (0, -1, 0), (0, -0.05, 0), 2.2, 0.10, 0.10),
    (0.01, (0, 0, 1), (0, 0, 0.15), 2.0, 0.30, 0.30), (0.01, (0, 0, -1), (0, 0, -0.15), 2.4, 0.00, 0.50),
]
N = np.array([f[1] for f in FACETS], dtype=float)
P = np.array([f[2] for f in FACETS], dtype=float) - COM   # centre of pressure from the centre of mass
AREA = np.array([f[0] for f in FACETS])
CD = np.array([f[3] for f in FACETS])
CS = np.array([f[4] for f in FACETS])
CDIFF = np.array([f[5] for f in FACETS])
PERIOD = 2 * math.pi * math.sqrt(A**3 / GM)


# --- the classical model (SI units; nothing from orbatt)
def kepler(t):
    """Position and velocity (m, m/s, inertial), each ``(len(t), 3)``, on the Keplerian orbit at
    the times ``t`` (s)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    out = np.array([_kepler(float(x)) for x in t])
    return out[:, 0], out[:, 1]


_ORBIT_N = math.sqrt(GM / A**3)
_E0 = 2 * math.atan(math.sqrt((1 - ECC) / (1 + ECC)) * math.tan(NU0 / 2))
_CO, _SO, _CI, _SI, _CW, _SW = (math.cos(RAAN), math.sin(RAAN), math.cos(INC), math.sin(INC), math.cos(ARGP),
                                math.sin(ARGP))
_PX = np.array([_CO * _CW - _SO * _SW * _CI, _SO * _CW + _CO * _SW * _CI, _SW * _SI])   # perifocal axes
_QX = np.array([-_CO * _SW - _SO * _CW * _CI, -_SO * _SW + _CO * _CW * _CI, _CW * _SI])


def _kepler(t):
    M = _E0 - ECC * math.sin(_E0) + _ORBIT_N * t
    E = M
    for _ in range(50):
        dE = (E - ECC * math.sin(E) - M) / (1 - ECC * math.cos(E))
        E -= dE
        if abs(dE) < 1e-15:
            break
    b = A * math.sqrt(1 - ECC**2)
    edot = _ORBIT_N / (1 - ECC * math.cos(E))
    return ((A * (math.cos(E) - ECC)) * _PX + (b * math.sin(E)) * _QX,
            (-A * math.sin(E) * edot) * _PX + (b * math.cos(E) * edot) * _QX)


def dcm(q):
    """The rotation matrix of the unit quaternion ``q`` (scalar first): inertial = R @ body."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def density(r):
    return DENSITY0 * math.exp(-(np.linalg.norm(r) - R_EARTH - ALTITUDE0) / SCALE_HEIGHT)


def torque_gravity_gradient(R, r):
    rb = R.T @ r
    return 3 * GM / np.linalg.norm(r) ** 5 * np.cross(rb, INERTIA * rb)


def torque_drag(R, v, rho):
    """Flat-plate drag: F = -1/2 rho C_D A max(0, n.v^) |v|^2 v^ per facet, tau = sum p x F."""
    vb = R.T @ v
    speed = np.linalg.norm(vb)
    vhat = vb / speed
    cos = np.maximum(N @ vhat, 0.0)
    F = -0.5 * rho * speed**2 * (CD * AREA * cos)[:, None] * vhat
    return np.cross(P, F).sum(axis=0)


def torque_srp(R, r, sun):
    """Flat-plate SRP (docs/design.md §10), full sunlight: F = -P A cos t [(1 - C_s) s +
    2 (C_s cos t + C_d/3) n] for cos t = n.s > 0."""
    d = sun - r
    dist = np.linalg.norm(d)
    s = R.T @ d / dist
    pressure = FLUX / C_LIGHT * (AU / dist) ** 2
    cos = N @ s
    lit = cos > 0
    c = cos[lit]
    F = -pressure * (AREA[lit] * c)[:, None] * ((1 - CS[lit])[:, None] * s + (2 * (CS[lit] * c + CDIFF[lit] / 3))[:, None] * N[lit])
    return np.cross(P[lit], F).sum(axis=0)


def reference_torques(t, q, sun):
    """Each term's torque (N m, body axes) of the classical formulas at ``t`` (s) and ``q``."""
    R = dcm(q)
    r, v = _kepler(t)
    return {"gravity_gradient": torque_gravity_gradient(R, r), "drag": torque_drag(R, v, density(r)),
            "srp": torque_srp(R, r, sun(t))}


def sun_spline(t_end):
    """Geocentric GCRS Sun (m) from astropy's built-in ephemeris, splined over [-600, t_end + 600] s."""
    from astropy import units as u
    from astropy.coordinates import GCRS, get_body, solar_system_ephemeris
    from astropy.time import Time
    from scipy.interpolate import CubicSpline

    ts = np.arange(-600.0, t_end + 1200.0, 600.0)
    times = Time(EPOCH) + ts * u.s
    with solar_system_ephemeris.set("builtin"):
        sun = get_body("sun", times).transform_to(GCRS(obstime=times))
    return CubicSpline(ts, sun.cartesian.xyz.to_value(u.m).T)


def classical_run(t_out, terms, sun=None, hold=None, rtol=1e-12):
    """Quaternions ``(len(t_out), 4)`` of the classical model with the ``terms`` (a subset of
    ``{"gravity_gradient", "drag", "srp"}``). ``hold``: hold the density and the Sun constant over
    steps of ``hold`` s (density at the step's start, the Sun at its midpoint), as Basilisk does."""
    from scipy.integrate import solve_ivp

    t_out = np.asarray(t_out, dtype=float)

    def rhs(t, y, rho_held=None, sun_held=None):
        q, w = y[:4], y[4:]
        R = dcm(q)
        r, v = _kepler(t)
        tau = np.zeros(3)
        if "gravity_gradient" in terms:
            tau += torque_gravity_gradient(R, r)
        if "drag" in terms:
            tau += torque_drag(R, v, density(r) if rho_held is None else rho_held)
        if "srp" in terms:
            tau += torque_srp(R, r, sun(t) if sun_held is None else sun_held)
        qdot = 0.5 * np.array([-q[1:] @ w, q[0] * w[0] + q[2] * w[2] - q[3] * w[1],
                               q[0] * w[1] + q[3] * w[0] - q[1] * w[2], q[0] * w[2] + q[1] * w[1] - q[2] * w[0]])
        return np.r_[qdot, (tau - np.cross(w, INERTIA * w)) / INERTIA]

    y0 = np.r_[Q0, OMEGA0]
    atol = np.r_[np.full(4, 1e-14), np.full(3, 1e-17)]
    if hold is None:
        sol = solve_ivp(rhs, (t_out[0], t_out[-1]), y0, method="DOP853", t_eval=t_out, rtol=rtol, atol=atol)
        return sol.y[:4].T
    k_out = np.rint(t_out / hold).astype(int)
    if t_out[0] != 0.0 or not np.allclose(k_out * hold, t_out, rtol=0, atol=1e-9):
        raise ValueError("classical_run: with hold, the output times must be multiples of hold from 0")
    ys, y = [y0], y0
    for k in range(k_out[-1]):
        a, b = k * hold, (k + 1) * hold
        args = (density(_kepler(a)[0]), None if sun is None else sun(0.5 * (a + b)))
        y = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol, atol=atol, args=args).y[:, -1]
        ys.append(y)
    return np.array(ys)[k_out, :4]


# --- orbatt
def orbatt_case(t_end, terms):
    """``(body, state0, potential)`` of the case in orbatt with the ``terms``."""
    from astropy import units as u

    import orbatt
    from orbatt.environment import ExponentialAtmosphere
    from orbatt.torques import EnvironmentTorques, Facet

    orbit = orbatt.KeplerOrbit(a=A * u.m, e=ECC, i=INC * u.rad, raan=RAAN * u.rad, argp=ARGP * u.rad,
                               true_anomaly=NU0 * u.rad, gm=GM * u.m**3 / u.s**2, epoch=EPOCH)
    body = orbatt.RigidBody(INERTIA * u.kg * u.m**2)
    facets = [Facet(AREA[k] * u.m**2, N[k], P[k] * u.m, CD[k], CS[k], CDIFF[k], name=f"facet{k}") for k in range(6)]
    atmosphere = ExponentialAtmosphere(DENSITY0 * u.kg / u.m**3, ALTITUDE0 * u.m, SCALE_HEIGHT * u.m,
                                       body_radius=R_EARTH * u.m)
    env = EnvironmentTorques(orbit, t_end * u.s, facets=facets, gravity_gradient="gravity_gradient" in terms,
                             drag="drag" in terms, srp="srp" in terms, atmosphere=atmosphere, corotation=False,
                             shadow="none")
    return body, orbatt.State.from_omega(body, Q0, OMEGA0 * u.rad / u.s), env


def orbatt_run(t_out, terms, rtol=1e-12):
    """``(q (N, 4), Dataset)`` of orbatt's run at the times ``t_out`` (s)."""
    import orbatt

    body, state0, env = orbatt_case(float(t_out[-1]), terms)
    traj = orbatt.propagate(body, state0, env, np.asarray(t_out, dtype=float), rtol=rtol, atol=rtol * 1e-2)
    return np.asarray(traj.q), orbatt.to_dataset(traj)


# --- Basilisk
def basilisk_sim(terms, dt, state=None, sun=None, tol=None, method="rkf78", record_dt=None):
    """A Basilisk simulation of the case with the ``terms``, task step ``dt`` (s), RKF78
    (``method="rk4"``: Basilisk's RK4, one step per task step). ``state``: ``(t, q, omega)`` to
    start from instead of the initial state (r, v from Kepler at t); ``sun``: a callable of the
    time (s) giving the Sun's position (m). ``record_dt``: the state recorder's sampling interval
    (s; default every task step). Returns ``(sim, spacecraft, effectors dict, sun message,
    recorder)``."""
    from Basilisk.architecture import messaging
    from Basilisk.simulation import (GravityGradientEffector, exponentialAtmosphere, facetDragDynamicEffector,
                                     facetSRPDynamicEffector, spacecraft, svIntegrators)
    from Basilisk.utilities import RigidBodyKinematics, SimulationBaseClass, simIncludeGravBody

    t0, q0, w0 = (0.0, Q0, OMEGA0) if state is None else state
    sim = SimulationBaseClass.SimBaseClass()
    sim.CreateNewProcess("dyn").addTask(sim.CreateNewTask("task", round(dt * 1e9)))
    sc = spacecraft.Spacecraft()
    sc.hub.mHub = 4e9      # drag must not move the orbit (orbatt's is prescribed); the inertia is the CubeSat's
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = np.diag(INERTIA).tolist()
    grav = simIncludeGravBody.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = GM
    grav.addBodiesTo(sc)
    r0, v0 = kepler(t0)
    sc.hub.r_CN_NInit = r0.reshape(3, 1).tolist()
    sc.hub.v_CN_NInit = v0.reshape(3, 1).tolist()
    sc.hub.sigma_BNInit = np.reshape(RigidBodyKinematics.EP2MRP(q0), (3, 1)).tolist()
    sc.hub.omega_BN_BInit = np.reshape(w0, (3, 1)).tolist()
    integrator = (svIntegrators.svIntegratorRK4 if method == "rk4" else svIntegrators.svIntegratorRKF78)(sc)
    if tol is not None:   # adaptive within each task step; default (relTol 1e-4): one step per task step
        integrator.relTol, integrator.absTol = tol, tol * 1e-3
    sc.setIntegrator(integrator)
    eff, sun_msg, models = {}, None, []
    if "gravity_gradient" in terms:
        eff["gravity_gradient"] = gg = GravityGradientEffector.GravityGradientEffector()
        gg.addPlanetName(earth.planetName)
        models.append((gg, 100))
    if "drag" in terms:
        atmo = exponentialAtmosphere.ExponentialAtmosphere()
        atmo.baseDensity = DENSITY0 * math.exp(ALTITUDE0 / SCALE_HEIGHT)   # rho at |r| = R
        atmo.scaleHeight = SCALE_HEIGHT
        atmo.planetRadius = R_EARTH
        atmo.addSpacecraftToModel(sc.scStateOutMsg)
        eff["drag"] = drag = facetDragDynamicEffector.FacetDragDynamicEffector()
        for k in range(6):
            drag.addFacet(AREA[k], CD[k], N[k].tolist(), P[k].tolist())
        drag.atmoDensInMsg.subscribeTo(atmo.envOutMsgs[0])
        models += [(atmo, 300), (drag, 200)]
        eff["atmosphere"] = atmo
    if "srp" in terms:
        eff["srp"] = srp = facetSRPDynamicEffector.FacetSRPDynamicEffector()
        srp.setNumFacets(6)
        for k in range(6):   # Basilisk's flux is 1368 W/m^2: scale the areas to orbatt's 1361 W/m^2
            srp.addFacet(AREA[k] * FLUX / BASILISK_FLUX, np.eye(3).tolist(), N[k].tolist(), [0.0, 0.0, 1.0],
                         P[k].tolist(), CDIFF[k], CS[k])
        sun_msg = messaging.SpicePlanetStateMsg()
        srp.sunInMsg.subscribeTo(sun_msg)
        models.append((srp, 100))
    for name in ("gravity_gradient", "drag", "srp"):
        if name in eff:
            sc.addDynamicEffector(eff[name])
    for model, priority in models:
        sim.AddModelToTask("task", model, priority)
    sim.AddModelToTask("task", sc, 50)
    rec = sc.scStateOutMsg.recorder() if record_dt is None else sc.scStateOutMsg.recorder(round(record_dt * 1e9))
    sim.AddModelToTask("task", rec, 10)
    if sun_msg is not None:
        write_sun(sun_msg, sun(t0))
    return sim, sc, eff, sun_msg, rec


def write_sun(msg, position):
    from Basilisk.architecture import messaging

    payload = messaging.SpicePlanetStateMsgPayload()
    payload.PositionVector = [float(x) for x in position]
    payload.PlanetName = "sun"
    msg.write(payload)


def basilisk_run(t_out, terms, dt, sun=None, tol=None, method="rkf78", sun_every=None, timings=None):
    """Quaternions ``(N, 4)`` of Basilisk at ``t_out`` (multiples of ``dt``), and the time spent in
    ``ExecuteSimulation`` (s). With SRP the Sun message is rewritten with ``sun`` at the midpoint
    of every ``sun_every`` s (a multiple of ``dt``; default ``dt``: before every task step).
    ``method``: ``"rkf78"`` or ``"rk4"``. ``timings``: a dict that receives ``"setup"`` (s: the
    simulation built and initialized) and ``"execute"``; with ``t_out`` evenly spaced by a multiple
    of ``dt`` from 0 the state is recorded at ``t_out`` only."""
    from Basilisk.utilities import RigidBodyKinematics

    t_out = np.asarray(t_out, dtype=float)
    dt_ns = round(dt * 1e9)
    n = int(round(t_out[-1] / dt))
    spacing = np.diff(t_out)
    record_dt = (float(spacing[0]) if len(t_out) > 1 and t_out[0] == 0.0 and np.allclose(spacing, spacing[0])
                 and abs(spacing[0] / dt - round(spacing[0] / dt)) < 1e-9 else None)
    t0 = time.perf_counter()
    sim, sc, eff, sun_msg, rec = basilisk_sim(terms, dt, sun=sun, tol=tol, method=method, record_dt=record_dt)
    sim.InitializeSimulation()
    t1 = time.perf_counter()
    if sun_msg is None:
        sim.ConfigureStopTime(n * dt_ns)
        sim.ExecuteSimulation()
    else:
        every = max(1, int(round((dt if sun_every is None else sun_every) / dt)))
        sim.ConfigureStopTime(0)
        sim.ExecuteSimulation()
        for k in range(0, n, every):
            m = min(every, n - k)
            write_sun(sun_msg, sun((k + 0.5 * m) * dt))
            sim.ConfigureStopTime((k + m) * dt_ns)
            sim.ExecuteSimulation()
    t2 = time.perf_counter()
    if timings is not None:
        timings.update(setup=t1 - t0, execute=t2 - t1)
    times = rec.times() * 1e-9
    sigma = rec.sigma_BN
    idx = np.clip(np.searchsorted(times, t_out - 0.5 * dt), 0, len(times) - 1)
    q = np.array([RigidBodyKinematics.MRP2EP(sigma[i]) for i in idx])
    return q * np.sign(q[:, :1]), t2 - t1


def basilisk_torques(t, q, w, terms, sun=None):
    """Basilisk's torque of each term (N m, body axes) at the time ``t``, attitude ``q`` and rate
    ``w``: a simulation started there, run at t = 0 only (the atmosphere writes the density),
    then each effector's ``computeForceTorque``."""
    sim, sc, eff, sun_msg, rec = basilisk_sim(terms, 1.0, state=(t, q, w), sun=sun)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(0)
    sim.ExecuteSimulation()
    out = {}
    for name in terms:
        eff[name].computeForceTorque(0.0, 0.0)
        out[name] = np.asarray(eff[name].torqueExternalPntB_B, dtype=float).ravel()
    return out


# --- the comparison
def _angle(qa, qb):
    """Largest rotation angle (rad) between two quaternion series ``(N, 4)``: that of
    ``qa~ qb``, whose vector part is ``a0 b - b0 a - a x b``."""
    vec = qa[:, :1] * qb[:, 1:] - qb[:, :1] * qa[:, 1:] - np.cross(qa[:, 1:], qb[:, 1:])
    return float(np.max(2 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(np.sum(qa * qb, axis=-1)))))


def check_sunlight(t_out, sun):
    """The smallest of orbatt's conical shadow function along the orbit (1: full sunlight)."""
    from orbatt.environment.sun import shadow

    r, _ = kepler(t_out)
    return float(np.min(shadow(r / 1e3, sun(t_out) / 1e3, kind="conical")))


def _series(qa, qb):
    return np.array([_angle(qa[k:k + 1], qb[k:k + 1]) for k in range(len(qa))])


def first_switch(t, q, terms, sun):
    """The first time in ``t`` at which a facet's ``cos`` (against the flow for drag, the Sun for
    SRP) changed sign since the previous time: the torque's derivative jumps there."""
    signs = []
    for tk, qk in zip(t, q):
        r, v = _kepler(tk)
        d = v if "drag" in terms else sun(tk) - r
        signs.append(np.sign(N @ (dcm(qk).T @ d)))
    changed = np.any(np.diff(np.array(signs), axis=0) != 0, axis=1)
    return float(t[1:][changed][0]) if changed.any() else float("nan")


def trajectories(t_out, terms, sun, dts, basilisk):
    """Rows ``(model, reference, max angle rad, wall s)`` of one run, orbatt's quaternions and
    Dataset, and (with Basilisk and a non-conservative term) ``(t0, t1, angle)``: the time at which
    Basilisk at ``dts[0]`` leaves the classical model held per step (by 1e-12 rad), the first
    facet switch, and their largest difference before it."""
    rows, story = [], None
    w = time.perf_counter()
    qc = classical_run(t_out, terms, sun=sun)
    rows.append(("classical (solve_ivp DOP853 rtol 1e-12)", "-", 0.0, time.perf_counter() - w))
    w = time.perf_counter()
    qo, ds = orbatt_run(t_out, terms)
    rows.append(("orbatt dop853 rtol 1e-12", "classical", _angle(qo, qc), time.perf_counter() - w))
    if basilisk:
        for dt in dts:
            qb, wall = basilisk_run(t_out, terms, dt, sun=sun)
            rows.append((f"Basilisk RKF78 task step {dt:g} s", "classical", _angle(qb, qc), wall))
        rows.append((f"Basilisk RKF78 task step {dts[-1]:g} s", "orbatt", _angle(qb, qo), None))
    if basilisk and terms != ("gravity_gradient",):
        dt = dts[0]
        fine = np.arange(0.0, t_out[-1] + 0.5 * dt, dt)
        on_out = np.isin(fine, t_out)
        w = time.perf_counter()
        qh = classical_run(fine, terms, sun=sun, hold=dt)
        rows.append((f"classical, environment held per {dt:g} s step", "classical", _angle(qh[on_out], qc),
                     time.perf_counter() - w))
        qb, _ = basilisk_run(fine, terms, dt, sun=sun)
        rows.append((f"Basilisk RKF78 task step {dt:g} s", f"classical held per {dt:g} s", _angle(qb, qh), None))
        a = _series(qb, qh)
        k = int(np.argmax(a > 1e-12)) if np.any(a > 1e-12) else len(a)
        story = (float(fine[k]) if k < len(a) else float("nan"), first_switch(fine, qh, terms, sun),
                 float(a[:k].max()) if k else 0.0)
    return rows, qo, ds, story


def instants(t_out, qo, ds, terms, sun, basilisk, picks=4):
    """Rows ``(t, term, |tau| N m, orbatt rel. diff, Basilisk rel. diff)`` against the classical
    formulas at a few instants, all at orbatt's attitude and rate there."""
    rows = []
    for k in np.linspace(0, len(t_out) - 1, picks).astype(int):
        t, q = float(t_out[k]), qo[k]
        ref = reference_torques(t, q, sun)
        tb = basilisk_torques(t, q, ds.omega.values[k], terms, sun=sun) if basilisk else {}
        for name in terms:
            tc = ref[name]
            scale = np.linalg.norm(tc)
            do = np.linalg.norm(ds[f"torque_{name}"].values[k] - tc) / scale
            db = np.linalg.norm(tb[name] - tc) / scale if name in tb else float("nan")
            rows.append((t, name, scale, do, db))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a fifth of an orbit")
    args = ap.parse_args(argv)
    try:
        import Basilisk  # noqa: F401
        basilisk = True
    except ImportError:
        basilisk = False
        print("Basilisk is not installed (pip install bsk): its rows are skipped")
    t_end = 1200.0 if args.quick else math.ceil(PERIOD / 60.0) * 60.0
    t_out = np.arange(0.0, t_end + 1.0, 60.0)
    sun = sun_spline(t_end)
    print(f"3U CubeSat, 400 km dawn-dusk orbit from {EPOCH}, {t_end:.0f} s (period {PERIOD:.1f} s); "
          f"smallest conical shadow function along it: {check_sunlight(t_out, sun):.3f} (1 = full sunlight)")
    for terms in (("gravity_gradient",), ("gravity_gradient", "drag"), ("srp",)):
        dts = (10.0,) if terms == ("gravity_gradient",) else (10.0, 2.0)
        rows, qo, ds, story = trajectories(t_out, terms, sun, dts if basilisk else (), basilisk)
        print(f"\n### {' + '.join(terms)}: attitude over {t_end:.0f} s (largest angle at the 60 s outputs)\n")
        print("| model | against | max angle (rad) | wall (s) |\n|---|---|---|---|")
        for name, ref, ang, wall in rows:
            print(f"| {name} | {ref} | {ang:.2g} | {'' if wall is None else f'{wall:.2f}'} |")
        if story is not None:
            until = "over the whole run" if math.isnan(story[0]) else f"until t = {story[0]:.0f} s"
            switch = ("no facet switches (cos = 0) in the run" if math.isnan(story[1]) else
                      f"the first facet switch (cos = 0) is in the step ending at {story[1]:.0f} s")
            print(f"\nBasilisk at {dts[0]:g} s follows the held classical model to {story[2]:.1g} rad {until}; {switch}.")
        if terms == ("gravity_gradient",):
            continue
        print("\nInstantaneous torques against the classical formulas (at orbatt's attitude):\n")
        print("| t (s) | term | abs tau (N m) | orbatt rel. diff | Basilisk rel. diff |\n|---|---|---|---|---|")
        for t, name, scale, do, db in instants(t_out, qo, ds, terms, sun, basilisk):
            print(f"| {t:.0f} | {name} | {scale:.3g} | {do:.1g} | {db:.1g} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

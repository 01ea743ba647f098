"""Monte Carlo studies (issue 23, item 5): orbatt's sweeps against Basilisk's one process per
case, and the environment-torque ensemble against the gravity-gradient-only one.

    python benchmarks/montecarlo.py            # about 3-4 minutes on 2 cores
    python benchmarks/montecarlo.py --quick    # smaller N, fewer repeats (about 1 minute)

Prints two tables of ratios against baselines measured in the same run (no number here is
quoted from elsewhere). Results: ``benchmarks/README.md``, section "Monte Carlo".

**A. The B-dot Monte Carlo** (``scenarios/cubesat-detumble-montecarlo.toml``: 1,000 tip-off
cases, each rate uniform in +-8 deg/s, inertia dispersed by 2 %, two orbits) with
``[environment] magnetic_field = "dipole"`` (IGRF-14's degree-1 terms at the epoch, fixed in
the Earth: Basilisk has no IGRF offline, and its ``magneticFieldCenteredDipole`` is this
field). Rows:

* orbatt in-process: ``orbatt.sweep.load_sweep(path).compute()`` (one ensemble call, numba on
  every core; the scenario loaded, the kernels compiled and cached before the timing);
* orbatt as a whole process: ``orbatt sweep FILE --workers 2 -o OUT.nc`` (interpreter start,
  imports, the Dask local cluster and its workers' start, the sweep, the netCDF file);
* Basilisk 2.12 with its own Monte Carlo framework, ``Basilisk.utilities.MonteCarlo.Controller``
  (``setThreadCount(cores)``: a fresh ``multiprocessing.Pool`` of ``cores`` processes per batch
  of ``cores`` runs, each process building, initializing and executing one simulation; a
  ``RetentionPolicy`` keeping ``omega_BN_B`` of every task step, archived as the framework does),
  run on a few copies of one case (no dispersions: the same work as a dispersed case) and
  scaled, ``time per case x N / cores``. Also printed: a case in a fresh interpreter
  (``python montecarlo.py --basilisk-case JSON``, imports included) and ``ExecuteSimulation``
  alone, one process at a time.

The Basilisk case: ``spacecraft.Spacecraft`` with the case's inertia (centre of mass at B),
point-mass Earth with orbatt's GM, the orbit from the same elements (``elem2rv``), identity
attitude and the case's body rates; ``GravityGradientEffector`` (orbatt's scenario has the
gravity gradient); ``magneticFieldCenteredDipole`` with orbatt's ``(g10, g11, h11)`` at the
epoch and radius 6371.2 km, its planet orientation (``J20002Pfix``) written every task step as
orbatt's GCRS -> ITRS rotation at the epoch turned by the Earth's rotation rate (the field
agrees with orbatt's ``DipoleField`` to 3e-6 relative along the run); ``MtbEffector`` with three
orthogonal torquers limited to 0.2 A m2; Basilisk has no B-dot module, so the law is a Python
``sysModel.SysModel`` (the usual way to add one): ``m = -k (C_BN dB_N/dt - omega x B_B)``, each
axis clipped, with ``dB_N/dt`` the backward difference of the field over the task step, held
over the step (Basilisk's flight software runs at the task rate); RK4 (Basilisk's default);
a recorder of the spacecraft state at every task step (what a retention policy keeps). The
detumble time is located on the recorded rates (the earliest time after which |omega| stays
below 0.5 deg/s, linear between task steps).

**B. The environment-torque ensemble** (``benchmarks/env_ensemble.py``, also run alone):
``scenarios/cubesat-3u-disturbances.toml`` (3U, six
facets, NRLMSIS drag with co-rotation, SRP with a conical shadow, a residual dipole in IGRF,
gravity gradient) over one orbit, as an ensemble of N members (random attitudes, rates 0.5
deg/s rms) through ``orbatt.propagate`` with a batch ``State``, against the same members under
the gravity gradient alone on the same orbit, at the scenario's tolerances (rtol 1e-10, atol
1e-12); ``dop853`` (members independent) and ``dop853-lanes``. Printed beside the
throughput: the error of the first members' final attitudes against a tight run of the same
model (rtol 3e-15), steps and right-hand sides per member, ns per right-hand side, and the time to
sample the environment along the orbit (building the tables, once per orbit, shared by the
members) with its largest items (cProfile).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))   # the sibling scripts, whoever loads this one
from env_ensemble import part_b, stats  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
BDOT_SCENARIO = ROOT / "scenarios" / "cubesat-detumble-montecarlo.toml"
EARTH_RATE = 7.292115146706979e-5      # rad/s, the Earth rotation angle's rate (IERS)
BSK_DT = 1.0                           # s, Basilisk's task step for the timing
BSK_DT_FINE = (0.5, 0.1)               # s, the agreement check's finer steps

warnings.simplefilter("ignore")


# --------------------------------------------------------------------------------------------
# A. B-dot Monte Carlo
# --------------------------------------------------------------------------------------------

def bdot_dipole_text(samples):
    """The B-dot Monte Carlo scenario with the centred tilted dipole.

    Parameters
    ----------
    samples : int
        The number of cases (``[sweep] samples``).

    Returns
    -------
    str
        ``scenarios/cubesat-detumble-montecarlo.toml`` with ``magnetic_field = "dipole"``.
    """
    text = BDOT_SCENARIO.read_text()
    text = text.replace('magnetic_field = "igrf"', 'magnetic_field = "dipole"')
    text = re.sub(r"^samples = \d+$", f"samples = {samples}", text, flags=re.M)
    assert 'magnetic_field = "dipole"' in text and f"samples = {samples}" in text
    return text


def final_rate(ds, k):
    """Body rate of case ``k`` at the end: ``I omega = Im(q~ Q) / 2``.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result with ``final_state`` (``q_final``, ``Q_final``) and ``inertia``.
    k : int
        The case.

    Returns
    -------
    ndarray (3,)
        rad/s, body axes.
    """
    q, Q, inertia = ds["q_final"].values[k], ds["Q_final"].values[k], ds["inertia"].values[k]
    w0, wv = q[0], -q[1:]
    vec = w0 * Q[1:] + Q[0] * wv + np.cross(wv, Q[1:])
    return vec / 2.0 / inertia


def orbatt_inprocess(path):
    """Run a sweep in this process.

    Parameters
    ----------
    path : Path
        A scenario file with ``[sweep]``.

    Returns
    -------
    seconds : float
        Wall time of ``load_sweep(path).compute()``.
    ds : xarray.Dataset
        Its result.
    """
    from orbatt.sweep import load_sweep

    t0 = time.perf_counter()
    ds = load_sweep(path).compute()
    return time.perf_counter() - t0, ds


def orbatt_cli(path, workers, folder):
    """Run ``orbatt sweep path --workers N -o folder/cli.nc`` in a fresh process.

    Parameters
    ----------
    path : Path
        A scenario file with ``[sweep]``.
    workers : int
        The local Dask cluster's worker processes.
    folder : Path
        Where the result file goes (replaced).

    Returns
    -------
    float
        Wall time (s) of the whole process.
    """
    exe = shutil.which("orbatt", path=str(Path(sys.executable).parent)) or shutil.which("orbatt")
    out = Path(folder) / "cli.nc"
    if out.exists():
        out.unlink()
    t0 = time.perf_counter()
    run = subprocess.run([exe, "sweep", str(path), "--workers", str(workers), "-o", str(out), "--quiet"],
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if run.returncode:
        raise RuntimeError(f"orbatt sweep failed ({run.returncode}): {run.stderr[-2000:]}")
    return wall


def basilisk_setup(epoch):
    """orbatt's dipole and Earth orientation at ``epoch``, for Basilisk.

    Parameters
    ----------
    epoch : astropy.time.Time
        The orbit's epoch.

    Returns
    -------
    coefficients : ndarray (3,)
        ``(g10, g11, h11)`` in tesla (:class:`orbatt.environment.magnetic.DipoleField`).
    c0 : ndarray (3, 3)
        The GCRS -> ITRS rotation at ``epoch`` (``x_ITRS = c0 x_GCRS``).
    """
    from orbatt.environment.frames import rotation_gcrs_to_itrs
    from orbatt.environment.magnetic import DipoleField

    return DipoleField(epoch).coefficients * 1e-9, rotation_gcrs_to_itrs(DipoleField(epoch).epoch)[0]


_BDOT_CLASS = None


def _bdot_class():
    """The B-dot flight-software module (a Python Basilisk module; defined on first use so
    that the script runs without Basilisk)."""
    global _BDOT_CLASS
    if _BDOT_CLASS is not None:
        return _BDOT_CLASS
    from Basilisk.architecture import messaging, sysModel
    from Basilisk.utilities import RigidBodyKinematics as rbk

    class BDot(sysModel.SysModel):
        """``m = -k (C_BN dB_N/dt - omega x B_B)`` per axis clipped to ``m_max``, held over the
        task step; also writes the Earth's orientation for the next task step."""

        def __init__(self, gain, mmax, c0, dt):
            super().__init__()
            self.gain, self.mmax, self.c0, self.dt = gain, mmax, np.asarray(c0), dt
            self.stateInMsg = messaging.SCStatesMsgReader()
            self.magInMsg = messaging.MagneticFieldMsgReader()
            self.cmdOutMsg = messaging.MTBCmdMsg()
            self.planetOutMsg = messaging.SpicePlanetStateMsg()
            self.cmd = messaging.MTBCmdMsgPayload()
            self.planet = messaging.SpicePlanetStateMsgPayload()
            self.planet.PlanetName = "earth"
            self.previous = None
            self.write_planet(0.0, 0)

        def write_planet(self, t, nanos):
            c, s = math.cos(EARTH_RATE * t), math.sin(EARTH_RATE * t)
            self.planet.J20002Pfix = (np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]) @ self.c0).tolist()
            self.planetOutMsg.write(self.planet, nanos, self.moduleID)

        def Reset(self, nanos):
            self.previous = None
            self.cmdOutMsg.write(self.cmd, nanos, self.moduleID)

        def UpdateState(self, nanos):
            s = self.stateInMsg()
            b_n = np.array(self.magInMsg().magField_N)
            c = rbk.MRP2C(s.sigma_BN)
            b_b = c @ b_n
            db_n = np.zeros(3) if self.previous is None else (b_n - self.previous) / self.dt
            self.previous = b_n
            m = np.clip(-self.gain * (c @ db_n - np.cross(np.array(s.omega_BN_B), b_b)), -self.mmax, self.mmax)
            self.cmd.mtbDipoleCmds = m.tolist()
            self.cmdOutMsg.write(self.cmd, nanos, self.moduleID)
            self.write_planet(nanos * 1e-9 + self.dt, nanos + round(self.dt * 1e9))

    _BDOT_CLASS = BDot
    return BDot


def basilisk_build(case, dt=BSK_DT):
    """Build one B-dot case as a Basilisk simulation (not initialized).

    Parameters
    ----------
    case : dict
        See :func:`basilisk_case`.
    dt : float
        Task step (s).

    Returns
    -------
    SimulationBaseClass.SimBaseClass
        The simulation, with ``msgRecList = {"state": recorder of the spacecraft state}`` (what
        a Monte Carlo retention policy reads), ``stop_ns`` and its modules kept alive in
        ``keep``.
    """
    from Basilisk.architecture import messaging
    from Basilisk.simulation import GravityGradientEffector, MtbEffector, magneticFieldCenteredDipole, spacecraft
    from Basilisk.utilities import SimulationBaseClass, orbitalMotion, simIncludeGravBody

    sim = SimulationBaseClass.SimBaseClass()
    sim.CreateNewProcess("proc").addTask(sim.CreateNewTask("task", round(dt * 1e9)))
    sc = spacecraft.Spacecraft()
    sc.ModelTag = "sc"
    sc.hub.mHub = 4.0
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = np.diag(case["inertia"]).tolist()
    grav = simIncludeGravBody.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = case["gm"]
    grav.addBodiesTo(sc)
    oe = orbitalMotion.ClassicElements()
    oe.a, oe.e, oe.i, oe.Omega, oe.omega, oe.f = case["elements"]
    r, v = orbitalMotion.elem2rv(case["gm"], oe)
    sc.hub.r_CN_NInit = np.reshape(r, (3, 1)).tolist()
    sc.hub.v_CN_NInit = np.reshape(v, (3, 1)).tolist()
    sc.hub.sigma_BNInit = [[0.0], [0.0], [0.0]]
    sc.hub.omega_BN_BInit = np.reshape(case["omega"], (3, 1)).tolist()
    gg = GravityGradientEffector.GravityGradientEffector()
    gg.ModelTag = "gg"
    gg.addPlanetName(earth.planetName)
    sc.addDynamicEffector(gg)
    mag = magneticFieldCenteredDipole.MagneticFieldCenteredDipole()
    mag.ModelTag = "dipole"
    mag.g10, mag.g11, mag.h11 = case["coefficients"]
    mag.planetRadius = 6371.2e3
    mag.addSpacecraftToModel(sc.scStateOutMsg)
    bdot = _bdot_class()(case["gain"], case["max_dipole"], case["c0"], dt)
    bdot.ModelTag = "bdot"
    mag.planetPosInMsg.subscribeTo(bdot.planetOutMsg)
    bdot.stateInMsg.subscribeTo(sc.scStateOutMsg)
    bdot.magInMsg.subscribeTo(mag.envOutMsgs[0])
    config = messaging.MTBArrayConfigMsgPayload()
    config.numMTB = 3
    config.GtMatrix_B = np.eye(3).ravel().tolist()
    config.maxMtbDipoles = [case["max_dipole"]] * 3
    config_msg = messaging.MTBArrayConfigMsg().write(config)
    mtb = MtbEffector.MtbEffector()
    mtb.ModelTag = "mtb"
    mtb.mtbCmdInMsg.subscribeTo(bdot.cmdOutMsg)
    mtb.magInMsg.subscribeTo(mag.envOutMsgs[0])
    mtb.mtbParamsInMsg.subscribeTo(config_msg)
    sc.addDynamicEffector(mtb)
    # each task step: the spacecraft integrates to t, the field at r(t), the law, the torquers
    for model, priority in ((sc, 100), (mag, 90), (bdot, 80), (mtb, 70), (gg, 60)):
        sim.AddModelToTask("task", model, priority)
    rec = sc.scStateOutMsg.recorder()
    sim.AddModelToTask("task", rec, 10)
    sim.msgRecList = {"state": rec}
    sim.stop_ns = round(case["t_end"] / dt) * round(dt * 1e9)
    sim.keep = [sc, grav, gg, mag, bdot, config_msg, mtb]
    return sim


def basilisk_case(case, dt=BSK_DT):
    """Build, initialize and execute one B-dot case in Basilisk.

    Parameters
    ----------
    case : dict
        ``inertia`` (kg m2, 3), ``omega`` (rad/s, 3), ``t_end`` (s), ``elements`` (a m, e, i,
        raan, argp, true anomaly rad), ``gm`` (m3/s2), ``coefficients`` (T), ``c0`` (3x3),
        ``gain``, ``max_dipole``, ``detumble_rate`` (rad/s).
    dt : float
        Task step (s).

    Returns
    -------
    dict
        ``detumble_time`` (s, NaN if never), ``final_rate`` (rad/s, 3), ``execute_s``
        (``ExecuteSimulation``), ``build_s`` (building and ``InitializeSimulation``).
    """
    t0 = time.perf_counter()
    sim = basilisk_build(case, dt)
    rec = sim.msgRecList["state"]
    sim.InitializeSimulation()
    sim.ConfigureStopTime(sim.stop_ns)
    t1 = time.perf_counter()
    sim.ExecuteSimulation()
    t2 = time.perf_counter()
    t = rec.times() * 1e-9
    w = np.asarray(rec.omega_BN_B)
    return {"detumble_time": detumble_time(t, np.linalg.norm(w, axis=1), case["detumble_rate"]),
            "final_rate": w[-1].tolist(), "execute_s": t2 - t1, "build_s": t1 - t0}


def detumble_time(t, rate, limit):
    """Earliest time after which ``rate < limit`` to the end, linear between samples.

    Parameters
    ----------
    t, rate : ndarray (N,)
        Sample times (s) and |omega| (rad/s).
    limit : float
        The threshold (rad/s).

    Returns
    -------
    float
        s; NaN if the last sample is not below ``limit``, 0 if every sample is.
    """
    above = np.nonzero(rate >= limit)[0]
    if len(above) == 0:
        return 0.0
    i = above[-1]
    if i + 1 >= len(t):
        return math.nan
    return float(t[i] + (t[i + 1] - t[i]) * (rate[i] - limit) / (rate[i] - rate[i + 1]))


def bdot_cases(sweep, ks):
    """The sweep's cases for :func:`basilisk_case`.

    Parameters
    ----------
    sweep : orbatt.sweep.Sweep
        The B-dot sweep (Kepler orbit, ``omega1..3`` and ``inertia1..3`` swept).
    ks : iterable of int
        The cases.

    Returns
    -------
    list of dict
        One :func:`basilisk_case` description per case, SI units.
    """
    sc = sweep.scenario
    o = sc.orbit
    coefficients, c0 = basilisk_setup(o.epoch)
    control = sc.spec.control["control"]
    out = []
    for k in ks:
        v = {name: float(sweep.values[name][k]) for name in sweep.values}
        out.append({"inertia": [v[f"inertia{i}"] * 1e6 for i in (1, 2, 3)],        # kg km2 -> kg m2
                    "omega": [v[f"omega{i}"] for i in (1, 2, 3)],
                    "t_end": float(sc.times[-1]), "gm": float(o.gm) * 1e9,
                    "elements": orbit_elements(o), "coefficients": coefficients.tolist(), "c0": c0.tolist(),
                    "gain": control["gain"], "max_dipole": control["max_dipole"],
                    "detumble_rate": float(sweep.spec.detumble_rate)})
    return out


def orbit_elements(orbit):
    """The Kepler orbit's elements at t = 0 for ``orbitalMotion.ClassicElements``.

    Parameters
    ----------
    orbit : orbatt.orbits.KeplerOrbit

    Returns
    -------
    tuple of float
        ``(a, e, i, raan, argp, true anomaly)``: m and rad.
    """
    el = orbit.elements
    return (el["a"] * 1e3, el["e"], el["i"], el["raan"], el["argp"], el["true_anomaly"])


#: the case every run of :func:`basilisk_controller` builds (set before the pool forks)
_CONTROLLER_CASE = {}


def _controller_create():
    """The Controller's simulation function: build :data:`_CONTROLLER_CASE`."""
    return basilisk_build(_CONTROLLER_CASE["case"], BSK_DT)


def _controller_execute(sim):
    """The Controller's execution function: initialize and run to the end."""
    sim.InitializeSimulation()
    sim.ConfigureStopTime(sim.stop_ns)
    sim.ExecuteSimulation()


def basilisk_controller(case, runs, cores, folder):
    """Run ``runs`` copies of a case with Basilisk's own ``MonteCarlo.Controller``.

    No dispersions (every run is ``case``: the same work as a dispersed one); the retention
    policy keeps the spacecraft state's ``omega_BN_B`` of every task step, archived in ``folder``
    as the framework does.

    Parameters
    ----------
    case : dict
        A :func:`basilisk_case` description.
    runs : int
        Runs (a multiple of ``cores`` keeps every pool full).
    cores : int
        ``setThreadCount``: processes per pool.
    folder : Path
        The archive's parent folder.

    Returns
    -------
    seconds : float
        Wall time of ``executeSimulations()``.
    failed : list of int
        The runs that failed.
    """
    from Basilisk.utilities.MonteCarlo.Controller import Controller
    from Basilisk.utilities.MonteCarlo.RetentionPolicy import RetentionPolicy

    _CONTROLLER_CASE["case"] = case
    mc = Controller()
    mc.setSimulationFunction(_controller_create)
    mc.setExecutionFunction(_controller_execute)
    mc.setExecutionCount(runs)
    mc.setArchiveDir(str(Path(folder) / "basilisk-mc"))
    mc.setShouldDisperseSeeds(False)
    mc.setThreadCount(cores)
    mc.setVerbose(False)
    mc.setShowProgressBar(False)
    policy = RetentionPolicy()
    policy.addMessageLog("state", ["omega_BN_B"])
    mc.addRetentionPolicy(policy)
    t0 = time.perf_counter()
    failed = mc.executeSimulations()
    return time.perf_counter() - t0, failed


def basilisk_fresh_process(case_json):
    """Run one case in a fresh interpreter (``montecarlo.py --basilisk-case JSON``).

    Parameters
    ----------
    case_json : str
        A :func:`basilisk_case` description as JSON.

    Returns
    -------
    seconds : float
        Wall time of the process (interpreter, imports, build, run).
    result : dict
        :func:`basilisk_case`'s result.
    """
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, __file__, "--basilisk-case", case_json], check=True, capture_output=True,
                         text=True).stdout
    return time.perf_counter() - t0, json.loads(out.strip().splitlines()[-1])


def part_a(samples, repeats, bsk_cases, fresh, fine, cores, workers):
    """Measure and print part A, the B-dot Monte Carlo against Basilisk.

    Parameters
    ----------
    samples : int
        Cases of the sweep.
    repeats : int
        Alternated repeats of the orbatt rows (Basilisk's Controller: at most 2).
    bsk_cases : int
        Runs per measurement with Basilisk's Controller.
    fresh : int
        Cases run in a fresh interpreter (at most ``repeats``).
    fine : bool
        Also run the agreement case at :data:`BSK_DT_FINE`.
    cores : int
        Processes of Basilisk's pools; the divisor of ``time per case x N``.
    workers : int
        ``orbatt sweep --workers``.
    """
    from orbatt.sweep import load_sweep

    folder = Path(tempfile.mkdtemp(prefix="orbatt-mc-"))
    path = folder / "cubesat-detumble-montecarlo-dipole.toml"
    path.write_text(bdot_dipole_text(samples))
    sweep = load_sweep(path)
    orbits = float(sweep.scenario.times[-1]) / sweep.scenario.orbit.period_value
    print(f"\n## A. B-dot Monte Carlo, centred dipole: N = {samples} cases, {orbits:.2f} orbits each, "
          f"{cores} cores\n")
    tw = time.perf_counter()
    _, ds = orbatt_inprocess(path)  # compile / load the kernels (numba cache)
    print(f"(warm-up: first in-process sweep {time.perf_counter() - tw:.1f} s)")
    try:
        import Basilisk  # noqa: F401
        have_bsk = True
    except ImportError:
        have_bsk = False
        print("Basilisk is not importable (pip install bsk): its rows are skipped")
    cases = bdot_cases(sweep, [0]) if have_bsk else []
    if have_bsk:  # the parent imports Basilisk before forking, as the Controller's script does
        from Basilisk.simulation import spacecraft  # noqa: F401
    tin, tcli, tpool, tfresh, fres = [], [], [], [], []
    for rep in range(repeats):   # alternate the measurements
        s, ds = orbatt_inprocess(path)
        tin.append(s)
        tcli.append(orbatt_cli(path, workers, folder))
        if have_bsk and rep < 2:
            s, failed = basilisk_controller(cases[0], bsk_cases, cores, folder)
            if failed:
                raise RuntimeError(f"Basilisk's Controller: runs {failed} failed")
            tpool.append(s)
        if have_bsk and rep < fresh:
            s, r = basilisk_fresh_process(json.dumps(cases[0]))
            tfresh.append(s)
            fres.append(r)
    body_orbits = samples * orbits
    rows = []
    b_in, m_in = stats(tin)
    b_cli, m_cli = stats(tcli)
    rows.append(("orbatt load_sweep().compute() (in-process)", b_in, m_in, b_in / samples))
    rows.append((f"orbatt sweep --workers {workers} (whole process)", b_cli, m_cli, b_cli / samples))
    bsk = {}
    if have_bsk:
        bsk["pool"] = stats([s * cores / bsk_cases for s in tpool])
        rows.append(("Basilisk MonteCarlo.Controller", *(x * samples / cores for x in bsk["pool"]), bsk["pool"][0]))
        if tfresh:
            bsk["fresh"] = stats(tfresh)
            rows.append(("Basilisk, a fresh interpreter per case", *(x * samples / cores for x in bsk["fresh"]),
                         bsk["fresh"][0]))
        serial = [r["execute_s"] for r in fres]
        bsk["execute"] = stats(serial)
        rows.append(("Basilisk, ExecuteSimulation alone", *(x * samples / cores for x in bsk["execute"]),
                     bsk["execute"][0]))
        print(f"Basilisk: task step {BSK_DT:g} s, RK4; per case: build + InitializeSimulation "
              f"{min(r['build_s'] for r in fres) * 1e3:.0f} ms, ExecuteSimulation {bsk['execute'][0]:.2f} s "
              f"(best of {len(serial)}, one process at a time); Controller: {len(tpool)} x {bsk_cases} runs on "
              f"{cores} processes; the Basilisk rows are time per case x N / {cores}")
    print(f"\n{'what':<50} {'best':>9} {'median':>9} {'per case':>10} {'body-orbits/s':>14} "
          f"{'vs Controller':>14} {'vs Execute':>11}")
    for label, best, med, per in rows:
        ratios = (f"{rows[2][1] / best:13.0f}x {rows[-1][1] / best:10.0f}x" if have_bsk else f"{'-':>14} {'-':>11}")
        print(f"{label:<50} {best:8.2f}s {med:8.2f}s {per * 1e3:8.2f}ms {body_orbits / best:14.0f} {ratios}")
    if have_bsk:
        print("(best against best; 'vs Execute': against Basilisk's ExecuteSimulation alone x N / cores, "
              "no process, build or retention cost: the bound most favourable to Basilisk)")
        k = 0
        od = float(ds["detumble_time"].values[k])
        ow = np.linalg.norm(final_rate(ds, k))
        print(f"\nAgreement, case {k} (omega0 = {np.round(np.degrees(cases[k]['omega']), 3).tolist()} deg/s): "
              f"detumble time (|omega| < {math.degrees(cases[k]['detumble_rate']):g} deg/s for good), "
              "final |omega|")
        print(f"  orbatt (dop853 rtol 1e-9, continuous law)      {od:9.1f} s   {math.degrees(ow):.4f} deg/s")
        r = fres[0]
        print(f"  Basilisk, task step {BSK_DT:g} s                     {r['detumble_time']:9.1f} s   "
              f"{math.degrees(np.linalg.norm(r['final_rate'])):.4f} deg/s")
        for dt in BSK_DT_FINE if fine else ():
            r = basilisk_case(cases[0], dt)
            print(f"  Basilisk, task step {dt:<4g}s                     {r['detumble_time']:9.1f} s   "
                  f"{math.degrees(np.linalg.norm(r['final_rate'])):.4f} deg/s  "
                  f"(ExecuteSimulation {r['execute_s']:.1f} s)")
    shutil.rmtree(folder, ignore_errors=True)


def main(argv=None):
    """The command line (``--help``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 200 B-dot cases, 50 members, fewer repeats")
    ap.add_argument("--workers", type=int, default=2, help="orbatt sweep --workers (default 2)")
    ap.add_argument("--only", choices=("a", "b"), help="run one part")
    ap.add_argument("--basilisk-case", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.basilisk_case:   # one case in this fresh interpreter (imports counted by the parent)
        from Basilisk.simulation import (GravityGradientEffector, MtbEffector,  # noqa: F401
                                         magneticFieldCenteredDipole, spacecraft)
        from Basilisk.utilities import SimulationBaseClass, orbitalMotion, simIncludeGravBody  # noqa: F401
        _bdot_class()
        r = basilisk_case(json.loads(args.basilisk_case))
        print(json.dumps(r))
        return
    cores = os.cpu_count() or 1
    print(f"orbatt Monte Carlo benchmark ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {cores} CPUs, "
          f"{'--quick' if args.quick else 'default'})")
    if args.only in (None, "a"):
        if args.quick:
            part_a(200, 2, bsk_cases=cores, fresh=1, fine=False, cores=cores, workers=args.workers)
        else:
            part_a(1000, 3, bsk_cases=2 * cores, fresh=3, fine=True, cores=cores, workers=args.workers)
    if args.only in (None, "b"):
        part_b(50 if args.quick else 200, 2 if args.quick else 3)


if __name__ == "__main__":
    main()

"""Flight software in the loop (issue 32, item 8): orbatt's PD law on reaction wheels at a
10 Hz flight-software rate against the same loop in Basilisk 2.12, one run and a Monte Carlo.

    python benchmarks/basilisk_fsw.py             # about 12 minutes on 2 busy cores
    python benchmarks/basilisk_fsw.py --quick     # 1/4 orbit, 100 + 8 + 1 + 4 cases (about 1.5 minutes)

Prints tables of ratios against baselines measured in the same run, interleaved (no number is
quoted from elsewhere). Results: ``benchmarks/README.md``, section "Flight software in the loop
against Basilisk".

The loop: ``scenarios/lvlh-hold-wheels.toml`` (50 kg microsatellite, inertia diag(1.8, 2.2, 1.2)
kg m2, three wheels on the body axes, 4e-4 kg m2, the third at 2000 rpm, motors limited to
5e-3 N m, 6000 rpm; 550 km orbit, e = 0.001; gravity gradient; holding the orbital (LVLH)
frame from 30 deg off at (0.5, -0.3, 0.2) deg/s) with ``[control] period = "0.1 s"`` added and
the law's ``max_torque`` (4e-3 N m per axis) removed, so that on both sides only the motors'
5e-3 N m limit acts (the law does not reach either here).

* orbatt: the scenario as loaded, ``dop853`` at its rtol = atol = 1e-10, and the same run with
  ``dopri5`` and ``bs32`` (Bogacki-Shampine 3(2): one step of 3 right-hand sides per tick, the
  derivative after the tick its last stage's with the wheels' rows rewritten) at
  rtol 1e-10 and ``bs32`` at 1e-12 (:data:`SINGLE_RUNS`), each with its error against
  ``dop853`` at rtol 1e-13; timed: ``propagate`` (compiled, warm) and ``Scenario.run()`` (the
  Dataset too).
* Basilisk: ``spacecraft.Spacecraft`` (hub inertia = orbatt's inertia with the rotors locked,
  ``BalancedWheels``), point-mass Earth with orbatt's GM, the orbit from the same elements
  (``elem2rv``; Basilisk integrates it), ``GravityGradientEffector``,
  ``reactionWheelStateEffector`` (same axes, Js, initial speeds relative to the body, u_max,
  Omega_max), and the flight software at one 0.1 s task: ``simpleNav`` (no noise) ->
  ``hillPoint`` -> ``attTrackingError`` -> ``mrpFeedback`` (K = 2 kp, P = kd, Ki = -1: no
  integral) -> ``rwMotorTorque`` (controlAxes = I). Within a task step the wheels read the
  command, the spacecraft integrates to the step's end, then the flight software computes the
  next command from the new state: a zero-order hold without delay, orbatt's ticks. RK4 at the
  task step (Basilisk's default integrator); RKF78 at relTol 1e-10 once, for its integration
  error. Timed: ``ExecuteSimulation`` and build + ``InitializeSimulation`` + execute.

The laws are not identical: orbatt's is ``tau = -kp e - kd (omega - omega_t)`` with ``e =
sgn(q_e0) Im(q_e)``; ``mrpFeedback`` is ``-K sigma - P dw + omega_r x (I omega) - I (domega_r -
omega x omega_r)`` with ``sigma = Im(q_e) / (1 + q_e0)`` (its wheel-momentum feed-forward left
out by not giving it the wheel speeds, as orbatt's law has none). With K = 2 kp the proportional
terms agree to first order (30 deg: 1.7 % apart); the feed-forward terms are ~|I| |omega_r| |dw|.
The attitude histories are compared at the 20 s outputs (largest rotation angle between them) and
each side's pointing error to the orbital frame is printed.

The Monte Carlo: the same scenario with ``[sweep]`` of 500 cases, each initial rate
``omega1..3`` uniform in +-1 deg/s; orbatt: ``orbatt.run_sweep(path)`` (the scheduler chosen by
the work) and ``load_sweep(path).compute()`` (one in-process ensemble call), outputs
``final_state`` and ``max_pointing_error``, with the scenario's ``dop853`` (each member its own
steps) and with ``[integration] method = "dopri5-lanes"`` and ``"bs32-lanes"`` (:data:`MC_METHODS`:
the members of a group of 32 step together between the shared ticks). Basilisk: (1) its
``MonteCarlo.Controller`` on one process per core (offline, from a fresh process: the helpers of
``basilisk_mc.py``, shared with ``basilisk_fine_pointing.py``; dispersions ``omega1..3`` uniform
in +-1 deg/s set on the hub before ``InitializeSimulation``, seeds dispersed, a retention function
returning the final attitude), timed at 4 and 12 cases (``--quick``: 1 and 4), fitted as ``a + b
N`` (its pool's start-up apart) and projected to 500: its worker sleeps 1 s after each case's
retained data, part of what its user waits for; (2) its cases one after the other in this process
(build, initialize, execute each: what a worker does, without the pool), 20 of the sweep's own
cases timed and scaled to 500, their final attitudes compared with orbatt's.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))   # the sibling scripts, whoever loads this one
from basilisk_mc import controller_subprocess, run_controller  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "lvlh-hold-wheels.toml"
DT = 0.1                 # s, the flight-software rate (orbatt's period, Basilisk's task step)
OUT_STEP = 20.0          # s, outputs compared
RATE_SPREAD_DEG = 1.0    # deg/s, the Monte Carlo's initial-rate dispersion (uniform, per axis)
#: the single runs timed: (method, rtol = atol); the first is the scenario's own
SINGLE_RUNS = (("dop853", 1e-10), ("dopri5", 1e-10), ("bs32", 1e-10), ("bs32", 1e-12))
#: the Monte Carlo's methods: the scenario's own (None: ``dop853``), then lockstep lanes
MC_METHODS = (None, "dopri5-lanes", "bs32-lanes")


def scenario_text(t_end, samples=None, rate_spread=f"{RATE_SPREAD_DEG:g} deg/s", method=None):
    """The shipped scenario with ``period = 0.1 s``, no law ``max_torque``, ``t_end`` seconds and,
    with ``samples``, a ``[sweep]`` over the initial rates; ``method``: ``[integration] method``
    (None: the scenario's ``dop853``)."""
    text = SCENARIO.read_text()
    text = text.replace('actuator = "wheels"\n', f'actuator = "wheels"\nperiod = "{DT} s"\n', 1)
    text = text.replace('max_torque = "4e-3 N m"\nactuator', 'actuator', 1)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end:g} s"', text)
    assert 'period = "0.1 s"' in text and 'max_torque = "4e-3' not in text
    if method is not None:
        text = text.replace('method = "dop853"', f'method = "{method}"', 1)
        assert f'method = "{method}"' in text
    if samples:
        text += (f'\n[sweep]\nsamples = {samples}\nseed = 20261201\noutputs = ["final_state", "max_pointing_error"]\n'
                 '\n[sweep.parameters]\n'
                 + "".join(f'omega{i} = {{ distribution = "uniform", low = "-{rate_spread}", high = "{rate_spread}" }}\n'
                           for i in (1, 2, 3)))
    return text


def gains(sc):
    """(kp N m, kd N m s) of the scenario's law."""
    c = sc.spec.control["control"]
    return float(c["kp"]), float(c["kd"])


def orbatt_single(sc, method=None, rtol=None):
    """orbatt's quaternions at the outputs and the wall time of ``propagate`` (s), with the
    scenario's method and tolerances or ``method`` at ``rtol = atol``."""
    import orbatt

    kw = dict(sc.settings) if rtol is None else dict(sc.settings, rtol=rtol, atol=rtol)
    w = time.perf_counter()
    tr = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method=method or sc.method, **kw)
    w = time.perf_counter() - w
    orbatt_single.stats = tr.stats
    return np.asarray(tr.q), w


def setup(sc):
    """The plain numbers Basilisk's side needs (SI), from the loaded orbatt scenario ``sc``: a
    dict that pickles (``MonteCarlo.Controller`` sends the simulation function to its workers)."""
    kp, kd = gains(sc)
    el = sc.orbit.elements
    return {"kp": kp, "kd": kd, "inertia": (np.asarray(sc.spec.inertia, dtype=float) * 1e6).tolist(),  # kg m2
            "mu": float(sc.orbit.gm) * 1e9,
            "elements": (el["a"] * 1e3, el["e"], el["i"], el["raan"], el["argp"], el["true_anomaly"]),
            "q0": np.asarray(sc.state0.q, dtype=float).tolist(),
            "omega0": np.asarray(getattr(sc.state0.omega, "value", sc.state0.omega), dtype=float).tolist(),
            "wheels": [(list(map(float, w.axis)), w.inertia_kg_m2, w.speed_rad_s * 60 / (2 * math.pi),
                        w.max_torque_n_m, w.max_speed_rad_s * 60 / (2 * math.pi)) for w in sc.body.wheels],
            "times": np.asarray(sc.times, dtype=float).tolist()}


def basilisk_build(p, integrator="rk4", tol=1e-10):
    """Build the loop in Basilisk for the numbers ``p`` (:func:`setup`; not initialized:
    :func:`basilisk_execute`); the simulation, its modules in ``sim.parts``."""
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import attTrackingError, hillPoint, mrpFeedback, rwMotorTorque
    from Basilisk.simulation import (GravityGradientEffector, reactionWheelStateEffector, simpleNav, spacecraft,
                                     svIntegrators)
    from Basilisk.utilities import RigidBodyKinematics as rbk
    from Basilisk.utilities import SimulationBaseClass, orbitalMotion, simIncludeGravBody, simIncludeRW

    kp, kd = p["kp"], p["kd"]
    inertia = np.asarray(p["inertia"])
    dt_ns = round(DT * 1e9)
    sim = SimulationBaseClass.SimBaseClass()
    sim.CreateNewProcess("proc").addTask(sim.CreateNewTask("task", dt_ns))
    s = spacecraft.Spacecraft()
    s.ModelTag = "sc"
    s.hub.mHub = 50.0
    s.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    s.hub.IHubPntBc_B = np.diag(inertia).tolist()
    grav = simIncludeGravBody.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = p["mu"]
    grav.addBodiesTo(s)
    oe = orbitalMotion.ClassicElements()
    oe.a, oe.e, oe.i, oe.Omega, oe.omega, oe.f = p["elements"]
    r, v = orbitalMotion.elem2rv(earth.mu, oe)
    s.hub.r_CN_NInit = np.reshape(r, (3, 1)).tolist()
    s.hub.v_CN_NInit = np.reshape(v, (3, 1)).tolist()
    s.hub.sigma_BNInit = np.reshape(rbk.EP2MRP(np.asarray(p["q0"])), (3, 1)).tolist()
    s.hub.omega_BN_BInit = np.reshape(p["omega0"], (3, 1)).tolist()
    if integrator == "rk4":
        integ = svIntegrators.svIntegratorRK4(s)
    else:
        integ = svIntegrators.svIntegratorRKF78(s)
        integ.relTol, integ.absTol = tol, tol
    s.setIntegrator(integ)
    gg = GravityGradientEffector.GravityGradientEffector()
    gg.ModelTag = "gg"
    gg.addPlanetName(earth.planetName)
    s.addDynamicEffector(gg)
    factory = simIncludeRW.rwFactory()
    for axis, js, rpm, u_max, rpm_max in p["wheels"]:
        factory.create("custom", axis, Js=js, Omega=rpm, RWModel=messaging.BalancedWheels, useMaxTorque=True,
                       u_max=u_max, Omega_max=rpm_max)
    rw = reactionWheelStateEffector.ReactionWheelStateEffector()
    rw.ModelTag = "rw"
    factory.addToSpacecraft("sc", rw, s)
    nav = simpleNav.SimpleNav()
    nav.ModelTag = "nav"
    nav.scStateInMsg.subscribeTo(s.scStateOutMsg)
    ref = hillPoint.hillPoint()
    ref.ModelTag = "hill"
    ref.transNavInMsg.subscribeTo(nav.transOutMsg)
    err = attTrackingError.attTrackingError()
    err.ModelTag = "err"
    err.attNavInMsg.subscribeTo(nav.attOutMsg)
    err.attRefInMsg.subscribeTo(ref.attRefOutMsg)
    vehicle = messaging.VehicleConfigMsgPayload()
    vehicle.ISCPntB_B = np.diag(inertia).ravel().tolist()
    vehicle_msg = messaging.VehicleConfigMsg().write(vehicle)
    ctrl = mrpFeedback.mrpFeedback()
    ctrl.ModelTag = "mrpFeedback"
    ctrl.K, ctrl.P, ctrl.Ki = 2 * kp, kd, -1.0
    ctrl.guidInMsg.subscribeTo(err.attGuidOutMsg)
    ctrl.vehConfigInMsg.subscribeTo(vehicle_msg)
    motor = rwMotorTorque.rwMotorTorque()
    motor.ModelTag = "rwMotorTorque"
    motor.controlAxes_B = np.eye(3).ravel().tolist()
    rw_params = factory.getConfigMessage()
    motor.rwParamsInMsg.subscribeTo(rw_params)
    motor.vehControlInMsg.subscribeTo(ctrl.cmdTorqueOutMsg)
    rw.rwMotorCmdInMsg.subscribeTo(motor.rwMotorTorqueOutMsg)
    for model, priority in ((rw, 100), (s, 90), (gg, 85), (nav, 80), (ref, 79), (err, 78), (ctrl, 77), (motor, 76)):
        sim.AddModelToTask("task", model, priority)
    step_ns = round(OUT_STEP * 1e9)
    sim.rec = s.scStateOutMsg.recorder(step_ns)
    sim.guid = err.attGuidOutMsg.recorder(step_ns)
    sim.AddModelToTask("task", sim.rec, 10)
    sim.AddModelToTask("task", sim.guid, 10)
    sim.parts = dict(grav=grav, gg=gg, rw=rw, s=s, nav=nav, ref=ref, err=err, ctrl=ctrl, motor=motor,
                     vehicle_msg=vehicle_msg, rw_params=rw_params, factory=factory)
    sim.out_times = np.asarray(p["times"])
    return sim


def basilisk_execute(sim):
    """Initialize and run ``sim`` (:func:`basilisk_build`) to its last output; returns the
    execute wall time (s)."""
    sim.InitializeSimulation()
    sim.ConfigureStopTime(round(float(sim.out_times[-1]) / DT) * round(DT * 1e9))
    w = time.perf_counter()
    sim.ExecuteSimulation()
    return time.perf_counter() - w


def basilisk_outputs(sim):
    """``(q (N, 4), pointing (N,) rad: 4 atan |sigma_BR|)`` of an executed ``sim`` at its outputs."""
    from Basilisk.utilities import RigidBodyKinematics as rbk

    times = sim.rec.times() * 1e-9
    idx = [int(np.argmin(np.abs(times - t))) for t in sim.out_times]
    assert np.allclose(times[idx], sim.out_times, atol=1e-6)
    q = np.array([rbk.MRP2EP(sim.rec.sigma_BN[i]) for i in idx])
    sig = np.asarray(sim.guid.sigma_BR)[idx]
    return q * np.sign(q[:, :1]), 4 * np.arctan(np.linalg.norm(sig, axis=1))


def basilisk_case(sc, integrator="rk4", tol=1e-10):
    """Build, initialize and run the loop in Basilisk for the scenario ``sc``'s initial state.

    Returns
    -------
    dict
        ``q`` (N, 4) at ``sc.times``, ``pointing`` (rad, N: 4 atan |sigma_BR|), ``execute_s``,
        ``total_s`` (build + initialize + execute).
    """
    t0 = time.perf_counter()
    sim = basilisk_build(setup(sc), integrator, tol)
    execute_s = basilisk_execute(sim)
    total_s = time.perf_counter() - t0
    q, pointing = basilisk_outputs(sim)
    return {"q": q, "pointing": pointing, "execute_s": execute_s, "total_s": total_s}


# -- Basilisk's Monte Carlo Controller (module-level functions: pickled by reference) --------

def mc_create(p):
    sim = basilisk_build(p)
    sim.omega1 = sim.omega2 = sim.omega3 = 0.0
    return sim


def mc_execute(sim):
    sim.parts["s"].hub.omega_BN_BInit = [[sim.omega1], [sim.omega2], [sim.omega3]]
    basilisk_execute(sim)


def mc_retain(sim):
    q, pointing = basilisk_outputs(sim)
    return {"q_final": q[-1].tolist(), "max_pointing": float(pointing.max())}


def _controller_main(arg):
    """The child of :func:`controller_subprocess`: ``T_END,CASES,WORKERS,FOLDER``."""
    import functools

    import orbatt

    t_end, cases, workers, folder = arg.split(",", 3)
    Path(folder).mkdir(parents=True, exist_ok=True)
    path = Path(folder) / "lvlh-hold-wheels-fsw.toml"
    path.write_text(scenario_text(float(t_end)))
    p = setup(orbatt.load_scenario(path))
    w = math.radians(RATE_SPREAD_DEG)
    wall, kept = run_controller(functools.partial(mc_create, p), mc_execute, mc_retain, int(cases), int(workers),
                                Path(folder) / "mc", [(f"omega{i}", (-w, w)) for i in (1, 2, 3)])
    print(json.dumps({"wall": wall, "kept": kept}))


def angle(qa, qb):
    """Rotation angles (rad) between two quaternion series ``(N, 4)``."""
    qa, qb = np.atleast_2d(qa), np.atleast_2d(qb)
    vec = qa[:, :1] * qb[:, 1:] - qb[:, :1] * qa[:, 1:] - np.cross(qa[:, 1:], qb[:, 1:])
    return 2 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(np.sum(qa * qb, axis=-1)))


def best_median(x):
    return min(x), statistics.median(x)


def part_single(t_end, repeats):
    import orbatt

    folder = Path(tempfile.mkdtemp(prefix="orbatt-fsw-"))
    path = folder / "lvlh-hold-wheels-fsw.toml"
    path.write_text(scenario_text(t_end))
    sc = orbatt.load_scenario(path)
    kp, kd = gains(sc)
    orbits = float(sc.times[-1]) / sc.orbit.period_value
    ticks = round(float(sc.times[-1]) / DT)
    print(f"\n## A. One run: {sc.times[-1]:g} s ({orbits:.2f} orbits), flight software at {DT:g} s "
          f"({ticks} ticks); kp = {kp:g} N m, kd = {kd:g} N m s -> Basilisk K = {2 * kp:g}, "
          f"P = {kd:g}, Ki = -1; load {load_line()}\n")
    assert SINGLE_RUNS[0] == (sc.method, sc.settings["rtol"]) and sc.settings["atol"] == sc.settings["rtol"]
    ds = sc.run()                                 # compiles / loads the kernels
    for m, rtol in SINGLE_RUNS:
        orbatt_single(sc, m, rtol)
    basilisk_case(sc)                             # imports, first build
    t_prop = {run: [] for run in SINGLE_RUNS}
    q_run, stats = {}, {}
    t_run, b_exec, b_total = [], [], []
    for _ in range(repeats):                      # interleaved
        for m, rtol in SINGLE_RUNS:
            q_run[m, rtol], w = orbatt_single(sc, m, rtol)
            stats[m, rtol] = orbatt_single.stats
            t_prop[m, rtol].append(w)
        w = time.perf_counter()
        ds = sc.run()
        t_run.append(time.perf_counter() - w)
        b = basilisk_case(sc)
        b_exec.append(b["execute_s"])
        b_total.append(b["total_s"])
    b78 = basilisk_case(sc, "rkf78", 1e-10)
    tight = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method="dop853", rtol=1e-13, atol=1e-13)
    qo_tight = np.asarray(tight.q)
    qrel = np.asarray(ds["q_orbital"].values)
    po = 2 * np.arctan2(np.linalg.norm(qrel[:, 1:], axis=1), np.abs(qrel[:, 0]))
    bx, bt = best_median(b_exec), best_median(b_total)
    rows = [(f"orbatt propagate ({m} rtol {rtol:.0e})", *best_median(t_prop[m, rtol]), stats[m, rtol],
             angle(q_run[m, rtol], qo_tight).max()) for m, rtol in SINGLE_RUNS]
    rows += [("orbatt Scenario.run() (dop853 + Dataset)", *best_median(t_run), None, None),
             ("Basilisk ExecuteSimulation (RK4, 0.1 s)", *bx, None, angle(b["q"], b78["q"]).max()),
             ("Basilisk build + Initialize + Execute", *bt, None, None)]
    print(f"{'what':<46} {'best s':>8} {'median s':>9} {'Bsk Exec / this':>16} {'Bsk total / this':>17} "
          f"{'RHS/tick':>9} {'ns/RHS':>7} {'us/tick':>8} {'error rad':>10}")
    for label, best, med, st, err in rows:
        nrhs = f"{st['rhs_evaluations'] / ticks:9.2f} {best / st['rhs_evaluations'] * 1e9:7.0f}" if st else f"{'':>17}"
        print(f"{label:<46} {best:8.4f} {med:9.4f} {bx[0] / best:15.1f}x {bt[0] / best:16.1f}x {nrhs} "
              f"{best / ticks * 1e6:8.2f} {'' if err is None else f'{err:10.2g}'}")
    print(f"(best of {repeats}, interleaved; error: the largest attitude difference at the {OUT_STEP:g} s outputs "
          f"from orbatt dop853 rtol 1e-13 (orbatt) or from Basilisk RKF78 relTol 1e-10 (Basilisk RK4; RKF78 "
          f"ExecuteSimulation once {b78['execute_s']:.2f} s); Basilisk RK4: 4 RHS per tick with its 5 "
          f"flight-software modules)")
    qo, qb = q_run[SINGLE_RUNS[0]], b["q"]
    print("\nAgreement (largest over the 20 s outputs):")
    d = angle(qo, qb)
    print(f"  orbatt vs Basilisk attitude                                        {d.max():.3g} rad "
          f"({math.degrees(d.max()):.3g} deg; at t = {sc.times[np.argmax(d)]:g} s; final {math.degrees(d[-1]):.3g} deg)")
    n = len(po)
    for label, p in (("orbatt", po), ("Basilisk", b["pointing"])):
        print(f"  {label:<9} pointing error to LVLH: {math.degrees(p[0]):.3g} -> {math.degrees(p[n // 8]):.3g} "
              f"(t = {sc.times[n // 8]:g} s) -> {math.degrees(p[n // 2]):.3g} -> {math.degrees(p[-1]):.3g} deg; "
              f"mean over the 2nd half {math.degrees(p[n // 2:].mean()):.3g} deg")
    dp = np.abs(po - b["pointing"])
    print(f"  pointing error difference: largest {math.degrees(dp.max()):.3g} deg, over the 2nd half "
          f"{math.degrees(dp[n // 2:].max()):.3g} deg")
    return {"exec_ratio": {run: bx[0] / min(t_prop[run]) for run in SINGLE_RUNS}}


def part_mc(t_end, samples, bsk_cases, ctrl_cases, repeats):
    import orbatt
    from orbatt.sweep import load_sweep

    cores = os.cpu_count() or 1
    folder = Path(tempfile.mkdtemp(prefix="orbatt-fsw-mc-"))
    paths, sweeps = {}, {}
    for m in MC_METHODS:
        paths[m] = folder / f"lvlh-hold-wheels-fsw-mc-{m or 'scenario'}.toml"
        paths[m].write_text(scenario_text(t_end, samples, method=m))
        sweeps[m] = load_sweep(paths[m])
    print(f"\n## B. Monte Carlo: {samples} cases, initial rates uniform in +-{RATE_SPREAD_DEG:g} deg/s, {t_end:g} s "
          f"each; Basilisk: {ctrl_cases} cases with MonteCarlo.Controller on {cores} processes and {bsk_cases} of "
          f"the sweep's cases one after the other in this process, each scaled to {samples}; {cores} cores; "
          f"load {load_line()}\n")
    w = time.perf_counter()
    for m in MC_METHODS:
        sweeps[m].compute()                       # compile / load
    print(f"(warm-up: first computes {time.perf_counter() - w:.1f} s)")
    cases = []
    for k in range(bsk_cases):
        p = folder / f"case{k}.toml"
        p.write_text(sweeps[None].case_text(k))
        cases.append(orbatt.load_scenario(p))
    t_comp = {m: [] for m in MC_METHODS}
    t_sweep = {m: [] for m in (None, "bs32-lanes")}
    t_bsk, res, ds, loads = [], {}, {}, []
    n_ctrl = (max(1, ctrl_cases // 3), ctrl_cases)   # the Controller at two sizes: its start-up apart
    t_ctrl = {n: [] for n in n_ctrl}
    half = (bsk_cases + 1) // 2
    for rep in range(repeats):
        loads.append(os.getloadavg()[0])
        print(f"  repeat {rep}: load {loads[-1]:.2f}", flush=True)
        for m in MC_METHODS:
            w = time.perf_counter()
            ds[m] = sweeps[m].compute()
            t_comp[m].append(time.perf_counter() - w)
        for m in t_sweep:
            w = time.perf_counter()
            ds["run_sweep", m] = orbatt.run_sweep(paths[m])
            t_sweep[m].append(time.perf_counter() - w)
        for n in n_ctrl:
            wall, kept = controller_subprocess(__file__, f"{t_end:g},{n},{cores},{folder / f'bsk{rep}-{n}'}")
            t_ctrl[n].append(wall)
        if rep < 2:                               # Basilisk case after case: two halves, interleaved with orbatt
            chunk = range(0, half) if rep == 0 else range(half, bsk_cases)
            for k in chunk:
                b = basilisk_case(cases[k])
                res[k] = b
                t_bsk.append(b["total_s"])
    per_case = sum(t_bsk) / len(t_bsk)
    exec_case = sum(res[k]["execute_s"] for k in res) / len(res)
    projected = per_case * samples
    # the Controller's time for N cases as a + b N from its two sizes (best of the repeats each)
    (n1, n2), (w1, w2) = n_ctrl, (min(t_ctrl[n_ctrl[0]]), min(t_ctrl[n_ctrl[1]]))
    b_ctrl = (w2 - w1) / (n2 - n1) if n2 > n1 else w2 / n2
    a_ctrl = max(0.0, w1 - b_ctrl * n1)
    proj_ctrl = a_ctrl + b_ctrl * samples
    ctrl_case = proj_ctrl / samples
    qf0 = np.asarray(ds[None]["q_final"].transpose("case", ...).values)
    rows = []
    for m in MC_METHODS:
        qf = np.asarray(ds[m]["q_final"].transpose("case", ...).values)
        err = angle(qf, qf0).max() if m is not None else None
        rows.append((f"orbatt compute() ({m or 'dop853'})", *best_median(t_comp[m]), err))
    for m in t_sweep:
        rows.append((f"orbatt run_sweep(path) ({m or 'dop853'})", *best_median(t_sweep[m]), None))
    ticks = round(t_end / DT)
    print(f"{'what':<44} {'best s':>8} {'median s':>9} {'ms/case':>8} {'us/case-tick':>12} {'vs Bsk Controller':>18} "
          f"{'vs Bsk serial':>14} {'vs dop853':>10}")
    for label, best, med, err in rows:
        print(f"{label:<44} {best:8.2f} {med:9.2f} {best / samples * 1e3:8.2f} {best / samples / ticks * 1e6:12.3f} "
              f"{proj_ctrl / best:17.0f}x {projected / best:13.0f}x {'' if err is None else f'{err:10.2g}'}")
    print(f"{'Basilisk Controller, ' + str(cores) + ' processes (projected)':<44} {proj_ctrl:8.1f} {'':>9} "
          f"{ctrl_case * 1e3:8.1f} {ctrl_case / ticks * 1e6:12.2f} {'1':>17}x")
    print(f"{'Basilisk, case after case (projected)':<44} {projected:8.1f} {'':>9} {per_case * 1e3:8.1f} "
          f"{per_case / ticks * 1e6:12.2f} {'':>18} {'1':>13}x")
    print(f"(Basilisk Controller: {n1} cases in {w1:.1f} s, {n2} in {w2:.1f} s, best of {repeats} each: {a_ctrl:.1f} s "
          f"+ {b_ctrl:.3f} s per case, incl. its 1 s sleep per case in each worker ({1 / cores:.2f} s per case); "
          f"case after case: build + Initialize + Execute "
          f"{per_case:.3f} s, ExecuteSimulation alone {exec_case:.3f} s, mean of {len(t_bsk)}; orbatt best of "
          f"{repeats}; 'vs dop853': the largest final-attitude difference (rad) from the dop853 sweep; loads at the "
          f"repeats' starts {', '.join(f'{x:.2f}' for x in loads)})")
    d = np.array([angle(qf0[k], res[k]["q"][-1])[0] for k in res])
    same = [np.array_equal(np.asarray(ds[None][v].values), np.asarray(ds["run_sweep", None][v].values))
            for v in ("q_final", "max_pointing_error")]
    print(f"Agreement: final attitude, orbatt vs Basilisk, {len(d)} cases: largest {math.degrees(d.max()):.3g} deg, "
          f"median {math.degrees(np.median(d)):.3g} deg; compute() and run_sweep() bitwise equal: {all(same)}")
    mpe = np.degrees(np.asarray(ds[None]["max_pointing_error"].values))
    bmp = np.degrees([k["max_pointing"] for k in kept])
    print(f"  max pointing error over the run across cases: orbatt {mpe.min():.3g} - {mpe.max():.3g} deg, "
          f"Basilisk Controller's cases {bmp.min():.3g} - {bmp.max():.3g} deg")
    return {m: proj_ctrl / min(t_comp[m]) for m in MC_METHODS}


def load_line():
    return "%.2f %.2f %.2f" % os.getloadavg()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1/4 orbit, 100 cases, 8 Basilisk cases, 1 + 4 Controller cases")
    ap.add_argument("--only", choices=("a", "b"), help="run one part")
    ap.add_argument("--controller", help=argparse.SUPPRESS)      # T_END,CASES,WORKERS,FOLDER: the child
    args = ap.parse_args(argv)
    if args.controller:
        return _controller_main(args.controller)
    try:
        import Basilisk  # noqa: F401
    except ImportError:
        raise SystemExit("Basilisk is not importable: pip install bsk (the 'bench' extra)")
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"orbatt flight software vs Basilisk ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{os.cpu_count()} CPUs, {'--quick' if args.quick else 'default'}); load: {uptime}")
    t_end = 1400.0 if args.quick else 5740.0
    if args.only in (None, "a"):
        part_single(t_end, 2 if args.quick else 3)
    if args.only in (None, "b"):
        part_mc(t_end, 100 if args.quick else 500, 8 if args.quick else 20, 4 if args.quick else 12, 2)
    print(f"\nload at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()

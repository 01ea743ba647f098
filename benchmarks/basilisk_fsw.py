"""Flight software in the loop (issue 32, item 8): orbatt's PD law on reaction wheels at a
10 Hz flight-software rate against the same loop in Basilisk 2.12, one run and a Monte Carlo.

    python benchmarks/basilisk_fsw.py             # about 9 minutes on 2 busy cores (load 4-5)
    python benchmarks/basilisk_fsw.py --quick     # 1/4 orbit, 100 + 8 cases (about 1 minute)

Prints tables of ratios against baselines measured in the same run, interleaved (no number is
quoted from elsewhere). Results: ``benchmarks/README.md``, section "Flight software in the loop
against Basilisk".

The loop: ``scenarios/lvlh-hold-wheels.toml`` (50 kg microsatellite, inertia diag(1.8, 2.2, 1.2)
kg m2, three wheels on the body axes, 4e-4 kg m2, the third at 2000 rpm, motors limited to
5e-3 N m, 6000 rpm; 550 km orbit, e = 0.001; gravity gradient; holding the orbital (LVLH)
frame from 30 deg off at (0.5, -0.3, 0.2) deg/s) with ``[control] period = "0.1 s"`` added and
the law's ``max_torque`` (4e-3 N m per axis) removed, so that on both sides only the motors'
5e-3 N m limit acts (the law does not reach either here).

* orbatt: the scenario as loaded, ``dop853`` at its rtol = atol = 1e-10; timed: ``propagate``
  (compiled, warm) and ``Scenario.run()`` (the Dataset too).
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
``final_state`` and ``max_pointing_error``. Basilisk: its cases run one after the other in this
process (build, initialize, execute each: what its ``MonteCarlo.Controller`` does in each worker
process, without the process start, pickling and retention), 20 of the sweep's own cases timed
and scaled to 500; ratios are given against that serial time and against it divided by the
cores (a perfect ``Controller`` pool). The 20 cases' final attitudes are compared with orbatt's.
"""
from __future__ import annotations

import argparse
import math
import os
import re
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "lvlh-hold-wheels.toml"
DT = 0.1                 # s, the flight-software rate (orbatt's period, Basilisk's task step)
OUT_STEP = 20.0          # s, outputs compared


def scenario_text(t_end, samples=None, rate_spread="1 deg/s"):
    """The shipped scenario with ``period = 0.1 s``, no law ``max_torque``, ``t_end`` seconds and,
    with ``samples``, a ``[sweep]`` over the initial rates."""
    text = SCENARIO.read_text()
    text = text.replace('actuator = "wheels"\n', f'actuator = "wheels"\nperiod = "{DT} s"\n', 1)
    text = text.replace('max_torque = "4e-3 N m"\nactuator', 'actuator', 1)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end:g} s"', text)
    assert 'period = "0.1 s"' in text and 'max_torque = "4e-3' not in text
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


def orbatt_single(sc):
    """orbatt's quaternions at the outputs and the wall time of ``propagate`` (s)."""
    import orbatt

    w = time.perf_counter()
    tr = orbatt.propagate(sc.body, sc.state0, sc.potential, sc.times, method=sc.method, **sc.settings)
    w = time.perf_counter() - w
    orbatt_single.stats = tr.stats
    return np.asarray(tr.q), w


def basilisk_case(sc, integrator="rk4", tol=1e-10):
    """Build, initialize and run the loop in Basilisk for the scenario ``sc``'s initial state.

    Returns
    -------
    dict
        ``q`` (N, 4) at ``sc.times``, ``pointing`` (rad, N: 4 atan |sigma_BR|), ``execute_s``,
        ``total_s`` (build + initialize + execute).
    """
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import attTrackingError, hillPoint, mrpFeedback, rwMotorTorque
    from Basilisk.simulation import (GravityGradientEffector, reactionWheelStateEffector, simpleNav, spacecraft,
                                     svIntegrators)
    from Basilisk.utilities import RigidBodyKinematics as rbk
    from Basilisk.utilities import SimulationBaseClass, orbitalMotion, simIncludeGravBody, simIncludeRW

    t0 = time.perf_counter()
    kp, kd = gains(sc)
    inertia = np.asarray(sc.spec.inertia, dtype=float) * 1e6          # kg km2 -> kg m2
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
    earth.mu = float(sc.orbit.gm) * 1e9
    grav.addBodiesTo(s)
    el = sc.orbit.elements
    oe = orbitalMotion.ClassicElements()
    oe.a, oe.e, oe.i, oe.Omega, oe.omega, oe.f = (el["a"] * 1e3, el["e"], el["i"], el["raan"], el["argp"],
                                                  el["true_anomaly"])
    r, v = orbitalMotion.elem2rv(earth.mu, oe)
    s.hub.r_CN_NInit = np.reshape(r, (3, 1)).tolist()
    s.hub.v_CN_NInit = np.reshape(v, (3, 1)).tolist()
    q0 = np.asarray(sc.state0.q, dtype=float)
    s.hub.sigma_BNInit = np.reshape(rbk.EP2MRP(q0), (3, 1)).tolist()
    s.hub.omega_BN_BInit = np.reshape(np.asarray(getattr(sc.state0.omega, "value", sc.state0.omega), dtype=float), (3, 1)).tolist()
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
    for w in sc.body.wheels:
        factory.create("custom", list(map(float, w.axis)), Js=w.inertia_kg_m2, Omega=w.speed_rad_s * 60 / (2 * math.pi),
                       RWModel=messaging.BalancedWheels, useMaxTorque=True, u_max=w.max_torque_n_m,
                       Omega_max=w.max_speed_rad_s * 60 / (2 * math.pi))
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
    rec = s.scStateOutMsg.recorder(step_ns)
    guid = err.attGuidOutMsg.recorder(step_ns)
    sim.AddModelToTask("task", rec, 10)
    sim.AddModelToTask("task", guid, 10)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(round(float(sc.times[-1]) / DT) * dt_ns)
    t1 = time.perf_counter()
    sim.ExecuteSimulation()
    t2 = time.perf_counter()
    times = rec.times() * 1e-9
    idx = [int(np.argmin(np.abs(times - t))) for t in sc.times]
    assert np.allclose(times[idx], sc.times, atol=1e-6)
    q = np.array([rbk.MRP2EP(rec.sigma_BN[i]) for i in idx])
    sig = np.asarray(guid.sigma_BR)[idx]
    keep = (grav, gg, rw, nav, ref, err, ctrl, motor, vehicle_msg, rw_params, factory)   # noqa: F841
    return {"q": q * np.sign(q[:, :1]), "pointing": 4 * np.arctan(np.linalg.norm(sig, axis=1)),
            "execute_s": t2 - t1, "total_s": t2 - t0}


def angle(qa, qb):
    """Rotation angles (rad) between two quaternion series ``(N, 4)``."""
    qa, qb = np.atleast_2d(qa), np.atleast_2d(qb)
    vec = qa[:, :1] * qb[:, 1:] - qb[:, :1] * qa[:, 1:] - np.cross(qa[:, 1:], qb[:, 1:])
    return 2 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(np.sum(qa * qb, axis=-1)))


def best_median(x):
    return min(x), statistics.median(x)


def load():
    return os.getloadavg()


def part_single(t_end, repeats):
    import orbatt

    folder = Path(tempfile.mkdtemp(prefix="orbatt-fsw-"))
    path = folder / "lvlh-hold-wheels-fsw.toml"
    path.write_text(scenario_text(t_end))
    sc = orbatt.load_scenario(path)
    kp, kd = gains(sc)
    orbits = float(sc.times[-1]) / sc.orbit.period_value
    print(f"\n## A. One run: {sc.times[-1]:g} s ({orbits:.2f} orbits), flight software at {DT:g} s "
          f"({round(sc.times[-1] / DT)} ticks); kp = {kp:g} N m, kd = {kd:g} N m s -> Basilisk K = {2 * kp:g}, "
          f"P = {kd:g}, Ki = -1\n")
    ds = sc.run()                                 # compiles / loads the kernels
    orbatt_single(sc)
    basilisk_case(sc)                             # imports, first build
    t_prop, t_run, b_exec, b_total = [], [], [], []
    for _ in range(repeats):                      # interleaved
        qo, w = orbatt_single(sc)
        t_prop.append(w)
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
    rows = [("orbatt propagate (dop853 rtol 1e-10)", *best_median(t_prop)),
            ("orbatt Scenario.run() (propagate + Dataset)", *best_median(t_run)),
            ("Basilisk ExecuteSimulation (RK4, 0.1 s)", *best_median(b_exec)),
            ("Basilisk build + Initialize + Execute", *best_median(b_total))]
    print(f"{'what':<46} {'best s':>9} {'median s':>9} {'Basilisk Exec / this':>21} {'Basilisk total / this':>22}")
    for label, best, med in rows:
        print(f"{label:<46} {best:9.4f} {med:9.4f} {rows[2][1] / best:20.1f}x {rows[3][1] / best:21.1f}x")
    st = orbatt_single.stats
    ticks = round(float(sc.times[-1]) / DT)
    print(f"orbatt: {st['steps']} steps, {st['rhs_evaluations']} right-hand sides ({st['rhs_evaluations'] / ticks:.1f} "
          f"per tick, {rows[0][1] / st['rhs_evaluations'] * 1e9:.0f} ns each); Basilisk RK4: 4 per tick, "
          f"{rows[2][1] / ticks * 1e6:.1f} us per tick with its 5 flight-software modules")
    print(f"(best of {repeats}, interleaved; Basilisk RKF78 relTol 1e-10 once: ExecuteSimulation {b78['execute_s']:.2f} s)")
    qb = b["q"]
    print("\nAgreement (largest over the 20 s outputs):")
    print(f"  orbatt rtol 1e-10 vs orbatt rtol 1e-13 (orbatt's integration)      {angle(qo, qo_tight).max():.3g} rad")
    print(f"  Basilisk RK4 0.1 s vs Basilisk RKF78 relTol 1e-10 (its integration) {angle(qb, b78['q']).max():.3g} rad")
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
    return {"exec_ratio": rows[2][1] / rows[0][1], "total_ratio": rows[3][1] / rows[1][1]}


def part_mc(t_end, samples, bsk_cases, repeats):
    import orbatt
    from orbatt.sweep import load_sweep

    cores = os.cpu_count() or 1
    folder = Path(tempfile.mkdtemp(prefix="orbatt-fsw-mc-"))
    path = folder / "lvlh-hold-wheels-fsw-mc.toml"
    path.write_text(scenario_text(t_end, samples))
    sweep = load_sweep(path)
    print(f"\n## B. Monte Carlo: {samples} cases, initial rates uniform in +-1 deg/s, {t_end:g} s each; "
          f"Basilisk: {bsk_cases} of the same cases one after the other in this process, scaled to {samples}; "
          f"{cores} cores\n")
    w = time.perf_counter()
    ds = sweep.compute()                          # compile / load
    print(f"(warm-up: first compute {time.perf_counter() - w:.1f} s)")
    cases = []
    for k in range(bsk_cases):
        p = folder / f"case{k}.toml"
        p.write_text(sweep.case_text(k))
        cases.append(orbatt.load_scenario(p))
    t_comp, t_sweep, t_bsk, res = [], [], [], {}
    half = (bsk_cases + 1) // 2
    for rep in range(repeats):
        print(f"  repeat {rep}: load {os.getloadavg()[0]:.2f}", flush=True)
        w = time.perf_counter()
        ds = sweep.compute()
        t_comp.append(time.perf_counter() - w)
        w = time.perf_counter()
        ds2 = orbatt.run_sweep(path)
        t_sweep.append(time.perf_counter() - w)
        if rep < 2:                               # Basilisk: two halves, interleaved with orbatt
            chunk = range(0, half) if rep == 0 else range(half, bsk_cases)
            for k in chunk:
                b = basilisk_case(cases[k])
                res[k] = b
                t_bsk.append(b["total_s"])
    per_case = sum(t_bsk) / len(t_bsk)
    exec_case = sum(res[k]["execute_s"] for k in res) / len(res)
    projected = per_case * samples
    rows = [("orbatt load_sweep().compute() (in-process)", *best_median(t_comp)),
            ("orbatt.run_sweep(path) (scheduler by the work)", *best_median(t_sweep))]
    print(f"{'what':<50} {'best s':>9} {'median s':>9} {'per case ms':>12} {'vs Basilisk serial':>19} "
          f"{'vs serial / cores':>18}")
    for label, best, med in rows:
        print(f"{label:<50} {best:9.2f} {med:9.2f} {best / samples * 1e3:12.2f} {projected / best:18.0f}x "
              f"{projected / cores / best:17.0f}x")
    print(f"{'Basilisk, case after case (projected)':<50} {projected:9.1f} {'':>9} {per_case * 1e3:12.1f} "
          f"{'1':>18}x {'':>18}")
    print(f"(Basilisk per case: build + Initialize + Execute {per_case:.3f} s, ExecuteSimulation alone "
          f"{exec_case:.3f} s, mean of {len(t_bsk)}; 'serial / cores': a perfect pool of {cores} processes; "
          f"orbatt best of {repeats})")
    qf = np.asarray(ds["q_final"].transpose("case", ...).values)
    d = np.array([angle(qf[k], res[k]["q"][-1])[0] for k in res])
    same = [np.array_equal(np.asarray(ds[v].values), np.asarray(ds2[v].values)) for v in ("q_final", "max_pointing_error")]
    print(f"Agreement: final attitude, orbatt vs Basilisk, {len(d)} cases: largest {math.degrees(d.max()):.3g} deg, "
          f"median {math.degrees(np.median(d)):.3g} deg; compute() and run_sweep() bitwise equal: {all(same)}")
    print(f"  max pointing error over the run (orbatt) across cases: "
          f"{np.degrees(np.asarray(ds['max_pointing_error'].values)).min():.3g} - "
          f"{np.degrees(np.asarray(ds['max_pointing_error'].values)).max():.3g} deg")
    return projected / min(t_sweep + t_comp)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1/4 orbit, 100 cases, 8 Basilisk cases")
    ap.add_argument("--only", choices=("a", "b"), help="run one part")
    args = ap.parse_args(argv)
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
        part_mc(t_end, 100 if args.quick else 500, 8 if args.quick else 20, 2)
    print(f"\nload at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()

"""The fine-pointing loop as flown (issue 33, item 6): noisy gyro and star tracker, an attitude
filter, a PD law on the estimate driving three reaction wheels, one orbit, against the closest
loop Basilisk 2.12 ships; one run and a Monte Carlo.

    python benchmarks/basilisk_fine_pointing.py           # 1,000 cases of one orbit (~25 min, 2 busy cores)
    python benchmarks/basilisk_fine_pointing.py --quick   # 1/8 orbit, 40 + 4 cases (under 2 minutes, warm cache)

Prints tables of ratios against baselines measured in the same run, interleaved (no number is
quoted from elsewhere), and the machine's load (``os.getloadavg()``). Results:
``benchmarks/README.md``, section "Fine pointing (sensors + filter + PD on wheels) against
Basilisk" (the scenario: the docstring below).

The loop: the text that ``tests/control/test_navigation.py::_fine_pointing_text`` builds
(``scenarios/cubesat-slew-wheels.toml``: a 6U, inertia diag(0.13, 0.11, 0.05) kg m2, three
wheels on the body axes, 2e-5 kg m2, 2e-3 N m, 6000 rpm, 10 Hz PD, kp = 4e-3 N m, kd = 1.4e-2
N m s, 550 km SSO, gravity gradient; plus a gyro at 10 Hz, ARW 0.15 deg/sqrt(h), RRW 0.3
deg/h^1.5, bias (5, -3, 2) deg/h, a star tracker at 1 Hz, 10 arcsec per axis, and the MEKF,
attitude_sigma 0.1 deg, bias_sigma 10 deg/h) with the initial attitude set to the target (90 deg
about body axis 3): an inertial hold for one orbit (5,677 s), outputs every second. Not the
shipped ``scenarios/cubesat-fine-pointing.toml``: it adds drag, solar pressure, a residual
dipole, a star tracker misalignment and exclusions, none of which the Basilisk loop here has.

* orbatt: ``Scenario.run()`` (propagate + Dataset); its sensors, MEKF and law run in the
  compiled kernel at the ticks (docs/design.md §14).
* Basilisk: ``spacecraft`` (hub = orbatt's inertia, 12 kg) + ``reactionWheelStateEffector``
  (BalancedWheels, same axes, Js, limits) + ``GravityGradientEffector``, point-mass Earth with
  orbatt's GM and the same elements; RK4 at 0.1 s (its default). Three tasks of one process, in
  this order at each time: dynamics (wheels read the command, the hub integrates to t), a 1 Hz
  sensor task (``starTracker``: white noise, 10 arcsec per axis as a rotation vector; ``stComm``)
  and the 10 Hz flight software: ``imuSensor`` (white rate noise sigma_v / sqrt(dt) per sample
  = the ARW, the constant bias ``senRotBias``; its error model is one Gauss-Markov process per
  axis, white *or* a random walk, so the RRW, 0.38 deg/h of drift over the orbit, is left out),
  a 20-line Python module that copies the IMU's rate into the ``AccDataMsg`` gyro buffer that
  ``inertialUKF`` reads (no Basilisk module writes that message from an IMU; its time is
  reported), ``inertialUKF``, ``inertial3D`` (the same target), ``attTrackingError``,
  ``mrpFeedback`` (K = 2 kp, P = kd, Ki = -1: no integral; -K sigma = -kp Im(q_e) to first
  order), ``rwMotorTorque``. Zero-order hold of the command on both sides. ``inertialUKF``
  writes nothing before its first star tracker sample with a time tag > 0 (t = 1 s): its output
  message is written before the run with the true initial attitude and rate (orbatt's MEKF
  starts 0.1 deg off, with the gyro's rate).

The filters differ (said in the README too). orbatt's MEKF: error state (attitude, gyro bias),
propagated with the gyro (``w_meas - b_hat``) at every 0.1 s tick, star tracker updates at 1 Hz;
the law gets ``q_hat`` and ``w_meas - b_hat``. Basilisk's ``inertialUKF`` (the attitude filter
of bsk 2.12 that takes a star tracker and a gyro; ``okeefeEKF``, ``sunline*`` and
``headingSuKF`` take Sun sensors): a square-root UKF on (MRP, body rate), no gyro bias state; it
propagates its state with Euler's equations and the wheels' speed changes (no gravity gradient)
from one star tracker time to the next in a single Euler step, and updates with the star tracker;
between star tracker samples its output attitude is propagated with the raw gyro samples (bias
included) and its output rate is the gyro through its low-pass filter (set here to a two-sample
mean, ``omegCutoff = 2 / dt``, the nearest to orbatt's unfiltered rate). So Basilisk's law sees a
rate biased by the gyro bias 9 ticks in 10; orbatt's sees the bias estimate removed. Both sides'
pointing error (APE, 0.9973, temporal: ``orbatt.pointing.index_value``) and knowledge error (AKE
and rms) are printed; they are not expected to be equal.

The Monte Carlo: the same scenario with ``[sweep]``: initial rates uniform in +-0.01 deg/s per
axis; each case draws its own sensor noise (orbatt: the case word; Basilisk: ``Controller``'s
seed dispersion of every module's ``RNGSeed``). orbatt: a whole ``orbatt sweep`` process (the
scheduler chosen by the work; outputs ``ape``, ``ake``, ``final_state``) and
``load_sweep(path).compute()`` in this process. Basilisk: ``Basilisk.utilities.MonteCarlo.
Controller`` (works offline; from a fresh process: forking one where numba has started threads
can hang its workers) with 2 worker processes, a retention function returning each case's
APE and AKE, on a subset of the cases, scaled linearly to N; and its per-case build + Initialize
+ Execute in this process (what each worker does, without the pool). Controller's worker sleeps
1 s after queueing each case's retained data (``time.sleep(1)`` in ``SimulationExecutor``): part
of what a user of it waits for, reported as such.
"""
from __future__ import annotations

import argparse
import ctypes
import functools
import json
import math
import os
import re
import shutil
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
BASE = ROOT / "scenarios" / "cubesat-slew-wheels.toml"
DT = 0.1                 # s, the flight software's rate, the gyro's, Basilisk's task step
ST_PERIOD = 1.0          # s, the star tracker's
OUT_STEP = 1.0           # s, outputs compared
CONFIDENCE = 0.9973
UKF_Q_NOISE = [1e-10] * 3 + [1e-10] * 3
RATE_SPREAD_DEG = 0.01   # deg/s, the Monte Carlo's initial-rate dispersion (uniform, per axis)
SENSORS = '''
[sensors]
seed = 20261128

[sensors.gyro]
rate = "10 Hz"
arw = "0.15 deg/sqrt(h)"
rrw = "0.3 deg / h(3/2)"
bias = ["5 deg/h", "-3 deg/h", "2 deg/h"]

[sensors.star_tracker]
rate = "1 Hz"
noise = "10 arcsec"

[estimator]
kind = "mekf"
attitude_sigma = "0.1 deg"
bias_sigma = "10 deg/h"
'''


def scenario_text(t_end, samples=None):
    """The fine-pointing scenario (the slew on wheels with the sensors and the MEKF and the
    initial attitude on the target), ``t_end`` seconds, outputs every second; with ``samples``,
    a ``[sweep]`` over the initial rates."""
    text = BASE.read_text().replace('period = "0.1 s"\n', 'period = "0.1 s"\n' + SENSORS, 1)
    target = re.search(r"target_q = (\[[^\]]*\])", text).group(1)
    text = re.sub(r'(\[initial\][^\[]*?)q = \[[^\]]*\]', lambda m: f"{m.group(1)}q = {target}", text, count=1)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end:g} s"', text)
    text = re.sub(r'output_step = "[^"]*"', f'output_step = "{OUT_STEP:g} s"', text)
    if samples:
        text += (f'\n[sweep]\nsamples = {samples}\nseed = 20261203\noutputs = ["ape", "ake", "final_state"]\n'
                 f'confidence = {CONFIDENCE}\n\n[sweep.parameters]\n'
                 + "".join(f'omega{i} = {{ distribution = "uniform", low = "-{RATE_SPREAD_DEG} deg/s", '
                           f'high = "{RATE_SPREAD_DEG} deg/s" }}\n' for i in (1, 2, 3)))
    return text


def setup(sc):
    """The plain numbers both sides need, from the loaded orbatt scenario ``sc``."""
    c = sc.spec.control["control"]
    nav = sc.potential.control.navigation
    el = sc.orbit.elements
    return dict(
        kp=float(c["kp"]), kd=float(c["kd"]),
        target=np.asarray(c["target_q"], dtype=float),
        inertia=np.asarray(sc.spec.inertia, dtype=float) * 1e6,                 # kg km2 -> kg m2
        gm=float(sc.orbit.gm) * 1e9,
        elements=(el["a"] * 1e3, el["e"], el["i"], el["raan"], el["argp"], el["true_anomaly"]),
        q0=np.asarray(sc.state0.q, dtype=float),
        omega0=np.asarray(getattr(sc.state0.omega, "value", sc.state0.omega), dtype=float),
        wheels=[(list(map(float, w.axis)), w.inertia_kg_m2, w.speed_rad_s, w.max_torque_n_m, w.max_speed_rad_s)
                for w in sc.body.wheels],
        arw=nav.gyro.arw, bias=np.asarray(nav.gyro.bias, dtype=float), st_sigma=nav.star_tracker.noise,
        att_sigma=nav.estimator.attitude_sigma, bias_sigma=nav.estimator.bias_sigma,
        t_end=float(sc.times[-1]))


def angle(qa, qb):
    """Rotation angles (rad) between two quaternion series ``(N, 4)``."""
    qa, qb = np.atleast_2d(qa), np.atleast_2d(qb)
    vec = qa[:, :1] * qb[:, 1:] - qb[:, :1] * qa[:, 1:] - np.cross(qa[:, 1:], qb[:, 1:])
    return 2 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(np.sum(qa * qb, axis=-1)))


def errors_stats(t, pointing, knowledge):
    """(APE, AKE at CONFIDENCE, knowledge rms, pointing rms), rad, from the angle series."""
    from orbatt.pointing import index_value

    return (index_value("ape", t, pointing, CONFIDENCE), index_value("ake", t, knowledge, CONFIDENCE),
            float(np.sqrt(np.mean(knowledge ** 2))), float(np.sqrt(np.mean(pointing ** 2))))


def orbatt_single(sc):
    """orbatt's run: (wall s, t, pointing error, knowledge error angle)."""
    w = time.perf_counter()
    ds = sc.run()
    w = time.perf_counter() - w
    target = np.asarray(sc.spec.control["control"]["target_q"], dtype=float)
    pe = angle(np.asarray(ds["q"].values), target[None, :])
    ke = np.linalg.norm(np.asarray(ds["knowledge_error"].values), axis=1)
    return w, np.asarray(sc.times, dtype=float), pe, ke


# -- Basilisk ---------------------------------------------------------------------------------

class _Packet(ctypes.Structure):
    """Basilisk's ``AccPktDataMsgPayload`` (56 bytes): the first slot of ``AccDataMsgPayload``."""
    _fields_ = [("measTime", ctypes.c_uint64), ("gyro_B", ctypes.c_double * 3), ("accel_B", ctypes.c_double * 3)]


def _gyro_bridge_class():
    """A Python module copying the IMU's rate into the gyro buffer ``inertialUKF`` reads: one
    sample in slot 0 (the filter stops at the next, empty slot), written in place through
    ctypes (assigning SWIG's ``accPkts`` list copies all 120 slots: 57 us a tick)."""
    from Basilisk.architecture import messaging, sysModel

    class GyroBuffer(sysModel.SysModel):
        def __init__(self):
            super().__init__()
            self.imuInMsg = messaging.IMUSensorMsgReader()
            self.accOutMsg = messaging.AccDataMsg()
            self.payload = messaging.AccDataMsgPayload()
            self.slot = _Packet.from_address(int(self.payload.this))
            self.busy_s = 0.0

        def Reset(self, CurrentSimNanos):
            self.busy_s = 0.0

        def UpdateState(self, CurrentSimNanos):
            w = time.perf_counter()
            if self.imuInMsg.isWritten():
                self.slot.measTime = CurrentSimNanos
                self.slot.gyro_B[:] = self.imuInMsg().AngVelPlatform
                self.accOutMsg.write(self.payload, CurrentSimNanos, self.moduleID)
            self.busy_s += time.perf_counter() - w

    return GyroBuffer


def basilisk_build(p, omega0=None, seeds=(11, 12), q_noise=None):
    """Build the Basilisk loop for the plain setup ``p`` (:func:`setup`); returns the sim with
    its parts as attributes (``sim.parts``)."""
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import (attTrackingError, inertial3D, inertialUKF, mrpFeedback, rwMotorTorque,
                                        stComm)
    from Basilisk.simulation import (GravityGradientEffector, imuSensor, reactionWheelStateEffector, spacecraft,
                                     starTracker)
    from Basilisk.utilities import RigidBodyKinematics as rbk
    from Basilisk.utilities import SimulationBaseClass, orbitalMotion, simIncludeGravBody, simIncludeRW

    dt_ns, st_ns = round(DT * 1e9), round(ST_PERIOD * 1e9)
    sim = SimulationBaseClass.SimBaseClass()
    proc = sim.CreateNewProcess("proc")
    proc.addTask(sim.CreateNewTask("dyn", dt_ns), 300)
    proc.addTask(sim.CreateNewTask("st", st_ns), 200)
    proc.addTask(sim.CreateNewTask("fsw", dt_ns), 100)
    s = spacecraft.Spacecraft()
    s.ModelTag = "sc"
    s.hub.mHub = 12.0
    s.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    s.hub.IHubPntBc_B = np.diag(p["inertia"]).tolist()
    grav = simIncludeGravBody.gravBodyFactory()
    earth = grav.createEarth()
    earth.isCentralBody = True
    earth.mu = p["gm"]
    grav.addBodiesTo(s)
    oe = orbitalMotion.ClassicElements()
    oe.a, oe.e, oe.i, oe.Omega, oe.omega, oe.f = p["elements"]
    r, v = orbitalMotion.elem2rv(earth.mu, oe)
    s.hub.r_CN_NInit = np.reshape(r, (3, 1)).tolist()
    s.hub.v_CN_NInit = np.reshape(v, (3, 1)).tolist()
    s.hub.sigma_BNInit = np.reshape(rbk.EP2MRP(p["q0"]), (3, 1)).tolist()
    w0 = p["omega0"] if omega0 is None else np.asarray(omega0, dtype=float)
    s.hub.omega_BN_BInit = np.reshape(w0, (3, 1)).tolist()
    gg = GravityGradientEffector.GravityGradientEffector()
    gg.ModelTag = "gg"
    gg.addPlanetName(earth.planetName)
    s.addDynamicEffector(gg)
    factory = simIncludeRW.rwFactory()
    for axis, js, speed, umax, smax in p["wheels"]:
        factory.create("custom", axis, Js=js, Omega=speed * 60 / (2 * math.pi), RWModel=messaging.BalancedWheels,
                       useMaxTorque=True, u_max=umax, Omega_max=smax * 60 / (2 * math.pi))
    rw = reactionWheelStateEffector.ReactionWheelStateEffector()
    rw.ModelTag = "rw"
    factory.addToSpacecraft("sc", rw, s)
    rw_params = factory.getConfigMessage()

    st = starTracker.StarTracker()
    st.ModelTag = "starTracker"
    st.RNGSeed = seeds[0]
    st.scStateInMsg.subscribeTo(s.scStateOutMsg)
    st.PMatrix = (np.eye(3) * p["st_sigma"]).tolist()           # rotation-vector noise, rad per axis
    st.setAMatrix(np.zeros((3, 3)).tolist())                    # white
    st.setWalkBounds([1e9, 1e9, 1e9])
    stc = stComm.stComm()
    stc.ModelTag = "stComm"
    stc.dcm_BP = np.eye(3).ravel().tolist()
    stc.stSensorInMsg.subscribeTo(st.sensorOutMsg)

    imu = imuSensor.ImuSensor()
    imu.ModelTag = "imu"
    imu.RNGSeed = seeds[1]
    imu.scStateInMsg.subscribeTo(s.scStateOutMsg)
    imu.PMatrixGyro = (np.eye(3) * p["arw"] / math.sqrt(DT)).tolist()    # white: the ARW per sample
    imu.setAMatrixGyro(np.zeros((3, 3)).tolist())
    imu.setErrorBoundsGyro([1e9, 1e9, 1e9])
    imu.senRotBias = p["bias"].tolist()
    bridge = _gyro_bridge_class()()
    bridge.ModelTag = "gyroBuffer"
    bridge.imuInMsg.subscribeTo(imu.sensorOutMsg)

    vehicle = messaging.VehicleConfigMsgPayload()
    vehicle.ISCPntB_B = np.diag(p["inertia"]).ravel().tolist()
    vehicle_msg = messaging.VehicleConfigMsg().write(vehicle)
    ukf = inertialUKF.inertialUKF()
    ukf.ModelTag = "inertialUKF"
    ukf.alpha, ukf.beta, ukf.kappa, ukf.switchMag = 0.02, 2.0, 0.0, 1.2
    st_data = inertialUKF.STMessage()
    r_mrp = (p["st_sigma"] / 4) ** 2                            # MRP ~ angle / 4
    st_data.noise = (np.eye(3) * r_mrp).ravel().tolist()
    ukf.STDatasStruct.STMessages = [st_data]
    ukf.STDatasStruct.numST = 1
    ukf.STDatasStruct.STMessages[0].stInMsg.subscribeTo(stc.stAttOutMsg)
    ukf.stateInit = list(rbk.EP2MRP(p["q0"])) + [0.0, 0.0, 0.0]
    rate_sigma = math.radians(RATE_SPREAD_DEG)
    ukf.covarInit = np.diag([(p["att_sigma"] / 4) ** 2] * 3 + [rate_sigma ** 2] * 3).ravel().tolist()
    qn = np.diag(UKF_Q_NOISE if q_noise is None else q_noise)
    ukf.qNoise = qn.ravel().tolist()
    lp = inertialUKF.LowPassFilterData()
    lp.hStep, lp.omegCutoff = DT, 2.0 / DT
    ukf.gyroFilt = [lp, lp, lp]
    ukf.massPropsInMsg.subscribeTo(vehicle_msg)
    ukf.rwParamsInMsg.subscribeTo(rw_params)
    ukf.rwSpeedsInMsg.subscribeTo(rw.rwSpeedOutMsg)
    ukf.gyrBuffInMsg.subscribeTo(bridge.accOutMsg)

    ref = inertial3D.inertial3D()
    ref.ModelTag = "inertial3D"
    ref.sigma_R0N = list(rbk.EP2MRP(p["target"]))
    err = attTrackingError.attTrackingError()
    err.ModelTag = "attTrackingError"
    err.attNavInMsg.subscribeTo(ukf.navStateOutMsg)
    err.attRefInMsg.subscribeTo(ref.attRefOutMsg)
    ctrl = mrpFeedback.mrpFeedback()
    ctrl.ModelTag = "mrpFeedback"
    ctrl.K, ctrl.P, ctrl.Ki = 2 * p["kp"], p["kd"], -1.0
    ctrl.guidInMsg.subscribeTo(err.attGuidOutMsg)
    ctrl.vehConfigInMsg.subscribeTo(vehicle_msg)
    motor = rwMotorTorque.rwMotorTorque()
    motor.ModelTag = "rwMotorTorque"
    motor.controlAxes_B = np.eye(3).ravel().tolist()
    motor.rwParamsInMsg.subscribeTo(rw_params)
    motor.vehControlInMsg.subscribeTo(ctrl.cmdTorqueOutMsg)
    rw.rwMotorCmdInMsg.subscribeTo(motor.rwMotorTorqueOutMsg)

    for model, prio in ((rw, 100), (s, 90), (gg, 85)):
        sim.AddModelToTask("dyn", model, prio)
    for model, prio in ((st, 100), (stc, 90)):
        sim.AddModelToTask("st", model, prio)
    for model, prio in ((imu, 100), (bridge, 95), (ukf, 90), (ref, 85), (err, 80), (ctrl, 75), (motor, 70)):
        sim.AddModelToTask("fsw", model, prio)
    out_ns = round(OUT_STEP * 1e9)
    sim.rec_truth = s.scStateOutMsg.recorder(out_ns)
    sim.rec_nav = ukf.navStateOutMsg.recorder(out_ns)
    sim.AddModelToTask("fsw", sim.rec_truth, 10)
    sim.AddModelToTask("fsw", sim.rec_nav, 10)
    sim.parts = dict(grav=grav, gg=gg, rw=rw, s=s, st=st, stc=stc, imu=imu, bridge=bridge, ukf=ukf, ref=ref,
                     err=err, ctrl=ctrl, motor=motor, vehicle_msg=vehicle_msg, rw_params=rw_params,
                     factory=factory, st_data=st_data, lp=lp)
    sim.setup = p
    return sim


def basilisk_execute(sim):
    """Initialize and run ``sim`` to ``t_end``; returns the execute wall time (s)."""
    from Basilisk.architecture import messaging

    sim.InitializeSimulation()
    nav0 = messaging.NavAttMsgPayload()      # the true initial state until the filter's first star tracker sample
    nav0.sigma_BN = list(sim.parts["ukf"].stateInit[:3])
    nav0.omega_BN_B = [float(np.ravel(x)[0]) for x in sim.parts["s"].hub.omega_BN_BInit]
    sim.parts["ukf"].navStateOutMsg.write(nav0, 0, -1)
    sim.ConfigureStopTime(round(sim.setup["t_end"] / DT) * round(DT * 1e9))
    w = time.perf_counter()
    sim.ExecuteSimulation()
    return time.perf_counter() - w


def basilisk_errors(sim):
    """(t, pointing error, knowledge error) at the outputs, rad, from the recorders."""
    from Basilisk.utilities import RigidBodyKinematics as rbk

    t = sim.rec_truth.times() * 1e-9
    qt = np.array([rbk.MRP2EP(x) for x in sim.rec_truth.sigma_BN])
    qn = np.array([rbk.MRP2EP(x) for x in sim.rec_nav.sigma_BN])
    return t, angle(qt, sim.setup["target"][None, :]), angle(qt, qn)


def basilisk_case(p, omega0=None, seeds=(11, 12), q_noise=None):
    """One whole case: build, initialize, execute. A dict of times and errors."""
    w = time.perf_counter()
    sim = basilisk_build(p, omega0, seeds, q_noise)
    execute_s = basilisk_execute(sim)
    total_s = time.perf_counter() - w
    t, pe, ke = basilisk_errors(sim)
    return dict(t=t, pe=pe, ke=ke, execute_s=execute_s, total_s=total_s, bridge_s=sim.parts["bridge"].busy_s)


# -- Basilisk's Monte Carlo Controller (module-level functions: pickled by reference) --------

def mc_create(p):
    sim = basilisk_build(p)
    sim.omega1 = sim.omega2 = sim.omega3 = 0.0
    return sim


def mc_execute(sim):
    sim.parts["s"].hub.omega_BN_BInit = [[sim.omega1], [sim.omega2], [sim.omega3]]
    basilisk_execute(sim)


def mc_retain(sim):
    t, pe, ke = basilisk_errors(sim)
    ape, ake, krms, _ = errors_stats(t, pe, ke)
    return {"ape": ape, "ake": ake, "knowledge_rms": krms}


def basilisk_controller(p, cases, workers, folder):
    """Run ``cases`` cases with ``MonteCarlo.Controller`` on ``workers`` processes; returns
    (wall s, retained dicts)."""
    w = math.radians(RATE_SPREAD_DEG)
    return run_controller(functools.partial(mc_create, p), mc_execute, mc_retain, cases, workers, folder,
                          [(f"omega{i}", (-w, w)) for i in (1, 2, 3)])


def controller_process(t_end, cases, workers, folder):
    """:func:`basilisk_controller` in a fresh Python process (:func:`controller_subprocess`).
    Returns (the Controller's wall s, retained dicts)."""
    return controller_subprocess(__file__, f"{t_end:g},{cases},{workers},{folder}")


def _controller_main(arg):
    import orbatt

    t_end, cases, workers, folder = arg.split(",", 3)
    Path(folder).mkdir(parents=True, exist_ok=True)
    path = Path(folder) / "fine-pointing.toml"
    path.write_text(scenario_text(float(t_end)))
    p = setup(orbatt.load_scenario(path))
    wall, kept = basilisk_controller(p, int(cases), int(workers), Path(folder) / "mc")
    print(json.dumps({"wall": wall, "kept": kept}))


# -- the parts --------------------------------------------------------------------------------

def best_median(x):
    return min(x), statistics.median(x)


def load_line():
    return "load average %.2f %.2f %.2f" % os.getloadavg()


def part_single(t_end, repeats):
    import orbatt

    folder = Path(tempfile.mkdtemp(prefix="orbatt-fp-"))
    path = folder / "fine-pointing.toml"
    path.write_text(scenario_text(t_end))
    sc = orbatt.load_scenario(path)
    p = setup(sc)
    orbits = p["t_end"] / sc.orbit.period_value
    print(f"\n## A. One run: {p['t_end']:g} s ({orbits:.2f} orbit), flight software and gyro at {DT:g} s, star "
          f"tracker at {ST_PERIOD:g} s ({round(p['t_end'] / DT)} ticks); scenario: built from "
          f"{BASE.name}; {load_line()}\n")
    w = time.perf_counter()
    orbatt_single(sc)                             # compiles or loads the kernels
    print(f"(warm-up: first orbatt run {time.perf_counter() - w:.1f} s)")
    basilisk_case(p)                              # imports, first build
    t_run, b_exec, b_total, b_bridge = [], [], [], []
    for _ in range(repeats):                      # interleaved
        w, t, pe, ke = orbatt_single(sc)
        t_run.append(w)
        b = basilisk_case(p)
        b_exec.append(b["execute_s"])
        b_total.append(b["total_s"])
        b_bridge.append(b["bridge_s"])
    rows = [("orbatt Scenario.run() (propagate + Dataset)", *best_median(t_run)),
            ("Basilisk ExecuteSimulation", *best_median(b_exec)),
            ("Basilisk build + Initialize + Execute", *best_median(b_total))]
    print(f"{'what':<46} {'best s':>9} {'median s':>9} {'Basilisk Exec / this':>21} {'Basilisk total / this':>22}")
    for label, best, med in rows:
        print(f"{label:<46} {best:9.3f} {med:9.3f} {rows[1][1] / best:20.1f}x {rows[2][1] / best:21.1f}x")
    print(f"(best of {repeats}, interleaved; Basilisk's Python gyro-buffer module: {min(b_bridge):.3f} s of its "
          f"execute, {min(b_bridge) / round(p['t_end'] / DT) * 1e6:.1f} us per tick)")
    o = errors_stats(t, pe, ke)
    bs = errors_stats(b["t"], b["pe"], b["ke"])
    print(f"\nAccuracy over the run ({len(t)} outputs, every {OUT_STEP:g} s; arcsec; not the same filter, "
          f"not the same noise draws):")
    print(f"  {'':<10} {'APE 0.9973':>11} {'pointing rms':>13} {'AKE 0.9973':>11} {'knowledge rms':>14}")
    for label, s in (("orbatt", o), ("Basilisk", bs)):
        a = [math.degrees(x) * 3600 for x in s]
        print(f"  {label:<10} {a[0]:11.2f} {a[3]:13.2f} {a[1]:11.2f} {a[2]:14.2f}")
    half = len(t) // 2
    print(f"  second half only: orbatt APE {math.degrees(errors_stats(t[half:], pe[half:], ke[half:])[0]) * 3600:.2f}, "
          f"Basilisk APE {math.degrees(errors_stats(b['t'][half:], b['pe'][half:], b['ke'][half:])[0]) * 3600:.2f}")
    return rows[1][1] / rows[0][1]


def part_mc(t_end, samples, bsk_cases, repeats):
    import orbatt
    from orbatt.sweep import load_sweep

    cores = os.cpu_count() or 1
    folder = Path(tempfile.mkdtemp(prefix="orbatt-fp-mc-"))
    path = folder / "fine-pointing-mc.toml"
    path.write_text(scenario_text(t_end, samples))
    sweep = load_sweep(path)
    p = setup(orbatt.load_scenario(path))
    print(f"\n## B. Monte Carlo: {samples} cases of {t_end:g} s, initial rates uniform in +-{RATE_SPREAD_DEG} deg/s, "
          f"each case its own sensor noise; Basilisk: {bsk_cases} cases with MonteCarlo.Controller on {cores} "
          f"processes, scaled to {samples}; {cores} cores; {load_line()}\n")
    w = time.perf_counter()
    sweep.compute(0, 1)                           # compile / load
    print(f"(warm-up: first case {time.perf_counter() - w:.1f} s)")
    out = folder / "out.nc"
    cli = [str(Path(sys.executable).parent / "orbatt"), "sweep", str(path), "-o", str(out), "--quiet", "--yes"]
    t_comp, t_cli, t_ctrl, t_serial, loads = [], [], [], [], []
    ds = kept = None
    for rep in range(repeats):                    # interleaved
        loads.append(os.getloadavg()[0])
        print(f"  repeat {rep}: {load_line()}", flush=True)
        if out.exists():
            out.unlink()
        shutil.rmtree(str(out) + ".parts", ignore_errors=True)
        w = time.perf_counter()
        subprocess.run(cli, check=True, cwd=folder)
        t_cli.append(time.perf_counter() - w)
        w = time.perf_counter()
        ds = sweep.compute()
        t_comp.append(time.perf_counter() - w)
        wall, kept = controller_process(t_end, bsk_cases, cores, folder / f"bsk{rep}")
        t_ctrl.append(wall)
        b = basilisk_case(p, omega0=np.radians([RATE_SPREAD_DEG / 2, -RATE_SPREAD_DEG / 3, RATE_SPREAD_DEG / 4]),
                          seeds=(100 + rep, 200 + rep))
        t_serial.append(b["total_s"])
    ctrl_per_case = min(t_ctrl) / bsk_cases
    proj_ctrl = ctrl_per_case * samples
    proj_serial = min(t_serial) * samples
    rows = [("orbatt sweep (whole process, CLI)", *best_median(t_cli)),
            ("orbatt load_sweep(path).compute() (in-process)", *best_median(t_comp))]
    print(f"{'what':<48} {'best s':>9} {'median s':>9} {'cases/s':>8} {'vs Bsk Controller':>18} "
          f"{'vs Bsk serial':>14}")
    for label, best, med in rows:
        print(f"{label:<48} {best:9.2f} {med:9.2f} {samples / best:8.2f} {proj_ctrl / best:17.1f}x "
              f"{proj_serial / best:13.1f}x")
    print(f"{'Basilisk Controller, ' + str(cores) + ' processes (projected)':<48} {proj_ctrl:9.1f} {'':>9} "
          f"{1 / ctrl_per_case:8.3f} {'1':>17}x {'':>14}")
    print(f"{'Basilisk case after case, one process (projected)':<48} {proj_serial:9.1f} {'':>9} "
          f"{1 / min(t_serial):8.3f} {'':>18} {'1':>13}x")
    print(f"(Basilisk Controller: {bsk_cases} cases in {min(t_ctrl):.1f} s, best of {repeats}, incl. its 1 s sleep "
          f"per case in each worker (~{bsk_cases / cores:.0f} s of it); serial case: build + Initialize + Execute "
          f"{min(t_serial):.2f} s; loads at the repeats' starts {', '.join(f'{x:.2f}' for x in loads)})")
    ape = np.degrees(np.asarray(ds["ape"].values)) * 3600
    ake = np.degrees(np.asarray(ds["ake"].values)) * 3600
    bape = np.degrees([k["ape"] for k in kept]) * 3600
    bake = np.degrees([k["ake"] for k in kept]) * 3600
    print(f"Per-case APE / AKE at {CONFIDENCE} (arcsec): orbatt over {samples} cases: APE median {np.median(ape):.2f} "
          f"(range {ape.min():.2f} - {ape.max():.2f}), AKE median {np.median(ake):.2f}; Basilisk over {bsk_cases}: "
          f"APE median {np.median(bape):.2f} ({bape.min():.2f} - {bape.max():.2f}), AKE median {np.median(bake):.2f}")
    return proj_ctrl / min(t_cli)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1/8 orbit, 40 cases, 4 Basilisk Controller cases")
    ap.add_argument("--only", choices=("a", "b"), help="run one part")
    ap.add_argument("--controller", help=argparse.SUPPRESS)      # T_END,CASES,WORKERS,FOLDER: the child
    args = ap.parse_args(argv)
    if args.controller:
        return _controller_main(args.controller)
    try:
        import Basilisk  # noqa: F401
    except ImportError:
        raise SystemExit("Basilisk is not importable: pip install bsk (the 'bench' extra)")
    print(f"orbatt fine pointing vs Basilisk ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{os.cpu_count()} CPUs, {'--quick' if args.quick else 'default'}); {load_line()}")
    t_end = 710.0 if args.quick else 5677.0
    if args.only in (None, "a"):
        part_single(t_end, 2 if args.quick else 3)
    if args.only in (None, "b"):
        part_mc(t_end, 40 if args.quick else 1000, 4 if args.quick else 8, 1 if args.quick else 1)
    print(f"\n{load_line()} at the end")


if __name__ == "__main__":
    main()

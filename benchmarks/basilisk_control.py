"""orbatt's reaction wheels and wheel-actuated PD law against Basilisk 2.12 and against a classical
gyrostat model written here.

Run from a checkout: ``python benchmarks/basilisk_control.py`` (about 30 s on 2 cores; ``--quick``
shortens both runs fourfold). Basilisk (``pip install bsk``, the ``bench`` extra) is optional:
without it only orbatt and the classical model are compared.

The spacecraft: inertia diag(12, 10, 6) kg m^2 with the rotors locked, four reaction wheels
(spin axes x, y, z and (1, 1, 1)/sqrt(3), axial moment 0.01 kg m^2), no external torque (no
gravity gradient), no motor or speed limits.

Two cases:

a. **the plant**: free wheels (no motor torque) at 300, -200, 100 and 500 rpm relative to the body
   (0.5 N m s stored, gyroscopic coupling stronger than the body's own), the body tumbling at
   ~0.5 deg/s, 3000 s;
b. **closed loop**: PD towards an inertial attitude, from 20 deg off it at 0.1 deg/s, the wheels at
   30, -20, 10 and 50 rpm, 1000 s.

The models:

* orbatt: ``PDControl("inertial", actuator="wheels")`` in ``EnvironmentTorques(gravity_gradient=
  False)``, ``dop853`` at rtol = atol 1e-12 and 1e-13 (the state's ``Q`` holds the total
  momentum, the rotors' included: with 0.5 N m s stored in the wheels against the body's 0.06,
  the body rate ``J^-1 (g - h)`` carries ~8 times the relative error of ``g``). Its law: ``tau = -kp sgn(q_e0) Im(q_e) - kd omega``, motor
  torques ``u = -A+ tau`` (``A`` the 3 x 4 matrix of spin axes), continuous in time.
* the classical model (:func:`classical_run`): the gyrostat in the textbook variables (body rate,
  rotor speeds relative to the body; Hughes ch. 3) ``J w' = -w x (I w + sum Js W_k a_k) - sum u_k
  a_k``, ``Js W_k' = u_k - Js a_k.w'``, ``q' = q (0, w) / 2``, scipy's DOP853 (rtol 1e-12), with
  either orbatt's law or Basilisk's, continuous or held over each task step (zero-order hold).
* Basilisk: ``spacecraft.Spacecraft`` (no gravity), ``reactionWheelStateEffector`` (BalancedWheels:
  the hub inertia ``IHubPntBc_B`` is then the whole spacecraft's with the rotors locked, orbatt's
  ``inertia``; the wheels add ``Js`` only through the spin dynamics), RKF78 at relTol 1e-12; for
  the closed loop ``simpleNav`` -> ``inertial3D`` -> ``attTrackingError`` -> ``mrpPD`` ->
  ``rwMotorTorque`` (the same minimum-norm distribution ``-A+``) at the task step, 0.5 s.

Basilisk's ``mrpPD`` is ``Lr = -K sigma - P omega`` for an inertial target (its feed-forward terms
vanish with ``omega_R = 0``), with the MRP ``sigma = Im(q_e) / (1 + q_e0)``. With ``K = 2 kp`` and
``P = kd`` it equals orbatt's law to first order in the error; at 20 deg the two differ by
``2 / (1 + q_e0) - 1 = 0.8 %`` in the proportional term. Basilisk also holds the command over
each task step. The script separates the three differences (integration, hold, law) with the
classical model, which can run either law either way.
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.integrate import solve_ivp

INERTIA = np.array([12.0, 10.0, 6.0])                    # kg m^2, rotors locked, principal axes
AXES = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
AXES = AXES / np.linalg.norm(AXES, axis=1)[:, None]
JS = 0.01                                                 # kg m^2, axial moment of each rotor
RPM = 2 * math.pi / 60
KP, KD = 2e-3, 0.16                                       # N m, N m s (Basilisk: K = 2 kp, P = kd)
DT = 0.5                                                  # s, Basilisk's task step (closed loop)
Q_TARGET = np.array([0.9, 0.1, -0.3, 0.3])
Q_TARGET = Q_TARGET / np.linalg.norm(Q_TARGET)
PINV = np.linalg.pinv(AXES.T)                             # (4, 3): u = -PINV @ tau


def qmul(a, b):
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return np.array([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0])


def axis_angle(axis, angle):
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * a])


#: the cases: (initial attitude, body rate rad/s, rotor speeds relative to the body rad/s, span s,
#: controlled)
CASES = {
    "plant": (qmul(Q_TARGET, axis_angle([0.3, -0.5, 0.8], 0.7)), np.deg2rad([0.3, -0.25, 0.35]),
              np.array([300.0, -200.0, 100.0, 500.0]) * RPM, 3000.0, False),
    "closed loop": (qmul(Q_TARGET, axis_angle([1.0, 2.0, -1.0], math.radians(20.0))), np.deg2rad([0.05, -0.08, 0.03]),
                    np.array([30.0, -20.0, 10.0, 50.0]) * RPM, 1000.0, True),
}


def conj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def torque(q, w, law):
    """The commanded body torque (N m) at the attitude ``q`` and body rate ``w``: orbatt's
    quaternion law or Basilisk's MRP law (``mrpPD``, K = 2 kp)."""
    qe = qmul(conj(Q_TARGET), q)
    if qe[0] < 0:
        qe = -qe
    if law == "quaternion":
        return -KP * qe[1:] - KD * w
    return -2 * KP * qe[1:] / (1 + qe[0]) - KD * w


def classical_run(t_out, case, law="quaternion", hold=None, rtol=1e-12):
    """The classical gyrostat (module docstring): quaternions ``(N, 4)`` and rotor speeds relative
    to the body ``(N, 4)`` at ``t_out``; ``law`` None for free wheels; ``hold``: the command held
    over steps of that many seconds (computed at each step's start)."""
    q0, w0, speed0, _, _ = CASES[case]
    J = np.diag(INERTIA) - JS * AXES.T @ AXES

    def rhs(_, y, u):
        q, w, W = y[:4], y[4:7], y[7:]
        if u is None:
            u = np.zeros(4) if law is None else -PINV @ torque(q / np.linalg.norm(q), w, law)
        wd = np.linalg.solve(J, -np.cross(w, INERTIA * w + JS * W @ AXES) - u @ AXES)
        return np.concatenate([0.5 * qmul(q, np.concatenate([[0.0], w])), wd, u / JS - AXES @ wd])

    y0 = np.concatenate([q0, w0, speed0])
    if hold is None:
        sol = solve_ivp(rhs, (0.0, t_out[-1]), y0, method="DOP853", t_eval=t_out, rtol=rtol, atol=rtol * 1e-3,
                        args=(None,))
        Y = sol.y.T
    else:
        n = int(round(t_out[-1] / hold))
        Y, y = [y0], y0
        for k in range(n):
            u = -PINV @ torque(y[:4] / np.linalg.norm(y[:4]), y[4:7], law)
            y = solve_ivp(rhs, (k * hold, (k + 1) * hold), y, method="DOP853", rtol=rtol, atol=rtol * 1e-3,
                          args=(u,)).y[:, -1]
            Y.append(y)
        Y = np.array(Y)[np.round(np.asarray(t_out) / hold).astype(int)]
    return Y[:, :4] / np.linalg.norm(Y[:, :4], axis=1)[:, None], Y[:, 7:]


def orbatt_run(t_out, case, rtol=1e-12):
    """orbatt's quaternions, rotor speeds relative to the body (rad/s), and the wall time of
    ``propagate`` (s)."""
    import astropy.units as u

    import orbatt
    from orbatt import canonical as cn

    q0, w0, speed0, t_end, controlled = CASES[case]
    wheels = [orbatt.ReactionWheel(a, JS * u.kg * u.m**2, s * u.rad / u.s) for a, s in zip(AXES, speed0)]
    body = orbatt.RigidBody(INERTIA * u.kg * u.m**2, wheels=wheels)
    s0 = orbatt.State.from_omega(body, q0, w0 * u.rad / u.s)
    if controlled:
        orbit = orbatt.KeplerOrbit(7000 * u.km, 0.0, 0 * u.deg, 0 * u.deg, 0 * u.deg)
        pd = orbatt.PDControl("inertial", kp=f"{KP} N m", kd=f"{KD} N m s", actuator="wheels", target_q=Q_TARGET)
        potential = orbatt.EnvironmentTorques(orbit, t_end * u.s, gravity_gradient=False, control=pd)
    else:
        potential = orbatt.TorqueFree()
    orbatt.propagate(body, s0, potential, t_out[:2], method="dop853", rtol=rtol, atol=rtol)   # compiled
    w = time.perf_counter()
    tr = orbatt.propagate(body, s0, potential, t_out, method="dop853", rtol=rtol, atol=rtol)
    wall = time.perf_counter() - w
    g = cn.body_momentum(tr.q, tr.Q) * 1e6                          # N m s
    h = tr.wheel_momenta * 1e6
    omega = np.linalg.solve(np.diag(INERTIA) - JS * AXES.T @ AXES, (g - h @ AXES).T).T
    return tr.q, h / JS - omega @ AXES.T, wall


def basilisk_run(t_out, case, dt=DT, tol=1e-12):
    """Basilisk's quaternions, rotor speeds (rad/s) at ``t_out`` (multiples of ``dt``) and the
    time spent in ``ExecuteSimulation`` (s)."""
    from Basilisk.architecture import messaging
    from Basilisk.fswAlgorithms import attTrackingError, inertial3D, mrpPD, rwMotorTorque
    from Basilisk.simulation import reactionWheelStateEffector, simpleNav, spacecraft, svIntegrators
    from Basilisk.utilities import RigidBodyKinematics as rbk
    from Basilisk.utilities import SimulationBaseClass, simIncludeRW

    q0, w0, speed0, t_end, controlled = CASES[case]
    sim = SimulationBaseClass.SimBaseClass()
    sim.CreateNewProcess("proc").addTask(sim.CreateNewTask("task", round(dt * 1e9)))
    sc = spacecraft.Spacecraft()
    sc.ModelTag = "sc"
    sc.hub.mHub = 100.0
    sc.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    sc.hub.IHubPntBc_B = np.diag(INERTIA).tolist()     # BalancedWheels: the rotors add no mass properties
    sc.hub.r_CN_NInit = [[7.0e6], [0.0], [0.0]]
    sc.hub.v_CN_NInit = [[0.0], [7.5e3], [0.0]]
    sc.hub.sigma_BNInit = np.reshape(rbk.EP2MRP(q0), (3, 1)).tolist()
    sc.hub.omega_BN_BInit = np.reshape(w0, (3, 1)).tolist()
    integrator = svIntegrators.svIntegratorRKF78(sc)
    integrator.relTol, integrator.absTol = tol, tol * 1e-3
    sc.setIntegrator(integrator)
    factory = simIncludeRW.rwFactory()
    for a, s in zip(AXES, speed0):
        factory.create("custom", a.tolist(), Js=JS, Omega=float(s / RPM), RWModel=messaging.BalancedWheels,
                       useMaxTorque=False)
    rw = reactionWheelStateEffector.ReactionWheelStateEffector()
    rw.ModelTag = "rw"
    factory.addToSpacecraft("sc", rw, sc)
    # within a task step: the wheels read the command, the spacecraft integrates, then the FSW
    # computes the next command from the new state (a zero-order hold without delay)
    sim.AddModelToTask("task", rw, 100)
    sim.AddModelToTask("task", sc, 90)
    keep = []
    if controlled:
        nav = simpleNav.SimpleNav()
        nav.scStateInMsg.subscribeTo(sc.scStateOutMsg)
        ref = inertial3D.inertial3D()
        ref.sigma_R0N = rbk.EP2MRP(Q_TARGET).tolist()
        err = attTrackingError.attTrackingError()
        err.attNavInMsg.subscribeTo(nav.attOutMsg)
        err.attRefInMsg.subscribeTo(ref.attRefOutMsg)
        vehicle = messaging.VehicleConfigMsgPayload()
        vehicle.ISCPntB_B = np.diag(INERTIA).ravel().tolist()
        vehicle_msg = messaging.VehicleConfigMsg().write(vehicle)
        pd = mrpPD.mrpPD()
        pd.K, pd.P = 2 * KP, KD
        pd.guidInMsg.subscribeTo(err.attGuidOutMsg)
        pd.vehConfigInMsg.subscribeTo(vehicle_msg)
        motor = rwMotorTorque.rwMotorTorque()
        motor.controlAxes_B = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        rw_params = factory.getConfigMessage()
        motor.rwParamsInMsg.subscribeTo(rw_params)
        motor.vehControlInMsg.subscribeTo(pd.cmdTorqueOutMsg)
        rw.rwMotorCmdInMsg.subscribeTo(motor.rwMotorTorqueOutMsg)
        for k, model in enumerate((nav, ref, err, pd, motor)):
            sim.AddModelToTask("task", model, 80 - k)
        keep += [vehicle_msg, rw_params]
    rec = sc.scStateOutMsg.recorder()
    speeds = rw.rwSpeedOutMsg.recorder()
    sim.AddModelToTask("task", rec, 10)
    sim.AddModelToTask("task", speeds, 10)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(round(t_out[-1] / dt) * round(dt * 1e9))
    w = time.perf_counter()
    sim.ExecuteSimulation()
    wall = time.perf_counter() - w
    times = rec.times() * 1e-9
    idx = [int(np.argmin(np.abs(times - t))) for t in t_out]
    q = np.array([rbk.MRP2EP(rec.sigma_BN[i]) for i in idx])
    return q * np.sign(q[:, :1]), np.asarray(speeds.wheelSpeeds)[idx, :4], wall


def angle(qa, qb):
    """Largest rotation angle (rad) between two quaternion series ``(N, 4)``."""
    vec = qa[:, :1] * qb[:, 1:] - qb[:, :1] * qa[:, 1:] - np.cross(qa[:, 1:], qb[:, 1:])
    return float(np.max(2 * np.arctan2(np.linalg.norm(vec, axis=-1), np.abs(np.sum(qa * qb, axis=-1)))))


def pointing_error(q):
    """Rotation angle (rad) from the target, ``(N,)``."""
    qe = np.array([qmul(conj(Q_TARGET), x) for x in q])
    return 2 * np.arctan2(np.linalg.norm(qe[:, 1:], axis=1), np.abs(qe[:, 0]))


def compare(case, basilisk, quick=False):
    """Rows ``(model, reference, attitude rad, rotor speeds rad/s, wall s)`` of one case."""
    t_end = CASES[case][3] / (4 if quick else 1)
    t_out = np.arange(0.0, t_end + DT / 2, 10.0 * DT)
    controlled = CASES[case][4]
    rows = []
    w = time.perf_counter()
    qc, Wc = classical_run(t_out, case, "quaternion" if controlled else None)
    rows.append(("classical, orbatt's law" if controlled else "classical", "-", 0.0, 0.0, time.perf_counter() - w))
    for rtol in (1e-12, 1e-13):
        qo, Wo, wall = orbatt_run(t_out, case, rtol)
        rows.append((f"orbatt dop853 rtol {rtol:g}", rows[0][0], angle(qo, qc), np.abs(Wo - Wc).max(), wall))
    ref = {"orbatt": (qo, Wo), rows[0][0]: (qc, Wc)}
    if controlled:
        w = time.perf_counter()
        qm, Wm = classical_run(t_out, case, "mrp")
        rows.append(("classical, Basilisk's law", rows[0][0], angle(qm, qc), np.abs(Wm - Wc).max(),
                     time.perf_counter() - w))
        w = time.perf_counter()
        qh, Wh = classical_run(t_out, case, "mrp", hold=DT)
        name = f"classical, Basilisk's law held {DT:g} s"
        rows.append((name, "classical, Basilisk's law", angle(qh, qm), np.abs(Wh - Wm).max(), time.perf_counter() - w))
        ref[name] = (qh, Wh)
    if basilisk:
        qb, Wb, wall = basilisk_run(t_out, case)
        label = f"Basilisk RKF78 relTol 1e-12, step {DT:g} s"
        for other in ([f"classical, Basilisk's law held {DT:g} s"] if controlled else []) + [rows[0][0], "orbatt"]:
            qr, Wr = ref[other]
            rows.append((label, other, angle(qb, qr), np.abs(Wb - Wr).max(), wall))
            wall = None
        ref["Basilisk"] = (qb, Wb)
    return rows, t_out, ref


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a quarter of each span")
    args = parser.parse_args(argv)
    try:
        import Basilisk  # noqa: F401
        basilisk = True
    except ImportError:
        basilisk = False
        print("Basilisk is not importable (pip install bsk): orbatt against the classical model only")
    for case in CASES:
        rows, t_out, ref = compare(case, basilisk, args.quick)   # "orbatt": the last rtol
        print(f"\n{case} ({t_out[-1]:g} s)")
        print(f"{'model':48s} {'against':40s} {'attitude rad':>12s} {'speeds rad/s':>12s} {'wall s':>8s}")
        for name, other, a, s, wall in rows:
            print(f"{name:48s} {other:40s} {a:12.3g} {s:12.3g} {'' if wall is None else f'{wall:8.3f}':>8s}")
        if CASES[case][4]:
            for name, (q, W) in ref.items():
                e = np.rad2deg(pointing_error(q))
                print(f"  {name:46s} pointing error {e[0]:.3g} -> {e[len(e) // 2]:.3g} -> {e[-1]:.3g} deg; "
                      f"final rotor speeds {np.round(W[-1] / RPM, 3)} rpm")


if __name__ == "__main__":
    main()

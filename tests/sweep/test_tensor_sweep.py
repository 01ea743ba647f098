"""Sweeps of a scenario whose [body] inertia is a full tensor (issue 32 item 6): each case is
built in the user's body frame B as its single run builds it and runs through the one boundary
(orbatt.frame_boundary), so every case equals the single run of its own scenario
(``Sweep.case_text``) bit for bit, and every body-fixed output is in B.

Oracles: the single run's Dataset (written in B) of each case's scenario: its ``q``, ``Q`` and
``omega`` bit for bit; the sweep outputs recomputed from it (the pointing error about a body
axis, the APE to the law's target, the largest rate and torque, the wheels' total momentum
``sum_k h_k a_k`` in B, the Jacobi integral); the refusal of a sweep that varies the tensor.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

from orbatt import quaternion as qt
from orbatt.pointing import index_value
from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.sweep import Sweep, run_sweep
from orbatt.sweep.chunk import pointing_error
from orbatt.sweep_outputs import target_pointing_error

from tensor_support import tensor_slew_text

pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")

_slew = tensor_slew_text


def _sweep(text, table, seed=3):
    sw = Sweep(Scenario(parse(text + "\n[sweep]\n" + table, "tensor-sweep.toml")), seed=seed)
    assert sw.scenario.body.frame is not None  # a full tensor: run in its principal frame
    return sw, run_sweep(sw, scheduler="synchronous")


def _single(sw, k):
    """The Dataset of case ``k``'s single run, and its initial state."""
    sc = Scenario(parse(sw.case_text(k), "case.toml"))
    return sc.run(), sc.state0


def _norms(v):
    return np.sqrt(v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1] + v[..., 2] * v[..., 2])


def test_every_case_of_a_tensor_sweep_is_its_single_run_with_its_outputs_in_b():
    """Initial rates (named parameters, in B) and the initial attitude: each case's states and
    trajectory are its single run's bit for bit; max_pointing_error (body axis x of B), the
    APE, max_body_rate (max_control_torque to round-off) are recomputed bit for bit from the single run's q
    and omega (B), final_wheel_momentum is the single run's sum_k h_k a_k (B) to round-off."""
    table = '''outputs = ["final_state", "trajectory", "max_pointing_error", "ape", "final_wheel_momentum", "max_rate",
           "max_control_torque", "max_wheel_speed"]
pointing_axis = [1, 0, 0]
[sweep.parameters]
omega1 = { values = ["0.5 deg/s", "-1 deg/s"] }
omega3 = { values = ["0.2 deg/s", "2 deg/s"] }
'''
    sw, ds = _sweep(_slew(), table)
    sc = sw.scenario
    finals = set()
    for k in range(sw.cases):
        one, state0 = _single(sw, k)
        q, omega = one["q"].values, one["omega"].values
        # the initial state as the case's scenario gives it (B; the Dataset's first output went
        # through P and back), the final one the Dataset's
        for name, ref in (("q_initial", state0.q), ("Q_initial", state0.Q * 1e6), ("q_final", q[-1]),
                          ("Q_final", one["Q"].values[-1])):
            assert np.array_equal(ds[name].values[k], ref), (name, k)
        for name in ("q", "Q", "omega", "torque_control", "wheel_speed"):
            assert np.array_equal(ds[name].values[k], one[name].values), (name, k)
        finals.add(q[-1].tobytes())
        assert ds["max_pointing_error"].values[k] == np.max(pointing_error(sw.spec, q[None], None))
        err = target_pointing_error(sc.potential.control, q, None)
        assert ds["ape"].values[k] == index_value("ape", sc.times, err, sw.spec.confidence, sw.spec.stability_window)
        assert ds["max_body_rate"].values[k] == np.max(_norms(omega))
        tau = np.max(_norms(one["torque_control"].values))  # (N m: scaled before, not after, the maximum)
        assert ds["max_control_torque"].values[k] == pytest.approx(tau, rel=1e-15, abs=0)
        assert np.allclose(ds["max_wheel_speed"].values[k], np.max(np.abs(one["wheel_speed"].values), axis=0),
                           rtol=1e-12, atol=0)
        H = one["wheel_momentum"].values[-1] @ one["wheel_axis"].values  # sum_k h_k a_k, B
        assert np.abs(ds["final_wheel_momentum"].values[k] - H).max() <= 1e-13 * np.abs(H).max(), k
    assert len(finals) == 4  # the rates act
    # the initial momentum is I_B omega (B) of the case's rates, not a principal-moments one
    w0 = np.array([ds["omega1"].values[0], 0.0, ds["omega3"].values[0]])
    g0 = qt.mul(qt.conj(ds["q_initial"].values[0]), ds["Q_initial"].values[0])[1:] / 2
    rotors = sum(w.inertia_kg_m2 * w.speed_rad_s * np.asarray(w.axis) for w in sc.body.wheels)
    want = sc.body.tensor * 1e6 @ w0 + rotors  # kg m^2 (the tensor in kg km^2)
    assert np.abs(g0 - want).max() <= 1e-12 * np.abs(want).max()
    again = run_sweep(sw, scheduler="synchronous", chunk_size=1)  # chunking changes no bit
    assert np.array_equal(again["q_final"].values, ds["q_final"].values)


def test_a_tensor_sweep_of_a_gain_by_path_is_each_case_s_single_run():
    """A PD gain by its path (two models: two ensemble groups) and a rate: bitwise single runs,
    the trajectories' tensor variables the single run's; slew_time (located on the continuous
    solution, a wheeled tensor body integrated again over one output interval) lies between the
    outputs around the single run's crossing."""
    table = '''outputs = ["final_state", "trajectory", "slew_time"]
settling_angle = "70 deg"
[sweep.parameters]
"control.kd" = { values = ["1.4e-2 N m s", "8e-3 N m s"] }
omega2 = { values = ["0 deg/s", "1 deg/s"] }
'''
    sw, ds = _sweep(_slew("30 s"), table)
    slews = []
    for k in range(sw.cases):
        one, _ = _single(sw, k)
        for name in ("q", "Q", "omega", "wheel_momentum", "g"):
            assert np.array_equal(ds[name].values[k], one[name].values), (name, k)
        assert np.array_equal(ds["inertia_tensor"].values[k], one["inertia_tensor"].values)
        err = target_pointing_error(sw.scenario.potential.control, one["q"].values, None)
        t = one["elapsed"].values
        last = int(np.flatnonzero(err >= sw.spec.settling_angle)[-1])  # the slew ends between outputs
        assert t[last] < ds["slew_time"].values[k] <= t[last + 1], k
        slews.append(ds["slew_time"].values[k])
    assert slews[0] < slews[1] and slews[2] < slews[3]  # the rate-limited slew: a stiffer rate loop is sooner


def test_each_case_of_a_tensor_sweep_with_sensors_draws_its_own_noise_as_its_single_run():
    """A gyro, a star tracker and the MEKF: each case runs alone with its noise (the case word)
    and equals its single run (whose scenario says its case) bit for bit, the AKE the single
    run's knowledge error (B) summarized."""
    table = '''outputs = ["final_state", "ake"]
[sweep.parameters]
omega1 = { values = ["0.5 deg/s", "-0.5 deg/s"] }
'''
    sw, ds = _sweep(_slew("10 s", sensors=True), table)
    akes = []
    for k in range(sw.cases):
        one, _ = _single(sw, k)
        assert np.array_equal(ds["q_final"].values[k], one["q"].values[-1]), k
        e = one["knowledge_error"].values
        assert ds["ake"].values[k] == index_value("ake", sw.scenario.times, e, sw.spec.confidence, sw.spec.stability_window), k
        akes.append(ds["ake"].values[k])
    assert akes[0] != akes[1]


def test_the_jacobi_integral_of_a_tensor_sweep_is_conserved_and_the_single_run_s():
    """The gravity gradient on a circular orbit without control: the Jacobi integral (T + U -
    n h.G), evaluated in the principal frame, is conserved (a principal-moments formula applied
    to B's momentum would drift) and equals the single run's (its Dataset's energy and G)."""
    text = '''name = "tensor-gg"
[body]
inertia = [["0.10 kg m2", "0.004 kg m2", "-0.003 kg m2"], ["0.004 kg m2", "0.12 kg m2", "0.002 kg m2"],
           ["-0.003 kg m2", "0.002 kg m2", "0.05 kg m2"]]
[initial]
frame = "orbital"
q = [1.0, 0.0, 0.0, 0.0]
omega = ["0.01 deg/s", "0.0 deg/s", "0.02 deg/s"]
[potential]
kind = "gravity-gradient"
[orbit]
provider = "kepler"
central_body = "earth"
a = "6778 km"
e = 0.0
i = "51.6 deg"
raan = "30 deg"
argp = "0 deg"
true_anomaly = "0 deg"
[integration]
method = "dop853"
rtol = 1e-12
atol = 1e-12
t_end = "1800 s"
output_step = "300 s"
'''
    table = '''outputs = ["final_state", "final_energy_error"]
[sweep.parameters]
omega1 = { values = ["0.01 deg/s", "0.05 deg/s"] }
omega2 = { values = ["0.0 deg/s", "-0.03 deg/s"] }
'''
    sw, ds = _sweep(text, table)
    orbit = sw.scenario.orbit
    h = qt.rotate(orbit.orbital_quaternion(np.array(0.0)), np.array([0.0, 0.0, 1.0]))
    n = orbit.n_value  # rad/s
    for k in range(sw.cases):
        one, _ = _single(sw, k)
        assert np.array_equal(ds["Q_final"].values[k], one["Q"].values[-1]), k
        J = one["energy"].values - n * (one["G"].values @ h)  # J, kg m^2 s^-2
        want = (J[-1] - J[0]) / abs(J[0])
        got = ds["final_energy_error"].values[k]
        assert abs(got) < 1e-10, (k, got)
        assert abs(got - want) < 1e-11, (k, got, want)


@pytest.mark.parametrize("param", ['inertia2 = { values = ["0.12 kg m2"] }',
                                   '"body.inertia[3]" = { values = ["0.004 kg m2"] }'])
def test_a_sweep_of_the_tensor_itself_is_refused(param):
    """The tensor's moments or entries vary: the cases would have different principal frames."""
    text = _slew() + '\n[sweep]\n[sweep.parameters]\n' + param + '\n'
    with pytest.raises(ScenarioError, match=r"\[sweep\] .*inertia.*tensor.*different principal frames"):
        parse(text, "tensor-sweep.toml")


def test_a_tensor_sweep_s_sun_pointing_error_is_the_angle_of_the_body_axis_to_the_sun():
    """Body axis 3 of B (not a principal axis) pointed at the Sun: the law's own error, which
    the kernel computes in P, is the angle between that body axis and the single run's Sun
    direction turned into B; the law brings the axis onto the Sun."""
    text = _slew("200 s").replace('target = "inertial"\ntarget_q = [0.7071067811865476, 0.0, 0.0, '
                                  '0.7071067811865476]   # 90 deg about body axis 3\n',
                                  'target = "sun"\ntarget_axis = [0.0, 0.0, 1.0]\n', 1)
    text = text.replace("[orbit]\n", '[orbit]\nepoch = "2026-03-20T12:00:00Z"\n', 1)
    text = re.sub(r'output_step = "[^"]*"', 'output_step = "5 s"', text)
    assert 'target = "sun"' in text
    sw, ds = _sweep(text, 'outputs = ["final_state", "ape"]\n[sweep.parameters]\n'
                          'omega1 = { values = ["0.2 deg/s", "-0.1 deg/s"] }\n')
    axis = np.array([0.0, 0.0, 1.0])
    for k in range(sw.cases):
        one, _ = _single(sw, k)
        assert np.array_equal(ds["q_final"].values[k], one["q"].values[-1]), k
        s = qt.rotate_inv(one["q"].values, one["sun_direction"].values)  # the Sun in B
        err = np.arctan2(_norms(np.cross(s, axis)), s @ axis)
        want = index_value("ape", sw.scenario.times, err, sw.spec.confidence, sw.spec.stability_window)
        assert ds["ape"].values[k] == pytest.approx(want, rel=1e-7, abs=1e-9), k
        assert err[-1] < np.radians(2.0), k

"""Sampled-data flight software (issue 32, item 2): a law with a ``period`` is evaluated at the
ticks ``t_k = k period`` on the state there, and its command is held until the next tick (zero-
order hold). Checked against an independent model (Euler's equations and the quaternion
kinematics with the held torque, scipy), for the held wheels' motor torques and B-dot dipole,
bitwise through pause/resume and an ensemble, and bitwise unchanged without a period."""
from __future__ import annotations

import re

import numpy as np
import pytest
from astropy import units as u
from scipy.integrate import solve_ivp

import orbatt
from orbatt import quaternion as qt
from orbatt.dataset.timeaxis import elapsed_values
from orbatt.errors import InputError, ScenarioError
from orbatt.scenario import parse
from orbatt.shipped import shipped_file

I_B = np.array([0.03, 0.04, 0.02])  # kg m^2: a 3U CubeSat
KP, KD, TMAX = 2e-4, 2e-3, 3e-5     # N m, N m s, N m: saturates at the start
TARGET = qt.normalize(np.array([0.9, 0.3, -0.2, 0.25]))


def _pd_reference(q, w):
    """The PD law as :mod:`orbatt.core.control` states it (inertial target), written again
    independently: ``q_e = q_t~ q``, ``tau = -kp sgn(q_e0) Im(q_e) - kd omega``, clipped."""
    qe = qt.mul(qt.conj(TARGET), q)
    sg = 1.0 if qe[0] >= 0 else -1.0
    return np.clip(-KP * sg * qe[1:] - KD * w, -TMAX, TMAX)


def _euler_held(q0, w0, period, t_end, times):
    """q at ``times`` of a rigid body under the PD torque held over each tick interval:
    Euler's equations ``I w' = (I w) x w + tau`` and ``q' = 1/2 q (0, w)`` integrated by scipy's
    DOP853 from tick to tick (rtol 1e-13), the torque recomputed at each tick."""
    def f(t, y, tau):
        q, w = y[:4], y[4:]
        wd = (np.cross(I_B * w, w) + tau) / I_B
        qd = 0.5 * qt.mul(q, np.concatenate([[0.0], w]))
        return np.concatenate([qd, wd])

    y = np.concatenate([q0, w0])
    out = {}
    for k in range(int(round(t_end / period))):
        a, b = k * period, (k + 1) * period
        tau = _pd_reference(y[:4], y[4:])
        sol = solve_ivp(f, (a, b), y, method="DOP853", rtol=1e-13, atol=1e-15, args=(tau,), dense_output=True)
        for t in times[(times >= a) & (times <= b)]:
            out.setdefault(float(t), sol.sol(t)[:4] if a < t < b else (y[:4] if t == a else sol.y[:4, -1]))
        y = sol.y[:, -1].copy()
    return np.array([out[float(t)] / np.linalg.norm(out[float(t)]) for t in times])


def _angle(qa, qb):
    """The rotation angle between attitudes (rad), accurate for tiny angles (not an arccos)."""
    d = qt.mul(qt.conj(np.broadcast_to(qa, np.broadcast_shapes(np.shape(qa), np.shape(qb)))), qb)
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))


def _law(period):
    return orbatt.PDControl("inertial", kp=KP * u.N * u.m, kd=KD * u.N * u.m * u.s, max_torque=TMAX * u.N * u.m,
                            target_q=TARGET, period=period)


@pytest.fixture(scope="module")
def slew():
    body = orbatt.RigidBody(I_B * u.kg * u.m**2)
    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    w0 = np.radians([1.0, -0.5, 0.8])
    state = orbatt.State.from_omega(body, q0, w0 * u.rad / u.s)
    return body, state, q0, w0


def test_zero_order_hold_matches_euler_equations_with_the_held_torque(slew):
    """A 1 s flight software slewing a CubeSat to an inertial target (saturated at first), 120 s:
    orbatt's attitude within 1e-8 rad of the independent model at every output, and far from
    the continuous law's (the hold matters)."""
    body, state, q0, w0 = slew
    period, t_end = 1.0, 120.0
    times = np.linspace(0.0, t_end, 49)  # every 2.5 s: on ticks and between them
    tr = orbatt.propagate(body, state, orbatt.TorqueFree(), times, control=_law(period * u.s), rtol=1e-12,
                          atol=1e-14)
    ref = _euler_held(q0, w0, period, t_end, times)
    err = _angle(tr.q, ref)
    assert err.max() < 1e-8, err.max()
    cont = orbatt.propagate(body, state, orbatt.TorqueFree(), times, control=_law(None), rtol=1e-12, atol=1e-14)
    assert _angle(cont.q, tr.q).max() > 1e-4  # a different loop: 1 s of lag
    assert _angle(tr.q[-1:], TARGET[None])[0] < _angle(tr.q[:1], TARGET[None])[0]  # it slews towards the target
    # the held command is the torque applied (Dataset), piecewise constant, issued at the ticks
    ds = orbatt.to_dataset(tr)
    tau = ds["torque_control"].values
    assert np.abs(tau).max() <= TMAX * (1 + 1e-12)
    on_tick = np.isclose(times % period, 0.0)
    for i in np.flatnonzero(~on_tick):  # between ticks: the command of the tick before
        k = int(times[i] // period)
        j = np.flatnonzero(np.isclose(times, k * period))
        if j.size:
            np.testing.assert_array_equal(tau[i], tau[j[0]])
    np.testing.assert_allclose(tr.command[0], _pd_reference(q0, w0) * 1e-6, rtol=0, atol=1e-22)
    # |q| = 1 and q.Q = 0 hold
    np.testing.assert_allclose(qt.norm(tr.q), 1.0, atol=1e-13)


def test_ticks_are_knots_of_the_step_loop(slew):
    """No step crosses a tick: a 0.25 s flight software makes at least one step per tick."""
    body, state, _, _ = slew
    tr = orbatt.propagate(body, state, orbatt.TorqueFree(), [0.0, 10.0], control=_law(0.25 * u.s), rtol=1e-8)
    assert tr.stats["steps"] >= 40
    free = orbatt.propagate(body, state, orbatt.TorqueFree(), [0.0, 10.0], control=_law(None), rtol=1e-8)
    assert free.stats["steps"] < 40


def test_pause_and_resume_do_not_change_a_bit(slew, monkeypatch):
    """The held command is part of the state: a run stopped every few steps (progress reports)
    gives the same bits as one that is not."""
    body, state, _, _ = slew
    times = np.linspace(0.0, 400.0, 9)
    law = _law(0.05 * u.s)
    once = orbatt.propagate(body, state, orbatt.TorqueFree(), times, control=law, rtol=1e-10)
    import orbatt.propagation as prop

    monkeypatch.setattr(prop, "CHUNK_SECONDS", 1e-9)  # after the first call: one attempt per call
    calls = []
    chunked = orbatt.propagate(body, state, orbatt.TorqueFree(), times, control=law, rtol=1e-10,
                               progress=lambda info: calls.append(info.t) or True)
    assert len(calls) > 100
    np.testing.assert_array_equal(chunked.q, once.q)
    np.testing.assert_array_equal(chunked.Q, once.Q)
    np.testing.assert_array_equal(chunked.command, once.command)


def test_an_ensemble_member_is_its_single_run_bitwise(slew):
    """dop853 runs an ensemble's members independently: each member, ticks and held commands
    included, is bitwise its own run."""
    body, _, _, _ = slew
    rng = np.random.default_rng(4)
    q = qt.normalize(rng.normal(size=(3, 4)))
    w = np.radians(rng.normal(size=(3, 3)))
    states = orbatt.State.from_omega(body, q, w * u.rad / u.s)
    times = np.linspace(0.0, 30.0, 7)
    law = _law(0.5 * u.s)
    ens = orbatt.propagate(body, states, orbatt.TorqueFree(), times, control=law, rtol=1e-10)
    for e in range(3):
        one = orbatt.propagate(body, orbatt.State.from_omega(body, q[e], w[e] * u.rad / u.s), orbatt.TorqueFree(),
                               times, control=law, rtol=1e-10)
        np.testing.assert_array_equal(ens.q[e], one.q)
        np.testing.assert_array_equal(ens.command[e], one.command)
    lanes = orbatt.propagate(body, states, orbatt.TorqueFree(), times, control=law, rtol=1e-10,
                             method="dop853-lanes", lanes=3)
    assert _angle(lanes.q, ens.q).max() < 1e-8


def _scenario(extra_control, base="lvlh-hold-wheels", t_end="300 s", output_step="0.125 s"):
    """A shipped scenario's text with ``extra_control`` added to ``[control]``, shorter."""
    text = shipped_file(base).read_text().replace("[control]\n", "[control]\n" + extra_control + "\n", 1)
    text = re.sub(r't_end = "[^"]*"', f't_end = "{t_end}"', text)
    return re.sub(r'output_step = "[^"]*"', f'output_step = "{output_step}"', text)


def test_wheels_motor_torques_are_held_between_ticks():
    """PD on wheels at 2 Hz: the wheels' motor torques change only at the ticks (outputs every
    1/8 s: four per tick interval share one command), clipped to the motors' limit."""
    sc = orbatt.Scenario(parse(_scenario('period = "0.5 s"', t_end="60 s"), "zoh-wheels.toml"))
    ds = sc.run()
    u_w = ds["wheel_torque"].values
    t = elapsed_values(ds)
    k = np.floor(t / 0.5 + 1e-9)
    for kk in np.unique(k)[:-1]:
        block = u_w[k == kk]
        np.testing.assert_array_equal(block, np.broadcast_to(block[0], block.shape))
    assert np.unique(k).size > 100
    assert np.abs(u_w).max() <= 5e-3 * (1 + 1e-12)
    assert np.abs(np.diff(u_w, axis=0)).max() > 0  # and they do change, at the ticks


def test_without_a_period_the_law_is_continuous_bitwise():
    """No ``period``: the row holds period 0 and the run is today's continuous law, bit for bit
    (the shipped reference outputs check it on every controlled scenario; here the API objects
    with period=None and without the keyword agree)."""
    body = orbatt.RigidBody(I_B * u.kg * u.m**2)
    state = orbatt.State.from_omega(body, [1.0, 0, 0, 0], np.radians([1.0, -0.5, 0.8]) * u.rad / u.s)
    a = orbatt.propagate(body, state, orbatt.TorqueFree(), [0.0, 5.0, 10.0], control=_law(None))
    law = orbatt.PDControl("inertial", kp=KP * u.N * u.m, kd=KD * u.N * u.m * u.s, max_torque=TMAX * u.N * u.m,
                           target_q=TARGET)
    b = orbatt.propagate(body, state, orbatt.TorqueFree(), [0.0, 5.0, 10.0], control=law)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.command is None and law.period is None


def test_period_is_checked_where_it_enters():
    with pytest.raises(InputError, match=r"^period: .* must be positive"):
        _law(0.0 * u.s)
    with pytest.raises(InputError, match=r"^period: .*outside"):
        _law(1e-9 * u.s)
    with pytest.raises(ScenarioError, match=r"\[control\] period"):
        parse(_scenario('period = "-1 s"'), "bad.toml")
    with pytest.raises(ScenarioError, match=r"\[control\] period"):
        parse(_scenario('period = "1 m"'), "bad.toml")
    body = orbatt.RigidBody(I_B * u.kg * u.m**2)
    state = orbatt.State.from_omega(body, [1.0, 0, 0, 0], np.radians([1.0, 0, 0]) * u.rad / u.s)
    with pytest.raises(InputError, match="flight-software period"):
        orbatt.propagate(body, state, orbatt.TorqueFree(), [0.0, 1.0], control=_law(0.1 * u.s), method="scipy-DOP853")


def test_bdot_dipole_is_held_and_still_detumbles():
    """B-dot at 1 Hz: the dipole changes only at the ticks (outputs every 0.25 s), the torque
    m x B(t) follows the field between them, and the body still loses its rate."""
    text = _scenario('period = "1 s"', base="cubesat-bdot-detumble", t_end="600 s", output_step="0.25 s")
    ds = orbatt.Scenario(parse(text, "zoh-bdot.toml")).run()
    m = ds["dipole_control"].values
    t = elapsed_values(ds)
    k = np.floor(t / 1.0 + 1e-9)
    for kk in np.unique(k)[:-1]:
        block = m[k == kk]
        np.testing.assert_array_equal(block, np.broadcast_to(block[0], block.shape))
    tau = ds["torque_control"].values
    assert np.abs(np.diff(tau[k == 5], axis=0)).max() > 0  # the field turns under the held dipole
    w = np.linalg.norm(ds["omega"].values, axis=1)
    assert w[-1] < 0.9 * w[0]
    cont = orbatt.Scenario(parse(_scenario("", base="cubesat-bdot-detumble", t_end="600 s", output_step="0.25 s"),
                                 "bdot.toml")).run()
    wc = np.linalg.norm(cont["omega"].values, axis=1)
    assert abs(w[-1] - wc[-1]) < 0.05 * wc[0]  # 1 Hz is fast against the detumbling: close to the continuous law

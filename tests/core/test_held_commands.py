"""The step loops' shortcuts for laws that hold their commands between ticks
(:mod:`orbatt.core.held_commands`): the structure-of-arrays right-hand side of a lockstep group
gives each lane its member's derivative bit for bit, and the derivative after a tick of
wheel-only laws, rewritten in its wheels' rows, is bit for bit the full evaluation."""
from __future__ import annotations

import numpy as np
import pytest

import orbatt
from orbatt.core import gyrostat as kg
from orbatt.core import held_commands as hc
from orbatt.core.control import CTL_Z0
from orbatt.core.model import KIND, P0, PD_CONTROL
from orbatt.core.potentials import WORK_SIZE
from orbatt.methods.problem import kernel_spec
from orbatt.shipped import shipped_file

LVLH = shipped_file("lvlh-hold-wheels").read_text()
BDOT = shipped_file("cubesat-bdot-detumble").read_text()
PERIOD = 'period = "0.1 s"\n'
FRICTION = 'friction_coulomb = "2e-5 N m"\nfriction_viscous = "1e-6 N m s"\nmax_speed = "6000 rpm"\n'


def _wheels(text, period=True, friction=False, actuator=True, dump=False):
    """The LVLH hold on three wheels at 10 Hz (``period``), with friction, as an ideal torque
    (no ``actuator``) or dumping the wheels' momentum with magnetorquers (``dump``)."""
    if friction:
        text = text.replace('max_speed = "6000 rpm"\n', FRICTION)
    if not actuator:
        text = text.replace('actuator = "wheels"\n', "")
    if dump:
        text = text.replace('actuator = "wheels"\n', 'actuator = "wheels"\ndump_gain = "0.01 / s"\n'
                            'dump_max_dipole = "0.5 A m2"\n')
        text = text.replace("[potential]", '[environment]\nmagnetic_field = "dipole"\n\n[potential]')
        text = text.replace('true_anomaly = "0 deg"\n', 'true_anomaly = "0 deg"\nepoch = "2025-06-01T00:00:00"\n')
    if period:
        text = text.replace('law = "pd"\n', 'law = "pd"\n' + PERIOD)
    return text


#: (label, scenario text, laws all held, ticks change only the wheels' rows)
MODELS = [
    ("wheels", _wheels(LVLH), True, True),
    ("wheels-friction", _wheels(LVLH, friction=True), True, True),
    ("ideal-torque", _wheels(LVLH, actuator=False), True, False),
    ("wheels-dumping", _wheels(LVLH, dump=True), True, False),
    ("bdot", BDOT.replace('law = "bdot"\n', 'law = "bdot"\n' + PERIOD), True, False),
    ("continuous-pd", _wheels(LVLH, period=False), False, False),
]


def _kernel(text, tmp_path):
    """``(scenario, kernel, (q, Q) of its initial state)`` of the scenario ``text``."""
    path = tmp_path / "s.toml"
    path.write_text(text)
    sc = orbatt.load_scenario(path)
    k = kernel_spec(sc.potential, [sc.body])
    y0 = np.concatenate([np.asarray(sc.state0.q, float), np.asarray(getattr(sc.state0.Q, "value", sc.state0.Q), float)])
    return sc, k, y0


def _width(k):
    """The model's state width: ``(q, Q)``, the wheels' momenta and the laws' held slots."""
    from orbatt.core import control as ctl
    width = 8 + kg.wheel_count(k.params, kg.wheel_row(k.terms))
    for j in range(1, k.terms.shape[0]):
        kind = k.terms[j, KIND]
        if kg.is_flight_software(kind):
            p0 = k.terms[j, P0]
            width = max(width, int(k.params[p0 + ctl.CTL_Z0]) + int(k.params[p0 + ctl.CTL_NZ]))
    return width


def _lanes(k, y0, inertia, nl, rng):
    """``nl`` member states about ``y0`` (the wheels' momenta and the held commands at random)
    and inertias, lanes last: ``(n, nl)``, ``(3, nl)``."""
    width = _width(k)
    Y = np.empty((width, nl))
    for l in range(nl):
        q = y0[:4] + 0.05 * rng.standard_normal(4)
        Y[:4, l] = q / np.linalg.norm(q)
        Y[4:8, l] = y0[4:8] * (1 + 0.1 * rng.standard_normal(4)) + 1e-3 * rng.standard_normal(4)
        Y[8:, l] = 1e-6 * rng.standard_normal(width - 8)
    I = inertia[:, None] * (1 + 0.01 * rng.random((3, nl)))
    return np.ascontiguousarray(Y), np.ascontiguousarray(I)


@pytest.mark.parametrize("label, text, held, wheels_only", MODELS, ids=[m[0] for m in MODELS])
def test_lanes_right_hand_side_is_each_members(label, text, held, wheels_only, tmp_path):
    """Each lane of the group's right-hand side equals its member's :func:`rhs_extended`, bit
    for bit, on states that differ in every component and inertias that differ per lane; the
    model's laws decide the form (structure of arrays when all hold their commands)."""
    sc, k, y0 = _kernel(text, tmp_path)
    assert bool(hc.held_lanes(k.terms, k.params)) is held
    assert bool(hc.wheel_ticks_only(k.terms, k.params)) is wheels_only
    rng = np.random.default_rng(7)
    nl = 13
    Y, I = _lanes(k, y0, np.asarray(sc.body.inertia_value, float), nl, rng)
    dY = np.full_like(Y, np.nan)
    S = np.empty((hc.LANE_SCRATCH, nl))
    for s in (0.0, 37.25, 1234.5):
        hc.rhs_extended_lanes(s, Y, nl, I, k.terms, k.params, k.table, np.full(WORK_SIZE, np.nan), dY, S)
        for l in range(nl):
            dy = np.full(Y.shape[0], np.nan)
            kg.rhs_extended(s, np.ascontiguousarray(Y[:, l]), np.ascontiguousarray(I[:, l]), k.terms, k.params,
                            k.table, np.full(WORK_SIZE, np.nan), dy)
            assert dy.tobytes() == np.ascontiguousarray(dY[:, l]).tobytes(), (label, s, l, dy, dY[:, l])


def test_wheel_speed_limits_in_lanes(tmp_path):
    """Lanes whose wheels sit at their speed limit, pushed further or back, and lanes well
    inside it: the group's motor torques are zeroed exactly where each member's are."""
    sc, k, y0 = _kernel(MODELS[0][1], tmp_path)   # no friction: a zeroed motor torque is dh/dt = 0
    rng = np.random.default_rng(3)
    nl = 8
    Y, I = _lanes(k, y0, np.asarray(sc.body.inertia_value, float), nl, rng)
    z0 = int(k.params[k.terms[[j for j in range(1, k.terms.shape[0]) if k.terms[j, KIND] == PD_CONTROL][0], P0]
                      + CTL_Z0])
    smax_momentum = 4e-4 * 6000 * 2 * np.pi / 60 * 1e-6   # kg km^2 / s: Iw x max speed
    Y[8:11, :4] = 1.02 * smax_momentum * np.sign(rng.standard_normal((3, 4)))
    Y[z0:z0 + 3, :] = 4e-9 * rng.standard_normal((3, nl))
    dY = np.empty_like(Y)
    hc.rhs_extended_lanes(0.0, Y, nl, I, k.terms, k.params, k.table, np.full(WORK_SIZE, np.nan), dY,
                          np.empty((hc.LANE_SCRATCH, nl)))
    zeroed = 0
    for l in range(nl):
        dy = np.empty(Y.shape[0])
        kg.rhs_extended(0.0, np.ascontiguousarray(Y[:, l]), np.ascontiguousarray(I[:, l]), k.terms, k.params,
                        k.table, np.full(WORK_SIZE, np.nan), dy)
        assert dy.tobytes() == np.ascontiguousarray(dY[:, l]).tobytes()
        zeroed += int(np.count_nonzero(dy[8:11] == 0.0))
    assert 2 <= zeroed < 12   # the commands pushing a wheel past its limit, and those only


@pytest.mark.parametrize("which", [0, 1])
def test_wheel_command_rates_is_the_full_derivative(which, tmp_path):
    """After a tick of wheel-only laws, the derivative before it with its wheels' rows rewritten
    (:func:`wheel_command_rates`) is the full right-hand side under the new command, bit for
    bit (friction, speed limits and all)."""
    sc, k, y0 = _kernel(MODELS[which][1], tmp_path)
    rng = np.random.default_rng(11)
    Y, I = _lanes(k, y0, np.asarray(sc.body.inertia_value, float), 6, rng)
    pd = [j for j in range(1, k.terms.shape[0]) if k.terms[j, KIND] == PD_CONTROL][0]
    for l in range(Y.shape[1]):
        inertia = np.ascontiguousarray(I[:, l])
        for s in (0.0, 311.0):
            y = np.array(Y[:, l])   # the commands held before the tick: random
            w1 = np.full(WORK_SIZE, np.nan)
            w2 = np.full(WORK_SIZE, np.nan)
            before = np.empty_like(y)
            kg.rhs_extended(s, y, inertia, k.terms, k.params, k.table, w1, before)
            kg.tick(s, y, inertia, k.terms, k.params, k.table, w1, True, np.nan)   # a new command
            full = np.empty_like(y)
            kg.rhs_extended(s, y.copy(), inertia, k.terms, k.params, k.table, w2, np.empty_like(y))
            kg.rhs_extended(s, y, inertia, k.terms, k.params, k.table, w2, full)
            part = before.copy()
            hc.wheel_command_rates(s, y, inertia, k.terms, k.params, k.table, w1, part)
            assert not np.array_equal(part, before)   # the command changed the wheels' rows
            assert part.tobytes() == full.tobytes()
    assert pd > 0


@pytest.mark.parametrize("which", [0, 1])
def test_wheel_tick_is_the_tick_and_the_wheels_rows(which, tmp_path):
    """The fused tick of wheel-only laws (:func:`wheel_tick`: one orbit and one body rate for
    the laws and the wheels' rows) writes the commands :func:`orbatt.core.gyrostat.tick` writes
    and the derivative :func:`wheel_command_rates` rewrites, bit for bit, on ticks of the
    grid and with the laws' integral state untouched elsewhere."""
    sc, k, y0 = _kernel(MODELS[which][1], tmp_path)
    rng = np.random.default_rng(13)
    Y, I = _lanes(k, y0, np.asarray(sc.body.inertia_value, float), 6, rng)
    changed = 0
    for l in range(Y.shape[1]):
        inertia = np.ascontiguousarray(I[:, l])
        for s in (0.0, 3110 * 0.1, 57399 * 0.1):   # ticks of the 0.1 s grid (phase 0)
            before = np.empty(Y.shape[0])
            kg.rhs_extended(s, np.array(Y[:, l]), inertia, k.terms, k.params, k.table, np.full(WORK_SIZE, np.nan),
                            before)
            y1, d1 = np.array(Y[:, l]), before.copy()
            w1 = np.full(WORK_SIZE, np.nan)
            kg.tick(s, y1, inertia, k.terms, k.params, k.table, w1, False, s)
            hc.wheel_command_rates(s, y1, inertia, k.terms, k.params, k.table, w1, d1)
            for lean in (False, True):   # tick_on, or the PD laws alone (no sensors here)
                y2, d2 = np.array(Y[:, l]), before.copy()
                hc.wheel_tick(s, y2, inertia, k.terms, k.params, k.table, np.full(WORK_SIZE, np.nan), s, d2, lean)
                assert y2.tobytes() == y1.tobytes() and d2.tobytes() == d1.tobytes()
                changed += int(not np.array_equal(y2, Y[:, l]))   # the tick wrote a new command
    assert changed == 6 * Y.shape[1]
    assert hc.wheel_ticks_only(k.terms, k.params) == 2   # the loop takes the lean form


@pytest.mark.parametrize("method", ["bs32", "dopri5"])
def test_group_of_one_lane_is_the_member(method, tmp_path):
    """End to end, ticks included: groups of one lane (the structure-of-arrays right-hand side,
    the wheels' rows rewritten after each tick) give each member's single run (the stages'
    orbit evaluated first, the fused tick of :func:`wheel_tick`) bit for bit; groups of three step
    together and agree to the tolerance."""
    import astropy.units as u

    sc, k, _ = _kernel(_wheels(LVLH, friction=True), tmp_path)
    rng = np.random.default_rng(5)
    q = rng.normal(size=(3, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w = np.radians(rng.normal(size=(3, 3)))
    states = orbatt.State.from_omega(sc.body, q, w * u.rad / u.s)
    times = np.linspace(0.0, 40.0, 9)
    kw = dict(rtol=1e-10, atol=1e-10)
    one_lane = orbatt.propagate(sc.body, states, sc.potential, times, method=f"{method}-lanes", lanes=1, **kw)
    group = orbatt.propagate(sc.body, states, sc.potential, times, method=f"{method}-lanes", lanes=3, **kw)
    for e in range(3):
        alone = orbatt.propagate(sc.body, orbatt.State.from_omega(sc.body, q[e], w[e] * u.rad / u.s), sc.potential,
                                 times, method=method, **kw)
        assert np.asarray(one_lane.q[e]).tobytes() == np.asarray(alone.q).tobytes()
        assert np.asarray(one_lane.Q[e]).tobytes() == np.asarray(alone.Q).tobytes()
        d = np.asarray(group.q[e]) - np.asarray(alone.q)
        assert np.abs(d).max() < 1e-7   # different steps: the group steps at its largest error

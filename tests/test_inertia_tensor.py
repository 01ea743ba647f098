"""A full inertia tensor in the body (mechanical) frame (issue 32 item 6): the principal frame
(orbatt.body_frame), the boundary (orbatt.frame_boundary) and the scenario key [body] inertia.

The oracle: a body whose tensor is R diag(I) R^T, with every body-fixed input and initial
condition turned by R (x_B = R x_P), is the principal-axes body seen in other axes: its attitude
is q_B = q_P r~ (r the quaternion of R), its body vectors R times the principal run's.
"""
import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import quaternion as qt
from orbatt.body_frame import principal_axes
from orbatt.errors import InputError, ScenarioError
from orbatt.scenario import Scenario
from orbatt.scenario.schema import parse


def load_scenario(text):
    """The scenario of a TOML text."""
    return Scenario(parse(text, "tensor.toml"))

I_P = np.array([0.10, 0.12, 0.05])  # kg m^2
#: a rotation of about 37 deg (each principal axis stays closest to its body axis)
R_Q = qt.normalize(np.array([0.95, 0.15, -0.2, 0.18]))
R_M = qt.to_matrix(R_Q)
TENSOR = R_M @ np.diag(I_P) @ R_M.T
TENSOR = 0.5 * (TENSOR + TENSOR.T)  # exactly symmetric (as a file's matrix or six values are)


def _b(v):
    """Body vectors of principal ones: R v."""
    return np.asarray(v, dtype=np.float64) @ R_M.T


def _qb(q):
    return qt.mul(q, qt.conj(R_Q))


def _angle(a, b):
    return float(np.max(qt.angle_between(a, b)))


# --- the principal frame ----------------------------------------------------------------------
def test_principal_axes_of_a_turned_tensor():
    moments, axes = principal_axes(TENSOR)
    assert np.allclose(moments, I_P, rtol=1e-14, atol=0)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-14)
    assert np.abs(axes - R_M).max() < 1e-13  # closest to the body axes, signed like them
    body = orbatt.RigidBody(TENSOR * u.kg * u.m**2)
    f = body.frame
    assert np.abs(f.R @ np.diag(f.moments) @ f.R.T - TENSOR * 1e-6).max() < 1e-21  # kg km^2
    assert np.allclose(body.inertia.to_value(u.kg * u.m**2), I_P, rtol=1e-14)


def test_a_diagonal_tensor_is_the_principal_body():
    d = [[0.1, 0.0, 0.0], [0.0, 0.12, 0.0], [0.0, 0.0, 0.05]]
    b = orbatt.RigidBody(np.array(d) * u.kg * u.m**2)
    assert b.frame is None and b.principal is b
    assert np.array_equal(b.inertia_value, orbatt.RigidBody(I_P * u.kg * u.m**2).inertia_value)


def test_degenerate_pair_gets_a_basis_from_the_body_axes():
    t = R_M @ np.diag([0.1, 0.1, 0.05]) @ R_M.T
    moments, axes = principal_axes(t)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-14)
    assert np.abs(axes @ np.diag(moments) @ axes.T - t).max() < 1e-16
    again = principal_axes(t + 0.0)
    assert np.array_equal(axes, again[1])


# --- refusals -----------------------------------------------------------------------------------
@pytest.mark.parametrize("tensor, words", [
    ([[0.1, 0.2, 0.0], [0.2, 0.1, 0.0], [0.0, 0.0, 0.05]], "positive definite"),
    ([[0.1, 0.002, 0.0], [0.001, 0.12, 0.0], [0.0, 0.0, 0.05]], "not symmetric"),
    ((R_M @ np.diag([0.1, 0.1, 0.3]) @ R_M.T).tolist(), "triangle inequality"),
])
def test_bad_tensors_are_refused(tensor, words):
    with pytest.raises(InputError, match=words):
        orbatt.RigidBody(np.array(tensor) * u.kg * u.m**2)
    rows = ", ".join("[" + ", ".join(f'"{v!r} kg m2"' for v in row) + "]" for row in tensor)
    with pytest.raises(ScenarioError, match=r"\[body\] inertia.*" + words):
        load_scenario(_text(f"[{rows}]"))


# --- scenario files -------------------------------------------------------------------------------
def _vec(v, unit):
    return "[" + ", ".join(f'"{float(x)!r} {unit}"' for x in v) + "]"


def _text(inertia, *, facets=(), q=(1.0, 0.0, 0.0, 0.0), omega=(0.0, 0.0, 0.0), dipole=None, constant=None,
          t_end="600 s", sweep=""):
    lines = ['name = "tensor"', "[body]", f"inertia = {inertia}"]
    for n, pos in facets:
        lines += ["[[body.facets]]", 'area = "0.03 m2"', f"normal = {list(map(float, n))!r}",
                  f"position = {_vec(pos, 'm')}", "drag_coefficient = 2.2", "specular = 0.1", "diffuse = 0.3"]
    tq = []
    if facets:
        tq.append("drag = true")
    if dipole is not None:
        tq.append(f"residual_dipole = {_vec(dipole, 'A m2')}")
    if constant is not None:
        tq.append(f"constant = {_vec(constant, 'N m')}")
    if tq:
        lines += ["[torques]", *tq, "[environment]", 'atmosphere = "exponential"', 'magnetic_field = "dipole"'] \
            if dipole is not None else ["[torques]", *tq, "[environment]", 'atmosphere = "exponential"']
    lines += ["[initial]", 'frame = "inertial"', f"q = {list(map(float, q))!r}", f"omega = {_vec(omega, 'rad/s')}",
              "[potential]", 'kind = "gravity-gradient"', "[orbit]", 'provider = "kepler"', 'central_body = "earth"',
              'a = "6778 km"', "e = 0.001", 'i = "51.6 deg"', 'raan = "30 deg"', 'argp = "10 deg"',
              'true_anomaly = "0 deg"', 'epoch = "2025-03-20T00:00:00"',
              "[integration]", 'method = "dop853"', "rtol = 1e-12", "atol = 1e-12", f't_end = "{t_end}"',
              'output_step = "60 s"', sweep]
    return "\n".join(lines) + "\n"


def _matrix(t):
    return "[" + ", ".join(_vec(row, "kg m2") for row in t) + "]"


FACETS_P = [((1.0, 0.0, 0.0), (0.05, 0.0, 0.02)), ((0.0, -1.0, 0.0), (0.0, -0.05, 0.02)),
            ((0.0, 0.0, 1.0), (0.01, 0.0, 0.17))]
Q0 = qt.normalize(np.array([0.7, 0.1, 0.5, -0.2]))
W0 = np.array([0.001, -0.002, 0.0015])
DIPOLE_P, CONSTANT_P = np.array([0.01, 0.0, 0.004]), np.array([1e-7, -2e-7, 5e-8])


def _pair(**kw):
    """The principal scenario and the same body given by its turned tensor, every body-fixed
    key and initial condition turned too."""
    p = load_scenario(_text(_vec(I_P, "kg m2"), facets=FACETS_P, q=Q0, omega=W0, **kw))
    turned = {k: _b(v) for k, v in kw.items() if v is not None}
    b = load_scenario(_text(_matrix(TENSOR), facets=[(_b(n), _b(pos)) for n, pos in FACETS_P], q=_qb(Q0),
                            omega=_b(W0), **turned))
    return p, b


def test_gravity_gradient_drag_dipole_constant_torque_in_the_body_frame():
    p, b = _pair(dipole=DIPOLE_P, constant=CONSTANT_P)
    assert b.body.frame is not None
    dp, db = p.run(), b.run()
    assert _angle(_qb(dp.q.values), db.q.values) < 1e-11
    assert np.abs(qt.mul(dp.Q.values, qt.conj(R_Q)) - db.Q.values).max() < 1e-11 * np.abs(dp.Q.values).max()
    for name in ("omega", "g", "torque", "torque_drag", "torque_gravity_gradient", "torque_magnetic",
                 "torque_constant"):
        scale = np.abs(dp[name].values).max()
        assert np.abs(_b(dp[name].values) - db[name].values).max() < 1e-9 * scale, name
    assert np.array_equal(dp.G.values.shape, db.G.values.shape)
    assert np.abs(dp.G.values - db.G.values).max() < 1e-11 * np.abs(dp.G.values).max()
    assert np.abs(dp.energy.values - db.energy.values).max() < 1e-11 * np.abs(dp.energy.values).max()
    assert _angle(qt.mul(dp.q_orbital.values, qt.conj(R_Q)), db.q_orbital.values) < 1e-11
    assert np.allclose(qt.from_euler313(*np.moveaxis(db.euler_313.values, -1, 0)) * np.sign(db.q.values[:, :1]),
                       db.q.values * np.sign(db.q.values[:, :1]), atol=1e-12)
    # the Dataset records the tensor, the principal moments and axes
    assert np.allclose(db.inertia_tensor.values, TENSOR, rtol=0, atol=1e-16)
    assert db.inertia_tensor.attrs["units"] == "kg m^2"
    assert np.allclose(db.inertia.values, I_P, rtol=1e-14)
    assert np.abs(db.principal_axes.values - R_M).max() < 1e-13


def test_torque_free_in_the_body_frame_conserves_energy_and_momentum():
    body = orbatt.RigidBody(TENSOR * u.kg * u.m**2)
    w = np.array([0.01, -0.02, 0.03])
    st = orbatt.State.from_omega(body, _qb(Q0), _b(w) * u.rad / u.s)
    assert np.allclose(st.omega, _b(w), rtol=1e-14)
    assert st.kinetic_energy == pytest.approx(0.5 * w @ (I_P * 1e-6 * w), rel=1e-14)
    t = np.linspace(0.0, 600.0, 11)
    tr_b = orbatt.propagate(body, st, orbatt.TorqueFree(), t, rtol=1e-12, atol=1e-12)
    base = orbatt.RigidBody(I_P * u.kg * u.m**2)
    tr_p = orbatt.propagate(base, orbatt.State.from_omega(base, Q0, w * u.rad / u.s), orbatt.TorqueFree(), t,
                            rtol=1e-12, atol=1e-12)
    assert _angle(_qb(tr_p.q), tr_b.q) < 1e-12
    assert tr_b.body is body
    ds = orbatt.to_dataset(tr_b)
    G = ds.G.values
    assert np.abs(G - G[0]).max() < 1e-12 * np.linalg.norm(G[0])
    E = ds.energy.values
    assert np.abs(E - E[0]).max() < 1e-11 * E[0]  # dop853 at rtol 1e-12 over 600 s, as in principal axes
    # omega in B: I_B omega = g
    assert np.abs(ds.omega.values @ TENSOR - ds.g.values).max() < 1e-12 * np.abs(ds.g.values).max()


def test_wheels_and_a_pd_law_in_the_body_frame():
    axes_p = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.577350269189626, 0.577350269189626,
                                                                            0.577350269189626]])
    axes_p /= np.linalg.norm(axes_p, axis=1, keepdims=True)
    target = qt.normalize(np.array([0.9, 0.3, -0.2, 0.25]))

    def run(body_inertia, axes, tq, q0, w0):
        wheels = [orbatt.ReactionWheel(a, "2e-5 kg m2", f"{500 * (k + 1)} rpm", max_torque="2e-3 N m")
                  for k, a in enumerate(axes)]
        body = orbatt.RigidBody(body_inertia * u.kg * u.m**2, wheels=wheels)
        law = orbatt.PDControl("inertial", kp="4e-3 N m", kd="1.4e-2 N m s", target_q=tq, actuator="wheels")
        st = orbatt.State.from_omega(body, q0, w0 * u.rad / u.s)
        tr = orbatt.propagate(body, st, orbatt.TorqueFree(), np.linspace(0, 120, 13), control=law, rtol=1e-12,
                              atol=1e-12)
        return orbatt.to_dataset(tr)

    dp = run(I_P, axes_p, target, Q0, W0)
    db = run(TENSOR, _b(axes_p), _qb(target), _qb(Q0), _b(W0))
    assert _angle(_qb(dp.q.values), db.q.values) < 1e-10
    assert _angle(dp.q.values[-1], target) < 0.05  # the law acts
    for name in ("omega", "torque_control"):
        assert np.abs(_b(dp[name].values) - db[name].values).max() < 1e-9 * np.abs(dp[name].values).max(), name
    for name in ("wheel_momentum", "wheel_speed", "wheel_torque"):
        assert np.abs(dp[name].values - db[name].values).max() < 1e-9 * np.abs(dp[name].values).max(), name
    assert np.abs(db.wheel_axis.values - _b(axes_p)).max() < 1e-15
    G = db.G.values  # free wheels inside, no external torque: the total momentum is kept
    assert np.abs(G - G[0]).max() < 1e-10 * np.linalg.norm(G[0])


def test_a_diagonal_tensor_is_bitwise_todays_run():
    facets = [(n, pos) for n, pos in FACETS_P]
    kw = dict(facets=facets, q=Q0, omega=W0, dipole=DIPOLE_P, constant=CONSTANT_P, t_end="180 s")
    d3 = load_scenario(_text(_vec(I_P, "kg m2"), **kw)).run()
    d9 = load_scenario(_text(_matrix(np.diag(I_P)), **kw)).run()
    six = _vec([*I_P, 0.0, 0.0, 0.0], "kg m2")
    d6 = load_scenario(_text(six, **kw)).run()
    for name in d3.data_vars:
        assert np.array_equal(d3[name].values, d9[name].values), name
        assert np.array_equal(d3[name].values, d6[name].values), name
    assert "inertia_tensor" in d9 and "principal_axes" not in d9


def test_six_values_equal_the_matrix():
    six = _vec([TENSOR[0, 0], TENSOR[1, 1], TENSOR[2, 2], TENSOR[0, 1], TENSOR[0, 2], TENSOR[1, 2]], "kg m2")
    a = load_scenario(_text(six, q=_qb(Q0), omega=_b(W0), t_end="180 s")).run()
    b = load_scenario(_text(_matrix(TENSOR), q=_qb(Q0), omega=_b(W0), t_end="180 s")).run()
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values), name


def test_heavy_top_centre_of_mass_in_the_body_frame():
    xc = np.array([0.0, 0.01, 0.3])
    t = np.linspace(0.0, 2.0, 5)

    def run(inertia, com, q0, w0):
        body = orbatt.RigidBody(inertia)
        top = orbatt.HeavyTop(2.0, com, dimensionless=True)
        return orbatt.propagate(body, orbatt.State.from_omega(body, q0, w0), top, t, rtol=1e-12, atol=1e-12)

    p = run(I_P.tolist(), xc, Q0, W0 * 100)
    b = run(TENSOR.tolist(), _b(xc), _qb(Q0), _b(W0 * 100))
    assert _angle(_qb(p.q), b.q) < 1e-12
    assert np.abs(qt.mul(p.Q, qt.conj(R_Q)) - b.Q).max() < 1e-12 * np.abs(p.Q).max()


def test_an_ensemble_of_states_of_a_tensor_body_is_each_member_alone():
    body = orbatt.RigidBody(TENSOR * u.kg * u.m**2)
    q0 = np.array([_qb(Q0), [1.0, 0.0, 0.0, 0.0]])
    w0 = np.array([_b(W0), [0.002, 0.001, -0.003]])
    t = np.linspace(0.0, 300.0, 4)
    ens = orbatt.propagate(body, orbatt.State.from_omega(body, q0, w0 * u.rad / u.s), orbatt.TorqueFree(), t)
    for e in range(2):
        one = orbatt.propagate(body, orbatt.State.from_omega(body, q0[e], w0[e] * u.rad / u.s), orbatt.TorqueFree(), t)
        assert np.array_equal(ens.q[e], one.q)
    ds = orbatt.to_dataset(ens)
    assert ds.inertia_tensor.dims == ("case", "axis", "axis_column")
    assert np.allclose(ds.inertia_tensor.values[1], TENSOR, rtol=0, atol=1e-16)

"""Building the result Dataset (issue 5): layout, CF attributes, derived and orbit variables,
ensembles."""
import json
import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt import canonical as cn
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.errors import InputError
from orbatt.potentials import Potential
from orbatt.trajectory import Trajectory

from dataset_support import EPOCH, I_PAPER, ORBIT_VARS, P0_PAPER, Q0_PAPER, REQUIRED, SCENARIO, _every_units_parses, _propagate, _tangent, assert_bitwise_identical


def test_layout_dimensionless(free_ds, free_traj):
    ds = free_ds
    assert all(v in ds for v in REQUIRED)
    assert not any(v in ds for v in ORBIT_VARS)
    assert ds["q"].dims == ("time", "quat") and ds["omega"].dims == ("time", "axis")
    assert ds["quat"].values.tolist() == [0, 1, 2, 3]
    assert ds["quat_label"].values.tolist() == ["w", "x", "y", "z"]
    assert ds["axis"].values.tolist() == [1, 2, 3]
    assert ds["axis_label"].values.tolist() == ["x", "y", "z"]
    assert ds["euler_313_label"].values.tolist() == ["phi", "theta", "psi"]
    _every_units_parses(ds)
    # a dimensionless problem says so: "1" everywhere but angles
    for name in ["time", "q", "Q", "omega", "g", "G", "energy", "kinetic_energy", "potential_energy",
                 "q_norm_error", "qQ", "inertia"]:
        assert ds[name].attrs["units"] == "1", name
    assert ds["euler_313"].attrs["units"] == "rad"
    assert ds.orbatt.dimensionless
    assert "epoch" not in ds.attrs
    assert ds.attrs["unit_system"].startswith("dimensionless")
    for name in ["q", "Q"]:
        assert ds[name].attrs["quaternion_order"] == "w x y z"
    assert ds["q"].attrs["frames"] == "B relative to S"
    assert ds["Q"].attrs["conjugate_to"] == "q (B relative to S)"
    assert ds["g"].attrs["frame"] == "B" and ds["G"].attrs["frame"] == "S" and ds["omega"].attrs["frame"] == "B"
    assert np.array_equal(ds["q"].values, free_traj.q) and np.array_equal(ds["Q"].values, free_traj.Q)
    assert np.array_equal(ds["time"].values, free_traj.t)


def test_global_attributes(free_ds):
    a = free_ds.attrs
    assert a["Conventions"] == "CF-1.11"
    assert a["orbatt_version"] == orbatt.__version__
    assert a["method"] == "scipy-DOP853" or a["method"]
    assert isinstance(json.loads(a["method_settings"]), dict)
    assert isinstance(json.loads(a["integration_stats"]), dict)
    assert a["scenario"] == SCENARIO
    assert json.loads(a["potential"])["kind"] == "torque-free"
    Time(a["date_created"][:-1], scale="utc")  # ISO UTC
    assert int(a["integration_complete"]) == 1
    for k, v in a.items():  # NetCDF-legal: strings and numbers only
        assert isinstance(v, (str, int, float, np.integer, np.floating)), k
    assert free_ds.orbatt.scenario == SCENARIO
    assert free_ds.orbatt.settings == json.loads(a["method_settings"])


def test_derived_quantities(free_ds, free_traj):
    ds = free_ds
    q, Q = free_traj.q, free_traj.Q
    assert np.array_equal(ds["g"].values, cn.body_momentum(q, Q))
    assert np.array_equal(ds["G"].values, cn.space_momentum(q, Q))
    assert np.array_equal(ds["omega"].values, cn.body_rate(q, Q, I_PAPER))
    assert np.array_equal(ds["kinetic_energy"].values, cn.kinetic_energy(q, Q, I_PAPER))
    assert np.all(ds["potential_energy"].values == 0.0)
    assert np.array_equal(ds["energy"].values, ds["kinetic_energy"].values)
    assert np.array_equal(ds["q_norm_error"].values, qt.norm(q) - 1)
    assert np.array_equal(ds["qQ"].values, qt.dot(q, Q))
    phi, th, ps = qt.to_euler313(q)
    assert np.array_equal(ds["euler_313"].values, np.stack([phi, th, ps], -1))
    # physics sanity: the torque-free invariants
    assert np.ptp(ds["energy"].values) < 1e-8
    assert np.ptp(ds["G"].values, axis=0).max() < 1e-8


def test_shape_mismatch_is_refused(free_traj):
    bad = Trajectory(body=free_traj.body, potential=free_traj.potential, t=free_traj.t[:-1], q=free_traj.q,
                     Q=free_traj.Q, inertia=I_PAPER, method="x")
    with pytest.raises(InputError, match="do not fit"):
        D.to_dataset(bad)


def test_orbit_variables(orbit_ds, orbit_traj):
    ds = orbit_ds
    orbit = orbit_traj.orbit
    t = orbit_traj.t
    assert all(v in ds for v in REQUIRED + ORBIT_VARS)
    _every_units_parses(ds)
    assert ds["r"].attrs["units"] == "km" and ds["velocity"].attrs["units"] == "km s^-1"
    assert ds["position"].attrs["frame"] == "S" and ds["true_anomaly"].attrs["units"] == "rad"
    assert ds["p"].attrs["frames"] == "O relative to S" and ds["q_orbital"].attrs["frames"] == "B relative to O"
    assert np.array_equal(ds["r"].values, orbit.radius(t))
    assert np.array_equal(ds["p"].values, orbit.orbital_quaternion(t))
    q = orbit_traj.q
    assert np.array_equal(ds["q_orbital"].values, qt.mul(qt.conj(orbit.orbital_quaternion(t)), q))
    # the orbital frame is where it should be: o1 radial, o3 along r x v
    p = ds["p"].values
    r, v = ds["position"].values, ds["velocity"].values
    assert np.allclose(qt.rotate(p, [1.0, 0, 0]), r / np.linalg.norm(r, axis=1)[:, None], atol=1e-14)
    h = np.cross(r, v)
    assert np.allclose(qt.rotate(p, [0, 0, 1.0]), h / np.linalg.norm(h, axis=1)[:, None], atol=1e-14)
    # roll/pitch/yaw are the scipy ZYX angles of q_orbital in the relabelled axes (o2, o3, o1)
    m = np.array([0.5, 0.5, 0.5, 0.5])
    ypr = qt.to_scipy(qt.mul(qt.mul(qt.conj(m), ds["q_orbital"].values), m)).as_euler("ZYX")
    assert np.allclose(ds["euler_321"].values, ypr[:, ::-1], atol=1e-12)
    # potential energy from the kernel agrees with MacCullagh's formula on the stored r, p, q
    xb = qt.rotate_inv(q, qt.rotate(p, [1.0, 0, 0]))
    I = orbit_traj.body.inertia_value
    U = 1.5 * orbit.gm / ds["r"].values ** 3 * np.sum(xb * I * xb, axis=1)  # kg km^2 s^-2
    assert np.allclose(ds["potential_energy"].values, U * 1e6, rtol=1e-12, atol=0)  # in J
    # the epoch comes from the orbit, in UTC with Z
    assert ds.attrs["epoch"] == "2024-03-20T03:06:00.000000000Z"
    assert abs((ds.orbatt.epoch - EPOCH).to_value(u.s)) < 1e-9
    times = ds.orbatt.times()
    assert abs((times[-1] - EPOCH).to_value(u.s) - t[-1]) < 1e-6
    assert ds["elapsed"].attrs["units"] == "s" and ds["time"].attrs["standard_name"] == "time"
    assert ds["time"].encoding["units"] == "seconds since 2024-03-20T03:06:00.000000000Z"
    assert ds["time"].values[0] == np.datetime64("2024-03-20T03:06:00", "ns")
    assert json.loads(ds.attrs["orbit"])["provider"] == "circular-test"


class _KernelPotential(Potential):
    """Gravity gradient from any provider's ``kernel()`` (used when
    ``orbatt.potentials.GravityGradient`` is not there)."""

    name = "gravity-gradient"

    def __init__(self, orbit):
        self.orbit = orbit
        self.kind, self.params, self.table = orbit.kernel()


def test_with_the_kepler_provider():
    orbits = pytest.importorskip("orbatt.orbits")
    if not hasattr(orbits, "KeplerOrbit"):
        pytest.skip("orbatt.orbits.KeplerOrbit not available")
    # the paper's Sect. 6.2 orbit and body
    orbit = orbits.KeplerOrbit(7000 * u.km, 0.2, 30 * u.deg, 45 * u.deg, 15 * u.deg, true_anomaly=0 * u.deg,
                               body_radius=None, epoch=EPOCH)
    gg = getattr(orbatt.potentials, "GravityGradient", None)
    pot = gg(orbit) if gg is not None else _KernelPotential(orbit)
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    t = np.linspace(0.0, orbit.period_value, 121)
    tr = _propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), pot, t, inertia=body.inertia_value)
    ds = D.to_dataset(tr)
    _every_units_parses(ds)
    assert np.array_equal(ds["r"].values, orbit.radius(t))
    assert np.array_equal(ds["true_anomaly"].values, orbit.true_anomaly(t))
    assert abs(ds["true_anomaly"].values[-1] - 2 * np.pi) < 1e-9
    assert ds["r"].values.min() == pytest.approx(5600.0) and ds["r"].values.max() == pytest.approx(8400.0)
    p = ds["p"].values
    xb = qt.rotate_inv(tr.q, qt.rotate(p, [1.0, 0, 0]))
    U = 1.5 * orbit.gm / ds["r"].values ** 3 * np.sum(xb * body.inertia_value * xb, axis=1)  # kg km^2 s^-2
    assert np.allclose(ds["potential_energy"].values, U * 1e6, rtol=1e-12, atol=0)  # in J
    assert ds.attrs["epoch"] == "2024-03-20T03:06:00.000000000Z"
    assert json.loads(ds.attrs["orbit"])["a_km"] == 7000.0


def test_ensemble_dimension(tmp_path):
    inertias = np.array([[1.25, 1.0, 0.75], [1.3, 1.0, 0.7], [1.1, 1.0, 0.9]])
    body = orbatt.RigidBody(inertias[0])
    t = np.linspace(0.0, 5.0, 51)
    Q0 = _tangent(Q0_PAPER, P0_PAPER)
    members = [_propagate(body, Q0_PAPER, Q0, orbatt.TorqueFree(), t, inertia=I) for I in inertias]
    tr = Trajectory(body=body, potential=orbatt.TorqueFree(), t=t, q=np.stack([m.q for m in members]),
                    Q=np.stack([m.Q for m in members]), inertia=inertias, method="scipy-DOP853")
    ds = D.to_dataset(tr)
    assert ds["q"].dims == ("case", "time", "quat") and ds.sizes["case"] == 3
    assert ds["energy"].dims == ("case", "time") and ds["inertia"].dims == ("case", "axis")
    for e in range(3):
        assert np.array_equal(ds["kinetic_energy"].values[e], cn.kinetic_energy(tr.q[e], tr.Q[e], inertias[e]))
        assert np.array_equal(ds["omega"].values[e], cn.body_rate(tr.q[e], tr.Q[e], inertias[e]))
    _every_units_parses(ds)
    pytest.importorskip("netCDF4")
    path = tmp_path / "ens.nc"
    ds.orbatt.to_netcdf(path)
    assert_bitwise_identical(ds, orbatt.open_dataset(path, load=True))
    # appending along time with the case dimension first
    p2 = tmp_path / "ens_appended.nc"
    with D.NetCDFWriter(p2) as w:
        w.append(ds.isel(time=slice(0, 20)))
        w.append(ds.isel(time=slice(20, None)))
    back = orbatt.open_dataset(p2, load=True)
    for name, var in ds.data_vars.items():
        assert np.asarray(back[name].values).tobytes() == var.values.tobytes(), name


def test_incomplete_run_is_marked(free_traj, tmp_path):
    tr = Trajectory(body=free_traj.body, potential=free_traj.potential, t=free_traj.t[:10], q=free_traj.q[:10],
                    Q=free_traj.Q[:10], inertia=I_PAPER, method="x", complete=False)
    ds = D.to_dataset(tr)
    assert int(ds.attrs["integration_complete"]) == 0

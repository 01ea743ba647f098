"""The results Dataset (issue 5): layout, units table, accessor, NetCDF round trips and
appends, CF attributes, orbit variables, 3-2-1 angles, plots."""
import json
import math

import numpy as np
import pytest
import xarray as xr
from astropy import units as u
from astropy.time import Time
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import orbatt
from orbatt import canonical as cn
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.core import hamiltonian as H
from orbatt.core import kepler as kk
from orbatt.core import potentials as kp
from orbatt.errors import InputError
from orbatt.potentials import Potential
from orbatt.trajectory import Trajectory

I_PAPER = np.array([1.25, 1.0, 0.75])
Q0_PAPER = np.array([0.5, -1 / np.sqrt(2), 0.0, 0.5])
P0_PAPER = np.array([0.3, -0.848528, 0.141421, -1.5])
SCENARIO = '# paper torque-free\nname = "paper-torque-free"\n[body]\ninertia = [1.25, 1.0, 0.75]\n'
GM_EARTH = 398600.4418
EPOCH = Time("2024-03-20T03:06:00", scale="utc")


def _tangent(q, Q):
    return Q - qt.dot(q, Q) * q


def _propagate(body, q0, Q0, potential, t, inertia=None):
    """A Trajectory: orbatt.propagate once it exists, scipy's DOP853 on the compiled
    right-hand side (eq. 7) until then."""
    if hasattr(orbatt, "propagate") and inertia is None:
        return orbatt.propagate(body, orbatt.State(body, q0, Q0), potential, t)
    inertia = body.inertia_value if inertia is None else inertia
    work = kp.new_work()

    def f(tt, y):
        dy = np.empty(8)
        H.rhs(tt, y, inertia, potential.kind, potential.params, potential.table, work, dy)
        return dy

    sol = solve_ivp(f, (t[0], t[-1]), np.r_[q0, Q0], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-12)
    assert sol.success
    return Trajectory(body=body, potential=potential, t=np.asarray(t, dtype=float), q=sol.y[:4].T.copy(),
                      Q=sol.y[4:].T.copy(), inertia=np.asarray(inertia, dtype=float), method="scipy-DOP853",
                      settings={"rtol": 1e-12, "atol": 1e-12}, stats={"steps": int(sol.nfev // 12),
                                                                      "rhs_evaluations": int(sol.nfev),
                                                                      "wall_time_s": 0.01})


class CircularOrbit:
    """A small stand-in for an orbit provider (the contract of DESIGN.md §5): circular
    Keplerian orbit, radius in km, times in s."""

    def __init__(self, a=7000.0, inc=math.pi / 6, raan=math.pi / 4, argp=math.pi / 12, gm=GM_EARTH, epoch=EPOCH):
        self.a, self.inc, self.raan, self.argp, self.gm, self.epoch = a, inc, raan, argp, gm, epoch
        self.n = math.sqrt(gm / a**3)
        self.period = 2 * math.pi / self.n

    def true_anomaly(self, t):
        return self.n * np.asarray(t, dtype=float)

    def radius(self, t):
        return np.full(np.shape(t), self.a)

    def orbital_quaternion(self, t):
        return qt.from_euler313(self.raan, self.inc, self.argp + self.true_anomaly(t))

    def radial_direction(self, t):
        return qt.rotate(self.orbital_quaternion(t), np.array([1.0, 0.0, 0.0]))

    def state(self, t):
        p = self.orbital_quaternion(t)
        r = self.a * qt.rotate(p, np.array([1.0, 0.0, 0.0]))
        v = self.a * self.n * qt.rotate(p, np.array([0.0, 1.0, 0.0]))
        return r, v

    def describe(self):
        return {"provider": "circular-test", "a": self.a, "gm": self.gm, "epoch": self.epoch.isot}


class GravityGradientStandIn(Potential):
    """Gravity gradient (eq. 20) on the Keplerian kernel, with the ``orbit`` attribute of
    the coming ``GravityGradient(orbit)``."""

    kind = kp.GRAVITY_GRADIENT_KEPLER
    name = "gravity-gradient"

    def __init__(self, orbit):
        self.orbit = orbit
        self.params = np.r_[orbit.gm, kk.orbit_vector(orbit.a, 0.0, orbit.inc, orbit.raan, orbit.argp, 0.0, orbit.n)]

    def describe(self):
        return {"kind": self.name}


@pytest.fixture(scope="module")
def free_traj():
    body = orbatt.RigidBody(I_PAPER)
    t = np.linspace(0.0, 20.0, 201)
    return _propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), orbatt.TorqueFree(), t)


@pytest.fixture(scope="module")
def free_ds(free_traj):
    return D.to_dataset(free_traj, scenario_text=SCENARIO)


@pytest.fixture(scope="module")
def orbit_traj():
    orbit = CircularOrbit()
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    t = np.linspace(0.0, 0.5 * orbit.period, 151)
    return _propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), GravityGradientStandIn(orbit), t,
                      inertia=body.inertia_value)


@pytest.fixture(scope="module")
def orbit_ds(orbit_traj):
    return D.to_dataset(orbit_traj, scenario_text=SCENARIO)


def _engines():
    out = []
    for eng, mods in (("netcdf4", ("netCDF4",)), ("h5netcdf", ("h5netcdf", "h5py"))):
        try:
            for m in mods:
                __import__(m)
            out.append(eng)
        except ImportError:
            out.append(pytest.param(eng, marks=pytest.mark.skip(reason=f"{eng} not installed")))
    return out


ENGINES = _engines()


def assert_bitwise_identical(a: xr.Dataset, b: xr.Dataset):
    """Same variables, dims, float64 values bit for bit, same attrs (global and per variable)."""
    assert set(a.variables) == set(b.variables)
    assert dict(a.sizes) == dict(b.sizes)
    for name in a.variables:
        va, vb = a[name], b[name]
        assert va.dims == vb.dims, name
        if va.dtype.kind == "f":
            assert vb.dtype == np.float64, name
            assert np.asarray(va.values).tobytes() == np.asarray(vb.values).tobytes(), name
        else:
            assert np.array_equal(va.values, vb.values), name
        assert va.attrs.keys() == vb.attrs.keys(), name
        for k in va.attrs:
            assert np.array_equal(va.attrs[k], vb.attrs[k]), (name, k)
    assert a.attrs.keys() == b.attrs.keys()
    for k in a.attrs:
        assert np.array_equal(a.attrs[k], b.attrs[k]), k
    assert a.identical(b)


# ------------------------------------------------------------------------------------------
# units table
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("spelling", list(D.CF_UNITS))
def test_cf_spelling_round_trips_through_astropy(spelling):
    unit = u.Unit(spelling)
    assert unit == D.CF_UNITS[spelling]
    assert unit.to_string() == D.CF_UNITS[spelling].to_string()
    assert D.unit_string(unit) == spelling
    assert D.parse_unit(spelling) == unit


def test_internal_units_have_table_spellings():
    from orbatt import units as U

    assert D.unit_string(U.RATE) == "rad s-1"
    assert D.unit_string(U.INERTIA) == "kg km2"
    assert D.unit_string(U.MOMENTUM) == "kg km2 s-1"
    assert D.unit_string(U.ENERGY) == "kg km2 s-2"
    assert D.unit_string(U.GM) == "km3 s-2"
    assert D.unit_string(U.DIMENSIONLESS) == "1"
    assert D.unit_string(u.deg / u.s) == "degree s-1"
    assert D.unit_string("deg/s") == "degree s-1"


def test_unit_string_falls_back_to_a_parseable_spelling():
    odd = u.kg * u.km**2 / u.s**3
    s = D.unit_string(odd)
    assert u.Unit(s) == odd
    assert D.parse_unit("seconds since 2024-01-01T00:00:00Z") == u.s
    with pytest.raises(InputError, match="not a unit"):
        D.parse_unit("furlongs per fortnight please")


def test_cf_spellings_are_udunits_valid():
    cfunits = pytest.importorskip("cfunits")
    for s in D.CF_UNITS:
        assert cfunits.Units(s).isvalid, s


# ------------------------------------------------------------------------------------------
# layout, units, metadata
# ------------------------------------------------------------------------------------------
REQUIRED = ["q", "Q", "omega", "g", "G", "energy", "kinetic_energy", "potential_energy", "q_norm_error",
            "qQ", "euler_313", "inertia"]
ORBIT_VARS = ["r", "p", "true_anomaly", "position", "velocity", "q_orbital", "euler_321"]


def _every_units_parses(ds):
    for name, var in ds.variables.items():
        if name.endswith("_label"):
            continue  # string labels of numeric coordinates
        assert "units" in var.attrs, name
        assert "long_name" in var.attrs, name
        u.Unit(var.attrs["units"])  # parses
        assert D.parse_unit(var.attrs["units"]) == u.Unit(var.attrs["units"])


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


def test_dimensional_units_and_omega_in_deg_per_s():
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    t = np.linspace(0.0, 100.0, 11)
    ds = D.to_dataset(_propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), orbatt.TorqueFree(), t))
    _every_units_parses(ds)
    expect = {"time": "s", "q": "1", "Q": "kg km2 s-1", "omega": "rad s-1", "g": "kg km2 s-1",
              "G": "kg km2 s-1", "energy": "kg km2 s-2", "kinetic_energy": "kg km2 s-2",
              "potential_energy": "kg km2 s-2", "q_norm_error": "1", "qQ": "kg km2 s-1",
              "euler_313": "rad", "inertia": "kg km2"}
    for name, units in expect.items():
        assert ds[name].attrs["units"] == units, name
    assert not ds.orbatt.dimensionless
    w = ds["omega"].values
    da = ds.orbatt.to("omega", "deg/s")
    assert da.attrs["units"] == "degree s-1"
    assert np.allclose(da.values, np.degrees(w), rtol=1e-15, atol=0)
    assert np.allclose(ds.orbatt.quantity("omega").to_value(u.deg / u.s), np.degrees(w), rtol=1e-15, atol=0)
    assert ds["omega"].attrs["units"] == "rad s-1"  # the dataset is unchanged
    qd = ds.orbatt.quantity("energy")
    assert qd.unit == u.kg * u.km**2 / u.s**2
    assert np.allclose(qd.to_value(u.J), ds["energy"].values * 1e6, rtol=1e-15)
    conv = ds.orbatt.convert(omega=u.deg / u.s, euler_313="degree")
    assert conv["euler_313"].attrs["units"] == "degree"
    assert np.allclose(conv["euler_313"].values, np.degrees(ds["euler_313"].values), rtol=1e-15)
    assert ds.orbatt.times().unit == u.s  # no epoch: a Quantity


def test_dimensionless_refuses_physical_units(free_ds):
    with pytest.raises(InputError, match="cannot convert"):
        free_ds.orbatt.to("omega", "deg/s")
    with pytest.raises(InputError, match="not a variable"):
        free_ds.orbatt.quantity("nope")
    with pytest.raises(InputError, match="dimensionless"):
        D.to_dataset(Trajectory(body=orbatt.RigidBody(I_PAPER), potential=orbatt.TorqueFree(), t=np.zeros(1),
                                q=Q0_PAPER[None], Q=P0_PAPER[None], inertia=I_PAPER, method="x"), epoch=EPOCH)


def test_shape_mismatch_is_refused(free_traj):
    bad = Trajectory(body=free_traj.body, potential=free_traj.potential, t=free_traj.t[:-1], q=free_traj.q,
                     Q=free_traj.Q, inertia=I_PAPER, method="x")
    with pytest.raises(InputError, match="do not fit"):
        D.to_dataset(bad)


# ------------------------------------------------------------------------------------------
# orbit variables
# ------------------------------------------------------------------------------------------
def test_orbit_variables(orbit_ds, orbit_traj):
    ds = orbit_ds
    orbit = orbit_traj.orbit
    t = orbit_traj.t
    assert all(v in ds for v in REQUIRED + ORBIT_VARS)
    _every_units_parses(ds)
    assert ds["r"].attrs["units"] == "km" and ds["velocity"].attrs["units"] == "km s-1"
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
    U = 1.5 * orbit.gm / ds["r"].values ** 3 * np.sum(xb * I * xb, axis=1)
    assert np.allclose(ds["potential_energy"].values, U, rtol=1e-12, atol=0)
    # the epoch comes from the orbit, in UTC with Z
    assert ds.attrs["epoch"] == "2024-03-20T03:06:00.000000000Z"
    assert abs((ds.orbatt.epoch - EPOCH).to_value(u.s)) < 1e-9
    times = ds.orbatt.times()
    assert abs((times[-1] - EPOCH).to_value(u.s) - t[-1]) < 1e-6
    assert ds["time"].attrs["units"] == "s" and ds["time"].attrs["standard_name"] == "time"
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
    t = np.linspace(0.0, orbit.period, 121)
    tr = _propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), pot, t, inertia=body.inertia_value)
    ds = D.to_dataset(tr)
    _every_units_parses(ds)
    assert np.array_equal(ds["r"].values, orbit.radius(t))
    assert np.array_equal(ds["true_anomaly"].values, orbit.true_anomaly(t))
    assert abs(ds["true_anomaly"].values[-1] - 2 * np.pi) < 1e-9
    assert ds["r"].values.min() == pytest.approx(5600.0) and ds["r"].values.max() == pytest.approx(8400.0)
    p = ds["p"].values
    xb = qt.rotate_inv(tr.q, qt.rotate(p, [1.0, 0, 0]))
    U = 1.5 * orbit.gm / ds["r"].values ** 3 * np.sum(xb * body.inertia_value * xb, axis=1)
    assert np.allclose(ds["potential_energy"].values, U, rtol=1e-12, atol=0)
    assert ds.attrs["epoch"] == "2024-03-20T03:06:00.000000000Z"
    assert json.loads(ds.attrs["orbit"])["a_km"] == 7000.0


# ------------------------------------------------------------------------------------------
# 3-2-1 angles
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("axis,which", [((1, 0, 0), 0), ((0, 1, 0), 1), ((0, 0, 1), 2)])
def test_euler321_ninety_degrees(axis, which):
    q = qt.from_axis_angle(np.array(axis, float), np.pi / 2 if which != 1 else np.pi / 3)
    angles = np.array(D.to_euler321(q))
    expect = np.zeros(3)
    expect[which] = np.pi / 2 if which != 1 else np.pi / 3
    assert np.allclose(angles, expect, atol=1e-15)


def test_euler321_sequence_and_scipy():
    rng = np.random.default_rng(5)
    q = qt.normalize(rng.normal(size=(500, 4)))
    roll, pitch, yaw = D.to_euler321(q)
    # q = q_z(yaw) q_y(pitch) q_x(roll)
    rebuilt = qt.mul(qt.mul(qt.from_axis_angle([0, 0, 1.0], yaw), qt.from_axis_angle([0, 1.0, 0], pitch)),
                     qt.from_axis_angle([1.0, 0, 0], roll))
    assert np.all(qt.angle_between(rebuilt, q) < 1e-14)
    ypr = qt.to_scipy(q).as_euler("ZYX")
    assert np.allclose(np.stack([roll, pitch, yaw], -1), ypr[:, ::-1], atol=1e-13)
    assert np.all(np.abs(pitch) <= np.pi / 2)


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2])
def test_euler321_gimbal_lock(pitch):
    q = qt.from_scipy(Rotation.from_euler("ZYX", [0.7, pitch, 0.2]))
    roll, p, yaw = D.to_euler321(q)
    assert np.isfinite([roll, p, yaw]).all() and roll == 0.0
    assert abs(p - pitch) < 1e-7
    rebuilt = qt.from_scipy(Rotation.from_euler("ZYX", [yaw, p, roll]))
    assert qt.angle_between(rebuilt, q) < 1e-7


# ------------------------------------------------------------------------------------------
# ensembles
# ------------------------------------------------------------------------------------------
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


# ------------------------------------------------------------------------------------------
# NetCDF
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("which", ["free", "orbit"])
def test_netcdf_round_trip_is_bitwise(engine, which, free_ds, orbit_ds, tmp_path):
    ds = free_ds if which == "free" else orbit_ds
    path = tmp_path / f"{which}.nc"
    ds.orbatt.to_netcdf(path, engine=engine)
    back = D.open_dataset(path, engine=engine, load=True)
    assert_bitwise_identical(ds, back)
    assert back.orbatt.scenario == SCENARIO
    for name in ds.variables:
        assert back[name].attrs.get("units") == ds[name].attrs.get("units")
    # and through the top-level entry point, with the other engine reading
    other = "h5netcdf" if engine == "netcdf4" else "netcdf4"
    if other in [e for e in ENGINES if isinstance(e, str)]:
        assert_bitwise_identical(ds, orbatt.open_dataset(path, engine=other, load=True))


def test_file_opens_with_plain_xarray_and_netcdf4(orbit_ds, free_ds, tmp_path):
    netCDF4 = pytest.importorskip("netCDF4")
    path = tmp_path / "orbit.nc"
    orbit_ds.orbatt.to_netcdf(path)
    # plain xarray decodes the CF time reference to datetimes at the epoch
    with xr.open_dataset(path) as plain:
        t0 = plain["time"].values[0]
        assert np.issubdtype(plain["time"].dtype, np.datetime64)
        assert str(t0).startswith("2024-03-20T03:06:00")
        step = (plain["time"].values[1] - t0) / np.timedelta64(1, "ns") * 1e-9
        assert abs(step - orbit_ds["time"].values[1]) < 1e-6
        assert plain["omega"].attrs["units"] == "rad s-1"
        assert np.array_equal(plain["q"].values, orbit_ds["q"].values)
    # the raw file: CF attributes that matter
    with netCDF4.Dataset(path) as nc:
        assert nc.getncattr("Conventions") == "CF-1.11"
        assert nc.getncattr("scenario") == SCENARIO
        tv = nc.variables["time"]
        assert tv.getncattr("units") == "seconds since 2024-03-20T03:06:00.000000000Z"
        assert tv.getncattr("calendar") == "standard"
        assert tv.getncattr("standard_name") == "time" and tv.getncattr("axis") == "T"
        assert nc.dimensions["time"].isunlimited()
        for name, var in nc.variables.items():
            if name.endswith("_label"):
                assert var.dtype == np.dtype("S1")  # CF char labels
                continue
            assert "long_name" in var.ncattrs(), name
            units = var.getncattr("units")
            if name != "time":
                u.Unit(units)
            assert "_FillValue" not in var.ncattrs(), name
            if "time" in var.dimensions and var.dtype == np.float64:
                assert var.filters()["zlib"] and var.filters()["shuffle"], name
                chunks = var.chunking()
                assert chunks[var.dimensions.index("time")] == D.DEFAULT_CHUNK_TIME, name
        for name in ["q", "Q", "p", "q_orbital"]:
            assert nc.variables[name].getncattr("quaternion_order") == "w x y z"
    # dimensionless: time units "1", no reference, plain xarray keeps numbers
    p2 = tmp_path / "free.nc"
    free_ds.orbatt.to_netcdf(p2)
    with xr.open_dataset(p2) as plain:
        assert plain["time"].attrs["units"] == "1"
        assert np.array_equal(plain["time"].values, free_ds["time"].values)


# minimal local tables so that cfchecker needs no network
_STD_TABLE = """<?xml version="1.0"?><standard_name_table><version_number>local</version_number>
<last_modified>local</last_modified><entry id="time"><canonical_units>s</canonical_units>
<description>time</description></entry></standard_name_table>"""
_LIST_TABLE = """<?xml version="1.0"?><{0}><version_number>local</version_number><date>local</date>
<entry id="x"></entry></{0}>"""


def test_cf_checker(orbit_ds, tmp_path):
    """cfchecker (CF <= 1.8 only: the file is checked under that label), where installed."""
    cfchecks = pytest.importorskip("cfchecker.cfchecks")
    netCDF4 = pytest.importorskip("netCDF4")
    path = tmp_path / "cf.nc"
    orbit_ds.orbatt.to_netcdf(path)
    with netCDF4.Dataset(path, "a") as nc:
        nc.setncattr("Conventions", "CF-1.8")
    (tmp_path / "std.xml").write_text(_STD_TABLE)
    (tmp_path / "area.xml").write_text(_LIST_TABLE.format("area_type_table"))
    (tmp_path / "region.xml").write_text(_LIST_TABLE.format("standardized_region_list"))
    checker = cfchecks.CFChecker(cfStandardNamesXML=str(tmp_path / "std.xml"),
                                 cfAreaTypesXML=str(tmp_path / "area.xml"),
                                 cfRegionNamesXML=str(tmp_path / "region.xml"),
                                 version=cfchecks.CFVersion((1, 8)), silent=True)
    res = checker.checker(str(path))
    errors = [m for v in [res["global"], *res["variables"].values()] for m in v["FATAL"] + v["ERROR"]]
    assert errors == []


@pytest.mark.parametrize("engine", ENGINES)
def test_appendable_writing(engine, orbit_traj, tmp_path):
    full = D.to_dataset(orbit_traj, scenario_text=SCENARIO)
    n = orbit_traj.t.size
    cuts = [(0, 50), (49, 100), (99, n)]  # pieces share their end points, as segment runs do
    path = tmp_path / "long.nc"
    with D.NetCDFWriter(path, engine=engine, chunk_time=16) as w:
        for a, b in cuts:
            piece = Trajectory(body=orbit_traj.body, potential=orbit_traj.potential, t=orbit_traj.t[a:b],
                               q=orbit_traj.q[a:b], Q=orbit_traj.Q[a:b], inertia=orbit_traj.inertia,
                               method=orbit_traj.method, settings=orbit_traj.settings,
                               stats={"steps": 10, "rhs_evaluations": 120, "wall_time_s": 0.5})
            w.append(D.to_dataset(piece, scenario_text=SCENARIO))
            assert w.samples == b
    back = D.open_dataset(path, engine=engine, load=True)
    assert back.sizes["time"] == n
    for name, var in full.data_vars.items():
        assert np.asarray(back[name].values).tobytes() == np.asarray(var.values).tobytes(), name
        assert back[name].attrs == var.attrs, name
    assert np.array_equal(back["time"].values, full["time"].values)
    stats = back.orbatt.stats
    assert stats["steps"] == 30 and stats["rhs_evaluations"] == 360 and abs(stats["wall_time_s"] - 1.5) < 1e-12
    assert "date_modified" in back.attrs and back.attrs["history"].count("appended") == 2
    assert back.orbatt.scenario == SCENARIO
    # an earlier time is refused; so is a different set of variables
    early = D.to_dataset(Trajectory(body=orbit_traj.body, potential=orbit_traj.potential, t=orbit_traj.t[:3],
                                    q=orbit_traj.q[:3], Q=orbit_traj.Q[:3], inertia=orbit_traj.inertia,
                                    method="x"))
    with pytest.raises(InputError, match="not after"):
        D.write_netcdf(early, path, engine=engine, append=True)
    late = D.to_dataset(Trajectory(body=orbit_traj.body, potential=orbit_traj.potential,
                                   t=orbit_traj.t[-2:] + 1e4, q=orbit_traj.q[-2:], Q=orbit_traj.Q[-2:],
                                   inertia=orbit_traj.inertia, method="x"))
    with pytest.raises(InputError, match="variables"):
        D.write_netcdf(late.drop_vars("euler_321"), path, engine=engine, append=True)
    # append=True on a missing file creates it
    p2 = tmp_path / "new.nc"
    D.write_netcdf(full, p2, engine=engine, append=True)
    assert_bitwise_identical(full, D.open_dataset(p2, engine=engine, load=True))


def test_incomplete_run_is_marked(free_traj, tmp_path):
    tr = Trajectory(body=free_traj.body, potential=free_traj.potential, t=free_traj.t[:10], q=free_traj.q[:10],
                    Q=free_traj.Q[:10], inertia=I_PAPER, method="x", complete=False)
    ds = D.to_dataset(tr)
    assert int(ds.attrs["integration_complete"]) == 0


def test_bad_engine(free_ds, tmp_path):
    with pytest.raises(InputError, match="engine"):
        free_ds.orbatt.to_netcdf(tmp_path / "x.nc", engine="scipy")


# ------------------------------------------------------------------------------------------
# plots
# ------------------------------------------------------------------------------------------
def test_plots(free_ds, orbit_ds, tmp_path):
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig = free_ds.orbatt.plot_state()
    axl, axr = fig.axes
    assert len(axl.lines) == 4 and len(axr.lines) == 4
    assert np.array_equal(axl.lines[0].get_ydata(), free_ds["q"].values[:, 0])
    assert np.array_equal(axr.lines[3].get_ydata(), free_ds["Q"].values[:, 3])
    fig.savefig(tmp_path / "state.png")
    fig2 = orbit_ds.orbatt.plot_attitude()
    assert len(fig2.axes) == 2 and len(fig2.axes[1].lines) == 3
    assert np.allclose(fig2.axes[0].lines[1].get_ydata(), np.degrees(orbit_ds["euler_313"].values[:, 1]))
    fig3 = free_ds.orbatt.plot_drift()
    assert len(fig3.axes) == 3
    fig3.savefig(tmp_path / "drift.png")
    plt.close("all")


@pytest.mark.parametrize("axis,index", [((0, 1, 0), 0), ((0, 0, 1), 1), ((1, 0, 0), 2)])
def test_lvlh_angles_name_the_orbital_axes(axis, index):
    """Roll is about along-track o2, pitch about the orbit normal o3, yaw about radial o1."""
    a = 0.3
    angles = np.array(D.lvlh_angles(qt.from_axis_angle(axis, a)))
    expected = np.zeros(3)
    expected[index] = a
    assert np.allclose(angles, expected, atol=1e-15)

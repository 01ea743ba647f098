"""What the tests of :mod:`orbatt.dataset` share: the paper's data, trajectories, stand-ins of
an orbit provider and of the gravity-gradient potential, the engines, and comparisons."""
import math

import numpy as np
import pytest
import xarray as xr
from astropy import units as u
from astropy.time import Time
from scipy.integrate import solve_ivp

import orbatt
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.core import hamiltonian as H
from orbatt.core import kepler as kk
from orbatt.core import potentials as kp
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
    model = potential.kernel_model()

    def f(tt, y):
        dy = np.empty(8)
        H.rhs(tt, y, inertia, *model, work, dy)
        return dy

    sol = solve_ivp(f, (t[0], t[-1]), np.r_[q0, Q0], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-12)
    assert sol.success
    return Trajectory(body=body, potential=potential, t=np.asarray(t, dtype=float), q=sol.y[:4].T.copy(),
                      Q=sol.y[4:].T.copy(), inertia=np.asarray(inertia, dtype=float), method="scipy-DOP853",
                      settings={"rtol": 1e-12, "atol": 1e-12}, stats={"steps": int(sol.nfev // 12),
                                                                      "rhs_evaluations": int(sol.nfev),
                                                                      "wall_time_s": 0.01})


class CircularOrbit:
    """A small stand-in for an orbit provider (the contract of docs/design.md §5): circular
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


REQUIRED = ["q", "Q", "omega", "g", "G", "energy", "kinetic_energy", "potential_energy", "q_norm_error",
            "qQ", "euler_313", "inertia"]


ORBIT_VARS = ["r", "p", "true_anomaly", "position", "velocity", "q_orbital", "euler_321"]


def _every_units_parses(ds):
    for name, var in ds.variables.items():
        if name.endswith("_label"):
            continue  # string labels of numeric coordinates
        if var.dtype.kind == "M":  # datetime64 time: its CF units are in the encoding
            assert "units" not in var.attrs and var.encoding["units"].startswith("seconds since "), name
            assert "long_name" in var.attrs, name
            continue
        assert "units" in var.attrs, name
        assert "long_name" in var.attrs, name
        u.Unit(var.attrs["units"])  # parses
        assert D.parse_unit(var.attrs["units"]) == u.Unit(var.attrs["units"])

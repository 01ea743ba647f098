"""I/O benchmark (issue 5): build, write and read a Dataset of N samples (default 1e6).

    python benchmarks/io.py [N] [--aem N_AEM]

The attitude is a steady spin about a tilted body axis (smooth like real output) of a
dimensional body in a circular-orbit gravity gradient, so that every variable of
docs/design.md §6 is written (orbit ones included). Prints one line per step: seconds, MB/s of
float64 payload, and the file size.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time

import numpy as np
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt import aem
from orbatt import canonical as cn
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.core import kepler as kk
from orbatt.core import potentials as kp
from orbatt.potentials import Potential
from orbatt.trajectory import Trajectory


class _CircularOrbit:
    """Circular Keplerian orbit with the provider interface (km, s)."""

    def __init__(self, a=7000.0, inc=math.pi / 6, raan=math.pi / 4, argp=0.0, gm=398600.4418):
        self.a, self.inc, self.raan, self.argp, self.gm = a, inc, raan, argp, gm
        self.n = math.sqrt(gm / a**3)
        self.period = 2 * math.pi / self.n
        self.epoch = Time("2024-01-01T00:00:00", scale="utc")

    def true_anomaly(self, t):
        return self.n * t

    def radius(self, t):
        return np.full(t.shape, self.a)

    def orbital_quaternion(self, t):
        return qt.from_euler313(self.raan, self.inc, self.argp + self.n * t)

    def state(self, t):
        p = self.orbital_quaternion(t)
        return (self.a * qt.rotate(p, np.array([1.0, 0, 0])),
                self.a * self.n * qt.rotate(p, np.array([0, 1.0, 0])))

    def describe(self):
        return {"provider": "benchmark-circular", "a": self.a}


class _GravityGradient(Potential):
    kind = kp.GRAVITY_GRADIENT_KEPLER
    name = "gravity-gradient"

    def __init__(self, orbit):
        self.orbit = orbit
        self.params = np.r_[orbit.gm, kk.orbit_vector(orbit.a, 0.0, orbit.inc, orbit.raan, orbit.argp, 0.0, orbit.n)]


def synthetic_trajectory(n):
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    orbit = _CircularOrbit()
    t = np.linspace(0.0, 10 * orbit.period, n)
    w = 1e-3
    q0 = qt.normalize(np.array([0.5, -1 / np.sqrt(2), 0.1, 0.5]))
    spin = np.stack([np.cos(w * t / 2), 0 * t, 0 * t, np.sin(w * t / 2)], axis=-1)
    q = qt.mul(q0, spin)
    Q = cn.momentum_from_body_momentum(q, np.broadcast_to([0.0, 0.0, 600.0 * w], (n, 3)))
    return Trajectory(body=body, potential=_GravityGradient(orbit), t=t, q=q, Q=Q, inertia=body.inertia_value,
                      method="synthetic", settings={}, stats={"steps": n})


def _timed(label, fn, payload_bytes=None, size_of=None):
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    extra = ""
    if payload_bytes:
        extra += f"  {payload_bytes / dt / 1e6:8.0f} MB/s"
    if size_of:
        extra += f"  file {os.path.getsize(size_of) / 1e6:7.1f} MB"
    print(f"{label:<40s} {dt:8.2f} s{extra}", flush=True)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="?", type=int, default=1_000_000)
    ap.add_argument("--aem", type=int, default=None, help="samples for the AEM lines (default: n)")
    args = ap.parse_args(argv)
    n = args.n
    tr = synthetic_trajectory(n)
    print(f"orbatt {orbatt.__version__}, N = {n:,} samples, numpy {np.__version__}", flush=True)
    ds = _timed("to_dataset (derived quantities)", lambda: D.to_dataset(tr, scenario_text="name = 'bench'\n"))
    payload = sum(v.nbytes for v in ds.variables.values())
    print(f"{'':<40s} {len(ds.data_vars)} variables, {payload / 1e6:.0f} MB of values")
    with tempfile.TemporaryDirectory() as tmp:
        engines = ["netcdf4"]
        try:
            import h5netcdf  # noqa: F401
            import h5py  # noqa: F401

            engines.append("h5netcdf")
        except ImportError:
            print("h5netcdf engine: not installed (h5netcdf + h5py), skipped")
        for eng in engines:
            for level in (1, 0):
                path = os.path.join(tmp, f"{eng}{level}.nc")
                _timed(f"write {eng} zlib={level}", lambda: D.write_netcdf(ds, path, engine=eng, complevel=level),
                       payload, path)
                back = _timed(f"read  {eng} zlib={level} (open + load)",
                              lambda: D.open_dataset(path, engine=eng, load=True), payload)
                assert np.asarray(back["q"].values).tobytes() == ds["q"].values.tobytes()
        # appended in 10 pieces
        path = os.path.join(tmp, "appended.nc")
        cuts = np.linspace(0, n, 11).astype(int)

        def appended():
            with D.NetCDFWriter(path) as w:
                for a, b in zip(cuts[:-1], cuts[1:]):
                    w.append(ds.isel(time=slice(a, b)))

        _timed("write netcdf4 appended in 10 pieces", appended, payload, path)
        na = n if args.aem is None else args.aem
        sub = ds.isel(time=slice(0, na))
        apath = os.path.join(tmp, "att.aem")
        _timed(f"write AEM ({na:,} lines)", lambda: aem.write_aem(sub, apath), None, apath)
        _timed(f"read  AEM ({na:,} lines)", lambda: aem.read_aem(apath))
    return 0


if __name__ == "__main__":
    sys.exit(main())

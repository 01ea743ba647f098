"""The REBOUND orbit provider: the satellite integrated by REBOUND as a massless particle
about the central body (optionally with the central body's J2 through REBOUNDx and the
Moon and the Sun from astropy's built-in ephemeris), sampled densely once and interpolated
by a compiled quintic Hermite polynomial (:mod:`orbatt.core.sampled`)."""
from __future__ import annotations

import ctypes
import math

import numpy as np
from astropy import constants as const
from astropy import units as u

from .. import fast_paths
from .. import units as U
from ..core import sampled as ks
from ..epoch import epoch_string
from ..errors import InputError
from .base import GM_EARTH
from .kepler import KeplerOrbit
from .sampled import SampledOrbit

#: Earth's J2 (unnormalized; EGM2008 tide-free ``C20bar = -0.484165143790815e-3``,
#: ``J2 = -sqrt(5) C20bar``).
J2_EARTH = 1.08262617385222e-3
#: Reference (equatorial) radius of the EGM2008 coefficients (km).
R_J2_EARTH = 6378.1363
#: The Moon's mass parameter (km^3 s^-2), JPL DE430.
GM_MOON = 4902.800066
#: The Sun's mass parameter (km^3 s^-2): astropy ``GM_sun`` (IAU 2015 nominal).
GM_SUN = float(const.GM_sun.to_value(U.GM))

PERTURBATIONS = ("j2", "moon", "sun")
INTEGRATORS = ("ias15", "whfast")

#: what a sample reads of each particle, in the order of REBOUND's ``reb_particle`` struct
PARTICLE_FIELDS = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az")
#: the fast path ``rebound-particles`` (:mod:`orbatt.fast_paths`): the particles' states read
#: from REBOUND's particle array in memory through ctypes (its private ``sim._particles``; the
#: struct's first nine doubles are :data:`PARTICLE_FIELDS`) instead of attribute by attribute.
#: None until its first use checks it against the attributes, bit for bit; False after a
#: mismatch or a failure (the attributes for the rest of the process), or with the switch off
_RAW_READS = {"ok": None if fast_paths.ENABLED else False}


def raw_reads_in_use() -> bool:
    """Whether the ``rebound-particles`` fast path may be used (not turned off, not failed)."""
    return _RAW_READS["ok"] is not False


def _particle_states(sim, indices):
    """``(len(indices), 9)``: :data:`PARTICLE_FIELDS` of those particles, read the public way."""
    return np.array([[getattr(sim.particles[k], f) for f in PARTICLE_FIELDS] for k in indices], dtype=np.float64)


def _raw_view(sim, nbody):
    """The particle array as a ``(N, stride)`` float64 view of REBOUND's memory (or None where
    the struct is not a whole number of doubles holding :data:`PARTICLE_FIELDS` first)."""
    size = ctypes.sizeof(type(sim._particles.contents))
    if size % 8 or size // 8 < len(PARTICLE_FIELDS):
        return None
    stride = size // 8
    buf = (ctypes.c_double * (nbody * stride)).from_address(ctypes.addressof(sim._particles.contents))
    return np.frombuffer(buf, dtype=np.float64).reshape(nbody, stride)


class ReboundOrbit(SampledOrbit):
    """An orbit integrated by REBOUND over ``[0, t_end]`` and interpolated in between.

    Parameters
    ----------
    initial : KeplerOrbit
        The osculating orbit at the epoch (``t = 0``): its state vector starts the
        integration; its ``gm``, ``central_body``, ``epoch`` are used. A dimensionless
        orbit (plain ``a`` and ``gm``) makes a dimensionless REBOUND orbit: ``t_end``,
        ``dt`` and ``reference_radius`` are then plain numbers in its units.
    t_end : Quantity (time), str, or float (dimensionless orbit)
        End of the sampled span (``> 0``); the orbit is available for ``0 <= t <= t_end``
        (the last sample may lie slightly beyond). Times outside raise.
    perturbations : sequence of str, optional
        Any of ``"j2"`` (the central body's J2 through REBOUNDx ``gravitational_harmonics``,
        about the ``s3`` axis), ``"moon"``, ``"sun"`` (point masses placed from astropy's
        built-in ephemeris at the epoch, then integrated with the rest: ``S`` has the ICRS
        axes, so orbital elements refer to the ICRS (~J2000) equator). Default: none
        (pure two-body).
    integrator : {"ias15", "whfast"}
        REBOUND integrator. ``"ias15"`` (default) is adaptive and accurate to machine
        precision; ``"whfast"`` (Wisdom-Holman, Jacobi coordinates, fixed step ``dt``) is
        exact for the Keplerian part and second order in the perturbations.
    samples_per_orbit : int
        Sample density ``N`` (IAS15): samples are spaced by ``h = (2 pi / N) sqrt(r^3 / GM)``
        at the radius ``r`` predicted for mid-interval (denser at periapsis). The quintic
        Hermite position error scales as ``N^-6``; measured at the default ``N = 128``
        (two-body, against Kepler, relative to ``r``): 3e-13 (e = 0), 2.4e-12 (e = 0.2,
        the paper's orbit), 4e-11 (e = 0.74), 2e-10 (e = 0.95 and 0.99); the velocity
        (derivative of the interpolant) is 50 to 70 times less accurate.
        ``tests/test_rebound_orbit.py`` checks these bounds.
    epsilon : float, optional
        IAS15 accuracy parameter (REBOUND's default 1e-9 if not given).
    dt : Quantity (time), optional
        WHFast step; default ``period / samples_per_orbit``. Samples are taken every
        ``max(1, round(h_nominal / dt))`` steps (``h_nominal = period / N``).
    j2, reference_radius : float, Quantity (length), optional
        J2 and its reference radius. Default for the Earth: EGM2008 (``J2_EARTH``,
        ``R_J2_EARTH``); required for another central body.

    Notes
    -----
    Units inside REBOUND: ``G = 1``, km, s; masses are mass parameters (km^3 s^-2). The
    central body is particle 0, the satellite (massless) particle 1, then Moon and Sun;
    the state given to the kernels is relative to the central body. After each sample
    time REBOUND's accelerations are recomputed (``reb_simulation_update_acceleration``,
    all gravity terms and REBOUNDx forces) so that the Hermite data ``(x, v, a)`` are
    consistent (this call does not change REBOUND's trajectory: checked bit for bit). The
    samples are in :attr:`samples` (``(N, 10)``: ``t, x, v, a``).

    J2 acts about the ``s3`` axis of ``S``. With third bodies ``S`` has the ICRS axes
    (geocentric), whose ``s3`` is the J2000 pole: the precession of the Earth's true pole
    since J2000 (about 0.15 deg by 2026) is neglected. The Moon and the Sun start from
    astropy's ``"builtin"`` ephemeris (no network) and are then integrated with the rest
    (Earth, Moon, Sun as point masses), which is ample for their tidal effect on the
    satellite over weeks.

    Measured (``tests/test_rebound_orbit.py``): two-body IAS15 against Kepler over 10
    orbits of the paper's orbit, 2.8e-12 relative at the samples and 4.8e-12 interpolated;
    with J2 over 30 days, the fitted nodal regression is within 0.25 % of
    ``-(3/2) n J2 (R/p)^2 cos i`` for time-averaged (mean) elements.

    Raises
    ------
    InputError
        Unknown perturbation or integrator names, a non-positive ``t_end``, third bodies
        without an epoch or about a central body other than the Earth, J2 about a custom
        body without ``j2`` and ``reference_radius``.
    """

    name = "rebound"
    span_hint = "build it with a larger t_end"

    def __init__(self, initial, t_end, *, perturbations=(), integrator="ias15", samples_per_orbit=128,
                 epsilon=None, dt=None, j2=None, reference_radius=None):
        if not isinstance(initial, KeplerOrbit):
            raise InputError(f"initial: expected a KeplerOrbit (the osculating orbit at the epoch), got "
                             f"{type(initial).__name__}; or use ReboundOrbit.from_elements(...)")
        self.initial = initial
        self.gm = initial.gm
        self.central_body = initial.central_body
        self.epoch = initial.epoch
        self.period_value = initial.period_value
        self.dimensionless = dimless = initial.dimensionless
        te = U.strip(t_end, U.TIME, "t_end", allow_plain=dimless)
        if te.shape != () or not te > 0:
            raise InputError(f"t_end: {t_end!r} must be one positive time, e.g. '1 d'")
        self.t_end = float(te)
        if isinstance(perturbations, str):
            perturbations = [perturbations]
        perts = []
        for p in perturbations:
            key = str(p).lower()
            if key not in PERTURBATIONS:
                raise InputError(f"perturbations: {p!r} is not known; choose from {list(PERTURBATIONS)}")
            if key not in perts:
                perts.append(key)
        self.perturbations = tuple(perts)
        if str(integrator).lower() not in INTEGRATORS:
            raise InputError(f"integrator: {integrator!r} is not known; choose 'ias15' or 'whfast'")
        self.integrator = str(integrator).lower()
        n = int(samples_per_orbit) if np.ndim(samples_per_orbit) == 0 else -1
        if n != samples_per_orbit or n < 8:
            raise InputError(f"samples_per_orbit: {samples_per_orbit!r} must be an integer >= 8 (default 128)")
        self.samples_per_orbit = n
        third = [p for p in self.perturbations if p in ("moon", "sun")]
        if third and self.central_body != "earth":
            raise InputError(f"perturbations: {third} are third bodies of an Earth orbit; this orbit is about "
                             f"{self.central_body!r}. Remove them or orbit the Earth")
        if third and self.epoch is None:
            raise InputError(f"epoch: third bodies {third} need an epoch to be placed; give the initial orbit "
                             "an epoch, e.g. epoch='2026-03-20T00:00:00'")
        self.j2 = None
        self.reference_radius = None
        if "j2" in self.perturbations:
            if self.central_body == "earth":
                self.j2 = J2_EARTH if j2 is None else float(U.strip(j2, U.DIMENSIONLESS, "j2"))
                self.reference_radius = (R_J2_EARTH if reference_radius is None
                                         else float(U.strip(reference_radius, U.LENGTH, "reference_radius",
                                                                allow_plain=dimless)))
            else:
                if j2 is None or reference_radius is None:
                    raise InputError(f"j2: the J2 perturbation about {self.central_body!r} needs j2=... and "
                                     "reference_radius=... (only the Earth's are built in)")
                self.j2 = float(U.strip(j2, U.DIMENSIONLESS, "j2"))
                self.reference_radius = float(U.strip(reference_radius, U.LENGTH, "reference_radius",
                                                      allow_plain=dimless))
            if not self.reference_radius > 0:
                raise InputError(f"reference_radius: {reference_radius!r} must be positive")
        self.epsilon = None
        self.dt = None
        if self.integrator == "ias15":
            if dt is not None:
                raise InputError("dt: only used by integrator='whfast' (IAS15 is adaptive); remove it")
            if epsilon is not None:
                self.epsilon = float(epsilon)
                if not self.epsilon >= 0:
                    raise InputError(f"epsilon: {epsilon!r} must be >= 0 (IAS15 accuracy parameter)")
        else:
            if epsilon is not None:
                raise InputError("epsilon: only used by integrator='ias15'; remove it or give dt for WHFast")
            self.dt = self.period_value / n if dt is None else float(U.strip(dt, U.TIME, "dt", allow_plain=dimless))
            if not self.dt > 0:
                raise InputError(f"dt: {dt!r} must be a positive time")
        table = self._integrate()
        table.flags.writeable = False
        self._table = table

    @classmethod
    def from_elements(cls, a, e, i, raan, argp, *, t_end, true_anomaly=None, mean_anomaly=None,
                      eccentric_anomaly=None, gm=None, central_body=None, epoch=None, body_radius="default",
                      **options):
        """Build from classical elements (as :class:`KeplerOrbit`); ``options`` are those of
        :class:`ReboundOrbit` (``perturbations``, ``integrator``, ...)."""
        initial = KeplerOrbit(a, e, i, raan, argp, true_anomaly=true_anomaly, mean_anomaly=mean_anomaly,
                              eccentric_anomaly=eccentric_anomaly, gm=gm, central_body=central_body,
                              epoch=epoch, body_radius=body_radius)
        return cls(initial, t_end, **options)

    @classmethod
    def from_simulation(cls, sim, *, t_end, particle=1, central=0, units=None, epoch=None, samples_per_orbit=128):
        """Sample a REBOUND simulation the user built: the ``particle``'s motion relative to
        the ``central`` one, with everything in the simulation (its integrator, its other
        particles, any REBOUNDx forces attached to it).

        Parameters
        ----------
        sim : rebound.Simulation
            Advanced in place from its current time ``sim.t`` (orbatt's ``t = 0``) to
            ``sim.t + t_end``; pass ``sim.copy()`` to keep the original.
        t_end : Quantity (time), or float in the simulation's time unit
            Span to sample (``> 0``).
        particle, central : int or str
            Index (or hash name) of the satellite and of the central body whose ``G m`` is
            the gravity gradient's ``GM``.
        units : tuple (length, time), dict, or ``"normalized"``, optional
            The simulation's length and time units, e.g. ``("au", "yr2pi")`` or ``("km",
            "s")`` (astropy names; REBOUND's ``yr2pi`` is a year over 2 pi). Default: read from
            ``sim.units`` (set by ``sim.units = ("au", "yr", "msun")``); refused when neither
            says. ``"normalized"`` makes a dimensionless orbit (plain numbers as they are).
        epoch : astropy.time.Time or str, optional
            The instant ``t = 0`` (dimensional orbits only).
        samples_per_orbit : int
            Sample density, as for :class:`ReboundOrbit` (IAS15: adaptive to the radius;
            other integrators: every ``round(period / N / sim.dt)`` steps).

        Returns
        -------
        ReboundOrbit
            ``initial`` is the osculating orbit at ``t = 0``; ``perturbations`` is
            ``("simulation",)``; the samples are in km, s (or plain numbers).
        """
        import rebound
        from rebound import clibrebound

        if not isinstance(sim, rebound.Simulation):
            raise InputError(f"sim: expected a rebound.Simulation, got {type(sim).__name__}")
        length, time = _simulation_units(sim, units)
        normalized = length is None
        try:
            pc, pp = sim.particles[central], sim.particles[particle]
        except (IndexError, KeyError, TypeError, ValueError, AttributeError):
            raise InputError(f"particle/central: {particle!r}/{central!r} are not particles of this simulation "
                             f"({sim.N} particles)") from None
        ic, ip = pc.index, pp.index
        if ic == ip:
            raise InputError(f"particle: {particle!r} is the central body too; choose another particle")
        gm_sim = sim.G * pc.m
        if not gm_sim > 0:
            raise InputError(f"central: particle {central!r} has G m = {gm_sim!r}; the central body needs a mass")
        Lk = 1.0 if normalized else float((1.0 * length).to_value(U.LENGTH))
        Ts = 1.0 if normalized else float((1.0 * time).to_value(U.TIME))
        r = np.array(pp.xyz) - np.array(pc.xyz)
        v = np.array(pp.vxyz) - np.array(pc.vxyz)
        gm = gm_sim * Lk**3 / Ts**2
        if normalized:
            initial = KeplerOrbit.from_state(r, v, gm=gm, body_radius=None)
            te = U.strip(t_end, U.TIME, "t_end", allow_plain=True)
        else:
            initial = KeplerOrbit.from_state(r * Lk * U.LENGTH, v * Lk / Ts * U.LENGTH / U.TIME, gm=gm * U.GM,
                                             epoch=epoch, body_radius=None)
            te = (U.strip(t_end, U.TIME, "t_end") if isinstance(t_end, (str, u.Quantity))
                  else np.asarray(float(t_end) * Ts))
        if te.shape != () or not te > 0:
            raise InputError(f"t_end: {t_end!r} must be one positive time")
        n = int(samples_per_orbit) if np.ndim(samples_per_orbit) == 0 else -1
        if n != samples_per_orbit or n < 8:
            raise InputError(f"samples_per_orbit: {samples_per_orbit!r} must be an integer >= 8 (default 128)")
        self = cls.__new__(cls)
        self.initial, self.gm, self.central_body = initial, initial.gm, "custom"
        self.epoch, self.period_value, self.dimensionless = initial.epoch, initial.period_value, normalized
        self.t_end, self.samples_per_orbit, self.perturbations = float(te), n, ("simulation",)
        self.integrator = str(sim.integrator)
        self.j2 = self.reference_radius = None
        self.epsilon = None
        self.dt = None if self.integrator == "ias15" else float(sim.dt) * Ts
        table = self._sample(sim, clibrebound, (ip, ic), gm_sim, self.t_end / Ts, self.period_value / Ts)
        scale = np.array([Ts] + [Lk] * 3 + [Lk / Ts] * 3 + [Lk / Ts**2] * 3)
        table = np.ascontiguousarray(table * scale)
        table.flags.writeable = False
        self._table = table
        return self

    # ---- integration ------------------------------------------------------------------
    def _third_bodies(self):
        """Geocentric ICRS states (km, km/s) and mass parameters of the Moon/Sun at the epoch."""
        from astropy.coordinates import get_body_barycentric_posvel

        out = []
        pe, ve = get_body_barycentric_posvel("earth", self.epoch, ephemeris="builtin")
        for name, gm in (("moon", GM_MOON), ("sun", GM_SUN)):
            if name not in self.perturbations:
                continue
            pb, vb = get_body_barycentric_posvel(name, self.epoch, ephemeris="builtin")
            r = (pb.xyz - pe.xyz).to_value(U.LENGTH)
            v = (vb.xyz - ve.xyz).to_value(U.LENGTH / U.TIME)
            out.append((name, gm, r, v))
        return out

    def _integrate(self):
        import rebound
        from rebound import clibrebound

        sim = rebound.Simulation()
        sim.G = 1.0
        r0, v0 = self.initial.state(0.0)
        sim.add(m=self.gm, x=0.0, y=0.0, z=0.0, vx=0.0, vy=0.0, vz=0.0)
        sim.add(m=0.0, x=r0[0], y=r0[1], z=r0[2], vx=v0[0], vy=v0[1], vz=v0[2])
        if self.epoch is not None and any(p in self.perturbations for p in ("moon", "sun")):
            for _, gm, r, v in self._third_bodies():
                sim.add(m=gm, x=r[0], y=r[1], z=r[2], vx=v[0], vy=v[1], vz=v[2])
        rebx = None
        if self.j2 is not None:
            import reboundx

            rebx = reboundx.Extras(sim)
            gh = rebx.load_force("gravitational_harmonics")
            rebx.add_force(gh)
            sim.particles[0].params["J2"] = self.j2
            sim.particles[0].params["R_eq"] = self.reference_radius
        sim.integrator = self.integrator
        if self.integrator == "ias15":
            if self.epsilon is not None:
                sim.integrator.epsilon = self.epsilon
        else:
            sim.dt = self.dt
        try:
            table = self._sample(sim, clibrebound, (1, 0), self.gm, self.t_end, self.period_value)
        finally:
            if rebx is not None:
                del rebx
            del sim
        return table

    def _sample(self, sim, clib, pair, gm, t_end, period):
        """Sample particle ``pair[0]`` relative to ``pair[1]`` over ``[sim.t, sim.t + t_end]``
        (the simulation's units; ``gm`` and ``period`` in them): rows ``t - t0, x, v, a``."""
        ip, ic = pair
        t0 = sim.t
        nbody = sim.N
        cache = {}

        def states():
            """``(2, >= 9)``: the states of particles ``ip`` and ``ic`` - from the fast path's
            view of REBOUND's memory (checked against the attributes on its first use in the
            process), else from the attributes (``_RAW_READS``)."""
            if _RAW_READS["ok"] is not False:
                try:
                    addr = ctypes.addressof(sim._particles.contents)
                    if cache.get("addr") != addr:  # the array moved (or a first read)
                        cache["addr"], cache["v"] = addr, _raw_view(sim, nbody)
                    raw = None if cache["v"] is None else cache["v"][[ip, ic]]
                    if raw is not None and _RAW_READS["ok"] is None:
                        _RAW_READS["ok"] = bool(np.array_equal(raw[:, :len(PARTICLE_FIELDS)],
                                                               _particle_states(sim, (ip, ic))))
                except (AttributeError, TypeError, ValueError):  # a REBOUND without the private array
                    raw = None
                if raw is not None and _RAW_READS["ok"]:
                    return raw
                _RAW_READS["ok"] = False
            return _particle_states(sim, (ip, ic))

        def record(rows):
            ignore = sim.gravity_ignore
            sim.gravity_ignore = 0  # WHFast skips the Keplerian term; we want all of it
            clib.reb_simulation_update_acceleration(ctypes.byref(sim))
            sim.gravity_ignore = ignore
            p, c = states()
            row = np.empty(ks.TABLE_COLUMNS)
            row[0] = sim.t - t0
            row[1:] = p[:9] - c[:9]  # x, y, z, vx, vy, vz, ax, ay, az relative to the centre
            rows.append(row)
            return row

        rows = []
        row = record(rows)
        c = 2.0 * math.pi / self.samples_per_orbit
        if self.integrator == "ias15":
            t = 0.0
            while t < t_end:
                r = math.sqrt(row[1] ** 2 + row[2] ** 2 + row[3] ** 2)
                rdot = (row[1] * row[4] + row[2] * row[5] + row[3] * row[6]) / r
                h = c * math.sqrt(r**3 / gm)
                rm = max(r + 0.5 * rdot * h, 0.5 * r)  # radius predicted at mid-interval
                h = c * math.sqrt(rm**3 / gm)
                left = t_end - t
                if left <= h:
                    t_next = t_end
                elif left < 2.0 * h:  # two equal intervals rather than a long or a sliver one
                    t_next = t + 0.5 * left
                else:
                    t_next = t + h
                sim.integrate(t0 + t_next, exact_finish_time=1)
                t = sim.t - t0
                row = record(rows)
        else:
            k = max(1, int(round(period / self.samples_per_orbit / sim.dt)))
            while sim.t - t0 < t_end:
                sim.steps(k)
                row = record(rows)
        return np.ascontiguousarray(np.array(rows))

    def describe(self):
        """Plain description: the initial orbit's keys (``a_km``, ...; ``type`` is
        ``"rebound"``), ``perturbations``, ``integrator``, ``t_end_s``, ``samples_per_orbit``,
        ``n_samples``, ``epsilon`` or ``dt_s``, ``j2`` and ``reference_radius_km`` with J2,
        and the REBOUND (and REBOUNDx) versions."""
        import rebound

        d = self.initial.describe()
        d["type"] = "rebound"
        d.update({"perturbations": list(self.perturbations), "integrator": self.integrator,
                  ("t_end" if self.dimensionless else "t_end_s"): self.t_end, "samples_per_orbit": self.samples_per_orbit,
                  "n_samples": int(self._table.shape[0]), "rebound_version": rebound.__version__})
        if self.integrator == "ias15":
            d["epsilon"] = self.epsilon if self.epsilon is not None else 1e-9
        else:
            d["dt" if self.dimensionless else "dt_s"] = self.dt
        if self.j2 is not None:
            import reboundx

            d.update({"j2": self.j2, ("reference_radius" if self.dimensionless else "reference_radius_km"):
                      self.reference_radius,
                      "reboundx_version": reboundx.__version__})
        if self.epoch is not None:
            d["epoch"] = epoch_string(self.epoch)
        return d


#: REBOUND time unit names astropy does not know
_REBOUND_TIMES = {"yr2pi": u.yr / (2.0 * math.pi)}


def _simulation_units(sim, units):
    """``(length, time)`` astropy units of a REBOUND simulation, from ``units`` or else
    ``sim.units``; ``(None, None)`` for ``units="normalized"``."""
    if isinstance(units, str) and units == "normalized":
        return None, None
    if units is None:
        su = sim.units
        if not su.get("length") or not su.get("time"):
            raise InputError("units: the simulation's units are not set (sim.units); give units=('km', 's'), "
                             "units=('au', 'yr2pi') ... or units='normalized', or set sim.units first")
        units = (su["length"], su["time"])
    if isinstance(units, dict):
        units = (units.get("length"), units.get("time"))
    try:
        length, time = units
        length = u.Unit(length)
        time = _REBOUND_TIMES.get(str(time).lower()) or u.Unit(time)
    except (TypeError, ValueError):
        raise InputError(f"units: {units!r} is not (length, time), e.g. ('km', 's') or ('au', 'yr2pi')") from None
    if length.physical_type != "length" or time.physical_type != "time":
        raise InputError(f"units: {units!r} is not (length, time), e.g. ('km', 's') or ('au', 'yr2pi')")
    return length, time


__all__ = ["ReboundOrbit", "J2_EARTH", "R_J2_EARTH", "GM_MOON", "GM_SUN", "GM_EARTH"]

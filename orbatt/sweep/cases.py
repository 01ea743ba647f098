"""The :class:`Sweep`: a scenario with a ``[sweep]`` table, its seed, and every case's
parameter values (drawn once, when it is built); :func:`load_sweep` reads one from a file.
Manual: ``docs/sweeps.md``."""
from __future__ import annotations

import hashlib
import json
import secrets
import time
import tomllib
import warnings

import numpy as np

from ..errors import InputError, ScenarioError
from ..units import LEGACY_OUTPUT
from ..scenario import Scenario, load_scenario, parse
from ..scenario.binary_schema import BinarySpec
from ..scenario.paths import toml_text
from .case_groups import case_data, case_text
from ..scenario.sweep_schema import sweep_units
from .chunk import compute_chunk
from .sampling import SAMPLING_VERSION, draw_samples, nominal_values

__all__ = ["Sweep", "load_sweep", "check_sweep_work", "si_description", "FORMAT", "MAX_SWEEP_WORK_STEPS",
           "MIN_CASE_STEPS"]

#: most integration steps a sweep may need by the lower estimate (cases times the nominal
#: case's steps): about an hour of a few cores at the compiled kernels' speed
MAX_SWEEP_WORK_STEPS = 1e9
#: the least work counted per case (its setup and study outputs cost as much as ~1000 steps: a
#: millisecond; 1e7 cases are hours)
MIN_CASE_STEPS = 1000.0

#: format tag of a sweep's fingerprint and parts manifest
FORMAT = "orbatt-sweep-1"


class Sweep:
    """A validated sweep: the nominal :class:`~orbatt.scenario.Scenario`, its ``[sweep]``
    table, and every case's parameter values (drawn once, here).

    Build one with :func:`load_sweep`.

    Parameters
    ----------
    scenario : Scenario
        A scenario with a ``[sweep]`` table.
    seed : int, optional
        Overrides the table's seed (or fixes the one to use when the table has none).

    Attributes
    ----------
    scenario : Scenario
    spec : SweepSpec
    seed : int
    seed_source : str
        ``"scenario"``, ``"argument"`` or ``"default"`` (drawn from OS entropy).
    cases : int
    values : dict of str to ndarray (cases,)
        Every swept parameter's value per case (internal units).
    attitude_axis : ndarray (cases, 3) or None
    resampled : int
        Cases redrawn for physical limits (``on_invalid = "resample"``).
    nominal : dict
        Nominal value of every parameter (internal units).
    fingerprint : str
        Hash of the scenario text, seed, number of cases and the version of the drawing code
        (:data:`~orbatt.sweep.sampling.SAMPLING_VERSION`); written into the parts folder's
        manifest and every part, checked on resume and before the merge.
    """

    def __init__(self, scenario, seed=None):
        spec = scenario.spec.sweep
        if spec is None:
            raise InputError(f"{scenario.path or scenario.name}: [sweep]: missing table; a sweep scenario needs "
                             "[sweep] with samples and [sweep.parameters] (see docs/sweeps.md)")
        self.scenario = scenario
        self.spec = spec
        if seed is not None:
            if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**63:
                raise InputError(f"seed: {seed!r} must be an integer in [0, 2**63)")
            self.seed, self.seed_source = int(seed), "argument"
        elif spec.seed is not None:
            self.seed, self.seed_source = spec.seed, "scenario"
        else:
            self.seed, self.seed_source = secrets.randbits(63), "default"
        self.cases = spec.cases
        check_sweep_work(scenario, spec)
        self.nominal = nominal_values(scenario)
        dimless = scenario.spec.dimensionless
        self.units = sweep_units(spec, dimless)
        check = _case_check(scenario, spec) if spec.paths else None
        # messages name a path's unit as the scenario file writes it ("kg m2"), the file the CF way
        said = {**self.units, **{k: v for k, v in spec.paths.items() if v is not None}}
        self.values, self.attitude_axis, self.resampled = draw_samples(spec, self.seed, self.nominal, said, check)
        h = hashlib.sha256(f"{FORMAT}\nsampling {SAMPLING_VERSION}\n{self.seed}\n{self.cases}\n".encode()
                           + scenario.text.encode())
        self.fingerprint = h.hexdigest()[:32]

    @property
    def source(self) -> str:
        return str(self.scenario.path) if self.scenario.path is not None else self.scenario.name

    def job(self, start, stop, numba_threads=None) -> dict:
        """The payload of a task: the chunk of cases ``start .. stop - 1``.

        Parameters
        ----------
        start, stop : int
            Case range (``stop`` excluded).
        numba_threads : int, optional
            Threads numba may use inside the task (None: numba's default).

        Returns
        -------
        dict
            The scenario text and source, the range, the chunk's parameter values and
            attitude axes (plain data: cheap to send, nothing to scatter).
        """
        return {"text": self.scenario.text, "source": self.source, "start": int(start), "stop": int(stop),
                "values": {k: v[start:stop].copy() for k, v in self.values.items()},
                "axis": None if self.attitude_axis is None else self.attitude_axis[start:stop].copy(),
                "numba_threads": numba_threads}

    def case_text(self, k) -> str:
        """The scenario (TOML text) of case ``k``: the file with the swept keys replaced, without
        ``[sweep]``. ``orbatt run`` of it gives the case's results bit for bit."""
        if not 0 <= k < self.cases:
            raise InputError(f"case: {k!r} is not one of the {self.cases} cases")
        return case_text(self.scenario, self.spec, self.values, k)

    def compute(self, start=0, stop=None):
        """Compute a range of cases here, as one chunk: one ensemble call of
        :func:`orbatt.propagate` per distinct orbit.

        This is what every Dask task runs; ``sweep.compute()`` is the serial reference of a
        whole sweep (numba uses every core).

        Parameters
        ----------
        start, stop : int
            Case range (``stop`` excluded; default all cases).

        Returns
        -------
        xarray.Dataset
            The cases' outputs (dimension ``case``), without the sweep's global attributes
            (:func:`run_sweep` adds them).
        """
        stop = self.cases if stop is None else stop
        if not 0 <= start < stop <= self.cases:
            raise InputError(f"cases: [{start}, {stop}) is not a range within the {self.cases} cases")
        return compute_chunk(self.scenario, self.spec, self.job(start, stop), self.units)

    def attrs(self) -> dict:
        """The sweep's global attributes (seed, parameters, cases, ...)."""
        desc = {k: si_description(d.describe(self.nominal.get(k)), self.units[k])
                for k, d in self.spec.parameters.items()}
        return {
            "sweep_format": FORMAT,
            "sweep_fingerprint": self.fingerprint,
            "sweep_seed": np.int64(self.seed),
            "sweep_seed_source": self.seed_source,
            "sweep_rng": "numpy.random.Generator(PCG64(sweep_seed))",
            "sweep_cases": np.int64(self.cases),
            "sweep_samples": np.int64(self.spec.samples),
            "sweep_grid_points": np.int64(self.spec.grid_points),
            "sweep_parameters": json.dumps(desc),  # canonical order
            "sweep_outputs": json.dumps(list(self.spec.outputs)),
            "sweep_on_invalid": self.spec.on_invalid,
            "sweep_resampled_cases": np.int64(self.resampled),
        }

    def __repr__(self):
        return (f"Sweep({self.scenario.name!r}, cases={self.cases}, parameters={list(self.spec.parameters)}, "
                f"seed={self.seed})")


def si_description(desc, unit):
    """A parameter's description (:meth:`~orbatt.scenario.sweep_schema.Distribution.describe`)
    with ``units``: its numbers in SI where ``unit`` is a kernel unit of the attitude family
    (the inertia parameters' kg km^2 -> kg m^2), as its case coordinate is written
    (:func:`orbatt.sweep.case_coords.parameter_coordinates`)."""
    conv = LEGACY_OUTPUT.get(unit)
    if conv is None:
        return dict(desc, units=unit)
    si_unit, factor = conv
    out = {k: ([x * factor for x in v] if k == "values" else v * factor if k in ("mean", "std", "low", "high") else v)
           for k, v in desc.items()}
    out["units"] = si_unit
    return out


def check_sweep_work(scenario, spec):
    """Refuse, naming ``[sweep] samples`` (or the grid), a sweep whose cases times the nominal
    case's estimated steps (:attr:`orbatt.scenario.Scenario.work_steps`, at least
    :data:`MIN_CASE_STEPS` a case) exceed :data:`MAX_SWEEP_WORK_STEPS`, before any sample is
    drawn."""
    per_case = getattr(scenario, "work_steps", None)  # None: a study without the estimate
    if per_case is None:
        return
    steps = spec.cases * max(per_case, MIN_CASE_STEPS)
    if steps <= MAX_SWEEP_WORK_STEPS:
        return
    where = "[sweep] samples" if spec.random else f"[sweep.parameters.{next(iter(spec.grid))}] values"
    raise ScenarioError(f"{scenario.path or scenario.name}: {where}: {spec.cases} cases of at least "
                        f"{max(per_case, MIN_CASE_STEPS):.3g} integration steps each is {steps:.3g} steps, "
                        f"more than {MAX_SWEEP_WORK_STEPS:.0e} (days of computing); run fewer cases or split the "
                        "study")


def _case_check(scenario, spec):
    """The ``check`` of :func:`~orbatt.sweep.sampling.draw_samples` for a sweep of scenario
    paths: each case's scenario validated as a file (its messages kept by case)."""
    base = tomllib.loads(scenario.text)
    source = str(scenario.path) if scenario.path is not None else scenario.name
    dimless = scenario.spec.dimensionless
    binary = isinstance(scenario.spec, BinarySpec)

    def check(values, cases):
        bad = np.zeros(spec.cases, dtype=bool)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for k in cases:
                try:
                    case = parse(toml_text(case_data(base, spec, values, int(k), dimless)), source)
                    if binary:  # a binary's orbit (bound, no contact) is checked when it is built
                        Scenario(case, path=scenario.path)
                except ScenarioError as exc:
                    bad[k] = True
                    check.messages[int(k)] = str(exc).split(": ", 1)[-1]
        return bad

    check.messages = {}
    return check


def load_sweep(path, *, seed=None) -> Sweep:
    """Read a scenario file with a ``[sweep]`` table, validate it and draw the samples.

    Parameters
    ----------
    path : str or Path
        A TOML file, or the name of a shipped scenario.
    seed : int, optional
        Use this seed instead of the file's (or where the file has none).

    Returns
    -------
    Sweep

    Raises
    ------
    InputError
        A malformed file or ``[sweep]`` table, a missing ``[sweep]``, or (with
        ``on_invalid = "error"``) a sample outside the physical limits, named.
    """
    t0 = time.perf_counter()
    sc = load_scenario(path)
    sweep = Sweep(sc, seed=seed)
    sweep.setup_seconds = time.perf_counter() - t0  # what a fresh worker pays again (run_sweep's choice)
    return sweep

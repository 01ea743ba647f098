"""The :class:`Scenario` (a validated study, built and ready to run) and how to load one:
:func:`load_scenario` from a file or a shipped name, :func:`shipped_scenarios`."""
from __future__ import annotations

import contextlib
import copy
import threading
import warnings
from collections import OrderedDict
from pathlib import Path

import numpy as np
from astropy import units as u

from .. import units as U
from ..body import RigidBody
from ..control import reaction_wheel
from ..environment.frames import one_dates_warning
from ..errors import ScenarioError, not_a_file
from .build import (build_initial_state, build_kepler_orbit, build_output_times, build_potential,
                    build_rebound_orbit, build_tle_orbit, check_field_span, check_work, environment_margin,
                    estimate_steps, run_to_content, tle_period)
from .fields import FieldContext
from .schema import Spec, parse
from .binary_schema import BinarySpec
from ..dataset.build import dataset_content
from ..dataset.content import Content
from ..propagation import propagate
from ..shipped import shipped_file, shipped_folder

__all__ = ["Scenario", "load_scenario", "shipped_scenarios", "read_scenario_text"]


class Scenario:
    """A validated study: the body, potential, orbit, initial state and integration settings.

    Build one with :func:`load_scenario`. :meth:`run` returns the result Dataset; calling it
    again in the same process reuses everything built (the orbit, the compiled kernels).

    Attributes
    ----------
    name, description : str
    text : str
        The scenario file's TOML text (stored in the Dataset's ``scenario`` attribute).
    body : RigidBody
    potential : Potential
    orbit : OrbitProvider or None
    state0 : State
        Initial state in inertial components (converted from the orbital frame if the file
        says ``frame = "orbital"``).
    times : ndarray
        Output times (s, or dimensionless): exactly ``k * output_step``.
    method : str
    settings : dict
        ``rtol``, ``atol``, ``step`` as given (step in the time unit).
    """

    def __new__(cls, spec=None, path=None, yes=False):
        if isinstance(spec, BinarySpec):  # [orbit] provider = "coupled": scenario/binary_scenario.py
            from .binary_scenario import BinaryScenario  # (imported for binaries only)

            return BinaryScenario(spec, path=path)
        return super().__new__(cls)

    def __init__(self, spec: Spec, path=None, yes=False):
        self.spec = spec
        self.path = path
        self.name = spec.name
        self.description = spec.description
        self.text = spec.text
        ctx = FieldContext(str(path) if path else spec.name)
        wheels = [reaction_wheel(w) for w in spec.control["wheels"]] if spec.control is not None else ()
        # u.Quantity(x, unit): what x * unit makes, in half the time
        inertia = spec.inertia if spec.inertia_tensor is None else spec.inertia_tensor  # a tensor: the body frame's
        self.body = RigidBody(inertia if spec.dimensionless else u.Quantity(inertia, U.INERTIA), wheels=wheels)
        self.orbit = None
        kepler = period = None
        provider = spec.orbit["provider"] if spec.orbit is not None else None
        if provider == "tle":
            period = tle_period(spec.orbit)
        elif spec.orbit is not None:
            kepler = build_kepler_orbit(ctx, spec.orbit)
            period = kepler.period_value
        self.times, self.t_end = build_output_times(ctx, spec.integration, period)
        max_steps = spec.integration.get("max_steps")
        #: check_work's consent to a long run: ``yes`` (orbatt run --yes) or [integration] max_steps
        work = {"outputs": len(self.times), "consent": bool(yes) or max_steps is not None, "max_steps": max_steps}
        check_work(ctx, self.t_end, period, spec=spec, **work)  # the orbit and the torques, before anything is sampled
        check_field_span(ctx, spec, float(self.times[-1]))
        if provider == "tle":
            self.orbit = build_tle_orbit(ctx, spec.orbit, float(self.times[-1]), environment_margin(spec))
        elif spec.orbit is not None:
            self.orbit = (kepler if provider == "kepler"
                          else build_rebound_orbit(ctx, spec.orbit, kepler, float(self.times[-1])))
        self.potential = build_potential(spec, self.orbit, float(self.times[-1]))
        self.state0 = build_initial_state(ctx, spec, self.body, self.orbit)
        self.method = spec.integration["method"]
        self.settings = {k: spec.integration[k] for k in ("rtol", "atol", "independent_variable", "max_steps")
                         if k in spec.integration}
        if "step" in spec.integration:
            kind, value = spec.integration["step"]
            self.settings["step"] = value * period if kind == "orbits" else value
        check_work(ctx, self.t_end, period, self.state0, spec, self.settings.get("step"), **work)
        #: check_work's lower estimate of the work in integration steps (a sweep multiplies it by its cases)
        self.work_steps = estimate_steps(self.t_end, period, self.state0, spec, self.settings.get("step"),
                                         work["outputs"])

    def run(self, method=None, progress=False, **overrides):
        """Propagate and return the result :class:`xarray.Dataset` (see :mod:`orbatt.dataset`).

        Parameters
        ----------
        method : str, optional
            Override the file's ``[integration] method`` (its rtol/atol/step still apply
            where the method takes them).
        progress : bool or callable
            Progress bar (True) or callback; off by default.
        **overrides
            Further keyword arguments for :func:`orbatt.propagate` (e.g. ``rtol``).

        Raises
        ------
        IntegrationError
            The integration could not continue (non-finite state, ``max_steps``, ...). Its
            ``dataset`` attribute holds what was computed until then, as a Dataset marked
            incomplete (``integration_complete = 0``; None if nothing was), its
            ``trajectory`` the same as a :class:`~orbatt.trajectory.Trajectory`.
        """
        return self.run_content(method, progress, **overrides).to_dataset()

    def run_content(self, method=None, progress=False, **overrides) -> Content:
        """:meth:`run`'s result as plain arrays: the :class:`~orbatt.dataset.content.Content`
        whose :meth:`~orbatt.dataset.content.Content.to_dataset` is :meth:`run`'s Dataset
        (what ``orbatt run`` writes, without importing xarray). Parameters and errors as
        :meth:`run`."""
        kw = dict(self.settings)
        kw.update(overrides)
        m = method or self.method
        epoch = None if self.orbit is None else self.orbit.epoch
        if epoch is not None:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                epoch = f"the run from {epoch.utc.isot} (+ {self.t_end:g} s)"
        # ERFA's and astropy's warnings for dates beyond their tables (tens of lines from the
        # environment's tables and the outputs) come out as one
        with one_dates_warning(epoch) if epoch is not None else contextlib.nullcontext():
            return run_to_content(self.path or self.name, m, lambda: propagate(
                self.body, self.state0, self.potential, self.times, method=m, progress=progress, **kw), self._content)

    def _content(self, traj):
        epoch = self.orbit.epoch if self.orbit is not None else None
        return dataset_content(traj, scenario_text=self.text, epoch=epoch, title=f"orbatt: {self.name}")

    def __repr__(self):
        return f"Scenario({self.name!r}, method={self.method!r}, outputs={self.times.size})"


def shipped_scenarios():
    """``[(name, description, path)]`` of the scenarios shipped with orbatt."""
    out = []
    for f in sorted(shipped_folder().iterdir(), key=lambda p: p.name):
        if f.name.endswith(".toml"):
            spec = parse(read_scenario_text(f), f.name)
            out.append((spec.name, spec.description, f))
    return out


#: the concrete Path class of this system (PosixPath or WindowsPath)
_PATH = type(Path())


def load_scenario(path, yes=False) -> Scenario:
    """Read and validate a scenario file; return a :class:`Scenario`.

    Parameters
    ----------
    path : str or Path
        A TOML file, or the name of a shipped scenario (``orbatt scenarios`` lists them).
    yes : bool
        Agree to a long run (the work estimate above
        :data:`~orbatt.scenario.build.LONG_WORK_STEPS`; ``orbatt run --yes``), as
        ``[integration] max_steps`` in the file does.

    Raises
    ------
    ScenarioError
        (an :class:`~orbatt.errors.InputError`) naming the file, the field, the value and
        the fix.
    """
    p = path if type(path) is _PATH else Path(path)  # (a Path is immutable: kept)
    if not p.is_file():
        f = shipped_file(str(p))
        if f is not None:
            key = f.name[:-5]
            return Scenario(parse_scenario_text(read_scenario_text(f), key), path=key, yes=yes)
        why = not_a_file(p)
        if why != "does not exist":  # a folder, a FIFO ...: say what it is
            raise ScenarioError(f"{path}: {why}; give a path to a TOML scenario file")
        raise ScenarioError(f"{path}: no such scenario file; give a path to a TOML file or one of: "
                            f"{', '.join(sorted(name for name, _, _ in shipped_scenarios()))}")
    return Scenario(parse_scenario_text(read_scenario_text(p), str(p)), path=p, yes=yes)


#: validated specs by ``(text, source)``, most recently used last (:func:`parse_scenario_text`)
_SPECS: OrderedDict = OrderedDict()
_SPECS_LOCK = threading.Lock()
#: most specs kept
SPEC_CACHE_SIZE = 32


def parse_scenario_text(text: str, source: str) -> Spec:
    """:func:`~orbatt.scenario.schema.parse` of ``text``, remembered by its content.

    Validating a scenario (TOML parsing, unit strings) costs ~0.25 ms, as much as a short
    run; loading the same file again (a study calling ``load_scenario(path).run()`` in a loop)
    reuses the validated :class:`Spec` of the same ``text`` and ``source`` (the file's name,
    which the error messages and the default ``name`` use). Every call returns its own deep
    copy, so a caller changing its spec changes no other. Not remembered: a spec whose
    validation warned (the warning is given again on every load) and a TLE orbit (its
    ``tle_file`` is read from disk, which may change without the scenario changing).
    """
    key = (text, source)
    with _SPECS_LOCK:
        spec = _SPECS.get(key)
        if spec is not None:
            _SPECS.move_to_end(key)
    if spec is None:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            spec = parse(text, source)
        for w in caught:  # given again outside, under the caller's filters
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
        if caught or (spec.orbit is not None and spec.orbit.get("provider") == "tle"):
            return spec
        with _SPECS_LOCK:
            _SPECS[key] = spec
            while len(_SPECS) > SPEC_CACHE_SIZE:
                _SPECS.popitem(last=False)
    return _copy_spec(spec)


_IMMUTABLE = (str, int, float, bool, type(None))
#: the exact types of :data:`_IMMUTABLE` (a set lookup instead of a call of :func:`_fresh`)
_ATOMS = frozenset(_IMMUTABLE)


def _fresh(x):
    """A deep copy of ``x``: plain containers and arrays copied directly (a generic
    ``copy.deepcopy`` of a spec costs ~4x more), anything else by ``copy.deepcopy``."""
    if isinstance(x, _IMMUTABLE):
        return x
    t = type(x)
    if t is dict:  # plain values kept without a call each
        return {k: v if v.__class__ in _ATOMS else _fresh(v) for k, v in x.items()}
    if t is list:
        return [_fresh(v) for v in x]
    if t is tuple:  # a tuple of plain values is immutable: kept
        return x if all(v.__class__ in _ATOMS for v in x) else tuple(_fresh(v) for v in x)
    if t is np.ndarray and x.dtype.kind in "fiub":
        return x.copy()
    return copy.deepcopy(x)


def _copy_spec(spec: Spec) -> Spec:
    """A deep copy of ``spec`` (every field)."""
    # a plain dataclass: its fields copied into a new instance directly (dataclasses.replace
    # runs __init__ and its checks again)
    out = object.__new__(type(spec))
    out.__dict__.update({k: v if v.__class__ in _ATOMS else _fresh(v) for k, v in vars(spec).items()})
    return out


#: leading bytes of binary formats a user may pass for a scenario by mistake
_MAGIC = {b"\x89HDF\r\n\x1a\n": "an HDF5/netCDF-4 file (an orbatt result?)", b"CDF\x01": "a netCDF-3 file",
          b"CDF\x02": "a netCDF-3 file", b"\x89PNG": "a PNG image", b"\x1f\x8b": "a gzip file",
          b"PK\x03\x04": "a zip file", b"\xff\xfe": "a UTF-16 text file", b"\xfe\xff": "a UTF-16 text file"}


def read_scenario_text(path) -> str:
    """The text of a scenario file: UTF-8 (TOML's encoding), or a :class:`ScenarioError`
    naming the file (a binary or NetCDF file, another encoding, an unreadable file)."""
    try:
        with open(path, "rb", buffering=0) as f:  # what Path.read_bytes reads, unbuffered (half its ~8 us)
            data = f.readall()
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read it ({exc.strerror or exc}); give a readable TOML file") from None
    for magic, what in _MAGIC.items():
        if data.startswith(magic):
            raise ScenarioError(f"{path}: is not a TOML scenario (it is {what}); give a scenario file "
                                "(orbatt info/plot read results)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: is not a TOML scenario: byte {data[exc.start]:#04x} at offset {exc.start} is "
                            "not UTF-8 (TOML files are UTF-8 text); save it as UTF-8") from None

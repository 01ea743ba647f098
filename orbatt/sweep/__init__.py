"""Parameter sweeps (dispersions, Monte Carlo, grids) run on Dask.

A scenario file with a ``[sweep]`` table describes many cases of one study; :func:`load_sweep`
validates it and draws every sample, :func:`run_sweep` runs the cases in chunks (each chunk
one ensemble call of :func:`orbatt.propagate` inside a Dask task), writes every chunk as it
finishes and merges them into one Dataset with a ``case`` dimension. ``orbatt sweep
SCENARIO.toml -o OUT.nc`` is the command-line form.

The manual (the ``[sweep]`` schema, cases, outputs, physical limits, reproducibility,
storage and resumption, execution): ``docs/sweeps.md``. Modules:

* :mod:`~orbatt.scenario.sweep_schema` - the ``[sweep]`` table (it is part of the scenario);
* :mod:`~orbatt.sweep.sampling` - nominal values, draws, resampling;
* :mod:`~orbatt.sweep.cases` - :class:`Sweep` (the cases of a study), :func:`load_sweep`;
* :mod:`~orbatt.sweep.chunk` - the physics and Dataset of one chunk (what a task runs);
* :mod:`~orbatt.sweep.parts` - part files: names, scan and repair on resume, reading back;
* :mod:`~orbatt.sweep.run` - the Dask client, :func:`run_sweep`, the global attributes.
"""
from ..errors import SweepError
from ..scenario.sweep_schema import (DEFAULT_OUTPUTS, DISTRIBUTIONS, MAX_CASES, OUTPUTS, PARAMETERS, SWEEP_KEYS, Distribution,
                                     Parameter, SweepSpec, parse_sweep_table)
from .cases import FORMAT, Sweep, load_sweep
from .run import MAX_AUTO_CHUNK, ChunkInfo, run_sweep
from .sampling import MAX_RESAMPLE_ROUNDS

__all__ = ["SweepSpec", "Distribution", "Sweep", "SweepError", "ChunkInfo", "load_sweep", "run_sweep",
           "PARAMETERS", "OUTPUTS", "DISTRIBUTIONS", "DEFAULT_OUTPUTS", "SWEEP_KEYS", "Parameter", "parse_sweep_table",
           "MAX_CASES", "MAX_RESAMPLE_ROUNDS", "MAX_AUTO_CHUNK", "FORMAT"]

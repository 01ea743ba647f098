"""Scenario files (TOML): schema, validation, and the objects they build.

A scenario describes one study; :func:`load_scenario` validates it completely (unknown keys
and tables are refused, every quantity is checked for its dimension) and returns a
:class:`Scenario` whose :meth:`Scenario.run` returns the result Dataset.

* :mod:`~orbatt.scenario.schema` - the schema (written out in its docstring) and
  :func:`parse`; :mod:`~orbatt.scenario.sweep_schema` - the ``[sweep]`` table;
* :mod:`~orbatt.scenario.fields` - the field parsers (quantities, vectors, durations);
* :mod:`~orbatt.scenario.build` - orbit, potential, initial state and output times;
* :mod:`~orbatt.scenario.load` - :class:`Scenario`, :func:`load_scenario`.

Data flows one way: ``scenario`` -> :mod:`orbatt.sweep` (which imports from here, never the
reverse).
"""
from ..errors import ScenarioError
from .build import build_initial_state, build_kepler_orbit, build_output_times, build_potential, build_rebound_orbit
from .fields import (FieldContext, parse_choice, parse_int, parse_plain_vector, parse_quantity, parse_time,
                     parse_vector)
from .load import Scenario, load_scenario, shipped_scenarios
from .schema import FRAMES, POTENTIAL_KINDS, PROVIDERS, REQUIRED_TABLES, TABLES, TOP_KEYS, Spec, parse

__all__ = ["Scenario", "load_scenario", "parse", "shipped_scenarios", "ScenarioError", "Spec", "FieldContext",
           "parse_quantity", "parse_vector", "parse_plain_vector", "parse_choice", "parse_int", "parse_time",
           "build_kepler_orbit", "build_rebound_orbit", "build_potential", "build_initial_state",
           "build_output_times", "TOP_KEYS", "TABLES", "REQUIRED_TABLES", "POTENTIAL_KINDS", "FRAMES", "PROVIDERS"]

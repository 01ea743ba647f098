"""The scenario files shipped with orbatt: where they are and which file a name means.

Standard library only: ``orbatt run`` looks its scenario up here before numba is imported
(:mod:`orbatt.coldstart` decides from the file whether the kernels of a first run run
interpreted), and :func:`orbatt.scenario.load_scenario` resolves a name here, so both read the
same file for the same argument.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ["shipped_folder", "shipped_file", "scenario_file"]

_PACKAGE = Path(__file__).resolve().parent


def shipped_folder() -> Path:
    """The folder of the shipped scenario files (``orbatt/scenarios`` of an installed orbatt,
    or ``scenarios/`` beside the package in a source checkout used without installing)."""
    try:
        from importlib.resources import files

        return Path(str(files("orbatt.scenarios")))
    except (ModuleNotFoundError, TypeError):  # a source checkout used without installing
        return _PACKAGE.parent / "scenarios"


def shipped_file(name) -> Path | None:
    """The shipped file of the scenario ``name`` (``"paper-keplerian"``, with or without
    ``.toml``, in any letter case), or None: the shipped files are named for their scenario
    (each file's ``name`` is its stem: ``tests/scenario/test_scenario_schema.py``)."""
    stem = str(name)
    if stem.endswith(".toml"):
        stem = stem[:-5]
    if not stem or "/" in stem or "\\" in stem:
        return None
    folder = shipped_folder()
    for candidate in (stem, stem.lower()):
        f = folder / f"{candidate}.toml"
        if f.is_file():
            return f
    return None


def scenario_file(scenario) -> Path | None:
    """The TOML file ``orbatt run SCENARIO`` reads: ``scenario`` itself when it is a file, else
    the shipped file of that name (:func:`shipped_file`), else None."""
    p = Path(scenario)
    if p.is_file():
        return p
    return shipped_file(str(p))  # (a name with a folder is no shipped name)

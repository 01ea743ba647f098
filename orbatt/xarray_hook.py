"""The ``ds.orbatt`` accessor (:mod:`orbatt.dataset.accessor`) on every :class:`xarray.Dataset`,
without importing xarray: importing orbatt does not import xarray and pandas (~0.3 s; a run
written by ``orbatt run`` needs neither), and the accessor is there all the same, whoever
imports xarray and when. :func:`install_accessor_hook` is called by ``import orbatt``.
"""
from __future__ import annotations

import sys

__all__ = ["install_accessor_hook"]


class _AccessorWithXarray:
    """Registers the ``ds.orbatt`` accessor (:mod:`orbatt.dataset.accessor`) right after xarray
    is imported, so that importing orbatt does not import xarray and pandas (~0.3 s; a run
    written by ``orbatt run`` needs neither) and ``ds.orbatt`` is there on every Dataset all
    the same, whoever imports xarray and when. A finder placed first in ``sys.meta_path``
    until xarray's import: it lets the usual finders find xarray and runs the accessor's
    module after xarray's own."""

    def find_spec(self, name, path=None, target=None):
        if name != "xarray":
            return None
        _remove_finder()
        import importlib.util

        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            _register_accessor()

        spec.loader.exec_module = exec_module
        return spec


def _register_accessor():
    import importlib

    importlib.import_module(".dataset.accessor", __package__)  # registers ds.orbatt


def _remove_finder():
    sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, _AccessorWithXarray)]


def install_accessor_hook():
    """Register the accessor now if xarray is imported (or the fast paths are off,
    ``ORBATT_FAST_PATHS=0``: then xarray is imported now), else right after its import."""
    from .fast_paths import ENABLED

    if "xarray" in sys.modules or not ENABLED:
        _register_accessor()
    elif not any(isinstance(f, _AccessorWithXarray) for f in sys.meta_path):
        sys.meta_path.insert(0, _AccessorWithXarray())

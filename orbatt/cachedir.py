"""Where orbatt keeps what it computes once per installation: numba's compiled kernels live
beside the sources (numba's own choice), and orbatt's own caches (the warm stamps of
:mod:`orbatt.coldstart`, the parsed Earth orientation table of
:mod:`orbatt.environment.frames`) in :func:`cache_folder`."""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cache_folder"]

_PACKAGE = Path(__file__).resolve().parent


def cache_folder() -> Path:
    """orbatt's cache folder, beside numba's cache of the kernels: ``$NUMBA_CACHE_DIR/orbatt``,
    else ``orbatt/core/__pycache__`` when it is writable, else ``$XDG_CACHE_HOME/orbatt`` or
    ``~/.cache/orbatt`` (numba's user-wide fallback). It may not exist yet."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]) / "orbatt"
    in_tree = _PACKAGE / "core" / "__pycache__"
    if os.access(in_tree if in_tree.is_dir() else in_tree.parent, os.W_OK):
        return in_tree
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "orbatt"

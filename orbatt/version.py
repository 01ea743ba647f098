"""orbatt's version string, from the installed package metadata."""
from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("orbatt")
except PackageNotFoundError:  # pragma: no cover - source tree without install
    __version__ = "0+unknown"

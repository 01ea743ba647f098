"""One variable of a result before xarray: :class:`Var` (dimension names, values, attributes).

Its own module so that what builds variables (:mod:`orbatt.dataset.eclipses`, ...) and
:class:`orbatt.dataset.content.Content`, which decodes them, import it without importing
each other (``orbatt.dataset.content`` re-exports it).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Var"]


class Var(NamedTuple):
    """One variable: dimension names, values (a numpy array of that many dimensions) and
    attributes (CF ``units``, ``long_name`` ...)."""

    dims: tuple
    values: np.ndarray
    attrs: dict

    @property
    def dtype(self):
        return self.values.dtype

    @property
    def shape(self):
        return self.values.shape

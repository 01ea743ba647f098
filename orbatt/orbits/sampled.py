"""Orbits known by samples (``docs/design.md`` §5, §11): the evaluation shared by the providers
that sample an orbit once and interpolate it (:class:`~orbatt.orbits.ReboundOrbit`,
:class:`~orbatt.orbits.TleOrbit`) with the compiled quintic Hermite polynomial of
:mod:`orbatt.core.sampled`."""
from __future__ import annotations

import numpy as np

from ..core import potentials as kp
from ..core import sampled as ks
from ..errors import InputError
from .base import OrbitProvider, as_times

__all__ = ["SampledOrbit"]


class SampledOrbit(OrbitProvider):
    """An orbit given by a sample table (read-only ``(N, 10)`` float64: ``t`` in s since the
    epoch, position km, velocity km/s, acceleration km/s^2, relative to the central body in
    ``S``; the format of :mod:`orbatt.core.sampled`).

    Subclass contract: set ``self._table`` (and ``gm``, ``period``, ``epoch``,
    ``central_body``) in ``__init__`` and implement ``describe()``. The provider answers for
    ``t_first <= t <= t_last`` and raises :class:`~orbatt.errors.InputError` outside.
    """

    #: what to build longer when a time is outside the span (error messages)
    span_hint = "build the orbit over a longer span (t_end)"

    @property
    def samples(self):
        """The sample table ``(N, 10)``: ``t`` (s), position (km), velocity (km/s) and
        acceleration (km/s^2) relative to the central body in ``S`` (read-only)."""
        return self._table

    @property
    def t_last(self):
        """Last sampled time (s): the provider answers for ``t_first <= t <= t_last``."""
        return float(self._table[-1, 0])

    @property
    def time_span(self):
        """``(t_first, t_last)`` (s): the sampled span, where the provider answers."""
        return float(self._table[0, 0]), float(self._table[-1, 0])

    def _interp(self, t):
        t = as_times(t)
        flat = np.ascontiguousarray(t.reshape(-1))
        lo, hi = self._table[0, 0], self._table[-1, 0]
        if flat.size and (flat.min() < lo or flat.max() > hi):
            bad = flat[(flat < lo) | (flat > hi)][0]
            raise InputError(f"t: {bad!r} s is outside the sampled span [{lo}, {hi}] s of this "
                             f"{type(self).__name__}; {self.span_hint}")
        pos, vel, acc = ks.sampled_many(flat, self._table)
        shape = t.shape + (3,)
        return pos.reshape(shape), vel.reshape(shape), acc.reshape(shape)

    def state(self, t):
        """``(position km, velocity km/s)`` relative to the central body in ``S``,
        interpolated; each ``t.shape + (3,)``."""
        pos, vel, _ = self._interp(t)
        return pos, vel

    def acceleration(self, t):
        """Acceleration relative to the central body in ``S`` (km/s^2), interpolated."""
        return self._interp(t)[2]

    def kernel(self):
        """``(GRAVITY_GRADIENT_SAMPLED, [GM, t_first, t_last], samples)``."""
        params = np.array([self.gm, self._table[0, 0], self._table[-1, 0]])
        return kp.GRAVITY_GRADIENT_SAMPLED, params, self._table

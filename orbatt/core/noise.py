"""Reproducible sensor noise: a counter-based generator (``docs/design.md`` §14, issue 33).

Every random number of a run is a pure function of its key ``(seed, case, sensor, tick,
channel)``: a standard normal deviate is made by Box-Muller from two uniforms, each the
SplitMix64 finalizer (Steele, Lea & Flood 2014; the mixing function of Java's
``SplittableRandom``) chained over the key's five integers. No generator state depends on the
order in which ticks, cases or chunks run: a case is bitwise the same alone, in any chunk,
after a resume, in any process.

All arithmetic is on unsigned 64-bit integers (wrapping), then one ``log``, one ``sqrt`` and one
``cos`` in float64 (libm through numba: the same results on any x86-64 CPU for a given libm;
numpy's SIMD paths are not used). :func:`normal_reference` is the same generator in plain
Python integers, for the tests.

Sensors (the ``sensor`` word of the key): :data:`GYRO_RATE`, :data:`GYRO_BIAS`,
:data:`STAR_TRACKER`, :data:`INITIAL_ESTIMATE`, :data:`MAGNETOMETER`, :data:`SUN_SENSOR`; ``channel``
is the axis (0..2).
"""
from __future__ import annotations

import math

import numpy as np

from ._jit import jit_inline

__all__ = ["normal", "normal_reference", "GYRO_RATE", "GYRO_BIAS", "STAR_TRACKER", "INITIAL_ESTIMATE", "MAGNETOMETER",
           "SUN_SENSOR"]

#: the sensor words of the key
GYRO_RATE, GYRO_BIAS, STAR_TRACKER, INITIAL_ESTIMATE, MAGNETOMETER, SUN_SENSOR = 1, 2, 3, 4, 5, 6

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO_53 = 1.0 / 9007199254740992.0


@jit_inline
def _mix(x):
    """The SplitMix64 finalizer of ``x + golden`` (uint64, wrapping)."""
    z = x + _GOLDEN
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@jit_inline
def _word(x):
    """A key word (a float holding an integer ``>= -1``, as the kernels' parameters hold it) as uint64."""
    return np.uint64(np.int64(x) + np.int64(1))


@jit_inline
def _uniform(seed, case, sensor, tick, channel):
    """A uniform deviate in ``(0, 1]`` of the key (53 bits)."""
    h = _mix(_word(seed))
    h = _mix(h ^ _word(case))
    h = _mix(h ^ _word(sensor))
    h = _mix(h ^ _word(tick))
    h = _mix(h ^ _word(channel))
    return (float(h >> _S11) + 1.0) * _TWO_53


@jit_inline
def normal(seed, case, sensor, tick, channel):
    """A standard normal deviate of the key ``(seed, case, sensor, tick, channel)`` (each an
    integer-valued float ``>= -1``): Box-Muller ``sqrt(-2 ln u1) cos(2 pi u2)`` with ``u1, u2``
    the uniforms of the channels ``2 channel`` and ``2 channel + 1``."""
    u1 = _uniform(seed, case, sensor, tick, 2.0 * channel)
    u2 = _uniform(seed, case, sensor, tick, 2.0 * channel + 1.0)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def normal_reference(seed, case, sensor, tick, channel):
    """:func:`normal` in plain Python integers and :mod:`math` (the tests' independent copy)."""
    mask = (1 << 64) - 1

    def mix(x):
        z = (x + 0x9E3779B97F4A7C15) & mask
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & mask
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & mask
        return z ^ (z >> 31)

    def uniform(ch):
        h = mix(int(seed) + 1)
        for w in (case, sensor, tick, ch):
            h = mix(h ^ (int(w) + 1))
        return ((h >> 11) + 1.0) * _TWO_53

    u1, u2 = uniform(2 * channel), uniform(2 * channel + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)

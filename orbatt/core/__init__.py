"""Unitless compiled kernels (numba). Nothing here imports from outside ``orbatt.core``.

Unit system of the kernels: whatever consistent system the caller strips to. The API layer
uses kilograms, kilometres and seconds (inertia in kg km^2, GM in km^3 s^-2, momenta in
kg km^2 s^-1), or plain numbers for dimensionless scenarios.

Modules: :mod:`._jit` (numba presets, intrinsics, status codes, flag names),
:mod:`.qalg` (scalar quaternion algebra), :mod:`.kepler` and :mod:`.sampled` (orbits),
:mod:`.potentials` (conservative terms), :mod:`.torques` (flat plates, dipole, the torque ->
generalized force map), :mod:`.environment` (densities, shadow, piece tables),
:mod:`.control` and :mod:`.gyrostat` (control laws, reaction wheels), :mod:`.model` (the term
list and the one dispatch on kinds), :mod:`.hamiltonian` (eq. 7), :mod:`.dop853` (+
:mod:`.rk_loop`, the one adaptive step loop, :mod:`.step_control`, its building blocks,
:mod:`.dop853_coefficients`, :mod:`.verner98_coefficients`, :mod:`.butcher`) and
:mod:`.splitting` (step loops), :mod:`.free_body` and
:mod:`.carlson` (the exact torque-free body); :mod:`.mutual` and :mod:`.mutual_splitting` (a
binary asteroid: the orbit and both attitudes together, ``docs/design.md`` §12).

The equations as orbatt implements them (signs, frames, the paper's errata, the units inside
the kernels) and the architecture are written up in ``docs/design.md`` §1, §2, §3, §3a, §4, §5,
§10 (conventions and units, canonical variables, potentials, the paper's errata, integrators,
orbits, torques and the environment) and §8 (the layout).

The paper's equations (Arribas, Elipe & Palacios 2006) and where they are computed:

========  ==================================================  ==========================================
equation  what                                                function
========  ==================================================  ==========================================
(5)       ``Q = 2 q g``, ``g = 1/2 Im(q~ Q)``                  :func:`orbatt.canonical.momentum_from_body_momentum`,
                                                              :func:`orbatt.canonical.body_momentum`;
                                                              compiled: :func:`.hamiltonian.kinetic_rates`
(6)       kinetic energy ``T = 1/8 (I^-1 (x) q~Q).(q~Q)``      :func:`.hamiltonian.kinetic`,
                                                              :func:`orbatt.canonical.kinetic_energy`
(7)       Hamilton's equations in ``(q, Q)``                  :func:`.hamiltonian.eq7`, :func:`.hamiltonian.rhs`,
                                                              :func:`.hamiltonian.rhs_lanes`; numpy form as
                                                              printed: :func:`orbatt.canonical.hamilton_rhs`
(10)      ``H`` in Euler angles and momenta                   :func:`orbatt.euler.hamiltonian`
(12)      Euler 3-1-3 angles -> ``q``                         :func:`orbatt.quaternion.from_euler313`
(13)      ``q`` -> Euler 3-1-3 angles                         :func:`orbatt.quaternion.to_euler313`
(14)      Euler angles and momenta -> ``(q, Q)``              :func:`orbatt.euler.to_canonical`
(15)      ``(q, Q)`` -> Euler angles and momenta              :func:`orbatt.euler.from_canonical`
(18)      heavy top potential                                 :func:`.potentials.heavy_top`
(20)      gravity gradient (MacCullagh) potential             :func:`.potentials.gravity_gradient`
§12       mutual potential to second order, its gradient,     :func:`.mutual.potential_gradient`,
          torques; the coupled equations; the splitting       :func:`.mutual.rhs_coupled`, :mod:`.mutual_splitting`
========  ==================================================  ==========================================
"""
from __future__ import annotations

import numpy as np

from ._jit import INTERPRETED, fast_paths_in_use

__all__ = ["INTERPRETED", "fast_paths_in_use", "kernel_floats"]


def kernel_floats(a):
    """``a`` as a C-contiguous, writeable float64 array, copied only where it is not one.

    Every array a compiled kernel takes from Python goes in this one form: a read-only array
    (a body's frozen inertia, a broadcast view, xarray's values) or a strided one is another
    numba type, for which the kernel compiles again (the evaluation kernels took 2-3
    specializations each, 10-45 s apiece, on a cold cache)."""
    a = np.asarray(a, dtype=np.float64)
    if a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=np.float64, order="C")

"""Unitless compiled kernels (numba). Nothing here imports from outside ``orbatt.core``.

Unit system of the kernels: whatever consistent system the caller strips to. The API layer
uses kilograms, kilometres and seconds (inertia in kg km^2, GM in km^3 s^-2, momenta in
kg km^2 s^-1), or plain numbers for dimensionless scenarios.
"""

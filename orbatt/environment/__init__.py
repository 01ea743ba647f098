"""The environment along a prescribed orbit (``DESIGN.md`` §10): frames, atmosphere,
geomagnetic field, Sun and shadow, and the sampled tables the compiled kernel interpolates.

Units at the boundary: astropy ``Time`` instants and GCRS positions in km in; plain float
arrays out in the units each docstring states (density kg/m^3, field T, positions km).
The compiled counterparts live in :mod:`orbatt.core.environment`.
"""

"""The environment along a prescribed orbit (``docs/design.md`` §10): frames, atmosphere,
geomagnetic field, Sun and shadow, and the sampled tables the compiled kernel interpolates.

Units at the boundary: astropy ``Time`` instants and GCRS positions in km in; plain float
arrays out in the units each docstring states (density kg/m^3, field T, positions km).
The compiled counterparts live in :mod:`orbatt.core.environment`.

Modules: :mod:`.frames` (GCRS <-> ITRS, geodetic), :mod:`.atmosphere`, :mod:`.magnetic`,
:mod:`.sun`, :mod:`.tables`.
"""
from .atmosphere import VALLADO_TABLE, NRLMSIS, ExponentialAtmosphere, PiecewiseExponentialAtmosphere
from .frames import EARTH_ROTATION_RATE, R_EARTH_WGS84, geodetic, gcrs_to_itrs, itrs_to_gcrs
from .magnetic import DipoleField, IGRFField
from .sun import AU, R_SUN, SRP_FLUX, SPEED_OF_LIGHT, shadow, sun_position
from .tables import (DENSITY_PIECES, LAYERED_DENSITY_PIECES, MAGNETIC_FIELD_PIECES, SUN_PIECES, TABLE_MARGIN,
                     OrbitSamples, Pieces, piece_table, piece_times, sample_along_orbit, sample_pieces, tabulate)

__all__ = ["ExponentialAtmosphere", "PiecewiseExponentialAtmosphere", "NRLMSIS", "VALLADO_TABLE",
           "DipoleField", "IGRFField", "sun_position", "shadow", "SRP_FLUX", "AU", "R_SUN", "SPEED_OF_LIGHT",
           "gcrs_to_itrs", "itrs_to_gcrs", "geodetic", "EARTH_ROTATION_RATE", "R_EARTH_WGS84",
           "OrbitSamples", "Pieces", "sample_along_orbit", "sample_pieces", "piece_times", "piece_table",
           "tabulate", "MAGNETIC_FIELD_PIECES", "SUN_PIECES", "DENSITY_PIECES", "LAYERED_DENSITY_PIECES",
           "TABLE_MARGIN"]

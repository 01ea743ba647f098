"""The study outputs of a sweep (issue 23): their computation now lives with their
descriptors in :mod:`orbatt.sweep_outputs` (issue 32 item 1); the names are kept here."""
from __future__ import annotations

from ..crossings import crossing_time, refine_crossing, study_series
from ..sweep_outputs import OUTPUTS, SATURATION_MARGIN, study_outputs, target_pointing_error, window_start

__all__ = ["STUDY_OUTPUTS", "crossing_time", "refine_crossing", "window_start", "study_series",
           "target_pointing_error", "study_outputs", "SATURATION_MARGIN"]

#: the study outputs of a sweep (those computed per case) and the variables each one adds
STUDY_OUTPUTS = {o.key: o.names for o in OUTPUTS.values() if o.compute is not None}

"""Progress reports of :func:`orbatt.propagate`: what a progress callback receives
(:class:`ProgressInfo`) and the text progress bar of ``progress=True``."""
from __future__ import annotations

import sys
from typing import NamedTuple

from .errors import InputError

__all__ = ["ProgressInfo", "progress_printer", "progress_callback"]


class ProgressInfo(NamedTuple):
    """What a progress callback receives after each compiled call (times in the body's
    time unit)."""

    fraction: float      #: of the time span done (slowest member, for ensembles)
    t: float             #: time reached (slowest member)
    t_end: float
    steps: int           #: steps so far (all members)
    wall_time_s: float   #: since the start of the integration


def progress_printer(stream=None):
    """A progress callback that draws a one-line bar on ``stream`` (default stderr), at most
    every 0.2 s, and nothing for runs shorter than a second."""
    stream = stream or sys.stderr
    state = {"last": 0.0, "shown": False}

    def report(info: ProgressInfo):
        now = info.wall_time_s
        if not state["shown"] and now < 1.0:
            return  # runs shorter than a second show no bar
        if now - state["last"] < 0.2 and info.fraction < 1.0:
            return
        state["last"] = now
        state["shown"] = True
        width = 30
        fill = int(round(width * info.fraction))
        stream.write(f"\rorbatt: [{'#' * fill}{'.' * (width - fill)}] {100 * info.fraction:5.1f}%  "
                     f"t = {info.t:.6g}/{info.t_end:.6g}  {info.steps} steps  {info.wall_time_s:.1f} s")
        if info.fraction >= 1.0:
            stream.write("\n")
        stream.flush()

    return report


def progress_callback(progress):
    """The callback for ``progress=`` of :func:`orbatt.propagate`: None (off; also for
    False), :func:`progress_printer` for True, or the callable itself."""
    if progress is True:
        return progress_printer()
    if progress is None or progress is False:
        return None
    if not callable(progress):
        raise InputError(f"progress: expected None, True or a callable, got {type(progress).__name__}")
    return progress

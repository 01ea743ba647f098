"""Summing the integration statistics of a sweep's runs (:func:`add_stats`): the chunks'
and, in a binary sweep, each case's."""
from __future__ import annotations

import json

__all__ = ["add_stats"]


def add_stats(total, stats, skip=()):
    """Add the numbers of the integration statistics ``stats`` (a dict, or its JSON text)
    into ``total`` (a dict, changed in place, and returned); non-numbers and the keys in
    ``skip`` are left out. The one place where a sweep sums statistics."""
    if stats is None or isinstance(stats, str):
        try:
            stats = json.loads(stats)
        except (TypeError, ValueError):
            return total
    for k, v in stats.items():
        if isinstance(v, (int, float)) and not isinstance(v, bool) and k not in skip:
            total[k] = total.get(k, 0) + v
    return total

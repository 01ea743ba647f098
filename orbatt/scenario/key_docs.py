"""The key tables of the scenario schema written as text: a table of what each key is
(``dimension``, ``default``, ``meaning``), parsed into the dicts
:data:`orbatt.scenario.schema.KEY_DOCS` and :data:`orbatt.scenario.sweep_schema.SWEEP_KEY_DOCS`
that validation messages and ``docs/scenarios.md`` (:mod:`orbatt.scenario.reference`) read.

The text: ``[table]`` starts a table (``[]``: the top-level keys); a line ``key  dimension
default  meaning`` (columns separated by two or more spaces, cells without double spaces)
describes one key; an indented line continues the meaning of the key above; blank lines and
lines starting with ``#`` are skipped.
"""
from __future__ import annotations

import re

__all__ = ["parse_key_docs"]


def parse_key_docs(text):
    """``{table: {key: (dimension, default, meaning)}}`` of a key table (module docstring),
    tables and keys in the order written."""
    docs = {}
    table = key = None
    for line in text.splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if line.startswith("["):
            table = line.strip()[1:-1]
            docs[table] = {}
        elif line[0].isspace():
            dimension, default, meaning = docs[table][key]
            docs[table][key] = (dimension, default, meaning + " " + line.strip())
        else:
            key, dimension, default, meaning = re.split(r" {2,}", line.strip(), maxsplit=3)
            docs[table][key] = (dimension, default, meaning)
    return docs

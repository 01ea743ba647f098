"""Scenario keys addressed by their path as written in TOML (issue 23; ``docs/design.md`` §13):
``"table.key"``, ``"table.key[i]"``, ``"table.array[i].key"`` (``"control.gain"``,
``"initial.omega[0]"``, ``"body.facets[0].drag_coefficient"``, ``"body.wheels[2].speed"``).

A sweep varies such a numeric leaf from case to case; a case's scenario is the file with the
leaves replaced (:func:`substitute`), written back as TOML (:func:`toml_text`), and that
scenario's single run defines the case. Nothing here validates a scenario: the schema does,
on the case's text.
"""
from __future__ import annotations

import copy
import math
import re

__all__ = ["ALIAS_PATHS", "PATH_PATTERN", "split_path", "resolve", "substitute", "toml_text", "coordinate_name",
           "leaf_quantity"]

#: the named parameters as scenario paths (their values are in internal units)
ALIAS_PATHS = {"inertia1": "body.inertia[0]", "inertia2": "body.inertia[1]", "inertia3": "body.inertia[2]",
               "omega1": "initial.omega[0]", "omega2": "initial.omega[1]", "omega3": "initial.omega[2]",
               "orbit_a": "orbit.a", "orbit_e": "orbit.e", "orbit_i": "orbit.i", "orbit_raan": "orbit.raan",
               "orbit_argp": "orbit.argp", "orbit_true_anomaly": "orbit.true_anomaly",
               "orbit_mean_anomaly": "orbit.mean_anomaly"}

#: a path: dotted keys, each optionally followed by one ``[index]``
PATH_PATTERN = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]*(\[\d+\])?(\.[A-Za-z_][A-Za-z0-9_-]*(\[\d+\])?)*$")
_SEGMENT = re.compile(r"([A-Za-z_][A-Za-z0-9_-]*)(?:\[(\d+)\])?")


def split_path(path):
    """The steps of ``path``: keys (str) and indices (int), in order; ValueError when it is not
    a path."""
    if not isinstance(path, str) or not PATH_PATTERN.match(path):
        raise ValueError(f"{path!r} is not a scenario path such as 'control.gain' or 'initial.omega[0]'")
    steps = []
    for seg in path.split("."):
        m = _SEGMENT.fullmatch(seg)
        steps.append(m.group(1))
        if m.group(2) is not None:
            steps.append(int(m.group(2)))
    return steps


def resolve(data, path, defaults=None):
    """The value at ``path`` in the TOML ``data`` (a dict); LookupError naming the first step
    that is not there (a missing key, an index past the end, a step into a value).

    ``defaults`` (``{(table, key): leaf}``, ``table`` the path of the key's table without
    indices, such as ``"body.facets"``) gives the value of a last key that the scenario does
    not write in a table it has: the key takes its default."""
    node = data
    done = ""
    steps = split_path(path)
    for i, step in enumerate(steps):
        where = f"{done}[{step}]" if isinstance(step, int) else (f"{done}.{step}" if done else step)
        if isinstance(step, int):
            if not isinstance(node, list):
                raise LookupError(f"{done or path} is not a list (no [{step}])")
            if step >= len(node):
                raise LookupError(f"{done} has {len(node)} entries; [{step}] is past its end")
        elif not isinstance(node, dict) or step not in node:
            table = ".".join(s for s in steps[:i] if isinstance(s, str))
            if isinstance(node, dict) and i == len(steps) - 1 and defaults and (table, step) in defaults:
                return defaults[table, step]
            raise LookupError(f"{where} is not in the scenario")
        node = node[step]
        done = where
    return node


def substitute(data, values):
    """A deep copy of ``data`` with the leaf at each path of ``values`` (``{path: new value}``)
    replaced."""
    out = copy.deepcopy(data)
    for path, value in values.items():
        steps = split_path(path)
        node = out
        for step in steps[:-1]:
            node = node[step]
        node[steps[-1]] = value
    return out


def leaf_quantity(leaf):
    """``(number, unit text)`` of a numeric leaf: a plain number gives ``(x, None)``, a string
    ``"<number> <unit>"`` its parts; ValueError for anything else."""
    if isinstance(leaf, bool):
        raise ValueError("true/false is not a number")
    if isinstance(leaf, (int, float)):
        return float(leaf), None
    if isinstance(leaf, str):
        parts = leaf.strip().split(None, 1)
        try:
            x = float(parts[0])
        except (ValueError, IndexError):
            raise ValueError(f"{leaf!r} is not a number with a unit") from None
        return x, (parts[1].strip() if len(parts) > 1 else None)
    raise ValueError(f"{leaf!r} is not a number")


def coordinate_name(path):
    """The Dataset coordinate of a swept path: every run of characters other than letters,
    digits and ``_`` replaced by one ``_``, a trailing one dropped
    (``body.facets[0].drag_coefficient`` -> ``body_facets_0_drag_coefficient``)."""
    return re.sub(r"[^A-Za-z0-9_]+", "_", path).rstrip("_")


def _scalar(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n").replace("\t", "\\t") + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_scalar(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_scalar(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


def _key(k):
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else _scalar(k)


def _table(lines, name, table):
    scalars = {k: v for k, v in table.items()
               if not isinstance(v, dict) and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))}
    for k, v in scalars.items():
        lines.append(f"{_key(k)} = {_scalar(v)}")
    for k, v in table.items():
        if k in scalars:
            continue
        sub = f"{name}.{_key(k)}" if name else _key(k)
        if isinstance(v, dict):
            lines.append("")
            lines.append(f"[{sub}]")
            _table(lines, sub, v)
        else:  # an array of tables
            for entry in v:
                lines.append("")
                lines.append(f"[[{sub}]]")
                _table(lines, sub, entry)


def toml_text(data):
    """TOML text of ``data`` (dicts, arrays of tables, lists, strings, numbers, booleans) that
    ``tomllib`` reads back to an equal dict (floats written with ``repr``: exactly)."""
    lines = []
    _table(lines, "", data)
    return "\n".join(lines).lstrip("\n") + "\n"

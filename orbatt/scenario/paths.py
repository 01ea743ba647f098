"""Scenario keys addressed by their path as written in TOML (issue 23; ``docs/design.md`` §13):
``"table.key"``, ``"table.key[i]"``, ``"table.array[i].key"`` (``"control.gain"``,
``"initial.omega[0]"``, ``"body.facets[0].drag_coefficient"``, ``"body.wheels[2].speed"``).

A sweep varies such a numeric leaf from case to case; a case's scenario is the file with the
leaves replaced (:func:`substitute`), written back as TOML (:func:`toml_text`), and that
scenario's single run defines the case. The schema validates the case's text; here only a
swept path is checked to name a numeric key (:func:`path_unit`), whose default it may take
(:data:`DEFAULT_LEAVES`).
"""
from __future__ import annotations

import copy
import math
import re

from .. import units as U

__all__ = ["DEFAULT_LEAVES", "FIXED_TABLES", "path_unit", "ALIAS_PATHS", "PATH_PATTERN", "split_path", "resolve", "substitute", "toml_text", "coordinate_name",
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


#: the value a numeric key takes when the scenario does not write it, as a TOML leaf, by its
#: table's path without indices and its name (``KEY_DOCS``' numeric defaults): a swept path may
#: name such a key, its nominal value being the default
DEFAULT_LEAVES = {("body.facets", "drag_coefficient"): 2.2, ("body.facets", "specular"): 0.0,
                  ("body.facets", "diffuse"): 0.0, ("body.wheels", "speed"): "0.0 rad / s",
                  ("sensors", "case"): 0, ("sensors.gyro", "rrw"): "0.0 rad / s(3/2)"}

#: tables whose keys a sweep does not vary: the output times and the method are shared by all cases
FIXED_TABLES = ("sweep", "integration", "name", "description")


def path_unit(ctx, path, data, given=None):
    """The unit text of the numeric scenario key at ``path`` (None for a plain number), checked:
    the path exists in ``data``, is not in :data:`FIXED_TABLES`, holds a number (a
    ``"<number> <unit>"`` string or a plain number), not an epoch; raises
    :class:`~orbatt.scenario.ScenarioError` naming the path. A plain ``0`` (a zero needs no
    unit: ``raan = 0``) takes the unit of the parameter's table ``given`` (its first value,
    mean, low, high or std with a unit), so that it varies by values with units; each case's
    scenario then checks that unit against the key."""
    where = f'[sweep.parameters."{path}"]'
    try:
        steps = split_path(path)
    except ValueError as exc:
        raise ctx.error(where, str(exc)) from None
    if steps[0] in FIXED_TABLES:
        raise ctx.error(where, f"[{steps[0]}] is shared by all cases (the output times and the method); vary the keys "
                               "of [body], [initial], [orbit], [control], [torques], [environment], [primary]")
    try:
        leaf = resolve(data or {}, path, DEFAULT_LEAVES)
    except LookupError as exc:
        raise ctx.error(where, f"{exc}; give the path of a key the scenario has") from None
    if isinstance(steps[-1], str) and steps[-1] == "epoch" or (isinstance(leaf, str) and re.match(r"^\s*\d{4}-", leaf)):
        raise ctx.error(where, f"{leaf!r} is a time (an epoch): time-valued keys do not vary in a sweep yet")
    if isinstance(leaf, list):
        raise ctx.error(where, f"holds a list; vary one element, e.g. \"{path}[0]\"")
    try:
        _, unit = leaf_quantity(leaf)
    except ValueError as exc:
        raise ctx.error(where, f"{exc}: only numeric keys vary") from None
    if unit is None and not isinstance(leaf, str) and leaf == 0:
        unit = _given_unit(given)
    if unit is not None:
        try:
            U.parse_unit(unit)
        except Exception:  # noqa: BLE001 - the scenario's own check names it better
            raise ctx.error(where, f"{leaf!r} is not a number with a unit: only numeric keys vary") from None
    return unit


def _given_unit(d):
    """The unit text of the first value with a unit in a parameter's table ``d`` (its values,
    then mean, low, high, std), or None."""
    if not isinstance(d, dict):
        return None
    vals = d.get("values")
    cands = (vals if isinstance(vals, list) else []) + [d.get(k) for k in ("mean", "low", "high", "std")]
    for x in cands:
        if isinstance(x, str):
            try:
                unit = leaf_quantity(x)[1]
            except ValueError:
                continue
            if unit is not None:
                return unit
    return None

"""No import cycles between orbatt's modules (issue 34 item 5).

A module graph read from the source alone (no import is run), as the team's
``import_cycles.py`` reads it: every ``import`` and ``from ... import`` of an orbatt module
counts, those inside functions too (an import deferred into a function is still a loop in the
design, deferred only to dodge the interpreter); ``from P import name`` is an edge to the
module ``P.name`` where there is one, else to ``P`` (a package's ``__init__``). A cycle is a
strongly connected group of two or more modules; each is reported with the import lines that
close it.
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "orbatt"


def modules(root: Path) -> dict[str, Path]:
    """``{dotted name: file}`` of every module of the package at ``root`` (a package by the
    name of its ``__init__``'s folder)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = (root.name,) + path.relative_to(root).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _targets(mod: str, node: ast.ImportFrom, mods: dict[str, Path]) -> list[str]:
    base = mod.split(".") if mods[mod].name == "__init__.py" else mod.split(".")[:-1]
    if node.level:
        base = base[:len(base) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    out = []
    for alias in node.names:
        cand = f"{target}.{alias.name}"
        out.append(cand if cand in mods else target)
    return [t for t in out if t in mods and t != mod]


def import_graph(root: Path) -> tuple[dict[str, Path], dict[str, dict[str, int]]]:
    """The modules and ``{module: {imported module: first line}}``."""
    mods = modules(root)
    edges: dict[str, dict[str, int]] = {m: {} for m in mods}
    for mod, path in mods.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.ImportFrom):
                for t in _targets(mod, node, mods):
                    edges[mod].setdefault(t, node.lineno)
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name in mods and alias.name != mod:
                        edges[mod].setdefault(alias.name, node.lineno)
    return mods, edges


def cycles(edges: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected groups of two or more modules (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10 * len(edges) + 100))
    try:
        for v in edges:
            if v not in index:
                visit(v)
    finally:
        sys.setrecursionlimit(limit)
    return out


def report(root: Path) -> list[str]:
    """One paragraph per cycle: its modules, then the imports between them (file:line)."""
    mods, edges = import_graph(root)
    out = []
    for group in cycles(edges):
        members = set(group)
        lines = [f"    {mods[a].relative_to(root.parent)}:{edges[a][b]} imports {b}"
                 for a in group for b in edges[a] if b in members]
        out.append(" <-> ".join(group) + "\n" + "\n".join(lines))
    return out


def test_the_graph_is_read():
    """The check sees the package's imports (it would pass vacuously on an empty graph)."""
    mods, edges = import_graph(PACKAGE)
    assert len(mods) > 100
    assert "orbatt.dataset.content" in edges["orbatt.dataset.build"]        # from .content import ...
    assert "orbatt.dataset.figure_data" in edges["orbatt.dataset.accessor"]  # inside a method
    assert "orbatt.quaternion" in edges["orbatt.dataset.build"]             # from .. import quaternion


def test_a_cycle_is_found(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    (pkg / "b.py").write_text("def f():\n    from .sub import c\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "c.py").write_text("import pkg.a\n")
    (pkg / "d.py").write_text("from .a import b\n")  # into the loop, not part of it
    found = report(pkg)
    assert len(found) == 1 and found[0].startswith("pkg.a <-> pkg.b <-> pkg.sub.c"), found
    assert "pkg/b.py:2 imports pkg.sub.c" in found[0]


def test_no_import_cycles():
    found = report(PACKAGE)
    assert not found, f"{len(found)} import cycle(s) in orbatt/:\n" + "\n".join(found)

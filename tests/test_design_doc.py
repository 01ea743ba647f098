"""Every citation of the design document resolves: ``docs/design.md §N`` (also ``§Na``,
``§N-M``, ``§N, §M``, ``§3a item K``) in the package, the tests, the benchmarks, the notebooks,
the shipped scenarios, README.md and docs/*.md names a section heading ``## N.`` of
``docs/design.md`` (and an item of the numbered list of §3a), and no citation of the team's
old private notes is left."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "design.md"

#: where citations are looked for: (folder, glob)
SOURCES = [("orbatt", "**/*.py"), ("tests", "**/*.py"), ("benchmarks", "*.py"), ("benchmarks", "*.md"),
           ("docs", "*.md"), ("notebooks", "*.ipynb"), ("scenarios", "*.toml"), (".", "README.md")]

_REF = r"\d+a?(?!\d|\.\d)"
#: ``docs/design.md`` (in backticks or not), then ``§N`` and more ``§M`` joined by ``,``, ``/``,
#: ``-``, ``and`` (``§1-2`` is a range), then optionally ``item(s) K, L and M`` of the last one
CITATION = re.compile(
    r"docs/design\.md`{0,2}\s*(?:section\s+)?§(?P<refs>" + _REF + r"(?:\s*(?:,|/|-|and)\s*§?" + _REF + r")*)"
    r"(?:\s+items?\s+(?P<items>\d+(?:(?:\s*,\s*|\s+and\s+)\d+)*))?")
#: a section number written after the path without ``§``: not a citation this test can check
UNMARKED = re.compile(r"docs/design\.md`{0,2}[ \t]+(?:section[ \t]+)?\d")
#: the team's notes were cited by this word (built in two parts, so that this file does not cite them)
OLD = re.compile(r"\b" + "DES" + r"IGN(?:\.md|'s|\b)")


def _files():
    for folder, pattern in SOURCES:
        for path in sorted((ROOT / folder).glob(pattern)):
            if path.is_file() and path != DOC:
                yield path


def _text(path):
    return path.read_text(encoding="utf-8")


def _sections():
    return set(re.findall(r"^## (\d+a?)\. ", _text(DOC), flags=re.M))


def _errata_items():
    body = _text(DOC).split("\n## 3a. ", 1)[1].split("\n## ", 1)[0]
    return {int(n) for n in re.findall(r"^(\d+)\. ", body, flags=re.M)}


def _expand(refs):
    """``"1-2"`` -> ``["1", "2"]``; ``"3 / §3a"`` -> ``["3", "3a"]``."""
    out = []
    for part in re.split(r"\s*(?:,|/|and)\s*", refs.replace("§", "")):
        if "-" in part:
            a, b = (int(x) for x in part.split("-"))
            out.extend(str(n) for n in range(a, b + 1))
        elif part:
            out.append(part)
    return out


def _citations():
    found = []
    for path in _files():
        text = _text(path)
        for m in CITATION.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            refs = _expand(m.group("refs"))
            items = [int(k) for k in re.findall(r"\d+", m.group("items") or "")]
            found.append((f"{path.relative_to(ROOT)}:{line}", refs, items))
    return found


def test_the_design_document_has_every_section():
    sections = _sections()
    expected = {str(n) for n in range(1, 14)} | {"3a"}
    assert expected <= sections, sorted(expected - sections)
    assert _errata_items() == set(range(1, 11))


def test_citations_are_found():
    # the code cites the document ~90 times; a broken pattern would find none and pass vacuously
    assert len(_citations()) >= 60


@pytest.mark.parametrize("where, refs, items", _citations(), ids=lambda v: v if isinstance(v, str) else None)
def test_every_citation_resolves(where, refs, items):
    sections = _sections()
    missing = [r for r in refs if r not in sections]
    assert not missing, f"{where}: docs/design.md has no section {missing}"
    if items:
        assert refs[-1] == "3a", f"{where}: items are cited of §{refs[-1]}, only §3a has numbered items"
        bad = sorted(set(items) - _errata_items())
        assert not bad, f"{where}: §3a has no item {bad}"


def test_no_unmarked_or_old_citation():
    bad = []
    for path in _files():
        text = _text(path)
        for rx in (UNMARKED, OLD):
            for m in rx.finditer(text):
                bad.append(f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)!r}")
    assert not bad, "cite docs/design.md §N instead:\n" + "\n".join(bad)


def _module_map():
    """The files ``docs/design.md`` §8's module map names, as paths under ``orbatt/``: a line
    ``  name.py ...`` (or ``  a.py, b.py  ...``) is a top-level module, ``  folder/ a.py, b.py``
    and its continuation lines (starting with a file) list a package's modules, and the lines
    indented under ``  core/`` are ``core/``'s."""
    text = _text(DOC).split("**Module map**", 1)[1].split("```", 2)[1]
    files, folder = [], None
    for line in text.splitlines()[1:]:  # after the "orbatt/" line
        tokens = line.split()
        if not tokens:
            continue
        indent = len(line) - len(line.lstrip())
        leading = []
        for tok in tokens:
            if not tok.rstrip(",").endswith(".py"):
                break
            leading.append(tok.rstrip(","))
        if indent == 2 and tokens[0].endswith("/"):
            folder = tokens[0]
            files += [folder + t.rstrip(",") for t in tokens[1:] if t.rstrip(",").endswith(".py")]
        elif indent == 2:
            folder = None
            files += leading
        elif indent == 4 and folder == "core/":
            files += ["core/" + t for t in leading]
        elif folder is not None and leading:
            files += [folder + t for t in leading]
    return files


def test_the_module_map_is_the_tree():
    """§8's module map names every module of the package (``__init__.py`` aside) and no file
    that is not there (issue 34: it described files that were not in the tree)."""
    files = _module_map()
    assert len(files) >= 100 and "core/rk_loop.py" in files and "dataset/netcdf_direct.py" in files
    missing = [f for f in files if not (ROOT / "orbatt" / f).is_file()]
    assert not missing, f"docs/design.md §8's module map names files that are not in orbatt/: {missing}"
    tree = sorted(str(p.relative_to(ROOT / "orbatt")) for p in (ROOT / "orbatt").rglob("*.py")
                  if p.name != "__init__.py")
    unnamed = [f for f in tree if f not in files]
    assert not unnamed, f"modules of orbatt/ that docs/design.md §8's module map does not name: {unnamed}"

"""``docs/scenarios.md`` is generated from the schema (issue 13): every table and key is
described, and the committed file is the generated text."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from orbatt.scenario.reference import markdown, undocumented_keys
from orbatt.scenario.schema import TABLES

DOC = Path(__file__).resolve().parent.parent.parent / "docs" / "scenarios.md"


def test_every_key_of_the_schema_is_described():
    assert undocumented_keys() == []


def test_committed_reference_is_the_generated_one():
    text = markdown()
    for table, keys in TABLES.items():
        assert f"## `[{table}]`" in text
        for k in keys or ():
            assert f"| `{k}` |" in text, (table, k)
    assert DOC.read_text() == text, "regenerate: python -m orbatt.scenario.reference > docs/scenarios.md"


def test_reference_module_prints_it():
    r = subprocess.run([sys.executable, "-m", "orbatt.scenario.reference"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and r.stdout == markdown()

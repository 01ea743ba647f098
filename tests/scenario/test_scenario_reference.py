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


def test_the_reference_says_control_needs_an_orbit_as_the_schema_refuses_it():
    """issue 35 item 3: docs/scenarios.md says [control] needs an [orbit], and a scenario without
    one is refused (an inertial target too: only the Python API runs that case); docs/design.md
    no longer says TLE sweeps are refused."""
    import pytest

    from orbatt.scenario import ScenarioError, parse

    root = Path(__file__).resolve().parents[2]
    control = markdown().split("## `[control]`")[1].split("| key |")[0]
    assert "Needs an `[orbit]`" in control and "TorqueFree()" in control
    text = ('[body]\ninertia = ["1 kg m2", "2 kg m2", "3 kg m2"]\n[initial]\nq = [1.0, 0.0, 0.0, 0.0]\n'
            'omega = ["0.01 rad/s", "0 rad/s", "0 rad/s"]\n[potential]\nkind = "torque-free"\n'
            '[integration]\nmethod = "dop853"\nt_end = "100 s"\noutput_step = "10 s"\n')
    text += '\n[control]\nlaw = "pd"\ntarget = "inertial"\ntarget_q = [1.0, 0.0, 0.0, 0.0]\nkp = "1e-3 N m"\nkd = "1e-2 N m s"\n'
    with pytest.raises(ScenarioError, match=r"control needs an orbit"):
        parse(text, "free.toml")
    design = (root / "docs" / "design.md").read_text()
    assert "TLE orbits are refused" not in design and "Sweeps\nover TLE orbits run (§13)" in design

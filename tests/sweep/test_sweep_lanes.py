"""A sweep whose scenario sets a lockstep-lanes method (issue 32 item 8): its members step together
between the flight software's shared ticks (one group step per tick per group of members), and
the cases agree with the same sweep stepped member by member."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from orbatt.quaternion import conj, mul
from orbatt.scenario import Scenario, parse
from orbatt.shipped import shipped_file
from orbatt.sweep import Sweep

pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")

SAMPLES = 12


def _text(method, t_end="40 s"):
    """The 10 Hz LVLH hold on three wheels (benchmarks/basilisk_fsw.py), ``SAMPLES`` cases of
    initial rates uniform in +-1 deg/s, ``[integration] method = method``."""
    text = shipped_file("lvlh-hold-wheels").read_text()
    text = text.replace('actuator = "wheels"\n', 'actuator = "wheels"\nperiod = "0.1 s"\n', 1)
    text = re.sub(r'^t_end = "[^"]*"', f't_end = "{t_end}"', text, flags=re.M)
    text = text.replace('method = "dop853"', f'method = "{method}"', 1)
    assert f'method = "{method}"' in text
    return text + (f'\n[sweep]\nsamples = {SAMPLES}\nseed = 7\noutputs = ["final_state"]\n\n[sweep.parameters]\n'
                   + "".join(f'omega{i} = {{ distribution = "uniform", low = "-1 deg/s", high = "1 deg/s" }}\n'
                             for i in (1, 2, 3)))


def _angle(qa, qb):
    w = mul(conj(qb), qa)
    return 2 * np.arctan2(np.linalg.norm(w[..., 1:], axis=-1), np.abs(w[..., 0]))


@pytest.mark.parametrize("lanes", ["bs32-lanes", "dopri5-lanes"])
def test_lanes_sweep_steps_its_members_together_between_ticks(lanes):
    """The cases share the ticks and form one group, which takes one group step per tick (the
    group's error is its largest member's: ``bs32`` takes ~1.6 per tick in these first 40 s of
    the 30 deg transient, ~1.1 over 200 s, ``dopri5`` one) and counts it for each member; its
    final attitudes agree with the member-by-member sweep of the same pair to 1e-9 rad and with
    ``dop853`` to the pair's own error (``bs32`` at rtol 1e-10: 1.3e-9 rad at the worst here,
    ``dopri5``: 1e-15)."""
    single = lanes.removesuffix("-lanes")
    res = {m: Sweep(Scenario(parse(_text(m), f"{m}.toml"))).compute() for m in (lanes, single, "dop853")}
    ticks = 400
    stats = json.loads(res[lanes].attrs["integration_stats"])
    assert stats["members"] == SAMPLES and stats["rejected_steps"] == 0
    assert ticks <= stats["group_steps"] <= (2 if single == "bs32" else 1) * ticks
    assert stats["steps"] == SAMPLES * stats["group_steps"]
    one = json.loads(res[single].attrs["integration_stats"])
    assert "group_steps" not in one and one["steps"] >= SAMPLES * ticks
    q = {m: np.asarray(ds["q_final"].transpose("case", ...).values) for m, ds in res.items()}
    assert _angle(q[lanes], q[single]).max() < 1e-9
    assert _angle(q[lanes], q["dop853"]).max() < (5e-9 if single == "bs32" else 1e-12)

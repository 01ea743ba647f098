"""The time-series figures shade the flight software's modes (issue 32 item 4): each mode's
interval, from the Dataset's ``mode`` (CF ``flag_values`` / ``flag_meanings``) and
``mode_entry_time``, one colour per mode, the legend naming them."""
from __future__ import annotations

import re

import matplotlib
import numpy as np
import pytest

import orbatt
from orbatt.dataset.figures import draw
from orbatt.dataset.timeaxis import elapsed_values
from orbatt.scenario import parse
from orbatt.shipped import shipped_file

matplotlib.use("Agg")

CONTROL = """[control]
period = "0.1 s"

[[control.modes]]
name = "acquire"
law = "pd"
target = "orbital"
kp = "4e-3 N m"
kd = "8e-2 N m s"
max_torque = "4e-3 N m"
actuator = "wheels"
until_time = "1.1 s"

[[control.modes]]
name = "hold"
law = "pd"
target = "orbital"
target_q = [0.9961946980917455, 0.0, 0.08715574274765817, 0.0]
kp = "4e-3 N m"
kd = "8e-2 N m s"
max_torque = "4e-3 N m"
actuator = "wheels"
"""


@pytest.fixture(scope="module")
def ds():
    """Two modes on wheels at 10 Hz, the switch at the tick 1.1 s, between the outputs 1.0 and
    1.25 s."""
    text = shipped_file("lvlh-hold-wheels").read_text()
    text = re.sub(r"\[control\]\n(?:[^\[]*\n)", CONTROL + "\n", text, count=1)
    text = re.sub(r't_end = "[^"]*"', 't_end = "4 s"', text)
    text = re.sub(r'output_step = "[^"]*"', 'output_step = "0.25 s"', text)
    return orbatt.Scenario(parse(text, "modes-shaded.toml")).run()


def _expected(ds):
    """The modes' intervals read off the Dataset: a stretch of equal ``mode`` values begins at
    its mode's ``mode_entry_time`` and ends where the next begins, or at the last output."""
    mode, t = ds["mode"].values, elapsed_values(ds)
    entry = ds["mode_entry_time"].values
    names = dict(zip(ds["mode"].attrs["flag_values"].tolist(), ds["mode"].attrs["flag_meanings"].split()))
    firsts = [i for i in range(mode.size) if i == 0 or mode[i] != mode[i - 1]]
    starts = [entry[mode[i]] for i in firsts]
    ends = starts[1:] + [t[-1]]
    return [(a, b, names[int(mode[i])]) for a, b, i in zip(starts, ends, firsts)]


@pytest.mark.parametrize("figure", ["pointing", "rates", "wheels"])
def test_each_modes_interval_is_shaded_with_its_name(ds, figure):
    want = _expected(ds)
    assert [w[2] for w in want] == ["acquire", "hold"]
    assert want[0][0] == 0.0 and abs(want[1][0] - 1.1) < 1e-9 and want[1][1] == 4.0  # between outputs
    fig = draw(ds, figure, time="elapsed")  # 4 s: the axis in s
    try:
        for ax in fig.axes:
            spans = sorted((p for p in ax.patches if str(p.get_gid()).startswith("mode ")), key=lambda p: p.get_x())
            if not spans:
                continue
            got = [(p.get_x(), p.get_x() + p.get_width(), int(p.get_gid().split()[1])) for p in spans]
            assert len(got) == len(want)
            for (a, b, k), (wa, wb, name) in zip(got, want):
                assert abs(a - wa) <= 1e-12 and abs(b - wb) <= 1e-12
                assert ds["mode"].attrs["flag_meanings"].split()[k] == name
            labels = ax.get_legend_handles_labels()[1]
            assert "mode: acquire" in labels and "mode: hold" in labels
            break
        else:
            pytest.fail(f"no mode shaded on the {figure} figure")
    finally:
        matplotlib.pyplot.close(fig)


def test_a_run_without_modes_shades_none():
    ds = orbatt.load_scenario("lvlh-hold-wheels").run()
    fig = draw(ds, "rates")
    try:
        assert not [p for ax in fig.axes for p in ax.patches if str(p.get_gid()).startswith("mode ")]
    finally:
        matplotlib.pyplot.close(fig)

"""The quick plots read as a user would keep them (issue 13 §4): every axis labelled with its
quantity and unit, time in orbits or UTC dates, unwrapped angles, the drift panel titled as
what it shows, no gaps at exact zeros on log axes. Checked on labels and data, not pixels."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest

import orbatt
from orbatt.dataset.plots import drift_series, time_axis

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SCEN = Path(__file__).resolve().parent.parent.parent / "scenarios"


def _run(name, t_end=None, **replace):
    text = (SCEN / f"{name}.toml").read_text()
    for key, value in replace.items():
        text = text.replace(*value)
    if t_end is not None:
        import re

        text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    from orbatt.scenario.schema import parse
    from orbatt.scenario.load import Scenario

    return Scenario(parse(text, name)).run()


@pytest.fixture(scope="module")
def free():
    return _run("paper-torque-free")


@pytest.fixture(scope="module")
def circular():  # gravity gradient on a circular Kepler orbit, no epoch
    return _run("gg-stabilized-leo", '"2 orbits"', e=("e = 0.001", "e = 0.0"))


@pytest.fixture(scope="module")
def eccentric():  # the same on the shipped, slightly eccentric orbit: nothing is conserved
    return _run("gg-stabilized-leo", '"2 orbits"')


@pytest.fixture(scope="module")
def tle():  # an epoch: UTC dates
    return _run("iss-tle-gravity-gradient", '"3000 s"')


def _labels(fig):
    return [(ax.get_title(), ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]


def test_every_axis_has_a_quantity_and_unit(free, circular, tle):
    for ds in (free, circular, tle):
        for plot in (ds.orbatt.plot_state, ds.orbatt.plot_attitude, ds.orbatt.plot_drift):
            fig = plot()
            for title, xl, yl in _labels(fig):
                assert title and xl and yl, (plot.__name__, title, xl, yl)
                assert "[" in yl or "(dimensionless)" in yl, yl
                assert "[" in xl or "(dimensionless)" in xl or xl.startswith("UTC"), xl
            plt.close(fig)


def test_time_axis_in_orbits_dates_or_time(free, circular, tle):
    x, label = time_axis(circular)
    assert label == "time [orbits]" and 1.99 < x[-1] <= 2.0 and x[0] == 0.0
    x, label = time_axis(tle)
    assert label.startswith("UTC (from 2019-12-09T17:38:29") and np.issubdtype(x.dtype, np.datetime64)
    assert (x[-1] - x[0]) == np.timedelta64(3000, "s")
    assert time_axis(free)[1] == "time (dimensionless)"
    assert time_axis(circular, "time")[1] == "elapsed time [s]"
    assert time_axis(tle, "orbits")[1] == "time [orbits]"
    with pytest.raises(ValueError, match="needs an epoch"):
        time_axis(circular, "utc")
    fig = tle.orbatt.plot_state()
    assert fig.axes[0].get_xlabel().startswith("UTC")
    plt.close(fig)


def test_angles_are_unwrapped(circular):
    fig = circular.orbatt.plot_attitude()
    ax = fig.axes[0]
    assert ax.get_ylabel() == "angle [degree]" and "unwrapped" in ax.get_title()
    # the 3-1-3 angles of a body turning once per orbit wrap in the file, not in the plot
    raw = np.degrees(circular["euler_313"].values)
    assert np.max(np.abs(np.diff(raw, axis=0))) > 300
    for line in ax.get_lines():
        assert np.max(np.abs(np.diff(line.get_ydata()))) < 180
    plt.close(fig)


def test_drift_panel_says_what_it_is(free, circular, eccentric, tle):
    _, title, ylabel = drift_series(free)
    assert title.startswith("energy H: |H - H0| / |H0|") and ylabel == "relative change (dimensionless)"
    y, title, _ = drift_series(circular)
    assert title.startswith("Jacobi integral J = H - n h.G")
    assert np.max(y) < 1e-12  # conserved on the circular orbit: 4.2e-15 measured (H changes by 0.21)
    H = circular["energy"].values
    assert np.max(np.abs(H - H[0])) / abs(H[0]) > 100 * np.max(y)  # while H itself is not
    for ds in (eccentric, tle):
        assert drift_series(ds)[1].startswith("energy change (not conserved)")
    fig = circular.orbatt.plot_drift()
    assert fig.axes[0].get_title().startswith("Jacobi integral")
    plt.close(fig)


def test_log_axes_have_no_gaps_at_exact_zeros(free):
    fig = free.orbatt.plot_drift()
    for ax in fig.axes:
        y = ax.get_lines()[0].get_ydata()
        assert np.all(np.isfinite(y)) and np.all(y > 0)  # the first point (exactly 0) is drawn
    plt.close(fig)

"""The figures as a design review reads them (issue 35 §2), checked on what is drawn - labels,
colours, data, axes - against the Dataset's own definitions, not on pixels:

- roll, pitch, yaw are the Dataset's ``euler_321`` (pitch about the orbit normal o3), stated on
  the panel and in each line's label;
- no value invented for a log axis (a zero is a gap, said so); no legend on the data; one
  colour per series of an axis;
- the torque budget closes with the wheels' gyroscopic term; a rotation angle never above 180
  deg; short runs in the time since the start; Sun pointing without SRP has its figure;
- Monte Carlo: per-wheel distributions, a grid parameter's cases drawn apart, short tick
  labels, no unit "1";
- binaries: the mutual orbit, period and libration, the impulses marked, time in h or d.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from orbatt import quaternion as qt  # noqa: E402
from orbatt.dataset import figures as F  # noqa: E402
from orbatt.dataset.figure_data import (LVLH_LABELS, choose_figures, impulse_times, libration_angle,  # noqa: E402
                                        log_values, pointing_error, wheel_gyroscopic)
from orbatt.dataset.plots import time_axis  # noqa: E402
from orbatt.dataset.sweep_figures import draw_sweep, grid_parameters, sweep_wheel_outputs  # noqa: E402
from orbatt.orbital import lvlh_angles  # noqa: E402

SCEN = Path(__file__).resolve().parent.parent.parent / "scenarios"


def _run(name, t_end=None, *replace):
    text = (SCEN / f"{name}.toml").read_text()
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    if t_end is not None:
        text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    from orbatt.scenario.load import Scenario
    from orbatt.scenario.schema import parse

    return Scenario(parse(text, name)).run()


@pytest.fixture(scope="module")
def gg():  # uncontrolled, librating about the orbital frame: pitch (about o3) the largest
    return _run("gg-stabilized-leo", '"1 orbits"')


@pytest.fixture(scope="module")
def wheels():  # PD on the orbital frame with three wheels, past its transient
    return _run("lvlh-hold-wheels", '"1500 s"')


@pytest.fixture(scope="module")
def disturbed():  # drag, SRP (0 in the eclipse), magnetic, gravity gradient; an epoch
    return _run("cubesat-3u-disturbances", '"1 orbits"')


@pytest.fixture(scope="module")
def tumbling():
    return _run("molniya-tumbling", '"3000 s"')


@pytest.fixture(scope="module")
def binary():  # one day, the impulse at 10 h
    return _run("didymos-dimorphos", '"1 d"', ('time = "86400 s"', 'time = "36000 s"'))


def _figures(ds):
    return {name: F.draw(ds, name) for name in choose_figures(ds)}


def _close(figs):
    for fig in figs.values():
        plt.close(fig)


# ------------------------------------------------------------------------------------------
# roll, pitch, yaw: one definition, the Dataset's euler_321
# ------------------------------------------------------------------------------------------

def test_roll_pitch_yaw_are_the_datasets_euler_321(gg):
    """The pointing figure of an uncontrolled run draws ``euler_321`` itself, each line named
    with the axis it turns about, the sequence stated on the panel; gg-stabilized-leo's pitch
    libration (about the orbit normal o3) is the line called pitch."""
    err = pointing_error(gg)
    np.testing.assert_allclose(err.components, gg["euler_321"].values, rtol=0, atol=1e-12)
    assert err.labels == LVLH_LABELS and "euler_321" in err.definition
    assert [str(v) for v in gg["euler_321_label"].values] == [lab.split()[0] for lab in err.labels]
    # each label names the axis as the Dataset's long_name does
    meaning = gg["euler_321"].attrs["long_name"]
    for lab in err.labels:
        name, axis = re.match(r"(\w+) \(about (o\d)", lab).groups()
        assert f"{name} (about along-track {axis})" in meaning or f"{name} (about orbit normal {axis})" in meaning \
            or f"{name} (about radial {axis})" in meaning
    fig = F.plot_pointing(gg)
    top, panel = fig.axes
    assert panel.get_title() == err.definition
    lines = {line.get_label(): line.get_ydata() for line in panel.get_lines()}
    for k, lab in enumerate(LVLH_LABELS):
        np.testing.assert_allclose(lines[lab], np.degrees(gg["euler_321"].values[:, k]), atol=1e-10)
    spread = {lab.split()[0]: np.ptp(y) for lab, y in lines.items()}
    assert max(spread, key=spread.get) == "pitch"  # the in-plane libration
    plt.close(fig)


def test_a_rotation_about_each_orbital_axis_is_named_for_it():
    """10 deg about o1, o2, o3 (``q_orbital``) read as yaw, roll, pitch: the convention pinned
    with one example per axis, as lvlh_angles and the figure's labels state it."""
    for axis, name in ((0, "yaw"), (1, "roll"), (2, "pitch")):
        e = np.zeros(3)
        e[axis] = 1.0
        q = np.concatenate([[np.cos(np.radians(5.0))], np.sin(np.radians(5.0)) * e])
        angles = np.degrees(np.array(lvlh_angles(q[None]))[:, 0])
        k = [lab.split()[0] for lab in LVLH_LABELS].index(name)
        assert LVLH_LABELS[k].startswith(f"{name} (about o{axis + 1}")
        np.testing.assert_allclose(angles[k], 10.0, rtol=1e-12)
        assert np.abs(np.delete(angles, k)).max() < 1e-12


# ------------------------------------------------------------------------------------------
# every figure: colours, legends, log axes
# ------------------------------------------------------------------------------------------

def _check_drawing(fig):
    """One colour (and line style) per labelled series of an axis; no legend over an axis'
    data; on a log axis no drawn value at or below 0 and no value that is not in the data."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        seen = {}
        for line in ax.get_lines():
            label = line.get_label()
            if label.startswith("_"):
                continue
            key = (matplotlib.colors.to_hex(line.get_color()), line.get_linestyle())
            assert key not in seen, f"{label!r} and {seen.get(key)!r} share {key} in {ax.get_title()!r}"
            seen[key] = label
        legend = ax.get_legend()
        if legend is not None:
            assert not legend.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer)), ax.get_title()
        if ax.get_yscale() == "log":
            for line in ax.get_lines():
                if isinstance(line.get_transform(), matplotlib.transforms.BlendedGenericTransform):
                    continue  # a reference line across the axis (a threshold, an impulse)
                y = np.asarray(line.get_ydata(), dtype=float)
                assert not np.any(y[np.isfinite(y)] <= 0.0)


def test_colours_legends_and_log_axes_of_every_figure(gg, wheels, disturbed, tumbling, binary):
    for ds in (gg, wheels, disturbed, tumbling, binary):
        figs = _figures(ds)
        for fig in figs.values():
            _check_drawing(fig)
        _close(figs)
    assert len(set(F.TORQUE_COLORS.values())) == len(F.TORQUE_COLORS)  # srp and control apart, and the rest


def test_zeros_on_a_log_axis_are_gaps():
    y, zeros = log_values([1e-7, 0.0, 2e-7, -0.0, np.nan])
    assert zeros == 2 and np.isnan(y[[1, 3, 4]]).all() and list(y[[0, 2]]) == [1e-7, 2e-7]


def test_the_torque_budget_closes_with_the_wheels_gyroscopic_term(wheels):
    """lvlh-hold-wheels: 6e-5 N m of control against 1e-7 N m of gravity gradient is the
    wheels' momentum carried round by the body, omega x h; drawn, and equal to the control."""
    gyro = wheel_gyroscopic(wheels)
    h = np.einsum("tk,ki->ti", wheels["wheel_momentum"].values, wheels["wheel_axis"].values)
    np.testing.assert_allclose(gyro, np.cross(wheels["omega"].values, h), rtol=1e-14)
    late = wheels["elapsed"].values >= 1000.0
    ctrl = wheels["torque_control"].values
    assert np.linalg.norm(ctrl[late] - gyro[late], axis=-1).max() < 0.02 * np.linalg.norm(ctrl[late], axis=-1).min()
    external = np.linalg.norm(wheels["torque"].values[late], axis=-1)
    assert external.max() < 1e-2 * np.linalg.norm(ctrl[late], axis=-1).min()
    fig = F.plot_torques(wheels)
    (ax,) = fig.axes
    lines = {line.get_label(): line for line in ax.get_lines()}
    np.testing.assert_allclose(lines["wheels' gyroscopic omega x h"].get_ydata(), np.linalg.norm(gyro, axis=-1))
    assert lines["wheels' gyroscopic omega x h"].get_linestyle() == "--"  # visible over the control
    assert "the control balances omega x h" in ax.get_title()
    plt.close(fig)


def test_a_tumbling_bodys_error_is_at_most_180_deg_on_a_linear_axis(tumbling):
    fig = F.plot_pointing(tumbling)
    ax = fig.axes[0]
    assert ax.get_yscale() == "linear" and ax.get_ylim() == (0.0, 180.0)
    assert "no roll/pitch/yaw panel" in ax.get_title()
    plt.close(fig)


def test_short_runs_in_time_since_the_start(disturbed, binary):
    x, label = time_axis(disturbed)  # one orbit from an epoch: minutes, not UTC ticks
    assert label.startswith("time since 2") and label.endswith("UTC [min]") and x[0] == 0.0
    x, label = time_axis(binary)  # no epoch, no orbit: hours
    assert label == "elapsed time [h]" and x[-1] == 24.0


def test_sun_pointing_without_srp_has_the_sun_direction_and_its_figure():
    """A PD law on the Sun with no SRP term: the Dataset carries the Sun's direction (the
    law's own table), and the pointing figure draws the angle to it."""
    from astropy import units as u
    from astropy.time import Time

    import orbatt
    from orbatt import dataset as D
    from orbatt.environment.sun import sun_position

    epoch = Time("2024-06-01T00:00:00", scale="utc")
    orbit = orbatt.KeplerOrbit(6878.137 * u.km, 0.0, 97.4 * u.deg, 30 * u.deg, 0 * u.deg, epoch=epoch)
    body = orbatt.RigidBody([0.05, 0.06, 0.02] * u.kg * u.m**2)
    pd = orbatt.PDControl("sun", kp="2e-3 N m", kd="0.16 N m s", max_torque="1e-3 N m", target_axis=[0.0, 0.0, 1.0])
    env = orbatt.EnvironmentTorques(orbit, 600 * u.s, gravity_gradient=False, control=pd)
    s0 = orbatt.State.from_omega(body, [0.8, 0.3, -0.4, 0.331662479035540], np.zeros(3) * u.rad / u.s)
    t = np.linspace(0.0, 600.0, 61)
    ds = D.to_dataset(orbatt.propagate(body, s0, env, t, rtol=1e-9, atol=1e-9))
    d = sun_position(epoch + t * u.s) - orbit.state(t)[0]
    np.testing.assert_allclose(ds["sun_direction"].values, d / np.linalg.norm(d, axis=1)[:, None], atol=1e-9)
    assert ds["sun_direction"].attrs["units"] == "1" and ds["sun_direction"].attrs["frame"] == "S"
    assert choose_figures(ds)[0] == "pointing"
    err = pointing_error(ds)
    b = qt.rotate(ds["q"].values, np.broadcast_to([0.0, 0.0, 1.0], (t.size, 3)))
    np.testing.assert_allclose(np.cos(err.angle), np.sum(b * ds["sun_direction"].values, axis=1), atol=1e-12)
    plt.close(F.plot_pointing(ds))


# ------------------------------------------------------------------------------------------
# Monte Carlo
# ------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def sweep():
    """A sweep result's layout (nadir-hold-montecarlo's): a grid of two kd values, per-wheel
    speeds, a dimensionless output, a speed parameter of a few mm/s."""
    import xarray as xr

    rng = np.random.default_rng(35)
    n = 40
    kd = np.repeat([0.08, 0.12], n // 2)
    spec = {"omega1": {"kind": "uniform", "low": 0.0, "high": 0.01, "units": "rad s^-1"},
            "control.kd": {"kind": "grid", "values": [0.08, 0.12], "units": "N m s"},
            "orbit.impulses[0].delta_v[1]": {"kind": "normal", "mean": -2.7e-3, "std": 3e-4, "units": "m s^-1"}}
    return xr.Dataset(
        {"settling_time": ("case", rng.uniform(300, 420, n) + 200 * (kd > 0.1), {"units": "s"}),
         "orbit_e_final": ("case", rng.uniform(0.01, 0.03, n), {"units": "1"}),
         "max_wheel_speed": (("case", "wheel"), rng.uniform(100, 250, (n, 3)), {"units": "rad s^-1"}),
         "wheel_saturated": (("case", "wheel"), np.zeros((n, 3), dtype=np.int8)),
         "integration_failed": ("case", np.zeros(n, dtype=np.int8))},
        coords={"case": np.arange(n), "omega1": ("case", rng.uniform(0, 0.01, n), {"units": "rad s^-1"}),
                "control_kd": ("case", kd, {"units": "N m s", "scenario_key": "control.kd"}),
                "dv": ("case", rng.normal(-2.7e-3, 3e-4, n),
                       {"units": "m s^-1", "scenario_key": "orbit.impulses[0].delta_v[1]"})},
        attrs={"title": "orbatt sweep: review (40 cases)", "sweep_parameters": json.dumps(spec)})


def test_monte_carlo_distributions(sweep):
    assert grid_parameters(sweep) == ["control_kd"] and sweep_wheel_outputs(sweep) == ["max_wheel_speed"]
    fig = draw_sweep(sweep, "distributions")
    assert len(fig.axes) == 6  # settling time, eccentricity, the wheels' speeds: histogram and CDF each
    hist, cdf = fig.axes[4], fig.axes[5]
    assert hist.get_xlabel() == "max_wheel_speed [rpm]" and "3 wheels" in hist.get_title()
    steps = [line.get_label() for line in cdf.get_lines() if not line.get_label().startswith(" ")]
    # a CDF per wheel and kd value, each with its own percentiles
    assert [s for s in steps if "(20 cases)" in s] == [
        f"wheel {w}, control.kd = {v} N m s (20 cases)" for w in (1, 2, 3) for v in ("0.08", "0.12")]
    np.testing.assert_allclose(cdf.get_lines()[0].get_xdata()[-1],
                               sweep["max_wheel_speed"].values[:20, 0].max() * 60 / (2 * np.pi))
    # the grid's two values drawn apart in every output: the settling time's two CDFs
    labels = [line.get_label() for line in fig.axes[1].get_lines()]
    assert "control.kd = 0.08 N m s (20 cases)" in labels and "control.kd = 0.12 N m s (20 cases)" in labels
    # a dimensionless output: no unit "1"
    assert fig.axes[2].get_xlabel() == "orbit_e_final (dimensionless)"
    assert not any(line.get_label().rstrip().endswith(" 1") for ax in fig.axes for line in ax.get_lines())
    _no_overlaps(fig)
    plt.close(fig)


def _no_overlaps(fig):
    """No two titles (or the figure's title and an axis') overlap; every legend beside its axis."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [ax.title.get_window_extent(r) for ax in fig.axes if ax.get_title()]
    boxes.append(fig._suptitle.get_window_extent(r))
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b)
    for ax in fig.axes:
        if ax.get_legend() is not None:
            assert not ax.get_legend().get_window_extent(r).overlaps(ax.get_window_extent(r))


def test_monte_carlo_scatter(sweep):
    fig = draw_sweep(sweep, "scatter")
    axes = np.array(fig.axes).reshape(3, 3)  # settling time, e, wheel speeds x omega1, kd, delta v
    kd_axis = axes[-1][1]
    assert kd_axis.get_xlabel() == "control.kd [N m s]"
    assert [t.get_text() for t in kd_axis.get_xticklabels()] == ["0.08", "0.12"]  # a column per grid value
    x = kd_axis.get_lines()[0].get_xdata()
    assert np.all(np.abs(x - np.round(x)) < 0.35)
    # the two kd values in two colours in every panel
    for ax in axes.ravel():
        assert len({matplotlib.colors.to_hex(line.get_color()) for line in ax.get_lines()}) == 2
    # short tick labels: Delta v in mm/s, rates in deg/s
    assert axes[-1][2].get_xlabel() == "orbit.impulses[0].delta_v[1] [mm/s]"
    assert axes[-1][0].get_xlabel() == "omega1 [deg/s]"
    for ax in axes.ravel():
        for t in ax.get_xticklabels() + ax.get_yticklabels():
            assert len(t.get_text()) <= 6, t.get_text()
    assert "(a colour per control.kd)" in fig.get_suptitle()
    _no_overlaps(fig)
    plt.close(fig)


# ------------------------------------------------------------------------------------------
# binaries
# ------------------------------------------------------------------------------------------

def test_binary_orbit_figure_with_the_impulse_marked(binary):
    assert choose_figures(binary) == ("orbit", "rates", "drift")
    assert impulse_times(binary) == [36000.0]
    fig = F.draw(binary, "orbit")
    sep, period, lib = fig.axes
    assert sep.get_ylabel() == "separation [km]" and period.get_ylabel() == "period [h]"
    assert lib.get_ylabel() == "libration [deg]" and lib.get_xlabel() == "elapsed time [h]"
    for ax in fig.axes:  # the impulse on every panel, at 10 h
        marks = [line for line in ax.get_lines() if line.get_label().startswith("impulse")]
        assert len(marks) == 1 and list(marks[0].get_xdata()) == [10.0, 10.0]
    lines = {line.get_label(): line for line in period.get_lines()}
    np.testing.assert_allclose(lines["orbit period (osculating)"].get_ydata(), binary["orbit_period"].values / 3600.0)
    # the mean period (issue 35 item 3) beside the osculating one, NaN within half a window of the ends
    np.testing.assert_allclose(lines["mean period"].get_ydata(), binary["mean_period"].values / 3600.0)
    angle = libration_angle(binary)
    before = binary["elapsed"].values < 36000.0
    assert np.abs(np.degrees(angle[before])).max() < 1.0 < np.abs(np.degrees(angle[~before])).max()
    # the sweep's unsigned angle in space is the same where axis 1 stays in the orbit plane
    from orbatt.sweep.binary_chunk import libration_angle as unsigned

    np.testing.assert_allclose(np.abs(angle), unsigned(binary["q"].values, binary["position"].values), atol=2e-3)
    plt.close(fig)
    fig = F.draw(binary, "drift")  # the energy's jump is the impulse: marked
    assert any(line.get_label().startswith("impulse") for line in fig.axes[0].get_lines())
    assert fig.axes[0].get_xlabel() == "elapsed time [h]"
    plt.close(fig)

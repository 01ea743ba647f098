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
    # a short run with an epoch: the time since its start, in a unit its length suits (not UTC ticks)
    x, label = time_axis(tle)
    assert label == "time since 2019-12-09T17:38:29 UTC [min]" and x[0] == 0.0 and x[-1] == 50.0
    x, label = time_axis(tle, "utc")
    assert label.startswith("UTC (from 2019-12-09T17:38:29") and np.issubdtype(x.dtype, np.datetime64)
    assert (x[-1] - x[0]) == np.timedelta64(3000, "s")
    assert time_axis(free)[1] == "time (dimensionless)"
    assert time_axis(circular, "time")[1] == "elapsed time [s]"
    assert time_axis(circular, "elapsed")[1] == "elapsed time [h]"
    assert time_axis(tle, "orbits")[1] == "time [orbits]"
    with pytest.raises(ValueError, match="needs an epoch"):
        time_axis(circular, "utc")
    fig = tle.orbatt.plot_state()
    assert fig.axes[0].get_xlabel().startswith("time since 2019-12-09")
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


def test_log_axes_leave_gaps_at_exact_zeros_and_say_so(free):
    """No value is invented for a log axis: an exact 0 (the drift's first sample) is a gap,
    counted in the panel's title (issue 35 §2)."""
    fig = free.orbatt.plot_drift()
    assert np.isnan(fig.axes[0].get_lines()[0].get_ydata()[0])  # |H - H0| is exactly 0 at the start: a gap
    for ax in fig.axes:
        y = ax.get_lines()[0].get_ydata()
        assert np.all(y[np.isfinite(y)] > 0)
        zeros = int(np.count_nonzero(np.isnan(y)))
        assert (f"(exactly 0 at {zeros} of {y.size} samples: gaps)" in ax.get_title()) == (zeros > 0)
    plt.close(fig)


# ------------------------------------------------------------------------------------------
# the engineering figures (issue 26 §4): chosen from the content, one file each, written
# atomically, never over a link or a foreign file (§6)
# ------------------------------------------------------------------------------------------
import errno  # noqa: E402
import os  # noqa: E402

from orbatt.cli import main  # noqa: E402
from orbatt.dataset import figures as F  # noqa: E402
from orbatt.dataset.figure_data import choose_figures, pointing_error, wheel_limits  # noqa: E402
from orbatt.dataset.figure_files import check_figure_folder, is_orbatt_figure, write_figures  # noqa: E402
from orbatt.errors import InputError, OrbattError  # noqa: E402


@pytest.fixture(scope="module")
def wheels():  # PD on the orbital frame with three reaction wheels
    return _run("lvlh-hold-wheels", '"600 s"')


@pytest.fixture(scope="module")
def bdot():  # B-dot in the IGRF field
    return _run("cubesat-bdot-detumble", '"300 s"')


@pytest.fixture(scope="module")
def disturbed():  # drag, SRP, magnetic and gravity-gradient torques; one orbit: an eclipse
    return _run("cubesat-3u-disturbances", '"1 orbits"')


@pytest.fixture(scope="module")
def ensemble():  # three members of the gravity-gradient LEO satellite, a quarter orbit
    import warnings

    from astropy import units as u

    from orbatt import quaternion as qt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = orbatt.load_scenario("gg-stabilized-leo")
    rng = np.random.default_rng(5)
    q0 = qt.normalize(sc.state0.q + 0.05 * rng.normal(size=(3, 4)))
    states = orbatt.State.from_momentum(sc.body, q0, np.broadcast_to(sc.state0.g, (3, 3)))
    tr = orbatt.propagate(sc.body, states, sc.potential, np.linspace(0.0, 1500.0, 51) * u.s, rtol=1e-9, atol=1e-9)
    from orbatt import dataset as D

    return D.to_dataset(tr, scenario_text=sc.spec.text)


RATES = ["magnitude of the body rate", "body components"]


def _shows(fig, suptitle, titles, lines):
    """The figure is titled ``suptitle``, has one panel per entry of ``titles`` (each titled
    so) with ``lines[k]`` lines, and a time axis label under the last panel; then it is closed."""
    try:
        assert fig.get_suptitle() == suptitle
        assert [ax.get_title() for ax in fig.axes] == titles
        assert [len(ax.get_lines()) for ax in fig.axes] == lines
        assert all(ax.get_ylabel() for ax in fig.axes)
        assert "time" in fig.axes[-1].get_xlabel() or "UTC" in fig.axes[-1].get_xlabel()
    finally:
        plt.close(fig)


def test_figures_chosen_from_the_content(free, circular, eccentric, wheels, bdot, disturbed, ensemble):
    assert choose_figures(free) == ("rates", "drift")  # torque-free: nothing to point, an invariant to check
    assert choose_figures(circular) == ("pointing", "rates", "torques", "drift")  # the Jacobi integral
    assert choose_figures(eccentric) == ("pointing", "rates", "torques")  # nothing conserved: no drift
    assert choose_figures(wheels) == ("pointing", "rates", "wheels", "torques")
    assert choose_figures(bdot) == ("rates", "torques")  # B-dot has no pointing target
    assert choose_figures(disturbed) == ("pointing", "rates", "torques")
    assert choose_figures(ensemble) == ("pointing", "rates", "torques")  # no drift for cases together
    assert free.orbatt.figures() == ("rates", "drift")


def test_pointing_is_the_error_to_the_target(wheels, eccentric):
    angle, title, rpy, labels, definition = pointing_error(wheels)
    assert "orbital frame target (PD)" in title
    assert 29.0 < np.degrees(angle[0]) < 32.0  # the scenario starts 30 deg off the orbital frame
    # the total angle bounds each of the 3-2-1 error angles
    assert np.all(np.abs(rpy) <= angle[:, None] + 1e-12)
    fig = wheels.orbatt.plot_figure("pointing")
    top, bottom = fig.axes
    # 30 deg down to a few: within two decades, a linear axis, never above 180 deg
    assert top.get_yscale() == "linear" and top.get_ylabel() == "pointing error [deg]"
    assert top.get_ylim()[1] <= 180.0
    np.testing.assert_allclose(top.get_lines()[0].get_ydata(), np.degrees(angle))
    assert [line.get_label() for line in bottom.get_lines()] == [
        "roll (about o2, along-track)", "pitch (about o3, orbit normal)", "yaw (about o1, radial)"]
    assert bottom.get_ylabel() == "error angle [deg]" and fig.axes[-1].get_xlabel() == "time [orbits]"
    _shows(fig, "lvlh-hold-wheels: pointing",
           ["attitude error to the orbital frame target (PD)", definition], [1, 3])
    # the rate relative to the orbital frame falls as the PD law catches the frame (0.6 -> 0.002 deg/s)
    fig = F.plot_rates(wheels)
    mag, rel = fig.axes[0].get_lines()
    assert rel.get_label() == "|omega| relative to the orbital frame"
    assert rel.get_ydata()[-1] < 0.01 < 0.05 < mag.get_ydata()[-1]  # |omega| -> the orbital rate, 0.063 deg/s
    _shows(fig, "lvlh-hold-wheels: rates", RATES, [2, 3])
    assert "relative to the orbital frame (no control)" in pointing_error(eccentric)[1]


def test_rates_in_deg_per_s_with_bdot_steady_state(bdot, free):
    from astropy import units as u

    fig = F.plot_rates(bdot, threshold=0.5 * u.deg / u.s)
    top, comps = fig.axes
    assert top.get_ylabel() == "|omega| [deg/s]" and comps.get_ylabel() == "omega [deg/s]"
    mag, *refs = top.get_lines()
    np.testing.assert_allclose(mag.get_ydata()[0], np.degrees(np.linalg.norm(bdot["omega"].values[0])))
    labels = [r.get_label() for r in refs]
    assert labels[0] == "detumble threshold = 0.5 deg/s" and labels[1].startswith("2 n: B-dot's steady state")
    assert len(comps.get_lines()) == 3
    _shows(fig, "cubesat-bdot-detumble: rates", RATES, [3, 3])  # |omega|, the threshold, 2 n
    # a scenario with a detumble threshold of its own ([sweep] detumble_rate): drawn without asking
    mc = _run("cubesat-detumble-montecarlo", '"120 s"')
    fig = F.plot_rates(mc)
    assert fig.axes[0].get_lines()[1].get_label() == "detumble threshold ([sweep] detumble_rate) = 0.5 deg/s"
    _shows(fig, "cubesat-detumble-montecarlo: rates", RATES, [3, 3])
    fig = F.plot_rates(free)  # a dimensionless problem keeps its units
    assert fig.axes[0].get_ylabel() == "|omega| [dimensionless]"
    assert fig.axes[1].get_xlabel() == "time (dimensionless)"
    _shows(fig, "paper-torque-free: rates", RATES, [1, 3])  # no reference rate without an orbit


def test_wheels_speeds_momentum_torque_and_limits(wheels):
    """The limits are drawn where the wheels come near them, else stated in the panel's title
    so that they do not flatten the data (issue 35 §2: 6000 rpm against 2000)."""
    fig = F.plot_wheels(wheels)
    speed, momentum, torque = fig.axes
    assert (speed.get_ylabel(), momentum.get_ylabel(), torque.get_ylabel()) == (
        "speed [rpm]", "momentum [N m s]", "motor torque [N m]")
    labels = [line.get_label() for line in speed.get_lines()]
    assert labels == ["wheel 1 (body +x)", "wheel 2 (body +y)", "wheel 3 (body +z)"]
    assert "max_speed +-6000 rpm (largest here 2.1e+03: off scale)" in speed.get_title()
    assert speed.get_ylim()[1] < 3000.0  # the axis keeps to the data
    np.testing.assert_allclose(speed.get_lines()[2].get_ydata()[0], 2000.0, rtol=1e-9)  # the momentum bias
    largest = np.abs(wheels["wheel_torque"].values).max()
    assert largest < F.LIMIT_SHOWN * 5e-3  # 1.7e-3 N m: the 5e-3 N m limit is stated, not drawn
    assert f"max_torque +-0.005 N m (largest here {largest:.2g}: off scale)" in torque.get_title()
    assert torque.get_ylim()[1] < 5e-3
    _shows(fig, "lvlh-hold-wheels: wheels", ["speed of each reaction wheel relative to the body; max_speed +-6000 rpm "
           "(largest here 2.1e+03: off scale)", "axial angular momentum of each reaction wheel",
           torque.get_title()], [3, 3, 3])
    # a limit the wheels come near is drawn: the speed limit halved
    import json

    near = wheels.copy()
    near.attrs["wheels"] = json.dumps([dict(w, max_speed_rad_s=2500 * 2 * np.pi / 60)
                                       for w in json.loads(wheels.attrs["wheels"])])
    fig = F.plot_wheels(near)
    assert "max_speed = +-2500 rpm" in [line.get_label() for line in fig.axes[0].get_lines()]
    assert "off scale" not in fig.axes[0].get_title()
    plt.close(fig)


def test_wheel_limits_from_the_wheels_attribute_or_an_older_files_scenario(wheels):
    """The Dataset carries the wheels' limits (``wheels``, JSON); a file written before it has
    them read from its stored scenario's TOML, which figure_data reads without importing the
    scenario package (issue 34: figure_data -> scenario.schema closed an import cycle)."""
    import ast
    import json

    from orbatt.dataset import figure_data

    stored = json.loads(wheels.attrs["wheels"])
    assert [w["max_speed_rad_s"] for w in stored] == [6000 * 2 * np.pi / 60] * 3
    assert [w["max_torque_N_m"] for w in stored] == [5e-3] * 3
    np.testing.assert_allclose(stored[2]["speed_rad_s"], 2000 * 2 * np.pi / 60, rtol=1e-15)
    speed, torque = wheel_limits(wheels)
    np.testing.assert_allclose(speed, [628.3185307179587] * 3, rtol=1e-15)
    np.testing.assert_array_equal(torque, [5e-3] * 3)
    older = wheels.copy()
    del older.attrs["wheels"]
    for got, want in zip(wheel_limits(older), (speed, torque)):
        np.testing.assert_allclose(got, want, rtol=1e-15)
    del older.attrs["scenario"]
    assert wheel_limits(older) is None
    one = wheels.copy()
    one.attrs["wheels"] = json.dumps([dict(w, max_speed_rad_s=None) for w in stored])  # no speed limit
    assert np.isnan(wheel_limits(one)[0]).all() and not np.isnan(wheel_limits(one)[1]).any()
    tree = ast.parse(Path(figure_data.__file__).read_text())
    imported = [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    imported += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    assert not [m for m in imported if "scenario" in m], imported


def test_torque_budget_and_eclipses(disturbed, bdot):
    fig = F.plot_torques(disturbed)
    (ax,) = fig.axes
    assert ax.get_yscale() == "log" and ax.get_ylabel() == "|torque| [N m]"
    labels = [line.get_label() for line in ax.get_lines()]
    # the total beneath the terms (wide, pale: magnetic does not hide under it); SRP is 0 in the
    # eclipse: gaps, said in its label (no value invented for the log axis)
    assert labels[:4] == ["total external", "drag", "gravity gradient", "magnetic"]
    dark = int(np.count_nonzero(np.linalg.norm(disturbed["torque_srp"].values, axis=-1) == 0.0))
    assert dark > 0 and labels[4] == f"srp (0 at {dark} of {disturbed.sizes['time']} samples: gaps)"
    assert np.isnan(ax.get_lines()[4].get_ydata()).sum() == dark
    assert ax.patches and "eclipse (shadow < 1)" in ax.get_legend_handles_labels()[1]
    assert len(ax.patches) == 1  # the run's one eclipse
    _shows(fig, "cubesat-3u-disturbances: torques (grey: eclipse)",
           ["torque budget: magnitude of each term (body frame)"], [5])
    fig = F.plot_torques(bdot)  # one external term: no separate total; the dipole below
    top, dip = fig.axes
    assert [line.get_label() for line in top.get_lines()] == ["gravity gradient", "control"]
    assert dip.get_ylabel() == "dipole [A m^2]"
    # the dipole reaches less than half its limit in 300 s: the limit stated, not drawn over the data
    assert "; max_dipole +-0.2 A m^2 (largest here" in dip.get_title()
    _shows(fig, "cubesat-bdot-detumble: torques", ["torque budget: magnitude of each term (body frame)",
           dip.get_title()], [2, 3])  # three components
    fig = F.plot_rates(bdot)  # no shadow variable: no shading
    assert not fig.axes[0].patches
    _shows(fig, "cubesat-bdot-detumble: rates", RATES, [2, 3])


def test_ensemble_draws_every_case(ensemble, monkeypatch):
    fig = F.plot_pointing(ensemble)
    (ax,) = fig.axes  # one panel: the per-axis angles of every case would be unreadable
    assert len(ax.get_lines()) == 3 and "3 cases, one line each" in ax.get_title()
    for e, line in enumerate(ax.get_lines()):
        np.testing.assert_allclose(line.get_ydata()[1:], np.degrees(pointing_error(ensemble.isel(case=e))[0])[1:])
    _shows(fig, "orbatt attitude propagation (gravity-gradient): pointing",
           ["attitude relative to the orbital frame (no control); 3 cases, one line each"], [3])
    monkeypatch.setattr(F, "ENSEMBLE_LINES", 2)  # more cases than lines: median and bands, said so
    fig = F.plot_rates(ensemble)
    ax = fig.axes[0]
    # |omega| and the rate relative to the orbital frame: a median line and two bands each
    assert len(ax.collections) == 4 and len(ax.get_lines()) == 2 and "median" in ax.get_title()
    _shows(fig, "orbatt attitude propagation (gravity-gradient): rates",  # no components: one panel
           ["magnitude of the body rate; 3 cases (over 2: median and bands)"], [2])
    with pytest.raises(ValueError, match="own invariant"):
        F.draw(ensemble, "drift")


def _png_names(folder):
    return sorted(p.name for p in folder.iterdir())


def test_files_named_after_the_figures_and_marked_as_orbatt(wheels, tmp_path):
    paths = write_figures(wheels, tmp_path / "figs", "hold", dpi=40)
    assert _png_names(tmp_path / "figs") == ["hold-pointing.png", "hold-rates.png", "hold-torques.png",
                                             "hold-wheels.png"]
    assert all(is_orbatt_figure(p) for p in paths)
    write_figures(wheels, tmp_path / "figs", "hold", dpi=40)  # its own figures are replaced
    other = tmp_path / "figs" / "hold-drift.png"  # a PNG orbatt did not write
    plt.imsave(other, np.zeros((4, 4)))
    assert not is_orbatt_figure(other)
    with pytest.raises(InputError, match="^--plot: .*hold-drift.png' exists and is not an orbatt figure"):
        check_figure_folder(tmp_path / "figs", "hold")


def test_symlink_is_refused_and_its_target_untouched(tmp_path, capsys, monkeypatch):
    """A link where a figure goes stops the run before it computes (exit 2); the target keeps
    its content and the link stays a link: orbatt never writes through or replaces one."""
    victim = tmp_path / "precious.txt"
    victim.write_text("keep me\n")
    (tmp_path / "figs").mkdir()
    link = tmp_path / "figs" / "paper-torque-free-rates.png"
    link.symlink_to(victim)
    monkeypatch.chdir(tmp_path)
    rc = main(["run", str(SCEN / "paper-torque-free.toml"), "-o", "r.nc", "--plot", "figs", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith("orbatt: error: --plot: ")
    assert "symbolic link" in err[0]
    assert victim.read_text() == "keep me\n" and link.is_symlink() and not (tmp_path / "r.nc").exists()


def _one_line(capsys, option):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"orbatt: error: {option}: "), err
    return err[0]


def test_plot_o_existing_file_and_unwritable_folders(free, tmp_path, capsys, monkeypatch):
    result = tmp_path / "r.nc"
    free.orbatt.to_netcdf(result)
    (tmp_path / "notes.txt").write_text("mine\n")
    monkeypatch.chdir(tmp_path)
    assert main(["plot", "r.nc", "-o", "notes.txt"]) == 2
    assert "'notes.txt' exists and is not a folder" in _one_line(capsys, "-o")
    assert (tmp_path / "notes.txt").read_text() == "mine\n"
    # a read-only folder (root writes in a mode-555 folder: /proc is read-only for everyone)
    assert main(["plot", "r.nc", "-o", "/proc/figs"]) == 2
    assert "cannot write" in _one_line(capsys, "-o")
    # --plot: refused before the run, which would take long (1e6 outputs; more are refused up front)
    text = (SCEN / "paper-torque-free.toml").read_text().replace("t_end = ", "t_end = 1e6 #")
    text = text.replace("output_step = ", "output_step = 1 #")
    (tmp_path / "long.toml").write_text(text)
    for folder, match in (("/proc/figs", "cannot write"), ("notes.txt", "exists and is not a folder")):
        assert main(["run", "long.toml", "-o", "long.nc", "--plot", folder]) == 2
        assert match in _one_line(capsys, "--plot")
    assert not (tmp_path / "long.nc").exists()


def test_plot_of_an_ensemble_file_draws_every_case(ensemble, tmp_path, capsys, monkeypatch):
    ensemble.orbatt.to_netcdf(tmp_path / "ens.nc")
    monkeypatch.chdir(tmp_path)
    assert main(["plot", "ens.nc", "-o", "figs"]) == 0
    assert _png_names(tmp_path / "figs") == ["ens-pointing.png", "ens-rates.png", "ens-torques.png"]
    assert all(is_orbatt_figure(p) for p in (tmp_path / "figs").iterdir())


def test_sweep_without_histories_says_why(tmp_path, capsys, monkeypatch):
    import xarray as xr

    ds = xr.Dataset({"integration_failed": ("case", np.zeros(3, dtype=np.int8))},
                    attrs={"sweep_format": "1", "orbatt_version": orbatt.__version__})
    ds.to_netcdf(tmp_path / "s.nc", engine="h5netcdf")
    monkeypatch.chdir(tmp_path)
    assert main(["plot", "s.nc", "-o", "figs"]) == 2
    assert "without time histories or per-case outputs" in _one_line(capsys, "file")


def test_failed_write_leaves_no_partial_figure(free, tmp_path, monkeypatch, capsys):
    """A full disk mid-write: the error names the option and the file, and nothing partial is
    left - the earlier figure of that name is unchanged, no .tmp- file remains."""
    folder = tmp_path / "figs"
    first = write_figures(free, folder, "tf", dpi=40)
    before = {p.name: p.read_bytes() for p in first}
    from matplotlib.figure import Figure

    real = Figure.savefig

    def full_disk(self, fname, *args, **kwargs):
        with open(fname, "wb") as f:
            f.write(b"\x89PNG\r\n\x1a\n half a figure")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Figure, "savefig", full_disk)
    with pytest.raises(OrbattError, match=r"^--plot: cannot write .*tf-rates.png' \(No space left on device\)"):
        write_figures(free, folder, "tf")
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    monkeypatch.setattr(Figure, "savefig", real)
    # from the command line: one line, exit 1, no result file half-written either
    monkeypatch.setattr(Figure, "savefig", full_disk)
    monkeypatch.chdir(tmp_path)
    text = (SCEN / "paper-torque-free.toml").read_text()
    (tmp_path / "s.toml").write_text(text.replace("t_end = ", "t_end = 2 #"))
    assert main(["run", "s.toml", "-o", "r.nc", "--plot", "new", "--quiet"]) == 1
    assert "No space left on device" in _one_line(capsys, "--plot")
    assert list((tmp_path / "new").iterdir()) == []

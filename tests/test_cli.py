"""The `orbatt` command driven as a user would (subprocess), and the scenario API."""
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.scenario import load_scenario

SCEN = Path(__file__).resolve().parent.parent / "scenarios"
SHORT = {  # t_end for a short CI run of each shipped scenario
    "paper-torque-free": "2", "paper-heavy-top": "2", "paper-keplerian": '"600 s"',
    "gg-stabilized-leo": '"600 s"', "molniya-tumbling": '"600 s"', "mercury-3-2": '"10 d"',
    "hyperion-chaotic": '"5 d"', "sso-j2-rebound": '"300 s"', "gg-leo-dispersion": '"600 s"',
    "iss-tle-gravity-gradient": '"600 s"', "cubesat-3u-disturbances": '"600 s"',
    "mercury-3-2-normalized": "0.7", "hyperion-chaotic-normalized": "1.5",
    "cubesat-bdot-detumble": '"600 s"', "lvlh-hold-wheels": '"600 s"', "iss-tle-disturbances": '"600 s"',
    "cubesat-detumble-montecarlo": '"600 s"', "nadir-hold-montecarlo": '"600 s"',
    "didymos-dimorphos": '"1.5 d"', "sphere-ellipsoid-equilibrium": '"1 orbits"',
    "didymos-dimorphos-montecarlo": '"1 d"', "cubesat-slew-wheels": '"60 s"', "cubesat-mission-modes": '"600 s"',
    "cubesat-fine-pointing": '"60 s"',
}


def cli(*args):
    # run outside the checkout, so that the installed package (not ./orbatt) is what runs
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=tempfile.gettempdir(), timeout=600)


def shorten(src: Path, dst_dir: Path) -> Path:
    text = src.read_text()
    text = re.sub(r"^t_end = .*$", f"t_end = {SHORT[src.stem]}", text, flags=re.M)
    dst = dst_dir / src.name
    dst.write_text(text)
    return dst


def test_every_shipped_scenario_is_tested():
    assert {p.stem for p in SCEN.glob("*.toml")} == set(SHORT)


@pytest.mark.parametrize("name", sorted(SHORT))
def test_shipped_scenario_runs_from_the_cli(name, tmp_path, capsys):
    """Every shipped scenario through the command line's own entry point, in this process (the
    commands in a process of their own: test_run_plot_and_plot_command and the cold-start tests;
    one process per scenario cost ~3 s of imports each)."""
    from orbatt.cli import main

    path = shorten(SCEN / f"{name}.toml", tmp_path)
    out = tmp_path / f"{name}.nc"
    code = main(["run", str(path), "-o", str(out), "--quiet"])
    assert code == 0, capsys.readouterr().err
    ds = orbatt.open_dataset(out)
    assert ds.attrs["scenario"] == path.read_text()
    assert ds["time"].size >= 2
    # constraints held to the integrator's tolerance (scenarios use rtol <= 1e-10)
    assert np.max(np.abs(ds["q_norm_error"].values)) < 1e-9
    qQ = ds["qQ"].values
    assert np.max(np.abs(qQ - qQ[0])) < 1e-9 * float(np.max(np.abs(ds["Q"].values)))
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    info = capsys.readouterr().out
    assert "span" in info and "q.Q" in info


def test_run_plot_and_plot_command(tmp_path):
    path = shorten(SCEN / "paper-torque-free.toml", tmp_path)
    r = cli("run", path, "-o", tmp_path / "tf.nc", "--plot", tmp_path / "figs")
    assert r.returncode == 0, r.stderr
    assert "energy" in r.stdout
    # torque-free, no orbit: the body rate and the drift of the invariants (issue 26 item 4)
    assert sorted(p.name for p in (tmp_path / "figs").glob("*.png")) == ["paper-torque-free-drift.png",
                                                                         "paper-torque-free-rates.png"]
    r = cli("plot", tmp_path / "tf.nc", "-o", tmp_path / "figs2")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (tmp_path / "figs2").glob("*.png")) == ["tf-drift.png", "tf-rates.png"]
    assert all(p.stat().st_size > 10_000 for p in (tmp_path / "figs2").glob("*.png"))


def test_scenarios_and_version():
    r = cli("scenarios")
    assert r.returncode == 0
    for name in SHORT:
        assert name in r.stdout
    r = cli("--version")
    assert r.returncode == 0 and orbatt.__version__ in r.stdout


def test_method_override(tmp_path):
    path = shorten(SCEN / "paper-torque-free.toml", tmp_path)
    r = cli("run", path, "-o", tmp_path / "a.nc", "--method", "scipy-DOP853", "--quiet")
    assert r.returncode == 0, r.stderr
    assert orbatt.open_dataset(tmp_path / "a.nc").attrs["method"] == "scipy-DOP853"


BAD = {
    "missing table": ("[potential]\nkind = \"gravity-gradient\"\n", "", r"\[potential\]"),
    "unknown key": ("\ne = 0.2\n", "\ne = 0.2\neccentricity = 0.2\n", r"\[orbit\] eccentricity: unknown key"),
    "wrong dimension": ('a = "7000 km"', 'a = "30 deg"', r"\[orbit\] a: '30 deg' has the wrong dimension"),
    "non-unit quaternion": ("q = [0.5, -0.7071067811865476, 0.0, 0.5]", "q = [1, 1, 0, 0]", r"\[initial\] q"),
    "negative inertia": ('"500 kg km2"', '"-500 kg km2"', r"\[body\] inertia"),
    "t_end <= 0": ('t_end = "2 orbits"', "t_end = \"0 s\"", r"\[integration\] t_end"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_malformed_file_exits_2_with_one_line(case, tmp_path):
    old, new, pattern = BAD[case]
    text = (SCEN / "paper-keplerian.toml").read_text()
    assert text.count(old) == 1
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(old, new))
    r = cli("run", bad, "-o", tmp_path / "x.nc")
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("orbatt: error:") and re.search(pattern, lines[0]), lines[0]
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "x.nc").exists()


def test_debug_shows_traceback(tmp_path):
    r = cli("--debug", "run", tmp_path / "missing.toml")
    assert r.returncode != 0 and "Traceback" in r.stderr


def test_info_on_missing_file(tmp_path):
    r = cli("info", tmp_path / "nope.nc")
    assert r.returncode == 2 and "does not exist" in r.stderr


def test_cli_and_api_give_identical_results(tmp_path):
    path = shorten(SCEN / "paper-keplerian.toml", tmp_path)
    r = cli("run", path, "-o", tmp_path / "k.nc", "--quiet")
    assert r.returncode == 0, r.stderr
    a = orbatt.open_dataset(tmp_path / "k.nc")
    b = load_scenario(path).run()
    for v in ("q", "Q", "omega", "energy", "position"):
        np.testing.assert_array_equal(a[v].values, b[v].values)


def test_run_twice_reuses_everything(tmp_path):
    """`.run()` twice in one process: same orbit object, no new compiled specializations."""
    import numba

    from orbatt import core

    path = shorten(SCEN / "sso-j2-rebound.toml", tmp_path)
    sc = orbatt.load_scenario(path)
    orbit = sc.orbit
    ds1 = sc.run()

    def signatures():
        out = {}
        import importlib
        import pkgutil

        for m in pkgutil.iter_modules(core.__path__):
            mod = importlib.import_module(f"orbatt.core.{m.name}")
            for name, obj in vars(mod).items():
                if isinstance(obj, numba.core.registry.CPUDispatcher):
                    out[f"{m.name}.{name}"] = len(obj.signatures)
        return out

    before = signatures()
    ds2 = sc.run()
    assert sc.orbit is orbit
    assert signatures() == before
    np.testing.assert_array_equal(ds1["q"].values, ds2["q"].values)


def test_outputs_fall_on_multiples_of_output_step():
    sc = load_scenario(SCEN / "paper-keplerian.toml")
    dt = 10.0
    assert np.array_equal(sc.times, np.arange(sc.times.size) * dt)
    assert sc.times[-1] <= sc.t_end < sc.times[-1] + dt


def test_orbital_frame_initial_state_is_aligned():
    sc = load_scenario(SCEN / "sso-j2-rebound.toml")
    p0 = sc.orbit.orbital_quaternion(np.array([0.0]))[0]
    assert orbatt.quaternion.angle_between(sc.state0.q, p0) < 1e-14
    # the body turns with the orbital frame: its rate is the frame's, ~ (0, 0, n) in O = B axes
    w_O = np.asarray(orbatt.orbital.orbital_rate(sc.orbit, 0.0)).reshape(3)
    assert np.allclose(sc.state0.omega, w_O, rtol=1e-13, atol=1e-20)
    n = 2 * np.pi / sc.orbit.period_value
    assert abs(w_O[2] / n - 1) < 3e-3 and abs(w_O[0]) < 1e-3 * n and w_O[1] == 0


def test_fixed_step_override_without_step_names_the_table(tmp_path):
    path = shorten(SCEN / "paper-torque-free.toml", tmp_path)
    r = cli("run", path, "-o", tmp_path / "s.nc", "--method", "splitting4")
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "[integration]" in lines[0] and "step" in lines[0]


def test_warnings_are_one_line(tmp_path):
    path = shorten(SCEN / "paper-keplerian.toml", tmp_path)
    r = cli("run", path, "-o", tmp_path / "k.nc", "--quiet")
    assert r.returncode == 0
    assert r.stderr.strip().startswith("orbatt: warning: periapsis") and len(r.stderr.strip().splitlines()) == 1


def test_a_reader_that_goes_away_ends_the_listing_quietly():
    """``orbatt scenarios | head -1``: the reader closed the pipe (here before the first write);
    no traceback, no error line, a non-zero exit."""
    import os

    r_fd, w_fd = os.pipe()
    os.close(r_fd)  # the reader is gone
    try:
        r = subprocess.run([sys.executable, "-m", "orbatt.cli", "scenarios"], stdout=w_fd, stderr=subprocess.PIPE,
                           text=True, cwd=tempfile.gettempdir(), timeout=120)
    finally:
        os.close(w_fd)
    assert r.stderr == "" and r.returncode != 0

"""No data loss from the `orbatt` command (issue 14 §1), driven as a user would: the output
never replaces the scenario or a file that is not an orbatt result, names cannot escape the
folder, unusable paths fail before the run, and SIGKILL or Ctrl-C during the NetCDF write
leave the earlier result or a complete new one."""
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt import dataset as D
from orbatt.cli import main

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


class Result:
    def __init__(self, returncode, stderr):
        self.returncode, self.stderr = returncode, stderr


@pytest.fixture
def cli(capsys, monkeypatch):
    """``orbatt ARGS`` in this process (the refusals come before any computation, so no
    subprocess is needed), run in ``cwd``."""
    def run(*args, cwd):
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        rc = main([str(a) for a in args])
        return Result(rc, capsys.readouterr().err)

    return run


def cli_process(*args, cwd):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=600)


def scenario(folder, name=None, t_end="2", output_step=None, file="s.toml"):
    text = (SCEN / "paper-torque-free.toml").read_text()
    text = re.sub(r"^t_end = .*$", lambda m: f"t_end = {t_end}", text, flags=re.M)
    if output_step is not None:
        text = re.sub(r"^output_step = .*$", lambda m: f"output_step = {output_step}", text, flags=re.M)
    if name is not None:
        text = re.sub(r"^name = .*$", lambda m: f"name = {name}", text, flags=re.M)
    path = folder / file
    path.write_text(text)
    return path


def assert_refused(r, what):
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"orbatt: error: {what}: "), r.stderr


# ------------------------------------------------------------------------------------------
# what -o and name may not overwrite
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["run", "sweep"])
@pytest.mark.parametrize("spelling", ["s.toml", "./s.toml", "ABS"])
def test_output_over_the_scenario_is_refused(command, spelling, tmp_path, cli):
    path = scenario(tmp_path)
    text = path.read_text()
    r = cli(command, path, "-o", path if spelling == "ABS" else spelling, cwd=tmp_path)
    assert_refused(r, "-o")
    assert "scenario file" in r.stderr
    assert path.read_text() == text


@pytest.mark.parametrize("name,match", [
    (r'"victim.toml\u0000"', "control character"), ('"../../escaped"', "path separator"),
    ('"ABS"', "path separator"), ('"sub/x"', "path separator"), ('".."', "starts with"),
])
def test_unsafe_name_is_refused_naming_name(name, match, tmp_path, cli):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    victim = work / "victim.toml"
    victim.write_text("keep me\n")
    if name == '"ABS"':
        name = '"' + str(tmp_path / "abs") + '"'
    path = scenario(work, name=name)
    for extra in ([], ["--plot", "figs"]):
        r = cli("run", path, *extra, cwd=work)
        assert_refused(r, "name")
        assert match in r.stderr
    assert victim.read_text() == "keep me\n"
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a", "b", "s.toml", "victim.toml"]


def test_plot_names_stay_in_the_plot_folder(tmp_path, cli):
    path = scenario(tmp_path, name='"../up"')
    r = cli("run", path, "-o", "r.nc", "--plot", "figs", cwd=tmp_path)
    assert_refused(r, "name")
    assert not (tmp_path / "figs").exists() and not list(tmp_path.parent.glob("up-*.png"))


def test_existing_file_that_is_not_a_result_is_refused(tmp_path, cli):
    path = scenario(tmp_path)
    other = tmp_path / "notes.nc"
    other.write_text("my notes\n")
    for command in ("run", "sweep"):
        r = cli(command, path, "-o", other, cwd=tmp_path)
        assert_refused(r, "-o")
        assert "not an orbatt result" in r.stderr
    assert other.read_text() == "my notes\n"
    # the default output NAME.nc is checked the same way, naming name
    (tmp_path / "paper-torque-free.nc").write_text("not mine\n")
    r = cli("run", path, cwd=tmp_path)
    assert_refused(r, "name")
    assert (tmp_path / "paper-torque-free.nc").read_text() == "not mine\n"


def test_earlier_result_is_overwritten(tmp_path, cli):
    path = scenario(tmp_path)
    out = tmp_path / "r.nc"
    assert cli("run", path, "-o", out, "--quiet", cwd=tmp_path).returncode == 0
    first = orbatt.open_dataset(out, load=True).attrs["date_created"]
    r = cli("run", path, "-o", out, "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert orbatt.open_dataset(out, load=True).attrs["date_created"] >= first
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp-")]


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_unusable_output_fails_before_the_run(command, tmp_path, cli):
    """The scenario would run for minutes: the refusal comes at once."""
    path = scenario(tmp_path, t_end="1e6", output_step="1")  # long (more outputs are refused up front)
    cases = [("missing/r.nc", "does not exist"), (".", "is a folder"), (str(tmp_path), "is a folder")]
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        cases.append(("ro/r.nc", "cannot write"))
    else:
        cases.append(("/proc/r.nc", "cannot write"))
    for out, match in cases:
        t0 = time.monotonic()
        r = cli(command, path, "-o", out, cwd=tmp_path)
        assert_refused(r, "-o")
        assert match in r.stderr
        assert time.monotonic() - t0 < 60


# ------------------------------------------------------------------------------------------
# kills during the NetCDF write
# ------------------------------------------------------------------------------------------
def _good_result(folder):
    """A small earlier result at folder/r.nc (written in this process), and its bytes."""
    out = folder / "r.nc"
    D.write_netcdf(orbatt.load_scenario(scenario(folder, file="small.toml")).run(), out)
    return out, out.read_bytes()


#: a child ``orbatt run`` whose result write blocks right before the rename of its complete
#: temporary file (the window the atomic write protects), after touching ``argv[1]``, until
#: ``argv[1] + ".go"`` exists
HELD_WRITE = """
import os, sys, time
marker = sys.argv.pop(1)
real = os.replace
def held(src, dst, *a, **k):
    if os.path.basename(str(src)).startswith('.tmp-'):
        open(marker, 'w').close()
        while not os.path.exists(marker + '.go'):
            time.sleep(0.01)
    return real(src, dst, *a, **k)
os.replace = held
from orbatt.cli import main
sys.exit(main())
"""


def _signal_during_write(folder, out, sig):
    """Start a run writing a result over ``out``, held inside its write (:data:`HELD_WRITE`);
    send ``sig`` once it is there. Returns (process, whether the write was reached)."""
    big = scenario(folder, t_end="80", output_step="0.005", file="big.toml")
    marker = folder / "inside-the-write"
    proc = subprocess.Popen([sys.executable, "-c", HELD_WRITE, str(marker), "run", str(big), "-o", str(out),
                             "--quiet"], cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "ORBATT_COLD_START": "compile"})
    deadline = time.monotonic() + 300
    while proc.poll() is None and time.monotonic() < deadline and not marker.exists():
        time.sleep(0.01)
    caught = marker.exists() and proc.poll() is None
    if caught:
        assert any(p.name.startswith(f".tmp-{out.name}.") for p in folder.iterdir())
        proc.send_signal(sig)
    else:
        proc.kill()
    return proc, caught


def test_sigkill_during_the_write_keeps_the_earlier_result(tmp_path):
    out, before = _good_result(tmp_path)
    proc, caught = _signal_during_write(tmp_path, out, signal.SIGKILL)
    _, err = proc.communicate(timeout=120)
    assert caught, err
    assert proc.returncode == -signal.SIGKILL
    assert out.read_bytes() == before  # untouched, readable
    assert orbatt.open_dataset(out, load=True)["time"].size == 101


def test_ctrl_c_during_the_write_leaves_a_complete_file(tmp_path):
    out, before = _good_result(tmp_path)
    proc, caught = _signal_during_write(tmp_path, out, signal.SIGINT)
    time.sleep(0.5)  # the interrupt is in while the write is held
    (tmp_path / "inside-the-write.go").touch()
    _, err = proc.communicate(timeout=120)  # no deadlock
    assert caught, err
    assert proc.returncode in (0, 130), err
    assert "finishing the write" in err
    ds = D.open_dataset(out, load=True)  # the write was finished: the new result, complete
    assert out.read_bytes() != before
    assert ds["time"].size == 16001
    assert np.isfinite(ds["energy"].values).all()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp-")]

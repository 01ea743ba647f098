"""The `orbatt` command on hostile input (issue 14 §2, §3): exit 2 for bad input, 1 for a
failed run, at most two lines on stderr and no traceback unless --debug; Ctrl-C on a sweep
(a real SIGINT to the process group, as a terminal sends it) prints orbatt's message only."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr
from not_utf8_files import not_utf8_files

SCEN = Path(__file__).resolve().parent.parent / "scenarios"
FREE = (SCEN / "paper-torque-free.toml").read_text()
KEP = (SCEN / "paper-keplerian.toml").read_text()


def cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=tempfile.gettempdir(), timeout=timeout)


def assert_one_line_error(r, code):
    assert r.returncode == code, (r.returncode, r.stderr)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip() and "warning:" not in ln]
    assert 1 <= len(lines) <= 2, r.stderr
    assert "Traceback" not in r.stderr and lines[-1].startswith("orbatt: error: "), r.stderr


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """A small orbatt result file."""
    d = tmp_path_factory.mktemp("res")
    scen = d / "tf.toml"
    scen.write_text(FREE.replace("t_end = 20", "t_end = 2"))
    out = d / "tf.nc"
    r = cli("run", scen, "-o", out, "--quiet")
    assert r.returncode == 0, r.stderr
    return out


SCENARIO_BYTES = {
    **not_utf8_files(FREE),
    "nested 50000 deep": FREE.replace("inertia = [1.25, 1.0, 0.75]",
                                      "inertia = " + "[" * 50_000 + "]" * 50_000).encode(),
    "method list": FREE.replace('method = "dop853"', "method = []").encode(),
    "nan t_end": KEP.replace('t_end = "2 orbits"', 't_end = "nan s"').encode(),
    "1e9 orbits": KEP.replace('t_end = "2 orbits"', 't_end = "1e9 orbits"').replace('"10 s"', '"1 s"').encode(),
    "deg deg": KEP.replace('i = "30 deg"', 'i = "98.2 deg deg"').encode(),
    "1 2 orbits": KEP.replace('t_end = "2 orbits"', 't_end = "1 2 orbits"').encode(),
    "rtol 1e10": KEP.replace("rtol = 1e-12", "rtol = 1e10").encode(),
    "omega 1e6 rad/s": KEP.replace("Q = [0.3, -0.848528, 0.141421, -1.5]",
                                   'omega = ["1e6 rad/s", "0 rad/s", "0 rad/s"]').encode(),
    "orbit inside the earth": KEP.replace('a = "7000 km"', 'a = "3000 km"').encode(),
}


@pytest.mark.parametrize("kind", sorted(SCENARIO_BYTES))
def test_run_refuses_bad_scenario_files_in_one_line(tmp_path, kind):
    p = tmp_path / "s.toml"
    p.write_bytes(SCENARIO_BYTES[kind])
    t0 = time.perf_counter()
    r = cli("run", p, "-o", tmp_path / "out.nc")
    assert_one_line_error(r, 2)
    assert time.perf_counter() - t0 < 60  # refused up front, not after a run
    assert str(p) in r.stderr
    assert not (tmp_path / "out.nc").exists()


def test_run_on_a_netcdf_result_says_it_is_not_a_scenario(tmp_path, result):
    r = cli("run", result, "-o", tmp_path / "x.nc")
    assert_one_line_error(r, 2)
    assert "is not a TOML scenario" in r.stderr


def test_debug_shows_the_traceback(tmp_path):
    p = tmp_path / "s.toml"
    p.write_bytes(SCENARIO_BYTES["method list"])
    r = cli("--debug", "run", p, "-o", tmp_path / "out.nc")
    assert r.returncode != 0 and "Traceback" in r.stderr and "ScenarioError" in r.stderr


def test_a_run_that_cannot_continue_fails_in_seconds_with_exit_1(tmp_path):
    """e = 0.9999999: a periapsis 0.7 m from the centre; the run stops at once (step size
    underflow) with exit 1 and one line, instead of running for minutes."""
    p = tmp_path / "ecc.toml"
    p.write_text(KEP.replace("\ne = 0.2\n", "\ne = 0.9999999\n"))
    t0 = time.perf_counter()
    r = cli("run", p, "-o", tmp_path / "ecc.nc", timeout=120)
    assert_one_line_error(r, 1)
    assert time.perf_counter() - t0 < 60


def _foreign_files(d: Path, result: Path):
    files = {}
    files["toml"] = d / "a.toml"
    files["toml"].write_text(FREE)
    files["text"] = d / "notes.txt"
    files["text"].write_text("hello\n")
    files["hdf5"] = d / "plain.h5"
    with h5py.File(files["hdf5"], "w") as f:
        f["x"] = np.arange(3.0)
    ds = xr.Dataset({"tas": ("time", np.arange(4.0), {"units": "K"})},
                    coords={"time": ("time", np.arange(4.0), {"units": "days since 2000-01-01"})},
                    attrs={"Conventions": "CF-1.8"})
    files["cf file"] = d / "cf.nc"
    ds.to_netcdf(files["cf file"], engine="netcdf4")
    files["netcdf3"] = d / "v3.nc"
    ds.to_netcdf(files["netcdf3"], format="NETCDF3_64BIT", engine="scipy")
    data = result.read_bytes()
    files["truncated"] = d / "truncated.nc"
    files["truncated"].write_bytes(data[: len(data) // 2])
    flipped = bytearray(data)
    with h5py.File(result, "r") as f:  # flip bytes inside the first data chunk of q (checksummed)
        info = f["q"].id.get_chunk_info(0)
    k = info.byte_offset + info.size // 2
    flipped[k:k + 8] = bytes(b ^ 0xFF for b in flipped[k:k + 8])
    files["byte-flipped"] = d / "flipped.nc"
    files["byte-flipped"].write_bytes(bytes(flipped))
    files["missing"] = d / "missing.nc"
    return files


FOREIGN = ["toml", "text", "hdf5", "cf file", "netcdf3", "truncated", "byte-flipped", "missing"]


@pytest.mark.parametrize("kind", FOREIGN)
@pytest.mark.parametrize("command", ["info", "plot"])
def test_info_and_plot_refuse_files_that_are_not_orbatt_results(tmp_path, result, command, kind):
    f = _foreign_files(tmp_path, result)[kind]
    args = (command, f) if command == "info" else (command, f, "-o", tmp_path / "figs")
    r = cli(*args)
    assert_one_line_error(r, 2)
    assert f.name in r.stderr


def test_open_dataset_says_a_file_was_not_written_by_orbatt(tmp_path, result):
    import orbatt

    files = _foreign_files(tmp_path, result)
    with pytest.raises(orbatt.InputError, match="not written by orbatt"):
        orbatt.open_dataset(files["cf file"])
    with pytest.raises(orbatt.InputError, match="netCDF-3 file, not written by orbatt"):
        orbatt.open_dataset(files["netcdf3"])
    with pytest.raises(orbatt.InputError, match="damaged"):
        orbatt.open_dataset(files["byte-flipped"], load=True)
    assert orbatt.open_dataset(result, load=True)["time"].size == 101


def test_plot_of_a_sweep_draws_its_outputs(tmp_path):
    text = (SCEN / "gg-leo-dispersion.toml").read_text()
    text = text.replace("samples = 2000", "samples = 2").replace('t_end = "300 orbits"', 't_end = "600 s"')
    p = tmp_path / "sw.toml"
    p.write_text(text)
    r = cli("sweep", p, "-o", tmp_path / "sw.nc", "--scheduler", "synchronous", "--quiet")
    assert r.returncode == 0, r.stderr
    assert cli("info", tmp_path / "sw.nc").returncode == 0
    r = cli("plot", tmp_path / "sw.nc", "-o", tmp_path / "figs")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == ["sw-distributions.png", "sw-scatter.png"]


def test_ctrl_c_on_a_sweep_prints_no_worker_tracebacks(tmp_path):
    text = (SCEN / "gg-leo-dispersion.toml").read_text()
    text = (text.replace("samples = 2000", "samples = 40").replace("chunk_size = 100", "chunk_size = 2")
            .replace('t_end = "300 orbits"', 't_end = "30 orbits"'))
    p = tmp_path / "sw.toml"
    p.write_text(text)
    proc = subprocess.Popen([sys.executable, "-m", "orbatt.cli", "sweep", p, "-o", tmp_path / "sw.nc",
                             "--workers", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, cwd=tmp_path)
    err = bytearray()
    started = threading.Event()

    def read():  # progress lines end with \r: read bytes as they come
        while chunk := os.read(proc.stderr.fileno(), 4096):
            err.extend(chunk)
            if b"chunks" in err:
                started.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        assert started.wait(240), err.decode()  # the cluster is up and the tasks are submitted
        time.sleep(1.0)
        os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C sends: the whole process group
        proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    reader.join(10)
    text = err.decode()
    lines = [ln for ln in text.replace("\r", "\n").splitlines() if ln.strip() and not ln.startswith("orbatt sweep:")]
    assert proc.returncode == 130, text
    assert "Traceback" not in text and "distributed" not in text, text
    assert len(lines) <= 2 and "interrupted" in lines[-1], text

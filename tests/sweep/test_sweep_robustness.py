"""Sweeps that go wrong (issue 14 §5): waiting for workers says what it waits for and stops
at the given timeout; a run that fails before any part leaves no parts folder behind; parts
carry the sweep's fingerprint and a part of another sweep is refused; temporaries of killed
merges are removed by the next run. Real schedulers here listen on 127.0.0.1 only."""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from orbatt.cli import main
from orbatt.errors import InputError
from orbatt.scenario import Scenario, parse
from orbatt.sweep import Sweep, run_sweep
from orbatt.sweep.parts import PART_FINGERPRINT, read_parts

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")


def text(samples=8):
    t = (SCEN / "gg-leo-dispersion.toml").read_text()
    t = re.sub(r"^t_end = .*$", 't_end = "240 s"', t, flags=re.M)
    return re.sub(r"^samples = .*$", f"samples = {samples}", t, flags=re.M)


def sweep(seed=None):
    return Sweep(Scenario(parse(text(), "s.toml")), seed=seed)


def dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


@pytest.fixture
def scheduler():
    """A dask.distributed scheduler on 127.0.0.1 with one (thread) worker: its address."""
    distributed = pytest.importorskip("dask.distributed")
    import logging

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", host="127.0.0.1",
                                  dashboard_address=None, silence_logs=logging.ERROR) as lc:
        yield lc.scheduler_address


def test_waiting_for_workers_says_so_and_stops_at_the_timeout(scheduler, tmp_path):
    said = []
    with pytest.raises(InputError, match=r"3 workers did not connect .* within 0.5 s \(1 connected\)"):
        run_sweep(sweep(), tmp_path / "s.nc", scheduler=scheduler, workers=3, worker_timeout=0.5, notify=said.append)
    assert said == [f"orbatt sweep: waiting up to 0.5 s for 3 workers at {scheduler}: 1 connected "
                    "(start them with 'dask worker ADDRESS')"]
    assert os.listdir(tmp_path) == []   # no parts folder: the next run is not refused as interrupted


def test_cli_wait_is_one_line_then_one_error(scheduler, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(text())
    rc = main(["sweep", "s.toml", "-o", "s.nc", "--scheduler", scheduler, "--workers", "2", "--worker-timeout", "0.5"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert err[0] == f"orbatt sweep: waiting up to 0.5 s for 2 workers at {scheduler}: 1 connected " \
                     "(start them with 'dask worker ADDRESS')"
    assert len(err) == 2 and err[1].startswith("orbatt: error: workers: 2 workers did not connect"), err
    assert sorted(os.listdir(tmp_path)) == ["s.toml"]


def test_enough_workers_no_message_and_bad_timeout(scheduler, tmp_path):
    said = []
    ds = run_sweep(sweep(), tmp_path / "s.nc", scheduler=scheduler, workers=1, notify=said.append, chunk_size=4)
    assert said == [] and ds.sizes["case"] == 8
    ds.close()
    for bad in (0, -1, float("nan"), float("inf"), True, "10"):
        with pytest.raises(InputError, match="worker_timeout"):
            run_sweep(sweep(), tmp_path / "t.nc", worker_timeout=bad)


def test_failed_connection_leaves_nothing_and_the_next_run_starts(tmp_path, monkeypatch):
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        with pytest.raises(InputError, match="cannot connect"):
            run_sweep(sweep(), tmp_path / "s.nc", scheduler="tcp://127.0.0.1:9")
    assert os.listdir(tmp_path) == []
    ds = run_sweep(sweep(), tmp_path / "s.nc", scheduler="synchronous", chunk_size=4)   # not refused
    assert ds.sizes["case"] == 8
    ds.close()


def test_a_failure_after_a_part_keeps_the_parts(tmp_path, monkeypatch):
    import orbatt.sweep.run as R

    real, calls = R.run_chunk, []

    def second_fails(job, *args, **kwargs):
        calls.append(job["start"])
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job, *args, **kwargs)

    monkeypatch.setattr(R, "run_chunk", second_fails)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep(), tmp_path / "s.nc", scheduler="synchronous", chunk_size=4)
    assert sorted(os.listdir(tmp_path / "s.nc.parts")) == ["cases-000000000-000000003.nc", "sweep.json"]


@pytest.fixture
def two_sweeps(tmp_path):
    """The same 8 cases drawn with seeds 1 and 2, each run to completion keeping its parts."""
    out = {}
    for seed in (1, 2):
        path = tmp_path / f"seed{seed}.nc"
        run_sweep(sweep(seed), path, scheduler="synchronous", chunk_size=4, keep_parts=True).close()
        out[seed] = path
    return out


def test_parts_carry_the_fingerprint_and_a_foreign_part_is_refused(two_sweeps, tmp_path):
    import xarray as xr

    a, b = two_sweeps[1], two_sweeps[2]
    pa, pb = Path(f"{a}.parts"), Path(f"{b}.parts")
    part = "cases-000000004-000000007.nc"
    with xr.open_dataset(pa / part) as d:
        assert d.attrs[PART_FINGERPRINT] == sweep(1).fingerprint
    assert sweep(1).fingerprint != sweep(2).fingerprint
    before = a.read_bytes()
    shutil.copy(pb / part, pa / part)   # a part of another sweep (other seed, same range)
    with pytest.raises(InputError) as info:
        run_sweep(sweep(1), a, scheduler="synchronous", resume=True)
    msg = str(info.value)
    assert "\n" not in msg and part in msg and "another sweep" in msg and sweep(2).fingerprint in msg
    assert a.read_bytes() == before and (pa / part).exists()   # nothing merged, nothing deleted
    with pytest.raises(InputError, match="another sweep"):   # the merge checks too
        read_parts(pa, 8, lazy=False, fingerprint=sweep(1).fingerprint)
    # the same folder with its own part again resumes (here: only the merge)
    shutil.copy(pb / part, tmp_path / "foreign.nc")
    os.unlink(pa / part)
    ds = run_sweep(sweep(1), a, scheduler="synchronous", resume=True, chunk_size=4)
    assert ds.sizes["case"] == 8 and ds.attrs["sweep_fingerprint"] == sweep(1).fingerprint
    ref = run_sweep(sweep(1), scheduler="synchronous")
    np.testing.assert_array_equal(ds["q_final"].values, ref["q_final"].values)
    ds.close()


def test_stale_merge_temporaries_are_removed_by_the_next_run(tmp_path):
    pid = dead_pid()
    stale = [f".tmp-s.nc-{pid}", f".tmp-s.nc.{pid}.0123abcd"]
    kept = [f".tmp-s.nc.{os.getpid()}.0123abcd", f".tmp-other.nc-{pid}"]
    for n in stale + kept:
        (tmp_path / n).write_bytes(b"partial merge")
    run_sweep(sweep(), tmp_path / "s.nc", scheduler="synchronous", chunk_size=4).close()
    assert sorted(os.listdir(tmp_path)) == sorted(kept + ["s.nc"])

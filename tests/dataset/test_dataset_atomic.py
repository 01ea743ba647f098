"""Atomic writes everywhere (issue 14 §1, §5): appends go into a copy renamed over the file,
so a failure or a SIGKILL during an append leaves the earlier file; the temporary files of
killed writes (``.tmp-<name>.<pid>.<hex>``) are removed by the next write once their process
is gone, and nothing else is touched."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import orbatt
from orbatt import dataset as D
from orbatt.dataset import atomic, netcdf
from dataset_support import assert_bitwise_identical


def _dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _names(folder):
    return sorted(p.name for p in folder.iterdir())


def test_stale_temporaries_of_dead_processes_are_removed_and_only_those(free_ds, tmp_path):
    dead, alive = _dead_pid(), os.getpid()
    assert not atomic.pid_alive(dead) and atomic.pid_alive(alive)
    stale = [f".tmp-r.nc.{dead}.0123abcd", f".tmp-r.nc-{dead}"]           # new and sweep-merge form
    kept = [f".tmp-r.nc.{alive}.0123abcd",                                 # a write in progress
            f".tmp-other.nc.{dead}.0123abcd",                              # another target
            f".tmp-r.nc.{dead}.notahex0", f"r.nc.{dead}.0123abcd", ".tmp-r.nc"]  # not orbatt's pattern
    for n in stale + kept:
        (tmp_path / n).write_bytes(b"partial")
    (tmp_path / f".tmp-r.nc.{dead}.fedcba98").mkdir()                      # a Zarr temporary (folder)
    (tmp_path / f".tmp-r.nc.{dead}.fedcba98" / "x").write_text("x")
    D.write_netcdf(free_ds, tmp_path / "r.nc")
    assert _names(tmp_path) == sorted(kept + ["r.nc"])
    assert_bitwise_identical(free_ds, D.open_dataset(tmp_path / "r.nc", load=True))


def test_check_output_path_does_not_remove_anything(free_ds, tmp_path):
    (tmp_path / f".tmp-r.nc.{_dead_pid()}.0123abcd").write_bytes(b"partial")
    D.check_output_path(tmp_path / "r.nc")
    assert len(_names(tmp_path)) == 1


def test_failed_append_keeps_the_earlier_file(free_ds, tmp_path, monkeypatch):
    out = tmp_path / "r.nc"
    D.write_netcdf(free_ds.isel(time=slice(0, 100)), out)
    before = out.read_bytes()
    real = netcdf._append

    def half_then_fail(ds, path, engine, name=None):
        assert os.path.basename(path).startswith(".tmp-r.nc.")  # into a copy, not in place
        real(ds, path, engine, name)
        raise OSError("disk full")

    monkeypatch.setattr(netcdf, "_append", half_then_fail)
    with pytest.raises(OSError, match="disk full"):
        D.write_netcdf(free_ds.isel(time=slice(99, None)), out, append=True)
    assert out.read_bytes() == before
    assert _names(tmp_path) == ["r.nc"]


def test_append_refusal_names_the_file_not_the_copy(free_ds, tmp_path):
    out = tmp_path / "r.nc"
    D.write_netcdf(free_ds, out)
    with pytest.raises(orbatt.InputError, match=r"r\.nc") as info:
        D.write_netcdf(free_ds.isel(time=slice(0, 5)), out, append=True)
    assert ".tmp-" not in str(info.value)
    assert _names(tmp_path) == ["r.nc"]


CHILD = textwrap.dedent("""
    import os, sys, time, numpy as np, orbatt
    from orbatt import dataset as D
    from orbatt.trajectory import Trajectory
    out, n = sys.argv[1], int(sys.argv[2])
    rng = np.random.default_rng(1)
    t = np.arange(n, dtype=float)
    q = rng.normal(size=(n, 4)); q /= np.linalg.norm(q, axis=1)[:, None]
    tr = Trajectory(body=orbatt.RigidBody([1.25, 1.0, 0.75]), potential=orbatt.TorqueFree(), t=t, q=q,
                    Q=rng.normal(size=(n, 4)), inertia=np.array([1.25, 1.0, 0.75]), method="dop853",
                    settings={}, stats={}, complete=True)
    ds = D.to_dataset(tr)
    D.write_netcdf(ds.isel(time=slice(0, 50)), out)
    print("first", flush=True)
    real = os.replace
    def held(src, dst, *a, **k):  # hold the append right before its rename: the parent kills it there
        if os.path.basename(str(src)).startswith(".tmp-"):
            print("inside", flush=True)
            while True:
                time.sleep(0.01)
        return real(src, dst, *a, **k)
    os.replace = held
    D.write_netcdf(ds.isel(time=slice(49, None)), out, append=True)
    print("done", flush=True)
""")


def test_sigkill_during_an_append_leaves_the_earlier_data(tmp_path):
    out = tmp_path / "r.nc"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(out), "3000"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "first", proc.stderr.read()
    first = out.read_bytes()
    assert proc.stdout.readline().strip() == "inside", proc.stderr.read()  # blocks until the child is there
    assert any(n.startswith(".tmp-r.nc.") for n in _names(tmp_path))
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    assert out.read_bytes() == first
    ds = D.open_dataset(out, load=True)
    np.testing.assert_array_equal(ds["time"].values, np.arange(50.0))
    assert any(n.startswith(".tmp-r.nc.") for n in _names(tmp_path))   # left by the kill ...
    ds.close()
    D.write_netcdf(ds, out)                                             # ... removed by the next write
    assert _names(tmp_path) == ["r.nc"]

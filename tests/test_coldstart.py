"""First runs on an empty compile cache (orbatt.coldstart): the interpreted kernels give the
compiled kernels' bits, the warm-up writes its stamp, and the pieces of the switch to the
compiled run."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from orbatt import coldstart
from orbatt.dataset import open_dataset
from orbatt.shipped import shipped_file

#: shipped scenarios whose interpreted run takes a few seconds (the others are checked by hand:
#: the closing note of the cold-start work lists them)
INTERPRETED = ["paper-torque-free", "paper-keplerian", "paper-heavy-top"]


def _env(**changes):
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", coldstart.ENV_MODE)}
    env.update({k: v for k, v in changes.items() if v is not None})
    return env


def _same_values(a, b):
    names = sorted(set(a.variables) | set(b.variables))
    assert sorted(a.variables) == sorted(b.variables)
    for v in names:
        x, y = np.asarray(a[v].values), np.asarray(b[v].values)
        assert x.dtype == y.dtype and x.shape == y.shape, v
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), f"{v} differs"


def test_import_orbatt_is_light():
    code = "import orbatt, sys; print(sorted(m for m in ('numba', 'numpy', 'astropy', 'xarray') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("name", INTERPRETED)
def test_interpreted_kernels_give_the_compiled_bits(name, tmp_path, shipped_outputs):
    out = tmp_path / f"{name}.nc"
    r = subprocess.run(["orbatt", "run", name, "-o", str(out), "--quiet"], capture_output=True, text=True,
                       env=_env(NUMBA_DISABLE_JIT="1"), timeout=300)
    assert r.returncode == 0, r.stderr
    with open_dataset(out) as a, open_dataset(shipped_outputs[name]) as b:
        _same_values(a, b)


def test_interpreted_closed_form_gives_the_compiled_bits(tmp_path):
    outs = {}
    for mode, env in (("interpreted", _env(NUMBA_DISABLE_JIT="1")), ("compiled", _env(ORBATT_COLD_START="compile"))):
        outs[mode] = tmp_path / f"{mode}.nc"
        r = subprocess.run(["orbatt", "run", "paper-torque-free", "--method", "exact", "-o", str(outs[mode]),
                            "--quiet"], capture_output=True, text=True, env=env, timeout=300)
        assert r.returncode == 0, r.stderr
    with open_dataset(outs["interpreted"]) as a, open_dataset(outs["compiled"]) as b:
        _same_values(a, b)


def test_first_run_interprets_and_starts_the_warm_up(tmp_path, shipped_outputs):
    cache = tmp_path / "numba-cache"
    out = tmp_path / "tf.nc"
    r = subprocess.run(["orbatt", "run", "paper-torque-free", "-o", str(out)], capture_output=True, text=True,
                       env=_env(NUMBA_CACHE_DIR=str(cache)), timeout=300)
    lock = next((cache / "orbatt").glob("warm-*.lock"), None)
    try:
        assert r.returncode == 0, r.stderr
        assert "first run of this kind of scenario" in r.stderr
        assert lock is not None, "no warm-up was started"
        with open_dataset(out) as a, open_dataset(shipped_outputs["paper-torque-free"]) as b:
            _same_values(a, b)
    finally:  # the warm-up compiles into the temporary cache for a minute: stop it
        if lock is not None:
            try:
                os.killpg(int(lock.read_text()), signal.SIGTERM)
            except (OSError, ValueError):
                pass


def _same_orbatt(env):
    """``env`` with ``PYTHONPATH`` leading to the orbatt this process imported (an installed
    copy and a source tree have different fingerprints)."""
    import orbatt

    root = str(Path(orbatt.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def _plan(scenario, cwd, **env):
    """``plan(scenario)`` in a fresh process (no numba imported) importing the same orbatt as
    this process."""
    code = ("import sys; from orbatt import coldstart; c = coldstart.plan(sys.argv[1]); "
            "print('none' if c is None else c.key)")
    r = subprocess.run([sys.executable, "-c", code, scenario], capture_output=True, text=True,
                       env=_same_orbatt(_env(**env)), check=True, cwd=cwd)
    return r.stdout.strip()


def _fingerprint(cwd):
    """:func:`coldstart.fingerprint` as the processes of :func:`_plan` see it."""
    code = "import json; from orbatt import coldstart; print(json.dumps(coldstart.fingerprint()))"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_same_orbatt(_env()),
                       check=True, cwd=cwd)
    return json.loads(r.stdout)


def test_plan_interprets_only_a_cold_first_run(tmp_path):
    cache = str(tmp_path / "cache")
    key = _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=cache)
    assert key == coldstart.kernel_key("paper-keplerian")
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=cache, ORBATT_COLD_START="compile") == "none"
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=cache, NUMBA_DISABLE_JIT="1") == "none"
    assert _plan(str(tmp_path / "missing.toml"), tmp_path, NUMBA_CACHE_DIR=cache) == "none"  # the run reports it
    stamp = tmp_path / "cache" / "orbatt" / f"warm-{key}.json"
    stamp.parent.mkdir(parents=True, exist_ok=True)  # (plan made it: it checks a stamp can be written)
    fp = _fingerprint(tmp_path)
    stamp.write_text(json.dumps(fp))
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=cache) == "none"
    stamp.write_text(json.dumps({**fp, "numba": "0.0"}))  # another numba: cold again
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=cache) == key


def test_kernel_key_follows_the_model_not_the_numbers(tmp_path, shipped_outputs):
    kep = coldstart.kernel_key("paper-keplerian")
    assert kep == coldstart.kernel_key("paper-keplerian", "dop853")
    assert kep != coldstart.kernel_key("paper-keplerian", "splitting4")
    assert kep != coldstart.kernel_key("paper-torque-free")
    text = shipped_file("paper-keplerian").read_text()
    other = tmp_path / "other.toml"
    other.write_text(text.replace('"400 kg km2"', '"410 kg km2"'))
    assert coldstart.kernel_key(other) == kep
    assert coldstart.kernel_key(tmp_path / "nothing.toml") is None


def test_warm_up_writes_the_stamp_and_the_run_switches(tmp_path):
    from orbatt.progress import ProgressInfo

    cold = coldstart.ColdStart("paper-torque-free", None, coldstart.kernel_key("paper-torque-free"), tmp_path)
    seen = []
    report = cold.progress(seen.append)
    info = ProgressInfo(0.5, 1.0, 2.0, 10, 0.1)
    assert report(info) is None and seen == [info] and not cold.is_warm()
    nice = os.nice(0)
    assert coldstart.warm_up("paper-torque-free", "", cold.stamp) == 0
    assert os.nice(0) == nice  # the warm-up process lowers its own priority, never its caller's
    assert cold.is_warm() and json.loads(cold.stamp.read_text()) == coldstart.fingerprint()
    assert report(info) is False and cold.switched and seen == [info] and cold.projected is None


def test_rerun_compiled_runs_the_same_command(tmp_path, shipped_outputs):
    cold = coldstart.ColdStart("paper-torque-free", None, "k", tmp_path)
    out = tmp_path / "tf.nc"
    assert cold.rerun_compiled(["run", "paper-torque-free", "-o", str(out), "--quiet"]) == 0
    with open_dataset(out) as a, open_dataset(shipped_outputs["paper-torque-free"]) as b:
        _same_values(a, b)


def test_no_interpreted_run_where_no_stamp_can_be_written(tmp_path):
    """A stamp folder that cannot be made (here: below a plain file; a read-only installation
    and home alike): the run compiles in its own process instead of interpreting to its end."""
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=str(blocker / "cache")) == "none"
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=str(tmp_path / "fresh")) != "none"
    assert not coldstart._writable(blocker / "cache") and coldstart._writable(tmp_path / "made" / "here")


def test_a_warm_up_that_cannot_start_says_so(tmp_path, monkeypatch):
    key = coldstart.kernel_key("paper-torque-free")
    cold = coldstart.ColdStart("paper-torque-free", None, key, tmp_path)

    def refuse(*args, **kwargs):
        raise OSError("no processes left")

    monkeypatch.setattr(coldstart.subprocess, "Popen", refuse)
    assert cold.start_warm_up() is False and cold.process is None
    # a warm-up of this kind already running (its pid in the lock): nothing started, and it will switch
    cold.lock.write_text(str(os.getppid()))
    assert cold.start_warm_up() is True and cold.process is None


def test_shipped_names_and_paths_mean_one_file(tmp_path):
    from orbatt.shipped import scenario_file, shipped_folder

    f = shipped_folder() / "paper-keplerian.toml"
    assert f.is_file()
    for name in ("paper-keplerian", "paper-keplerian.toml", "PAPER-KEPLERIAN", "./paper-keplerian"):
        assert shipped_file(name) == f or name.startswith("./"), name
        assert scenario_file(name) == f, name
    assert coldstart.kernel_key("paper-keplerian") == coldstart.kernel_key(f)
    for name in ("no-such-scenario", "", "elsewhere/paper-keplerian", str(tmp_path / "paper-keplerian.toml")):
        assert shipped_file(name) is None and scenario_file(name) is None, name
    mine = tmp_path / "mine.toml"
    mine.write_text(f.read_text())
    assert scenario_file(mine) == mine


def _wait_for_stamp(folder: Path, timeout=300.0):
    """The warm stamp the warm-up writes in ``folder`` (None if none within ``timeout`` s, or once
    every warm-up there has ended without one)."""
    import time

    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        stamp = next(folder.glob("warm-*.json"), None)
        if stamp is not None:
            return stamp
        locks = list(folder.glob("warm-*.lock"))
        if locks and not any(coldstart._alive(int(x.read_text() or 0)) for x in locks if x.read_text().strip()):
            return next(folder.glob("warm-*.json"), None)
        time.sleep(0.5)
    return None


def test_first_run_from_a_clone_root_warms_the_installed_package(tmp_path, shipped_outputs):
    """Issue 26: from a clone's root, the warm-up used to import the source tree ``./orbatt``
    (``python -m`` puts the current folder first on sys.path) and wrote a stamp that never
    matched the installed package: every run interpreted. Here ``./orbatt`` is a decoy that
    cannot be imported; the warm-up must compile the installed package and the second run
    must be compiled."""
    root = tmp_path / "clone"
    (root / "orbatt").mkdir(parents=True)
    (root / "orbatt" / "__init__.py").write_text("raise ImportError('the source tree beside the run was imported')\n")
    cache = tmp_path / "cache"
    env = _env(NUMBA_CACHE_DIR=str(cache))
    env.pop("PYTHONSAFEPATH", None)  # (conftest.py) as a user's shell: the warm-up itself must not import ./orbatt
    first = subprocess.run(["orbatt", "run", "paper-torque-free", "-o", "one.nc"], capture_output=True, text=True,
                           env=env, cwd=root, timeout=300)
    assert first.returncode == 0, first.stderr
    assert "first run of this kind of scenario" in first.stderr
    stamp = _wait_for_stamp(cache / "orbatt")
    assert stamp is not None, "the warm-up wrote no stamp"
    assert json.loads(stamp.read_text()) == coldstart.fingerprint()  # the installed package's, this process's
    second = subprocess.run(["orbatt", "run", "paper-torque-free", "-o", "two.nc"], capture_output=True, text=True,
                            env=env, cwd=root, timeout=300)
    assert second.returncode == 0, second.stderr
    assert "first run" not in second.stderr and "warning" not in second.stderr
    for name in ("one.nc", "two.nc"):
        with open_dataset(root / name) as a, open_dataset(shipped_outputs["paper-torque-free"]) as b:
            _same_values(a, b)


def test_warm_up_refuses_another_package(tmp_path):
    stamp = tmp_path / "warm-k.json"
    assert coldstart.warm_up("paper-torque-free", "", stamp, package=str(tmp_path)) == 3
    assert not stamp.exists()


def test_a_compiled_run_marks_its_kind_warm(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    key = _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=str(cache))
    assert key != "none"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    assert coldstart.mark_warm("paper-keplerian") is True  # after ORBATT_COLD_START=compile orbatt run (cli)
    assert coldstart.mark_warm("paper-keplerian") is False  # warm already
    assert _plan("paper-keplerian", tmp_path, NUMBA_CACHE_DIR=str(cache)) == "none"
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")
    assert coldstart.mark_warm("paper-torque-free") is False  # an interpreted run compiled nothing


def test_a_long_interpreted_run_waits_for_the_compiler(tmp_path):
    from orbatt.progress import ProgressInfo

    cold = coldstart.ColdStart("paper-torque-free", None, "k", tmp_path)
    report = cold.progress(None)
    assert report(ProgressInfo(0.5, 5.0, 10.0, 100, 1.0)) is None  # too early to project
    assert report(ProgressInfo(0.5, 5.0, 10.0, 100, coldstart.PROJECT_AFTER_S)) is None  # projected 4 s: go on
    assert not cold.switched and cold.projected is None
    f = coldstart.PROJECT_AFTER_S / (2 * coldstart.LONG_RUN_S)
    assert report(ProgressInfo(f, 1.0, 10.0, 100, coldstart.PROJECT_AFTER_S)) is False  # projected 2x too long
    assert cold.switched and cold.projected == pytest.approx(2 * coldstart.LONG_RUN_S)
    cold = coldstart.ColdStart("paper-torque-free", None, "k", tmp_path)
    assert cold.progress(None)(ProgressInfo(0.0, 0.0, 10.0, 0, 10.0)) is False  # no progress at all
    assert cold.projected == float("inf")


KERNEL = """
from orbatt.core._jit import jit

@jit
def twice(x):
    return 2.0 * x
"""


def test_an_unreadable_cache_entry_is_recompiled(tmp_path):
    """A truncated ``.nbi``/``.nbc`` (a full disk, a killed writer) used to make every later
    run fail until the user deleted it: now it is removed, recompiled, and said once."""
    (tmp_path / "kernel_mod.py").write_text(KERNEL)
    env = _same_orbatt(_env(NUMBA_CACHE_DIR=str(tmp_path / "cache")))
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), env["PYTHONPATH"]])
    code = "import kernel_mod; print(kernel_mod.twice(1.5))"

    def run():
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path,
                           timeout=300)
        assert r.returncode == 0, r.stderr
        return r.stdout.strip(), r.stderr

    assert run() == ("3.0", "")
    files = list((tmp_path / "cache").rglob("*.nb[ic]"))
    assert {f.suffix for f in files} == {".nbi", ".nbc"}
    for f in files:
        f.write_bytes(f.read_bytes()[:7])
    out, err = run()
    assert out == "3.0" and "CacheWarning" in err and "unreadable" in err and err.count("CacheWarning") == 1
    assert run() == ("3.0", "")  # written again, readable

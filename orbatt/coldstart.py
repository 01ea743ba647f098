"""First runs on an empty compile cache: the kernels interpreted while they compile in the
background.

numba compiles orbatt's kernels on their first use and keeps the machine code in its disk
cache; compiling the step loop and the kernels a run needs takes 15-30 s, ~100x what a small
study then takes. So the first ``orbatt run`` of a kind of scenario (its method, potential,
orbit provider, torques and control: :func:`kernel_key`) on a fresh install does not wait for
the compiler:

1. before numba is imported, ``orbatt run`` looks for this kind's **warm stamp**
   (:func:`stamp_folder`): a file the background warm-up writes once the kernels are compiled
   and cached for the current sources, orbatt, numba, Python and machine (:func:`fingerprint`);
2. without one it sets ``NUMBA_DISABLE_JIT=1`` (the kernels run as plain Python: the same source,
   the same IEEE arithmetic and libm calls, hence **the same bits**, tested on the shipped
   scenarios; ~1000x slower per step) and starts the **warm-up**, a detached process that runs
   the scenario compiled over its first outputs only, which fills numba's cache, and writes the
   stamp (one warm-up per kind at a time: a lock file holds its pid);
3. the interpreted run goes on until it is done or the stamp appears: then it stops and the same
   command runs again, compiled, from the cache (:meth:`ColdStart.rerun_compiled`). A run whose
   projected interpreted time (measured over its first 2 s) exceeds :data:`LONG_RUN_S` stops
   too and waits for the compiler in the foreground, saying so (a disturbed day-long study
   would interpret for minutes). A run that fails in the interpreted kernels (an exception
   Python raises where compiled code gives inf or NaN) also waits for the warm-up and runs
   again compiled, so errors are the compiled code's.

The child processes (warm-up, compiled rerun) run ``python -P``: started from a clone's root,
they import the installed orbatt the parent runs, not the source tree ``./orbatt`` beside it
(the warm-up checks the folder it imported and writes no stamp for another one). A compiled
``orbatt run`` (``ORBATT_COLD_START=compile``) writes its kind's stamp too (:func:`mark_warm`),
so the next plain run does not interpret. An unreadable (truncated, corrupted) entry of numba's
cache is removed and recompiled, with a warning (:mod:`orbatt.core._jit`).

Measured on the shipped ``paper-keplerian`` with an empty cache (2-core machine): 23.6 s
compiled before, 1.8 s interpreted, the same file contents bit for bit
(``benchmarks/run.py``'s first-run rows).

Where no stamp can be written (the stamp folder cannot be made or written: a read-only
installation and home) or no warm-up can start, the run compiles in a process of its own
instead: an interpreted run with no warm-up behind it would never switch, and a long study
would run ~1000x slower to its end.

``ORBATT_COLD_START=compile`` turns this off (wait for the compiler, as with the Python API,
which always compiles); a process that has already imported numba is never switched.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from .cachedir import cache_folder
from .fast_paths import ENABLED as FAST_PATHS
from .shipped import scenario_file

__all__ = ["ENV_MODE", "LONG_RUN_S", "PROJECT_AFTER_S", "ColdStart", "plan", "kernel_key", "fingerprint",
           "stamp_folder", "warm_up", "mark_warm", "write_stamp"]

#: the environment variable that turns interpreted first runs off (``compile``)
ENV_MODE = "ORBATT_COLD_START"
#: an interpreted first run projected to take longer than this (s) stops and waits for the
#: compiler instead (compiling a kind's kernels takes 20-60 s on a 2-core machine)
LONG_RUN_S = 20.0
#: the interpreted run's projection starts after this much wall time (s)
PROJECT_AFTER_S = 2.0
_PACKAGE = Path(__file__).resolve().parent


def stamp_folder() -> Path:
    """Where the warm stamps and locks live: orbatt's cache folder
    (:func:`orbatt.cachedir.cache_folder`, beside numba's cache of the kernels)."""
    return cache_folder()


_FINGERPRINT = None


def fingerprint() -> dict:
    """What numba's cache of the kernels depends on: the package's source files (path,
    modification time, size: numba's own test), the versions of orbatt, numba and Python, and
    the machine. Computed once per process (a warm run asks twice: before and after)."""
    global _FINGERPRINT
    if _FINGERPRINT is None:
        _FINGERPRINT = _compute_fingerprint()
    return dict(_FINGERPRINT)


def _compute_fingerprint() -> dict:
    from importlib.metadata import PackageNotFoundError, version

    h = hashlib.sha1()
    for f in sorted(_PACKAGE.rglob("*.py")):
        st = f.stat()
        h.update(f"{f.relative_to(_PACKAGE)}:{st.st_mtime_ns}:{st.st_size};".encode())
    try:
        nb_version = version("numba")
    except PackageNotFoundError:  # pragma: no cover - numba is a dependency
        nb_version = "?"
    from .version import __version__

    return {"sources": h.hexdigest(), "orbatt": __version__, "numba": nb_version,
            "python": sys.version, "machine": f"{platform.machine()} {platform.processor()}"}


def kernel_key(scenario, method=None) -> str | None:
    """The kind of ``scenario`` as far as compiled kernels go: its method and the shape of its
    model (potential kind, orbit provider, torque and control tables, wheels), read from the
    TOML without validating it; None when the file cannot be read (the run then reports it)."""
    import tomllib

    f = scenario_file(scenario)
    if f is None:
        return None
    try:
        doc = tomllib.loads(f.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return None

    def table(name):
        return doc[name] if isinstance(doc.get(name), dict) else {}

    m = method or table("integration").get("method", "dop853")
    shape = {"tables": sorted(k for k, v in doc.items() if isinstance(v, (dict, list))),
             "potential": table("potential").get("kind"), "orbit": table("orbit").get("provider"),
             "wheels": bool(table("body").get("wheels"))}
    digest = hashlib.sha1(json.dumps(shape, sort_keys=True, default=str).encode()).hexdigest()[:12]
    return f"{''.join(c if c.isalnum() or c in '-_' else '_' for c in str(m))[:40]}-{digest}"


def _python() -> list[str]:
    """The interpreter command of the child processes (warm-up, compiled rerun): ``-P`` keeps
    the current folder off ``sys.path``, so a child started from a clone's root imports the
    installed orbatt the parent runs, not the source tree ``./orbatt`` beside it (whose
    fingerprint never matches the installed one: every later run would interpret)."""
    return [sys.executable, "-P"]


def _compiled_env() -> dict:
    """This process's environment for a child that runs compiled: no ``NUMBA_DISABLE_JIT``,
    and ``ORBATT_COLD_START=compile`` (it never starts a warm-up of its own)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"}
    env[ENV_MODE] = "compile"
    return env


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. no permission: it exists
        return True
    return True


class ColdStart:
    """The first run of one kind of scenario on an empty compile cache (:func:`plan` makes
    one): the warm-up process, the progress wrapper that stops the interpreted run once the
    warm-up is done, and the compiled rerun."""

    def __init__(self, scenario, method, key, folder):
        self.scenario, self.method, self.key, self.folder = scenario, method, key, Path(folder)
        self.stamp = self.folder / f"warm-{key}.json"
        self.lock = self.folder / f"warm-{key}.lock"
        self.process = None
        self.switched = False
        self.projected = None  # the projected interpreted time (s) when that stopped the run
        self._fingerprint = None  # this process's sources do not change while it runs

    def is_warm(self) -> bool:
        """The warm stamp is there and matches :func:`fingerprint`."""
        if not self.stamp.is_file():
            return False
        if self._fingerprint is None:
            self._fingerprint = fingerprint()
        try:
            return json.loads(self.stamp.read_text()) == self._fingerprint
        except (OSError, ValueError):
            return False

    def start_warm_up(self) -> bool:
        """Start the detached warm-up (:func:`warm_up`) unless one for this kind is running;
        False when none runs (it could not be started): the caller then runs compiled, since
        an interpreted run with no warm-up behind it would never switch."""
        try:
            pid = int(self.lock.read_text())
            if pid != os.getpid() and _alive(pid):
                return True
        except (OSError, ValueError):
            pass
        cmd = [*_python(), "-m", "orbatt.coldstart", str(self.scenario), str(self.method or ""),
               str(self.stamp), str(_PACKAGE)]
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            self.process = subprocess.Popen(cmd, env=_compiled_env(), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                            stderr=subprocess.DEVNULL, start_new_session=True)
            self.lock.write_text(str(self.process.pid))
        except OSError:  # no warm-up (or no lock: then a warm-up that cannot write its stamp)
            if self.process is not None:
                self.process.kill()
            self.process = None
            return False
        return True

    def progress(self, inner):
        """A progress callback for the interpreted run: ``inner`` (None or a callback), and
        False (stop) once the warm-up's stamp is there, or once the run's projected
        interpreted time exceeds :data:`LONG_RUN_S` (measured over its first
        :data:`PROJECT_AFTER_S` seconds: a long study then waits for the compiler in the
        foreground, :attr:`projected` set, instead of interpreting for minutes)."""
        def report(info):
            if self.is_warm():
                self.switched = True
                return False
            if info.wall_time_s >= PROJECT_AFTER_S:
                projected = info.wall_time_s / info.fraction if info.fraction > 0 else math.inf
                if projected > LONG_RUN_S:
                    self.switched, self.projected = True, projected
                    return False
            return inner(info) if inner is not None else None

        return report

    def wait_for_warm_up(self, timeout=600.0, stream=None):
        """Wait until the warm-up process has ended (at most ``timeout`` seconds); with a
        ``stream``, say so there and how long the compiler took."""
        if self.process is None:
            return
        t0 = time.monotonic()
        if stream is not None:
            stream.write("orbatt: compiling the kernels of this kind of scenario (once; typically 20-60 s) ...\n")
            stream.flush()
        try:
            self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            pass
        if stream is not None:
            stream.write(f"orbatt: compiled in {time.monotonic() - t0:.0f} s; running compiled\n")
            stream.flush()

    def rerun_compiled(self, argv, stream=None) -> int:
        """Run ``orbatt argv`` again in a new process with the compiled kernels (after the
        warm-up has filled the cache; ``stream``: see :meth:`wait_for_warm_up`); its exit code."""
        self.wait_for_warm_up(stream=stream)
        return subprocess.call([*_python(), "-m", "orbatt.cli", *argv], env=_compiled_env())


def mark_warm(scenario, method=None) -> bool:
    """After a compiled ``orbatt run`` of ``scenario`` (``ORBATT_COLD_START=compile``, or a
    first run that could not interpret): write this kind's warm stamp, since the run compiled
    and cached every kernel of its kind, so the next plain run of the kind does not interpret
    again. True when a stamp was written; False where none is needed or none can be written."""
    if os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0"):
        return False  # nothing was compiled
    key = kernel_key(scenario, method)
    if key is None:
        return False
    cold = ColdStart(scenario, method, key, stamp_folder())
    if cold.is_warm() or not _writable(cold.folder):
        return False
    write_stamp(cold.stamp)
    return True


def write_stamp(stamp) -> None:
    """Write the warm ``stamp`` (this process's :func:`fingerprint`) atomically."""
    stamp = Path(stamp)
    tmp = stamp.with_name(f".{stamp.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(json.dumps(fingerprint()))
        os.replace(tmp, stamp)
    except OSError:
        tmp.unlink(missing_ok=True)


def plan(scenario, method=None) -> ColdStart | None:
    """For ``orbatt run SCENARIO [--method METHOD]``: a :class:`ColdStart` when this kind of
    scenario has no warm stamp (the caller must then set ``NUMBA_DISABLE_JIT=1`` before numba is
    imported and start the warm-up), or None to run compiled (a warm cache, numba already
    imported, ``ORBATT_COLD_START=compile``, or a file the run will refuse anyway)."""
    if (os.environ.get(ENV_MODE, "interpret").lower() == "compile" or "numba" in sys.modules
            or not FAST_PATHS):  # ORBATT_FAST_PATHS=0 (orbatt.fast_paths): every run compiles
        return None
    if os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0"):
        return None  # the user asked for interpreted kernels: nothing to warm up
    key = kernel_key(scenario, method)
    if key is None:
        return None
    cold = ColdStart(scenario, method, key, stamp_folder())
    if cold.is_warm() or not _writable(cold.folder):
        return None  # warm; or no stamp can ever be written there: every run would interpret
    return cold


def _writable(folder: Path) -> bool:
    """Whether ``folder`` exists or can be made, and files can be written in it (a read-only
    installation and home, a full or read-only file system: no warm stamp can be written, so
    first runs compile in their own process, as with ``ORBATT_COLD_START=compile``)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(folder, os.W_OK | os.X_OK)


def warm_up(scenario, method, stamp, package=None) -> int:
    """The warm-up process: run ``scenario`` compiled over its first outputs (which compiles
    and caches every kernel a full run calls), then write the warm ``stamp``; 0 on success.

    ``package``: the folder of the orbatt the parent run imported; a warm-up that imported
    another one (a source tree on ``sys.path``) compiles the wrong files, so it writes no
    stamp and returns 3."""
    if package is not None and Path(package).resolve() != _PACKAGE:
        return 3
    from .scenario import load_scenario

    sc = load_scenario(scenario)
    sc.times = sc.times[:min(3, sc.times.size)]
    try:
        sc.run_content(method=method or None)
    except Exception:  # noqa: BLE001 - a failing run still compiled its kernels
        pass
    stamp = Path(stamp)
    write_stamp(stamp)
    try:
        lock = stamp.with_suffix(".lock")
        if lock.read_text().strip() == str(os.getpid()):
            lock.unlink()
    except OSError:
        pass
    return 0


if __name__ == "__main__":  # pragma: no cover - the warm-up process (ColdStart.start_warm_up)
    try:  # behind the interpreted run it speeds up for (the process only: warm_up called in
        os.nice(10)  # a test or a notebook must not lower its caller's priority for good)
    except (AttributeError, OSError):  # no nice() on this platform
        pass
    sys.exit(warm_up(*sys.argv[1:5]))

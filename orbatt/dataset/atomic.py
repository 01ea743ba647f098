"""Files replaced atomically, and the temporary files that a killed write leaves behind.

Every file orbatt writes for a user (NetCDF results, sweep merges and parts, AEM) is written to
a temporary file beside its target, named ``.tmp-<name>.<pid>.<hex>`` (:func:`temp_path`),
flushed to disk and renamed over the target (:func:`replacing`): the target is the earlier file
or the complete new one, never a partial one. A SIGKILL leaves the temporary file; the next
write of the same target removes it (:func:`remove_stale_temporaries`) once the process named by
``<pid>`` is gone. Only files of that pattern, for that target, in its folder are touched; the
check of the PID is made on this machine, so two machines must not write the same file in a
shared folder at the same time.
"""
from __future__ import annotations

import os
import re
import secrets
import shutil
import stat
from contextlib import contextmanager
from pathlib import Path

__all__ = ["TEMP_PREFIX", "temp_path", "pid_alive", "stale_temporaries", "remove_stale_temporaries", "replacing"]

#: name prefix of the temporary file written beside the target before the rename
TEMP_PREFIX = ".tmp-"


def temp_path(path) -> Path:
    """A new temporary name beside ``path``: ``.tmp-<name>.<pid>.<8 hex digits>``."""
    p = Path(os.path.abspath(os.fspath(path)))
    return p.with_name(f"{TEMP_PREFIX}{p.name}.{os.getpid()}.{secrets.token_hex(4)}")


def pid_alive(pid) -> bool:
    """True when a process ``pid`` exists on this machine (also one of another user)."""
    pid = int(pid)
    if pid <= 0:
        return False
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except OSError:  # pragma: no cover - e.g. a platform without signal 0: keep the file
        return True
    return True


def _pattern(name):
    n = re.escape(name)
    # .tmp-<name>.<pid>.<hex> (this module); .tmp-<name>-<pid> (sweep merges and parts before issue 14)
    return re.compile(rf"^{re.escape(TEMP_PREFIX)}{n}(?:\.(\d+)\.[0-9a-f]{{8}}|-(\d+))$")


def stale_temporaries(path):
    """The temporary files (or folders: Zarr) of earlier writes of ``path`` whose process is
    gone: ``[Path]`` in ``path``'s folder, of the pattern of :func:`temp_path`."""
    p = Path(os.path.abspath(os.fspath(path)))
    pat = _pattern(p.name)
    out = []
    try:
        entries = list(os.scandir(p.parent))
    except OSError:
        return out
    for e in entries:
        m = pat.match(e.name)
        if m and not pid_alive(m.group(1) or m.group(2)):
            out.append(Path(e.path))
    return sorted(out)


def remove_stale_temporaries(path):
    """Remove :func:`stale_temporaries` of ``path``; returns those removed (a file that cannot be
    removed is left and not returned)."""
    gone = []
    for t in stale_temporaries(path):
        try:
            if t.is_dir() and not t.is_symlink():
                shutil.rmtree(t)
            else:
                t.unlink()
            gone.append(t)
        except OSError:
            pass
    return gone


def _fsync(path):
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _remove(path):
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        try:
            path.unlink()
        except OSError:
            pass


@contextmanager
def replacing(path, *, folder=False):
    """Write ``path`` atomically: yield a temporary path beside it to write, then rename it over
    ``path``.

    Before: the stale temporaries of ``path`` are removed (:func:`remove_stale_temporaries`).
    On success: the temporary file is flushed to disk, given the mode of the file it replaces
    (a new file gets the umask's default) and renamed over ``path``; the folder is flushed.
    On any exception (KeyboardInterrupt included) the temporary file is removed.

    Parameters
    ----------
    path : str or os.PathLike
    folder : bool
        The result is a folder (a Zarr store): the temporary path is not created here, and an
        existing folder at ``path`` is removed just before the rename (that step is not atomic).

    Yields
    ------
    pathlib.Path
        The temporary path (``.tmp-<name>.<pid>.<hex>``; a new empty file unless ``folder``).
    """
    target = Path(os.path.abspath(os.fspath(path)))
    remove_stale_temporaries(target)
    tmp = temp_path(target)
    if not folder:
        os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
    try:
        yield tmp
        if not folder:
            _fsync(tmp)
            try:
                os.chmod(tmp, stat.S_IMODE(os.stat(target).st_mode))
            except FileNotFoundError:
                pass
        elif target.is_dir() and not target.is_symlink():
            shutil.rmtree(target)
        os.replace(tmp, target)
    except BaseException:
        _remove(tmp)
        raise
    _fsync(target.parent)  # the rename itself to disk

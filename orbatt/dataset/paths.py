"""Output paths of results, checked before a run computes anything: file names derived from a
scenario's ``name`` (:func:`file_name`), and the output file itself (:func:`check_output_path`:
a writable folder, and no file there but an earlier orbatt result, :func:`is_orbatt_result`;
never a symbolic link: :func:`check_replaceable`, shared with :func:`write_netcdf`).
"""
from __future__ import annotations

import os
import secrets
from pathlib import Path

from ..errors import InputError
from .atomic import TEMP_PREFIX
from .netcdf import check_replaceable, is_orbatt_result

__all__ = ["file_name", "is_orbatt_result", "check_output_path", "check_replaceable"]

_NAME_MAX = 255  # bytes in one file name (Linux, macOS, Windows)
#: what a temporary name (``.tmp-<name>.<pid>.<8 hex>``, :func:`orbatt.dataset.atomic.temp_path`)
#: adds to a file's name, at most (a pid of 10 digits)
_DECORATION = len(".tmp-") + 1 + 10 + 1 + 8
#: the longest output file name: its temporary must fit too
_NAME_ROOM = _NAME_MAX - _DECORATION


def file_name(name, suffix="", *, what="name"):
    """``name + suffix`` as a file name in the current folder, or an error naming ``what``.

    Names are refused, not rewritten: a name with a path separator (``/``, ``\\``), a NUL or
    other control character, a leading ``.`` (``.``, ``..``, hidden and ``.tmp-`` files), an
    absolute path, or more than 255 bytes with the suffix would write somewhere other than a
    plain file of that name.

    Parameters
    ----------
    name : str
        E.g. a scenario's ``name``.
    suffix : str
        Appended (``".nc"``, ``"-state.png"``).
    what : str
        The field named in the error message.

    Raises
    ------
    InputError
        The name is not a plain file name.
    """
    if not isinstance(name, str) or not name.strip():
        raise InputError(f"{what}: {name!r} cannot name a file; give a plain name such as 'my-run'")
    bad = [c for c in name if ord(c) < 32 or ord(c) == 127]
    if bad:
        raise InputError(f"{what}: {name!r} contains the control character {bad[0]!r}; output files are named "
                         "after it: give a plain name such as 'my-run'")
    seps = {"/", "\\", os.sep} | ({os.altsep} if os.altsep else set())
    if any(c in name for c in seps) or os.path.isabs(name):
        raise InputError(f"{what}: {name!r} contains a path separator; output files are named after it and "
                         "must stay in the output folder: give a plain name such as 'my-run' (and -o for the path)")
    if name.startswith("."):
        raise InputError(f"{what}: {name!r} starts with '.'; output files are named after it: give a plain name "
                         "such as 'my-run'")
    out = name + suffix
    if len(os.fsencode(out)) > _NAME_ROOM:
        raise InputError(f"{what}: {name[:40]!r}... is too long for a file name ({len(os.fsencode(out))} bytes "
                         f"with {suffix!r}, at most {_NAME_ROOM}: the file is written through a temporary "
                         f"name {_DECORATION} bytes longer, at most {_NAME_MAX}); give a shorter name")
    return out


def _check_length(p, what, s, extra=""):
    """Refuse ``p`` when its name, or that of its temporary (:func:`orbatt.dataset.atomic.temp_path`)
    or of ``extra`` appended (a sweep's ``OUTPUT.parts``), is longer than the folder's file
    system takes, or the whole path longer than its paths."""
    folder = p.parent
    try:
        name_max = os.pathconf(folder, "PC_NAME_MAX")
        path_max = os.pathconf(folder, "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):
        name_max, path_max = _NAME_MAX, 4096
    n = len(os.fsencode(p.name + extra)) + _DECORATION
    if n > name_max:
        raise InputError(f"{what}: the file name {p.name[:40]!r}... is too long ({n - _DECORATION} bytes"
                         f"{' with ' + repr(extra) if extra else ''}; its temporary takes {_DECORATION} more, "
                         f"at most {name_max} here); give a shorter name")
    full = len(os.fsencode(os.path.abspath(s))) + len(os.fsencode(extra)) + _DECORATION
    if full >= path_max:
        raise InputError(f"{what}: {s[:40]!r}... is too long a path ({full - _DECORATION} bytes, at most "
                         f"{path_max - 1 - _DECORATION} here); give a shorter one")


def check_output_path(path, *, what="-o", zarr=False, ours=None):
    """Refuse an output path that cannot or must not be written, before any computation.

    Parameters
    ----------
    path : str or os.PathLike
        Where a result will be written (atomically, :func:`write_netcdf`).
    what : str
        The option or field named in error messages (``"-o"``, ``"name"``).
    zarr : bool
        Accept an existing Zarr store (a folder) that orbatt wrote at ``path``.
    ours : callable, optional
        ``ours(path) -> bool``: whether an existing file is one orbatt may replace (default
        :func:`is_orbatt_result`; :func:`orbatt.dataset.aem.is_orbatt_aem` for AEM files).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    InputError
        ``path`` is a folder or a symbolic link; its folder is missing, not a folder, or not
        writable (tested by creating and removing a ``.tmp-`` file there); or ``path`` exists
        and is not an orbatt result (``ours``): only earlier orbatt results are overwritten
        (:func:`check_replaceable`, which :func:`write_netcdf` and ``ds.orbatt.to_netcdf`` apply
        too).
    """
    s = os.fspath(path)
    bad = [c for c in s if ord(c) < 32 or ord(c) == 127]
    if bad:
        raise InputError(f"{what}: {s!r} contains the control character {bad[0]!r}; give a plain path")
    p = Path(s)
    if not s or s.endswith(("/", os.sep)):
        raise InputError(f"{what}: {s!r} is not a file name; give a file such as 'result.nc'")
    if p.is_symlink():
        check_replaceable(p, what=what, zarr=zarr, ours=ours)
    if p.is_dir() and not (zarr and p.suffix == ".zarr"):
        raise InputError(f"{what}: {s!r} is a folder; give a file in it such as '{p / 'result.nc'}'")
    folder = p.parent
    if not folder.is_dir():
        state = "is not a folder" if folder.exists() else "does not exist"
        raise InputError(f"{what}: the folder {str(folder)!r} of {s!r} {state}; create it or give another path")
    _check_length(p, what, s, ".parts" if zarr else "")
    probe = folder / f"{TEMP_PREFIX}probe.{os.getpid()}.{secrets.token_hex(4)}"
    try:
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"{what}: cannot write in the folder {str(folder)!r} of {s!r} "
                         f"({exc.strerror or exc}); give a writable folder") from None
    check_replaceable(p, what=what, zarr=zarr, ours=ours)
    return p

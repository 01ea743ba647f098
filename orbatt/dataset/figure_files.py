"""The figure files of a result: ``FOLDER/<name>-<figure>.png`` (issue 26 §4, §6), checked
before a run (:func:`check_figure_folder`) and written atomically (:func:`write_figures`).

Safety, as for NetCDF results (:mod:`orbatt.dataset.atomic`, :mod:`orbatt.dataset.paths`):

- each PNG is written to a ``.tmp-`` file beside its target and renamed over it, so a failed
  write (a full disk, an exception inside matplotlib) leaves the earlier figure or none, never
  a truncated one;
- only orbatt's own figures are replaced: a PNG whose ``Software`` text chunk starts with
  ``orbatt`` (:func:`is_orbatt_figure`, written into every figure); any other file of a
  figure's name is refused, and so is a **symbolic link** of that name (never followed, never
  replaced: the run stops with exit 2 before computing, and the link's target is untouched);
- the folder (or, when it is to be created, its nearest existing parent) must be a writable
  folder, tested by creating and removing a ``.tmp-`` file, before any computation.
"""
from __future__ import annotations

import os
import secrets
import sys
from pathlib import Path

from ..errors import InputError, OrbattError
from .atomic import TEMP_PREFIX, replacing
from .figure_data import FIGURES, choose_figures
from .paths import file_name

__all__ = ["SOFTWARE", "figure_path_names", "is_orbatt_figure", "check_figure_folder", "write_figures",
           "figure_notes"]

#: the ``Software`` text chunk of every figure orbatt writes starts with this
SOFTWARE = "orbatt"
_PNG = b"\x89PNG\r\n\x1a\n"


def figure_path_names(stem, figures=FIGURES, *, what="name"):
    """``{figure: "<stem>-<figure>.png"}``; ``stem`` must be a plain file name
    (:func:`orbatt.dataset.file_name`, errors naming ``what``)."""
    return {f: file_name(stem, f"-{f}.png", what=what) for f in figures}


def is_orbatt_figure(path) -> bool:
    """True when ``path`` is a regular file (not a link) holding a PNG whose ``Software`` text
    chunk starts with ``orbatt`` (reads the chunks before the image data only)."""
    p = Path(path)
    if p.is_symlink() or not p.is_file():
        return False
    try:
        with open(p, "rb") as f:
            if f.read(8) != _PNG:
                return False
            for _ in range(64):
                head = f.read(8)
                if len(head) < 8:
                    return False
                size, kind = int.from_bytes(head[:4], "big"), head[4:]
                if kind in (b"IDAT", b"IEND") or size > 1 << 20:
                    return False
                body = f.read(size)
                f.read(4)  # CRC
                if kind == b"tEXt" and b"\0" in body:
                    key, value = body.split(b"\0", 1)
                    if key == b"Software" and value.startswith(SOFTWARE.encode()):
                        return True
    except OSError:
        return False
    return False


def _probe(folder, what, shown):
    probe = Path(folder) / f"{TEMP_PREFIX}probe.{os.getpid()}.{secrets.token_hex(4)}"
    try:
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"{what}: cannot write in the folder {str(folder)!r} of {shown!r} "
                         f"({exc.strerror or exc}); give a writable folder for the figures") from None


def check_figure_folder(folder, stem, *, what="--plot", figures=FIGURES):
    """Refuse a figure folder that cannot or must not be written, before any computation.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder of the figures (created by :func:`write_figures` when missing).
    stem : str
        The figures' name stem (``<stem>-<figure>.png``; a plain file name, else an error
        naming ``name``).
    what : str
        The option named in errors (``"--plot"``, ``"-o"``).
    figures : sequence of str
        The figures that may be written (default: every one of :data:`FIGURES`, as before a run,
        when the content is not known yet).

    Returns
    -------
    dict
        ``{figure: pathlib.Path}``.

    Raises
    ------
    InputError
        ``folder`` exists and is not a folder; its nearest existing parent is not a folder or
        not writable; or a figure's path is a symbolic link or a file that is not an orbatt
        figure.
    """
    s = os.fspath(folder)
    bad = [c for c in s if ord(c) < 32 or ord(c) == 127]
    if not s or bad:
        detail = f"contains the control character {bad[0]!r}" if bad else "is empty"
        raise InputError(f"{what}: {s!r} {detail}; give a folder for the figures such as 'figs'")
    names = figure_path_names(stem, figures)
    p = Path(s)
    if p.exists() and not p.is_dir():
        raise InputError(f"{what}: {s!r} exists and is not a folder; the figures go into a folder "
                         f"({stem}-<figure>.png files): give a folder such as 'figs'")
    parent = p
    while not parent.exists() and not parent.is_symlink():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{what}: {str(parent)!r} in {s!r} is not a folder; give a folder for the figures")
    _probe(parent, what, s)
    out = {}
    for figure, name in names.items():
        path = p / name
        if path.is_symlink():
            raise InputError(f"{what}: {str(path)!r} is a symbolic link; orbatt never writes through or replaces "
                             "a link: remove it or give another folder")
        if path.exists() and not is_orbatt_figure(path):
            raise InputError(f"{what}: {str(path)!r} exists and is not an orbatt figure; orbatt overwrites only its "
                             "own figures: remove that file or give another folder")
        out[figure] = path
    return out


def figure_notes(ds):
    """The figures left out of an ensemble, each with why (one line each)."""
    if "case" in ds.dims and "drift" not in choose_figures(ds) and choose_figures(ds.isel(case=0)).count("drift"):
        return [f"drift: not drawn for the {ds.sizes['case']} cases together (each has its own invariant); "
                "draw one in Python: ds.isel(case=k).orbatt.plot_drift()"]
    return []


def write_figures(ds, folder, stem, *, what="--plot", figures=None, time="auto", dpi=120, draw_figure=None):
    """Write the figures of ``ds`` as ``folder/<stem>-<figure>.png``, atomically.

    Parameters
    ----------
    ds : xarray.Dataset
        A run or an ensemble (a ``case`` dimension: every case drawn).
    folder : str or os.PathLike
        Created (with its parents) when missing.
    stem : str
        The name stem (a plain file name).
    what : str
        The option named in errors.
    figures : sequence of str, optional
        Default: :func:`orbatt.dataset.figure_data.choose_figures`.
    time : {"auto", "utc", "orbits", "time"}
        The time axis.
    dpi : int
    draw_figure : callable, optional
        ``draw_figure(ds, figure) -> matplotlib Figure`` (default: the run figures of
        :mod:`orbatt.dataset.figures`; a sweep's: :func:`orbatt.dataset.sweep_figures.draw_sweep`).

    Returns
    -------
    list of pathlib.Path
        The files written, in :data:`FIGURES` order.

    Raises
    ------
    InputError
        :func:`check_figure_folder` (checked again here: the folder may have changed since).
    OrbattError
        A figure could not be written (e.g. a full disk); the message names ``what``, the file
        and the cause. No partial file is left; figures written before it stay.
    """
    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:  # files only: no window system needed
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..version import __version__
    from .figures import draw

    chosen = tuple(choose_figures(ds) if figures is None else figures)
    paths = check_figure_folder(folder, stem, what=what, figures=chosen)
    try:
        Path(folder).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OrbattError(f"{what}: cannot create the folder {os.fspath(folder)!r} ({exc.strerror or exc}); "
                          "give a writable folder") from None
    written = []
    for figure in chosen:
        fig = draw(ds, figure, time=time) if draw_figure is None else draw_figure(ds, figure)
        try:
            with replacing(paths[figure]) as tmp:
                fig.savefig(tmp, format="png", dpi=dpi, metadata={"Software": f"{SOFTWARE} {__version__}"})
        except OSError as exc:
            raise OrbattError(f"{what}: cannot write {str(paths[figure])!r} ({exc.strerror or exc}); nothing partial "
                              "was left: free some space or give another folder") from None
        finally:
            plt.close(fig)
        written.append(paths[figure])
    return written

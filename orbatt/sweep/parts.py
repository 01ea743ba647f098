"""A sweep's parts on disk: one netCDF file per finished chunk in ``OUTPUT.parts/``, named by
its case range and carrying its sweep's fingerprint, plus ``sweep.json`` (the fingerprint
checked on resume); scanning and repairing them on resume, and reading them back for the
merge (``docs/sweeps.md``: Storage and resumption)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from .cases import FORMAT
from ..dataset import check_engine, decode, encode, encoding, write_netcdf
from ..dataset.atomic import replacing

__all__ = ["parts_dir", "part_name", "parse_part", "done_parts", "chunk_ranges", "write_reductions", "write_part",
           "write_manifest", "read_manifest", "read_parts", "MANIFEST", "PART_FINGERPRINT"]

#: the manifest of a parts folder
MANIFEST = "sweep.json"
#: the global attribute of a part that holds its sweep's fingerprint
PART_FINGERPRINT = "sweep_fingerprint"


def parts_dir(output: Path) -> Path:
    """The parts folder beside ``output``: ``OUTPUT.parts/``."""
    return output.with_name(output.name + ".parts")


def part_name(start, stop):
    """File name of the part holding cases ``start .. stop - 1``."""
    return f"cases-{start:09d}-{stop - 1:09d}.nc"


def parse_part(name):
    """``(start, stop)`` of a part's file name, or None for another file."""
    if not (name.startswith("cases-") and name.endswith(".nc")):
        return None
    try:
        a, b = name[6:-3].split("-")
        return int(a), int(b) + 1
    except ValueError:
        return None


def _foreign(parts, name, found, fingerprint):
    """The one-line refusal of a part whose fingerprint is not the sweep's."""
    return InputError(f"resume: the part {name} in {str(parts)!r} belongs to another sweep (fingerprint "
                      f"{found or 'missing'}, this sweep {fingerprint}: other scenario text, seed, cases or "
                      "orbatt sampling code); remove that part (or the folder) and rerun with --resume")


def done_parts(parts: Path, n_cases, fingerprint):
    """``[(start, stop, path)]`` of the complete parts (a damaged one is removed); a part of
    another sweep (its ``sweep_fingerprint`` attribute is not ``fingerprint``) is refused
    with :class:`InputError`."""

    engine = check_engine(None)
    done = []
    for f in sorted(parts.iterdir()):
        if f.name.startswith(".tmp-"):
            f.unlink()  # a part whose writing was interrupted
            continue
        r = parse_part(f.name)
        if r is None:
            continue
        ok = 0 <= r[0] < r[1] <= n_cases
        found = None
        if ok:
            try:
                if engine == "netcdf4":
                    import netCDF4

                    with netCDF4.Dataset(f) as nc:
                        ok = len(nc.dimensions["case"]) == r[1] - r[0]
                        found = nc.getncattr(PART_FINGERPRINT) if PART_FINGERPRINT in nc.ncattrs() else None
                else:
                    import h5netcdf

                    with h5netcdf.File(f, "r") as nc:
                        ok = nc.dimensions["case"].size == r[1] - r[0]
                        found = nc.attrs.get(PART_FINGERPRINT)
            except Exception:  # noqa: BLE001 - any unreadable part is recomputed
                ok = False
        if not ok:
            f.unlink()
            continue
        if found != fingerprint:
            raise _foreign(parts, f.name, found, fingerprint)
        done.append((r[0], r[1], f))
    # overlapping parts cannot come from orbatt; keep the first of any overlap
    out, covered = [], np.zeros(n_cases, dtype=bool)
    for a, b, f in done:
        if covered[a:b].any():
            f.unlink()
            continue
        covered[a:b] = True
        out.append((a, b, f))
    return out, covered


def chunk_ranges(missing, chunk_size):
    """Runs of consecutive missing cases, cut into chunks of at most ``chunk_size``."""
    idx = np.flatnonzero(missing)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) != 1) + 1
    out = []
    for run in np.split(idx, breaks):
        a, b = int(run[0]), int(run[-1]) + 1
        for s in range(a, b, chunk_size):
            out.append((s, min(s + chunk_size, b)))
    return out


def write_reductions(ds, path):
    """:func:`orbatt.dataset.write_netcdf`, also for a Dataset without ``time`` (reductions
    only); atomic either way (:func:`orbatt.dataset.atomic.replacing`)."""

    if "time" in ds.dims:
        write_netcdf(ds, path)
        return
    enc = encode(ds)
    with replacing(path) as tmp:
        enc.to_netcdf(tmp, engine=check_engine(None), format="NETCDF4", encoding=encoding(enc, 1, 1))


def write_part(ds, parts: Path, start, stop, fingerprint):
    """Write a chunk's Dataset as the part of cases ``start .. stop - 1`` (under a temporary
    name, then renamed: a part with its final name is complete), with the sweep's
    ``fingerprint`` as its ``sweep_fingerprint`` attribute; returns its path."""
    final = parts / part_name(start, stop)
    ds.attrs[PART_FINGERPRINT] = fingerprint
    write_reductions(ds, final)
    return final


def write_manifest(parts: Path, sweep):
    """Create ``parts`` with its manifest: format, fingerprint, seed, cases, source."""
    parts.mkdir(parents=True)
    with replacing(parts / MANIFEST) as tmp:
        tmp.write_text(json.dumps({"format": FORMAT, "fingerprint": sweep.fingerprint, "seed": sweep.seed,
                                   "cases": sweep.cases, "scenario": sweep.source}, indent=1))


def read_manifest(parts: Path) -> dict:
    """The manifest of an existing parts folder; :class:`InputError` if it has none."""
    try:
        return json.loads((parts / MANIFEST).read_text())
    except (OSError, ValueError):
        raise InputError(f"resume: {str(parts)!r} has no readable {MANIFEST}; it is not an orbatt sweep's "
                         "parts folder (delete it to start again)") from None


def read_parts(parts: Path, n_cases, lazy, fingerprint):
    """Open every part in case order (decoded); trajectories stay on disk when ``lazy``
    (dask), reductions are loaded. :class:`InputError` if they do not cover every case or
    one belongs to another sweep (its fingerprint is not ``fingerprint``)."""
    import xarray as xr


    files = sorted((p for p in parts.iterdir() if parse_part(p.name)), key=lambda p: parse_part(p.name)[0])
    ranges = [parse_part(p.name) for p in files]
    if ranges[0][0] != 0 or ranges[-1][1] != n_cases or any(r[1] != s[0] for r, s in zip(ranges, ranges[1:])):
        raise InputError(f"output: the parts in {str(parts)!r} do not cover cases 0..{n_cases - 1}; rerun with "
                         "--resume")
    engine = check_engine(None)
    chunks = {"chunks": {}} if lazy else {}
    opened = []
    try:
        for f in files:
            opened.append(decode(xr.open_dataset(f, engine=engine, decode_times=False, decode_timedelta=False,
                                                 **chunks)))
            found = opened[-1].attrs.get(PART_FINGERPRINT)
            if found != fingerprint:
                raise _foreign(parts, f.name, found, fingerprint)
        return opened if lazy else [d.load() for d in opened]
    except BaseException:
        for d in opened:
            d.close()
        raise

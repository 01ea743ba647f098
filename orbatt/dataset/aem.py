"""CCSDS Attitude Ephemeris Message (AEM), KVN form: export of orbatt's attitude and a reader.

Standards: CCSDS 504.0-B-1 (ADM, AEM version 1.0, the default here) and 504.0-B-2 (AEM
version 2.0). Such files feed Orekit, GMAT and STK.

How orbatt's ``q`` maps onto an AEM quaternion
----------------------------------------------
orbatt's attitude ``q`` (``docs/design.md`` §1) maps body components to space components,
``x_S = q x_B q~``; equivalently it is the rotation by an angle ``a`` about a unit axis ``e``
that turns the ``S`` axes into the ``B`` axes, ``q = (cos a/2, e sin a/2)``: the attitude of
``B`` relative to ``S``.

An AEM quaternion with ``REF_FRAME_A = <inertial frame>``, ``REF_FRAME_B = SC_BODY_1`` and
``ATTITUDE_DIR = A2B`` is the rotation *from frame A to frame B*: the same ``(e, a)``, written
``Q1 Q2 Q3 = e sin a/2``, ``QC = cos a/2``. Its direction-cosine matrix (ADM annex) transforms
A components into B components, ``x_B = M x_A`` with::

        | Q1²-Q2²-Q3²+QC²   2(Q1Q2+Q3QC)      2(Q1Q3-Q2QC)    |
    M = | 2(Q1Q2-Q3QC)      -Q1²+Q2²-Q3²+QC²  2(Q2Q3+Q1QC)    |  = R(q)^T  (R = orbatt.quaternion.to_matrix)
        | 2(Q1Q3+Q2QC)      2(Q2Q3-Q1QC)      -Q1²-Q2²+Q3²+QC² |

So **no conjugation and no sign change**: only the position of the scalar differs.

==========================  ===============================================================
AEM header                   data line after the epoch
==========================  ===============================================================
1.0, QUATERNION_TYPE=FIRST   ``QC Q1 Q2 Q3`` = ``q0 q1 q2 q3`` (orbatt's order)
1.0, QUATERNION_TYPE=LAST    ``Q1 Q2 Q3 QC`` = ``q1 q2 q3 q0``
2.0 (no QUATERNION_TYPE,     ``Q1 Q2 Q3 QC`` = ``q1 q2 q3 q0`` (version 2 always writes the
no ATTITUDE_DIR)             scalar last and always means A to B)
==========================  ===============================================================

Example (90 degrees, tested): a body turned by +90 degrees about ``s3`` (so ``b1 = s2``) has
``q = (cos 45°, 0, 0, sin 45°)`` and the line ``<epoch> 0.7071067811865476 0.0 0.0
0.7071067811865476`` with ``QUATERNION_TYPE = FIRST``; Orekit reads it as the rotation taking
``s2`` (A components) to ``(1, 0, 0)`` (B components).

The inertial frame: a Dataset with an epoch (the AEM needs one) has astropy's GCRS as its ``S``
(``docs/design.md`` §1, §11: TLE states rotated TEME -> GCRS, the Sun, the Earth's fields and
ground sites given in GCRS), so ``REF_FRAME_A`` is ``GCRF`` by default, the Geocentric Celestial
Reference Frame of the CCSDS/SANA frame names (504.0-B-2 annex; Orekit reads it as its GCRF). Not
``EME2000`` (the mean equator and equinox of J2000, 17-23 mas of frame bias away) nor ``ICRF``
(barycentric: the same axes, another origin).

The attitude relative to the orbital frame, ``q_orbital`` (``B`` relative to
``O`` = radial, transverse, normal), is written the same way with ``REF_FRAME_A = RTN``.

Times: ``elapsed`` (seconds since the Dataset's ``epoch``, :mod:`orbatt.dataset.build`) becomes
absolute epochs ``epoch + elapsed`` (SI seconds of TT/TAI, leap seconds counted by astropy) written in ``TIME_SYSTEM``
(UTC by default; TAI, TT, TDB, TCB, TCG also accepted) with nanosecond digits. Quaternion
components are written with the shortest decimal that gives back the same float64, so a
read gives the same bits.

Interoperability: files in UTC, TAI or TT give the same instants in astropy (orbatt) and
Orekit (checked with Orekit 13, ``AemParser``: exactly). In TDB and TCB the two differ by
tens of microseconds (different TDB - TT models), about 1e-6 rad of attitude for a body
turning at 0.05 rad/s: write UTC, TAI or TT when another tool reads the file.

Form: KVN lines ``KEY = value`` (CCSDS 504.0-B-2; keys padded to a column, then `` = ``).
:func:`read_aem` also reads the ``KEY= value`` lines that earlier versions of orbatt wrote,
and any spacing around ``=``. The command line writes an AEM with ``orbatt run
SCENARIO.toml --aem FILE`` or ``orbatt export RESULT.nc --aem FILE``; the file is written
atomically (:mod:`orbatt.dataset.atomic`).
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from datetime import datetime, timezone

import numpy as np

from .. import quaternion as qt
from ..epoch import parse_epoch
from ..errors import InputError
from .atomic import replacing
from .timeaxis import elapsed_unit, elapsed_values

__all__ = ["write_aem", "read_aem", "is_orbatt_aem", "Aem", "AemSegment", "aem_direction_cosine_matrix"]

_SCALES = {"UTC": "utc", "TAI": "tai", "TT": "tt", "TDB": "tdb", "TCB": "tcb", "TCG": "tcg"}
# CCSDS spacecraft frame names (SANA): a frame whose name starts with one of these is on the body
_BODY_PREFIXES = ("SC_BODY", "ACTUATOR", "CSS", "DSS", "ESA", "GYRO", "IMU", "INSTRUMENT", "MTA",
                  "RADIATOR", "RW", "SENSOR", "STARTRACKER", "THRUSTER")
_PAD = 20


def aem_direction_cosine_matrix(Q):
    """Direction-cosine matrix of CCSDS quaternions (ADM annex), ``x_B = M x_A``.

    Parameters
    ----------
    Q : array-like (..., 4)
        ``(Q1, Q2, Q3, QC)``, **scalar last** as in the standard, rotation from A to B.

    Returns
    -------
    ndarray (..., 3, 3)
        Transforms components in frame A into components in frame B.
    """
    Q = np.asarray(Q, dtype=np.float64)
    q1, q2, q3, qc = np.moveaxis(Q, -1, 0)
    M = np.stack([
        q1 * q1 - q2 * q2 - q3 * q3 + qc * qc, 2 * (q1 * q2 + q3 * qc), 2 * (q1 * q3 - q2 * qc),
        2 * (q1 * q2 - q3 * qc), -q1 * q1 + q2 * q2 - q3 * q3 + qc * qc, 2 * (q2 * q3 + q1 * qc),
        2 * (q1 * q3 + q2 * qc), 2 * (q2 * q3 - q1 * qc), -q1 * q1 - q2 * q2 + q3 * q3 + qc * qc,
    ], axis=-1)
    return M.reshape(Q.shape[:-1] + (3, 3))


def _check_text(name, value):
    """Refuse a metadata value that would break the message's lines: a control character (a
    newline would start a second ``KEY = value`` line, even a second ``META_STOP``)."""
    if value is None:
        return
    text = str(value)
    bad = next((ch for ch in text if ord(ch) < 32 or 127 <= ord(ch) < 160 or ch in "\u2028\u2029"), None)
    if bad is not None:
        raise InputError(f"{name}: {text!r} holds the control character {bad!r}; an AEM value is one line of "
                         "printable text")


def _kvn(key, value):
    return f"{key:<{_PAD}} = {value}"


def _fmt_time(times, scale):
    t = getattr(times, scale)
    t.precision = 9
    return np.atleast_1d(t.isot)


def write_aem(ds, path=None, *, attitude="q", case=None, object_name="SATELLITE", object_id="UNKNOWN",
              center_name=None, ref_frame_a=None, ref_frame_b="SC_BODY_1", time_system="UTC",
              quaternion_type="FIRST", version="1.0", originator="ORBATT", comments=(),
              interpolation_method="LAGRANGE", interpolation_degree=7):
    """Write an attitude history as a CCSDS AEM in KVN form.

    Parameters
    ----------
    ds : xarray.Dataset
        An orbatt Dataset (:func:`orbatt.dataset.to_dataset`) with an ``epoch`` (dimensional
        problems only: a dimensionless time has no calendar).
    path : str or os.PathLike, optional
        Where to write (atomically: a temporary file beside it, renamed); the text is
        returned in any case. Any file there is replaced: check it first
        (:func:`orbatt.dataset.check_output_path` with ``ours=is_orbatt_aem``).
    attitude : {"q", "q_orbital"}
        ``"q"``: the body relative to the inertial frame ``S`` (default frame name
        ``GCRF``); ``"q_orbital"``: relative to the orbital frame (default ``RTN``).
    case : int, optional
        The ensemble member to write (required for ensembles).
    object_name, object_id, center_name : str
        Metadata (``OBJECT_ID`` is the international designator where there is one).
    ref_frame_a : str, optional
        Name of orbatt's reference frame in the file: by default ``GCRF`` for ``q`` (orbatt's
        ``S`` is astropy's GCRS whenever there is an epoch, and an AEM needs one), ``RTN`` for
        ``q_orbital``. Give another name only to relabel: nothing is rotated.
    ref_frame_b : str
        The body frame (``SC_BODY_1``).
    time_system : {"UTC", "TAI", "TT", "TDB", "TCB", "TCG"}
    quaternion_type : {"FIRST", "LAST"}
        Position of the scalar ``QC`` (version 1.0 only; version 2.0 always writes it last).
    version : {"1.0", "2.0"}
        ``CCSDS_AEM_VERS``: 504.0-B-1 (with ``ATTITUDE_DIR = A2B`` and ``QUATERNION_TYPE``) or
        504.0-B-2.
    originator : str
    comments : sequence of str
        Extra ``COMMENT`` lines for the header.
    interpolation_method, interpolation_degree : str, int or None
        Recommended interpolation (``None`` leaves both out). The degree is capped at the
        number of samples minus one.

    Returns
    -------
    str
        The message text.
    """
    from astropy.time import TimeDelta

    version = str(version)
    if version not in ("1.0", "2.0"):
        raise InputError(f"version: {version!r} is not '1.0' (CCSDS 504.0-B-1) or '2.0' (504.0-B-2)")
    qtype = str(quaternion_type).upper()
    if qtype not in ("FIRST", "LAST"):
        raise InputError(f"quaternion_type: {quaternion_type!r} is not 'FIRST' or 'LAST'")
    if version == "2.0":
        qtype = "LAST"
    ts = str(time_system).upper()
    if ts not in _SCALES:
        raise InputError(f"time_system: {time_system!r} is not one of {sorted(_SCALES)}")
    if attitude not in ("q", "q_orbital"):
        raise InputError(f"attitude: {attitude!r} is not 'q' or 'q_orbital'")
    if attitude not in ds:
        raise InputError(f"attitude: the dataset has no {attitude!r} (q_orbital needs an orbit)")
    if ref_frame_a is None:
        ref_frame_a = "GCRF" if attitude == "q" else "RTN"  # S = GCRS with an epoch (design.md §11)
    for name, value in (("object_name", object_name), ("object_id", object_id), ("center_name", center_name),
                        ("ref_frame_a", ref_frame_a), ("ref_frame_b", ref_frame_b), ("originator", originator),
                        *((f"comments[{k}]", c) for k, c in enumerate(comments))):
        _check_text(name, value)
    if "case" in ds[attitude].dims:
        if case is None:
            raise InputError("case: this is an ensemble; choose the member to write with case=...")
        cases = ds["case"].values
        if isinstance(case, bool) or not isinstance(case, (int, np.integer)) or case not in cases:
            span = f"{cases[0]} .. {cases[-1]}" if cases.size else "none"
            raise InputError(f"case: {case!r} is not a case of this ensemble (cases {span}); give one of them")
        ds = ds.sel(case=case)
    elif case is not None:
        raise InputError("case: this dataset is not an ensemble; leave case out")
    epoch = ds.attrs.get("epoch")
    if not epoch or elapsed_unit(ds) != "s":
        raise InputError("AEM needs absolute times: this dataset has no epoch (or a dimensionless "
                         "time); give the scenario an epoch")

    q = np.asarray(ds[attitude].values, dtype=np.float64)
    t = elapsed_values(ds)  # seconds since the epoch, exact (time's datetimes ignore leap seconds)
    if q.ndim != 2 or q.shape[1] != 4 or len(t) == 0:
        raise InputError(f"{attitude}: expected shape (N, 4) with N >= 1, got {q.shape}")
    ep = parse_epoch(str(epoch))
    stamps = _fmt_time(ep + TimeDelta(t, format="sec"), _SCALES[ts])
    cols = q if qtype == "FIRST" else q[:, [1, 2, 3, 0]]

    created = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")
    lines = [_kvn("CCSDS_AEM_VERS", version)]
    frames = "B relative to S" if attitude == "q" else "B relative to O (radial, transverse, normal)"
    for c in (f"orbatt {ds.attrs.get('orbatt_version', '')}: attitude {attitude} ({frames})",
              *comments):
        lines.append(f"COMMENT {c}")
    lines += [_kvn("CREATION_DATE", created), _kvn("ORIGINATOR", originator), "", "META_START",
              _kvn("OBJECT_NAME", object_name), _kvn("OBJECT_ID", object_id)]
    if center_name:
        lines.append(_kvn("CENTER_NAME", center_name))
    lines += [_kvn("REF_FRAME_A", ref_frame_a), _kvn("REF_FRAME_B", ref_frame_b)]
    if version == "1.0":
        lines.append(_kvn("ATTITUDE_DIR", "A2B"))
    lines += [_kvn("TIME_SYSTEM", ts), _kvn("START_TIME", stamps[0]), _kvn("STOP_TIME", stamps[-1]),
              _kvn("ATTITUDE_TYPE", "QUATERNION")]
    if version == "1.0":
        lines.append(_kvn("QUATERNION_TYPE", qtype))
    if interpolation_method is not None:
        deg = min(int(interpolation_degree), max(len(t) - 1, 1))
        lines += [_kvn("INTERPOLATION_METHOD", interpolation_method), _kvn("INTERPOLATION_DEGREE", deg)]
    lines += ["META_STOP", "", "DATA_START"]
    c = cols.tolist()
    lines += [f"{s} {a!r} {b!r} {d!r} {e!r}" for s, (a, b, d, e) in zip(stamps, c)]
    lines += ["DATA_STOP", ""]
    text = "\n".join(lines)
    if path is not None:
        with replacing(path) as tmp, open(tmp, "w", encoding="ascii", newline="\n") as fh:
            fh.write(text)
    return text


def is_orbatt_aem(path) -> bool:
    """True when ``path`` is a file that :func:`write_aem` wrote: it starts with
    ``CCSDS_AEM_VERS`` and its first comment names orbatt (reads the first 4 KiB only)."""
    try:
        with open(os.fspath(path), "rb") as fh:
            head = fh.read(4096).decode("ascii", errors="replace")
    except OSError:
        return False
    lines = [ln.strip() for ln in head.splitlines()]
    comments = [ln for ln in lines if ln.startswith("COMMENT")]
    return bool(lines) and lines[0].startswith("CCSDS_AEM_VERS") and bool(comments) and \
        comments[0].split()[1:2] == ["orbatt"]


@dataclass
class AemSegment:
    """One AEM segment, read.

    Attributes
    ----------
    metadata : dict
        ``KEY -> value`` strings of the metadata block.
    comments : list of str
    epochs : astropy.time.Time (N,)
        In the segment's ``TIME_SYSTEM``.
    data : ndarray (N, 4)
        The four numbers of each line, in file order.
    q : ndarray (N, 4)
        orbatt convention (scalar first): the attitude of frame ``frame_b`` relative to
        ``frame_a`` (``x_A = q x_B q~``), whatever ``QUATERNION_TYPE`` and ``ATTITUDE_DIR``
        the file used.
    frame_a, frame_b : str
    """

    metadata: dict
    comments: list
    epochs: object
    data: np.ndarray
    q: np.ndarray
    frame_a: str
    frame_b: str

    @property
    def body_attitude(self):
        """``(q, reference frame name)``: the body relative to the external frame (orbatt's
        ``q`` when the reference is inertial), conjugating if the file names the body frame
        as ``REF_FRAME_A``."""
        a_body = self.frame_a.upper().startswith(_BODY_PREFIXES)
        b_body = self.frame_b.upper().startswith(_BODY_PREFIXES)
        if a_body and not b_body:
            return qt.conj(self.q), self.frame_b
        return self.q, self.frame_a

    def seconds_since(self, epoch):
        """Seconds (float64) from ``epoch`` (astropy Time or ISO UTC string) to each epoch.

        Counted in TT (= TAI) seconds, as :func:`write_aem` adds orbatt's ``time`` to the
        epoch; TDB seconds differ from these by up to 3e-10 s per s.
        """
        epoch = parse_epoch(epoch)
        return np.asarray((self.epochs.tt - epoch.tt).sec, dtype=np.float64)


@dataclass
class Aem:
    """A parsed AEM: ``version``, ``header`` (dict), header ``comments`` and ``segments``."""

    version: str
    header: dict
    comments: list = field(default_factory=list)
    segments: list = field(default_factory=list)


_DOY = re.compile(r"^(\d{4})-(\d{3})T(.*)$")


def _parse_epochs(strings, time_system):
    from astropy.time import Time

    ts = time_system.upper()
    if ts not in _SCALES:
        raise InputError(f"TIME_SYSTEM: {time_system!r} is not supported (use one of {sorted(_SCALES)})")
    clean = [s[:-1] if s.endswith("Z") else s for s in strings]
    if clean and _DOY.match(clean[0]):
        conv = []
        for s in clean:
            m = _DOY.match(s)
            if not m:
                raise InputError(f"AEM epoch: {s!r} mixes calendar and day-of-year formats")
            conv.append(f"{m.group(1)}:{m.group(2)}:{m.group(3)}")
        return Time(conv, format="yday", scale=_SCALES[ts])
    try:
        return Time(clean, format="isot", scale=_SCALES[ts])
    except ValueError as exc:
        raise InputError(f"AEM epoch: cannot parse ({exc})") from None


def read_aem(source):
    """Read a KVN AEM (versions 1.0 and 2.0) with ``ATTITUDE_TYPE = QUATERNION``.

    Parameters
    ----------
    source : str or os.PathLike
        A path, or the message text itself (a string starting with ``CCSDS_AEM_VERS``).

    Returns
    -------
    Aem
        Each segment's ``q`` in orbatt's convention (see :class:`AemSegment`).

    Raises
    ------
    InputError
        Not an AEM, an attitude type other than QUATERNION, or a malformed line (the message
        quotes the line number).
    """
    if isinstance(source, str) and source.lstrip().startswith("CCSDS_AEM_VERS"):
        text = source
    else:
        try:
            with open(os.fspath(source), encoding="utf-8") as fh:
                text = fh.read()
        except UnicodeDecodeError as exc:
            raise InputError(f"{os.fspath(source)}: not an AEM: byte {exc.object[exc.start]:#04x} at offset "
                             f"{exc.start} is not UTF-8 text (KVN AEM files are ASCII)") from None
        except OSError as exc:
            raise InputError(f"{os.fspath(source)}: cannot read it ({exc.strerror or exc})") from None
    header, hcomments, segments = {}, [], []
    state = "header"
    meta, mcomments, stamps, rows = None, None, None, None
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("COMMENT"):
            c = line[7:].strip()
            (hcomments if state == "header" else mcomments).append(c)
            continue
        if line == "META_START":
            state, meta, mcomments = "meta", {}, []
            continue
        if line == "META_STOP":
            state = "between"
            continue
        if line == "DATA_START":
            if meta is None:
                raise InputError(f"AEM line {lineno}: DATA_START before any META_START")
            state, stamps, rows = "data", [], []
            continue
        if line == "DATA_STOP":
            segments.append(_segment(meta, mcomments, stamps, rows, header))
            state = "between"
            continue
        if state == "data":
            parts = line.split()
            if len(parts) != 5:
                raise InputError(f"AEM line {lineno}: expected an epoch and 4 quaternion components, "
                                 f"got {raw!r}")
            stamps.append(parts[0])
            try:
                rows.append([float(x) for x in parts[1:]])
            except ValueError:
                raise InputError(f"AEM line {lineno}: not numbers: {raw!r}") from None
            continue
        if "=" not in line:
            raise InputError(f"AEM line {lineno}: expected KEY = value, got {raw!r}")
        key, value = (s.strip() for s in line.split("=", 1))
        if state == "header":
            header[key] = value
        elif state == "meta":
            meta[key] = value
        else:
            raise InputError(f"AEM line {lineno}: {key} outside a header or metadata block")
    if "CCSDS_AEM_VERS" not in header:
        raise InputError("AEM: no CCSDS_AEM_VERS line; this is not an attitude ephemeris message")
    if state == "data":
        raise InputError("AEM: the last data block has no DATA_STOP")
    return Aem(version=header["CCSDS_AEM_VERS"], header=header, comments=hcomments, segments=segments)


def _segment(meta, comments, stamps, rows, header):
    version = header.get("CCSDS_AEM_VERS", "1.0")
    v2 = version.startswith("2")
    atype = meta.get("ATTITUDE_TYPE", "").upper()
    if atype != "QUATERNION":
        raise InputError(f"ATTITUDE_TYPE: {atype!r} is not supported; orbatt reads QUATERNION")
    qtype = "LAST" if v2 else meta.get("QUATERNION_TYPE", "").upper()
    if qtype not in ("FIRST", "LAST"):
        raise InputError("QUATERNION_TYPE: missing or not FIRST/LAST (required in AEM version 1)")
    direction = "A2B" if v2 else meta.get("ATTITUDE_DIR", "").upper()
    if direction not in ("A2B", "B2A"):
        raise InputError("ATTITUDE_DIR: missing or not A2B/B2A (required in AEM version 1)")
    data = np.array(rows, dtype=np.float64).reshape(-1, 4)
    q = data if qtype == "FIRST" else data[:, [3, 0, 1, 2]]
    q = np.ascontiguousarray(q)
    if direction == "B2A":  # the rotation from B to A is the inverse
        q = qt.conj(q)
    epochs = _parse_epochs(stamps, meta.get("TIME_SYSTEM", "UTC"))
    return AemSegment(metadata=meta, comments=comments, epochs=epochs, data=data, q=q,
                      frame_a=meta.get("REF_FRAME_A", ""), frame_b=meta.get("REF_FRAME_B", ""))

"""CCSDS AEM export/import (issue 5): the quaternion convention pinned by a 90-degree
example, header keywords of versions 1.0 and 2.0, and lossless round trips."""
import re
import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt.dataset import aem
from orbatt import canonical as cn
from orbatt import dataset as D
from orbatt import quaternion as qt
from orbatt.errors import InputError
from orbatt.trajectory import Trajectory

EPOCH = "2024-01-01T00:00:00.000000000Z"
C45 = float(np.cos(np.pi / 4))


def _spin_dataset(q_start, rate=0.01, n=11, step=10.0, epoch=EPOCH, ensemble=False):
    """Exact torque-free motion: a steady spin about body axis 3 (a principal axis), so
    ``q(t) = q_start (cos(w t/2), 0, 0, sin(w t/2))`` and ``Q = 2 q g`` with constant ``g``."""
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    t = np.arange(n) * step
    spin = np.stack([np.cos(rate * t / 2), 0 * t, 0 * t, np.sin(rate * t / 2)], axis=-1)
    q = qt.mul(np.asarray(q_start, float), spin)
    g = np.array([0.0, 0.0, 600.0 * rate])
    Q = cn.momentum_from_body_momentum(q, np.broadcast_to(g, (n, 3)))
    inertia = body.inertia_value
    if ensemble:
        q, Q, inertia = np.stack([q, q]), np.stack([Q, Q]), np.stack([inertia, inertia])
    tr = Trajectory(body=body, potential=orbatt.TorqueFree(), t=t, q=q, Q=Q, inertia=inertia, method="exact")
    return D.to_dataset(tr, epoch=epoch)


def _data_lines(text):
    lines = text.splitlines()
    return lines[lines.index("DATA_START") + 1:lines.index("DATA_STOP")]


def _meta(text):
    lines = text.splitlines()
    block = lines[lines.index("META_START") + 1:lines.index("META_STOP")]
    return dict((s.strip() for s in ln.split("=", 1)) for ln in block if "=" in ln)


def test_ninety_degree_example_pins_the_convention():
    # body turned +90 deg about s3: b1 = s2, b2 = -s1
    q90 = np.array([C45, 0.0, 0.0, C45])
    assert np.allclose(qt.rotate(q90, [1.0, 0, 0]), [0, 1.0, 0], atol=1e-15)  # b1 in S
    ds = _spin_dataset(q90, rate=0.0, n=3)
    text = aem.write_aem(ds)
    meta = _meta(text)
    assert meta["REF_FRAME_A"] == "GCRF" and meta["REF_FRAME_B"] == "SC_BODY_1"
    assert meta["ATTITUDE_DIR"] == "A2B" and meta["QUATERNION_TYPE"] == "FIRST"
    assert meta["ATTITUDE_TYPE"] == "QUATERNION" and meta["TIME_SYSTEM"] == "UTC"
    first = _data_lines(text)[0].split()
    assert first[0] == "2024-01-01T00:00:00.000000000"
    assert [float(x) for x in first[1:]] == [C45, 0.0, 0.0, C45]
    # the standard's direction-cosine matrix of that quaternion takes A (= S) components to
    # B components: s2 is b1 = (1, 0, 0) in the body
    Q_ccsds = np.array([0.0, 0.0, C45, C45])  # (Q1, Q2, Q3, QC)
    M = aem.aem_direction_cosine_matrix(Q_ccsds)
    assert np.allclose(M @ [0, 1.0, 0], [1.0, 0, 0], atol=1e-15)
    assert np.allclose(M @ [1.0, 0, 0], [0, -1.0, 0], atol=1e-15)
    # scalar last
    last = _data_lines(aem.write_aem(ds, quaternion_type="LAST"))[0].split()
    assert [float(x) for x in last[1:]] == [0.0, 0.0, C45, C45]


def test_mapping_for_random_attitudes():
    rng = np.random.default_rng(2)
    q = qt.normalize(rng.normal(size=(200, 4)))
    M = aem.aem_direction_cosine_matrix(q[:, [1, 2, 3, 0]])
    # x_B = M x_S = q~ x_S q: the transpose of orbatt's body-to-space matrix
    assert np.allclose(M, np.swapaxes(qt.to_matrix(q), -1, -2), atol=1e-15)
    x = rng.normal(size=(200, 3))
    assert np.allclose(np.einsum("nij,nj->ni", M, x), qt.rotate_inv(q, x), atol=1e-14)


@pytest.mark.parametrize("qtype", ["FIRST", "LAST"])
@pytest.mark.parametrize("time_system", ["UTC", "TDB"])
def test_round_trip(qtype, time_system, tmp_path):
    q_start = qt.normalize(np.array([0.5, -1 / np.sqrt(2), 0.1, 0.5]))
    ds = _spin_dataset(q_start, n=101, step=0.37)
    path = tmp_path / "att.aem"
    text = ds.orbatt.to_aem(path, quaternion_type=qtype, time_system=time_system, object_name="TEST SAT",
                            object_id="2024-001A", center_name="EARTH", comments=["a test"])
    assert path.read_text() == text
    msg = aem.read_aem(path)
    assert msg.version == "1.0" and msg.header["ORIGINATOR"] == "ORBATT"
    assert "a test" in msg.comments
    (seg,) = msg.segments
    assert seg.metadata["OBJECT_NAME"] == "TEST SAT" and seg.metadata["CENTER_NAME"] == "EARTH"
    assert seg.metadata["TIME_SYSTEM"] == time_system
    assert seg.frame_a == "GCRF" and seg.frame_b == "SC_BODY_1"
    assert seg.q.tobytes() == ds["q"].values.tobytes()  # bit for bit
    q_body, ref = seg.body_attitude
    assert ref == "GCRF" and np.array_equal(q_body, ds["q"].values)
    assert np.allclose(seg.seconds_since(ds.attrs["epoch"]), ds["elapsed"].values, rtol=0, atol=2e-9)
    assert seg.seconds_since(ds.orbatt.epoch)[0] == pytest.approx(0.0, abs=1e-9)
    # the text itself is also accepted
    assert np.array_equal(aem.read_aem(text).segments[0].q, seg.q)


def test_version_2():
    ds = _spin_dataset([C45, 0.0, 0.0, C45], rate=0.0, n=2)
    text = aem.write_aem(ds, version="2.0", quaternion_type="FIRST")
    meta = _meta(text)
    assert re.match(r"CCSDS_AEM_VERS += 2.0\n", text)
    assert "ATTITUDE_DIR" not in meta and "QUATERNION_TYPE" not in meta
    assert [float(x) for x in _data_lines(text)[0].split()[1:]] == [0.0, 0.0, C45, C45]  # scalar last
    assert np.array_equal(aem.read_aem(text).segments[0].q, ds["q"].values)


def _hand_written(frame_a, frame_b, direction, row, stamp="2024-01-01T00:00:10"):
    return f"""CCSDS_AEM_VERS = 1.0
CREATION_DATE = 2024-01-02T00:00:00
ORIGINATOR = HAND

META_START
OBJECT_NAME = X
OBJECT_ID = 2024-001A
REF_FRAME_A = {frame_a}
REF_FRAME_B = {frame_b}
ATTITUDE_DIR = {direction}
TIME_SYSTEM = UTC
START_TIME = {stamp}
STOP_TIME = {stamp}
ATTITUDE_TYPE = QUATERNION
QUATERNION_TYPE = LAST
META_STOP

DATA_START
COMMENT data comment
{stamp} {row}
DATA_STOP
"""


def test_reader_handles_direction_and_frame_order():
    q90 = np.array([C45, 0.0, 0.0, C45])
    # the same attitude, four ways
    a2b = aem.read_aem(_hand_written("EME2000", "SC_BODY_1", "A2B", f"0 0 {C45!r} {C45!r}")).segments[0]
    b2a = aem.read_aem(_hand_written("EME2000", "SC_BODY_1", "B2A", f"0 0 {-C45!r} {C45!r}")).segments[0]
    body_first = aem.read_aem(_hand_written("SC_BODY_1", "EME2000", "A2B", f"0 0 {-C45!r} {C45!r}")).segments[0]
    body_first_b2a = aem.read_aem(_hand_written("SC_BODY_1", "EME2000", "B2A", f"0 0 {C45!r} {C45!r}")).segments[0]
    for seg in (a2b, b2a, body_first, body_first_b2a):
        q, ref = seg.body_attitude
        assert ref == "EME2000"
        assert np.allclose(q, q90, atol=0, rtol=0)
    assert "data comment" in a2b.comments


def test_day_of_year_epochs():
    seg = aem.read_aem(_hand_written("EME2000", "SC_BODY_1", "A2B", "0 0 0 1", stamp="2024-032T12:00:00.5")).segments[0]
    assert abs((seg.epochs[0] - Time("2024-02-01T12:00:00.5", scale="utc")).sec) < 1e-9


def test_orbital_attitude_export():
    ds = _spin_dataset([1.0, 0, 0, 0], n=3)
    with pytest.raises(InputError, match="q_orbital"):
        aem.write_aem(ds, attitude="q_orbital")
    ds = ds.assign(q_orbital=ds["q"])  # stand-in: an orbit dataset has q_orbital
    meta = _meta(aem.write_aem(ds, attitude="q_orbital"))
    assert meta["REF_FRAME_A"] == "RTN"


def test_refusals():
    free = D.to_dataset(Trajectory(body=orbatt.RigidBody([1.25, 1.0, 0.75]), potential=orbatt.TorqueFree(),
                                   t=np.array([0.0, 1.0]), q=np.array([[1.0, 0, 0, 0]] * 2),
                                   Q=np.zeros((2, 4)), inertia=np.array([1.25, 1.0, 0.75]), method="x"))
    with pytest.raises(InputError, match="epoch"):
        aem.write_aem(free)
    ds = _spin_dataset([1.0, 0, 0, 0], n=3)
    with pytest.raises(InputError, match="version"):
        aem.write_aem(ds, version="3.0")
    with pytest.raises(InputError, match="time_system"):
        aem.write_aem(ds, time_system="GMST")
    with pytest.raises(InputError, match="quaternion_type"):
        aem.write_aem(ds, quaternion_type="MIDDLE")
    ens = _spin_dataset([1.0, 0, 0, 0], n=3, ensemble=True)
    with pytest.raises(InputError, match="case"):
        aem.write_aem(ens)
    assert np.array_equal(aem.read_aem(aem.write_aem(ens, case=1)).segments[0].q, ens["q"].values[1])
    bad = _hand_written("EME2000", "SC_BODY_1", "A2B", "0 0 0 1").replace("ATTITUDE_TYPE = QUATERNION",
                                                                         "ATTITUDE_TYPE = EULER_ANGLE")
    with pytest.raises(InputError, match="ATTITUDE_TYPE"):
        aem.read_aem(bad)
    with pytest.raises(InputError, match="line"):
        aem.read_aem(_hand_written("EME2000", "SC_BODY_1", "A2B", "0 0 1"))
    with pytest.raises(InputError, match="ATTITUDE_DIR"):
        aem.read_aem(_hand_written("EME2000", "SC_BODY_1", "SIDEWAYS", "0 0 0 1"))


def test_interpolation_degree_capped():
    ds = _spin_dataset([1.0, 0, 0, 0], n=3)
    meta = _meta(aem.write_aem(ds))
    assert meta["INTERPOLATION_METHOD"] == "LAGRANGE" and meta["INTERPOLATION_DEGREE"] == "2"
    assert "INTERPOLATION_METHOD" not in _meta(aem.write_aem(ds, interpolation_method=None))


def test_old_module_name_still_works():
    from orbatt.aem import read_aem, write_aem

    assert read_aem is aem.read_aem and write_aem is aem.write_aem
    assert orbatt.read_aem is aem.read_aem


def test_a_gcrs_run_writes_ref_frame_gcrf():
    """The frame a run's ``S`` is (issue 35 item 3): with an epoch orbatt's inertial frame is
    astropy's GCRS (a TLE state rotated TEME -> GCRS; ``docs/design.md`` §11), the CCSDS/SANA
    ``GCRF``, not ``EME2000`` (the J2000 mean equator and equinox, a frame bias away);
    ``q_orbital`` stays ``RTN``; ``ref_frame_a`` relabels."""
    import json
    import warnings
    from pathlib import Path

    from orbatt.scenario import Scenario, parse

    text = (Path(__file__).resolve().parents[2] / "scenarios" / "iss-tle-gravity-gradient.toml").read_text()
    text = re.sub(r"^t_end = .*$", 't_end = "300 s"', text, flags=re.M)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = Scenario(parse(text, "iss.toml")).run()
    assert json.loads(ds.attrs["orbit"])["frame"] == "GCRS"
    seg = aem.read_aem(aem.write_aem(ds)).segments[0]
    q, frame = seg.body_attitude
    assert seg.frame_a == frame == "GCRF" and np.array_equal(q, ds["q"].values)
    assert aem.read_aem(aem.write_aem(ds, attitude="q_orbital")).segments[0].frame_a == "RTN"
    assert aem.read_aem(aem.write_aem(ds, ref_frame_a="ICRF")).segments[0].frame_a == "ICRF"

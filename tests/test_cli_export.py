"""The CCSDS AEM from the command line (issue 14 §5): ``orbatt run ... --aem FILE`` and
``orbatt export RESULT.nc --aem FILE`` write what :func:`orbatt.write_aem` writes, atomically
and with the checks of ``-o``; KVN lines are ``KEY = value`` and old ``KEY= value`` files
still read."""
import re
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.cli import main
from orbatt.dataset import aem as A

SCEN = Path(__file__).resolve().parent.parent / "scenarios"
EPOCH = "2024-01-01T00:00:00"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")


def scenario(folder, epoch=True, file="kep.toml"):
    text = (SCEN / "paper-keplerian.toml").read_text()
    text = re.sub(r"^t_end = .*$", 't_end = "300 s"', text, flags=re.M)
    if epoch:
        text = text.replace('true_anomaly = "0 deg"\n', f'true_anomaly = "0 deg"\nepoch = "{EPOCH}"\n')
    path = folder / file
    path.write_text(text)
    return path


@pytest.fixture
def cli(capsys, monkeypatch):
    def run(*args, cwd):
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        rc = main([str(a) for a in args])
        out = capsys.readouterr()
        return rc, out.out, out.err

    return run


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """``orbatt run kep.toml -o r.nc --aem r.aem`` once: (folder, r.nc, r.aem)."""
    folder = tmp_path_factory.mktemp("aem")
    rc = main(["run", str(scenario(folder)), "-o", str(folder / "r.nc"), "--aem", str(folder / "r.aem"), "--quiet"])
    assert rc == 0
    return folder, folder / "r.nc", folder / "r.aem"


def assert_one_line_refusal(rc, err, *words):
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("orbatt: error: --aem"), (rc, err)
    for w in words:
        assert w in lines[0], (w, lines[0])


def _kvn_lines(text):
    return [ln for ln in text.splitlines() if "=" in ln and not ln.startswith("COMMENT")]


@pytest.fixture
def small_ds(tmp_path):
    return orbatt.load_scenario(scenario(tmp_path)).run()


def test_kvn_lines_are_key_space_equals_space_value(small_ds):
    text = A.write_aem(small_ds)
    lines = _kvn_lines(text)
    assert any(ln.startswith("INTERPOLATION_METHOD ") for ln in lines)  # the 20-character key of issue 14
    for ln in lines:
        assert re.fullmatch(r"[A-Z_]+ += \S.*", ln), ln


def test_old_kvn_spelling_still_reads(small_ds):
    text = A.write_aem(small_ds)
    old = "\n".join(re.sub(r"^([A-Z_]+) += ", lambda m: f"{m.group(1)}=", ln) for ln in text.splitlines())
    assert "INTERPOLATION_METHOD=LAGRANGE" in old
    a, b = A.read_aem(text), A.read_aem(old)
    assert a.header == b.header and a.segments[0].metadata == b.segments[0].metadata
    assert np.array_equal(a.segments[0].q, b.segments[0].q)


def test_run_writes_the_aem_of_the_result(result):
    folder, nc, aem = result
    ds = orbatt.open_dataset(nc, load=True)
    seg = A.read_aem(aem).segments[0]
    q, frame = seg.body_attitude
    assert frame == "GCRF" and seg.metadata["TIME_SYSTEM"] == "UTC"  # S is GCRS with an epoch (issue 35)
    assert np.array_equal(q, ds["q"].values)                      # bit for bit
    np.testing.assert_allclose(seg.seconds_since(EPOCH), ds["elapsed"].values, rtol=0, atol=1e-9)
    assert A.is_orbatt_aem(aem) and not A.is_orbatt_aem(nc)
    assert not [p for p in folder.iterdir() if p.name.startswith(".tmp-")]


def test_export_writes_the_same_attitude_in_other_time_systems(result, cli):
    folder, nc, aem = result
    for ts in ("TAI", "TT"):
        rc, _, err = cli("export", nc, "--aem", folder / "x.aem", "--time-system", ts, cwd=folder)
        assert rc == 0, err
        seg = A.read_aem(folder / "x.aem").segments[0]
        assert seg.metadata["TIME_SYSTEM"] == ts
        assert np.array_equal(seg.q, A.read_aem(aem).segments[0].q)  # an earlier orbatt AEM is replaced
        np.testing.assert_allclose(seg.seconds_since(EPOCH), A.read_aem(aem).segments[0].seconds_since(EPOCH),
                                   rtol=0, atol=1e-9)
    rc, _, err = cli("export", nc, "--aem", folder / "o.aem", "--attitude", "q_orbital", "--ref-frame", "LVLH",
                     cwd=folder)
    assert rc == 0, err
    seg = A.read_aem(folder / "o.aem").segments[0]
    assert seg.frame_a == "LVLH"
    assert np.array_equal(seg.q, orbatt.open_dataset(nc, load=True)["q_orbital"].values)


def test_export_refuses_to_replace_a_file_that_is_not_an_orbatt_aem(result, cli):
    folder, nc, _ = result
    other = folder / "notes.aem"
    other.write_text("my notes\n")
    rc, _, err = cli("export", nc, "--aem", other, cwd=folder)
    assert_one_line_refusal(rc, err, "notes.aem", "not an orbatt result")
    assert other.read_text() == "my notes\n"
    rc, _, err = cli("export", nc, "--aem", nc, cwd=folder)  # the result being read
    assert_one_line_refusal(rc, err, "r.nc")
    assert orbatt.open_dataset(nc, load=True)["q"].size
    rc, _, err = cli("export", nc, "--aem", folder / "missing" / "x.aem", cwd=folder)
    assert_one_line_refusal(rc, err, "does not exist")


@pytest.mark.parametrize("case", ["no-epoch", "same-as-o", "scenario", "folder"])
def test_run_refuses_a_bad_aem_before_the_run(case, tmp_path, cli, monkeypatch):
    import orbatt.scenario.load as load

    def never(*a, **k):
        raise AssertionError("the run started")

    monkeypatch.setattr(load, "propagate", never)
    src = scenario(tmp_path, epoch=case != "no-epoch")
    aem = {"no-epoch": tmp_path / "a.aem", "same-as-o": tmp_path / "r.nc", "scenario": src,
           "folder": tmp_path}[case]
    rc, _, err = cli("run", src, "-o", tmp_path / "r.nc", "--aem", aem, cwd=tmp_path)
    assert_one_line_refusal(rc, err, {"no-epoch": "epoch", "same-as-o": "NetCDF output", "scenario": "kep.toml",
                                      "folder": "folder"}[case])
    assert src.read_text().startswith("# Arribas")

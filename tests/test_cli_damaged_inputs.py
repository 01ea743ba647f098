"""Clean refusals instead of catch-alls (issue 34 item 4): ``--aem`` on a binary asteroid, a
damaged global attribute (truncated JSON, a non-integer ``integration_complete``), time units
that are not a date, and a folder or FIFO given as input: exit 2 and one line naming the key
(``info``, ``plot``, ``export``, ``run``), :class:`InputError` from :func:`orbatt.open_dataset`."""
import os
import re
import shutil
import threading
from pathlib import Path

import pytest

import orbatt
from orbatt.cli import main
from orbatt.errors import InputError

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


@pytest.fixture
def cli(capsys, monkeypatch):
    def run(*args, cwd):
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        rc = main([str(a) for a in args])
        return rc, capsys.readouterr().err

    return run


def _refused(rc, err, *words):
    assert rc == 2, (rc, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("orbatt: error: "), err
    for w in words:
        assert w in lines[0], (w, err)
    assert "unexpected failure" not in err


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    folder = tmp_path_factory.mktemp("good")
    text = re.sub(r"^t_end = .*$", "t_end = 2", (SCEN / "paper-torque-free.toml").read_text(), flags=re.M)
    (folder / "s.toml").write_text(text)
    out = folder / "good.nc"
    orbatt.load_scenario(folder / "s.toml").run().orbatt.to_netcdf(out)
    return out


def _damaged(good, folder, edit):
    netCDF4 = pytest.importorskip("netCDF4")
    path = folder / "damaged.nc"
    shutil.copyfile(good, path)
    with netCDF4.Dataset(path, "a") as f:
        edit(f)
    return path


DAMAGES = {
    "method_settings": (lambda f: f.setncattr("method_settings", '{"rtol": 1e-12, "at'), "method_settings"),
    "integration_stats": (lambda f: f.setncattr("integration_stats", "[1, 2]"), "integration_stats"),
    "integration_complete": (lambda f: f.setncattr("integration_complete", "yes"), "integration_complete"),
    "integration_complete_2": (lambda f: f.setncattr("integration_complete", 2), "integration_complete"),
    "time_units": (lambda f: f.variables["time"].setncattr("units", "seconds since notadate"), "notadate"),
}


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_attribute_is_named(damage, good, tmp_path, cli):
    edit, key = DAMAGES[damage]
    path = _damaged(good, tmp_path, edit)
    for args in (("info", path), ("plot", path, "-o", tmp_path / "figs"), ("export", path, "--aem", "x.aem")):
        rc, err = cli(*args, cwd=tmp_path)
        _refused(rc, err, key, "damaged.nc")
    assert not (tmp_path / "x.aem").exists() and not list(tmp_path.glob("figs/*.png"))
    with pytest.raises(InputError, match=re.escape(key)):
        orbatt.open_dataset(path)


def test_aem_of_a_binary_is_refused_before_the_run(tmp_path, cli):
    rc, err = cli("run", "didymos-dimorphos", "-o", "b.nc", "--aem", "b.aem", cwd=tmp_path)
    _refused(rc, err, "--aem:", "binary")
    assert not list(tmp_path.iterdir())


def test_a_folder_or_fifo_given_as_input_is_named(good, tmp_path, cli):
    (tmp_path / "folder.nc").mkdir()
    fifo = tmp_path / "pipe.nc"
    os.mkfifo(fifo)
    broken = tmp_path / "broken.nc"
    broken.symlink_to("nowhere.nc")
    for name, what in (("folder.nc", "is a folder"), ("pipe.nc", "is a FIFO"), ("broken.nc", "is a broken symbolic link")):
        for args in (("info", name), ("plot", name, "-o", "figs"), ("export", name, "--aem", "x.aem")):
            rc, err = cli(*args, cwd=tmp_path)
            _refused(rc, err, f"file: {name!r} {what}")
        with pytest.raises(InputError, match=what):
            orbatt.open_dataset(tmp_path / name)  # a FIFO is not opened (it would block)
    for name, what in (("folder.nc", "is a folder"), ("pipe.nc", "is a FIFO")):
        rc, err = cli("run", name, cwd=tmp_path)
        _refused(rc, err, what)
    rc, err = cli("info", "missing.nc", cwd=tmp_path)
    _refused(rc, err, "does not exist")


def test_a_fifo_never_blocks_open_dataset(tmp_path):
    fifo = tmp_path / "p.nc"
    os.mkfifo(fifo)
    done = []

    def target():
        try:
            orbatt.open_dataset(fifo)
        except InputError as exc:
            done.append(str(exc))

    t = threading.Thread(target=target, daemon=True)
    t.start()
    t.join(30)
    assert done and "FIFO" in done[0]


def test_a_small_file_declaring_1e8_samples_is_refused_without_reading_them(good, tmp_path, cli):
    import time

    netCDF4 = pytest.importorskip("netCDF4")
    path = tmp_path / "sparse.nc"
    shutil.copyfile(good, path)
    with netCDF4.Dataset(path, "a") as f:  # one value at sample 1e8: the chunks between are never written
        f.set_auto_maskandscale(False)
        f.variables["time"][10**8 - 1] = 1e9
    assert path.stat().st_size < 2**20
    t0 = time.monotonic()
    for args in (("info", path), ("plot", path, "-o", tmp_path / "figs"), ("export", path, "--aem", "x.aem")):
        rc, err = cli(*args, cwd=tmp_path)
        _refused(rc, err, "sparse.nc", "declares 100000000 samples")
    with pytest.raises(InputError, match="data are missing"):
        orbatt.open_dataset(path)
    assert time.monotonic() - t0 < 30


def test_values_the_machine_cannot_hold_are_refused_before_loading(good, tmp_path, cli, monkeypatch):
    from orbatt.dataset import file_checks

    monkeypatch.setattr(file_checks, "available_memory", lambda: 10_000)  # a 10 kB machine
    with pytest.raises(InputError, match=r"more than this machine can hold \(1e-05 GB available\)"):
        orbatt.open_dataset(good, load=True)
    assert orbatt.open_dataset(good)["q"].shape[0] == 101  # lazily: opened
    rc, err = cli("info", good, cwd=tmp_path)
    _refused(rc, err, "good.nc", "samples", "more than this machine can hold")

"""Output paths and atomic writes (issue 14 §1): names derived from ``name``, paths checked
before a run, the temporary file beside the target, Ctrl-C held back during a write."""
import os
import signal
import stat
import threading

import numpy as np
import pytest
import xarray as xr

from orbatt import dataset as D
from orbatt.dataset import netcdf
from orbatt.errors import InputError

from dataset_support import assert_bitwise_identical


def _temporaries(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(D.TEMP_PREFIX))


# ------------------------------------------------------------------------------------------
# names
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["run", "paper-torque-free", "a..b", "café 2", "x" * 200])
def test_plain_names_are_kept(name):
    assert D.file_name(name, ".nc") == name + ".nc"


@pytest.mark.parametrize("name,match", [
    ("victim.toml\u0000", "control character"), ("a\nb", "control character"), ("a\x7fb", "control character"),
    ("../../escaped", "path separator"), ("/tmp/abs", "path separator"), ("a/b", "path separator"),
    ("a\\b", "path separator"), ("..", "starts with '.'"), (".", "starts with '.'"), (".hidden", "starts with '.'"),
    ("", "cannot name a file"), ("   ", "cannot name a file"), ("x" * 260, "too long"),
])
def test_unsafe_names_are_refused_naming_name(name, match):
    with pytest.raises(InputError, match=match) as err:
        D.file_name(name, ".nc")
    assert str(err.value).startswith("name: ")


def test_long_name_counts_the_suffix():
    """And the temporary's decoration (.tmp-NAME.PID.HEX, 25 bytes at most): the file must fit
    in 255 bytes through its temporary name too."""
    D.file_name("x" * 227, ".nc")
    with pytest.raises(InputError, match="too long"):
        D.file_name("x" * 227, "-attitude.png")
    with pytest.raises(InputError, match="too long"):
        D.file_name("x" * 250, ".nc")


# ------------------------------------------------------------------------------------------
# output paths
# ------------------------------------------------------------------------------------------
def test_new_file_in_a_writable_folder_is_accepted(tmp_path):
    assert D.check_output_path(tmp_path / "new.nc") == tmp_path / "new.nc"
    assert _temporaries(tmp_path) == []  # the write probe is gone


def test_earlier_result_may_be_overwritten(free_ds, tmp_path):
    out = tmp_path / "old.nc"
    D.write_netcdf(free_ds, out)
    assert D.is_orbatt_result(out)
    assert D.check_output_path(out) == out


@pytest.mark.parametrize("content", [b"name = 'x'\n", b"", b"\x89HDF\r\n\x1a\ngarbage"])
def test_other_files_are_refused_naming_o(tmp_path, content):
    other = tmp_path / "other.nc"
    other.write_bytes(content)
    assert not D.is_orbatt_result(other)
    with pytest.raises(InputError, match="not an orbatt result") as err:
        D.check_output_path(other)
    assert str(err.value).startswith("-o: ")
    assert other.read_bytes() == content


def test_netcdf_of_another_program_is_refused(tmp_path):
    other = tmp_path / "plain.nc"
    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(other, engine=D.check_engine(None))
    assert not D.is_orbatt_result(other)
    with pytest.raises(InputError, match="not an orbatt result"):
        D.check_output_path(other)


def test_unusable_paths_are_refused(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        D.check_output_path(tmp_path / "missing" / "x.nc")
    with pytest.raises(InputError, match="is a folder"):
        D.check_output_path(tmp_path)
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a folder"):
        D.check_output_path(tmp_path / "file" / "x.nc")
    with pytest.raises(InputError, match="control character"):
        D.check_output_path(str(tmp_path / "x\x00.nc"))
    with pytest.raises(InputError, match="^name: "):
        D.check_output_path(tmp_path, what="name")


def test_read_only_folder_is_refused(tmp_path):
    if os.geteuid() == 0:  # root writes in a mode-555 folder: take a read-only file system
        folder = "/proc"
    else:
        folder = tmp_path / "ro"
        folder.mkdir()
        folder.chmod(0o555)
    try:
        with pytest.raises(InputError, match="cannot write in the folder"):
            D.check_output_path(os.path.join(folder, "x.nc"))
    finally:
        if folder != "/proc":
            folder.chmod(0o755)


def test_zarr_store_of_orbatt_only_with_zarr(tmp_path):
    store = tmp_path / "out.zarr"
    store.mkdir()
    (store / "zarr.json").write_text('{"attributes": {"orbatt_version": "0.1.0"}}')
    assert D.is_orbatt_result(store)
    assert D.check_output_path(store, zarr=True) == store
    with pytest.raises(InputError, match="is a folder"):
        D.check_output_path(store)
    other = tmp_path / "other.zarr"
    other.mkdir()
    (other / "zarr.json").write_text('{"attributes": {}}')
    with pytest.raises(InputError, match="not an orbatt result"):
        D.check_output_path(other, zarr=True)


# ------------------------------------------------------------------------------------------
# atomic writes
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("writer", ["direct", "xarray"])
def test_failed_write_keeps_the_old_file_and_no_temporary(free_ds, tmp_path, monkeypatch, writer):
    out = tmp_path / "r.nc"
    D.write_netcdf(free_ds, out)
    before = out.read_bytes()

    def check(path):
        assert os.path.basename(path).startswith(D.TEMP_PREFIX + "r.nc.")
        assert os.path.dirname(os.path.abspath(path)) == str(tmp_path)

    if writer == "direct":  # orbatt's own netCDF4 writer (a run's plain arrays)
        real = netcdf.write_content

        def half_then_fail(path, *a, **k):
            check(path)
            real(path, *a, **k)
            raise OSError("disk full")

        monkeypatch.setattr(netcdf, "write_content", half_then_fail)
    else:  # xarray's, for what the direct writer does not cover
        real = xr.Dataset.to_netcdf

        def half_then_fail(self, path, *a, **k):
            check(path)
            real(self, path, *a, **k)
            raise OSError("disk full")

        monkeypatch.setattr(netcdf, "writable", lambda *a: False)
        monkeypatch.setattr(xr.Dataset, "to_netcdf", half_then_fail)
    with pytest.raises(OSError, match="disk full"):
        D.write_netcdf(free_ds, out)
    assert out.read_bytes() == before
    assert _temporaries(tmp_path) == []


def test_replacing_keeps_the_mode_of_the_old_file(free_ds, tmp_path):
    out = tmp_path / "r.nc"
    D.write_netcdf(free_ds, out)
    out.chmod(0o640)
    D.write_netcdf(free_ds, out)
    assert stat.S_IMODE(out.stat().st_mode) == 0o640
    assert_bitwise_identical(free_ds, D.open_dataset(out, load=True))


def test_ctrl_c_during_the_write_is_held_back(free_ds, tmp_path, monkeypatch):
    """SIGINT in the middle of the write: the write finishes (no KeyboardInterrupt inside the
    NetCDF libraries, whose lock it could leave held), the file is complete, no temporary file
    is left, and the interrupt comes afterwards."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals are handled in the main thread only")
    out = tmp_path / "r.nc"
    real = netcdf.write_content  # the writer of a run's arrays (orbatt.dataset.netcdf_direct)
    seen = []

    def interrupted(path, *a, **k):
        os.kill(os.getpid(), signal.SIGINT)
        seen.append(os.path.basename(path))
        return real(path, *a, **k)

    monkeypatch.setattr(netcdf, "write_content", interrupted)
    with pytest.raises(KeyboardInterrupt):
        D.write_netcdf(free_ds, out)
    assert seen and seen[0].startswith(D.TEMP_PREFIX)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert _temporaries(tmp_path) == []
    assert_bitwise_identical(free_ds, D.open_dataset(out, load=True))

"""No data loss through links, the API or appends (issue 34 item 4): ``-o`` (and ``--aem``, a
sweep's output) through a symbolic link is refused, the link and the file it points to kept;
``ds.orbatt.to_netcdf`` and ``write_netcdf`` refuse what the CLI refuses (a user's file, a
folder, a link) with the CLI's own check; ``write_netcdf(..., append=True)`` refuses the samples
of another run (another inertia, the scenario text) and variables in other units, naming what
differs."""
import os
import re
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt import dataset as D
from orbatt.cli import main
from orbatt.errors import InputError

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


def _scenario(folder, *, inertia=None, file="s.toml"):
    text = re.sub(r"^t_end = .*$", "t_end = 2", (SCEN / "paper-torque-free.toml").read_text(), flags=re.M)
    if inertia is not None:
        text = re.sub(r"^inertia = .*$", f"inertia = {inertia}", text, flags=re.M)
    path = folder / file
    path.write_text(text)
    return path


def _run(inertia=None):
    """The result of the short torque-free run (another inertia if given)."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        return orbatt.load_scenario(_scenario(Path(d), inertia=inertia)).run()


@pytest.fixture(scope="module")
def run_ds():
    return _run()


@pytest.fixture
def cli(capsys, monkeypatch):
    def run(*args, cwd):
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        rc = main([str(a) for a in args])
        return rc, capsys.readouterr().err

    return run


def _refused(rc, err, what):
    assert rc == 2, (rc, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"orbatt: error: {what}: "), err


# ------------------------------------------------------------------------------------------
# symbolic links
# ------------------------------------------------------------------------------------------
def test_output_through_a_link_to_an_earlier_result_is_refused(tmp_path, cli, run_ds):
    earlier = tmp_path / "earlier.nc"
    D.write_netcdf(run_ds, earlier)
    before = earlier.read_bytes()
    link = tmp_path / "latest.nc"
    link.symlink_to(earlier.name)
    path = _scenario(tmp_path)
    for command in ("run", "sweep"):
        rc, err = cli(command, path, "-o", link, cwd=tmp_path)
        _refused(rc, err, "-o")
        assert "symbolic link" in err
    assert link.is_symlink() and os.readlink(link) == earlier.name
    assert earlier.read_bytes() == before
    # a dangling link too (the rename would put a file where it is)
    dangling = tmp_path / "dangling.nc"
    dangling.symlink_to("nowhere.nc")
    rc, err = cli("run", path, "-o", dangling, cwd=tmp_path)
    _refused(rc, err, "-o")
    assert dangling.is_symlink() and not (tmp_path / "nowhere.nc").exists()


def test_aem_and_api_refuse_links(tmp_path, run_ds, cli):
    earlier = tmp_path / "earlier.nc"
    D.write_netcdf(run_ds, earlier)
    before = earlier.read_bytes()
    link = tmp_path / "link.nc"
    link.symlink_to(earlier)
    for write in (lambda: run_ds.orbatt.to_netcdf(link), lambda: D.write_netcdf(run_ds, link),
                  lambda: D.write_netcdf(run_ds, link, append=True)):
        with pytest.raises(InputError, match="symbolic link"):
            write()
    assert link.is_symlink() and earlier.read_bytes() == before
    # --aem of export, and a sweep's output given to the API
    aem_link = tmp_path / "a.aem"
    aem_link.symlink_to(tmp_path / "target.aem")
    rc, err = cli("export", earlier, "--aem", aem_link, cwd=tmp_path)
    _refused(rc, err, "--aem")
    assert aem_link.is_symlink()
    from orbatt.sweep import run_sweep, Sweep
    from orbatt.scenario import Scenario, parse

    text = _scenario(tmp_path).read_text() + '\n[sweep]\n[sweep.parameters]\ninertia1 = { values = [1.25] }\n'
    with pytest.raises(InputError, match=r"output: .*symbolic link"):
        run_sweep(Sweep(Scenario(parse(text, "s.toml"))), link)
    assert link.is_symlink() and earlier.read_bytes() == before


# ------------------------------------------------------------------------------------------
# the API refuses what the CLI refuses
# ------------------------------------------------------------------------------------------
def test_to_netcdf_refuses_a_file_that_is_not_a_result(tmp_path, run_ds):
    notes = tmp_path / "notes.nc"
    notes.write_text("my notes\n")
    with pytest.raises(InputError, match=r"to_netcdf: .*notes\.nc.* exists and is not an orbatt result"):
        run_ds.orbatt.to_netcdf(notes)
    for append in (False, True):
        with pytest.raises(InputError, match=r"write_netcdf: .*not an orbatt result"):
            D.write_netcdf(run_ds, notes, append=append)
    assert notes.read_text() == "my notes\n"
    # another program's NetCDF file, a folder, a missing folder: as the CLI says
    import xarray as xr

    other = tmp_path / "other.nc"
    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(other, engine=D.check_engine(None))
    size = other.stat().st_size
    with pytest.raises(InputError, match="not an orbatt result"):
        run_ds.orbatt.to_netcdf(other)
    assert other.stat().st_size == size
    with pytest.raises(InputError, match="is a folder"):
        run_ds.orbatt.to_netcdf(tmp_path)
    with pytest.raises(InputError, match="does not exist"):
        run_ds.orbatt.to_netcdf(tmp_path / "missing" / "r.nc")
    with pytest.raises(InputError, match=r"to_aem: .*not an orbatt result"):
        run_ds.orbatt.to_aem(notes)
    # a new file, then an earlier result, are written
    out = tmp_path / "r.nc"
    run_ds.orbatt.to_netcdf(out)
    run_ds.orbatt.to_netcdf(out)
    assert D.is_orbatt_result(out)


def test_the_check_is_public_and_shared():
    from orbatt.dataset import netcdf, paths

    assert D.check_output_path is paths.check_output_path
    assert paths.check_replaceable is netcdf.check_replaceable
    assert D.is_orbatt_result is netcdf.is_orbatt_result


# ------------------------------------------------------------------------------------------
# appends of another run
# ------------------------------------------------------------------------------------------
def test_append_refuses_another_scenario_and_other_units(tmp_path, run_ds):
    path = tmp_path / "run.nc"
    D.write_netcdf(run_ds.isel(time=slice(0, 50)), path)
    size = path.stat().st_size
    # another inertia: the samples of another scenario
    other = _run(inertia="[1.3, 1.0, 0.75]")
    with pytest.raises(InputError, match=r"another run: inertia is \[1\.25, 1\. *, 0\.75\] in .*run\.nc and "
                                         r"\[1\.3 *, 1\. *, 0\.75\] in the new samples"):
        D.write_netcdf(other.isel(time=slice(49, None)), path, append=True)
    # the same inertia, another scenario text
    again = run_ds.isel(time=slice(49, None)).copy()
    again.attrs["scenario"] = again.attrs["scenario"].replace("rtol = 1e-12", "rtol = 1e-11")
    with pytest.raises(InputError, match=r"global attribute 'scenario' differs"):
        D.write_netcdf(again, path, append=True)
    # a variable in other units
    later = run_ds.isel(time=slice(49, None)).copy()
    later["energy"] = later["energy"].copy()
    later["energy"].attrs["units"] = "J"
    with pytest.raises(InputError, match=r"append: energy is in '1' in .*run\.nc and in 'J' in the new samples"):
        D.write_netcdf(later, path, append=True)
    assert path.stat().st_size == size
    # the same run's later samples are appended
    D.write_netcdf(run_ds.isel(time=slice(49, None)), path, append=True)
    back = orbatt.open_dataset(path, load=True)
    assert np.array_equal(back["q"].values, run_ds["q"].values)

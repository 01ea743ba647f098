"""Fuzz round 4 (issue 34, item 4, "Also"): each reproducer refused before anything is
computed, exit 2 and one line naming the key, or run as its line in the issue says (the
binary reproducers: tests/binary/test_binary_round4.py)."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from orbatt.scenario.binary_schema import BINARY_TABLES, IMPULSE_KEYS
from orbatt.scenario.reference import markdown, undocumented_keys

SCEN = Path(__file__).resolve().parent.parent / "scenarios"
DISPERSION = (SCEN / "gg-leo-dispersion.toml").read_text()
DD = (SCEN / "didymos-dimorphos.toml").read_text()
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")


def edit(text, *pairs):
    for old, new in zip(pairs[::2], pairs[1::2]):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


def cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=600)


def refused(r, *names):
    """Exit 2, one line ``orbatt: error: ...`` (warnings aside) naming each of ``names``."""
    lines = [ln for ln in r.stderr.splitlines() if ln.strip() and not ln.startswith("orbatt: warning:")]
    assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith("orbatt: error: "), (r.returncode, r.stderr)
    assert "Traceback" not in r.stderr
    for name in names:
        assert name in lines[0], (name, lines[0])
    return lines[0]


def sweep(parameters, raan='"0 deg"'):
    """The dispersion study over one orbit, ``parameters`` its only ones, ``[orbit] raan`` given."""
    text = DISPERSION[:DISPERSION.index("[sweep.parameters]")] + f"[sweep.parameters]\n{parameters}\n"
    return edit(text, "samples = 2000\n", "", 'on_invalid = "resample"\n', "", 't_end = "300 orbits"',
                't_end = "1 orbits"', 'raan = "0 deg"', f"raan = {raan}")


def kepler(folder, extra=""):
    """The paper's Keplerian case over 300 s with an epoch (an AEM can be written)."""
    text = re.sub(r"^t_end = .*$", 't_end = "300 s"', (SCEN / "paper-keplerian.toml").read_text(), flags=re.M)
    text = edit(text, 'true_anomaly = "0 deg"\n', 'true_anomaly = "0 deg"\nepoch = "2024-01-01T00:00:00"\n') + extra
    p = folder / "kep.toml"
    p.write_text(text)
    return p


# ---------------------------------------------------------------------------------------------
# [sweep]


@pytest.mark.parametrize("a,b", [("inertia1", '"body.inertia[0]"'), ('"body.inertia[0]"', "inertia1"),
                                 ("orbit_raan", '"orbit.raan"'), ('"initial.omega[0]"', '"initial.omega[00]"')])
def test_a_key_varied_under_two_spellings_is_refused_naming_both(tmp_path, a, b):
    unit = '"0 deg"' if "raan" in a else '"0 rad/s"' if "omega" in a else '"12 kg m2"'
    unit2 = '"10 deg"' if "raan" in a else '"0.001 rad/s"' if "omega" in a else '"11 kg m2"'
    p = tmp_path / "twice.toml"
    p.write_text(sweep(f"{a} = {{ values = [{unit}, {unit2}] }}\n{b} = {{ values = [{unit}, {unit2}] }}"))
    refused(cli("sweep", p, "-o", tmp_path / "o.nc", cwd=tmp_path), "twice.toml", a.strip('"'), b.strip('"'),
            "same key")


def test_an_angle_written_as_a_plain_zero_is_swept_with_angle_values(tmp_path):
    import xarray as xr

    p = tmp_path / "zero.toml"
    p.write_text(sweep('"orbit.raan" = { values = ["0 deg", "10 deg"] }', raan="0"))
    r = cli("sweep", p, "-o", tmp_path / "z.nc", "--scheduler", "synchronous", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with xr.open_dataset(tmp_path / "z.nc") as ds:
        from astropy import units as u

        assert u.Unit(ds["orbit_raan"].attrs["units"]) == u.deg and list(ds["orbit_raan"].values) == [0.0, 10.0]
        assert abs(float(ds["q_final"][0, 0]) - float(ds["q_final"][1, 0])) > 1e-6  # two orbits, two results
    # a unit that is not the key's is refused by the cases' own check, naming the key
    p.write_text(sweep('"orbit.raan" = { values = ["0 kg", "10 kg"] }', raan="0"))
    refused(cli("sweep", p, "-o", tmp_path / "k.nc", cwd=tmp_path), "zero.toml", "orbit.raan")


# ---------------------------------------------------------------------------------------------
# export


@pytest.fixture(scope="module")
def ensemble(tmp_path_factory):
    """A sweep of two cases with their trajectories and an epoch (export writes one case)."""
    folder = tmp_path_factory.mktemp("ens")
    p = kepler(folder, '\n[sweep]\nseed = 1\noutputs = ["trajectory"]\n\n[sweep.parameters]\n'
                       'omega1 = { values = ["0 rad/s", "0.001 rad/s"] }\n')
    r = cli("sweep", p, "-o", folder / "ens.nc", "--scheduler", "synchronous", "--quiet", cwd=folder)
    assert r.returncode == 0, r.stderr
    return folder, folder / "ens.nc"


@pytest.mark.parametrize("case", ["2", "-1", "99999999999"])
def test_export_case_out_of_range_is_refused(ensemble, case):
    folder, nc = ensemble
    refused(cli("export", nc, "--aem", folder / "x.aem", "--case", case, cwd=folder), "case", case, "0 .. 1")
    assert not (folder / "x.aem").exists()
    r = cli("export", nc, "--aem", folder / f"ok{case}.aem", "--case", "1", cwd=folder)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("frame", ["EME2000\nMETA_STOP", "EME2000\r", "ICRF\x7f", "GCRF\x1b[31m"])
def test_export_ref_frame_with_a_control_character_is_refused(ensemble, frame):
    folder, nc = ensemble
    refused(cli("export", nc, "--aem", folder / "f.aem", "--case", "0", "--ref-frame", frame, cwd=folder),
            "--ref-frame", "control character")
    assert not (folder / "f.aem").exists()
    import xarray as xr

    from orbatt import write_aem
    from orbatt.errors import InputError

    with xr.open_dataset(nc) as ds, pytest.raises(InputError, match="ref_frame_a: .* control character"):
        write_aem(ds, case=0, ref_frame_a=frame)  # the API refuses it too: no second META_STOP


# ---------------------------------------------------------------------------------------------
# output names


def test_a_name_too_long_for_the_file_system_is_refused_before_the_run(tmp_path):
    """A name whose file fits in 255 bytes but whose temporary (.tmp-NAME.PID.HEX) does not."""
    p = kepler(tmp_path)
    text = p.read_text()
    p.write_text(re.sub(r'^name = .*$', f'name = "{"n" * 240}"', text, flags=re.M))
    refused(cli("run", p, "--quiet", cwd=tmp_path), "name", "too long")
    p.write_text(text)
    refused(cli("run", p, "-o", tmp_path / ("o" * 240 + ".nc"), "--quiet", cwd=tmp_path), "-o", "too long")
    refused(cli("run", p, "-o", tmp_path / "ok.nc", "--aem", tmp_path / ("a" * 240 + ".aem"), "--quiet",
                cwd=tmp_path), "--aem", "too long")
    assert sorted(os.listdir(tmp_path)) == ["kep.toml"]


def test_output_where_a_figure_goes_is_refused_before_the_run(tmp_path):
    p = kepler(tmp_path)
    figs = tmp_path / "figs"
    figs.mkdir()
    refused(cli("run", p, "--plot", figs, "-o", figs / "paper-keplerian-pointing.png", "--quiet", cwd=tmp_path),
            "-o", "pointing figure")
    refused(cli("run", p, "--plot", figs, "-o", tmp_path / "r.nc", "--aem", figs / "paper-keplerian-drift.png",
                "--quiet", cwd=tmp_path), "--aem", "drift figure")
    assert sorted(os.listdir(tmp_path)) == ["figs", "kep.toml"] and not os.listdir(figs)


def test_a_concurrent_sweep_of_one_output_is_refused_at_once(tmp_path):
    """While one ``orbatt sweep -o OUT`` holds OUT (computing, merging), a second one (a
    concurrent --resume) is refused in one line; the lock goes with the first run."""
    from orbatt.cli import _sweep_lock

    p = tmp_path / "sw.toml"
    p.write_text(sweep('"initial.omega[0]" = { values = ["0 rad/s", "0.001 rad/s"] }'))
    out = tmp_path / "sw.nc"
    with _sweep_lock(out):  # as a running sweep holds it
        assert (tmp_path / ".sw.nc.lock").exists()
        for extra in (("--resume",), ()):
            refused(cli("sweep", p, "-o", out, "--scheduler", "synchronous", *extra, cwd=tmp_path), "-o",
                    "another orbatt sweep is writing")
    r = cli("sweep", p, "-o", out, "--scheduler", "synchronous", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["sw.nc", "sw.toml"]


# ---------------------------------------------------------------------------------------------
# impulses and the reference


@pytest.mark.parametrize("dv", ['"299792.458 km/s"', '"1e9 m/s"', '"-101 km/s"'])
def test_an_impulse_has_a_physical_range(tmp_path, dv):
    p = tmp_path / "dv.toml"
    p.write_text(edit(DD, 'delta_v = ["0 m/s", "-2.7e-3 m/s", "0 m/s"]', f'delta_v = ["0 m/s", {dv}, "0 m/s"]'))
    refused(cli("run", p, "-o", tmp_path / "dv.nc", cwd=tmp_path), "dv.toml", "[[orbit.impulses]] 0 delta_v[1]",
            "[-100, 100] km s^-1")


def test_the_reference_describes_every_binary_key():
    assert undocumented_keys() == []
    text = markdown()
    assert 'provider = "coupled"' in text
    for table, keys in BINARY_TABLES.items():
        part = text.split(f"### `[{table}]` (binary)", 1)[1].split("###", 1)[0]
        for k in keys:
            assert f"| `{k}` |" in part, (table, k)
    part = text.split("#### `[[orbit.impulses]]` (binary)", 1)[1]
    for k in IMPULSE_KEYS:
        assert f"| `{k}` |" in part

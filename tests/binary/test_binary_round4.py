"""Fuzz round 4 (issue 34, item 4) on binaries: Ctrl-C and progress as for a single body,
impulses at one instant, contact between outputs, the orbital frame of a radial orbit, and the
sweep's refusals named in the scenario file."""
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_binary_physics import P_ORBIT, binary_system, tilted_state
from test_binary_scenario import CONTRACT, DD, edit

from orbatt.binary import Impulse, propagate_binary
from orbatt.binary import propagate as bp
from orbatt.binary.propagate import apply_impulse
from orbatt.errors import IntegrationError
from orbatt.progress import ProgressInfo
from orbatt.scenario import parse
from orbatt.scenario.binary_scenario import BinaryScenario

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
MC = (SCEN / "didymos-dimorphos-montecarlo.toml").read_text()
SPLIT = ('method = "dop853"\nrtol = 1e-12\natol = 1e-16', 'method = "splitting"\nstep = "100 s"')


def cli(*args, cwd, timeout=300):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)


def one_line_refusal(r, *names):
    """Exit 2 and one line ``orbatt: error: ...`` naming each of ``names``."""
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("orbatt: error: "), r.stderr
    assert "Traceback" not in r.stderr
    for name in names:
        assert name in lines[0], (name, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def case():
    s = binary_system(rigid=True)
    return s, tilted_state(s)


# ---------------------------------------------------------------------------------------------
# Ctrl-C and progress


def test_call_length_does_not_change_a_bit(case, monkeypatch):
    """The compiled loops return every ~0.25 s (progress, Ctrl-C); where they return does not
    change the result: calls of a few steps give the same bits as one long call."""
    s, y0 = case
    t = np.linspace(0.0, 2 * P_ORBIT, 41)
    h = (t[1] - t[0]) / 8
    imp = [Impulse(t[10], (1e-6, -2e-6, 5e-7)), Impulse(t[25] + 3 * h, (0.0, 1e-6, 0.0))]  # one between outputs
    kw = {"dop853": {}, "vern98": {}, "splitting": {"step": h}}
    long = {m: propagate_binary(s, y0, t, method=m, impulses=imp, **k) for m, k in kw.items()}
    monkeypatch.setattr(bp, "CHUNK_SECONDS", 0.0)  # the budget shrinks to a step per call
    calls = []
    for m, k in kw.items():
        short = propagate_binary(s, y0, t, method=m, impulses=imp, progress=lambda info: calls.append(info), **k)
        assert short.complete and np.array_equal(short.y, long[m].y), m
        assert short.stats["steps"] == long[m].stats["steps"]
    assert len(calls) > 100 and all(isinstance(c, ProgressInfo) for c in calls)
    fr = [c.fraction for c in calls]
    assert fr[-1] == 1.0 and all(0.0 <= f <= 1.0 for f in fr)


@pytest.mark.parametrize("method", ["dop853", "splitting"])
def test_progress_false_and_keyboard_interrupt_keep_what_was_computed(case, monkeypatch, method):
    s, y0 = case
    t = np.linspace(0.0, 4 * P_ORBIT, 401)
    kw = {"step": (t[1] - t[0]) / 4} if method == "splitting" else {}
    full = propagate_binary(s, y0, t, method=method, **kw)
    monkeypatch.setattr(bp, "CHUNK_SECONDS", 0.0)
    for stop in ("false", "interrupt"):
        n = []

        def report(info):
            n.append(info)
            if len(n) == 200:
                if stop == "false":
                    return False
                raise KeyboardInterrupt  # as Ctrl-C raises it between two compiled calls
            return None

        tr = propagate_binary(s, y0, t, method=method, progress=report, **kw)
        assert not tr.complete and 1 < tr.t.size < t.size, (stop, tr.t.size)
        assert tr.settings["stopped"] == ("progress callback" if stop == "false" else "KeyboardInterrupt")
        assert len(n) == 200
        assert np.array_equal(tr.y, full.y[:tr.t.size])  # what was computed, bit for bit


def _long_run(tmp_path, split):
    text = edit(edit(DD, 't_end = "6 d"', 't_end = "20000 d"'), 'output_step = "600 s"', 'output_step = "10 d"')
    if split:
        text = edit(text, *SPLIT)
    p = tmp_path / "long.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("split", [False, True], ids=["dop853", "splitting"])
def test_ctrl_c_stops_a_binary_run_within_a_second_and_keeps_what_it_computed(tmp_path, split):
    """A SIGINT to the process group (a terminal's Ctrl-C) during a long binary run: exit 130
    within about a second, the file holds the outputs computed (integration_complete = 0); the
    run draws a progress bar meanwhile."""
    import xarray as xr

    p = _long_run(tmp_path, split)
    out = tmp_path / "long.nc"
    proc = subprocess.Popen([sys.executable, "-m", "orbatt.cli", "run", p, "-o", out], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True, cwd=tmp_path)
    err = b""
    try:
        t0 = time.monotonic()
        while b"orbatt: [" not in err:  # the progress bar: the run is under way (after its first second)
            assert proc.poll() is None and time.monotonic() - t0 < 240, err.decode()
            if select.select([proc.stderr], [], [], 1.0)[0]:
                err += os.read(proc.stderr.fileno(), 4096)
        time.sleep(0.5)
        sent = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        stdout, rest = proc.communicate(timeout=120)
        waited = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    text = (err + rest).decode()
    assert proc.returncode == 130, text
    assert "Traceback" not in text and "interrupted" in text, text
    assert waited < 10.0, waited  # ~0.3 s of stepping, then the file: not minutes
    with xr.open_dataset(out) as ds:
        assert int(ds.attrs["integration_complete"]) == 0
        assert 2 < ds.sizes["time"] < 2001
        assert json.loads(ds.attrs["method_settings"])["stopped"] == "KeyboardInterrupt"


# ---------------------------------------------------------------------------------------------
# Semantics


@pytest.mark.parametrize("method", ["dop853", "vern98", "splitting"])
def test_impulses_at_one_instant_are_applied_in_order(case, method):
    """Two impulses at the same time: both, in the order given, under every method; the same as
    stopping there, applying them one after the other and starting again."""
    s, y0 = case
    t = np.linspace(0.0, P_ORBIT, 9)
    a, b = (0.0, 0.0, 2e-6), (0.0, -3e-6, 0.0)  # normal (turns the plane) then along-track: order matters
    kw = {"step": (t[1] - t[0]) / 50} if method == "splitting" else {"rtol": 1e-12, "atol": 1e-15}
    both = propagate_binary(s, y0, t, method=method, impulses=[Impulse(t[3], a), Impulse(t[3], b)], **kw)
    swapped = propagate_binary(s, y0, t, method=method, impulses=[Impulse(t[3], b), Impulse(t[3], a)], **kw)
    assert both.complete and both.t.size == t.size
    assert [k["delta_v"] for k in both.settings["impulses"]] == [list(a), list(b)]
    first = propagate_binary(s, y0, t[:4], method=method, **kw)
    y3 = apply_impulse(apply_impulse(first.y[-1], first.c, a), first.c, b)
    rest = propagate_binary(s, y3, t[3:], method=method, **kw)
    assert np.array_equal(both.y[:4], first.y)
    assert np.allclose(both.y[3:, :3], rest.y[:, :3], rtol=0, atol=1e-9)
    assert np.max(np.abs(swapped.y[-1, :3] - both.y[-1, :3])) > 1e-7  # the other order is another orbit


#: a point-mass primary and the contract's secondary (contact at 0.0894 km), from the apoapsis
#: (2.32 km) to a periapsis of 0.06 km; outputs only at the apoapsis
PLUNGE = edit(edit(edit(edit(CONTRACT[:CONTRACT.index("[primary]")] + CONTRACT[CONTRACT.index("[potential]"):],
                             'e = 0.02', 'e = 0.9495798319327731'), 'true_anomaly = "0 deg"', 'true_anomaly = "180 deg"'),
                   'output_step = "0.1 orbits"', 'output_step = "1 orbits"'), 'kind = "gravity-gradient"', 'kind = "coupled"')


@pytest.mark.parametrize("method", ['method = "dop853"', 'method = "splitting"\nstep = "0.001 orbits"',
                                    'method = "splitting"\nstep = "0.1 orbits"'])
def test_contact_between_outputs_stops_every_method(method):
    """The periapsis lies inside the contact distance, the outputs at the apoapsis only: every
    method stops at the contact (the splitting checks every step's path, even a coarse one's)."""
    sc = BinaryScenario(parse(edit(PLUNGE, "[integration]\n", f"[integration]\n{method}\n"), "plunge.toml"))
    assert abs(sc.system.contact_distance - 0.0894427) < 1e-6
    with pytest.raises(IntegrationError, match=r"contact .* 0\.0894427 km") as info:
        sc.run()
    import re

    t_contact = float(re.search(r"t = (\S+) s", str(info.value)).group(1))
    assert 0.45 * sc.period < t_contact < 0.75 * sc.period  # near the periapsis, half an orbit on
    ds = info.value.dataset
    assert ds is not None and ds.sizes["time"] == 1 and int(ds.attrs["integration_complete"]) == 0


def test_orbital_frame_of_a_radial_orbit_is_refused(tmp_path):
    text = edit(DD, 'velocity = ["0 km/s", "1.747354701391355e-4 km/s", "3.0500189765412352e-6 km/s"]',
                'velocity = ["1e-5 km/s", "0 km/s", "0 km/s"]')
    p = tmp_path / "radial.toml"
    p.write_text(text)
    line = one_line_refusal(cli("run", p, "-o", tmp_path / "r.nc", cwd=tmp_path), "radial.toml", "[initial] frame")
    assert "parallel" in line
    assert not (tmp_path / "r.nc").exists()
    # frame = "inertial" with the same orbit is a valid (radial, plunging) start
    BinaryScenario(parse(edit(text, "[initial]\nframe = \"orbital\"", "[initial]\nframe = \"inertial\""), "radial.toml"))


def _sweep(tmp_path, parameters, outputs='["final_state"]'):
    text = MC[:MC.index("[sweep]")] + f"[sweep]\nseed = 1\noutputs = {outputs}\n\n[sweep.parameters]\n{parameters}\n"
    text = edit(edit(text, 't_end = "3 d"', 't_end = "1 d"'), 'time = "86400 s"', 'time = "3600 s"')
    p = tmp_path / "sw.toml"
    p.write_text(text)
    return p


def test_sweep_case_inside_the_primary_names_the_scenario_file(tmp_path):
    p = _sweep(tmp_path, '"orbit.position[0]" = { values = ["1.19 km", "0.3 km"] }')
    line = one_line_refusal(cli("sweep", p, "-o", tmp_path / "sw.nc", cwd=tmp_path), "sw.toml: [sweep.parameters]",
                            "case 1", "orbit.position[0] = 0.3 km", "inside the bodies")
    assert line.startswith(f"orbatt: error: {p}: ")


def test_sweep_outputs_as_a_nested_list_is_refused(tmp_path):
    p = _sweep(tmp_path, '"body.mass" = { values = ["4e9 kg", "5e9 kg"] }', outputs='[["final_state"]]')
    one_line_refusal(cli("sweep", p, "-o", tmp_path / "sw.nc", cwd=tmp_path), "sw.toml", "[sweep] outputs",
                     "['final_state']")


def test_an_impulse_on_a_radial_orbit_stops_the_run_keeping_what_was_computed():
    """A radial orbit (r parallel to v) has no along-track or normal direction: the impulse
    stops the run with a message, the outputs before it kept (no NaN state)."""
    import astropy.units as u

    s = binary_system(rigid=False)
    y0 = s.state([1.19, 0.0, 0.0] * u.km, [1e-5, 0.0, 0.0] * u.km / u.s, [1.0, 0.0, 0.0, 0.0],
                 [0.0, 0.0, 0.0] * u.rad / u.s)
    t = np.linspace(0.0, 600.0, 4)
    for kw in ({}, {"method": "splitting", "step": 20.0}):
        with pytest.raises(IntegrationError, match=r"radial orbit .* \(at t = 400 s\)") as info:
            propagate_binary(s, y0, t, impulses=[Impulse(400.0, (0.0, 1e-6, 0.0))], **kw)
        tr = info.value.trajectory
        assert tr.t.tolist() == t[:3].tolist() and np.all(np.isfinite(tr.y)) and not tr.complete

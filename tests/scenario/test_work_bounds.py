"""Nothing runs for minutes on meaningless input (issue 34 item 3): the work estimate
(:func:`orbatt.scenario.build.check_work`) counts the laws' and the wheels' time scales, the
flight software's ticks, the environment tables' samples, the outputs and a sweep's cases, and
refuses before anything is integrated, in one line naming the key; a long run that is meant
(``--yes``, ``[integration] max_steps``) is allowed."""
from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from orbatt.errors import ScenarioError
from orbatt.scenario import load_scenario
from orbatt.scenario.build import LONG_WORK_STEPS, MAX_WORK_STEPS

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
CUBESAT = (SCEN / "cubesat-3u-disturbances.toml").read_text()
WHEELS = (SCEN / "lvlh-hold-wheels.toml").read_text()
HYPERION = (SCEN / "hyperion-chaotic-normalized.toml").read_text()
DISPERSION = (SCEN / "gg-leo-dispersion.toml").read_text()


def edit(text, *pairs):
    for old, new in zip(pairs[::2], pairs[1::2]):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


PD_1E6 = edit(WHEELS, 'kp = "4e-3 N m"', 'kp = "1e6 N m"', 'kd = "8e-2 N m s"', 'kd = "1e6 N m s"',
              't_end = "3 orbits"', 't_end = "300 s"')
TINY = edit(CUBESAT, 'inertia = ["0.0387 kg m2", "0.0387 kg m2", "0.0067 kg m2"]',
            'inertia = ["1e-9 kg m2", "1e-9 kg m2", "1e-9 kg m2"]')
DAYS_1000 = edit(CUBESAT, 't_end = "1 d"', 't_end = "1000 d"')
GM_1E12 = edit(HYPERION, "gm = 1.0", "gm = 1e12", 't_end = "50 orbits"', "t_end = 100.0")
PERIOD_1MS = edit(WHEELS, 'actuator = "wheels"', 'actuator = "wheels"\nperiod = "1 ms"', 't_end = "3 orbits"',
                  't_end = "30 d"', 'output_step = "20 s"', 'output_step = "600 s"')

# (id, scenario text, the key the message must name); each ran for minutes (3.4e7 steps, 5 min,
# for the PD law; the 1000 days sampled NRLMSIS and IGRF for more than 6 min) before
REPRODUCERS = [
    ("PD 1e6 with wheels", PD_1E6, r"\[control\] kd"),
    ("tiny inertia with environment torques", TINY, r"\[body\] inertia"),
    ("1000-day disturbed run", DAYS_1000, r"\[integration\] t_end"),
    ("normalized orbit with gm 1e12", GM_1E12, r"\[orbit\] gm"),
    ("control period 1 ms over 30 d", PERIOD_1MS, r"\[control\] period"),
]


@pytest.mark.parametrize("text,key", [c[1:] for c in REPRODUCERS], ids=[c[0] for c in REPRODUCERS])
def test_meaningless_runs_are_refused_up_front_naming_the_key(tmp_path, text, key):
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError, match=rf"^{tmp_path / 's.toml'}: {key}: .* at least [0-9.e+]+ integration "
                                            r"steps, more than") as info:
        load_scenario(write(tmp_path, text))
    assert "\n" not in str(info.value)
    assert time.perf_counter() - t0 < 10.0


def test_a_period_of_1_ms_over_30_days_is_beyond_max_steps(tmp_path):
    with pytest.raises(ScenarioError, match=r"\[control\] period: the flight software's 2.59e\+09 ticks .* more than "
                                            r"1e\+08 \(hours"):
        load_scenario(write(tmp_path, PERIOD_1MS), yes=True)


def test_a_long_run_says_so_and_runs_when_agreed_to(tmp_path):
    """The PD law's 8e7 steps: refused with the estimate and how to agree; --yes, yes=True or
    [integration] max_steps let it load (a run beyond max_steps never does)."""
    p = write(tmp_path, PD_1E6)
    with pytest.raises(ScenarioError, match=r"at least 7.97e\+07 integration steps, more than 1e\+07: about 80 s or "
                                            r"more of computing; .* \(orbatt run --yes"):
        load_scenario(p)
    assert LONG_WORK_STEPS < load_scenario(p, yes=True).work_steps < MAX_WORK_STEPS
    sc = load_scenario(write(tmp_path, edit(PD_1E6, 'output_step = "20 s"', 'output_step = "20 s"\n'
                                                    "max_steps = 100_000_000"), "m.toml"))
    assert sc.settings["max_steps"] == 100_000_000
    with pytest.raises(ScenarioError, match=r"\[control\] kd: .* more than \[integration\] max_steps = 5e\+07"):
        load_scenario(write(tmp_path, edit(PD_1E6, 'output_step = "20 s"', 'output_step = "20 s"\nmax_steps = 5e7'),
                            "n.toml"))


def cli(*args, timeout=60):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def test_the_cli_refuses_in_one_line_and_exit_2(tmp_path):
    t0 = time.perf_counter()
    r = cli("run", write(tmp_path, DAYS_1000), "-o", tmp_path / "out.nc", "--quiet")
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "[integration] t_end: the environment tables" in lines[0], r.stderr
    assert "--yes" in lines[0] and not (tmp_path / "out.nc").exists()
    assert time.perf_counter() - t0 < 30.0


def test_a_sweep_of_ten_million_cheap_cases_is_refused_before_drawing(tmp_path):
    text = edit(DISPERSION, "samples = 2000", "samples = 10000000", 't_end = "300 orbits"', 't_end = "1 orbits"')
    t0 = time.perf_counter()
    r = cli("sweep", write(tmp_path, text), "-o", tmp_path / "out.nc", "--scheduler", "synchronous", "--quiet")
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "[sweep] samples: 10000000 cases" in lines[0], r.stderr
    assert time.perf_counter() - t0 < 30.0


@pytest.mark.parametrize("path", sorted(SCEN.glob("*.toml")), ids=lambda p: p.stem)
def test_every_shipped_scenario_is_within_the_estimate(path):
    sc = load_scenario(path)
    steps = getattr(sc, "work_steps", None)
    assert steps is None or steps < LONG_WORK_STEPS / 10

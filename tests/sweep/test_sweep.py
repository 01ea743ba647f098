"""Sweeps (issue 7): the [sweep] schema, sampling, reproducibility, and runs on a real
dask.distributed LocalCluster (2 worker processes on 127.0.0.1): >= 1000 cases equal to the
serial ensemble run, a worker killed mid-sweep, an interrupted run resumed."""
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import orbatt
from orbatt.scenario import Scenario, ScenarioError, parse
from orbatt.sweep import PARAMETERS, Sweep, run_sweep

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
pytestmark = pytest.mark.filterwarnings("ignore::orbatt.orbits.base.PeriapsisWarning")
SHIPPED = (SCEN / "gg-leo-dispersion.toml").read_text()
KEPLER = (SCEN / "paper-keplerian.toml").read_text()
TORQUE_FREE = (SCEN / "paper-torque-free.toml").read_text()


def edit(text, old, new, count=1):
    assert text.count(old) == count, old
    return text.replace(old, new)


def short(text=SHIPPED, samples=1000, t_end='"0.1 orbits"', extra=""):
    """The shipped sweep, shortened: ``samples`` cases over ``t_end``."""
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    text = re.sub(r"^samples = .*$", f"samples = {samples}", text, flags=re.M)
    return text + extra


def sweep_of(text, source="test.toml", seed=None):
    return Sweep(Scenario(parse(text, source)), seed=seed)


def assert_same(a, b):
    """Bitwise equal values and coordinates (attributes aside)."""
    xr.testing.assert_equal(a.drop_attrs(deep=False), b.drop_attrs(deep=False))


def sweep_on(base, table):
    return base + "\n[sweep]\n" + table


# ---------------------------------------------------------------------------------------
# schema


def test_shipped_sweep_validates_and_is_big_enough():
    spec = parse(SHIPPED, "gg-leo-dispersion.toml")
    sw = spec.sweep
    assert spec.name == "gg-leo-dispersion" and spec.description
    assert sw.cases >= 100 and sw.seed is not None
    assert list(sw.parameters) == [k for k in PARAMETERS if k in sw.parameters]  # canonical order
    assert set(sw.outputs) == {"final_state", "max_pointing_error", "tumbling", "final_energy_error"}
    assert sw.energy == "jacobi"


KEP_SWEEP = '[sweep.parameters]\ninertia1 = { distribution = "normal", std = "4 kg km2" }\n'
BAD = [
    ("unknown parameter", "samples = 3\n[sweep.parameters]\ninertia4 = { values = [\"1 kg km2\"] }\n",
     r"\[sweep.parameters\] inertia4: unknown parameter; give a scenario path such as \"control.gain\" .* or one of "
     r"inertia1"),
    ("unknown sweep key", "samples = 3\nseeds = 3\n" + KEP_SWEEP, r"\[sweep\] seeds: unknown key"),
    ("unknown distribution key", 'samples = 3\n[sweep.parameters]\ninertia1 = { distribution = "normal", sd = 1 }\n',
     r"\[sweep.parameters.inertia1\] sd: unknown key for a normal distribution"),
    ("unknown distribution", 'samples = 3\n[sweep.parameters]\ninertia1 = { distribution = "cauchy" }\n',
     r"\[sweep.parameters.inertia1\] distribution: 'cauchy' is not one of"),
    ("wrong dimension", 'samples = 3\n[sweep.parameters]\ninertia1 = { distribution = "normal", std = "3 km" }\n',
     r"\[sweep.parameters.inertia1\] std: '3 km' has the wrong dimension"),
    ("uniform below a physical limit",
     'samples = 3\n[sweep.parameters]\ninertia1 = { distribution = "uniform", low = "-1 kg km2", high = "5 kg km2" }\n',
     r"inertia1\] low: '-1 kg km2' leaves the physical range \(0, inf\)"),
    ("eccentricity range", 'samples = 3\n[sweep.parameters]\norbit_e = { distribution = "truncnormal", std = 0.1, '
                           'low = 0, high = 1.5 }\n', r"orbit_e\] high: 1.5 leaves the physical range \[0, 1\)"),
    ("grid value outside", '[sweep.parameters]\norbit_i = { values = ["30 deg", "200 deg"] }\n',
     r"orbit_i\] values\[1\]: '200 deg' is outside the physical range"),
    ("low above high", 'samples = 3\n[sweep.parameters]\nomega1 = { distribution = "uniform", low = "1 rad/s", '
                       'high = "0 rad/s" }\n', r"omega1\] high: '0 rad/s' is not above low"),
    ("std not positive", 'samples = 3\n[sweep.parameters]\nomega1 = { distribution = "normal", std = "0 rad/s" }\n',
     r"omega1\] std: '0 rad/s' must be positive"),
    ("samples missing", KEP_SWEEP, r"\[sweep\] samples: missing"),
    ("samples with grids only", 'samples = 4\n[sweep.parameters]\norbit_a = { values = ["7000 km"] }\n',
     r"\[sweep\] samples: only random parameters"),
    ("wrong anomaly", '[sweep.parameters]\norbit_mean_anomaly = { values = [0, 1] }\n',
     r"the \[orbit\] gives true_anomaly; vary orbit_true_anomaly"),
    ("energy on an eccentric orbit", 'samples = 3\noutputs = ["final_energy_error"]\n' + KEP_SWEEP,
     r"\[sweep\] outputs: 'final_energy_error': nothing is conserved .* eccentric \(e = 0.2\)"),
    ("unknown output", 'samples = 3\noutputs = ["max_speed"]\n' + KEP_SWEEP, r"\[sweep\] outputs: 'max_speed' is not one of"),
    ("tumbling angle without tumbling", 'samples = 3\noutputs = ["final_state"]\ntumbling_angle = "30 deg"\n' + KEP_SWEEP,
     r"\[sweep\] tumbling_angle: only used with 'tumbling'"),
    ("bad seed", "samples = 3\nseed = -4\n" + KEP_SWEEP, r"\[sweep\] seed: -4 must be an integer in \[0, "),
    ("no parameters", "samples = 3\n", r"\[sweep\] parameters: missing or empty"),
]


@pytest.mark.parametrize("table,match", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_sweep_tables_are_refused_with_the_field(table, match):
    with pytest.raises(ScenarioError, match=match):
        parse(sweep_on(KEPLER, table), "k.toml")


def test_orbit_parameters_need_an_orbit():
    with pytest.raises(ScenarioError, match=r"orbit_a\]: orbit elements vary only in a scenario with an \[orbit\]"):
        parse(sweep_on(TORQUE_FREE, '[sweep.parameters]\norbit_a = { values = ["7000 km"] }\n'))


def test_dimensionless_scenarios_take_plain_numbers():
    sw = sweep_of(sweep_on(TORQUE_FREE, 'samples = 5\nseed = 1\n[sweep.parameters]\n'
                                        'inertia2 = { distribution = "uniform", low = 0.9, high = 1.1 }\n'))
    assert sw.units["inertia2"] == "1" and np.all((sw.values["inertia2"] >= 0.9) & (sw.values["inertia2"] < 1.1))
    with pytest.raises(ScenarioError, match=r"has a unit but \[body\] inertia is plain"):
        parse(sweep_on(TORQUE_FREE, 'samples = 5\n[sweep.parameters]\ninertia2 = { distribution = "normal", '
                                    'std = "1 kg m2" }\n'))


# ---------------------------------------------------------------------------------------
# sampling


TRI = sweep_on(KEPLER, 'samples = 400\nseed = 7\n[sweep.parameters]\n'
                       'inertia3 = { distribution = "normal", std = "250 kg km2" }\n')


def test_triangle_inequality_refused_by_default():
    # I1 + I2 = 900 >= I3 ~ N(600, 250): some draws violate it
    with pytest.raises(orbatt.InputError, match=r"inertia: case \d+ drew I = .* violates the triangle inequality"
                                                r".*on_invalid = \"resample\""):
        sweep_of(TRI)


def test_triangle_inequality_resampled_when_asked():
    sw = sweep_of(TRI.replace("seed = 7\n", 'seed = 7\non_invalid = "resample"\n'))
    I3 = sw.values["inertia3"]
    assert sw.resampled > 0 and np.all((I3 > 0) & (I3 <= 900))
    assert sw.attrs()["sweep_resampled_cases"] == sw.resampled
    again = sweep_of(TRI.replace("seed = 7\n", 'seed = 7\non_invalid = "resample"\n'))
    assert np.array_equal(again.values["inertia3"], I3)


def test_normal_draw_outside_a_limit_names_the_case():
    text = sweep_on(KEPLER, 'samples = 200\nseed = 3\n[sweep.parameters]\n'
                            'orbit_i = { distribution = "normal", std = "10 deg", mean = "5 deg" }\n')
    with pytest.raises(orbatt.InputError, match=r"orbit_i: case \d+ drew -[\d.e-]+, outside the physical range"):
        sweep_of(text)


def test_samples_are_reproducible_and_follow_the_documented_order():
    text = sweep_on(KEPLER, 'samples = 3\nseed = 11\n[sweep.parameters]\n'
                            'omega2 = { distribution = "normal", std = "1e-3 rad/s" }\n'
                            'orbit_a = { values = ["7000 km", "7100 km"] }\n'
                            'inertia1 = { distribution = "uniform", low = "350 kg km2", high = "450 kg km2" }\n'
                            'attitude_angle = { distribution = "truncnormal", std = "5 deg", low = 0, high = "20 deg" }\n')
    sw = sweep_of(text)
    assert sw.cases == 6
    assert np.array_equal(sw.values["orbit_a"], [7000, 7000, 7000, 7100, 7100, 7100])
    rng = np.random.Generator(np.random.PCG64(11))
    inertia1 = rng.uniform(350, 450, 6)  # canonical order: inertia1, omega2, attitude_angle, then the axes
    omega2 = rng.normal(sw.nominal["omega2"], 1e-3, 6)
    assert np.array_equal(sw.values["inertia1"], inertia1) and np.array_equal(sw.values["omega2"], omega2)
    a = sw.values["attitude_angle"]
    assert np.all((a >= 0) & (a <= np.radians(20)))
    assert np.allclose(np.linalg.norm(sw.attitude_axis, axis=1), 1)
    assert sw.nominal["omega2"] == pytest.approx(orbatt.load_scenario("paper-keplerian").state0.omega[1])


def test_missing_seed_is_drawn_recorded_and_reusable():
    text = sweep_on(re.sub(r"^t_end = .*$", "t_end = 1", TORQUE_FREE, flags=re.M),
                    'samples = 4\n[sweep.parameters]\nomega1 = { distribution = "normal", std = 0.01 }\n')
    a, b = sweep_of(text), sweep_of(text)
    assert a.seed_source == "default" and a.seed != b.seed
    ds = run_sweep(a, scheduler="synchronous")
    assert int(ds.attrs["sweep_seed"]) == a.seed and ds.attrs["sweep_seed_source"] == "default"
    again = sweep_of(text, seed=int(ds.attrs["sweep_seed"]))
    assert np.array_equal(again.values["omega1"], a.values["omega1"])
    assert_same(run_sweep(again, scheduler="synchronous"), ds)


def test_resume_without_a_seed_reuses_the_recorded_one(tmp_path):
    text = sweep_on(re.sub(r"^t_end = .*$", "t_end = 1", TORQUE_FREE, flags=re.M),
                    'samples = 12\n[sweep.parameters]\nomega1 = { distribution = "normal", std = 0.01 }\n')
    first = sweep_of(text)

    def stop(info):
        if info.chunks_done == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(first, tmp_path / "n.nc", scheduler="synchronous", chunk_size=5, progress=stop)
    fresh = sweep_of(text)  # draws another seed; resume takes the interrupted run's
    assert fresh.seed != first.seed
    with run_sweep(fresh, tmp_path / "n.nc", scheduler="synchronous", chunk_size=5, resume=True) as ds:
        assert int(ds.attrs["sweep_seed"]) == first.seed and ds.attrs["sweep_seed_source"] == "default"
        assert json.loads(ds.attrs["sweep_run"])["chunks_reused"] == 1
        assert_same(ds.load(), first.compute())


# ---------------------------------------------------------------------------------------
# results


def test_chunking_does_not_change_a_bit_and_nominal_case_is_orbatt_run():
    text = short(samples=13, t_end='"900 s"', extra="")
    sw = sweep_of(text)
    whole = sw.compute()
    for size in (1, 5):
        assert_same(run_sweep(sw, scheduler="synchronous", chunk_size=size), whole)
    assert whole.sizes["case"] == 13 and not whole["integration_failed"].any()
    assert {"inertia1", "omega3", "attitude_angle", "attitude_axis"} <= set(whole.coords)
    assert np.all(np.abs(whole["final_energy_error"].values) < 1e-9)
    # a grid holding only the nominal orbit: the case is the scenario's nominal run, bit for bit
    grid = re.sub(r"^\w+ = \{ distribution.*\n", "", text, flags=re.M).replace("samples = 13\n", "")
    grid = grid.replace("[sweep.parameters]\n", '[sweep.parameters]\norbit_a = { values = ["7078 km", "7200 km"] }\n')
    sw = sweep_of(grid)
    ds = sw.compute()
    ref = sw.scenario.run()
    assert np.array_equal(ds["q_final"].values[0], ref["q"].values[-1])
    assert np.array_equal(ds["Q_final"].values[0], ref["Q"].values[-1])
    assert not np.array_equal(ds["q_final"].values[1], ref["q"].values[-1])


def test_trajectory_output_with_an_orbit_grid(tmp_path):
    text = sweep_on(re.sub(r"^t_end = .*$", 't_end = "300 s"', KEPLER, flags=re.M).replace("rtol = 1e-12", "rtol = 1e-9"),
                    'samples = 2\nseed = 5\noutputs = ["trajectory", "max_pointing_error"]\n[sweep.parameters]\n'
                    'orbit_a = { values = ["7000 km", "7500 km"] }\n'
                    'inertia2 = { distribution = "normal", std = "5 kg km2" }\n')
    sw = sweep_of(text)
    ds = run_sweep(sw, tmp_path / "traj.nc", scheduler="synchronous", chunk_size=3)
    with ds:
        assert ds.sizes["case"] == 4 and ds["q"].dims == ("case", "time", "quat")
        assert ds["r"].dims == ("case", "time")  # the orbit varies from case to case
        assert ds["r"].values[0, 0] == pytest.approx(7000 * 0.8) and ds["r"].values[2, 0] == pytest.approx(7500 * 0.8)
        assert np.array_equal(ds["inertia"].values[:, 1], ds["inertia2"].values)
        assert ds["max_pointing_error"].dims == ("case",)
        assert_same(ds.load(), sw.compute())
        assert ds.attrs["scenario"] == text
    assert not (tmp_path / "traj.nc.parts").exists()


def test_a_failing_case_is_flagged_and_the_others_kept():
    # rk4 with a huge step: fast spinners blow up, slow ones do not
    text = sweep_on(re.sub(r"^t_end = .*$", "t_end = 60", TORQUE_FREE, flags=re.M)
                    .replace('method = "dop853"', 'method = "rk4"\nstep = 0.5'),
                    '[sweep.parameters]\nomega1 = { values = [0.1, 1e6] }\n')
    text = re.sub(r"^(rtol|atol) = .*\n", "", text, flags=re.M)
    ds = sweep_of(text).compute()
    assert ds["integration_failed"].values.tolist() == [0, 1]
    assert np.isfinite(ds["q_final"].values[0]).all() and np.isnan(ds["q_final"].values[1]).all()
    assert ds["tumbling"].values[1] == -1


# ---------------------------------------------------------------------------------------
# a real dask.distributed cluster


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("dask.distributed")
    import logging

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, silence_logs=logging.ERROR) as lc, \
            distributed.Client(lc) as client:
        yield lc, client


@pytest.fixture(scope="module")
def big():
    """1000 cases of the shipped sweep over 0.1 orbit, and their serial ensemble run."""
    sw = sweep_of(short(samples=1000), source=str(SCEN / "gg-leo-dispersion.toml"))
    return sw, sw.compute()


def test_1000_cases_on_a_local_cluster_equal_the_serial_run(cluster, big, tmp_path):
    _, client = cluster
    sw, serial = big
    ds = run_sweep(sw, tmp_path / "big.nc", client=client, chunk_size=90)
    with ds:
        assert_same(ds.load(), serial)
        run = json.loads(ds.attrs["sweep_run"])
        assert run["chunks"] == 12 and run["chunks_computed"] == 12 and run["workers"] == 2
        assert int(ds.attrs["sweep_seed"]) == 20260320 and int(ds.attrs["sweep_cases"]) == 1000
        assert ds["tumbling"].dtype == np.int8 and ds["inertia1"].attrs["units"] == "kg m^2"
        assert json.loads(ds.attrs["integration_stats"])["steps"] > 1000
    assert sorted(os.listdir(tmp_path)) == ["big.nc"]


def test_a_worker_killed_mid_sweep_is_retried(cluster, big):
    lc, client = cluster
    sw, serial = big
    before = set(client.scheduler_info()["workers"])
    killed = []

    def kill_one(info):
        if killed or info.chunks_done < 2:
            return
        busy = [w for w, keys in client.processing().items() if keys] or sorted(before)
        pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
        os.kill(pid, signal.SIGKILL)  # the worker process dies with its task in flight
        killed.append(busy[0])

    ds = run_sweep(sw, client=client, chunk_size=20, progress=kill_one)
    assert killed
    assert_same(ds, serial)
    client.wait_for_workers(2, timeout=60)
    assert set(client.scheduler_info()["workers"]) != before  # the nanny started a new worker


def test_resume_after_an_interrupt_computes_only_the_missing_chunks(cluster, big, tmp_path):
    _, client = cluster
    sw, serial = big
    out = tmp_path / "r.nc"

    def stop_after_3(info):
        if info.chunks_done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sw, out, client=client, chunk_size=100, progress=stop_after_3)
    parts = out.with_name("r.nc.parts")
    kept = {p.name: p.stat().st_mtime_ns for p in parts.glob("cases-*.nc")}
    assert len(kept) == 3 and not out.exists()
    with pytest.raises(orbatt.InputError, match=r"holds the chunks of an interrupted sweep; pass --resume"):
        run_sweep(sw, out, client=client)
    seen = []
    ds = run_sweep(sw, out, client=client, chunk_size=100, resume=True, progress=seen.append)
    with ds:
        run = json.loads(ds.attrs["sweep_run"])
        assert run["chunks_reused"] == 3 and run["chunks_computed"] == 7 and run["cases_computed"] == 700
        assert_same(ds.load(), serial)
    kept_cases = {c for n in kept for c in range(int(n[6:15]), int(n[16:25]) + 1)}
    computed = [c for i in seen[1:] for c in range(i.start, i.stop)]
    assert len(computed) == 700 and not kept_cases & set(computed)


def test_cli_sweep_killed_then_resumed(cluster, big, tmp_path):
    """The command, SIGKILLed mid-run (a crash), then --resume: the complete parts are kept
    untouched and only the missing chunks are computed."""
    lc, _ = cluster
    sw, serial = big
    scen = tmp_path / "gg-leo-dispersion.toml"
    scen.write_text(sw.scenario.text)
    out = tmp_path / "cli.nc"
    parts = tmp_path / "cli.nc.parts"
    cmd = [sys.executable, "-m", "orbatt.cli", "sweep", str(scen), "-o", str(out), "--scheduler",
           lc.scheduler_address, "--chunk-size", "25", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if parts.is_dir() and len(list(parts.glob("cases-*.nc"))) >= 2:
                break
            time.sleep(0.005)
        assert proc.poll() is None, "the sweep finished before it could be interrupted"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    kept = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in parts.glob("cases-*.nc")}
    assert 2 <= len(kept) < 40 and not out.exists()
    r = subprocess.run(cmd[:-1] + ["--resume"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    m = re.search(r"(\d+) chunks computed, (\d+) reused", r.stdout)
    assert m and int(m.group(2)) == len(kept) and int(m.group(1)) == 40 - len(kept), r.stdout
    with orbatt.open_dataset(out) as ds:
        assert_same(ds.load(), serial)
    r = subprocess.run(cmd[:-1] + ["--resume"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and not parts.exists()  # complete already: nothing to do


# ---------------------------------------------------------------------------------------
# command line


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def test_cli_sweep_synchronous_and_bad_input(tmp_path):
    scen = tmp_path / "s.toml"
    scen.write_text(short(samples=20, t_end='"300 s"').replace("seed = 20260320\n", ""))
    r = cli("sweep", scen, "-o", tmp_path / "s.nc", "--scheduler", "synchronous", "--chunk-size", "7")
    assert r.returncode == 0, r.stderr
    assert "drew seed = " in r.stderr and "3 chunks computed, 0 reused" in r.stdout
    info = cli("info", tmp_path / "s.nc")
    assert info.returncode == 0 and "20 (inertia1, inertia2" in info.stdout and "(default)" in info.stdout
    # bad input: one line, exit code 2
    scen.write_text(short(samples=20).replace("omega1 = {", "omega4 = {"))
    r = cli("sweep", scen, "-o", tmp_path / "t.nc")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "omega4: unknown parameter" in r.stderr
    r = cli("sweep", SCEN / "paper-keplerian.toml", "-o", tmp_path / "t.nc")
    assert r.returncode == 2 and "[sweep]: missing table" in r.stderr
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="1s")
    r = subprocess.run([sys.executable, "-m", "orbatt.cli", "sweep", str(SCEN / "gg-leo-dispersion.toml"), "-o",
                        str(tmp_path / "t.nc"), "--scheduler", "tcp://127.0.0.1:9"], capture_output=True, text=True,
                       env=env, timeout=120)
    assert r.returncode == 2 and "cannot connect to 'tcp://127.0.0.1:9'" in r.stderr, r.stderr


def test_zarr_output(tmp_path):
    pytest.importorskip("zarr")
    sw = sweep_of(short(samples=10, t_end='"120 s"'))
    ds = run_sweep(sw, tmp_path / "z.zarr", scheduler="synchronous", chunk_size=4)
    assert_same(ds.load(), sw.compute())

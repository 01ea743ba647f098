"""Binary scenarios: [orbit] provider = "coupled" parsed, run, and refused with the key named."""
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.errors import IntegrationError
from orbatt.scenario import ScenarioError, load_scenario, parse
from orbatt.scenario.binary_scenario import BinaryScenario

SCEN = Path(__file__).resolve().parents[2] / "scenarios"
DD = (SCEN / "didymos-dimorphos.toml").read_text()
EQ = (SCEN / "sphere-ellipsoid-equilibrium.toml").read_text()
# the contract, verbatim
CONTRACT = """
[body]
mass = "4.3e9 kg"
inertia = ["8.6e12 kg m2", "1.17e13 kg m2", "1.41e13 kg m2"]

[initial]
q = [1.0, 0.0, 0.0, 0.0]
omega = ["0 rad/s", "0 rad/s", "1.46e-4 rad/s"]

[orbit]
provider = "coupled"
primary_mass = "5.3e11 kg"
a = "1190 m"
e = 0.02
i = "3 deg"
raan = "0 deg"
argp = "0 deg"
true_anomaly = "0 deg"

[primary]
inertia = ["2.93e16 kg m2", "2.93e16 kg m2", "3.83e16 kg m2"]
q = [1.0, 0.0, 0.0, 0.0]
omega = ["0 rad/s", "0 rad/s", "7.72e-4 rad/s"]

[potential]
kind = "gravity-gradient"

[integration]
t_end = "2 orbits"
output_step = "0.1 orbits"
"""


def edit(text, old, new):
    assert text.count(old) == 1, old
    return text.replace(old, new)


#: from the apoapsis (2.08 km) down to a periapsis of 0.30 km, inside the bodies (0.52 km)
PLUNGE = edit(edit(CONTRACT, 'e = 0.02', 'e = 0.75'), 'true_anomaly = "0 deg"', 'true_anomaly = "180 deg"')


def test_contract_parses_and_runs(tmp_path):
    p = tmp_path / "contract.toml"
    p.write_text(CONTRACT)
    sc = load_scenario(p)
    assert isinstance(sc, BinaryScenario) and sc.system.potential == "gravity-gradient"
    ds = sc.run()
    for name in ("position", "velocity", "q", "Q", "omega", "q_primary", "Q_primary", "omega_primary", "energy",
                 "angular_momentum_total", "separation", "orbit_a", "orbit_e", "orbit_i", "orbit_period"):
        assert name in ds and "units" in ds[name].attrs and "long_name" in ds[name].attrs, name
    assert ds.time.size == 21
    assert math.isclose(float(ds.orbit_a[0]), 1.19, rel_tol=1e-12)
    assert math.isclose(float(ds.orbit_i[0]), math.radians(3), rel_tol=1e-12)
    # gravity-gradient: the primary is torque-free, its rate constant
    assert np.allclose(ds.omega_primary.values, [0, 0, 7.72e-4], rtol=0, atol=1e-9 * 7.72e-4)


def test_orbital_frame_initial_attitude_is_synchronous():
    """frame = 'orbital', q = 1, omega = 0: the body's x axis along the position, its rate the
    orbit's."""
    sc = BinaryScenario(parse(DD, "dd.toml"))
    y = sc.y0
    xb = orbatt.quaternion.rotate(y[6:10], np.array([1.0, 0, 0]))
    assert np.allclose(xb, y[0:3] / np.linalg.norm(y[0:3]), atol=1e-15)
    n = np.linalg.norm(np.cross(y[0:3], y[3:6] / sc.system.reduced_mass)) / np.sum(y[0:3] ** 2)
    g = 0.5 * orbatt.quaternion.mul(orbatt.quaternion.conj(y[6:10]), y[10:14])[1:]
    h = orbatt.quaternion.rotate(y[6:10], g / sc.system.inertia)   # the rate, inertial
    hat = np.cross(y[0:3], y[3:6]) / np.linalg.norm(np.cross(y[0:3], y[3:6]))
    assert np.allclose(h, n * hat, rtol=0, atol=1e-15 * n)


def test_equilibrium_scenario_stays_put():
    sc = load_scenario(SCEN / "sphere-ellipsoid-equilibrium.toml")
    ds = sc.run()
    sep = ds.separation.values
    assert np.max(np.abs(sep - 1.19)) < 1e-11
    per = ds.orbit_period.values
    n = 1.455434142805217e-4
    assert abs(sc.period * 0 + per[0] - per[-1]) < 1e-9 * per[0]
    # one revolution after 2 pi / n: the position angle is back (period = 2 pi / n)
    res = sc.run_content()
    assert res.attrs["integration_complete"] == 1
    assert abs(2 * math.pi / n / 3600 - 11.9918119320079) < 1e-9


def test_dart_like_impulse_shortens_the_period():
    text = edit(DD, 't_end = "6 d"', 't_end = "2 d"')
    sc = BinaryScenario(parse(text, "dd.toml"))
    ds = sc.run()
    t, P = ds.elapsed.values, ds.orbit_period.values
    before, after = P[t <= 86400].mean(), P[t > 86400].mean()
    assert -40 * 60 < after - before < -25 * 60   # about -33 min observed (-31 min here with -2.7 mm/s)


@pytest.mark.parametrize("old,new,where", [
    ('mass = "4.3e9 kg"\n', "", "[body] mass"),
    ('mass = "4.3e9 kg"', 'mass = "-4.3e9 kg"', "[body] mass"),
    ('primary_mass = "5.3e11 kg"', 'primary_mass = "0 kg"', "[orbit] primary_mass"),
    ('inertia = ["8.6e12 kg m2", "1.17e13 kg m2", "1.41e13 kg m2"]',
     'inertia = ["8.6e12 kg m2", "1.17e12 kg m2", "1.41e13 kg m2"]', "[body] inertia"),
    ('inertia = ["2.93e16 kg m2", "2.93e16 kg m2", "3.83e16 kg m2"]',
     'inertia = ["2.93e16 kg m2", "-2.93e16 kg m2", "3.83e16 kg m2"]', "[primary] inertia"),
    ('a = "1190 m"', 'a = "300 m"', "[orbit] a"),
    ('kind = "gravity-gradient"', 'kind = "heavy-top"', "[potential] kind"),
    ('[integration]', '[torques]\ndrag = true\n\n[integration]', "[torques]"),
    ('[integration]', '[control]\nlaw = "pd"\n\n[integration]', "[control]"),
    ('[integration]', '[integration]\nmethod = "rk4"', "[integration] method"),
    ('e = 0.02', 'e = 1.5', "[orbit] e"),
    ('true_anomaly = "0 deg"', 'true_anomaly = "0 deg"\nposition = ["1 km", "0 km", "0 km"]', "[orbit] position"),
    ('[integration]', '[[orbit.impulses]]\ntime = "-5 s"\ndelta_v = ["0 m/s", "1 m/s", "0 m/s"]\n\n[integration]',
     "[[orbit.impulses]] 0 time"),
])
def test_bad_input_names_the_key(old, new, where):
    with pytest.raises(ScenarioError) as exc:
        text = edit(CONTRACT, old, new)
        BinaryScenario(parse(text, "bad.toml"), path="bad.toml")
    assert f"bad.toml: {where}" in str(exc.value), str(exc.value)


def test_primary_without_coupled_orbit_is_refused():
    text = (SCEN / "paper-keplerian.toml").read_text() + '\n[primary]\ninertia = ["1 kg m2", "1 kg m2", "1 kg m2"]\n'
    with pytest.raises(ScenarioError, match=r"\[primary\]: only used with \[orbit\] provider = 'coupled'"):
        parse(text, "k.toml")


def test_contact_during_the_run_stops_and_keeps_what_was_computed():
    """A radial plunge: the run stops at contact with the outputs before it."""
    text = PLUNGE   # periapsis 0.30 km < contact 0.52 km
    sc = BinaryScenario(parse(text, "plunge.toml"))
    with pytest.raises(IntegrationError, match="contact") as exc:
        sc.run()
    ds = exc.value.dataset
    assert ds is not None and ds.attrs["integration_complete"] == 0 and 1 < ds.time.size < 21


def cli(*args):
    return subprocess.run([sys.executable, "-m", "orbatt.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=tempfile.gettempdir(), timeout=300)


def test_cli_exit_codes(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(edit(CONTRACT, 'mass = "4.3e9 kg"\n', ""))
    r = cli("run", bad, "-o", tmp_path / "bad.nc", "--quiet")
    assert r.returncode == 2 and "[body] mass" in r.stderr and "Traceback" not in r.stderr
    plunge = tmp_path / "plunge.toml"
    plunge.write_text(PLUNGE)
    r = cli("run", plunge, "-o", tmp_path / "plunge.nc", "--quiet")
    assert r.returncode == 1 and "contact" in r.stderr, r.stderr
    assert orbatt.open_dataset(tmp_path / "plunge.nc").attrs["integration_complete"] == 0


def test_splitting_from_the_scenario():
    text = edit(EQ, 'method = "dop853"\nrtol = 1e-13\natol = 1e-18\n',
                'method = "splitting"\nstep = "0.01 orbits"\ncomposition = "yoshida6"\n')
    ds = BinaryScenario(parse(text, "eq.toml")).run()
    assert np.max(np.abs(ds.separation.values - 1.19)) < 1e-8   # h = T/100: the splitting's equilibrium is ~7e-9 off
    L = ds.angular_momentum_total.values
    assert np.max(np.abs(L - L[0])) < 1e-13 * np.linalg.norm(L[0])
    with pytest.raises(ScenarioError, match=r"\[integration\] step: missing"):
        parse(edit(text, 'step = "0.01 orbits"\n', ""), "eq.toml")


def test_contact_between_outputs_stops_the_step_loop():
    """Outputs too sparse to see the plunge: the right-hand side refuses the inside of the bodies,
    so the step loop stops at the contact itself (not after passing through)."""
    text = edit(PLUNGE, 'output_step = "0.1 orbits"', 'output_step = "1 orbits"')
    sc = BinaryScenario(parse(text, "plunge.toml"))
    with pytest.raises(IntegrationError, match="contact") as exc:
        sc.run()
    traj = exc.value.trajectory
    assert traj.t.size == 1 and exc.value.t == 0.0   # only the start was an output
    assert "touch at 0.517" in str(exc.value)


def test_cli_run_info_plot(tmp_path):
    src = tmp_path / "eq.toml"
    src.write_text(edit(EQ, 't_end = "10 orbits"', 't_end = "0.5 orbits"'))
    out = tmp_path / "eq.nc"
    assert cli("run", src, "-o", out, "--quiet").returncode == 0
    info = cli("info", out)
    assert info.returncode == 0 and "energy" in info.stdout
    r = cli("plot", out, "-o", tmp_path / "fig")
    figs = sorted(f.name for f in (tmp_path / "fig").glob("*.png"))
    # the figures a binary's content calls for (the secondary's rates; the conserved energy's drift)
    assert r.returncode == 0 and figs == ["eq-drift.png", "eq-orbit.png", "eq-rates.png"], (figs, r.stderr)

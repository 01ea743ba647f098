"""A run that fails mid-way (:class:`orbatt.IntegrationError`, here ``max_steps``) keeps
what it computed (issue 14 §5): ``Scenario.run`` attaches it to the error as a Dataset
marked incomplete, and ``orbatt run`` writes it, then exits 1 with one line."""
import re
from pathlib import Path

import numpy as np
import pytest

import orbatt
from orbatt.cli import main
from orbatt.errors import IntegrationError
from orbatt.scenario import load as scenario_load

SCEN = Path(__file__).resolve().parent.parent / "scenarios"


def _scenario(folder):
    text = (SCEN / "paper-torque-free.toml").read_text()
    text = re.sub(r"^t_end = .*$", "t_end = 20", text, flags=re.M)
    path = folder / "s.toml"
    path.write_text(text)
    return path


@pytest.fixture
def few_steps(monkeypatch):
    """``orbatt.propagate`` as the scenario calls it, limited to 40 step attempts."""
    real = scenario_load.propagate

    def limited(*args, **kw):
        kw["max_steps"] = 40
        return real(*args, **kw)

    monkeypatch.setattr(scenario_load, "propagate", limited)


def test_scenario_run_gives_the_partial_dataset(tmp_path, few_steps):
    sc = orbatt.load_scenario(_scenario(tmp_path))
    with pytest.raises(IntegrationError, match="max_steps") as info:
        sc.run()
    ds = info.value.dataset
    assert int(ds.attrs["integration_complete"]) == 0
    n = ds.sizes["time"]
    assert 1 < n < sc.times.size
    assert ds["time"].values[-1] <= info.value.t
    # the outputs computed so far, at the scenario's output times
    np.testing.assert_array_equal(ds["time"].values, sc.times[:n])


def test_cli_writes_the_partial_result_and_exits_1(tmp_path, few_steps, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out.nc"
    rc = main(["run", str(_scenario(tmp_path)), "-o", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1
    assert len(err) == 1 and err[0].startswith("orbatt: error:") and "max_steps" in err[0], err
    assert "out.nc" in err[0] and "integration_complete = 0" in err[0]
    ds = orbatt.open_dataset(out, load=True)
    assert int(ds.attrs["integration_complete"]) == 0
    assert ds.sizes["time"] > 1 and np.isfinite(ds["q"].values).all()
    assert "INCOMPLETE" in orbatt.cli.summary(ds)

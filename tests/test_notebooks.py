"""The notebooks in ``notebooks/`` execute from top to bottom (their cells assert their own
checks), in fast mode (``ORBATT_NOTEBOOK_FAST=1``), on a kernel running this interpreter.

Needs ``nbformat``, ``nbclient`` and ``ipykernel`` (in the ``test`` extra); skipped with the
reason when they are missing. The notebooks are committed WITH their outputs, so that the
figures show where the repository is browsed (checked without those packages); refresh them
by executing each notebook in place with nbclient (full mode: ``ORBATT_NOTEBOOK_FAST`` unset),
e.g. ``nbclient.NotebookClient(nb, timeout=1200).execute()`` then ``nbformat.write``.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import pytest

NOTEBOOK_DIR = Path(__file__).resolve().parent.parent / "notebooks"
NOTEBOOKS = ["paper_figures.ipynb", "gg_stabilized_satellite.ipynb", "torque_budget.ipynb", "attitude_control.ipynb",
             "binary_asteroid.ipynb", "monte_carlo.ipynb", "flight_software.ipynb",
             "pointing_budget.ipynb"]
KERNEL_NAME = "orbatt-test-python"
CELL_TIMEOUT_S = 600  # a cold numba cache compiles the kernels on first use


def _path(name):
    path = NOTEBOOK_DIR / name
    if not path.exists():
        pytest.skip(f"{path} not found (tests run outside a source checkout)")
    return path


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_committed_with_outputs(name):
    nb = json.loads(_path(name).read_text(encoding="utf-8"))
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    unrun = [i for i, c in enumerate(code) if c.get("execution_count") is None]
    assert not unrun, f"{name}: code cells {unrun} were not executed; commit the notebook with its outputs"
    counts = [c["execution_count"] for c in code]
    assert counts == list(range(1, len(code) + 1)), f"{name}: executed out of order ({counts}); run it top to bottom"
    outputs = [o for c in code for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"], f"{name}: committed with an error output"
    assert any("image/png" in o.get("data", {}) for o in outputs), f"{name}: no figure among the outputs"


def _kernel_manager(tmp_path):
    """A kernel manager whose kernel is ``sys.executable -m ipykernel_launcher``.

    A private kernelspec in ``tmp_path`` (not the ``python3`` spec found on the Jupyter path,
    which a user-level install could point at another interpreter)."""
    from jupyter_client import KernelManager
    from jupyter_client.kernelspec import KernelSpecManager

    spec_dir = tmp_path / "kernels" / KERNEL_NAME
    spec_dir.mkdir(parents=True)
    (spec_dir / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "orbatt test kernel", "language": "python"}))
    ksm = KernelSpecManager(kernel_dirs=[str(tmp_path / "kernels")])
    return KernelManager(kernel_name=KERNEL_NAME, kernel_spec_manager=ksm)


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_executes(name, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat", reason="nbformat not installed (pip install 'orbatt[test]')")
    nbclient = pytest.importorskip("nbclient", reason="nbclient not installed (pip install 'orbatt[test]')")
    pytest.importorskip("ipykernel", reason="ipykernel not installed (pip install 'orbatt[test]')")
    path = _path(name)
    nb = nbformat.read(path, as_version=4)
    # the kernel must run in this environment: check it in the kernel itself
    nb.cells.insert(0, nbformat.v4.new_code_cell(
        f"import sys\nassert sys.prefix == {sys.prefix!r}, (sys.prefix, sys.executable)"))
    monkeypatch.setenv("ORBATT_NOTEBOOK_FAST", "1")
    monkeypatch.delenv("MPLBACKEND", raising=False)  # the kernel's inline backend
    work = tmp_path / "work"  # the notebooks' working folder: nothing lands in the checkout
    work.mkdir()
    client = nbclient.NotebookClient(nb, km=_kernel_manager(tmp_path), timeout=CELL_TIMEOUT_S,
                                     resources={"metadata": {"path": str(work)}})
    t0 = time.perf_counter()
    client.execute()
    elapsed = time.perf_counter() - t0
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors  # execute() raises CellExecutionError first; belt and braces
    print(f"{name}: executed in {elapsed:.1f} s")

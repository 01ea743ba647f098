"""Kernels load from numba's disk cache without initializing numba's compiler (issue 15):
a warm run spends no time importing numba's lowering registries, and gives the same bits."""
import subprocess
from pathlib import Path
import sys

import pytest

# they check what is in the cache, compiling what it lacks first: collected last (conftest.py)
pytestmark = pytest.mark.cache_check

CODE = """
import sys, numpy as np, orbatt
body = orbatt.RigidBody([1.25, 1.0, 0.75])
st = orbatt.State(body, [0.5, -0.5**0.5, 0.0, 0.5], [0.3, -0.848528, 0.141421, -1.5])
tr = orbatt.propagate(body, st, orbatt.TorqueFree(), np.linspace(0.0, 10.0, 5), atol=1e-12, max_steps=10**6)
print("numba.np.arraymath" in sys.modules, tr.q[-1].tobytes().hex())
"""


def _run():
    out = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, check=True)
    compiler_loaded, bits = out.stdout.split()
    return compiler_loaded == "True", bits


def test_a_cached_kernel_loads_without_the_compiler_and_gives_the_same_bits():
    _, first = _run()  # compiles and caches the kernels if this checkout has not yet
    compiler_loaded, again = _run()
    assert not compiler_loaded
    assert again == first


FAMILIES = """
import re, sys, warnings, numpy as np, orbatt
from pathlib import Path
from orbatt.scenario import Scenario, parse
warnings.simplefilter("ignore")
scen = Path(sys.argv[1])
out = []
# single (DOP853) and lockstep lanes on the torque-free body
body = orbatt.RigidBody([1.25, 1.0, 0.75])
st = orbatt.State(body, [0.5, -0.5**0.5, 0.0, 0.5], [0.3, -0.848528, 0.141421, -1.5])
out.append(orbatt.propagate(body, st, orbatt.TorqueFree(), np.linspace(0.0, 5.0, 3), atol=1e-12).q[-1])
bodies = [orbatt.RigidBody([1.25, 1.0, 0.75 + 0.01 * k]) for k in range(4)]
ens = orbatt.propagate(bodies, st, orbatt.TorqueFree(), np.linspace(0.0, 5.0, 3), method="dop853-lanes", atol=1e-12)
out.append(ens.q[:, -1].ravel())
# environment tables (drag, SRP, magnetic), and the control laws (PD + wheels, B-dot)
for name in ("cubesat-3u-disturbances", "lvlh-hold-wheels", "cubesat-bdot-detumble"):
    text = re.sub(r"^t_end = .*$", 't_end = "120 s"', (scen / f"{name}.toml").read_text(), flags=re.M)
    out.append(Scenario(parse(text, name)).run()["q"].values[-1])
print("numba.np.arraymath" in sys.modules, "numba.core.compiler" in sys.modules and
      any(m.startswith("numba.parfors") for m in sys.modules), np.concatenate(out).tobytes().hex())
"""


def test_every_kernel_family_loads_from_the_cache_in_a_fresh_process():
    """Issue 22: single, lanes, environment and control kernels all come from numba's cache in
    a new process (none is compiled again: the compiler's lowering registries stay unloaded),
    with the same bits."""
    scen = Path(__file__).resolve().parents[2] / "scenarios"

    def run():
        r = subprocess.run([sys.executable, "-c", FAMILIES, str(scen)], capture_output=True, text=True, timeout=900)
        assert r.returncode == 0, r.stderr
        lowering, parfors, bits = r.stdout.split()
        return lowering == "True", bits

    _, first = run()  # compiles and caches what this checkout has not yet
    lowering, again = run()
    assert not lowering, "a kernel was compiled again instead of loaded from the cache"
    assert again == first

"""Kernels load from numba's disk cache without initializing numba's compiler (issue 15):
a warm run spends no time importing numba's lowering registries, and gives the same bits."""
import subprocess
import sys

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

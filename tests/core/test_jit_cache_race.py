"""Processes compiling into one numba cache at once keep every kernel's own machine code
(issue 26: numba's unlocked saves gave two kernels one data file, and later processes loaded
the wrong kernel silently)."""
import os
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("fcntl")

# eight variants of one closure share one index file (as the step loops of rk_loop.loop_of do):
# the variant is a constant of the closure, so each compiles to its own machine code
MODULE = textwrap.dedent('''
    from orbatt.core._jit import jit

    def variant(k):
        K = float(k)

        def f(x):
            return x * 1000.0 + K
        return jit(f)
''')
# each process imports, then waits for all the others (a barrier of files), then compiles: the
# saves fall within milliseconds of each other
COMPILE = textwrap.dedent('''
    import sys, time
    from pathlib import Path
    import racemod
    k, n, barrier = int(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3])
    (barrier / f"ready-{k}").touch()
    while len(list(barrier.glob("ready-*"))) < n:
        time.sleep(0.002)
    print(racemod.variant(k)(1.0))
''')
LOAD = textwrap.dedent('''
    import sys, racemod
    print(" ".join(repr(racemod.variant(k)(1.0)) for k in range(int(sys.argv[1]))),
          "numba.np.arraymath" in sys.modules)
''')


def test_concurrent_compiles_into_one_cache_keep_each_kernel(tmp_path):
    (tmp_path / "racemod.py").write_text(MODULE)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}
    n = 8
    for r in range(2):  # twice: the second round saves beside the first round's entries
        barrier = tmp_path / f"barrier-{r}"
        barrier.mkdir()
        procs = [subprocess.Popen([sys.executable, "-c", COMPILE, str(k), str(n), str(barrier)], env=env,
                                  stdout=subprocess.PIPE, text=True) for k in range(n)]
        outs = [p.communicate(timeout=300)[0].strip() for p in procs]
        assert all(p.returncode == 0 for p in procs)
        assert outs == [repr(1000.0 + k) for k in range(n)]
        n += 4
    out = subprocess.run([sys.executable, "-c", LOAD, str(n - 4)], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    # a fresh process loads every variant from the cache (no compiler), each its own code
    assert out[:-1] == [repr(1000.0 + k) for k in range(n - 4)]
    assert out[-1] == "False"

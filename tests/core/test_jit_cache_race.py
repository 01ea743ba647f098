"""Processes compiling into one numba cache at once keep every kernel's own machine code
(issue 26: numba's unlocked saves gave two kernels one data file, and later processes loaded
the wrong kernel silently; issue 34: two variants of one closure compiled in two processes
shared one machine-code name, and a process loading both ran one's callers on the other)."""
import os
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("fcntl")

# one kernel compiled for twelve types (tuples of 1 ... 12 floats) keeps one index file of its
# signatures (as a kernel called with several array layouts does); each type compiles to its
# own machine code (the length is a constant of the signature)
MODULE = textwrap.dedent('''
    from orbatt.core._jit import jit

    @jit
    def f(t):
        return len(t) * 1000.0 + t[0]

    def call(k):
        return f((1.0,) * (k + 1))
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
    print(racemod.call(k))
''')
LOAD = textwrap.dedent('''
    import sys, racemod
    print(" ".join(repr(racemod.call(k)) for k in range(int(sys.argv[1]))),
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
        assert outs == [repr(1000.0 * (k + 1) + 1.0) for k in range(n)]
        n += 4
    out = subprocess.run([sys.executable, "-c", LOAD, str(n - 4)], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    # a fresh process loads every signature from the one index (no compiler), each its own code
    assert [f.name for f in (tmp_path / "cache").rglob("*.nbi")] == ["racemod.f-4.py%d%d.nbi" % sys.version_info[:2]]
    assert out[:-1] == [repr(1000.0 * (k + 1) + 1.0) for k in range(n - 4)]
    assert out[-1] == "False"


# two variants of one closure, and a caller of each: a caller's machine code holds a copy of its
# callee's (a weak symbol, named by the callee's qualified name, types and numba's per-process
# count of compiled functions)
LINKED = textwrap.dedent('''
    from orbatt.core._jit import jit

    def variant(k):
        K = float(k)

        def f(x):  # long enough that LLVM keeps it a function of its own in its callers
            s = x
            for i in range(int(x) + 2):
                if s > K:
    %s
                else:
                    s = s + K
            return s
        return jit(f)

    f0 = variant(0)
    f1 = variant(1)

    @jit
    def g0(x):
        return f0(x)

    @jit
    def g1(x):
        return f1(x)
''') % "\n".join(f"{' ' * 16}s = s * {1.0 + j / 64} - K / {j + 1}" for j in range(64))
CALL = textwrap.dedent('''
    import sys, linkmod
    print(" ".join(repr(getattr(linkmod, name)(1.0)) for name in sys.argv[1:]),
          "numba.np.arraymath" in sys.modules)
''')


def test_a_caller_loaded_beside_another_variant_of_its_callee_runs_its_own(tmp_path):
    """Issue 34: numba names a kernel's machine code by its qualified name, its types and a
    count of the functions this process compiled, and a caller's code holds a copy of its
    callee's under that name, which a process binds to the first code loaded under it. Two
    processes that compile two variants of one closure first (a cold parallel start) named
    both alike: a third that loaded one variant ran the other's callers on it (seen: an
    ensemble of DOP853 runs integrated with the Verner loop, sweeps of wheel models failing
    every case)."""
    (tmp_path / "linkmod.py").write_text(LINKED)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}

    def call(*names):
        out = subprocess.run([sys.executable, "-c", CALL, *names], env=env, capture_output=True, text=True,
                             check=True).stdout.split()
        return out[:-1], out[-1] == "True"

    (v0,), _ = call("f0")  # compiles variant 0 first
    (v1, w1), _ = call("f1", "g1")  # variant 1 first, then its caller
    assert v1 == w1 != v0
    values, compiled = call("f0", "g1")  # both from the cache, variant 0 loaded first
    assert not compiled
    assert values == [v0, v1]

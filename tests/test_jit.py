"""pipeline.model.jit: numba's compiled loops, loaded once a process.

A numba cache left half written (a process killed while numba wrote it, a full disk) must not
stop every later compiled job: compiled_loops removes it and compiles again. A loops module's
entry points have one signature each (no second specialisation compiled behind a user's back),
its compiled code reads nothing but its own text (numba's cache is keyed by the file), and an
import that compiles is announced while it runs."""

import ast
import logging
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from pipeline.model import crossings, faces, jit, nullspace, rounding
from pipeline.workspace import fused_loops

MODULE = """
from numba import njit

SIGNATURES = {"twice": "void(f8[::1], f8[::1])"}


@njit(SIGNATURES["twice"], cache=True)
def twice(values, out):
    for i in range(values.shape[0]):
        out[i] = 2.0 * values[i]
"""

CALL = """
import logging, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
logging.basicConfig(level=logging.WARNING)
from pipeline.model.jit import compiled_loops
if sys.argv[2] == "healing":
    twice = compiled_loops("healme").twice
else:
    from healme import twice
out = np.empty(3)
twice(np.arange(3.0), out)
print(out.tolist())
"""


def run(folder, how):
    return subprocess.run([sys.executable, "-c", CALL, str(folder), how], capture_output=True, text=True,
                          timeout=120)


def test_a_truncated_or_empty_cache_is_compiled_again_with_a_warning(tmp_path):
    (tmp_path / "healme.py").write_text(textwrap.dedent(MODULE))
    assert run(tmp_path, "healing").stdout.strip() == "[0.0, 2.0, 4.0]"  # compiles, writes the cache
    cached = sorted((tmp_path / "__pycache__").glob("healme.*.nb[ic]"))
    assert cached
    for damage in (lambda data: data[: len(data) // 3], lambda data: b""):
        for path in cached:
            path.write_bytes(damage(path.read_bytes()))
        plain = run(tmp_path, "plain")
        assert plain.returncode != 0 and ("pickle" in plain.stderr or "EOFError" in plain.stderr)
        healed = run(tmp_path, "healing")
        assert healed.returncode == 0 and healed.stdout.strip() == "[0.0, 2.0, 4.0]", healed.stderr
        assert "unreadable" in healed.stderr and "compiling again" in healed.stderr
        assert run(tmp_path, "plain").stdout.strip() == "[0.0, 2.0, 4.0]"  # the cache is whole again
        cached = sorted((tmp_path / "__pycache__").glob("healme.*.nb[ic]"))


SPECIALISATIONS = """
import numba, sys
sys.path.insert(0, sys.argv[1])
from conftest import make_cfg, compute_workspace
from pipeline.model import crossings, faces, nullspace, rounding
from pipeline.model.catalogue import load_catalogue
from pipeline.model.intervals import Interval
from pipeline.app.problem import build_problem
from pipeline.workspace import fused_loops
from pipeline.workspace.feasibility import feasible_flags

make, catalogue = make_cfg, load_catalogue()
for overrides in (["compute.kernel=fused", "grid.n=4"], ["compute.kernel=fused", "grid.n=4", "orientation.psi=0.5"],
                  ["compute.kernel=fused", "grid.n=4", "tension.t_max=[9e3,9e3,9e3,9e3,9e3,9e3,9e3,9e3]"],
                  ["compute.kernel=fused", "grid.n=4", "model.pinv_columns=translational"],
                  ["robot=irpm6", "compute.kernel=fused", "robot.search.step=2"],
                  ["robot=irpm6", "compute.kernel=fused", "robot.search.step=2", "tension.t_min=[1,1,1,1,1,1]"],
                  ["tension=feasible", "grid.n=3"], ["robot=irpm6", "tension=feasible", "robot.search.step=2"],
                  ["tension=feasible", "grid.n=3", "orientation.psi=0.3", "output.cables=true"],
                  ["analysis=statics", "tension=feasible", "grid.n=3", "output.metrics=true"]):
    compute_workspace(make(*overrides), catalogue)
problem, grid = build_problem(make("robot=irpm6", "tension=feasible", "robot.search.step=2"), catalogue)
feasible_flags(problem, grid[0:len(grid)])
(Interval.point([1.0, 2.0]) * Interval.point(3.0)).sqrt()
for module in (fused_loops, crossings, faces, nullspace, rounding):
    for name, value in sorted(vars(module).items()):
        if isinstance(value, numba.core.registry.CPUDispatcher):
            print(module.__name__, name, len(value.signatures))
"""


def test_each_compiled_function_has_one_specialisation():
    """The entry points are compiled for their one signature when imported; a helper is compiled
    for the types its caller passes, once: the papers' robots, with scalar and per-cable limits,
    both readings and the feasible tension model use one of each. A call with another type (a
    literal, a read-only array) is a TypeError, not seconds of compiling."""
    done = subprocess.run([sys.executable, "-c", SPECIALISATIONS, str(Path(__file__).parent)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    counts = dict(line.rsplit(" ", 1) for line in done.stdout.splitlines())
    assert len(counts) >= 10 and set(counts.values()) <= {"0", "1"}, counts
    for entry in ("fused_loops cpr_wwa", "fused_loops statics", "crossings least_margins", "faces least_norm",
                  "nullspace pulling_verdicts", "rounding step"):
        assert counts[f"pipeline.workspace.{entry}" if entry.startswith("fused") else f"pipeline.model.{entry}"] == "1"
    import numpy as np

    read_only = np.zeros((1, 3))
    read_only.setflags(write=False)
    with pytest.raises(TypeError, match="No matching definition"):
        fused_loops.statics(read_only, np.zeros((6, 3)), np.zeros((6, 3)), False, False, np.zeros((6, 1)),
                            1e-9, 1e-9, np.zeros(6), np.zeros(6), 1.0, np.inf, 1e-9, np.empty((1, 4)), np.zeros(1, dtype=bool))


def test_a_compile_is_announced_only_where_numba_has_no_cache_of_the_module(tmp_path, monkeypatch, caplog):
    """A warm run of a loaded machine, whose cache took over a second to load, said numba was
    compiling: the announcement now follows the cache (none of this version of the file: a
    compile), with the measured time and how much longer a loaded machine takes."""
    import os

    (tmp_path / "slowloops.py").write_text("VALUE = 1\n")
    (tmp_path / "cachedloops.py").write_text("VALUE = 2\n")
    (tmp_path / "__pycache__").mkdir()
    cache = tmp_path / "__pycache__" / "cachedloops.f-1.py311.nbi"
    cache.write_text("")
    later = (tmp_path / "cachedloops.py").stat().st_mtime + 10
    os.utime(cache, (later, later))
    monkeypatch.syspath_prepend(str(tmp_path))
    with caplog.at_level(logging.INFO, logger="pipeline.model.jit"):
        jit.compiled_loops("cachedloops")
        assert not caplog.records
        jit.compiled_loops("slowloops")
    lines = [r.getMessage() for r in caplog.records]
    assert lines[0] == ("numba is compiling the loops of slowloops, once per machine and version of the file: "
                        "about 1 s on an idle core, up to 5 times that on a loaded machine")
    assert lines[1].startswith("compiled the loops of slowloops in 0.")
    assert jit.compile_seconds("pipeline.workspace.fused_loops") in (0.0, 45.0)


@pytest.mark.parametrize("module, exports", [(fused_loops, {"cpr_wwa", "statics"}),
                                             (crossings, {"least_margins", "largest_wrenches"}),
                                             (faces, {"least_norm"}), (nullspace, {"pulling_verdicts"}),
                                             (rounding, {"step"})])
def test_the_compiled_loops_use_nothing_but_their_own_text(module, exports):
    """numba keys its cache of a module's functions by the module's file: the compiled code may use
    numpy, numba and the module's own names only (any other value is an argument), else a
    constant imported from another module would be kept, stale, after that module changed."""
    tree = ast.parse(Path(module.__file__).read_text())
    assert not [alias.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                for alias in node.names if alias.name not in ("numpy", "numba")]
    assert all(node.level == 0 and node.module in ("__future__", "numpy", "numba")
               for node in ast.walk(tree) if isinstance(node, ast.ImportFrom))
    assert set(module.SIGNATURES) == exports
    # the entry points let go of the GIL: a job's worker threads run them at once (compute.backend=threading)
    assert {name for name in exports if getattr(module, name).targetoptions.get("nogil")} == exports


SLOW = "import time\ntime.sleep(1.5)  # a long compile: the window two starting processes share\n" + MODULE

MISSES = """
import sys
sys.path.insert(0, sys.argv[1])
from pipeline.model.jit import compiled_loops
twice = compiled_loops("slowloops").twice
print(sum(twice.stats.cache_misses.values()), sum(twice.stats.cache_hits.values()))
"""


def test_processes_starting_at_once_compile_a_loops_module_once(tmp_path):
    """Two processes on a fresh cache (a study's two workers on a new machine): the first
    compiles, the second waits for its lock and loads the cache it wrote; without the lock both
    would compile (both import while no cache exists)."""
    (tmp_path / "slowloops.py").write_text(textwrap.dedent(SLOW))
    procs = [subprocess.Popen([sys.executable, "-c", MISSES, str(tmp_path)], stdout=subprocess.PIPE, text=True)
             for _ in range(2)]
    counts = sorted(tuple(map(int, proc.communicate(timeout=120)[0].split())) for proc in procs)
    assert counts == [(0, 1), (1, 0)]  # (cache misses, cache hits): one compiled, one loaded
    assert (tmp_path / "__pycache__" / "slowloops.compile.lock").exists()


def test_the_first_compile_is_counted_until_numbas_cache_is_newer_than_the_module(tmp_path, monkeypatch):
    """compile_seconds: a module without a cache beside it, or with one older than its source
    (numba compiles again), costs its first compile; a cache at least as new costs nothing."""
    import os

    (tmp_path / "loopsmod.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(jit.COMPILE_S, "loopsmod", 9.0)
    assert jit.compile_seconds("loopsmod") == 9.0
    (tmp_path / "__pycache__").mkdir(exist_ok=True)
    index = tmp_path / "__pycache__" / "loopsmod.f-1.py311.nbi"
    index.write_bytes(b"")
    source = (tmp_path / "loopsmod.py").stat().st_mtime
    os.utime(index, (source + 5, source + 5))
    assert jit.compile_seconds("loopsmod") == 0.0
    os.utime(tmp_path / "loopsmod.py", (source + 10, source + 10))  # the module edited since
    assert jit.compile_seconds("loopsmod") == 9.0

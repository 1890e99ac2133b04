"""The two ways pipeline.model.jit runs numba's loops.

Just in time: a numba cache left half written (a process killed while numba wrote it, a full
disk) must not stop every later compiled job: call_compiled removes it and compiles again.

Ahead of time (compiled_loops): an extension built once per text of the loops module, loaded
without numba, giving the bits numba's own functions give; built again when damaged or when the
text changes; built by one process while another waits; kept in the user's cache when the
module's folder cannot be written; numba's functions, with one warning, without a C compiler."""

import ast
import importlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from pipeline.model import crossings
from pipeline.workspace import fused_loops

MODULE = """
from numba import njit

@njit(cache=True)
def twice(values, out):
    for i in range(values.shape[0]):
        out[i] = 2.0 * values[i]
"""

CALL = """
import logging, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
logging.basicConfig(level=logging.WARNING)
from healme import twice
from pipeline.model.jit import call_compiled
out = np.empty(3)
if sys.argv[2] == "healing":
    call_compiled(twice, np.arange(3.0), out)
else:
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
from conftest import make_cfg
from pipeline.model import crossings
from pipeline.model.catalogue import load_catalogue
import importlib
from pipeline.workspace import fused, fused_loops
from pipeline.workspace.compute import compute_workspace

from pipeline.model import jit
fused.compiled_loops = jit.compiled_loops = importlib.import_module  # numba's own functions, not the extensions

make, catalogue = make_cfg.__wrapped__(), load_catalogue()
for overrides in (["compute.kernel=fused", "grid.n=4"], ["compute.kernel=fused", "grid.n=4", "orientation.psi=0.5"],
                  ["compute.kernel=fused", "grid.n=4", "tension.t_max=[9e3,9e3,9e3,9e3,9e3,9e3,9e3,9e3]"],
                  ["compute.kernel=fused", "grid.n=4", "model.pinv_columns=translational"],
                  ["robot=irpm6", "compute.kernel=fused", "robot.search.step=2"],
                  ["robot=irpm6", "compute.kernel=fused", "robot.search.step=2", "tension.t_min=[1,1,1,1,1,1]"],
                  ["tension=feasible", "grid.n=3"], ["robot=irpm6", "tension=feasible", "robot.search.step=2"]):
    compute_workspace(make(*overrides), catalogue)
for module in (fused_loops, crossings):
    for name, value in sorted(vars(module).items()):
        if isinstance(value, numba.core.registry.CPUDispatcher):
            print(module.__name__, name, len(value.signatures))
"""


def test_each_compiled_function_has_one_specialisation():
    """A literal argument (``6``, ``False``) or a read-only array is another type to numba, which
    compiles (seconds) and caches the function once more for it: the papers' robots, with scalar
    and per-cable limits, both readings and the feasible tension model use one of each."""
    done = subprocess.run([sys.executable, "-c", SPECIALISATIONS, str(Path(__file__).parent)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    counts = dict(line.rsplit(" ", 1) for line in done.stdout.splitlines())
    assert len(counts) >= 10 and set(counts.values()) <= {"0", "1"}, counts


LOOPS = """
import numpy as np
from numba import njit

EXPORTS = {"spread": "void(f8[::1], f8, f8[:, ::1])"}


@njit(cache=True)
def _scaled(value, factor):
    return np.sqrt(value) * factor + 1.0 / (value + 3.0)


@njit(cache=True)
def spread(values, factor, out):
    for i in range(values.shape[0]):
        out[i, 0] = _scaled(values[i], factor)
        out[i, 1] = np.sin(values[i]) * np.exp(-values[i] * factor)
"""

LOAD = """
import logging, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
logging.basicConfig(level=logging.INFO, format="%(levelname)s %(message)s")
from pipeline.model.jit import compiled_loops
loops = compiled_loops("aotme")
values = np.linspace(0.0, 7.0, 1001)
out = np.empty((1001, 2))
loops.spread(values, 0.37, out)
print(out.tobytes().hex(), getattr(loops, "__file__", ""), "numba" in sys.modules)
"""


def load(folder, **env):
    """(bits of the loops' result, the file they came from, whether numba was imported, stderr)"""
    done = subprocess.run([sys.executable, "-c", LOAD, str(folder)], capture_output=True, text=True,
                          timeout=300, env={**os.environ, "XDG_CACHE_HOME": str(folder / "cache"), **env})
    assert done.returncode == 0, done.stderr[-3000:]
    bits, path, numba = done.stdout.split()
    return bits, Path(path), numba == "True", done.stderr


def numba_bits(folder):
    """The result of the module's own functions (numba just in time), in this process."""
    sys.path.insert(0, str(folder))
    try:
        import numpy as np
        module = importlib.import_module("aotme")
        out = np.empty((1001, 2))
        module.spread(np.linspace(0.0, 7.0, 1001), 0.37, out)
        return out.tobytes().hex()
    finally:
        sys.path.remove(str(folder))
        sys.modules.pop("aotme", None)


def test_loops_built_ahead_of_time_load_without_numba_and_are_rebuilt_when_damaged_or_changed(tmp_path):
    (tmp_path / "aotme.py").write_text(textwrap.dedent(LOOPS))
    expected = numba_bits(tmp_path)
    bits, path, numba, err = load(tmp_path)  # builds it
    assert bits == expected and path.parent == tmp_path / "__pycache__" and path.suffix == ".so"
    assert "compiling the loops of aotme ahead of time" in err
    bits, again, numba, err = load(tmp_path)
    assert (bits, again, numba) == (expected, path, False) and "compiling" not in err
    path.write_bytes(path.read_bytes()[:4096])  # damaged
    bits, again, numba, err = load(tmp_path)
    assert (bits, again) == (expected, path) and "is damaged" in err and "building it again" in err
    (tmp_path / "aotme.py").write_text(textwrap.dedent(LOOPS).replace("+ 3.0", "+ 4.0"))
    bits, changed, numba, err = load(tmp_path)
    assert changed != path and bits != expected and "compiling the loops of aotme" in err
    assert sorted(p.name for p in (tmp_path / "__pycache__").glob("aotme_*")) == [
        changed.name, changed.name + ".sha256"]  # the old one gone


def test_two_processes_at_once_build_once_and_an_unwritable_folder_uses_the_user_cache(tmp_path):
    (tmp_path / "aotme.py").write_text(textwrap.dedent(LOOPS))
    (tmp_path / "__pycache__").write_text("a file where the folder would be")  # cannot be written
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    both = [subprocess.Popen([sys.executable, "-c", LOAD, str(tmp_path)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env=env) for _ in range(2)]
    outcomes = [process.communicate(timeout=300) for process in both]
    assert [process.returncode for process in both] == [0, 0], outcomes
    assert sum("compiling the loops of aotme" in err for _, err in outcomes) == 1
    results = {out.split()[0] for out, _ in outcomes}
    paths = {Path(out.split()[1]) for out, _ in outcomes}
    assert results == {numba_bits(tmp_path)}
    assert len(paths) == 1 and next(iter(paths)).parent == tmp_path / "cache" / "cdpr-studies"


@pytest.mark.parametrize("broken", [{"CC": "no-such-compiler"}, {"LDSHARED": "false"}])
def test_without_a_c_compiler_or_a_linker_the_loops_run_through_numba_with_one_warning(tmp_path, broken):
    """No C compiler (refused before numba compiles anything), or a link that fails (as a full
    disk would): numba's own functions, the same bits, one warning, no extension left behind."""
    (tmp_path / "aotme.py").write_text(textwrap.dedent(LOOPS))
    bits, path, numba, err = load(tmp_path, **broken)
    assert bits == numba_bits(tmp_path) and path == tmp_path / "aotme.py" and numba
    assert err.count("WARNING the compiled loops of aotme could not be built ahead of time") == 1
    assert not list(tmp_path.rglob("aotme_*.so*")) and not list(tmp_path.rglob(".aotme_*"))


@pytest.mark.parametrize("module, exports", [(fused_loops, {"cpr_wwa", "statics"}),
                                             (crossings, {"least_margins"})])
def test_the_compiled_loops_use_nothing_but_their_own_text(module, exports):
    """An extension is keyed by its loops module's text, and numba's cache of the functions it
    compiles just in time (no C compiler) by the module's file: the compiled code may use numpy,
    numba and the module's own names only (any other value is an argument), else a constant
    imported from another module would be kept, stale, after that module changed."""
    tree = ast.parse(Path(module.__file__).read_text())
    assert not [alias.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                for alias in node.names if alias.name not in ("numpy", "numba")]
    assert all(node.level == 0 and node.module in ("__future__", "numpy", "numba")
               for node in ast.walk(tree) if isinstance(node, ast.ImportFrom))
    assert set(module.EXPORTS) == exports

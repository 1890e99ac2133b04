"""A numba cache left half written (a process killed while numba wrote it, a full disk) must not
stop every later compiled job: pipeline.model.jit.call_compiled removes it and compiles again."""

import subprocess
import sys
import textwrap
from pathlib import Path

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
from pipeline.workspace import fused
from pipeline.workspace.compute import compute_workspace

make, catalogue = make_cfg.__wrapped__(), load_catalogue()
for overrides in (["compute.kernel=fused", "grid.n=4"], ["compute.kernel=fused", "grid.n=4", "orientation.psi=0.5"],
                  ["compute.kernel=fused", "grid.n=4", "tension.t_max=[9e3,9e3,9e3,9e3,9e3,9e3,9e3,9e3]"],
                  ["compute.kernel=fused", "grid.n=4", "model.pinv_columns=translational"],
                  ["robot=irpm6", "compute.kernel=fused", "robot.search.step=2"],
                  ["robot=irpm6", "compute.kernel=fused", "robot.search.step=2", "tension.t_min=[1,1,1,1,1,1]"],
                  ["tension=feasible", "grid.n=3"], ["robot=irpm6", "tension=feasible", "robot.search.step=2"]):
    compute_workspace(make(*overrides), catalogue)
for module in (fused, crossings):
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

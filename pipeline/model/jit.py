"""numba's compiled loops (``pipeline.model.crossings``, ``pipeline.workspace.fused_loops``), loaded
once a process.

A loops module declares ``SIGNATURES`` (name -> numba signature) and decorates those functions
with ``@njit(SIGNATURES[name], cache=True)``: numba compiles them, with everything they call,
when the module is first imported on a machine (seconds, once) and keeps the machine code in
its cache (``__pycache__`` beside the module, or numba's user cache where that cannot be
written); later processes load it (numba's import and the cache, what
``pipeline.workspace.dispatch.FUSED_START_S`` allows for; docs/performance.md). A signature also keeps
numba from compiling a second specialisation for another argument type (a literal, a read-only
array): such a call is a TypeError instead of seconds of compiling.

:func:`compiled_loops` imports a loops module and says, while it waits, that numba is compiling.
A process killed while numba writes its cache (or a full disk) leaves a truncated file, on which
numba then fails at every import with a pickle error instead of compiling again: the module's
cache files are removed, with a warning, and it is compiled once more.

numba keys its cache by the module's file (its time stamp and size), not by what the code reads
from other modules: the compiled code must depend on the loops module's own text only (numpy,
numba, its own constants; any other value is an argument), which ``tests/test_jit.py`` checks.
The functions are compiled with numba's default options (no fast-math, so no fused multiply-add).
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import importlib
import importlib.util
import logging
import os
import pickle
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType

log = logging.getLogger(__name__)
# numba's first compile of each loops module on a machine (docs/performance.md; benchmarks/LOG.md, 2026-11-26;
# the fused loops' with their blocks of poses 2026-11-30, with the deflated route in blocks 45 s)
COMPILE_S = {"pipeline.workspace.fused_loops": 45.0, "pipeline.model.crossings": 9.0, "pipeline.model.faces": 2.5,
             "pipeline.model.nullspace": 4.0, "pipeline.model.rounding": 1.0}


def compile_seconds(name: str) -> float:
    """The seconds numba will spend compiling the loops module ``name`` at its first use here:
    0 when its cache beside it is at least as new as the module (a cache kept elsewhere, or a
    stale one numba finds unusable, counts as none: the estimate errs long)."""
    origin = Path(importlib.util.find_spec(name).origin)
    newest = max((p.stat().st_mtime for p in (origin.parent / "__pycache__").glob(f"{origin.stem}.*.nbi")), default=0.0)
    return 0.0 if newest >= origin.stat().st_mtime else COMPILE_S.get(name, 1.0)


@functools.cache
def compiled_loops(name: str) -> ModuleType:
    """The loops module ``name``, compiled (or loaded from numba's cache) once a process; its
    cache compiled again, with a warning, where it cannot be read. Processes that start at once
    on a fresh machine (a study's two workers, the test suite's) compile it once: each holds a
    lock on the module's compile while it imports it, so the others wait and then load the
    cache the first one wrote."""
    origin = Path(importlib.util.find_spec(name).origin)
    with _compile_lock(origin):
        try:
            return _timed_import(name)
        except (pickle.UnpicklingError, EOFError) as exc:  # a half-written cache file
            log.warning("numba's cache of %s is unreadable (%s): removed, compiling again", origin.name, exc)
            for path in (origin.parent / "__pycache__").glob(f"{origin.stem}.*.nb[ic]"):
                path.unlink(missing_ok=True)
            sys.modules.pop(name, None)
            return _timed_import(name)


@contextlib.contextmanager
def _compile_lock(origin: Path):
    """An exclusive lock on the compile of the loops module at ``origin``: a file beside numba's
    cache, or in the temporary folder where that cannot be written."""
    folder = origin.parent / "__pycache__"
    if not os.access(folder if folder.is_dir() else origin.parent, os.W_OK):
        digest = hashlib.sha256(str(origin).encode()).hexdigest()[:16]
        folder = Path(tempfile.gettempdir()) / f"cdpr-numba-{digest}"
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / f"{origin.stem}.compile.lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _timed_import(name: str) -> ModuleType:
    """Import the loops module ``name``, announcing numba's compile only where one happens (no
    cache of the module's version here: a warm run of a loaded machine, whose cache loads slowly,
    said it was compiling), with the range measured: an idle core's time, several times that
    loaded (84 s for the fused loops' 17)."""
    compiling = compile_seconds(name) > 0
    if compiling:
        log.info("numba is compiling the loops of %s, once per machine and version of the file: about %.0f s on "
                 "an idle core, up to 5 times that on a loaded machine", name, COMPILE_S.get(name, 1.0))
    start = time.perf_counter()
    module = importlib.import_module(name)
    if compiling:
        log.info("compiled the loops of %s in %.1f s (kept in numba's cache)", name, time.perf_counter() - start)
    return module

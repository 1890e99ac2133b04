"""Running the loops that numba compiles (``pipeline.model.crossings``,
``pipeline.workspace.fused_loops``), in one of two ways:

- **ahead of time** (:func:`compiled_loops`): a loops module that declares ``EXPORTS`` (name ->
  signature) is compiled by ``numba.pycc`` into an extension module, once for each text of the
  module, and kept in the ``__pycache__`` folder beside it (or the user's cache folder,
  ``$XDG_CACHE_HOME/cdpr-studies``, where that one cannot be written). A process then loads its
  loops in about a millisecond without importing numba, whose import and the registries it
  loads with a cached function (``scipy.linalg`` among them) cost 0.3 s of CPU in every process
  (docs/performance.md). Building it takes 8-17 s once and needs a C compiler; the first
  process that needs it builds it while the others wait (a lock), and writes it under a
  temporary name renamed when whole, with its digest beside it: an extension that does not
  match its digest (damaged) is built again, never loaded; where none can be built (no C compiler, no
  setuptools, no writable folder), the module's own functions run, compiled by numba in that
  process, with one warning a process.
- **just in time** (:func:`call_compiled`): numba caches the machine code of ``cache=True``
  functions in ``__pycache__``. A process killed while numba writes that cache (or a full disk)
  leaves a truncated file, and numba then fails on every later call with a pickle error instead
  of compiling again. So a call that meets an unreadable cache removes the module's cache files,
  says so, and compiles once more: the result is the same, only the first call is slower.

Either way the compiled code must depend on the loops module's own text only (numpy, numba,
its own constants; any other value is an argument): that text is the extension's key, and
numba keys its cache of the just-in-time functions by the module's file alone, so a constant
imported from another module would be kept, stale, after that module changed
(``tests/test_jit.py`` checks the imports).

Both ways compile the same functions, with numba's default options (no fast-math, so no fused
multiply-add), for the generic CPU of the platform (ahead of time) or this one (just in time);
``tests/test_jit.py`` checks that they give the same bits.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
import importlib
import importlib.machinery
import importlib.util
import inspect
import logging
import os
import pickle
import re
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from types import ModuleType

from pipeline.errors import one_line

log = logging.getLogger(__name__)

# Part of an extension's key with the module's text: a change in how extensions are built
# builds them again.
BUILD = b"numba.pycc, generic CPU, 1\n"
BUILD_TIMEOUT_S = 600


def call_compiled(function, *args):
    """``function(*args)`` for a numba function compiled with ``cache=True``, compiled again
    (its module's cache files removed, with a warning) when its cache cannot be read; any other
    compiled function (an extension's) is simply called."""
    try:
        return function(*args)
    except (pickle.UnpicklingError, EOFError) as exc:  # a half-written cache file
        module = Path(inspect.getfile(function.py_func))
        log.warning("numba's cache of %s is unreadable (%s): removed, compiling again", module.name, exc)
        for path in (module.parent / "__pycache__").glob(f"{module.stem}.*.nb[ic]"):
            path.unlink(missing_ok=True)
        return function(*args)


@functools.cache
def compiled_loops(name: str) -> ModuleType:
    """The loops of module ``name`` (its ``EXPORTS``) as an extension module built ahead of
    time, loaded or built once a process; the module itself (numba's just-in-time functions),
    with a warning, where no extension can be built."""
    origin = Path(importlib.util.find_spec(name).origin)
    stem = f"{origin.stem}_{hashlib.sha256(BUILD + origin.read_bytes()).hexdigest()[:16]}"
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    reasons = []
    for folder in (origin.parent / "__pycache__", user_cache()):
        try:
            return _load_or_build(name, folder, stem, suffix)
        except OSError as exc:  # this folder cannot be written: the next one
            reasons.append(f"{folder}: {one_line(exc)}")
        except Exception as exc:  # no compiler or pycc, a failed compile or link: not the folder's
            reasons.append(f"{folder}: {one_line(exc)}")
            break
    log.warning("the compiled loops of %s could not be built ahead of time (%s): numba compiles them "
                "in this process instead (about 0.3 s more per process; a C compiler and setuptools "
                "avoid it)", name, "; ".join(reasons))
    return importlib.import_module(name)


def user_cache() -> Path:
    """The user's cache folder of this package (XDG's rule)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "cdpr-studies"


def _load_or_build(name: str, folder: Path, stem: str, suffix: str) -> ModuleType:
    path = folder / f"{stem}{suffix}"
    if _whole(path):
        return _load(stem, path)
    if path.exists():
        log.warning("%s is damaged (not the file that was built): building it again", path)
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / f"{stem.rsplit('_', 1)[0]}.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # another process's build finishes first
        if not _whole(path):
            _build(name, stem, folder, path)
    return _load(stem, path)


def _whole(path: Path) -> bool:
    """Whether ``path`` is the extension as built, by the digest written beside it: loading a
    damaged one would not fail cleanly (a truncated shared library ends the process with
    SIGBUS)."""
    try:
        recorded = path.with_name(path.name + ".sha256").read_text()
        return hashlib.sha256(path.read_bytes()).hexdigest() == recorded
    except OSError:  # not built (yet)
        return False


def _load(stem: str, path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _build(name: str, stem: str, folder: Path, path: Path) -> None:
    """Compile ``name``'s EXPORTS into the extension ``path``, and remove the extensions of
    the module's earlier texts. The compiler runs in a process of its own, whose numba cache is
    empty (the extension is compiled from the text it is keyed by, not from numba's cache,
    keyed by the file's time and size), and this process does not import numba."""
    start = time.perf_counter()
    log.info("compiling the loops of %s ahead of time (once for this version of its text)", name)
    with tempfile.TemporaryDirectory(dir=folder, prefix=f".{stem}-") as scratch:
        env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(scratch) / "numba"),
               "PYTHONPATH": os.pathsep.join(entry or os.getcwd() for entry in sys.path)}
        done = subprocess.run([sys.executable, "-m", __name__, name, stem, scratch], env=env,
                              capture_output=True, text=True, timeout=BUILD_TIMEOUT_S)
        if done.returncode != 0:
            errors = re.findall(r"^(?:\w+\.)*\w*(?:Error|Exception): .*$", done.stderr, re.MULTILINE)
            raise RuntimeError(errors[-1] if errors
                               else done.stderr.strip()[-500:] or f"exit {done.returncode}")
        built = Path(scratch) / done.stdout.strip()
        digest = built.with_name(built.name + ".sha256")
        digest.write_text(hashlib.sha256(built.read_bytes()).hexdigest())
        os.replace(built, path)  # each file whole or absent: a reader checks one against the other
        os.replace(digest, path.with_name(path.name + ".sha256"))
    for older in folder.glob(f"{stem.rsplit('_', 1)[0]}_*{path.name[len(stem):]}*"):
        if not older.name.startswith(stem):
            older.unlink(missing_ok=True)
    log.info("compiled %s in %.1f s", path, time.perf_counter() - start)


def _compile(name: str, stem: str, output_dir: str) -> None:
    """The compiler's process (``python -m pipeline.model.jit NAME STEM DIR``): ``name``'s
    EXPORTS into DIR/<the extension's file name>, which it prints."""
    with warnings.catch_warnings():  # pycc is "pending deprecation" since numba 0.57
        warnings.simplefilter("ignore")
        from numba.pycc import CC
    module = importlib.import_module(name)
    compiler = CC(stem, source_module=module)  # RuntimeError at once without a C compiler
    compiler.output_dir = output_dir
    for export, signature in module.EXPORTS.items():
        compiler.export(export, signature)(getattr(module, export).py_func)
    compiler.compile()
    print(compiler.output_file)


if __name__ == "__main__":
    _compile(*sys.argv[1:])

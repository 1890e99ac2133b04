"""Calling the numba-compiled loops (``pipeline.model.crossings``, ``pipeline.workspace.fused``),
whose machine code numba caches in the ``__pycache__`` folder beside their module.

A process killed while numba writes that cache (or a full disk) leaves a truncated file, and
numba then fails on every later call with a pickle error instead of compiling again. So a call
that meets an unreadable cache removes the module's cache files, says so, and compiles once
more: the result is the same, only the first call is slower.
"""

from __future__ import annotations

import inspect
import logging
import pickle
from pathlib import Path

log = logging.getLogger(__name__)


def call_compiled(function, *args):
    """``function(*args)`` for a numba function compiled with ``cache=True``, compiled again
    (its module's cache files removed, with a warning) when its cache cannot be read."""
    try:
        return function(*args)
    except (pickle.UnpicklingError, EOFError) as exc:  # a half-written cache file
        module = Path(inspect.getfile(function.py_func))
        log.warning("numba's cache of %s is unreadable (%s): removed, compiling again", module.name, exc)
        for path in (module.parent / "__pycache__").glob(f"{module.stem}.*.nb[ic]"):
            path.unlink(missing_ok=True)
        return function(*args)

"""Chunked parallel map over poses: one level of parallelism, one task per chunk of poses.

Follows scikit-learn's ``_parallel_pairwise``: the poses are split into contiguous slices, each
worker evaluates the vectorised kernel on its slice, and results are concatenated in order. A
problem that fits in a single chunk runs in-process (no pool start-up). The joblib backend is a
parameter, so another engine registered with joblib is a configuration change.
"""

from __future__ import annotations

import logging
import math
from typing import Callable

import numpy as np
from joblib import Parallel, delayed, effective_n_jobs

log = logging.getLogger(__name__)


def chunk_slices(n_items: int, n_jobs: int, chunk_size: int) -> list[slice]:
    """Contiguous slices: at least one per worker when there is enough work, none over chunk_size."""
    n_chunks = max(math.ceil(n_items / chunk_size), 1)
    if n_items > chunk_size:
        n_chunks = max(n_chunks, n_jobs)
    bounds = np.linspace(0, n_items, n_chunks + 1).round().astype(int)
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def map_chunks(
    function: Callable[..., dict[str, np.ndarray]],
    problem,
    positions: np.ndarray,
    n_jobs: int = 2,
    backend: str = "loky",
    chunk_size: int = 20_000,
) -> dict[str, np.ndarray]:
    """``function(problem, positions[s])`` for every chunk s, concatenated per output key."""
    workers = effective_n_jobs(n_jobs)
    slices = chunk_slices(len(positions), workers, chunk_size)
    if len(slices) <= 1 or workers == 1:
        parts = []
        for i, s in enumerate(slices, start=1):
            parts.append(function(problem, positions[s]))
            _progress(i, len(slices))
    else:
        runner = Parallel(n_jobs=workers, backend=backend, return_as="generator")
        parts = []
        for i, part in enumerate(runner(delayed(function)(problem, positions[s]) for s in slices), 1):
            parts.append(part)
            _progress(i, len(slices))
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}


def _progress(done: int, total: int) -> None:
    if total > 1:
        log.info("chunk %d/%d done (%.0f%%)", done, total, 100.0 * done / total)

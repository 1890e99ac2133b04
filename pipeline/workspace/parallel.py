"""Chunked parallel map over poses: one level of parallelism, one task per chunk of poses.

Follows scikit-learn's ``_parallel_pairwise``: the poses are split into contiguous slices, each
worker evaluates the vectorised kernel on its slice, and the results come back in order. A
problem that fits in a single chunk runs in-process (no pool start-up). The joblib backend is a
parameter: ``threading`` (the default) runs the chunks on threads of this process, which the
compiled loops (``nogil``) and numpy's array work leave free to run at once, with no second
interpreter's memory; ``loky`` on worker processes; ``dask`` sends the same chunks to a Dask distributed cluster (the scheduler at
``scheduler``, or a local cluster of ``n_jobs`` single-threaded worker processes) through
joblib's dask backend, with no other change.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
from typing import Callable, Iterator

import numpy as np

from pipeline.errors import ConfigError, one_line
from pipeline.workspace.progress import Progress

log = logging.getLogger(__name__)
SCHEDULER_TIMEOUT_S = 10  # a named Dask scheduler that has not answered by then is not there
CHUNK_REPORT_S = 10.0  # a line about the chunks at most this often (and at the end)


def chunk_slices(n_items: int, n_jobs: int, chunk_size: int) -> list[slice]:
    """Contiguous slices: at least one per worker when there is enough work, none over chunk_size."""
    n_chunks = max(math.ceil(n_items / chunk_size), 1)
    if n_items > chunk_size:
        n_chunks = max(n_chunks, n_jobs)
    bounds = np.linspace(0, n_items, n_chunks + 1).round().astype(int)
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def iter_chunks(
    function: Callable[..., dict[str, np.ndarray]],
    problem,
    positions,
    n_jobs: int = 2,
    backend: str = "threading",
    chunk_size: int = 20_000,
    scheduler: str | None = None,
    estimate: float | None = None,
) -> Iterator[tuple[slice, dict[str, np.ndarray]]]:
    """(slice, ``function(problem, positions[slice])``) for every chunk, in order, as each
    finishes: a caller can write results out chunk by chunk (bounded memory). ``positions``: an
    (n, 3) array or a ``Grid``, whose chunks are made as they are dispatched; ``estimate``: the
    cost model's seconds for them all, the progress lines' time left until the rate is measured."""
    here = backend != "dask" or not scheduler  # loky, or a Dask cluster started on this machine
    workers = local_workers(n_jobs) if here else n_jobs if n_jobs > 0 else 1
    slices = chunk_slices(len(positions), workers, chunk_size)
    progress = Progress("chunks", len(slices), log, every=CHUNK_REPORT_S, estimate=estimate)
    if (len(slices) <= 1 or workers == 1) and here:  # a named scheduler gets the work it was named for
        for s in slices:
            yield s, function(problem, positions[s])
            progress.step()
        return
    from joblib import Parallel, delayed  # only here: imports a one-chunk job skips

    with _engine(backend, workers, scheduler) as joblib_backend:
        runner = Parallel(n_jobs=workers, backend=joblib_backend, return_as="generator")
        tasks = (delayed(function)(problem, positions[s]) for s in slices)
        for s, part in zip(slices, runner(tasks)):
            yield s, part
            progress.step()


def local_workers(n_jobs: int) -> int:
    """Worker processes on this machine for ``compute.n_jobs`` (joblib's rule for a negative
    count), capped at its cores, with a warning: more would only thrash memory."""
    workers = n_jobs if n_jobs > 0 else max((os.cpu_count() or 1) + 1 + n_jobs, 1)
    if workers > (os.cpu_count() or 1):
        log.warning("compute.n_jobs=%d: capped at the %d cores of this machine", n_jobs, os.cpu_count())
        workers = os.cpu_count() or 1
    return workers


@contextlib.contextmanager
def local_cluster(workers: int):
    """A Dask cluster of ``workers`` single-threaded worker processes on this machine while the
    block runs, its client the process's current one: the chunks of every job run meanwhile
    with ``compute.backend=dask`` and no scheduler go to it (:func:`_engine`), so a sweep
    starts one cluster (``pipeline.app.run``), not one per job."""
    distributed = _distributed()
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        yield client


def _current_client():
    """The process's current Dask client (a sweep's cluster, :func:`local_cluster`), or None."""
    try:
        return _distributed().Client.current()
    except ValueError:  # none
        return None


def _distributed():
    """``dask.distributed``, its loggers at WARNING (dozens of INFO lines per cluster otherwise)
    unless the run asked for their debug lines (``hydra.verbose=true`` or ``=[distributed]`` set
    its logger, or the root's, to DEBUG: read before Dask's import sets its loggers' levels)."""
    verbose = logging.getLogger("distributed").isEnabledFor(logging.DEBUG)
    import dask.distributed

    if not verbose:
        logging.getLogger("distributed").setLevel(logging.WARNING)
    return dask.distributed


def _client(scheduler: str):
    """A client of the Dask scheduler at ``scheduler``; ConfigError when none answers there
    within SCHEDULER_TIMEOUT_S (the work is never done here instead, without a word)."""
    try:
        return _distributed().Client(scheduler, timeout=SCHEDULER_TIMEOUT_S)
    except (OSError, ValueError, TypeError) as exc:  # refused, no answer, or not an address
        raise ConfigError(f"compute.scheduler={scheduler}: no Dask scheduler answers there ({one_line(exc)}); "
                          "start one (dask scheduler) or set compute.scheduler=null for a local cluster") from None


def check_scheduler(scheduler: str) -> None:
    """ConfigError unless a Dask scheduler answers at ``scheduler`` (a job's pre-flight)."""
    _client(scheduler).close()


@contextlib.contextmanager
def _engine(backend: str, workers: int, scheduler: str | None):
    """The joblib backend to pass to Parallel; for Dask, None (the backend set by
    ``parallel_config``) with a client connected while it is in use."""
    if backend != "dask":
        yield backend
        return
    from joblib import parallel_config

    if scheduler:
        context = _client(scheduler)
    else:  # the sweep's cluster, else one for this job
        current = _current_client()
        context = contextlib.nullcontext(current) if current is not None else local_cluster(workers)
    with context as client, parallel_config(backend="dask"):
        log.info("chunks on the Dask cluster %s", client.scheduler.address)
        yield None

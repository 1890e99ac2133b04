"""The cost model: every decision of how work runs, from measured speeds (docs/performance.md,
benchmarks/LOG.md). :func:`decide` chooses a job's kernel, chunk size and chunk workers;
:func:`fused_pays` whether a sweep pays for the compiled kernels; :func:`workers_pay` whether
job worker processes pay for their start; :func:`announce_cost` warns before a long or large
job. Parallelism is at one level: job workers run their jobs' chunks here (``compute.n_jobs=1``
under a study's pool), and a job alone uses chunk workers only where they pay.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, replace

from omegaconf import DictConfig

from pipeline.model.dynamics import REFERENCE_SET
from pipeline.model.metrics import WORK as METRICS_WORK
from pipeline.workspace.criteria import GEOMETRY, REGISTRY
from pipeline.workspace.fused import COMPILED
from pipeline.workspace.quantities import WORK as CABLES_WORK
from pipeline.workspace.kernel import WorkspaceProblem
from pipeline.workspace.progress import clock_text

log = logging.getLogger("pipeline")

CHUNK_BUDGET_FLOATS = 500_000  # largest (poses x cables x set size) array of one chunk: 4 MB
FUSED_CHUNK_FLOATS = 4_000_000  # the fused kernel holds no such array, only its (poses x cables) outputs: 32 MB
FEASIBLE_CHUNK_POSES = 4096  # tension.model=feasible: about 1 s per chunk, so progress is visible
CHUNK_POSES = 20_000  # compute.chunk_size=null: a chunk's poses, between 2 000 and 20 000 barely matter
# On Dask a chunk carries at least DASK_CHUNK_S of kernel by the cost model: a task's round
# trip through the scheduler costs milliseconds, and the default 20 000 poses are 20 ms of the
# fused kernel (benchmarks/LOG.md, 2026-11-26: 10^7 fused poses on a 2-worker local cluster
# x1.26 loky's wall with 20 000-pose chunks, x1.16 with 200 000; 500 000 and 10^6 no better)
DASK_CHUNK_S = 0.2


# Cost model of the choice between chunk workers and this process alone (docs/performance.md).
# A worker thread (compute.backend=threading, the default) shares this process: the compiled
# loops run without the GIL (nogil) and numpy's array work releases it, so two threads run two
# chunks at once for about THREAD_START_S (the pool, the hand-offs of the GIL) and no memory but
# the chunks in flight (benchmarks/LOG.md, 2026-11-29: 3 x 10^5 fused poses 1.73-2.25 s wall on
# two threads against 1.99-2.55 s alone; 40 000 numpy poses about even). A worker process (loky,
# multiprocessing) costs about WORKER_START_S of CPU before its first chunk (process start and
# the kernel's imports, numpy only) and its own interpreter's memory (about 190 MiB). Two workers
# at best halve the kernel time, so they pay off when the kernel alone would take more than
# twice their start here. Kernel speeds per core,
# measured by benchmarks/bench_kernel.py and bench_feasible.py (lower ends of their ranges).
# The speeds hold for the paper's set of 93 velocities per pose (grid.n_vel = 6) and the statics
# of one wrench; a pose's cost grows with its set (each spec's ``work()``: its velocities, a wrench
# set's vertices, the payload's LP). A job estimated above LONG_JOB_S is announced with a warning.
WORKER_START_S = 0.4
THREAD_START_S = 0.1
# The compiled kernels cost a process FUSED_START_S to load from numba's cache (numba's import,
# with scipy.linalg, and the machine code: pipeline.model.jit), and the first process on a machine
# compiles them: a job whose numpy kernel would take less keeps it, so a small job never pays
# more than it could save.
FUSED_START_S = 0.4
# Fused chunks are computed several times faster than the parent classifies and writes them, so
# worker processes pay only for long fused jobs (benchmarks/LOG.md, 2026-11-24: about 1.5 x 10^6 poses).
FUSED_WORKERS_FROM_S = 1.5  # the fused kernel's time (cost model) from which workers are used
# Jobs at a time (hydra.launcher.n_jobs, a study's pool): a job worker imports the whole job's
# code (Hydra, pandas, pyarrow) and loads numba's cache, about JOB_WORKER_START_S of wall each
# before its first job, and a job also writes its files (JOB_S each, a 216-pose study job in a
# warm process); the straight lines of ``analysis=lines`` cost LINE_SAMPLES kernel poses per
# line, 2 N^2 lines (benchmarks/LOG.md, 2026-11-26: the CPR-8's 72 lines, 26 388 samples).
JOB_WORKER_START_S = 1.0
JOB_S = 0.012
LINE_SAMPLES = 370
# A paper pose per second on one core, whole process (benchmarks/LOG.md, 2026-11-26): the numpy
# kernel 82 000 at the zero orientation (rank 5: every pose takes the SVD) and about 190 000 at
# 0.5 rad, so 150 000 keeps both within 2x (the IRPM's statics run 476 000); the feasible model
# 23 000; the fused kernel 1 000 000.
POSES_PER_SECOND = {"pinv": 150_000, "feasible": 20_000, "fused": 1_000_000}
# each obstacle's cable_obstacle test, numpy in either kernel: 3.1e-5 s per pose (CPR-8, 4 000
# poses: 0.21 s without, 1.9 s with 10 boxes, 12.6 s with 100; 2026-11-27)
OBSTACLE_SECONDS = 3.1e-5
LONG_JOB_S = 30.0
# Memory: a job holds the chunks in flight (each array within CHUNK_BUDGET_FLOATS), never the
# grid (pipeline.workspace.grid), so its peak is about PROCESS_BYTES whatever the grid's size
# (benchmarks/LOG.md, 2026-11-26: 226 MiB at 10^6 and at 10^7 poses in one process, 302-309 MiB
# from 4 x 10^6 to 2 x 10^7 poses with two workers, 330 MiB writing 10^7 points), plus 8 bytes
# per pose for each column it keeps whole. A job expected above LARGE_JOB_BYTES is announced.
PROCESS_BYTES = 320 * 2**20
LARGE_JOB_BYTES = 2 * 2**30


def estimated_seconds(problem: WorkspaceProblem, n_points: int) -> float:
    """The kernel's time for ``n_points`` positions on one core here, by the cost model."""
    evaluations = n_points * len(problem.orientations)
    model = problem.spec.tension.model
    per_pose = (problem.spec.work() + (METRICS_WORK[model] if problem.metrics else 0.0)
                + (CABLES_WORK[model] if problem.cables else 0.0))
    speed = POSES_PER_SECOND["fused" if problem.fused else problem.spec.tension.model]
    return evaluations * (per_pose / speed + OBSTACLE_SECONDS * len(problem.robot.obstacles))


def fused_unfit(problem: WorkspaceProblem) -> str | None:
    """Why the compiled kernels (``pipeline.workspace.fused``) cannot evaluate this problem; None
    when they can: the criteria of the spec's options they evaluate
    (:meth:`pipeline.model.dynamics.MotionSpec.fused_unfit`), no per-pose cable quantities, and
    no criterion it does not compile unless that one reads the pose alone (a registered criterion
    that reads the forces leaves the problem to the numpy kernel, which evaluates every one)."""
    if problem.cables:
        return "it does not write the per-pose cable quantities of output.cables=true"
    if problem.metrics:
        return "it does not write the per-pose metrics of output.metrics=true"
    if problem.robot.pulleys is not None:
        return "it models cables that leave fixed anchors (no robot.pulleys)"
    if len(problem.robot.dofs) != 6 and problem.spec.kind == "statics":
        return "it balances all six rows of a free platform only (robot.dofs)"
    unfit = problem.spec.fused_unfit()
    compiled = COMPILED.get(problem.spec.kind, ())
    foreign = [name for name in problem.criteria if name not in compiled and REGISTRY[name].reads != GEOMETRY]
    return unfit or (f"it does not compile the criterion {foreign[0]}" if foreign else None)


def use_fused(cfg: DictConfig, problem: WorkspaceProblem, n_points: int, sweep_pays: bool = False) -> bool:
    """``compute.kernel``: fused (checked by the config), numpy, or auto: the compiled kernels
    where they apply and either the job's sweep pays for them (``sweep_pays``, decided by the
    plan: a job's kernel follows from its sweep, never from what its process ran before) or the
    numpy kernel would take longer than their start (FUSED_START_S)."""
    kernel = getattr(cfg.compute.kernel, "name", cfg.compute.kernel)
    if kernel != "auto":
        return kernel == "fused"
    pays = sweep_pays or estimated_seconds(problem, n_points) > FUSED_START_S
    return pays and fused_unfit(problem) is None


def worth_workers(problem: WorkspaceProblem, n_points: int, n_jobs: int, backend: str) -> int:
    """``n_jobs``, or 1 when the cost model says local workers would not pay for their start:
    threads (``threading``) from 2 x THREAD_START_S of kernel; worker processes from 2 x
    WORKER_START_S (measured on 2 cores: 125 000 CPR-WWA poses took 1.13x the wall time and
    1.44x the CPU on two processes; 10^6 poses 0.7x the wall time), for the fused kernel from
    FUSED_WORKERS_FROM_S. A Dask cluster is the user's explicit choice."""
    if backend == "dask" or n_jobs == 1:
        return n_jobs
    serial_s = estimated_seconds(problem, n_points)
    if backend == "threading":
        threshold = 2 * THREAD_START_S
    else:
        threshold = FUSED_WORKERS_FROM_S if problem.fused else 2 * WORKER_START_S
    if serial_s > threshold:
        return n_jobs
    log.debug("compute.n_jobs=%d: about %.2f s of kernel, too little for %s workers to pay for their "
              "start; running here", n_jobs, serial_s, backend)
    return 1


def estimated_bytes(problem: WorkspaceProblem, n_points: int, keeps_points: bool) -> int:
    """The job's peak memory by the cost model: PROCESS_BYTES and 8 bytes per pose for each
    column kept whole: those the summary takes the median of (``spec.summarised``) and, for a
    caller that takes the points as one table (``keeps_points``: no sink), every point's row."""
    columns = len(problem.spec.summarised) + (8 + len(problem.criteria) if keeps_points else 0)
    return PROCESS_BYTES + 8 * columns * n_points


def announce_cost(cfg: DictConfig, problem: WorkspaceProblem, n_points: int, workers: int,
                  keeps_points: bool = False) -> None:
    """A warning before a job the cost model expects to take long or to need much memory, with
    the key that matters."""
    used = cores(workers)
    compiling = first_compile_seconds(problem)
    seconds = estimated_seconds(problem, n_points) / used + compiling
    memory = estimated_bytes(problem, n_points, keeps_points)
    if seconds < LONG_JOB_S and memory < LARGE_JOB_BYTES:
        return
    hint = ""
    if "n_vel" in cfg.get("grid", {}) and cfg.grid.n_vel is None and problem.spec.set_size() > REFERENCE_SET:
        hint = (f"; grid.n_vel is null (grid.n's), so each pose tests {problem.spec.set_size()} velocities "
                f"(grid.n_vel=6 tests {REFERENCE_SET}, as the paper's grid)")
    if problem.robot.obstacles:
        share = OBSTACLE_SECONDS * len(problem.robot.obstacles) * n_points * len(problem.orientations) / used
        hint += f"; its {len(problem.robot.obstacles)} obstacles take about {clock_text(share)} of it"
    size = f"{memory / 2**30:.1f} GiB" if memory >= 2**30 else f"{memory / 2**20:.0f} MiB"
    if compiling:
        hint += f"; this includes numba's first compile of the loops it needs, about {compiling:.0f} s, once per machine"
    log.warning("this job evaluates %d poses x %d orientations: about %s on %d core%s and %s of memory by "
                "the cost model%s", n_points, len(problem.orientations), clock_text(seconds), used,
                "" if used == 1 else "s", size, hint)


def cores(workers: int) -> int:
    """The cores ``workers`` chunk workers keep busy here (joblib's -1: every core)."""
    return min(max(workers, 1), os.cpu_count() or 1)


def first_compile_seconds(problem: WorkspaceProblem) -> float:
    """numba's compile of the loops this job runs, where this machine has not cached them yet:
    the fused kernels', the feasible model's search and its least-norm tensions
    (``pipeline.model.jit``)."""
    from pipeline.model.jit import compile_seconds

    tension = problem.spec.tension
    feasible = tension.model == "feasible"
    needed = (["pipeline.workspace.fused_loops"] if problem.fused else []) + (
        ["pipeline.model.crossings"] if feasible else []) + (
        ["pipeline.model.faces"] if feasible and tension.distribution == "min_norm" and (problem.cables or problem.metrics)
        else [])
    return sum(compile_seconds(name) for name in needed)


@dataclass(frozen=True)
class Dispatch:
    """How a job runs its grid: the problem with the kernel chosen (``problem.fused``), the poses
    per chunk, the chunk workers and the kernel's seconds by the cost model on them."""

    problem: WorkspaceProblem
    chunk_size: int
    workers: int
    seconds: float


def decide(cfg: DictConfig, problem: WorkspaceProblem, n_points: int, sweep_pays: bool = False) -> Dispatch:
    """The one decision of how a job of ``n_points`` poses runs: the kernel (:func:`use_fused`),
    the poses per chunk (:func:`bounded_chunk_size`; more than one chunk uses workers or a Dask
    cluster) and the chunk workers (:func:`worth_workers`)."""
    problem = replace(problem, fused=use_fused(cfg, problem, n_points, sweep_pays))
    compute = cfg.compute
    workers = worth_workers(problem, n_points, compute.n_jobs, compute.backend)
    return Dispatch(problem, bounded_chunk_size(problem, compute.chunk_size, compute.backend), workers,
                    estimated_seconds(problem, n_points) / cores(workers))


def bounded_chunk_size(problem: WorkspaceProblem, requested: int | None, backend: str = "threading") -> int:
    """Poses per chunk: the requested size, or for None (``compute.chunk_size=null``) the cost
    model's, CHUNK_POSES and on Dask at least DASK_CHUNK_S of kernel; lowered so that a chunk's
    largest intermediate array (poses x cables x velocity or acceleration set) stays within
    CHUNK_BUDGET_FLOATS (about forty such arrays are alive at once: 4 MB keeps a chunk's pages in
    use instead of faulting fresh ones; the fused kernel holds no such array and takes at most
    FUSED_CHUNK_FLOATS in its (poses x cables) outputs), and to FEASIBLE_CHUNK_POSES under the feasible tension model."""
    if requested is None:
        requested = CHUNK_POSES
        if backend == "dask":
            requested = max(requested, int(DASK_CHUNK_S / estimated_seconds(problem, 1)))
    if problem.spec.tension.model == "feasible":
        requested = min(requested, FEASIBLE_CHUNK_POSES)
    if problem.fused:
        return max(1, min(requested, FUSED_CHUNK_FLOATS // problem.robot.n_cables))
    return max(1, min(requested, CHUNK_BUDGET_FLOATS // (problem.robot.n_cables * problem.spec.set_size())))


def fused_pays(jobs) -> bool:
    """Whether the compiled kernels pay for their start over these jobs together (triples of a
    typed config, its problem and its poses, a sweep: the IRPM wrench studies are 180 jobs of
    25 000 poses, each too small alone; each process that runs its jobs loads them once)."""
    seconds = 0.0
    for cfg, problem, n_points in jobs:
        if getattr(cfg.compute.kernel, "name", cfg.compute.kernel) == "auto" and fused_unfit(problem) is None:
            seconds += n_points * len(problem.orientations) / POSES_PER_SECOND["pinv"]
    return seconds > FUSED_START_S


def workers_pay(jobs, workers: int) -> bool:
    """Whether ``workers`` job processes finish these jobs (triples of a typed config, its
    problem and its poses) sooner than this process alone, by the cost model: they share the
    jobs' kernel time and files but each first starts (``JOB_WORKER_START_S``). A study's 40
    jobs of 216 poses take less than starting one worker."""
    seconds = 0.0
    for cfg, problem, n_points in jobs:
        seconds += JOB_S + estimated_seconds(problem, n_points)
        if cfg.analysis == "lines":
            seconds += 2 * cfg.grid.n ** 2 * LINE_SAMPLES / POSES_PER_SECOND[problem.spec.tension.model]
    return seconds * (1.0 - 1.0 / workers) > workers * JOB_WORKER_START_S

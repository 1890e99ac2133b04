"""A workspace from a built problem: run the kernel over the grid, classify, tabulate, summarise,
and the cost model that picks the kernel and the workers (``pipeline.app.problem`` builds the
problem from a config).
"""

from __future__ import annotations

import logging
import os
from dataclasses import replace
from typing import TYPE_CHECKING, Callable

import numpy as np
import pyarrow as pa
from omegaconf import DictConfig, OmegaConf

from pipeline.model.dynamics import REFERENCE_SET
from pipeline.model.metrics import WORK as METRICS_WORK
from pipeline.workspace.arrow import categories, numbers
from pipeline.workspace.criteria.interference import obstacle_pairs
from pipeline.workspace.degeneracy import Degeneracy
from pipeline.workspace.grid import Grid
from pipeline.workspace.kernel import WorkspaceProblem, evaluate_chunk
from pipeline.workspace.parallel import iter_chunks
from pipeline.workspace.progress import clock_text
from pipeline.workspace.verdict import classify

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger("pipeline")

CHUNK_BUDGET_FLOATS = 4_000_000  # largest (poses x cables x set size) array of one chunk: 32 MB
FEASIBLE_CHUNK_POSES = 4096  # tension.model=feasible: about 1 s per chunk, so progress is visible
CHUNK_POSES = 20_000  # compute.chunk_size=null: a chunk's poses, between 2 000 and 20 000 barely matter
# On Dask a chunk carries at least DASK_CHUNK_S of kernel by the cost model: a task's round
# trip through the scheduler costs milliseconds, and the default 20 000 poses are 20 ms of the
# fused kernel (benchmarks/LOG.md, 2026-11-26: 10^7 fused poses on a 2-worker local cluster
# x1.26 loky's wall with 20 000-pose chunks, x1.16 with 200 000; 500 000 and 10^6 no better)
DASK_CHUNK_S = 0.2


def grid_workspace(
    cfg: DictConfig, problem: WorkspaceProblem, grid: Grid,
    sink: Callable[[pa.Table], None] | None = None, sweep_pays: bool = False,
) -> tuple[pd.DataFrame | None, dict]:
    """Points table (one row per grid pose) and the one-row summary (counts, share, volume) of
    the grid procedure (for ``analysis=lines``, the CPR-WWA grid it is compared with).

    With ``sink``, each chunk's rows go to ``sink`` as an Arrow table as soon as the chunk is
    done and no table is kept (returns None for it): memory stays bounded by a chunk, whatever
    the grid size, and pandas is not imported (``docs/performance.md``, "What a process
    imports"). Without, the points come back as one pandas DataFrame. ``sweep_pays``: the job's
    sweep pays, as a whole, for the compiled kernels (``pipeline.app.problem.fused_pays``)."""
    problem, chunk_size = chunking(cfg, problem, grid.n_points, sweep_pays)
    workers = worth_workers(problem, grid.n_points, cfg.compute.n_jobs, cfg.compute.backend)
    announce_cost(cfg, problem, grid.n_points, workers, keeps_points=sink is None)
    if problem.fused or problem.spec.tension.model == "feasible":
        # one pose first: the compiled loops are loaded, or built once, before the
        # progress clock starts, which would count that in the first chunk's time
        evaluate_chunk(problem, grid[:1])
    chunks = iter_chunks(
        evaluate_chunk, problem, grid,
        n_jobs=workers,
        backend=cfg.compute.backend,
        chunk_size=chunk_size,
        scheduler=cfg.compute.scheduler,
    )
    parts, n_feasible, by_lp = [], 0, 0
    degenerate = Degeneracy(problem)
    lost = np.zeros(len(problem.criteria), dtype=np.int64)  # infeasible poses by limiting criterion
    least = dict.fromkeys(problem.criteria, np.inf)
    summarised = {key: [] for key in problem.spec.summarised}  # per-pose columns, 8 bytes a pose
    for span, raw in chunks:
        for key, values in summarised.items():
            values.append(raw[key])
        margins, feasible, limiting = classify(
            {name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)
        n_feasible += int(np.count_nonzero(feasible))
        for name in problem.criteria:  # the feasible poses' headroom to each limit
            least[name] = np.min(margins[name], initial=least[name], where=feasible)
        by_lp += int(np.count_nonzero(raw.get("lp_poses", False)))
        lost += np.bincount(limiting[~feasible], minlength=len(problem.criteria))
        positions = grid[span]  # computed again from the axes: no chunk's positions are kept
        degenerate.add(positions, raw, margins)
        points = tabulate(problem, positions, raw, margins, feasible, limiting)
        if sink is None:
            parts.append(points)
        else:
            sink(points)
    counts = {"n_points": grid.n_points, "n_feasible": n_feasible,
              "lost": dict(zip(problem.criteria, lost.tolist())), "least": least,
              "summarised": {key: np.concatenate(values) for key, values in summarised.items()},
              "degenerate": degenerate.summary()}
    if problem.spec.tension.model == "feasible":
        log.info("feasible tension model: %d of %d poses by LP (poor conditioning or fallback), "
                 "the rest by hyperplane shifting", by_lp, grid.n_points)
    degenerate.explain(grid.n_points)
    table = pa.concat_tables(parts).to_pandas() if sink is None else None
    return table, summarize(cfg, counts, grid.cell_volume, problem)


def tabulate(problem: WorkspaceProblem, positions: np.ndarray, raw: dict,
             margins: dict[str, np.ndarray], feasible: np.ndarray, limiting: np.ndarray) -> pa.Table:
    """One chunk's points (its grid rows: positions, or orientations for a robot whose reference
    point a joint holds, ``WorkspaceProblem.angles``): position, orientation, verdict, limiting criterion (a dictionary
    column: int8 codes into the criteria's names), margins; ``margins``, ``feasible`` and
    ``limiting`` as :func:`pipeline.workspace.verdict.classify` returns them."""
    if problem.angles is None:
        columns = {"x": positions[:, 0], "y": positions[:, 1], "z": positions[:, 2]}
        for name, value in zip(("psi", "theta", "phi"), problem.nominal):
            columns[name] = np.full(len(positions), value)
    else:  # the rows are orientations (a joint holds the reference point at the origin)
        columns = {name: np.zeros(len(positions)) for name in "xyz"}
        columns.update(psi=positions[:, 0], theta=positions[:, 1], phi=positions[:, 2])
    columns["feasible"] = feasible
    columns["limiting"] = categories(limiting, list(problem.criteria))
    for name, margin in margins.items():
        columns[f"margin_{name}"] = margin
    for key in ("jacobian_rank", "max_payload_kg", "min_payload_kg", "limiting_wrench"):
        if key in raw:
            columns[key] = raw[key]
    if "closest_pair" in raw:  # the cable_cable criterion's closest cables, "i-j" by their names
        names, (i, j) = problem.robot.cable_names, problem.robot.cable_pairs
        columns["closest_cables"] = categories(raw["closest_pair"], [f"{names[a]}-{names[b]}" for a, b in zip(i, j)])
    if "closest_obstacle" in raw:  # the cable_obstacle criterion's closest obstacle and body
        columns["closest_obstacle"] = categories(raw["closest_obstacle"], obstacle_pairs(problem.robot))
    for key, values in raw.items():  # output.cables and output.metrics (quantities, pipeline.model.metrics)
        if key.startswith(("length_", "tension_", "wrench_max_", "wrench_min_", "capacity_margin")):
            columns[key] = values
    if "unreachable" in margins:  # |S S^+ w - w| / |w|, worst over the required wrenches
        columns["wrench_residual"] = (1.0 - margins["unreachable"]) * problem.spec.tension.residual_limit
    return pa.table({name: numbers(values) if isinstance(values, np.ndarray) else values
                     for name, values in columns.items()})


# Cost model of the choice between worker processes and this one (docs/performance.md): a
# local worker costs about WORKER_START_S of CPU before its first chunk (process start and the
# kernel's imports, numpy only) and two workers at best halve the kernel time, so they pay off
# when the kernel alone would take more than 2 x WORKER_START_S here. Kernel speeds per core,
# measured by benchmarks/bench_kernel.py and bench_feasible.py (lower ends of their ranges).
# The speeds hold for the paper's set of 93 velocities per pose (grid.n_vel = 6) and the statics
# of one wrench; a pose's cost grows with its set (each spec's ``work()``: its velocities, a wrench
# set's vertices, the payload's LP). A job estimated above LONG_JOB_S is announced with a warning.
WORKER_START_S = 0.4
# The compiled kernels cost a process FUSED_START_S to load from numba's cache (numba's import,
# with scipy.linalg, and the machine code: pipeline.model.jit), and the first process on a machine
# compiles them: a job whose numpy kernel would take less keeps it, so a small job never pays
# more than it could save.
FUSED_START_S = 0.4
# Fused chunks are computed several times faster than the parent classifies and writes them, so
# workers pay only for long fused jobs (benchmarks/LOG.md, 2026-11-24: about 1.5 x 10^6 poses).
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
    per_pose = problem.spec.work() + (METRICS_WORK[problem.spec.tension.model] if problem.metrics else 0.0)
    speed = POSES_PER_SECOND["fused" if problem.fused else problem.spec.tension.model]
    return evaluations * (per_pose / speed + OBSTACLE_SECONDS * len(problem.robot.obstacles))


def fused_unfit(problem: WorkspaceProblem) -> str | None:
    """Why the compiled kernels (``pipeline.workspace.fused``) cannot evaluate this problem; None
    when they can: the criteria of the spec's options they evaluate
    (:meth:`pipeline.model.dynamics.MotionSpec.fused_unfit`) and no per-pose cable quantities."""
    if problem.cables:
        return "it does not write the per-pose cable quantities of output.cables=true"
    if problem.metrics:
        return "it does not write the per-pose metrics of output.metrics=true"
    if len(problem.robot.dofs) != 6 and problem.spec.kind == "statics":
        return "it balances all six rows of a free platform only (robot.dofs)"
    return problem.spec.fused_unfit()


def use_fused(cfg: DictConfig, problem: WorkspaceProblem, n_points: int, sweep_pays: bool = False) -> bool:
    """``compute.kernel``: fused (checked by the config), numpy, or auto: the compiled kernels
    where they apply and either the job's sweep pays for them (``sweep_pays``, decided by the
    plan: a job's kernel follows from its sweep, never from what its process ran before) or the
    numpy kernel would take longer than their start (FUSED_START_S)."""
    kernel = name_of(cfg.compute.kernel)
    if kernel != "auto":
        return kernel == "fused"
    pays = sweep_pays or estimated_seconds(problem, n_points) > FUSED_START_S
    return pays and fused_unfit(problem) is None


def worth_workers(problem: WorkspaceProblem, n_points: int, n_jobs: int, backend: str) -> int:
    """``n_jobs``, or 1 when the cost model says local workers would not pay for their start
    (measured on 2 cores: 125 000 CPR-WWA poses took 1.13x the wall time and 1.44x the CPU on
    two workers; 10^6 poses 0.7x the wall time); for the fused kernel, FUSED_WORKERS_FROM_S.
    A Dask cluster is the user's explicit choice."""
    if backend == "dask" or n_jobs == 1:
        return n_jobs
    serial_s = estimated_seconds(problem, n_points)
    if serial_s > (FUSED_WORKERS_FROM_S if problem.fused else 2 * WORKER_START_S):
        return n_jobs
    log.debug("compute.n_jobs=%d: about %.2f s of kernel, too little for worker processes to pay "
              "for their start; running here", n_jobs, serial_s)
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
    cores = min(max(workers, 1), os.cpu_count() or 1)
    compiling = first_compile_seconds(problem)
    seconds = estimated_seconds(problem, n_points) / cores + compiling
    memory = estimated_bytes(problem, n_points, keeps_points)
    if seconds < LONG_JOB_S and memory < LARGE_JOB_BYTES:
        return
    hint = ""
    if "n_vel" in cfg.get("grid", {}) and cfg.grid.n_vel is None and problem.spec.set_size() > REFERENCE_SET:
        hint = (f"; grid.n_vel is null (grid.n's), so each pose tests {problem.spec.set_size()} velocities "
                f"(grid.n_vel=6 tests {REFERENCE_SET}, as the paper's grid)")
    if problem.robot.obstacles:
        share = OBSTACLE_SECONDS * len(problem.robot.obstacles) * n_points * len(problem.orientations) / cores
        hint += f"; its {len(problem.robot.obstacles)} obstacles take about {clock_text(share)} of it"
    size = f"{memory / 2**30:.1f} GiB" if memory >= 2**30 else f"{memory / 2**20:.0f} MiB"
    if compiling:
        hint += f"; this includes numba's first compile of the loops it needs, about {compiling:.0f} s, once per machine"
    log.warning("this job evaluates %d poses x %d orientations: about %s on %d core%s and %s of memory by "
                "the cost model%s", n_points, len(problem.orientations), clock_text(seconds), cores,
                "" if cores == 1 else "s", size, hint)


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


def chunking(cfg: DictConfig, problem: WorkspaceProblem, n_points: int,
             sweep_pays: bool = False) -> tuple[WorkspaceProblem, int]:
    """The problem with the kernel :func:`grid_workspace` chooses for ``n_points`` poses, and
    its poses per chunk (a job of more than one chunk uses workers or a Dask cluster)."""
    problem = replace(problem, fused=use_fused(cfg, problem, n_points, sweep_pays))
    return problem, bounded_chunk_size(problem, cfg.compute.chunk_size, cfg.compute.backend)


def bounded_chunk_size(problem: WorkspaceProblem, requested: int | None, backend: str = "loky") -> int:
    """Poses per chunk: the requested size, or for None (``compute.chunk_size=null``) the cost
    model's, CHUNK_POSES and on Dask at least DASK_CHUNK_S of kernel; lowered so that a chunk's
    largest intermediate array (poses x cables x velocity or acceleration set) stays within
    CHUNK_BUDGET_FLOATS (the fused kernel holds no such array), and to FEASIBLE_CHUNK_POSES
    under the feasible tension model."""
    if requested is None:
        requested = CHUNK_POSES
        if backend == "dask":
            requested = max(requested, int(DASK_CHUNK_S / estimated_seconds(problem, 1)))
    per_pose = problem.robot.n_cables * (1 if problem.fused else problem.spec.set_size())
    if problem.spec.tension.model == "feasible":
        requested = min(requested, FEASIBLE_CHUNK_POSES)
    return max(1, min(requested, CHUNK_BUDGET_FLOATS // per_pose))


def summarize(cfg: DictConfig, counts: dict, cell_volume: float, problem) -> dict:
    """Flattened config (every swept key is a column) plus counts, percentage and volume;
    ``counts``: n_points, n_feasible, ``lost`` (limiting criterion -> infeasible points) and
    ``least`` (criterion -> its smallest margin over the feasible poses: ``least_margin_*``, the
    headroom the feasible workspace keeps to each limit; NaN when no pose is feasible)."""
    n_points, n_feasible = counts["n_points"], counts["n_feasible"]
    row = flatten(OmegaConf.to_container(cfg, resolve=True, enum_to_str=True))
    row.update(problem.limits.described())  # the actuator's name and power, for CPR-WWA
    row["n_orientations"] = len(problem.orientations)
    row["kernel"] = "fused" if problem.fused else "numpy"  # which code computed the margins
    for axis, lo, hi in zip("xyz", problem.robot.box_lo, problem.robot.box_hi):
        row[f"box.{axis}_min"], row[f"box.{axis}_max"] = float(lo), float(hi)
    row.update(
        n_points=n_points,
        n_feasible=n_feasible,
        feasible_pct=100.0 * n_feasible / n_points,
        volume_m3=n_feasible * cell_volume,
    )
    for name in problem.criteria:
        row[f"lost_{name}"] = int(counts["lost"].get(name, 0))
    for name in problem.criteria:
        least = counts["least"][name]
        row[f"least_margin_{name}"] = float(least) if np.isfinite(least) else np.nan
    row.update(counts.get("degenerate", {}))  # the rank and the missing direction at a degenerate pose
    for key, values in counts.get("summarised", {}).items():  # over the poses that have one
        known = values[~np.isnan(values)]
        for stat, value in (("min", np.min), ("median", np.median), ("max", np.max)):
            row[f"{key}_{stat}"] = float(value(known)) if len(known) else np.nan
    return row


def flatten(tree: dict, prefix: str = "") -> dict:
    """{'a': {'b': 1}} -> {'a.b': 1}; lists are kept as their string form."""
    flat = {}
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, f"{name}."))
        else:
            flat[name] = str(value) if isinstance(value, list) else value
    return flat


def name_of(value) -> str:
    """An enum member's name, or the value as text."""
    return value.name if hasattr(value, "name") else str(value)

"""A workspace from a built problem: run the kernel over the grid, classify, tabulate, summarise
(``pipeline.app.problem`` builds the problem from a config; ``pipeline.workspace.dispatch``
decides how the grid runs).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Callable

import numpy as np
import pyarrow as pa
from omegaconf import DictConfig, OmegaConf

from pipeline.workspace.arrow import categories, numbers
from pipeline.workspace.criteria import CATENARY, UNREACHABLE
from pipeline.workspace.criteria.interference import obstacle_pairs
from pipeline.workspace.degeneracy import Degeneracy
from pipeline.workspace.dispatch import announce_cost, decide
from pipeline.workspace.grid import Grid
from pipeline.workspace.kernel import WorkspaceProblem, evaluate_chunk
from pipeline.workspace.parallel import iter_chunks
from pipeline.workspace.verdict import Tally, classify

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger("pipeline")


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
    sweep pays, as a whole, for the compiled kernels (``pipeline.workspace.dispatch.fused_pays``)."""
    run = decide(cfg, problem, grid.n_points, sweep_pays)
    problem = run.problem
    announce_cost(cfg, problem, grid.n_points, run.workers, keeps_points=sink is None)
    if problem.fused or problem.spec.tension.model == "feasible":
        # one pose first: the compiled loops are loaded, or built once, before the
        # progress clock starts, which would count that in the first chunk's time
        evaluate_chunk(problem, grid[:1])
    chunks = iter_chunks(
        evaluate_chunk, problem, grid,
        n_jobs=run.workers,
        backend=cfg.compute.backend,
        chunk_size=run.chunk_size,
        scheduler=cfg.compute.scheduler,
        estimate=run.seconds,
    )
    parts, by_lp, undecided = [], 0, 0
    degenerate = Degeneracy(problem)
    tally = Tally(problem.criteria)
    summarised = {key: [] for key in problem.spec.summarised}  # per-pose columns, 8 bytes a pose
    for span, raw in chunks:
        for key, values in summarised.items():
            values.append(raw[key])
        margins, feasible, limiting = classify(
            {name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)
        tally.add(margins, feasible, limiting)
        by_lp += int(np.count_nonzero(raw.get("lp_poses", False)))
        undecided += int(np.count_nonzero(raw.get("catenary_undecided", False)))
        positions = grid[span]  # computed again from the axes: no chunk's positions are kept
        degenerate.add(positions, raw, margins)
        points = tabulate(problem, positions, raw, margins, feasible, limiting)
        if sink is None:
            parts.append(points)
        else:
            sink(points)
    counts = {**tally.counts(grid.n_points), "undecided": undecided,
              "summarised": {key: np.concatenate(values) for key, values in summarised.items()},
              "degenerate": degenerate.summary()}
    if CATENARY in problem.criteria:
        log.info("sagging cables: %d of %d poses undecided by the proofs, counted out (column catenary_undecided)",
                 undecided, grid.n_points)
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
    for key in ("jacobian_rank", "max_payload_kg", "min_payload_kg", "limiting_wrench", "catenary_undecided",
                "sag_max_ratio", "added_length_max"):
        if key in raw:
            columns[key] = raw[key]
    if "closest_pair" in raw:  # the cable_cable criterion's closest cables, "i-j" by their names
        names, (i, j) = problem.robot.cable_names, problem.robot.cable_pairs
        columns["closest_cables"] = categories(raw["closest_pair"], [f"{names[a]}-{names[b]}" for a, b in zip(i, j)])
    if "closest_obstacle" in raw:  # the cable_obstacle criterion's closest obstacle and body
        columns["closest_obstacle"] = categories(raw["closest_obstacle"], obstacle_pairs(problem.robot))
    for key, values in raw.items():  # output.cables and output.metrics (quantities, pipeline.model.metrics)
        if key.startswith(("length_", "tension_", "wrench_max_", "wrench_min_", "capacity_margin", "stiffness_",
                           "unstrained_", "wrap_", "exit_", "sag_", "angle_platform_", "angle_anchor_", "added_length_")):
            columns[key] = values
    if UNREACHABLE in margins:  # |S S^+ w - w| / |w|, worst over the required wrenches
        columns["wrench_residual"] = (1.0 - margins[UNREACHABLE]) * problem.spec.tension.residual_limit
    return pa.table({name: numbers(values) if isinstance(values, np.ndarray) else values
                     for name, values in columns.items()})


def summarize(cfg: DictConfig, counts: dict, cell_volume: float, problem) -> dict:
    """Flattened config (every swept key is a column) plus counts, percentage and volume;
    ``counts``: n_points, n_feasible, ``lost`` (limiting criterion -> infeasible points),
    ``undecided`` (the poses the proofs of sagging cables leave undecided: ``undecided_pct``),
    ``alone`` (criterion -> the poses it alone removes, every other criterion holding there:
    ``alone_*``, what relaxing it alone would win) and ``least`` (criterion -> its smallest
    margin over the feasible poses: ``least_margin_*``, the headroom the feasible workspace
    keeps to each limit; NaN when no pose is feasible)."""
    n_points, n_feasible = counts["n_points"], counts["n_feasible"]
    row = described_job(cfg, problem)
    row["kernel"] = "fused" if problem.fused else "numpy"  # which code computed the margins
    row.update(
        n_points=n_points,
        n_feasible=n_feasible,
        feasible_pct=100.0 * n_feasible / n_points,
        volume_m3=n_feasible * cell_volume,
    )
    if CATENARY in problem.criteria:  # poses the proofs of sagging cables left undecided (counted out)
        row["undecided_pct"] = 100.0 * counts.get("undecided", 0) / n_points
    for name in problem.criteria:
        row[f"lost_{name}"] = int(counts["lost"].get(name, 0))
    for name in problem.criteria:
        row[f"alone_{name}"] = int(counts["alone"].get(name, 0))
    for name in problem.criteria:
        least = counts["least"][name]
        row[f"least_margin_{name}"] = float(least) if np.isfinite(least) else np.nan
    row.update(counts.get("degenerate", {}))  # the rank and the missing direction at a degenerate pose
    for key, values in counts.get("summarised", {}).items():  # over the poses that have one
        known = values[~np.isnan(values)]
        for stat, value in (("min", np.min), ("median", np.median), ("max", np.max)):
            row[f"{key}_{stat}"] = float(value(known)) if len(known) else np.nan
    return row


def described_job(cfg: DictConfig, problem) -> dict:
    """What every summary begins with: the flattened config (every swept key a column), what the
    limits say of themselves (the actuator's name and power, for CPR-WWA), the orientations'
    count and the search box."""
    row = flatten(OmegaConf.to_container(cfg, resolve=True, enum_to_str=True))
    row.update(problem.limits.described())
    row["n_orientations"] = len(problem.orientations)
    for axis, lo, hi in zip("xyz", problem.robot.box_lo, problem.robot.box_hi):
        row[f"box.{axis}_min"], row[f"box.{axis}_max"] = float(lo), float(hi)
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

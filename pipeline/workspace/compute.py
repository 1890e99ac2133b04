"""A workspace as a function of a composed config: build the problem, run the kernel, tabulate.

One code path for every robot and analysis. The robot config only places points
(``pipeline.model.robots``); the analysis picks the per-chunk state and its criteria:

- ``cpr_wwa``: CPR-WWA of Filipovic & Kevac (2018), dynamics over the velocity and acceleration
  sets against the limits of a catalogue actuator (eqs. 19-34);
- ``statics``: static equilibrium under the applied wrench and the load's weight, tensions in
  [t_min, t_max] and lengths
  <= l_max (eqs. 7-10 of Hamed & Zohoor).

``tension.model=feasible`` replaces the minimum-norm cable forces of both by pulling cables only
(``pipeline.model.tensions``) and adds the criteria ``unreachable`` and ``slack``.
"""

from __future__ import annotations

import logging
import os
from dataclasses import replace
from typing import TYPE_CHECKING, Callable

import numpy as np
import pyarrow as pa
from omegaconf import DictConfig, OmegaConf

from pipeline.model.actuators import actuator_model
from pipeline.model.catalogue import Catalogue
from pipeline.model.dynamics import Load, MotionSpec
from pipeline.model.geometry import CableRobot
from pipeline.workspace.arrow import categories, numbers
from pipeline.workspace.grid import Grid, box_grid, step_grid
from pipeline.workspace.kernel import WorkspaceProblem, evaluate_chunk
from pipeline.model.motion import acceleration_set, cartesian_cube, extreme_points, velocity_set
from pipeline.workspace.parallel import iter_chunks
from pipeline.workspace.progress import clock_text
from pipeline.model.robots import PointsRobot, cpr8, irpm6, point_list
from pipeline.model.statics import StaticLimits, StaticsSpec
from pipeline.model.tensions import TensionSpec
from pipeline.workspace.verdict import classify

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger("pipeline")

CPR_WWA_CRITERIA = ("speed", "torque", "acceleration", "voltage")  # eqs. (30), (32), (33), (34)
FEASIBLE_GATES = ("unreachable", "slack")  # tension=feasible (pipeline.model.tensions)
DEFAULT_N_VEL = 6  # velocity grid of robots without an N x N x N position grid (section 3.1's N)
CHUNK_BUDGET_FLOATS = 4_000_000  # largest (poses x cables x set size) array of one chunk: 32 MB
FEASIBLE_CHUNK_POSES = 4096  # tension.model=feasible: about 1 s per chunk, so progress is visible


def build_problem(cfg: DictConfig, catalogue: Catalogue | None) -> tuple[WorkspaceProblem, Grid]:
    """The workspace problem of the configured robot and analysis, and its position grid."""
    robot = build_robot(cfg)
    if cfg.poses is None:
        grid = ROBOTS[cfg.robot.name][1](cfg, robot)
    else:  # the user's own poses: no grid cell, no volume
        grid = Grid(point_list("poses", cfg.poses), cell_volume=float("nan"))
    analysis = analysis_name(cfg)
    spec, limits, criteria = ANALYSES[analysis](cfg, catalogue, robot)
    problem = WorkspaceProblem(robot, orientation_set(cfg.orientation), spec, limits, criteria,
                               cfg.model.margin_atol, cfg.output.cables)
    return problem, grid


def analysis_name(cfg: DictConfig) -> str:
    return _name(cfg.analysis)


def orientation_count(orientation: DictConfig) -> int:
    """k of :func:`orientation_set`, counted without building it."""
    total = orientation.total
    return 1 if total.n == 1 or total.bound == 0 else int(total.n) ** 3


def orientation_set(orientation: DictConfig) -> np.ndarray:
    """(k, 3) Euler angles: the constant orientation, or the total-orientation grid around it."""
    nominal = np.array([orientation.psi, orientation.theta, orientation.phi], dtype=float)
    total = orientation.total
    if orientation_count(orientation) == 1:
        return nominal[None, :]
    offsets = np.linspace(-total.bound, total.bound, total.n)
    grid = cartesian_cube(offsets)
    order = np.argsort(np.abs(grid).sum(axis=1), kind="stable")  # nominal orientation first
    return nominal + grid[order]


def build_robot(cfg: DictConfig) -> CableRobot:
    """The configured robot as data (``pipeline.model.robots``)."""
    return ROBOTS[cfg.robot.name][0](cfg.robot)


def _cpr8(rc: DictConfig) -> CableRobot:
    return cpr8(rc.frame.d, rc.frame.s, rc.frame.v, rc.carrier.l, rc.carrier.w, rc.carrier.h,
                lower_anchor_drop=rc.lower_anchor_drop)


def _irpm6(rc: DictConfig) -> CableRobot:
    return irpm6(rc.r_base, rc.r_end, rc.gamma_deg, rc.search.lo, rc.search.hi, rc.l_max)


def _box_grid(cfg: DictConfig, robot: CableRobot) -> Grid:
    return box_grid(robot.box_lo, robot.box_hi, cfg.grid.n, _name(cfg.grid.spacing))


def _step_grid(cfg: DictConfig, robot: CableRobot) -> Grid:
    search = cfg.robot.search
    return step_grid(robot.box_lo, robot.box_hi, search.step, search.get("spacing", "faces"))


def _cpr_wwa(cfg: DictConfig, catalogue: Catalogue, robot):
    actuator = actuator_model(
        catalogue.row(cfg.actuator), cfg.drive.winch_radius, cfg.drive.gear_ratio,
        cfg.model.xi_in_torque_limit,
    )
    model = cfg.model
    n_vel = cfg.grid.n_vel or cfg.grid.get("n") or DEFAULT_N_VEL
    velocities = velocity_set(cfg.motion.v_max, n_vel, _name(model.velocity_boundary))
    motion = MotionSpec(
        velocities=velocities,
        velocity_extremes=extreme_points(velocities, 2 * cfg.motion.v_max / n_vel),
        accelerations=acceleration_set(
            cfg.motion.v_max, cfg.motion.t_acc, cfg.motion.t_dec, _name(model.acceleration_set)
        ),
        load=load_spec(cfg),
        winch_radius=np.full(robot.n_cables, actuator.winch_radius),
        pinv_columns=_name(model.pinv_columns),
        rank_rtol=model.rank_rtol,
        jdot=model.jdot,
        tension=tension_spec(cfg),
        inertia=_name(model.inertia),
    )
    gates = FEASIBLE_GATES if motion.tension.model == "feasible" else ()
    return motion, actuator, (*gates, *cable_limits(motion.tension, robot), *CPR_WWA_CRITERIA)


def _statics(cfg: DictConfig, catalogue: Catalogue | None, robot):
    spec = StaticsSpec(
        moment_arm=_name(cfg.model.moment_arm),
        cable_direction=_name(cfg.model.cable_direction),
        rank_rtol=cfg.model.rank_rtol,
        tension=tension_spec(cfg),
        load=load_spec(cfg),
    )
    rating = spec.tension.t_max
    force = spec.load.external[:3] - spec.load.mass * spec.load.gravity * robot.up
    scale = float(np.max(rating)) if rating is not None else max(float(np.linalg.norm(force)), 1.0)
    limits = StaticLimits(np.inf if rating is None else rating, cfg.model.rank_rtol, scale)
    gates = ("singular", "slack") if spec.tension.model == "pinv" else FEASIBLE_GATES
    return spec, limits, (*gates, *cable_limits(spec.tension, robot))


def cable_limits(tension: TensionSpec, robot: CableRobot) -> tuple[str, ...]:
    """The cable criteria every analysis checks when their limit is given: the rating
    (``tension.t_max``) and the longest cable (the robot's ``l_max``)."""
    return (("tension_max",) if tension.t_max is not None else ()) + (
        ("length",) if robot.l_max is not None else ())


def load_spec(cfg: DictConfig) -> Load:
    """The load of every analysis: mass, gravity, centre of mass, and as its external wrench
    ``load.external`` plus the applied wrench ``wrench.*`` (IRPM eq. 11)."""
    load, w = cfg.load, cfg.wrench
    applied = np.array([w.fx, w.fy, w.fz, w.mx, w.my, w.mz], dtype=float)
    return Load(float(load.mass), float(load.gravity), np.asarray(load.com, dtype=float),
                np.asarray(load.external, dtype=float) + applied)


def tension_spec(cfg: DictConfig) -> TensionSpec:
    t = cfg.tension
    return TensionSpec(_name(t.model), per_cable(t.t_min), per_cable(cable_rating(cfg)), t.residual_rtol)


def cable_rating(cfg: DictConfig):
    """The largest cable tension (N, a scalar or one per cable): ``tension.t_max``, replaced by
    its alias ``limits.s_max`` (the IRPM paper's name) when that is given; None = no rating."""
    t_max, s_max = cfg.tension.t_max, cfg.limits.s_max
    return s_max if s_max is not None else t_max


def per_cable(value):
    """A tension limit as the kernels take it: a float, an (m,) array for a list, or None."""
    if value is None:
        return None
    if isinstance(value, (int, float)):
        return float(value)
    return np.asarray(list(value), dtype=float)


def grid_size(cfg: DictConfig) -> int:
    """Poses a job checks, counted without building the grid (``config`` bounds it)."""
    if cfg.poses is not None:
        return len(cfg.poses)
    if "search" not in cfg.robot:
        return int(cfg.grid.n) ** 3
    search = cfg.robot.search
    spans = np.asarray(search.hi, dtype=float) - np.asarray(search.lo, dtype=float)
    counts = np.floor(spans / search.step + 1e-9) + (search.get("spacing", "faces") == "faces")
    return int(np.prod(np.maximum(counts, 0)))


# robot name -> (robot from its config node, position grid from the config and the robot)
ROBOTS = {
    "cpr8": (_cpr8, _box_grid),
    "irpm6": (_irpm6, _step_grid),
    "points": (lambda rc: PointsRobot.from_config(rc).build(), _step_grid),
}
ANALYSES = {"cpr_wwa": _cpr_wwa, "statics": _statics, "lines": _cpr_wwa}


def compute_workspace(
    cfg: DictConfig, catalogue: Catalogue | None, sink: Callable[[pa.Table], None] | None = None,
    sweep_pays: bool = False,
) -> tuple[pd.DataFrame | None, dict]:
    """Points table (one row per grid pose) and the one-row summary (counts, share, volume) of
    the grid procedure (for ``analysis=lines``, the CPR-WWA grid it is compared with).

    With ``sink``, each chunk's rows go to ``sink`` as an Arrow table as soon as the chunk is
    done and no table is kept (returns None for it): memory stays bounded by a chunk, whatever
    the grid size, and pandas is not imported (``docs/performance.md``, "What a process
    imports"). Without, the points come back as one pandas DataFrame. ``sweep_pays``: the job's
    sweep pays, as a whole, for the compiled kernels (:func:`fused_pays`)."""
    return grid_workspace(cfg, *build_problem(cfg, catalogue), sink, sweep_pays)


def grid_workspace(
    cfg: DictConfig, problem: WorkspaceProblem, grid: Grid,
    sink: Callable[[pa.Table], None] | None = None, sweep_pays: bool = False,
) -> tuple[pd.DataFrame | None, dict]:
    """:func:`compute_workspace` for an already built problem and grid."""
    problem = replace(problem, fused=use_fused(cfg, problem, grid.n_points, sweep_pays))
    workers = worth_workers(problem, grid.n_points, cfg.compute.n_jobs, cfg.compute.backend)
    announce_cost(cfg, problem, grid.n_points, workers)
    if problem.fused or problem.spec.tension.model == "feasible":
        # one pose first: the compiled loops are loaded, or built once, before the
        # progress clock starts, which would count that in the first chunk's time
        evaluate_chunk(problem, grid.positions[:1])
    chunks = iter_chunks(
        evaluate_chunk, problem, grid.positions,
        n_jobs=workers,
        backend=cfg.compute.backend,
        chunk_size=bounded_chunk_size(problem, cfg.compute.chunk_size),
        scheduler=cfg.compute.scheduler,
    )
    parts, n_feasible, by_lp = [], 0, 0
    lost = np.zeros(len(problem.criteria), dtype=np.int64)  # infeasible poses by limiting criterion
    least = dict.fromkeys(problem.criteria, np.inf)
    for span, raw in chunks:
        margins, feasible, limiting = classify(
            {name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)
        n_feasible += int(np.count_nonzero(feasible))
        for name in problem.criteria:  # the feasible poses' headroom to each limit
            least[name] = np.min(margins[name], initial=least[name], where=feasible)
        by_lp += int(np.count_nonzero(raw.get("lp_poses", False)))
        lost += np.bincount(limiting[~feasible], minlength=len(problem.criteria))
        points = tabulate(problem, grid.positions[span], raw, margins, feasible, limiting)
        if sink is None:
            parts.append(points)
        else:
            sink(points)
    counts = {"n_points": grid.n_points, "n_feasible": n_feasible,
              "lost": dict(zip(problem.criteria, lost.tolist())), "least": least}
    if problem.spec.tension.model == "feasible":
        log.info("feasible tension model: %d of %d poses by LP (poor conditioning or fallback), "
                 "the rest by hyperplane shifting", by_lp, grid.n_points)
    table = pa.concat_tables(parts).to_pandas() if sink is None else None
    return table, summarize(cfg, counts, grid.cell_volume, problem)


def tabulate(problem: WorkspaceProblem, positions: np.ndarray, raw: dict,
             margins: dict[str, np.ndarray], feasible: np.ndarray, limiting: np.ndarray) -> pa.Table:
    """One chunk's points: position, orientation, verdict, limiting criterion (a dictionary
    column: int8 codes into the criteria's names), margins; ``margins``, ``feasible`` and
    ``limiting`` as :func:`pipeline.workspace.verdict.classify` returns them."""
    columns = {"x": positions[:, 0], "y": positions[:, 1], "z": positions[:, 2]}
    for name, value in zip(("psi", "theta", "phi"), problem.orientation):
        columns[name] = np.full(len(positions), value)
    columns["feasible"] = feasible
    columns["limiting"] = categories(limiting, list(problem.criteria))
    for name, margin in margins.items():
        columns[f"margin_{name}"] = margin
    if "jacobian_rank" in raw:
        columns["jacobian_rank"] = raw["jacobian_rank"]
    for key, values in raw.items():  # output.cables: lengths and tensions (pipeline.workspace.quantities)
        if key.startswith(("length_", "tension_")):
            columns[key] = values
    if "unreachable" in margins:  # |S S^+ w - w| / |w|, worst over the required wrenches
        columns["wrench_residual"] = (1.0 - margins["unreachable"]) * problem.spec.tension.residual_rtol
    return pa.table({name: numbers(values) if isinstance(values, np.ndarray) else values
                     for name, values in columns.items()})


# Cost model of the choice between worker processes and this one (docs/performance.md): a
# local worker costs about WORKER_START_S of CPU before its first chunk (process start and the
# kernel's imports, numpy only) and two workers at best halve the kernel time, so they pay off
# when the kernel alone would take more than 2 x WORKER_START_S here. Kernel speeds per core,
# measured by benchmarks/bench_kernel.py and bench_feasible.py (lower ends of their ranges).
# The speeds hold for the paper's set of REFERENCE_SET velocities per pose (grid.n_vel = 6);
# a pose's cost grows with its set. A job estimated above LONG_JOB_S is announced with a warning.
WORKER_START_S = 0.4
# The compiled kernels cost a process FUSED_START_S to load from numba's cache (numba's import,
# with scipy.linalg, and the machine code: pipeline.model.jit), and the first process on a machine
# compiles them: a job whose numpy kernel would take less keeps it, so a small job never pays
# more than it could save.
FUSED_START_S = 0.4
# Fused chunks are computed several times faster than the parent classifies and writes them, so
# workers pay only for long fused jobs (benchmarks/LOG.md, 2026-11-24: about 1.5 x 10^6 poses).
FUSED_WORKERS_FROM_S = 1.5  # the fused kernel's time (cost model) from which workers are used
POSES_PER_SECOND = {"pinv": 200_000, "feasible": 20_000, "fused": 1_000_000}
REFERENCE_SET = 93
LONG_JOB_S = 30.0


def estimated_seconds(problem: WorkspaceProblem, n_points: int) -> float:
    """The kernel's time for ``n_points`` positions on one core here, by the cost model."""
    evaluations = n_points * len(problem.orientations)
    per_pose = max(1.0, problem.spec.set_size() / REFERENCE_SET)
    speed = POSES_PER_SECOND["fused" if problem.fused else problem.spec.tension.model]
    return evaluations * per_pose / speed


def fused_unfit(cfg: DictConfig) -> str | None:
    """Why the compiled kernels (``pipeline.workspace.fused``) cannot evaluate this config's
    problem; None when they can: the CPR-WWA and statics criteria of the ``pinv`` model
    (CPR-WWA without J-dot: the extreme velocities, a product acceleration set, both readings of
    eqs. 27-29) and no per-pose cable quantities."""
    if _name(cfg.tension.model) != "pinv":
        return "it evaluates tension.model=pinv only"
    if "jdot" in cfg.model and cfg.model.jdot:
        return "it evaluates model.jdot=false only"
    if cfg.output.cables:
        return "it does not write the per-pose cable quantities of output.cables=true"
    return None


def use_fused(cfg: DictConfig, problem: WorkspaceProblem, n_points: int, sweep_pays: bool = False) -> bool:
    """``compute.kernel``: fused (checked by the config), numpy, or auto: the compiled kernels
    where they apply and either the job's sweep pays for them (``sweep_pays``, decided by the
    plan: a job's kernel follows from its sweep, never from what its process ran before) or the
    numpy kernel would take longer than their start (FUSED_START_S)."""
    kernel = _name(cfg.compute.kernel)
    if kernel != "auto":
        return kernel == "fused"
    pays = sweep_pays or estimated_seconds(problem, n_points) > FUSED_START_S
    return pays and fused_unfit(cfg) is None


def fused_pays(configs) -> bool:
    """Whether the compiled kernels pay for their start over these jobs together (typed configs
    of a sweep: the IRPM wrench studies are 180 jobs of 25 000 poses, each too small alone;
    each process that runs its jobs loads them once)."""
    seconds = 0.0
    for cfg in configs:
        if _name(cfg.compute.kernel) == "auto" and fused_unfit(cfg) is None:
            seconds += grid_size(cfg) * orientation_count(cfg.orientation) / POSES_PER_SECOND["pinv"]
    return seconds > FUSED_START_S


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


def announce_cost(cfg: DictConfig, problem: WorkspaceProblem, n_points: int, workers: int) -> None:
    """A warning before a job the cost model expects to take long, with the key that matters."""
    cores = min(max(workers, 1), os.cpu_count() or 1)
    seconds = estimated_seconds(problem, n_points) / cores
    if seconds < LONG_JOB_S:
        return
    hint = ""
    if "n_vel" in cfg.get("grid", {}) and cfg.grid.n_vel is None and problem.spec.set_size() > REFERENCE_SET:
        hint = (f"; grid.n_vel is null, so each pose tests {problem.spec.set_size()} velocities "
                f"(grid.n_vel=6 tests {REFERENCE_SET}, as the paper's grid)")
    log.warning("this job evaluates %d poses x %d orientations: about %s on %d core%s by the cost "
                "model%s", n_points, len(problem.orientations), clock_text(seconds), cores,
                "" if cores == 1 else "s", hint)


def bounded_chunk_size(problem: WorkspaceProblem, requested: int) -> int:
    """Poses per chunk: the requested size, lowered so that a chunk's largest intermediate
    array (poses x cables x velocity or acceleration set) stays within CHUNK_BUDGET_FLOATS
    (the fused kernel holds no such array), and to FEASIBLE_CHUNK_POSES under the feasible
    tension model."""
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
    row["analysis"] = analysis_name(cfg)
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


def _name(value) -> str:
    return value.name if hasattr(value, "name") else str(value)

"""The config builds the problem: one registry per kind, and the one place where a typed config
becomes domain objects.

A robot kind (:data:`ROBOTS`, named by ``robot.name``) is its keys (a schema of
:mod:`pipeline.app.config`), the robot they place (``pipeline.model.robots``), its position grid
and that grid's size counted without building it. An analysis kind (:data:`ANALYSES`, named by
``analysis``) builds the per-chunk spec, the limits and the criteria of its workspace, and
refuses what it cannot mean:

- ``cpr_wwa``: CPR-WWA of Filipovic & Kevac (2018), dynamics over the velocity and acceleration
  sets against the limits of a catalogue actuator (eqs. 19-34);
- ``statics``: static equilibrium under the applied wrench and the load's weight, tensions in
  [t_min, t_max] and lengths <= l_max (eqs. 7-10 of Hamed & Zohoor);
- ``lines``: CPR-WWA's problem, whose grid the straight-line simulations are compared with;
- ``payload``: the statics' problem and, per pose, the largest payload held (``max_payload_kg``);
- ``trajectory``: the statics at each sample of a path in time, its wrench with the rate of change
  of the platform's momentum (``pipeline.app.paths``; no grid).

``tension.model=feasible`` replaces the minimum-norm cable forces of both by pulling cables only
(``pipeline.model.tensions``) and adds the criteria ``unreachable`` and ``slack``; under the
minimum-norm forces CPR-WWA gates the share of the wrench they miss (``unreachable``, where J^T
lacks a direction), and every analysis begins with the ``zero_length`` gate.
:func:`validate` types a composed config, checks every declared rule, and returns it with its
built problem, so a job builds its robot once.
"""

from __future__ import annotations

import importlib.util
import itertools
import math
from dataclasses import dataclass, fields, replace
from typing import Callable

import numpy as np
from omegaconf import DictConfig, ListConfig, OmegaConf

from pipeline.app.paths import certified_motion, path_samples
from pipeline.app.config import (
    MAX_ACCELERATION, MAX_FORCE, Config, Cpr8Config, Irpm6Config, PointsConfig, check_values, masked, merged, shown,
    unknown_keys, vector,
)
from pipeline.errors import ConfigError
from pipeline.model.actuators import ActuatorModel, actuator_model, rest_tension_cap
from pipeline.model.catalogue import Catalogue
from pipeline.model.clearance import Obstacle, Polytope
from pipeline.model.dynamics import Load, MotionSpec, inertia_fault, inertia_tensor
from pipeline.model.geometry import FREEDOMS, CableRobot, eq9_angles
from pipeline.model.intervals import down, up
from pipeline.model.pulleys import Pulleys
from pipeline.model.sagging import MAX_CABLES, SaggingSpec
from pipeline.model.motion import acceleration_set, cartesian_cube, extreme_points, velocity_set
from pipeline.model.robots import PointsRobot, cpr8, irpm6, point_list
from pipeline.model.statics import DrivenLimits, PathSpec, PayloadSpec, StaticsSpec
from pipeline.model.tensions import TensionSpec
from pipeline.workspace.compute import grid_workspace, name_of
from pipeline.workspace.dispatch import fused_unfit
from pipeline.workspace.criteria import REGISTRY, checked_settings, selected
from pipeline.workspace.grid import Grid, box_grid, listed_grid, step_grid
from pipeline.workspace.kernel import WorkspaceProblem
from pipeline.workspace.reach import home_node
from pipeline.workspace.shape import MESH_MAX_POSES, GridShape, meshable, volume_spread

DEFAULT_N_VEL = 6  # velocity grid of robots without an N x N x N position grid (section 3.1's N)
MAX_VELOCITY_CANDIDATES = 10_000_000  # (n_vel + 1)^3 grid velocities of eq. (23), built in memory


@dataclass(frozen=True)
class RobotKind:
    """A robot a config can name: its keys (``schema``), the robot its config node places
    (``build``), its position grid from the job's config and the robot (``grid``), and the
    grid's size from the config alone (``size``: the plan bounds a job before building it)."""

    schema: type
    build: Callable[[DictConfig], CableRobot]
    grid: Callable[[DictConfig, CableRobot], Grid]
    size: Callable[[DictConfig], int]


def _box_grid(cfg: DictConfig, robot: CableRobot) -> Grid:
    return box_grid(robot.box_lo, robot.box_hi, cfg.grid.n, name_of(cfg.grid.spacing))


def _box_size(cfg: DictConfig) -> int:
    return int(cfg.grid.n) ** 3


def _step_grid(spacing: Callable[[DictConfig], str]):
    """The grid of a robot with a search box and step (IRPM section III), and its size."""
    def grid(cfg: DictConfig, robot: CableRobot) -> Grid:
        return step_grid(robot.box_lo, robot.box_hi, cfg.robot.search.step, spacing(cfg.robot.search))

    def size(cfg: DictConfig) -> int:
        search = cfg.robot.search
        with np.errstate(over="ignore"):  # a count past any float is refused below
            spans = np.asarray(search.hi, dtype=float) - np.asarray(search.lo, dtype=float)
            counts = np.floor(spans / search.step + 1e-9) + (spacing(search) == "faces")
            total = float(np.prod(np.maximum(counts, 0)))
        if not np.isfinite(total):
            raise ConfigError(f"robot.search.step={search.step}: the box from lo={list(search.lo)} to "
                              f"hi={list(search.hi)} holds more grid points than a number can count")
        return int(total)
    return grid, size


ROBOTS = {
    "cpr8": RobotKind(
        Cpr8Config,
        lambda rc: replace(cpr8(rc.frame.d, rc.frame.s, rc.frame.v, rc.carrier.l, rc.carrier.w, rc.carrier.h,
                                lower_anchor_drop=rc.lower_anchor_drop), l_max=rc.l_max),
        _box_grid, _box_size),
    "irpm6": RobotKind(
        Irpm6Config,
        lambda rc: irpm6(rc.r_base, rc.r_end, rc.gamma_deg, rc.search.lo, rc.search.hi, rc.l_max),
        *_step_grid(lambda search: "faces")),
    "points": RobotKind(
        PointsConfig, lambda rc: PointsRobot.from_config(rc).build(),  # checks its points as it builds
        *_step_grid(lambda search: search.spacing)),
}


def _cpr_wwa(cfg: DictConfig, catalogue: Catalogue, robot: CableRobot):
    """CPR-WWA's spec (velocity and acceleration sets, load, readings), the actuator's limits
    and the criteria; refuses an actuator id the catalogue lacks, a velocity grid that would not
    fit in memory, too few cables for the rows eq. (20) balances, and pushing cables under the
    minimum-norm model."""
    _known_actuator(cfg, catalogue)
    model = cfg.model
    n_vel = cfg.grid.n_vel or cfg.grid.get("n") or DEFAULT_N_VEL
    if (n_vel + 1) ** 3 > MAX_VELOCITY_CANDIDATES:
        limit = round(MAX_VELOCITY_CANDIDATES ** (1 / 3)) - 1
        raise ConfigError(f"grid.n_vel={n_vel}: the velocity grid would have {(n_vel + 1) ** 3:.3g} "
                          f"candidates; at most grid.n_vel={limit}")
    if robot.dofs != (0, 1, 2, 3, 4, 5) and not (robot.dofs == (0, 1, 2) and name_of(model.pinv_columns) == "translational"):
        freedoms = ", ".join(FREEDOMS[i] for i in robot.dofs)
        hint = "; with model.pinv_columns=translational" if robot.dofs == (0, 1, 2) else ""
        raise ConfigError(f"robot.dofs=[{freedoms}]: the dynamics of eqs. (19)-(31) move a spatial platform (all six "
                          f"freedoms, or x, y, z with model.pinv_columns=translational){hint}; use analysis=statics")
    if model.jdot and robot.pulleys is not None:
        raise ConfigError("model.jdot=true: the J-dot term of eq. (33) is that of cables from fixed anchors, not from "
                          "swivelling pulleys (robot.pulleys); set model.jdot=false")
    # a point platform (every attachment at its reference point) has no moment rows to balance
    forces_only = name_of(model.pinv_columns) == "translational" or not robot.attachments.any()
    _enough_cables(cfg, robot, 3 if forces_only else 6,
                   "; model.pinv_columns=translational balances forces only")
    if cfg.wrench.set is not None:
        raise ConfigError(f"wrench.set: analysis={cfg.analysis} balances its acceleration set (eq. 31); a required "
                          "wrench set is for analysis=statics")
    tension = tension_spec(cfg, robot)
    if tension.model == "pinv" and np.any(tension.t_min != 0):
        raise ConfigError(f"tension.t_min={shown(cfg.tension.t_min)}: the pinv model checks the papers' "
                          "minimum-norm torques, which may push; set tension.model=feasible")
    actuator = actuator_model(catalogue.row(cfg.actuator), cfg.drive.winch_radius, cfg.drive.gear_ratio,
                              model.xi_in_torque_limit)
    if name_of(model.acceleration_set) == "colon":  # MATLAB's -V/t_dec : V/t_acc, step 1 m/s^2, per axis
        per_axis = math.ceil(cfg.motion.v_max / cfg.motion.t_acc + 1e-12 - -cfg.motion.v_max / cfg.motion.t_dec)  # numpy's count
        if per_axis**3 > MAX_SET_VERTICES:
            raise ConfigError(f"model.acceleration_set=colon: {per_axis} accelerations per axis at motion.v_max="
                              f"{cfg.motion.v_max:g}, t_acc={cfg.motion.t_acc:g}, t_dec={cfg.motion.t_dec:g}, {per_axis**3:,} "
                              f"in all; at most {MAX_SET_VERTICES} (the corners decide the same box)")
    velocities = velocity_set(cfg.motion.v_max, n_vel, name_of(model.velocity_boundary))
    motion = MotionSpec(
        velocities=velocities,
        velocity_extremes=extreme_points(velocities, 2 * cfg.motion.v_max / n_vel),
        accelerations=acceleration_set(
            cfg.motion.v_max, cfg.motion.t_acc, cfg.motion.t_dec, name_of(model.acceleration_set)
        ),
        load=load_spec(cfg),
        winch_radius=np.full(robot.n_cables, actuator.winch_radius),
        pinv_columns=name_of(model.pinv_columns),
        rank_rtol=model.rank_rtol,
        jdot=model.jdot,
        tension=tension,
    )
    return motion, actuator


def _known_actuator(cfg: DictConfig, catalogue: Catalogue) -> None:
    if cfg.actuator is None:
        raise ConfigError(f"actuator=null: analysis={cfg.analysis} checks a catalogue actuator; give its id (actuator=ID)")
    if cfg.actuator not in set(catalogue.ids):
        ids = ", ".join(str(i) for i in sorted(catalogue.ids))
        raise ConfigError(f"actuator={cfg.actuator}: no such id in the catalogue (ids: {ids})")


def _drive(cfg: DictConfig, catalogue: Catalogue | None) -> ActuatorModel | None:
    """The catalogue actuator that drives every cable (``actuator``, ``drive.*`` overriding its
    winch radius and gear ratio; eq. (32) with xi, the default reading); None without one, and a
    ``drive.*`` given without one refused."""
    if cfg.actuator is not None:
        _known_actuator(cfg, catalogue)
        return actuator_model(catalogue.row(cfg.actuator), cfg.drive.winch_radius, cfg.drive.gear_ratio)
    given = next((key for key, value in cfg.drive.items() if value is not None), None)
    if given is not None:
        raise ConfigError(f"drive.{given}={cfg.drive[given]}: the drive is a catalogue actuator's; give its id, "
                          "actuator=ID")
    return None


def _statics(cfg: DictConfig, catalogue: Catalogue | None, robot: CableRobot):
    """The statics' spec (eqs. 7-10), limits and criteria, balancing the rows of the robot's
    freedoms, with ``actuator`` the drive of every cable (:func:`_drive`; its criteria, eqs. 30-34,
    in each required motion of the platform); refuses moments about the base for a platform with
    mass, and, under the minimum-norm model, fewer cables than freedoms (its gram ratio would make
    every pose singular; ``tension=feasible`` finds the poses where fewer cables hold the load, as a crane's)."""
    load = load_spec(cfg)
    if name_of(cfg.model.moment_arm) == "base" and load.mass > 0:
        raise ConfigError(f"model.moment_arm=base: moments about the base are only read for a "
                          f"massless platform (robot.platform.mass={cfg.robot.platform.mass}, "
                          f"load.mass={cfg.load.mass}); set both to 0 and put the weight in wrench.*")
    if name_of(cfg.tension.model) == "pinv":
        _enough_cables(cfg, robot, len(robot.dofs), "; tension=feasible finds where fewer cables hold the load")
    drive = _drive(cfg, catalogue)
    spec = StaticsSpec(
        moment_arm=name_of(cfg.model.moment_arm),
        cable_direction=name_of(cfg.model.cable_direction),
        rank_rtol=cfg.model.rank_rtol,
        tension=tension_spec(cfg, robot),
        load=load,
        **dict(zip(("wrench_set", "vertex_numbers"), wrench_set(cfg.wrench.set))),
        **platform_motion(cfg, load),
        winch_radius=None if drive is None else np.full(robot.n_cables, drive.winch_radius),
    )
    if np.any(spec.velocities) and drive is None:
        raise ConfigError("platform_motion.velocity: the reference point's velocity changes no wrench the cables "
                          "balance; it turns a drive's motors: give actuator=ID")
    if spec.set_size() > MAX_SET_VERTICES:
        raise ConfigError(f"platform_motion: {max(1, len(spec.accelerations))} accelerations x "
                          f"{len(spec.angular_velocities)} angular velocities x {len(spec.velocities)} velocities with each "
                          f"of {max(1, len(spec.wrench_set))} wrenches, {spec.set_size()}; at most {MAX_SET_VERTICES}")
    rating = spec.tension.t_max
    force = spec.load.external[:3] - spec.load.mass * spec.load.gravity * robot.up
    scale = float(np.max(rating)) if rating is not None else max(float(np.linalg.norm(force)), 1.0)
    required = spec.set_size() if len(spec.wrench_set) or spec.moves else 0  # a set's wrenches (summary)
    limits = DrivenLimits(np.inf if rating is None else rating, cfg.model.rank_rtol, scale, required, drive=drive)
    return spec, limits


def _payload(cfg: DictConfig, catalogue: Catalogue | None, robot: CableRobot):
    """The largest payload at ``load.com`` each pose holds on top of the robot's platform, within
    the tension limits (the statics of eqs. 7-10 with the payload's weight linear in its mass);
    ``load.mass`` is the payload required. Refuses a weightless payload."""
    if not cfg.load.gravity > 0:
        raise ConfigError(f"load.gravity={cfg.load.gravity}: analysis=payload weighs the payload; needs gravity > 0")
    if cfg.wrench.set is not None:
        raise ConfigError("wrench.set: analysis=payload finds the largest payload under one wrench; a required "
                          "wrench set is for analysis=statics")
    spec, limits = _statics(cfg, catalogue, robot)
    if spec.winch_radius is not None:
        raise ConfigError(f"actuator={cfg.actuator}: analysis=payload finds the largest payload the cables hold; a "
                          "drive's limits are checked by analysis=statics or trajectory")
    if spec.moves:
        raise ConfigError("platform_motion: analysis=payload finds the largest payload of a platform at rest; "
                          "a platform's motion is for analysis=statics")
    platform = cfg.robot.platform
    applied = spec.load.external  # load.external + wrench.*, as the statics has it
    load = Load(float(platform.mass), float(cfg.load.gravity), np.asarray(platform.com, dtype=float), applied)
    spec = PayloadSpec(spec.moment_arm, spec.cable_direction, spec.rank_rtol, spec.tension, load,
                       payload=float(cfg.load.mass), payload_com=np.asarray(cfg.load.com, dtype=float))
    return spec, limits


def _grid_files(cfg: DictConfig, problem: WorkspaceProblem, grid: Grid, files, sweep_pays: bool) -> dict:
    """A grid job's files: points.parquet streamed chunk by chunk (memory bounded by a chunk, not
    by the grid), or with ``output.points=false`` no file (each chunk's rows counted, then
    dropped); returns the summary. The feasible set's boundary (``pipeline.workspace.shape``):
    its volume and area in the summary where the grid has one, the mesh files with
    ``output.mesh``; with ``workspace.home``, the connected reach in the summary and as the
    column ``connected``."""
    home = cfg.workspace.home
    mesh = meshable(grid, problem.angles is not None) is None and (
        cfg.output.mesh or grid.n_points <= MESH_MAX_POSES)
    if home is None and not mesh:
        if not cfg.output.points:
            summary = grid_workspace(cfg, problem, grid, lambda chunk: None, sweep_pays)[1]
        else:
            with files.stream("points") as sink:
                summary = grid_workspace(cfg, problem, grid, sink.write, sweep_pays)[1]
        return {**summary, "mesh_volume_m3": float("nan"), "mesh_surface_m2": float("nan"), "volume_spread_m3": float("nan")}
    robot = problem.robot
    shape = GridShape(grid, (robot.box_lo, robot.box_hi) if mesh else None, home, cfg.workspace.neighbourhood)
    if not cfg.output.points:
        summary = {**grid_workspace(cfg, problem, grid, shape.watching(None), sweep_pays)[1], **shape.summary()}
    else:
        with files.stream("points", then=None if home is None else shape.label) as sink:
            summary = {**grid_workspace(cfg, problem, grid, shape.watching(sink.write), sweep_pays)[1],
                       **shape.summary()}
    if cfg.output.mesh:
        files.mesh("boundary", shape.vertices, shape.triangles, f"cdpr-studies feasible set of {problem.robot.name}, m")
    return {**summary, **volume_spread(summary["volume_m3"], summary["mesh_volume_m3"])}


def _line_files(cfg: DictConfig, problem: WorkspaceProblem, grid: Grid, files, sweep_pays: bool) -> dict:
    from pipeline.workspace.lines import line_files  # pandas: only this analysis needs it

    return line_files(cfg, problem, grid, files, sweep_pays)


def _trajectory(cfg: DictConfig, catalogue: Catalogue | None, robot: CableRobot):
    """The statics of a path's samples (``pipeline.model.statics.PathSpec``): the statics' spec
    and limits at every sample (with ``actuator`` the statics' drive, :func:`_drive`, at each
    sample's own motion), the path ``trajectory.*`` gives (``pipeline.app.paths``). Refuses a
    platform's motion apart from its path's, an orientation set and listed poses."""
    spec, limits = _statics(cfg, catalogue, robot)
    if spec.moves:
        raise ConfigError("platform_motion: analysis=trajectory takes the platform's motion from its path "
                          "(trajectory.*); leave platform_motion at rest")
    if orientation_count(cfg.orientation) > 1:
        raise ConfigError("orientation.total: a path has its own orientation at every sample (the way-points' "
                          "angles); leave orientation.total.n=1")
    if cfg.poses is not None:
        raise ConfigError("poses: analysis=trajectory checks its path's samples (trajectory.points or "
                          "trajectory.file), not listed poses")
    spec = PathSpec(**{f.name: getattr(spec, f.name) for f in fields(spec)}, samples=path_samples(cfg, robot),
                    convention=name_of(cfg.orientation.convention))
    return spec, limits


def _path_files(cfg: DictConfig, problem: WorkspaceProblem, grid: Grid | None, files, sweep_pays: bool) -> dict:
    from pipeline.workspace.samples import path_files  # pandas: only this analysis needs it

    return path_files(cfg, problem, files)


MAX_CERTIFIED_ORIENTATIONS = 1000  # n = 10: 32 s at depth 4 for IPAnema 1 (n = 20: 80 s, 3 GB at n = 100 after 10 min)


def _certified(cfg: DictConfig, catalogue: Catalogue | None, robot: CableRobot):
    """The statics' spec and limits over boxes of positions (``pipeline.workspace.paving``):
    refuses in one line what the certificates cannot bound yet or a paving does not write. A
    drive at rest is one tension cap per cable (``actuators.rest_tension_cap``: eqs. 32 and 34
    at zero speed), folded into ``t_max``: its boxes are those of that rating."""
    spec, limits = _statics(cfg, catalogue, robot)
    moving = cfg.certified.times is not None or cfg.certified.law != "quintic"
    refused = (
        (spec.tension.model != "feasible", "tension.model=pinv", "the certificates are of cables that pull; "
         "use tension=feasible"),
        (robot.fixed_point, "robot.dofs", "a robot on a joint has orientations to pave, not positions; not certified yet"),
        (spec.winch_radius is not None and (spec.moves or moving or np.any(spec.velocities)), f"actuator={cfg.actuator}",
         "a drive in motion (its speed, acceleration and back-EMF) has no certified bound yet; at rest it is a "
         "proven tension cap; analysis=statics checks it in motion"),
        (not (np.isfinite(robot.box_lo).all() and np.isfinite(robot.box_hi).all()), "robot.search",
         "the paving starts from the search box; give robot.search.lo and hi"),
        (robot.pulleys is not None, "robot.pulleys", "a pulley's exit point moves with the pose; no certified bound yet"),
        (spec.moment_arm == "base", "model.moment_arm=base", "moments about the base move the wrench with the pose; "
         "not certified yet"),
        (cfg.poses is not None, "poses", "a paving proves boxes of the search box, not listed poses"),
        (cfg.workspace.home is not None, "workspace.home", "the connected reach is of a grid analysis"),
        (cfg.output.mesh, "output.mesh=true", "the mesh is of a grid analysis; boxes.parquet holds the certified boxes"),
        (cfg.output.metrics, "output.metrics=true", "the metrics are per pose, of analysis=statics"),
        (cfg.output.cables, "output.cables=true", "the cables' forces are per pose, of analysis=statics"),
        (name_of(cfg.compute.kernel) == "fused", "compute.kernel=fused", "the certificates have one kernel; use auto"),
        (spec.moves and moving, "platform_motion",
         "a moving path's accelerations are its own (certified.times or law); leave platform_motion at rest"),
        ((spec.moves or moving) and (cfg.robust.mass > 0 or cfg.robust.com > 0),
         "robust.mass, robust.com", "the moving platform's inertia changes with its mass and centre of mass; give them "
         "without platform_motion or a moving path"),
        (cfg.robust.attachments > 0 and robot.platform_shape is not None, "robust.attachments",
         "an attachment built off its place leaves the platform shape's surface, which cable_platform reads: "
         "not certified yet; use robust.anchors, or no robot.platform.shape"),
        (cfg.robust.mass > cfg.robot.platform.mass + cfg.load.mass, f"robust.mass={cfg.robust.mass}",
         "a tolerance on the mass larger than the mass itself"),
        (cfg.certified.orientations == "box" and cfg.orientation.total.bound == 0, "certified.orientations=box",
         "orientation.total.bound is 0: no box of orientations; give its half-width (rad), or certified.orientations=listed"),
        (cfg.certified.orientations == "box" and (spec.moves or moving), "certified.orientations=box",
         "a moving platform's inertia turns with it over the box of orientations: not certified yet; prove the box at rest"),
        (orientation_count(cfg.orientation) > MAX_CERTIFIED_ORIENTATIONS, f"orientation.total.n={cfg.orientation.total.n}",
         f"every box is proven at each of the n^3 = {orientation_count(cfg.orientation):,} orientations (or boxes of "
         f"them), at most {MAX_CERTIFIED_ORIENTATIONS} (n <= 10): a level's work grows with them past certified.time"),
    )
    for asked, key, why in refused:
        if asked:
            raise ConfigError(f"{key}: analysis=certified: {why}")
    speeds = [key for key in ("times", "v_max", "t_acc", "t_dec") if cfg.certified[key] is not None]
    if (speeds or moving) and cfg.certified.path is None:
        key = f"certified.{speeds[0]}" if speeds else f"certified.law={cfg.certified.law}"
        raise ConfigError(f"{key}: the motion along certified.path's segments; give the path's way-points")
    if cfg.certified.path is not None:
        points = np.asarray(OmegaConf.to_container(cfg.certified.path), dtype=float)
        certified_motion(cfg, points)
        flat = np.flatnonzero(robot.box_lo == robot.box_hi)  # a planar robot's plane
        off = np.flatnonzero((points[:, flat] != robot.box_lo[flat]).any(axis=1))
        if len(off):
            axis = "xyz"[flat[0]]
            raise ConfigError(f"certified.path: way-point {off[0] + 1} leaves the robot's plane {axis} = "
                              f"{robot.box_lo[flat[0]]:g} (robot.dofs={[FREEDOMS[i] for i in robot.dofs]})")
    if limits.drive is not None:  # at rest (refused in motion above)
        limits = replace(limits, t_max=np.minimum(limits.t_max, rest_tension_cap(limits.drive)))
        spec = replace(spec, winch_radius=None)
    return spec, limits


def _paving_files(cfg: DictConfig, problem: WorkspaceProblem, grid: Grid | None, files, sweep_pays: bool) -> dict:
    from pipeline.workspace.paving import paving_files  # pandas: only this analysis needs it

    path = cfg.certified.path
    motion = None if path is None else certified_motion(cfg, np.asarray(OmegaConf.to_container(path), dtype=float))
    boxes = cfg.certified.orientations == "box"
    turns = orientation_cells(cfg.orientation) if boxes else None
    return paving_files(cfg, problem, files, motion, turns, given_angles(cfg.orientation, boxes))


@dataclass(frozen=True)
class AnalysisKind:
    """An analysis a config can name: the spec and limits of its workspace from the typed config,
    its catalogue (or None) and the robot (``build``; its criteria are the registry's that apply
    to it, ``pipeline.workspace.criteria.selected``), and the files a job of it
    writes (``files``: (typed config, problem, grid, the job's files, whether its sweep pays for
    the compiled kernels) -> the summary; the job's files (``pipeline.app.job.JobFiles``) take
    tables whole or streamed chunk by chunk)."""

    build: Callable[[DictConfig, Catalogue | None, CableRobot], tuple]
    files: Callable[..., dict]
    keys: tuple[str, ...]  # the keys of its analysis file it reads (dotted), beyond conf/config.yaml's
    gridded: bool = True  # whether it checks the robot's grid (False: its own samples, and ``files`` gets no grid)
    certified: bool = False  # whether its verdicts are proofs: every criterion it checks has a certified bound


DRIVE_KEYS = ("actuator", "catalogue", "drive", "choice")
STATICS_KEYS = ("model.moment_arm", "model.cable_direction", "platform_motion", *DRIVE_KEYS)
CPR_WWA_KEYS = (*DRIVE_KEYS, "motion", "grid.n_vel", "model.pinv_columns", "model.velocity_boundary",
                "model.acceleration_set", "model.jdot", "model.xi_in_torque_limit")
ANALYSES = {
    "cpr_wwa": AnalysisKind(_cpr_wwa, _grid_files, CPR_WWA_KEYS),
    "statics": AnalysisKind(_statics, _grid_files, STATICS_KEYS),
    "lines": AnalysisKind(_cpr_wwa, _line_files, (*CPR_WWA_KEYS, "lines")),
    "payload": AnalysisKind(_payload, _grid_files, STATICS_KEYS),
    "trajectory": AnalysisKind(_trajectory, _path_files, (*STATICS_KEYS, "trajectory"), gridded=False),
    "certified": AnalysisKind(_certified, _paving_files, (*STATICS_KEYS, "certified", "robust"), gridded=False,
                              certified=True),
}


def foreign_key(cfg: DictConfig) -> None:
    """ConfigError on a key of another analysis's file that ``cfg`` has (one added with ``+``, or
    kept by a study or robot file): its analysis would not read it, so a job would ignore it."""
    reads = ANALYSES[cfg.analysis].keys
    for key in dict.fromkeys(key for kind in ANALYSES.values() for key in kind.keys):
        if key not in reads and OmegaConf.select(cfg, key, default=None, throw_on_missing=False) is not None:
            readers = ", ".join(name for name, kind in ANALYSES.items() if key in kind.keys)
            raise ConfigError(f"{key}: analysis={cfg.analysis} does not read it (a key of analysis={readers}); "
                              "remove it or choose that analysis")


MAX_SET_VERTICES = 4096  # wrenches of a wrench.set: each is an LP block or a solve per pose


def wrench_set(value) -> tuple[np.ndarray, tuple[int, ...]]:
    """(K, 6) the vertices of ``wrench.set``: a box's (every combination of each coordinate's min
    and max, once where they are equal) or the listed ones, each once; (0, 6) for null. And
    each vertex's number in the set as given (1 = its first), which ``limiting_wrench`` reports."""
    return vertex_set(value, "wrench.set", _wrench, "[fx, fy, fz, mx, my, mz] (N, N m)", "the one wrench")


def vertex_set(value, key: str, parse: Callable, what: str, empty: str) -> tuple[np.ndarray, tuple[int, ...]]:
    """(K, 6) the vertices of the set ``key`` gives (a box or a list of ``what``, each parsed by
    ``parse(value, key)``) and their numbers (above); null: (0, 6), ``empty``."""
    if value is None:
        return np.zeros((0, 6)), ()
    shown_value = OmegaConf.to_container(value) if isinstance(value, (DictConfig, ListConfig)) else value
    if isinstance(value, DictConfig):
        if set(value) != {"min", "max"}:
            raise ConfigError(f"{key}={shown_value}: a box needs min and max, 6 numbers each")
        low, high = (parse(value[side], f"{key}.{side}") for side in ("min", "max"))
        if not (low <= high).all():
            raise ConfigError(f"{key}.min={low.tolist()}: must be <= {key}.max={high.tolist()}")
        box = np.array(list(itertools.product(*(sorted({a, b}) for a, b in zip(low, high)))), dtype=float)
        return box, tuple(range(1, len(box) + 1))
    if not isinstance(value, ListConfig):
        raise ConfigError(f"{key}={shown_value}: a box {{min: [6], max: [6]}} or a list of {what}")
    if not len(value):
        raise ConfigError(f"{key}=[]: no vertices (null: {empty})")
    if len(value) > MAX_SET_VERTICES:
        raise ConfigError(f"{key}: {len(value)} vertices; at most {MAX_SET_VERTICES}")
    vertices = np.array([parse(v, f"{key}: vertex {i}") for i, v in enumerate(value, start=1)])
    _, first = np.unique(vertices, axis=0, return_index=True)  # a repeated vertex is one more solve for nothing
    first = np.sort(first)
    return vertices[first], tuple(int(i) + 1 for i in first)


GOLDEN = (1 + 5 ** 0.5) / 2
ICOSAHEDRON = np.array([p for a, b in ((1, GOLDEN), (-1, GOLDEN), (1, -GOLDEN), (-1, -GOLDEN))
                        for p in ((0, a, b), (a, b, 0), (b, 0, a))], dtype=float)
ICOSAHEDRON_INRADIUS = 0.7946544722917661  # of the icosahedron whose vertices lie on the unit sphere


def ball_vertices(node) -> np.ndarray:
    """(V, 6) the accelerations of ``platform_motion.acceleration={linear: r, angular: r}``: each
    ball (m/s^2, rad/s^2; a missing one is 0) by the regular icosahedron around it, its faces
    tangent to the ball (12 vertices at 1.258 r from the centre): it contains the ball, so a pose
    holding its vertices holds every acceleration of the ball (and somewhat more); both balls
    together, every pair of their vertices."""
    radii = []
    for key in ("linear", "angular"):
        value = node.get(key, 0.0)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= MAX_ACCELERATION:
            raise ConfigError(f"platform_motion.acceleration.{key}={value}: a ball's radius, a number from 0 to "
                              f"{MAX_ACCELERATION:g} (m/s^2 or rad/s^2)")
        radii.append(float(value))
    unit = ICOSAHEDRON / np.linalg.norm(ICOSAHEDRON, axis=1, keepdims=True) / ICOSAHEDRON_INRADIUS
    sets = [unit * r if r > 0 else np.zeros((1, 3)) for r in radii]
    return np.array([np.concatenate([a, b]) for a in sets[0] for b in sets[1]])


def platform_motion(cfg: DictConfig, load: Load) -> dict:
    """The statics' ``accelerations``, ``angular_velocities`` and ``velocities`` of
    ``platform_motion`` (at rest without the node); refuses angular motion of a platform without
    its inertia."""
    if "platform_motion" not in cfg:
        return {}
    node = cfg.platform_motion
    given = node.acceleration
    if isinstance(given, DictConfig) and set(given) <= {"linear", "angular"} and len(given):
        accelerations = ball_vertices(given)
    else:
        accelerations = vertex_set(given, "platform_motion.acceleration", _acceleration,
                                   "[ax, ay, az, alpha_x, alpha_y, alpha_z] (m/s^2, rad/s^2)", "at rest")[0]
    omega = velocity_list(node.angular_velocity, "platform_motion.angular_velocity", OMEGA_RULE, "[wx, wy, wz] (rad/s)")
    velocities = velocity_list(node.velocity, "platform_motion.velocity", VELOCITY_RULE, "[vx, vy, vz] (m/s)")
    if load.inertia is None and load.mass > 0 and (np.any(omega) or np.any(accelerations[:, 3:])):
        raise ConfigError("platform_motion: a platform that turns needs its inertia, robot.platform.inertia "
                          "([Ixx, Iyy, Izz(, Ixy, Ixz, Iyz)] kg m^2 about its centre of mass)")
    return {"accelerations": accelerations, "angular_velocities": omega, "velocities": velocities}


MAX_VELOCITIES = 64  # listed (angular) velocities: each multiplies the wrenches a pose holds


def velocity_list(value, key: str, rule, what: str) -> np.ndarray:
    """(V, 3) one velocity ``what`` or a list of them (``platform_motion.angular_velocity``,
    ``velocity``)."""
    given = OmegaConf.to_container(value) if isinstance(value, ListConfig) else value
    rows = given if isinstance(given, list) and given and all(isinstance(v, list) for v in given) else [given]
    if len(rows) > MAX_VELOCITIES:
        raise ConfigError(f"{key}: {len(rows)} velocities, at most {MAX_VELOCITIES}")
    return np.array([_checked(row, key, rule, f"{what}, or a list of them") for row in rows])


WRENCH_RULE = vector(6, "fx fy fz mx my mz, N and N m", MAX_FORCE)  # the rule of load.external
ACCELERATION_RULE = vector(6, "ax ay az alpha_x alpha_y alpha_z, m/s^2 and rad/s^2", MAX_ACCELERATION)
OMEGA_RULE = vector(3, "wx wy wz, rad/s", MAX_ACCELERATION)
VELOCITY_RULE = vector(3, "vx vy vz, m/s", MAX_ACCELERATION)
POINT_RULE = vector(3, "x, y, z, m", MAX_FORCE)  # an obstacle's or a platform box's corner, point, normal


def _wrench(value, key: str) -> np.ndarray:
    return _checked(value, key, WRENCH_RULE, "must be a list of 6 numbers (fx fy fz mx my mz)")


def _acceleration(value, key: str) -> np.ndarray:
    return _checked(value, key, ACCELERATION_RULE, "must be a list of 6 numbers (ax ay az alpha_x alpha_y alpha_z)")


def _point(value, key: str) -> np.ndarray:
    return _checked(value, key, POINT_RULE, "must be 3 numbers [x, y, z] (m)")


def _checked(value, key: str, rule, shape: str) -> np.ndarray:
    """``value`` (a list node) as an array, or ConfigError '<key>=<value>: <what rule says>'."""
    items = OmegaConf.to_container(value) if isinstance(value, ListConfig) else value
    broken = rule(items) if isinstance(items, list) else shape
    if broken:
        raise ConfigError(f"{key}={items}: {broken}")
    return np.asarray(items, dtype=float)


def _enough_cables(cfg: DictConfig, robot: CableRobot, rows: int, hint: str) -> None:
    if robot.n_cables < rows:
        what = {3: "forces", 6: "forces and moments"}.get(rows, f"{rows} freedoms")
        raise ConfigError(f"robot: {robot.n_cables} cables; analysis={cfg.analysis} balances {what} "
                          f"({rows} rows of the structure matrix) and needs >= {rows} cables{hint}")


def typed_config(cfg: DictConfig) -> DictConfig:
    """The composed config with every value of its declared type (numbers, enums, lists), keeping
    only the keys it has: a statics job has no ``actuator``, so its summary has none either.
    An undeclared key (also one added with ``+``) or a value of the wrong type: ConfigError."""
    return masked(typed_schema(cfg), cfg)


def typed_schema(cfg: DictConfig) -> DictConfig:
    """``cfg`` merged into the typed schema of its robot kind (every declared key, typed nodes
    that check any later assignment); :func:`pipeline.app.config.masked` keeps the keys ``cfg``
    has."""
    unknown_keys(cfg, Config)
    robot = cfg.get("robot")
    if not isinstance(robot, DictConfig) or "name" not in robot:
        raise ConfigError("robot: the robot file gives no robot keys (an empty file, or not a mapping of "
                          "keys): start your own with 'defaults: [points, _self_]'")
    name = known_kinds(cfg)
    unknown_keys(cfg.robot, ROBOTS[name].schema, "robot.")
    full = merged(Config, cfg, "")
    full.robot = merged(ROBOTS[name].schema, cfg.robot, "robot.")
    return full


def known_kinds(cfg: DictConfig) -> str:
    """The robot kind ``cfg`` names, once its robot and analysis kinds are known to be ones the
    registries hold (ConfigError otherwise)."""
    name = cfg.robot.get("name")
    if name not in ROBOTS:
        raise ConfigError(f"robot.name={name}: unknown robot ({', '.join(ROBOTS)})")
    if cfg.get("analysis") not in ANALYSES:
        raise ConfigError(f"analysis={cfg.get('analysis')}: unknown analysis ({', '.join(ANALYSES)})")
    return name


def validate(cfg: DictConfig, catalogue: Catalogue | None,
             typed: bool = False) -> tuple[DictConfig, WorkspaceProblem]:
    """The typed config (:func:`typed_config`; ``typed``: ``cfg`` already is) and its built
    problem, or ConfigError on the first value the model cannot use: '<key>=<value>: <rule>'.
    First every field's declared rule (:func:`pipeline.app.config.check_values`), then the
    robot and analysis kinds' own rules as they build, then the rules that join several groups.
    ``catalogue``: the actuators an analysis with an actuator chooses from."""
    cfg = cfg if typed else typed_config(cfg)
    check_values(cfg, Config)
    schema = ROBOTS[known_kinds(cfg)].schema
    foreign = [key for key in cfg.robot if key not in {f.name for f in fields(schema)}]
    if foreign:  # robot.name set on the command line to another kind than the robot's file
        raise ConfigError(f"robot.name={cfg.robot.name}: the robot's file has keys the robot kind {cfg.robot.name} "
                          f"does not ({', '.join(foreign)}); choose a robot with robot=NAME, not robot.name")
    check_values(cfg.robot, schema, "robot.")
    foreign_key(cfg)
    if cfg.output.cables and not cfg.output.points:
        raise ConfigError("output.cables=true: the cables go into points.parquet, which "
                          "output.points=false does not write")
    if cfg.compute.backend == "dask" and importlib.util.find_spec("distributed") is None:
        raise ConfigError("compute.backend=dask: needs Dask, pip install 'cdpr-studies[dask]'")
    if cfg.poses is not None:
        point_list("poses", cfg.poses)
    elif cfg.robot.name == "points" and ANALYSES[cfg.analysis].gridded:
        missing = [key for key in ("lo", "hi", "step") if cfg.robot.search[key] is None]
        if missing:
            raise ConfigError(f"robot.search.{missing[0]}: no value given (the box searched needs lo, hi and step; "
                              "or list the poses to check: poses=[[x, y, z], ...])")
    if ANALYSES[cfg.analysis].gridded:  # a path bounds its samples as it builds them
        _validate_size(cfg)  # before anything the size would make large is built
    problem = build(cfg, catalogue)
    for key, asked in (("workspace.home", cfg.workspace.home is not None), ("output.mesh=true", cfg.output.mesh)):
        if asked and cfg.analysis in ("lines", "trajectory"):
            follows = "straight lines" if cfg.analysis == "lines" else "its path"
            raise ConfigError(f"{key}: analysis={cfg.analysis} follows {follows}; the connected reach and the mesh are "
                              "of a grid analysis (cpr_wwa, statics, payload)")
    if cfg.analysis == "lines":
        from pipeline.workspace.lines import check_samples  # pandas: only this analysis needs it

        check_samples(cfg.motion, build_grid(cfg, problem.robot))
    if cfg.workspace.home is not None:
        home_node(build_grid(cfg, problem.robot), cfg.workspace.home)
    if cfg.output.mesh:
        unfit = meshable(build_grid(cfg, problem.robot), problem.angles is not None)
        if unfit:
            raise ConfigError(f"output.mesh=true: {unfit}, so there is no boundary to write")
    if name_of(cfg.compute.kernel) == "fused":
        unfit = fused_unfit(problem)
        if unfit:
            raise ConfigError(f"compute.kernel=fused: {unfit}; use compute.kernel=auto or numpy")
    return cfg, problem


def build(cfg: DictConfig, catalogue: Catalogue | None) -> WorkspaceProblem:
    """The workspace problem of a typed config: its robot kind's robot, its analysis kind's
    spec, limits and criteria, the orientation set."""
    robot = surroundings(cfg, elastic(cfg, guided(cfg, plausible(ROBOTS[cfg.robot.name].build(cfg.robot)))))
    spec, limits = ANALYSES[cfg.analysis].build(cfg, catalogue, robot)
    if robot.catenary is not None:
        spec = sagging(cfg, spec, robot)
    settings = checked_settings(OmegaConf.to_container(cfg.criteria)) if "criteria" in cfg else {}
    criteria = selected(cfg.analysis, spec, robot, settings)  # the registry's, by what each applies to
    uncertified = [name for name in criteria if not REGISTRY[name].certified]
    if ANALYSES[cfg.analysis].certified and uncertified:
        raise ConfigError(f"analysis={cfg.analysis}: this problem checks {uncertified[0]}, which has no certified "
                          "bound yet; remove the key that adds it, or use analysis=statics")
    refused = [name for name in settings if name not in criteria]
    if refused:
        raise ConfigError(f"criteria.{refused[0]}: analysis={cfg.analysis} does not check it on this robot; "
                          "remove its keys or choose an analysis it applies to")
    for name, keys in settings.items():  # what a criterion itself cannot evaluate on this problem
        reason = REGISTRY[name].refuses(spec, robot, keys) if REGISTRY[name].refuses else None
        if reason:
            raise ConfigError(f"criteria.{name}: {reason}")
    bounded = {name: keys for name, keys in settings.items() if REGISTRY[name].bounds is not None}
    if bounded:  # the feasible model nests their intervals with their keys
        spec = replace(spec, tension=replace(spec.tension, bounded=bounded))
    given = cfg.orientation
    if robot.fixed_point and (orientation_count(given) > 1 or any(given[a] != 0 for a in ("psi", "theta", "phi"))):
        freedoms = ", ".join(FREEDOMS[i] for i in robot.dofs)
        raise ConfigError(f"orientation: robot.dofs=[{freedoms}] holds the platform at the origin and its grid is "
                          "of orientations (robot.search: psi, theta, phi in rad, in orientation.convention); "
                          "orientation.psi, theta, phi and total are not read, leave them 0")
    if cfg.output.metrics and (cfg.analysis != "statics" or len(spec.wrench_set) or spec.moves):
        why = ("a wrench set or a platform's motion has several loads" if cfg.analysis == "statics"
               else f"analysis={cfg.analysis} is not")
        raise ConfigError(f"output.metrics=true: the tension factor and the largest wrenches are of a static pose "
                          f"under one load (analysis=statics without wrench.set); {why}")
    boxes = cfg.analysis == "certified" and cfg.certified.orientations == "box"
    return WorkspaceProblem(robot, orientation_set(given, boxes), spec, limits, criteria, cfg.model.margin_atol,
                            cfg.output.cables, nominal=(float(given.psi), float(given.theta), float(given.phi)),
                            angles=name_of(given.convention) if robot.fixed_point else None,
                            metrics=bool(cfg.output.metrics), settings=settings)


def sagging(cfg: DictConfig, spec, robot: CableRobot) -> SaggingSpec:
    """The statics of sagging cables (``robot.catenary``, docs/model.md section 9), refused in one
    line where they cannot mean anything yet: another analysis, cables that may push, pulleys,
    cables to the platform's centre, more than ``sagging.MAX_CABLES`` cables (the proof's 2^m
    corners), the metrics of straight cables."""
    if cfg.analysis != "statics":
        why = f"analysis={cfg.analysis}: sagging cables are checked by analysis=statics"
    elif spec.tension.model != "feasible":
        why = "tension.model=pinv: sagging cables need tension=feasible (cables pull)"
    elif robot.pulleys is not None:
        why = "robot.pulleys: a pulley turns with its catenary's end, not modelled"
    elif spec.cable_direction != "attachment":
        why = "model.cable_direction: sagging cables run to their attachments"
    elif robot.n_cables > MAX_CABLES:
        why = f"{robot.n_cables} cables: the proof checks 2^m corners, at most {MAX_CABLES} cables"
    elif cfg.output.metrics:
        why = "output.metrics: the tension factor and wrench capacity are of straight cables"
    else:
        why = None
    if why:
        raise ConfigError(f"robot.catenary={cfg.robot.catenary}: {why}")
    return SaggingSpec(**{f.name: getattr(spec, f.name) for f in fields(spec)})


MAX_CABLE_MASS = 100.0  # kg/m: a steel rope of 13 cm, past any cable robot's
MAX_WINCH_LENGTH = 10_000.0  # m: the cable stored between an anchor and its winch, past any robot
MAX_SIZE_RATIO = 10_000  # anchors' span over the platform's: past any cable robot, a unit typed wrong


def plausible(robot: CableRobot) -> CableRobot:
    """The robot, unless its frame and platform differ in size past any cable robot's (a frame
    typed in mm with the platform in m): ConfigError naming both sizes."""
    frame = float(np.ptp(robot.anchors, axis=0).max())
    platform = float(np.linalg.norm(robot.attachments, axis=1).max())
    if platform > 0 and frame > MAX_SIZE_RATIO * platform:
        raise ConfigError(f"robot: the anchors span {frame:.4g} m and the attachments reach {platform:.4g} m from the "
                          f"platform's reference point, {frame / platform:.3g} times less: past any cable robot; are "
                          "both in metres (robot.anchors, robot.attachments)?")
    return robot


def guided(cfg: DictConfig, robot: CableRobot) -> CableRobot:
    """The robot with its swivelling pulleys (``robot.pulleys``, docs/model.md section 6): one
    mapping {axis: [x, y, z], radius: m} for every cable, or a list of one per cable. The axis is
    the way the cable runs into the pulley from its winch (any length, normalised); the radius at
    least 0 and at most a tenth of the robot's size (a larger one is a unit typed wrong)."""
    value, key = cfg.robot.pulleys, "robot.pulleys"
    if value is None:
        return robot
    items = list(value) if isinstance(value, ListConfig) else [value]
    if len(items) not in (1, robot.n_cables):
        raise ConfigError(f"{key}: {len(items)} pulleys for {robot.n_cables} cables (one for all, or one per cable)")
    axes, radii = [], []
    for k, item in enumerate(items):
        where = f"{key}[{k}]" if isinstance(value, ListConfig) else key
        if not isinstance(item, DictConfig) or set(item) != {"axis", "radius"}:
            raise ConfigError(f"{where}={shown(item)}: a mapping {{axis: [x, y, z], radius: m}}")
        axis = _checked(item.axis, f"{where}.axis", POINT_RULE, "must be 3 numbers [x, y, z]")
        radius = item.radius
        if not np.linalg.norm(axis) > 0:
            raise ConfigError(f"{where}.axis={axis.tolist()}: must not be zero (the way the cable runs into the pulley)")
        if isinstance(radius, bool) or not isinstance(radius, (int, float)) or not 0 <= radius <= robot.extent / 10:
            raise ConfigError(f"{where}.radius={radius}: must be a number from 0 to a tenth of the robot's size "
                              f"({robot.extent / 10:.3g} m), in m")
        axes.append(axis / np.linalg.norm(axis))
        radii.append(float(radius))
    shape = (robot.n_cables,)
    return replace(robot, pulleys=Pulleys(np.broadcast_to(axes, (*shape, 3)).copy(), np.broadcast_to(radii, shape).copy()))


def elastic(cfg: DictConfig, robot: CableRobot) -> CableRobot:
    """The robot with elastic and heavy cables (docs/model.md sections 7-8): ``robot.cable_ea`` (N,
    > 0, one or one per cable; null: rigid), ``robot.winch_length`` (m, >= 0, the cable between
    the anchor and the winch, in series) and ``robot.cable_mass`` (kg/m, > 0; null: weightless)."""
    if cfg.robot.cable_mass is not None:
        mass = _limit_values("robot.cable_mass", cfg.robot.cable_mass, robot.n_cables, "kg/m", MAX_CABLE_MASS)
        if not (mass > 0).all():
            raise ConfigError(f"robot.cable_mass={shown(cfg.robot.cable_mass)}: must be > 0 (kg/m; null: weightless)")
        robot = replace(robot, cable_mass=mass.copy())
    if cfg.robot.catenary is not None:
        if robot.cable_mass is None:
            raise ConfigError(f"robot.catenary={cfg.robot.catenary}: sagging cables need their weight, robot.cable_mass (kg/m)")
        robot = replace(robot, catenary=float(cfg.robot.catenary))
    if cfg.robot.cable_ea is None:
        return robot
    ea = _limit_values("robot.cable_ea", cfg.robot.cable_ea, robot.n_cables)
    if not (ea > 0).all():
        raise ConfigError(f"robot.cable_ea={shown(cfg.robot.cable_ea)}: must be > 0 (N)")
    winch = _limit_values("robot.winch_length", cfg.robot.winch_length, robot.n_cables, "m", MAX_WINCH_LENGTH)
    if (winch < 0).any():
        raise ConfigError(f"robot.winch_length={shown(cfg.robot.winch_length)}: must be >= 0 (m)")
    return replace(robot, cable_ea=ea.copy(), winch_lengths=winch.copy())


def surroundings(cfg: DictConfig, robot: CableRobot) -> CableRobot:
    """The robot with what its cables could touch (docs/model.md section 5; the interference
    criteria apply to what it has): ``robot.cable_diameter`` (one or one per cable, m) gives the
    cables' radii (``cable_cable``), ``robot.platform.shape`` the platform's body
    (``cable_platform``), ``obstacles`` the cell's obstacles (``cable_obstacle``). Each is refused
    where it cannot mean anything: no two cables that can meet along their length, a body with
    no inside or an attachment off its surface, an obstacle that holds an anchor."""
    diameter = cfg.robot.cable_diameter
    if diameter is not None:
        items = OmegaConf.to_container(diameter) if isinstance(diameter, ListConfig) else [diameter]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v < float("inf") for v in items):
            raise ConfigError(f"robot.cable_diameter={shown(diameter)}: must be a number > 0 (m) or a list of one per cable")
        if len(items) not in (1, robot.n_cables):
            raise ConfigError(f"robot.cable_diameter={shown(diameter)}: {len(items)} values for {robot.n_cables} cables")
        if max(items) > robot.extent / 10:
            raise ConfigError(f"robot.cable_diameter={shown(diameter)}: must be at most a tenth of the robot's size "
                              f"({robot.extent / 10:.3g} m: its farthest anchor or attachment coordinate / 10)")
        robot = replace(robot, cable_radii=np.broadcast_to(np.asarray(items, dtype=float) / 2, (robot.n_cables,)).copy())
        if not len(robot.cable_pairs[0]):
            raise ConfigError(f"robot.cable_diameter={shown(diameter)}: every two cables share an anchor or an attachment "
                              "point (a point platform), so none can touch another along its length; set it null")
    if cfg.robot.platform.shape is not None:
        robot = replace(robot, platform_shape=platform_shape(cfg.robot.platform.shape, robot))
    if cfg.obstacles is not None and not (isinstance(cfg.obstacles, ListConfig) and not len(cfg.obstacles)):
        robot = replace(robot, obstacles=obstacles(cfg.obstacles, robot))
    return robot


def platform_shape(value, robot: CableRobot) -> Polytope:
    """The body of ``robot.platform.shape``: ``hull`` or a box {lo, hi} (m, platform frame),
    every attachment point on its surface (a cable leaves the platform there)."""
    shown_value = OmegaConf.to_container(value) if isinstance(value, DictConfig) else value
    key = "robot.platform.shape"
    tol = robot.shortest_cable
    if value == "hull":
        shape = Polytope.hull(robot.attachments, tol)
        if not len(shape.normals):
            raise ConfigError(f"{key}=hull: the attachment points span no volume (a plate, a line or a point), so no "
                              "cable can enter it; declare a box {lo: [x, y, z], hi: [x, y, z]} (m, platform frame)")
    elif isinstance(value, DictConfig) and set(value) == {"lo", "hi"}:
        lo, hi = (_point(value[end], f"{key}.{end}") for end in ("lo", "hi"))
        if not (lo < hi).all():
            raise ConfigError(f"{key}.lo={lo.tolist()}: must be below {key}.hi={hi.tolist()} on every axis")
        shape = Polytope.box(lo, hi)
    else:
        raise ConfigError(f"{key}={shown_value}: hull, or a box {{lo: [x, y, z], hi: [x, y, z]}} (m, platform frame)")
    heights = robot.attachments @ shape.normals.T - shape.offsets  # <= 0 inside, 0 on a face
    for i, row in enumerate(heights):
        if row.max() > tol or row.max() < -tol:
            where = "outside" if row.max() > tol else "inside"
            raise ConfigError(f"{key}: attachment {i + 1} {robot.attachments[i].tolist()} is {where} the platform's "
                              "body, not on its surface (each cable leaves the platform at its surface)")
    return shape


MAX_OBSTACLES = 100
ANCHOR_RTOL = 1e-9  # an anchor this far (times the robot's extent) inside an obstacle already touches it


def obstacles(value, robot: CableRobot) -> tuple[Obstacle, ...]:
    """The obstacles of ``obstacles``: boxes {lo, hi} and planes {point, normal} (m, fixed frame,
    each with an optional name); refuses one that holds an anchor or lies within its cable's
    radius of one (every cable from it would touch it at every pose)."""
    if not isinstance(value, ListConfig):
        raise ConfigError(f"obstacles={shown(value)}: a list of boxes {{lo: [3], hi: [3]}} and planes "
                          "{point: [3], normal: [3]} (m)")
    if len(value) > MAX_OBSTACLES:
        raise ConfigError(f"obstacles: {len(value)} of them; at most {MAX_OBSTACLES} (each costs about the work of "
                          "a pose's whole statics: merge neighbouring boxes into one)")
    found = []
    for number, item in enumerate(value):
        key = f"obstacles[{number}]"
        fields_ = set(item) - {"name"} if isinstance(item, DictConfig) else None
        name = str(item.get("name", f"obstacle {number + 1}")) if fields_ is not None else ""
        if fields_ == {"lo", "hi"}:
            lo, hi = (_point(item[end], f"{key}.{end}") for end in ("lo", "hi"))
            if not (lo < hi).all():
                raise ConfigError(f"{key}.lo={lo.tolist()}: must be below {key}.hi={hi.tolist()} on every axis")
            obstacle = Obstacle(name, lo=lo, hi=hi)
        elif fields_ == {"point", "normal"}:
            point, normal = (_point(item[end], f"{key}.{end}") for end in ("point", "normal"))
            if not np.linalg.norm(normal) > 0:
                raise ConfigError(f"{key}.normal={normal.tolist()}: must not be zero")
            obstacle = Obstacle(name, point=point, normal=normal / np.linalg.norm(normal))
        else:
            raise ConfigError(f"{key}={shown(item)}: a box {{lo: [3], hi: [3]}} or a plane {{point: [3], normal: [3]}} "
                              "(m, fixed frame), with an optional name")
        none = np.zeros((robot.n_cables, 0, 3))  # each anchor a point body, measured as cable_obstacle measures
        clearance = obstacle.clearance(robot.anchors[:, None, :], none, none)  # < 0: inside
        radii = np.zeros(robot.n_cables) if robot.cable_radii is None else robot.cable_radii
        touching = clearance - radii < -ANCHOR_RTOL * robot.extent
        if touching.any():  # a cable from that anchor starts on or in it: every pose loses it
            anchor = int(np.flatnonzero(touching)[0])
            where = "inside it" if clearance[anchor] < 0 else f"within its cable's radius ({radii[anchor]:.3g} m) of it"
            raise ConfigError(f"{key} ({name}): anchor {anchor + 1} {robot.anchors[anchor].tolist()} is {where}, so "
                              "every pose would have a cable touching it")
        found.append(obstacle)
    return tuple(found)



def build_grid(cfg: DictConfig, robot: CableRobot) -> Grid:
    """The positions a job checks: the robot kind's grid, or the user's own ``poses`` (no grid
    cell, no volume); for a robot whose reference point a joint holds, the orientations (the
    same boxes and lists, in rad; no volume)."""
    grid = ROBOTS[cfg.robot.name].grid(cfg, robot) if cfg.poses is None else listed_grid(point_list("poses", cfg.poses))
    return replace(grid, cell_volume=float("nan")) if robot.fixed_point else grid  # rad^3 is no volume


def build_problem(cfg: DictConfig, catalogue: Catalogue | None) -> tuple[WorkspaceProblem, Grid]:
    """The workspace problem of the configured robot and analysis, and its position grid."""
    problem = build(cfg, catalogue)
    return problem, build_grid(cfg, problem.robot)


def grid_size(cfg: DictConfig) -> int:
    """Grid poses a job checks, counted without building the grid (``compute.max_poses`` bounds
    it); 0 for an analysis without a grid (a path's samples are bounded as they are built)."""
    if not ANALYSES[cfg.analysis].gridded:
        return 0
    return len(cfg.poses) if cfg.poses is not None else ROBOTS[cfg.robot.name].size(cfg)


def orientation_count(orientation: DictConfig) -> int:
    """k of :func:`orientation_set`, counted without building it."""
    total = orientation.total
    return 1 if total.n == 1 or total.bound == 0 else int(total.n) ** 3


def orientation_set(orientation: DictConfig, boxes: bool = False) -> np.ndarray:
    """(k, 3) eq. (9) angles: :func:`given_angles` each converted from ``orientation.convention``
    (xyz: the same rotations, eq. 9's angles)."""
    angles = given_angles(orientation, boxes)
    if name_of(orientation.convention) == "xyz":
        return np.array([eq9_angles(*row) for row in angles])
    return angles


def given_angles(orientation: DictConfig, boxes: bool = False) -> np.ndarray:
    """(k, 3) the job's orientations in ``orientation.convention``: the constant orientation, or
    the total-orientation grid around it (the nominal first); with ``boxes`` the centres of
    :func:`orientation_cells` instead (``certified.orientations=box``)."""
    nominal = np.array([orientation.psi, orientation.theta, orientation.phi], dtype=float)
    total = orientation.total
    angles = nominal[None, :]
    if boxes:
        angles = np.array([cell[2] for cell in orientation_cells(orientation)])
    elif orientation_count(orientation) > 1:
        offsets = np.linspace(-total.bound, total.bound, total.n)
        grid = cartesian_cube(offsets)
        order = np.argsort(np.abs(grid).sum(axis=1), kind="stable")  # nominal orientation first
        angles = nominal + grid[order]
    return angles


def orientation_cells(orientation: DictConfig) -> list[tuple]:
    """The total-orientation box, every orientation whose angles lie within ``total.bound`` (rad)
    of the nominal ones (in ``orientation.convention``), cut into ``total.n`` boxes per angle
    (``certified.orientations=box``: a paving proves a box of positions inside at every orientation
    of every one, ``pipeline.workspace.paving.Turn``): (lo, hi, centre (3,) each, convention) per
    box, the one nearest the nominal orientation first, as :func:`orientation_set` orders its grid.
    Neighbours share their edges' doubles; the outer edges are rounded outward, so the boxes cover
    the whole box of reals."""
    nominal = np.array([orientation.psi, orientation.theta, orientation.phi], dtype=float)
    total, convention = orientation.total, name_of(orientation.convention)
    edges = nominal[:, None] + np.linspace(-total.bound, total.bound, int(total.n) + 1)[None]  # (3, n + 1)
    edges[:, 0], edges[:, -1] = down(nominal - total.bound), up(nominal + total.bound)
    cells = []
    for index in itertools.product(range(int(total.n)), repeat=3):
        lo = edges[np.arange(3), list(index)]
        hi = edges[np.arange(3), [i + 1 for i in index]]
        cells.append((lo, hi, np.clip(lo + (hi - lo) / 2, lo, hi), convention))
    order = np.argsort([np.abs(cell[2] - nominal).sum() for cell in cells], kind="stable")
    return [cells[i] for i in order]


def load_spec(cfg: DictConfig) -> Load:
    """The load of every analysis: the robot's platform and the payload on it as one body (their
    masses added, the centre of mass their mass-weighted mean, platform frame), gravity, and as
    its external wrench ``load.external`` plus the applied wrench ``wrench.*`` (IRPM eq. 11)."""
    # plain containers: numpy reads an OmegaConf list node item by item, 1 ms a job
    platform, load, w = (OmegaConf.to_container(node) for node in (cfg.robot.platform, cfg.load, cfg.wrench))
    mass = float(platform["mass"]) + float(load["mass"])
    moments = float(platform["mass"]) * np.asarray(platform["com"], dtype=float) + float(load["mass"]) * np.asarray(
        load["com"], dtype=float)
    com = moments / mass if mass > 0 else np.zeros(3)
    applied = np.array([w[key] for key in ("fx", "fy", "fz", "mx", "my", "mz")], dtype=float)
    inertia = None
    if platform.get("inertia") is not None:  # the platform's about its own centre, the payload a point mass
        def shifted(body_mass, at):  # parallel axes: the inertia of a point mass about the joint centre
            offset = np.asarray(at, dtype=float) - com
            return body_mass * (offset @ offset * np.eye(3) - np.outer(offset, offset))
        inertia = (platform_inertia(platform["inertia"], float(platform["mass"]))
                   + shifted(float(platform["mass"]), platform["com"]) + shifted(float(load["mass"]), load["com"]))
    return Load(mass, float(load["gravity"]), com, np.asarray(load["external"], dtype=float) + applied, inertia)


def platform_inertia(value, mass: float) -> np.ndarray:
    """``robot.platform.inertia``: [Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], kg m^2, about
    the platform's centre of mass (platform frame), as a (3, 3) matrix: a rigid body's
    (:func:`pipeline.model.dynamics.inertia_fault`; a planar platform's may be Izz alone), of a
    platform with a mass."""
    key = "robot.platform.inertia"
    if not (isinstance(value, list) and len(value) in (3, 6)
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        raise ConfigError(f"{key}={value}: [Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (kg m^2, about the "
                          "platform's centre of mass)")
    matrix = inertia_tensor(*value)
    fault = inertia_fault(matrix)
    if fault:
        raise ConfigError(f"{key}={value}: {fault}")
    if not mass > 0:
        raise ConfigError(f"{key}={value}: a platform with an inertia needs its mass (robot.platform.mass > 0)")
    return matrix


def tension_spec(cfg: DictConfig, robot: CableRobot) -> TensionSpec:
    """The cable tension model and limits, each limit one number or one per cable of ``robot``
    (``tension.t_max`` null = no rating). Refuses a negative ``t_min`` and a rating not above it."""
    t = cfg.tension
    t_min = _limit_values("tension.t_min", t.t_min, robot.n_cables)
    if not (t_min >= 0).all():
        raise ConfigError(f"tension.t_min={shown(t.t_min)}: must be >= 0 (a cable cannot push)")
    if t.t_max is not None and not (t_min < _limit_values("tension.t_max", t.t_max, robot.n_cables)).all():
        raise ConfigError(f"tension.t_max={shown(t.t_max)}: must be > tension.t_min={shown(t.t_min)}")
    return TensionSpec(name_of(t.model), _per_cable(t.t_min), _per_cable(t.t_max), t.residual_rtol,
                       name_of(t.distribution), t.pinv_residual)


def _per_cable(value):
    """A tension limit as the kernels take it: a float, an (m,) array for a list, or None."""
    if value is None:
        return None
    if isinstance(value, (int, float)):
        return float(value)
    return np.asarray(list(value), dtype=float)


def _limit_values(key: str, value, n_cables: int, unit: str = "N", largest: float = MAX_FORCE) -> np.ndarray:
    """A tension limit (or another per-cable value in ``unit``, at most ``largest``) as an (m,)
    array: one finite number for every cable, or one per cable."""
    items = [value] if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    try:
        items = list(items)
    except TypeError:
        items = None
    if items is None or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items):
        raise ConfigError(f"{key}={shown(value)}: must be a number ({unit}) or a list of one per cable")
    if len(items) not in (1, n_cables):
        raise ConfigError(f"{key}={shown(value)}: {len(items)} values for {n_cables} cables")
    values = np.broadcast_to(np.asarray(items, dtype=float), (n_cables,))
    if not np.isfinite(values).all():
        raise ConfigError(f"{key}={shown(value)}: must be finite (null: no limit)")
    if (np.abs(values) > largest).any():
        raise ConfigError(f"{key}={shown(value)}: must be at most {largest:g} {unit}")
    return values


def _validate_size(cfg: DictConfig) -> None:
    """Refuse, before any work, a job larger than ``compute.max_poses`` pose x orientation
    evaluations, naming the key to change."""
    poses = grid_size(cfg)
    if poses == 0:  # a cell of side step larger than the box: no centre inside it
        search = cfg.robot.search
        raise ConfigError(f"robot.search.step={search.step}: no grid point in the search box (cells of that side "
                          f"do not fit between lo={list(search.lo)} and hi={list(search.hi)}); use a smaller "
                          "step or spacing: faces")
    orientations = orientation_count(cfg.orientation)
    if poses * orientations > cfg.compute.max_poses:
        raise ConfigError(
            f"compute.max_poses={cfg.compute.max_poses}: this job has {poses:.3g} poses x "
            f"{orientations:.3g} orientations = {poses * orientations:.3g} evaluations; use a "
            "coarser grid (grid.n, robot.search.step), fewer orientation.total.n, or raise "
            "compute.max_poses knowingly")

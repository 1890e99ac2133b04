"""Certified workspaces by branch and prune (``analysis=certified``, issue 57).

The robot's search box is bisected, level by level, along each box's longest side; every box is
certified inside (every pose in it feasible at every orientation of the job), outside (no pose in
it feasible at one of them, or a cable too long) or left undecided and bisected again
(``pipeline.model.certificates``), until ``certified.depth`` levels or ``certified.time``
seconds. The inside boxes are an inner approximation of the workspace, inside and undecided an
outer one: its volume lies in [V_inside, V_inside + V_undecided] (summary ``inside_m3``,
``undecided_m3``, ``undecided_pct`` of the search box). A box's verdict is a proof for the
criteria that have a certified bound (``Criterion.certified``); a problem with another is refused.

At each box's centre the floats the certificates try are the statics' own: the structure matrix
and its pseudo-inverse, the LP's tensions with the most room to both limits
(``pipeline.model.tensions.capacity_margins``) and the facet normals of hyperplane shifting.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from pipeline.model import certificates
from pipeline.model.certificates import INSIDE, OUTSIDE, UNDECIDED, WRENCH_RTOL, BoxStatics
from pipeline.model.intervals import Interval, rotation_enclosure
from pipeline.model.tensions import Family, capacity_margins, reachability
from pipeline.workspace.compute import flatten, name_of
from pipeline.workspace.kernel import WorkspaceProblem
from pipeline.workspace.parallel import iter_chunks

log = logging.getLogger(__name__)

CHUNK = 2048  # boxes certified at once (memory: the facet normals' scores, ~50 MB for 8 cables)
VERDICTS = {INSIDE: "inside", OUTSIDE: "outside", UNDECIDED: "undecided"}


@dataclass(frozen=True)
class Paving:
    """The boxes (lo, hi (B, 3), m), their verdicts (B,) and the level each was decided at (B,)."""

    lo: np.ndarray
    hi: np.ndarray
    verdict: np.ndarray
    depth: np.ndarray

    def volumes(self, axes: np.ndarray) -> np.ndarray:
        """(B,) each box's volume along the searched axes (an area for a planar robot)."""
        return np.prod((self.hi - self.lo)[:, axes], axis=1)


def box_statics(problem: WorkspaceProblem, angles: np.ndarray) -> BoxStatics:
    """The certificates' data at one orientation (eq. 9's angles): enclosures of R b_i - a_i and
    R b_i, the required wrenches widened by ``WRENCH_RTOL`` of the terms that form them, the
    tension limits and the cables' lengths."""
    robot, spec = problem.robot, problem.spec
    rotation = rotation_enclosure(*angles)
    arms = (rotation[None] * robot.attachments[:, None, :]).sum(axis=-1)  # (m, 3)
    offsets = (-Interval.point(robot.anchors)) if spec.cable_direction == "centre" else arms - robot.anchors
    state = spec.state(robot, ((robot.box_lo + robot.box_hi) / 2)[None], tuple(angles))
    wrenches = np.asarray(state.required_wrenches, dtype=float).reshape(-1, len(robot.dofs))
    load = spec.load
    size = (1.0 + np.abs(wrenches).max() + np.abs(load.external).max() + np.abs(spec.wrench_set).max(initial=0.0)
            + load.mass * (load.gravity + np.abs(spec.accelerations).max(initial=0.0)) * (1.0 + np.linalg.norm(load.com))
            + (0.0 if load.inertia is None else np.abs(load.inertia).max())
            * (np.abs(spec.accelerations).max(initial=0.0) + np.abs(spec.angular_velocities).max() ** 2))
    radius = WRENCH_RTOL * size
    m = robot.n_cables
    lower = np.broadcast_to(np.asarray(spec.tension.t_min, dtype=float), (m,)).copy()
    upper = np.broadcast_to(np.asarray(problem.limits.t_max, dtype=float), (m,)).copy()
    return BoxStatics(offsets, arms, tuple(robot.dofs), Interval(wrenches - radius, wrenches + radius), lower, upper,
                      np.inf if robot.l_max is None else float(robot.l_max), robot.shortest_cable)


def certify(problem: WorkspaceProblem, statics: list[BoxStatics], lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(N,) the verdict of each box [lo, hi] (N, 3): inside at every orientation, outside at one."""
    centre = np.clip(lo + (hi - lo) / 2, lo, hi)
    verdict = np.full(len(lo), INSIDE)
    for angles, box in zip(problem.orientations, statics):
        open_ = np.flatnonzero(verdict != OUTSIDE)
        if not len(open_):
            break
        found = _certified(problem, box, tuple(angles), lo[open_], hi[open_], centre[open_])
        verdict[open_] = np.where(found == OUTSIDE, OUTSIDE, np.minimum(verdict[open_], found))
    return verdict


def _certified(problem: WorkspaceProblem, box: BoxStatics, angles, lo, hi, centre) -> np.ndarray:
    state = problem.spec.state(problem.robot, centre, angles)
    structure = state.structure
    pinv, rank = state.wrench_pinv
    enclosure = certificates.structure_enclosure(box, lo, hi, centre)
    wrenches = (box.wrenches.lo + box.wrenches.hi) / 2
    family = Family("tension", box.lower, box.upper, np.full(len(box.lower), problem.limits.scale))
    every = np.broadcast_to(wrenches, (len(lo), *wrenches.shape))
    residual, projected = reachability(structure, pinv, every)
    margin = capacity_margins(structure, pinv, rank, projected, [family])[0]["tension"]
    held = (margin >= 0) & (residual.max(axis=1) <= problem.spec.tension.residual_rtol) & (rank == structure.shape[1])
    slopes, half = (enclosure.slopes.lo + enclosure.slopes.hi) / 2, (hi - lo) / 2
    verdict = np.full(len(lo), UNDECIDED)
    rows = np.flatnonzero(held & enclosure.regular)
    if len(rows):  # the centre holds: the LP's tensions with the most room, moved to first order by A(c)^+
        tensions = capacity_margins(structure[rows], pinv[rows], rank[rows], projected[rows], [family], distribution=True)[1]
        rates = -np.einsum("nmk,nlkj,nKj->nKml", pinv[rows], slopes[rows], tensions)  # A(c) D_l = -(dA/dp_l) t0
        proven = certificates.inside(box, enclosure.rows(rows), tensions, rates, pinv[rows])
        verdict[rows[proven]] = INSIDE
    rows = np.flatnonzero(~held)
    if len(rows):  # the centre fails: the separating direction that holds best over the box, to first order
        separators, gap = certificates.robust_separators(structure[rows], slopes[rows], half[rows], wrenches,
                                                         box.lower, box.upper)
        proven = certificates.outside(box, enclosure.rows(rows), np.where((gap > 0)[..., None], separators, 0.0))
        verdict[rows[proven]] = OUTSIDE
    too_long = (enclosure.lengths.lo > box.l_max).any(axis=1)
    return np.where(too_long, OUTSIDE, verdict)


def pave(problem: WorkspaceProblem, depth: int, seconds: float, compute: DictConfig) -> tuple[Paving, dict]:
    """Branch and prune from the robot's search box: the paving and how it ended. A level's boxes
    are certified in chunks (``pipeline.workspace.parallel``: ``compute.n_jobs`` workers); past
    ``seconds`` the chunks not yet certified stay undecided."""
    robot = problem.robot
    given = (problem, [box_statics(problem, angles) for angles in problem.orientations])
    axes = np.flatnonzero(robot.box_hi > robot.box_lo)
    boxes = np.concatenate([robot.box_lo, robot.box_hi])[None].astype(float)  # (B, 6): lo, hi
    kept: list[tuple] = []
    start, level = time.perf_counter(), 0
    total, decided = float(np.prod((robot.box_hi - robot.box_lo)[axes])), 0.0
    while True:
        verdict = np.full(len(boxes), UNDECIDED)
        late = False
        for rows, part in iter_chunks(_verdicts, given, boxes, compute.n_jobs, name_of(compute.backend), CHUNK,
                                      compute.scheduler):
            verdict[rows] = part["verdict"]
            if time.perf_counter() - start > seconds:
                late = True  # the rest of the level stays undecided
                break
        done = verdict != UNDECIDED
        last = late or level >= depth or not (~done).any()
        keep = done | last
        kept.append((boxes[keep, :3], boxes[keep, 3:], verdict[keep], np.full(int(keep.sum()), level)))
        decided += float(np.prod((boxes[done, 3:] - boxes[done, :3])[:, axes], axis=1).sum())
        log.info("certified level %d: %d boxes, %.2f%% of the search box decided (%.1f s)", level, len(boxes),
                 100.0 * decided / total, time.perf_counter() - start)
        if last:
            stopped = "decided" if not (~done).any() else "time" if late else "depth"
            break
        boxes = _bisected(boxes[~done], axes)
        level += 1
    paving = Paving(*(np.concatenate(parts) for parts in zip(*kept)))
    return paving, {"stopped": stopped, "depth_reached": level, "seconds": time.perf_counter() - start}


def _verdicts(given: tuple, boxes: np.ndarray) -> dict[str, np.ndarray]:
    """The chunk task: the verdicts of boxes (B, 6) [lo, hi]."""
    problem, statics = given
    return {"verdict": certify(problem, statics, boxes[:, :3], boxes[:, 3:])}


def _bisected(boxes: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Both halves of each box (B, 6) [lo, hi], cut across its longest side among ``axes``."""
    rows = np.arange(len(boxes))
    axis = axes[np.argmax((boxes[:, 3:] - boxes[:, :3])[:, axes], axis=1)]
    middle = boxes[rows, axis] + (boxes[rows, axis + 3] - boxes[rows, axis]) / 2
    lower, upper = boxes.copy(), boxes.copy()
    lower[rows, axis + 3] = middle
    upper[rows, axis] = middle
    return np.concatenate([lower, upper])


def paving_files(cfg: DictConfig, problem: WorkspaceProblem, files) -> dict:
    """A certified job's boxes.parquet and summary (module doc)."""
    paving, ended = pave(problem, int(cfg.certified.depth), float(cfg.certified.time), cfg.compute)
    robot = problem.robot
    axes = np.flatnonzero(robot.box_hi > robot.box_lo)
    volumes = paving.volumes(axes)
    total = float(np.prod((robot.box_hi - robot.box_lo)[axes]))
    shares = {VERDICTS[v]: float(volumes[paving.verdict == v].sum()) for v in VERDICTS}
    if cfg.output.points:
        table = pd.DataFrame({**{f"lo_{a}": paving.lo[:, k] for k, a in enumerate("xyz")},
                              **{f"hi_{a}": paving.hi[:, k] for k, a in enumerate("xyz")},
                              "verdict": pd.Categorical([VERDICTS[v] for v in paving.verdict],
                                                        categories=list(VERDICTS.values())),
                              "depth": paving.depth, "volume": volumes})
        files.write("boxes", table)
    row = flatten(OmegaConf.to_container(cfg, resolve=True, enum_to_str=True))
    row.update(problem.limits.described())
    row["n_orientations"] = len(problem.orientations)
    for axis, lo, hi in zip("xyz", robot.box_lo, robot.box_hi):
        row[f"box.{axis}_min"], row[f"box.{axis}_max"] = float(lo), float(hi)
    counts = {name: int((paving.verdict == v).sum()) for v, name in VERDICTS.items()}
    row.update(
        n_points=len(paving.verdict), n_feasible=counts["inside"], feasible_pct=100.0 * shares["inside"] / total,
        volume_m3=shares["inside"], n_inside=counts["inside"], n_outside=counts["outside"], n_undecided=counts["undecided"],
        box_m3=total, inside_m3=shares["inside"], outside_m3=shares["outside"], undecided_m3=shares["undecided"],
        inside_pct=100.0 * shares["inside"] / total, undecided_pct=100.0 * shares["undecided"] / total, **ended,
    )
    log.info("%s certified: %.4g to %.4g m^3 feasible (inside %.2f%%, undecided %.2f%% of the search box), %d boxes "
             "in %.1f s (%s)", robot.name, shares["inside"], shares["inside"] + shares["undecided"], row["inside_pct"],
             row["undecided_pct"], len(paving.verdict), ended["seconds"], ended["stopped"])
    return row

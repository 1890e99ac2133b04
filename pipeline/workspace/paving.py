"""Certified workspaces by branch and prune (``analysis=certified``, issue 57).

The robot's search box is bisected, level by level, along each box's longest side; every box is
certified inside (every pose in it feasible at every orientation of the job), outside (no pose in
it feasible at one of them, or a cable too long) or left undecided and bisected again
(``pipeline.model.certificates``), until ``certified.depth`` levels or ``certified.time``
seconds. The inside boxes are an inner approximation of the workspace, inside and undecided an
outer one: its volume lies in [V_inside, V_inside + V_undecided] (summary ``inside_m3``,
``undecided_m3``, ``undecided_pct`` of the search box). A box's verdict is a proof for the
criteria that have a certified bound (``Criterion.certified``); a problem with another is refused.
With ``certified.path`` the straight segments between way-points are certified piece by piece
instead, at rest or moving rest to rest in ``certified.times`` (:func:`certify_path`).

At each box's centre the floats the certificates try are the statics' own: the structure matrix
and its pseudo-inverse, the LP's tensions with the most room to both limits
(``pipeline.model.tensions.capacity_margins``) and the facet normals of hyperplane shifting.
"""

from __future__ import annotations

import itertools
import logging
import os
import time
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from pipeline.model import certificates
from pipeline.model.certificates import INSIDE, OUTSIDE, UNDECIDED, WRENCH_RTOL, BoxStatics
from pipeline.model.intervals import Interval, cross, rotation_box_enclosure, rotation_enclosure, stack, up
from pipeline.model.path import StraightMotion
from pipeline.model.tensions import Family, capacity_margins, reachability
from pipeline.workspace.compute import described_job, name_of
from pipeline.workspace.criteria import REGISTRY
from pipeline.workspace.feasibility import null_space_verdicts
from pipeline.workspace.kernel import WorkspaceProblem
from pipeline.workspace.parallel import iter_chunks
from pipeline.workspace.tolerances import NOMINAL, Tolerances, culprits

log = logging.getLogger(__name__)

CHUNK = 2048  # boxes certified at once (memory: the facet normals' scores, ~50 MB for 8 cables)
VERDICTS = {INSIDE: "inside", OUTSIDE: "outside", UNDECIDED: "undecided"}


@dataclass(frozen=True)
class Paving:
    """The boxes (lo, hi (B, 3), m), their verdicts (B,), the level each was decided at (B,) and,
    for an outside box, the orientation (an index of the problem's, -1 for the others) at which it
    was proven infeasible."""

    lo: np.ndarray
    hi: np.ndarray
    verdict: np.ndarray
    depth: np.ndarray
    at: np.ndarray

    def volumes(self, axes: np.ndarray) -> np.ndarray:
        """(B,) each box's volume along the searched axes (an area for a planar robot)."""
        return np.prod((self.hi - self.lo)[:, axes], axis=1)


Turn = tuple  # (lo, hi, centre (3,) each, convention): a box of orientations and a point of it, angles in rad
#               (``certified.orientations=box``, ``pipeline.app.problem.orientation_cells``)


def rotations(angles, turn: Turn | None) -> tuple[Interval, Interval | None]:
    """Enclosures of the rotation at eq. (9)'s ``angles``, or of every rotation of the box ``turn``
    and of its partial derivatives (3, 3, 3) (``intervals.rotation_box_enclosure``)."""
    if turn is None:
        return rotation_enclosure(*angles), None
    lo, hi, _, convention = turn
    return rotation_box_enclosure(lo, hi, convention)


def box_statics(problem: WorkspaceProblem, angles: np.ndarray, tolerances: Tolerances = NOMINAL,
                turn: Turn | None = None) -> BoxStatics:
    """The certificates' data at one orientation (eq. 9's angles), or over every orientation of
    the box ``turn`` about it, for every robot within ``tolerances``: enclosures of R b_i - a_i
    and R b_i, the required wrenches widened by ``WRENCH_RTOL`` of the terms that form them (over
    a box of orientations also by the weight's moment as the centre of mass turns,
    ((R - R(angles)) c) x m g, R over the box), the tension limits and the cables' lengths.
    Within a mass and centre-of-mass tolerance each required wrench is required at every corner of
    their box, each corner its own wrench (corners x K rows): the wrench is affine in the mass
    and in the centre of mass, so over the box it lies in the hull of its values at the corners,
    and the wrenches a robot balances at a pose are a convex set: the corners suffice, each
    with its own tensions (their box hull would lose how the mass moves force and moment together)."""
    robot, spec = problem.robot, problem.spec
    rotation = rotations(angles, turn)[0]
    def within(points: np.ndarray, tolerance: float) -> Interval:
        return Interval.point(points) + Interval(np.full(3, -tolerance), np.full(3, tolerance))

    attachments, anchors = within(robot.attachments, tolerances.attachments), within(robot.anchors, tolerances.anchors)
    arms = (rotation[None] * attachments[:, None, :]).sum(axis=-1)  # (m, 3)
    offsets = -anchors if spec.cable_direction == "centre" else arms - anchors
    centre = ((robot.box_lo + robot.box_hi) / 2)[None]
    load = spec.load
    corners = [replace(spec, load=replace(load, mass=load.mass + dm, com=np.asarray(load.com) + np.array(dc)))
               for dm in sorted({-tolerances.mass, tolerances.mass})
               for dc in itertools.product(*[sorted({-tolerances.com, tolerances.com})] * 3)]
    wrenches = np.stack([np.asarray(corner.state(robot, centre, tuple(angles)).required_wrenches, dtype=float)
                         .reshape(-1, len(robot.dofs)) for corner in corners])  # (corners, K, k)
    radius = _radius(spec, tolerances, wrenches)
    enclosed = Interval(wrenches - radius, wrenches + radius)
    if turn is not None:  # the weight's moment about the reference point turns with the platform
        turned = rotation - rotation_enclosure(*angles)  # R - R(angles) over the box, (3, 3)
        weights = [Interval.point(-corner.load.mass * corner.load.gravity * np.asarray(robot.up, dtype=float))
                   for corner in corners]
        moments = [cross((turned * Interval.point(np.asarray(corner.load.com, dtype=float))[None]).sum(axis=-1), weight)
                   for corner, weight in zip(corners, weights)]  # (3,) each
        zero = np.zeros((len(corners), 3))
        change = Interval(np.concatenate([zero, np.stack([m.lo for m in moments])], axis=1)[:, list(robot.dofs)],
                          np.concatenate([zero, np.stack([m.hi for m in moments])], axis=1)[:, list(robot.dofs)])
        enclosed = enclosed + change[:, None, :]
    m = robot.n_cables
    lower = np.broadcast_to(np.asarray(spec.tension.t_min, dtype=float), (m,)).copy()
    upper = np.broadcast_to(np.asarray(problem.limits.t_max, dtype=float), (m,)).copy()
    hull = robot.platform_shape is None  # the attachments' hull: its vertices move with them
    vertices = within(robot.platform_body.vertices, tolerances.attachments if hull else 0.0)
    body = (rotation[None] * vertices[:, None, :]).sum(axis=-1)  # R v_k, (k, 3)
    faces = np.zeros((0, 3)) if robot.platform_shape is None else robot.platform_shape.normals
    normals = (rotation[None] * Interval.point(faces)[:, None, :]).sum(axis=-1)  # R n_f, (f, 3)
    k = wrenches.shape[-1]
    return BoxStatics(offsets, arms, tuple(robot.dofs), Interval(enclosed.lo.reshape(-1, k), enclosed.hi.reshape(-1, k)),
                      lower, upper, np.inf if robot.l_max is None else float(robot.l_max), robot.shortest_cable, anchors, body,
                      normals)


def build_errors(problem: WorkspaceProblem, angles, tolerances: Tolerances,
                 turn: Turn | None = None) -> tuple[Interval, Interval, np.ndarray] | None:
    """The build errors the tensions follow to first order (``certificates.BuildErrors``): every
    coordinate of every anchor and attachment within its tolerance, and over a box of orientations
    ``turn`` every angle within it of the box's centre, as (moves, arms, tolerances): an anchor's
    a_il moves the cable's vector by -e_l, an attachment's b_il moves it (unless the cables run to
    the reference point) and the arm by R e_l, an angle moves both by (dR/dangle) b_i, R and its
    derivative enclosed over the box. None without either."""
    robot = problem.robot
    m = robot.n_cables
    rotation, partials = rotations(angles, turn)
    zero = np.zeros((m, 3))
    still = problem.spec.cable_direction == "centre"
    moves, arms, sizes = [], [], []
    for cable in range(m):
        for axis in range(3):
            if tolerances.anchors:
                moved = zero.copy()
                moved[cable, axis] = -1.0
                moves.append(Interval.point(moved))
                arms.append(Interval.point(zero))
                sizes.append(tolerances.anchors)
            if tolerances.attachments:
                lo, hi = zero.copy(), zero.copy()
                lo[cable], hi[cable] = rotation.lo[:, axis], rotation.hi[:, axis]  # R e_l
                moves.append(Interval.point(zero) if still else Interval(lo, hi))
                arms.append(Interval(lo, hi))
                sizes.append(tolerances.attachments)
    if turn is not None:
        lo, hi, centre, _ = turn
        attachments = Interval.point(robot.attachments) + Interval(np.full(3, -tolerances.attachments),
                                                                   np.full(3, tolerances.attachments))
        for axis in np.flatnonzero(hi > lo):
            turned = (partials[axis][None] * attachments[:, None, :]).sum(axis=-1)  # (dR/dangle) b_i
            moves.append(Interval.point(zero) if still else turned)
            arms.append(turned)
            sizes.append(float(up(np.maximum(hi[axis] - centre[axis], centre[axis] - lo[axis]))))
    return (stack(moves, axis=0), stack(arms, axis=0), np.array(sizes)) if sizes else None


def _radius(spec, tolerances: Tolerances, wrenches: np.ndarray) -> float:
    """How far the statics' rounding may have moved ``wrenches`` formed from ``spec``: ``WRENCH_RTOL``
    of the size of the terms that form them (the load's, the wrench set's, the motion's)."""
    load = spec.load
    size = (1.0 + np.abs(wrenches).max() + np.abs(load.external).max() + np.abs(spec.wrench_set).max(initial=0.0)
            + (load.mass + tolerances.mass) * (load.gravity + np.abs(spec.accelerations).max(initial=0.0))
            * (1.0 + np.linalg.norm(load.com) + 2 * tolerances.com)
            + (0.0 if load.inertia is None else np.abs(load.inertia).max())
            * (np.abs(spec.accelerations).max(initial=0.0) + np.abs(spec.angular_velocities).max() ** 2))
    return WRENCH_RTOL * size


def moving_wrenches(problem: WorkspaceProblem, angles, accelerations: np.ndarray) -> Interval:
    """(N, K, k) the required wrenches of a platform that does not turn, each box's linear
    acceleration anywhere on the segment between its two ends ``accelerations`` (N, 2, 3), m/s^2:
    the wrench is affine in the acceleration (``dynamics.inertial_wrenches``), so its range over the
    segment is the hull of its values at the ends, widened as :func:`box_statics` widens."""
    robot, n, k = problem.robot, len(accelerations), len(problem.robot.dofs)
    given = np.concatenate([accelerations.reshape(-1, 3), np.zeros((2 * n, 3))], axis=1)
    spec = replace(problem.spec, accelerations=given)
    centre = ((robot.box_lo + robot.box_hi) / 2)[None]  # moments about the platform: the same at every position
    values = np.asarray(spec.state(robot, centre, tuple(angles)).required_wrenches, dtype=float).reshape(-1, n, 2, k)
    radius = _radius(spec, NOMINAL, values)
    return Interval(np.moveaxis(values.min(axis=2), 0, 1) - radius, np.moveaxis(values.max(axis=2), 0, 1) + radius)


def centres(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(N, 3) a point of each box [lo, hi] at its middle (clipped into it against rounding)."""
    return np.clip(lo + (hi - lo) / 2, lo, hi)


def certify(problem: WorkspaceProblem, statics: list[tuple[BoxStatics, BoxStatics]], lo: np.ndarray,
            hi: np.ndarray, accelerations: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(N,) the verdict of each box [lo, hi] (N, 3): inside at every orientation for every robot
    within the tolerances, outside at one for the nominal robot (then for none within them); and
    (N,) that orientation's index in ``problem.orientations`` (-1 where the box is not outside).
    ``statics``: (nominal, within the tolerances, within them but the anchors' and attachments',
    those followed to first order: :func:`build_errors`) per orientation of ``problem.orientations``;
    ``accelerations`` (N, 2, 3): a platform moving through each box with its linear acceleration
    on the segment between the two (:func:`moving_wrenches`; None: the statics' own wrenches)."""
    centre = centres(lo, hi)
    verdict, at = np.full(len(lo), INSIDE), np.full(len(lo), -1)
    for k, (angles, boxes) in enumerate(zip(problem.orientations, statics)):
        open_ = np.flatnonzero(verdict != OUTSIDE)
        if not len(open_):
            break
        moving = None if accelerations is None else moving_wrenches(problem, angles, accelerations[open_])
        found = _certified(problem, *boxes, tuple(angles), lo[open_], hi[open_], centre[open_], moving)
        verdict[open_] = np.where(found == OUTSIDE, OUTSIDE, np.minimum(verdict[open_], found))
        at[open_[found == OUTSIDE]] = k
    return verdict, at


def _certified(problem: WorkspaceProblem, box: BoxStatics, robust: BoxStatics, rest: BoxStatics, errors, angles,
               lo, hi, centre, moving: Interval | None) -> np.ndarray:
    state = problem.spec.state(problem.robot, centre, angles)
    structure = state.structure
    pinv, rank = state.wrench_pinv
    enclosure = certificates.structure_enclosure(box, lo, hi, centre)
    within = enclosure if robust is box else certificates.structure_enclosure(robust, lo, hi, centre)
    def per_box(wrenches: Interval) -> Interval:
        shape = (len(lo), *wrenches.shape[-2:])
        return Interval(np.broadcast_to(wrenches.lo, shape), np.broadcast_to(wrenches.hi, shape))
    nominal, held_by = (per_box(box.wrenches), per_box(robust.wrenches)) if moving is None else (moving, moving)
    every = (nominal.lo + nominal.hi) / 2  # (N, K, k)
    family = Family("tension", box.lower, box.upper, np.full(len(box.lower), problem.limits.scale))

    def holding(wrenches: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Whether the centre holds every wrench, and the wrenches projected on A(c)'s range."""
        residual, projected = reachability(structure, pinv, wrenches)
        margin = capacity_margins(structure, pinv, rank, projected, [family])[0]["tension"]
        return (margin >= 0) & (residual.max(axis=1) <= problem.spec.tension.residual_rtol) & (rank == structure.shape[1]), \
            projected

    held, projected = holding(every)
    same_wrenches = held_by.lo.shape == nominal.lo.shape  # else a mass or centre-of-mass tolerance: its corners' wrenches
    held_in, projected_in = (held, projected) if same_wrenches else holding((held_by.lo + held_by.hi) / 2)
    fails, holds = _corners(problem, box, angles, lo, hi, every)
    slopes, half = (enclosure.gradient.lo + enclosure.gradient.hi) / 2, (hi - lo) / 2  # dA/dp at the centre
    verdict = np.full(len(lo), UNDECIDED)
    rows = np.flatnonzero(held_in & enclosure.regular & ~fails)
    if len(rows):  # the centre holds: the LP's tensions with the most room, moved to first order through the cables with room
        tensions = capacity_margins(structure[rows], pinv[rows], rank[rows], projected_in[rows], [family],
                                    distribution=True)[1]
        inverse = _roomy_inverse(structure[rows], tensions, box, problem.limits.scale)
        rates = -np.einsum("nmk,nlkj,nKj->nKml", inverse, slopes[rows], tensions)  # A(c) D_l = -(dA/dp_l) t0
        followed = None
        if errors is not None:  # the tensions follow the build errors to first order too: A(c) E_j = -(dA/ddelta_j)(c) t0
            moves, arms, sizes = errors
            designed = enclosure if rest is box else certificates.structure_enclosure(rest, lo, hi, centre)
            unit = Interval.point(state.unit[rows])
            slopes_j = [certificates.error_slopes(box, enclosure.gradient[rows], unit, moves, arms, j) for j in range(len(sizes))]
            middle = np.stack([(part.lo + part.hi) / 2 for part in slopes_j], axis=1)  # (N, P, k, m)
            at_centre = certificates.structure_enclosure(robust, centre[rows], centre[rows], centre[rows])
            followed = certificates.BuildErrors(designed.rows(rows), at_centre,
                                                -np.einsum("nmk,nPkj,nKj->nKmP", inverse, middle, tensions), moves, arms, sizes)
        proven = certificates.inside(robust, within.rows(rows), held_by[rows], tensions, rates, inverse, followed)
        verdict[rows[proven]] = INSIDE
    rows = np.flatnonzero(~held & ~holds)
    if len(rows):  # the centre fails: the separating direction that holds best over the box, to first order
        separators, gap = certificates.robust_separators(structure[rows], slopes[rows], half[rows], every[rows],
                                                         box.lower, box.upper)
        proven = certificates.outside(box, enclosure.rows(rows), nominal[rows], np.where((gap > 0)[..., None], separators, 0.0))
        verdict[rows[proven]] = OUTSIDE
    too_long = (enclosure.lengths.lo > box.l_max).any(axis=1)
    verdict = np.where(too_long, OUTSIDE, verdict)
    for name in problem.criteria:  # the criteria that bound boxes themselves (the interference criteria)
        bound = REGISTRY[name].boxes
        if bound is not None:
            found = bound(problem.robot, robust, box, lo, hi, centre, problem.margin_atol)
            verdict = np.where((verdict == OUTSIDE) | (found == OUTSIDE), OUTSIDE, np.minimum(verdict, found))
    return verdict


def _roomy_inverse(structure: np.ndarray, tensions: np.ndarray, box: BoxStatics, scale: float) -> np.ndarray:
    """(N, m, k) a right inverse of each A(c) (N, k, m) that moves the cables with room: K = W A^T
    (A W A^T)^-1, W the squares of each cable's least room to its limits over the wrenches
    (``tensions`` (N, K, m)), at least 1e-3 of ``scale``. Through it the tensions follow the box's
    poses (D) and absorb the residual (K e) where they can, not in a cable at its limit, as the
    pseudo-inverse (W = I) would: a quarter more of IPAnema 1's boxes at depth 15 are proven
    inside (benchmarks/LOG.md). Any K is sound: :func:`certificates.inside` checks A(B) K."""
    room = np.minimum(tensions - box.lower, box.upper - tensions).min(axis=1)
    weights = np.maximum(room, 1e-3 * scale) ** 2  # (N, m)
    weighted = structure * weights[:, None, :]  # A W
    return np.swapaxes(np.linalg.solve(weighted @ np.swapaxes(structure, 1, 2), weighted), 1, 2)


def _corners(problem: WorkspaceProblem, box: BoxStatics, angles, lo: np.ndarray, hi: np.ndarray,
             wrenches: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N,) whether a corner of each box [lo, hi] surely fails, and whether one surely holds, the
    box's required ``wrenches`` (N, K, k) with the tension limits widened, and narrowed, by the
    margins' tolerance (the compiled null-space test, ``pipeline.model.nullspace``; a corner it
    cannot decide decides nothing). No certificate of inside (of outside) can hold for such a
    box, so its LP is not tried: the verdicts are those of trying it (a quarter of IPAnema 1's
    boxes at depth 15 cost no LP). ``wrenches``: each box's own, the middle of its enclosure (for
    every robot within the tolerances, the nominal robot's: a corner it fails, the robust box fails)."""
    corners = np.where(np.arange(8)[:, None] >> np.arange(3) & 1, hi[:, None], lo[:, None]).reshape(-1, 3)
    structure = problem.spec.state(problem.robot, corners, angles).structure
    every = np.repeat(wrenches, 8, axis=0)
    slack = problem.margin_atol * problem.limits.scale
    found = [null_space_verdicts(structure, every, lower, upper).reshape(-1, 8)
             for lower, upper in ((box.lower - slack, box.upper + slack), (box.lower + slack, box.upper - slack))]
    return (found[0] == 0).any(axis=1), (found[1] == 1).any(axis=1)


def pave(problem: WorkspaceProblem, depth: int, seconds: float, compute: DictConfig,
         tolerances: Tolerances = NOMINAL, turns: list[Turn] | None = None) -> tuple[Paving, dict]:
    """Branch and prune from the robot's search box: the paving and how it ended (``turns``: a box
    of orientations about each of the problem's, :func:`_branch_and_prune`)."""
    robot = problem.robot
    axes = np.flatnonzero(robot.box_hi > robot.box_lo)
    boxes = np.concatenate([robot.box_lo, robot.box_hi])[None].astype(float)  # (B, 6): lo, hi
    found, verdict, level, at, ended = _branch_and_prune(
        problem, tolerances, boxes, lambda items: items, lambda items: _bisected(items, axes),
        lambda items: np.prod((items[:, 3:] - items[:, :3])[:, axes], axis=1), depth, seconds, compute, "of the search box",
        turns)
    return Paving(found[:, :3], found[:, 3:], verdict, level, at), ended


def certify_path(problem: WorkspaceProblem, points: np.ndarray, depth: int, seconds: float, compute: DictConfig,
                 tolerances: Tolerances = NOMINAL, motion: StraightMotion | None = None,
                 turns: list[Turn] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
    """The straight segments between the way-points ``points`` (P, 3) in pieces, each proven
    feasible at every point or at none through the box that holds it (its ends' bounding box,
    widened by a few ulps so that it holds the exact segment, not only the rounded ends), an
    undecided piece halved again: the pieces (N, 3) [segment, t0, t1], their verdicts, levels,
    outside orientations (:func:`certify`) and how it ended. At rest (``motion`` None) t is the
    share of the segment's length; with a
    ``motion`` (``pipeline.model.path.StraightMotion``: quintic or trapezoid) the platform moves rest
    to rest along each segment, t = tau / T is the share of its duration, and each piece is proven
    with every acceleration it has there (:func:`moving_wrenches` over the motion's range of
    accelerations along the segment)."""
    starts, ends = points[:-1], points[1:]

    def shape(segment, t):
        return t if motion is None else motion.share(segment, t)

    def bounds(items):
        segment = items[:, 0].astype(int)
        delta = ends[segment] - starts[segment]
        first = starts[segment] + shape(segment, items[:, 1])[:, None] * delta
        last = starts[segment] + shape(segment, items[:, 2])[:, None] * delta
        reach = np.maximum(np.abs(first), np.abs(last))  # the share and t * delta: a few ulps of delta (a dozen roundings)
        slack = np.finfo(float).eps * (8 * np.maximum(1.0, reach) if motion is None else 16 * (1.0 + reach + np.abs(delta)))
        box = np.concatenate([np.minimum(first, last) - slack, np.maximum(first, last) + slack], axis=1)
        if motion is None:
            return box
        low, high = motion.acceleration_range(segment, items[:, 1], items[:, 2])
        ends_of = np.stack([low[:, None] * delta, high[:, None] * delta], axis=1)  # a factor of delta: the segment's ends
        return np.concatenate([box, ends_of.reshape(len(items), 6)], axis=1)

    def halves(items):
        middle = items[:, 1] + (items[:, 2] - items[:, 1]) / 2
        return np.concatenate([np.column_stack([items[:, 0], items[:, 1], middle]),
                               np.column_stack([items[:, 0], middle, items[:, 2]])])

    spans = np.linalg.norm(ends - starts, axis=1) if motion is None else motion.durations
    pieces = np.column_stack([np.arange(len(starts)), np.zeros(len(starts)), np.ones(len(starts))]).astype(float)
    return _branch_and_prune(problem, tolerances, pieces, bounds, halves,
                             lambda items: (items[:, 2] - items[:, 1]) * spans[items[:, 0].astype(int)],
                             depth, seconds, compute, "of the path's length" if motion is None else "of the path's time",
                             turns)


def _branch_and_prune(problem: WorkspaceProblem, tolerances: Tolerances, items: np.ndarray, bounds, split, size,
                      depth: int, seconds: float, compute: DictConfig, what: str, turns: list[Turn] | None = None):
    """Certify ``items`` (boxes or pieces of a path: ``bounds(items)`` their boxes (N, 6) [lo, hi], or
    (N, 12) with the ends of a moving platform's acceleration in each, :func:`_verdicts`)
    level by level, splitting the undecided ones (``split``), until ``depth`` levels or ``seconds``:
    every item kept, its verdict, level and outside orientation (:func:`certify`), and how it
    ended. A level's boxes are certified in chunks (``pipeline.workspace.parallel``:
    ``compute.n_jobs`` workers); past ``seconds`` the chunks not yet certified stay undecided.
    ``size``: each item's volume or length, for the log.
    ``turns``: a box of orientations about each of ``problem.orientations`` (their centres), every
    orientation of which a box is proven inside at (outside: at its centre); None: those alone."""
    statics = []
    rest = replace(tolerances, anchors=0.0, attachments=0.0)  # what the enclosures hold alone; the rest is followed
    for k, angles in enumerate(problem.orientations):
        turn = None if turns is None else turns[k]
        at = None if turn is None else (turn[2], turn[2], turn[2], turn[3])  # the box's centre, enclosed alike
        nominal = box_statics(problem, angles, turn=at)
        statics.append((nominal, nominal, nominal, None) if tolerances.nominal and turn is None else
                       (nominal, box_statics(problem, angles, tolerances, turn), nominal if rest.nominal else
                        box_statics(problem, angles, rest, at), build_errors(problem, angles, tolerances, turn)))
    given = (problem, statics)
    kept: list[tuple] = []
    start, level = time.perf_counter(), 0
    total, decided = float(size(items).sum()), 0.0
    while True:
        verdict, at = np.full(len(items), UNDECIDED), np.full(len(items), -1)
        late = False
        for rows, part in iter_chunks(_verdicts, given, bounds(items), compute.n_jobs, name_of(compute.backend), CHUNK,
                                      compute.scheduler):
            verdict[rows], at[rows] = part["verdict"], part["at"]
            if time.perf_counter() - start > seconds:
                late = True  # the rest of the level stays undecided
                break
        done = verdict != UNDECIDED
        last = late or level >= depth or not (~done).any()
        keep = done | last
        kept.append((items[keep], verdict[keep], np.full(int(keep.sum()), level), at[keep]))
        decided += float(size(items[done]).sum())
        log.info("certified level %d: %d boxes, %.2f%% %s decided (%.1f s)", level, len(items),
                 100.0 * decided / total, what, time.perf_counter() - start)
        if last:
            stopped = "decided" if not (~done).any() else "time" if late else "depth"
            break
        items = split(items[~done])
        level += 1
    found, verdict, levels, at = (np.concatenate(parts) for parts in zip(*kept))
    return found, verdict, levels, at, {"stopped": stopped, "depth_reached": level, "seconds": time.perf_counter() - start}


def _verdicts(given: tuple, boxes: np.ndarray) -> dict[str, np.ndarray]:
    """The chunk task: the verdicts of boxes (B, 6) [lo, hi], or (B, 12) [lo, hi, the two ends of
    each box's linear acceleration] for a moving platform."""
    problem, statics = given
    moving = boxes[:, 6:].reshape(-1, 2, 3) if boxes.shape[1] > 6 else None
    verdict, at = certify(problem, statics, boxes[:, :3], boxes[:, 3:6], moving)
    return {"verdict": verdict, "at": at}


def outside_columns(at: np.ndarray, given: np.ndarray | None) -> dict:
    """With several orientations (a set, or boxes of them), the one each outside box or piece was
    proven infeasible at: ``outside_orientation`` (its number, from 1, in the order of
    ``given_angles``: the nominal first) and its angles ``outside_psi``, ``outside_theta``,
    ``outside_phi`` (rad, in ``orientation.convention``; a box of orientations' centre); NaN for the
    other boxes. No column with one orientation (the job's own)."""
    if given is None or len(given) < 2:
        return {}
    outside = at >= 0
    angles = np.where(outside[:, None], given[np.maximum(at, 0)], np.nan)
    return {"outside_orientation": np.where(outside, at + 1.0, np.nan),
            **{f"outside_{name}": angles[:, k] for k, name in enumerate(("psi", "theta", "phi"))}}


def _bisected(boxes: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Both halves of each box (B, 6) [lo, hi], cut across its longest side among ``axes``."""
    rows = np.arange(len(boxes))
    axis = axes[np.argmax((boxes[:, 3:] - boxes[:, :3])[:, axes], axis=1)]
    middle = boxes[rows, axis] + (boxes[rows, axis + 3] - boxes[rows, axis]) / 2
    lower, upper = boxes.copy(), boxes.copy()
    lower[rows, axis + 3] = middle
    upper[rows, axis] = middle
    return np.concatenate([lower, upper])


def paving_files(cfg: DictConfig, problem: WorkspaceProblem, files, motion: StraightMotion | None = None,
                 turns: list[Turn] | None = None, given: np.ndarray | None = None) -> dict:
    """A certified job's boxes.parquet and summary (module doc), or with ``certified.path`` its
    segments.parquet and summary (:func:`path_files`; ``motion``: the path's, None at rest;
    ``turns``: a box of orientations about each of the problem's, ``certified.orientations=box``;
    ``given``: the problem's orientations as the job gives them, ``pipeline.app.problem.given_angles``)."""
    tolerances = Tolerances(**{key: float(value) for key, value in cfg.robust.items()})
    if cfg.certified.path is not None:
        return path_files(cfg, problem, files, tolerances, motion, turns, given)
    paving, ended = pave(problem, int(cfg.certified.depth), float(cfg.certified.time), cfg.compute, tolerances, turns)
    robot = problem.robot
    axes = np.flatnonzero(robot.box_hi > robot.box_lo)
    volumes = paving.volumes(axes)
    total = float(np.prod((robot.box_hi - robot.box_lo)[axes]))
    shares = {VERDICTS[v]: float(volumes[paving.verdict == v].sum()) for v in VERDICTS}
    lost = {} if tolerances.nominal else _lost(problem, tolerances, paving, volumes, cfg.compute.n_jobs)
    if cfg.output.points:
        table = pd.DataFrame({**{f"lo_{a}": paving.lo[:, k] for k, a in enumerate("xyz")},
                              **{f"hi_{a}": paving.hi[:, k] for k, a in enumerate("xyz")},
                              "verdict": pd.Categorical([VERDICTS[v] for v in paving.verdict],
                                                        categories=list(VERDICTS.values())),
                              "depth": paving.depth, "volume": volumes, **outside_columns(paving.at, given),
                              **lost.pop("columns", {})})
        files.write("boxes", table)
    row = described_job(cfg, problem)
    counts = {name: int((paving.verdict == v).sum()) for v, name in VERDICTS.items()}
    row.update(
        n_points=len(paving.verdict), n_feasible=counts["inside"], feasible_pct=100.0 * shares["inside"] / total,
        volume_m3=shares["inside"], n_inside=counts["inside"], n_outside=counts["outside"], n_undecided=counts["undecided"],
        box_m3=total, inside_m3=shares["inside"], outside_m3=shares["outside"], undecided_m3=shares["undecided"],
        inside_pct=100.0 * shares["inside"] / total, undecided_pct=100.0 * shares["undecided"] / total, **ended,
        **{key: value for key, value in lost.items() if key != "columns"},
    )
    log.info("%s certified: %.4g to %.4g m^3 feasible (inside %.2f%%, undecided %.2f%% of the search box), %d boxes "
             "in %.1f s (%s)", robot.name, shares["inside"], shares["inside"] + shares["undecided"], row["inside_pct"],
             row["undecided_pct"], len(paving.verdict), ended["seconds"], ended["stopped"])
    return row


def _lost(problem: WorkspaceProblem, tolerances: Tolerances, paving: Paving, volumes: np.ndarray, n_jobs: int) -> dict:
    """A robust paving's undecided boxes whose centre one build error breaks (``tolerances.culprits``):
    boxes.parquet's ``lost_to`` (the error's name) and ``lost_at`` (the share of its tolerance that
    breaks the centre), and the summary's ``lost_named_m3`` (their volume: certainly not in the
    robust workspace), ``lost_to_top`` and ``lost_to_top_m3`` (the error that names most of it); the
    errors tried on ``compute.n_jobs`` threads."""
    from joblib import effective_n_jobs

    undecided = np.flatnonzero(paving.verdict == UNDECIDED)
    started = time.perf_counter()
    threads = min(effective_n_jobs(n_jobs), os.cpu_count() or 1)  # compute.n_jobs, at most this machine's cores
    names, at = culprits(problem, tolerances, centres(paving.lo[undecided], paving.hi[undecided]), threads)
    lost_to, lost_at = np.full(len(volumes), None, dtype=object), np.full(len(volumes), np.nan)
    lost_to[undecided], lost_at[undecided] = names, at
    named = np.array([name is not None for name in lost_to])
    by_error = pd.Series(volumes[named]).groupby(lost_to[named]).sum().sort_values(ascending=False, kind="stable")
    top = by_error.index[0] if len(by_error) else None
    row = {"lost_named_m3": float(volumes[named].sum()), "lost_to_top": top,
           "lost_to_top_m3": float(by_error.iloc[0]) if len(by_error) else 0.0}
    log.info("of the undecided boxes, %.4g m^3 have a centre one build error within the tolerances breaks (certainly "
             "lost), most to %s (%.4g m^3); %.1f s", row["lost_named_m3"], top or "none", row["lost_to_top_m3"],
             time.perf_counter() - started)
    return {**row, "columns": {"lost_to": pd.Categorical(lost_to, categories=list(by_error.index)), "lost_at": lost_at}}


def path_files(cfg: DictConfig, problem: WorkspaceProblem, files, tolerances: Tolerances,
               motion: StraightMotion | None, turns: list[Turn] | None = None, given: np.ndarray | None = None) -> dict:
    """A certified path's segments.parquet (one row per piece: its segment, its parameters t0, t1
    and ends, where along the path it starts, its length, verdict and level) and summary: the path's
    length, the shares of it proven feasible, infeasible and undecided, ``path_certified`` (every
    point proven) and ``first_outside_m`` (where along the path the first piece proven infeasible
    starts; NaN when none); with several orientations, where a piece is outside, at which
    (:func:`outside_columns`)."""
    points = np.asarray(OmegaConf.to_container(cfg.certified.path), dtype=float)
    pieces, verdict, level, at, ended = certify_path(problem, points, int(cfg.certified.depth), float(cfg.certified.time),
                                                     cfg.compute, tolerances, motion, turns)
    order = np.lexsort((pieces[:, 1], pieces[:, 0]))  # along the path
    pieces, verdict, level, at = pieces[order], verdict[order], level[order], at[order]
    segment = pieces[:, 0].astype(int)
    starts, ends = points[:-1], points[1:]
    lengths = np.linalg.norm(ends - starts, axis=1)
    before = np.concatenate([[0.0], np.cumsum(lengths)])[segment]
    begin, end = (pieces[:, 1], pieces[:, 2]) if motion is None else (motion.share(segment, pieces[:, 1]),
                                                                      motion.share(segment, pieces[:, 2]))
    first = starts[segment] + begin[:, None] * (ends[segment] - starts[segment])  # shares of the segment's length
    last = starts[segment] + end[:, None] * (ends[segment] - starts[segment])
    length = (end - begin) * lengths[segment]
    from_m = before + begin * lengths[segment]
    timing = {}
    if motion is not None:  # when the platform passes each piece
        durations = motion.durations
        earlier = np.concatenate([[0.0], np.cumsum(durations)])[segment]
        timing = {"from_s": earlier + pieces[:, 1] * durations[segment], "to_s": earlier + pieces[:, 2] * durations[segment]}
    if cfg.output.points:
        files.write("segments", pd.DataFrame({
            "segment": segment + 1, "t0": pieces[:, 1], "t1": pieces[:, 2],
            **{f"start_{a}": first[:, k] for k, a in enumerate("xyz")}, **{f"end_{a}": last[:, k] for k, a in enumerate("xyz")},
            "from_m": from_m, "length_m": length, **timing,
            "verdict": pd.Categorical([VERDICTS[v] for v in verdict], categories=list(VERDICTS.values())), "depth": level,
            **outside_columns(at, given)}))
    total = float(lengths.sum())
    shares = {VERDICTS[v]: float(length[verdict == v].sum()) for v in VERDICTS}
    outside = np.flatnonzero(verdict == OUTSIDE)
    row = described_job(cfg, problem)
    row.update(
        n_points=len(verdict), n_feasible=int((verdict == INSIDE).sum()), feasible_pct=100.0 * shares["inside"] / total,
        volume_m3=float("nan"), path_m=total, inside_m=shares["inside"], outside_m=shares["outside"],
        undecided_m=shares["undecided"], inside_pct=100.0 * shares["inside"] / total,
        outside_pct=100.0 * shares["outside"] / total, undecided_pct=100.0 * shares["undecided"] / total,
        path_certified=bool((verdict == INSIDE).all()),
        first_outside_m=float(from_m[outside[0]]) if len(outside) else float("nan"), **ended,
    )
    if motion is not None:
        row.update(duration_s=float(durations.sum()),
                   first_outside_s=float(timing["from_s"][outside[0]]) if len(outside) else float("nan"))
    how = "at rest" if motion is None else f"moving ({motion.law}, {row['duration_s']:.4g} s)"
    log.info("%s certified path: %.4g of %.4g m proven feasible %s (%.2f%%), %.4g m infeasible%s, %.4g m undecided; "
             "%d pieces in %.1f s (%s)", problem.robot.name, shares["inside"], total, how, row["inside_pct"], shares["outside"],
             f" from {row['first_outside_m']:.4g} m" if len(outside) else "", shares["undecided"], len(verdict),
             ended["seconds"], ended["stopped"])
    return row

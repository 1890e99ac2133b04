"""Certified clearances over boxes of positions (issue 57): the interference criteria's proofs.

Over a box B of platform positions at one orientation (its enclosures: the anchors a_i, the
attachment points' offsets R b_i and the platform's vertices R v_k, each an interval, wider for a
robot within build tolerances), every cable is the segment from a_i to p + R b_i, p in B. All
bounds are computed in :mod:`pipeline.model.intervals` (outward rounding); the floats chosen at
the box's centre (the closest points of two cables) need no rigour, the interval tests check them.

- **Two cables apart** (:func:`pair_verdicts`): for any vector n, the distance between two
  segments is at least (min over the second's points of n . y - max over the first's of n . x) / |n|,
  and both extremes are at segment ends (the points are convex combinations of them); with n the
  direction between the centre's closest points the bound is the distance there. Over B the four
  pairs of ends are bounded with p's shared part cancelled (two attachment points differ by
  R b_j - R b_i whatever p). Inside when it reaches r_i + r_j for every pair. Every pose of B
  collides when, for one pair, the two points at the centre's closest parameters, each an
  enclosure over B (their p parts combined, (s - t) p), are nearer than (1 - atol)(r_i + r_j):
  the distance is at most theirs.
- **A cable or the platform from a half-space** (:func:`plane_verdicts`): the clearance of a
  segment or a convex body from the half-space behind the plane through q with normal n is
  min over its vertices of n . (x - q) (``clearance.plane_clearance``), linear in each vertex:
  its enclosure over B is exact up to rounding. Inside when every cable keeps r_i and the platform
  0; outside when one body's upper bound is below -atol times the robot's extent (the exact
  test's tolerance).
- **A cable or the platform from an axis-aligned box** (:func:`box_verdicts`): the exact test's
  clearance is the separating-axis gap (``clearance.box_separation``), the largest over its axes,
  so at least the gap along any one of the box's own axes e_k, max(lo_k - max x_k, min x_k - hi_k)
  over the body's vertices (a segment's two ends), linear in each vertex. Inside when every cable
  keeps r_i along one axis and the platform 0 along one (a sufficient condition: an axis crossed
  with the cable is not tried). Outside when a cable's end lies deeper in the box than atol times
  the robot's extent at every position: a ball of that depth about it is in the box, so every
  axis's projections overlap by that depth and the gap is below minus it.
- **A cable out of the platform's body** (:func:`face_verdicts`): cable i is clear of the convex
  body exactly when n . t >= 0 for some face holding its attachment, n = R n_f the face's normal
  and t = a_i - p - R b_i the cable's vector from the attachment (``criteria.interference
  .cable_platform``). n . t is affine in p: its enclosure over B is exact up to rounding. Inside
  when every cable has such a face over all of B (one face for the whole box: a sufficient
  condition); outside when some cable has n . t < -atol |t| at every position for every face
  holding it (the exact test's margin is that sine).
"""

from __future__ import annotations

import numpy as np

from pipeline.model.certificates import INSIDE, OUTSIDE, UNDECIDED
from pipeline.model.clearance import closest_parameters
from pipeline.model.intervals import Interval, down, up


def _dot(intervals: Interval, vectors: np.ndarray) -> Interval:
    """intervals (..., 3) . vectors (..., 3), rounded outward."""
    return (intervals * Interval.point(vectors)).sum(axis=-1)


def _norm_upper(values: Interval) -> np.ndarray:
    return values.square().sum(axis=-1).sqrt().hi


def pair_verdicts(anchors: Interval, arms: Interval, lo: np.ndarray, hi: np.ndarray, centre: np.ndarray,
                  pairs: tuple[np.ndarray, np.ndarray], reach: np.ndarray, atol: float,
                  collide: tuple[Interval, Interval] | None = None) -> np.ndarray:
    """(N,) whether every two cables of ``pairs`` (i, j) stay ``reach`` (P,) apart (r_i + r_j, m)
    at every position of each box [lo, hi] (N, 3): INSIDE, OUTSIDE (one pair nearer at every
    position, by ``collide``'s enclosures (anchors, arms) when given: a nominal robot's) or
    UNDECIDED (module doc). ``anchors``, ``arms`` (m, 3): enclosures of a_i and R b_i;
    ``centre`` (N, 3): a position of each box."""
    i, j = pairs
    box = Interval(lo, hi)[:, None, :]  # (N, 1, 3)
    verdict = np.full(len(lo), UNDECIDED)
    if not len(i):
        return np.full(len(lo), INSIDE)
    starts = (anchors.lo + anchors.hi) / 2  # floats at the centre, (m, 3)
    attached = centre[:, None, :] + ((arms.lo + arms.hi) / 2)[None]  # (N, m, 3)
    gap, s, t = closest_parameters(starts[i][None], attached[:, i] - starts[i][None], starts[j][None],
                                   attached[:, j] - starts[j][None])
    first = starts[i][None] + s[..., None] * (attached[:, i] - starts[i][None])
    second = starts[j][None] + t[..., None] * (attached[:, j] - starts[j][None])
    normal = second - first  # (N, P, 3)
    ends = (arms[j] - arms[i],  # p + R b_j - (p + R b_i): p cancels
            box + arms[j] - anchors[i], anchors[j] - box - arms[i], anchors[j] - anchors[i])
    separation = np.min([_dot(end, normal).lo for end in ends], axis=0)  # (N, P): n . (y - x) >= this
    needed = (Interval.point(reach) * Interval.point(_norm_upper(Interval.point(normal)))).hi  # (r_i + r_j) |n|
    inside = (separation >= needed).all(axis=1)
    near_anchors, near_arms = collide or (anchors, arms)
    s_, t_ = Interval.point(s)[..., None], Interval.point(t)[..., None]
    one = Interval.point(1.0)
    between = ((one - s_) * near_anchors[i] + s_ * near_arms[i] - (one - t_) * near_anchors[j] - t_ * near_arms[j]
               + (s_ - t_) * box)  # x_i(s) - y_j(t) over the box, (N, P, 3)
    outside = (_norm_upper(between) < down(down(1.0 - atol) * reach)).any(axis=1)
    verdict[inside] = INSIDE
    verdict[outside & ~inside] = OUTSIDE
    return verdict


def plane_verdicts(anchors: Interval, arms: Interval, body: Interval, lo: np.ndarray, hi: np.ndarray,
                   planes: list[tuple[np.ndarray, np.ndarray]], radii: np.ndarray, allowance: float,
                   nominal: tuple[Interval, Interval, Interval] | None = None) -> np.ndarray:
    """(N,) whether every cable keeps its radius ``radii`` (m,) and the platform (its vertices'
    offsets ``body`` (k, 3): R v_k) 0 from every half-space behind ``planes`` (point, normal) at
    every position of each box: INSIDE, OUTSIDE (some body deeper than ``allowance`` at every
    position, by ``nominal``'s enclosures when given) or UNDECIDED."""
    box = Interval(lo, hi)[:, None, :]
    inside = np.ones(len(lo), dtype=bool)
    outside = np.zeros(len(lo), dtype=bool)
    for point, normal in planes:
        def clearances(a: Interval, w: Interval, v: Interval) -> tuple[Interval, Interval, Interval]:
            return _dot(a - point, normal), _dot(box + w - point, normal), _dot(box + v - point, normal)

        fixed, ends, platform = clearances(anchors, arms, body)  # (m,), (N, m), (N, k)
        cables = down(np.minimum(ends.lo, fixed.lo) - radii)  # each cable's clearance, lower bound
        inside &= (cables >= 0).all(axis=1) & (platform.lo.min(axis=1) >= 0)
        fixed, ends, platform = clearances(*(nominal or (anchors, arms, body)))
        cables = up(np.minimum(ends.hi, fixed.hi) - radii)  # upper bound
        outside |= np.minimum(cables.min(axis=1), platform.hi.min(axis=1)) < -allowance
    return np.where(inside, INSIDE, np.where(outside, OUTSIDE, UNDECIDED))


def box_verdicts(anchors: Interval, arms: Interval, body: Interval, lo: np.ndarray, hi: np.ndarray, centre: np.ndarray,
                 boxes: list[tuple[np.ndarray, np.ndarray]], radii: np.ndarray, allowance: float,
                 nominal: tuple[Interval, Interval, Interval] | None = None) -> np.ndarray:
    """(N,) whether every cable keeps its radius ``radii`` (m,) and the platform (its vertices'
    offsets ``body`` (k, 3): R v_k) 0 from every axis-aligned box [low, high] of ``boxes`` at every
    position of each box of positions (``centre`` (N, 3): a point of each; module doc): INSIDE,
    OUTSIDE (a cable's end deeper in an obstacle than ``allowance`` at every position, by
    ``nominal``'s enclosures when given) or UNDECIDED."""
    box = Interval(lo, hi)[:, None, :]
    inside = np.ones(len(lo), dtype=bool)
    outside = np.zeros(len(lo), dtype=bool)

    def gap(lowest: np.ndarray, highest: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """A lower bound of the largest gap along the box's axes of bodies spanning [lowest, highest] (..., 3)."""
        return np.maximum(down(low - highest), down(lowest - high)).max(axis=-1)

    for low, high in boxes:
        ends, platform = box + arms, box + body  # (N, m, 3), (N, k, 3)
        cables = gap(np.minimum(anchors.lo, ends.lo), np.maximum(anchors.hi, ends.hi), low, high)  # (N, m)
        apart = (cables >= radii) | ((radii == 0) & (_crossed_gap(anchors, ends, centre, arms, low, high) > 0))
        inside &= apart.all(axis=1) & (gap(platform.lo.min(axis=1), platform.hi.max(axis=1), low, high) >= 0)
        fixed, offsets = (nominal or (anchors, arms, body))[:2]
        for end in (fixed[None], box + offsets):  # each cable's anchor (1, m, 3) and attachment point (N, m, 3)
            depth = np.minimum(down(end.lo - low), down(high - end.hi)).min(axis=-1)  # how deep in, a lower bound
            outside |= (depth > allowance).any(axis=1)
    return np.where(inside, INSIDE, np.where(outside, OUTSIDE, UNDECIDED))


def _crossed_gap(anchors: Interval, ends: Interval, centre: np.ndarray, arms: Interval, low: np.ndarray,
                 high: np.ndarray) -> np.ndarray:
    """(N, m) a lower bound over each box of positions of the gap between each cable and the box
    [low, high] along one fixed axis: the separating axis of the centre's cable (the box's axes
    and the cable's direction crossed with each) that parts them most there. A positive bound
    proves them apart at every position, so that the separating-axis test of the exact criterion
    finds a positive gap too (it decides a segment and a box); it says nothing of a cable's
    radius (that gap is along the centre's axis, not one the exact test tries)."""
    direction = centre[:, None, :] + (arms.lo + arms.hi) / 2 - (anchors.lo + anchors.hi) / 2  # (N, m, 3)
    axes = np.concatenate([np.broadcast_to(np.eye(3), (*direction.shape[:2], 3, 3)),
                           np.cross(direction[:, :, None, :], np.eye(3))], axis=2)  # (N, m, 6, 3)
    middle, half = (high + low) / 2, (high - low) / 2
    start, end = (anchors.lo + anchors.hi) / 2, centre[:, None, :] + (arms.lo + arms.hi) / 2
    seen = np.stack([np.einsum("nmad,md->nma", axes, start), np.einsum("nmad,nmd->nma", axes, end)])  # (2, N, m, 6)
    reach = np.abs(axes) @ half
    score = np.maximum(seen.min(axis=0) - (axes @ middle + reach), (axes @ middle - reach) - seen.max(axis=0))
    score /= np.maximum(np.linalg.norm(axes, axis=-1), 1e-300)
    axis = np.take_along_axis(axes, score.argmax(axis=2)[..., None, None], axis=2)[:, :, 0]  # (N, m, 3), doubles
    along = Interval.point(axis)
    fixed = (anchors[None] * along).sum(axis=-1)  # (N, m)
    moving = (ends * along).sum(axis=-1)
    centre_of = (Interval.point(middle) * along).sum(axis=-1)
    spread = (Interval.point(half) * Interval.point(np.abs(axis))).sum(axis=-1)
    upper, lower = centre_of + spread, centre_of - spread
    return np.maximum(down(np.minimum(fixed.lo, moving.lo) - upper.hi), down(lower.lo - np.maximum(fixed.hi, moving.hi)))


def face_verdicts(anchors: Interval, arms: Interval, normals: Interval, faces: np.ndarray, lo: np.ndarray,
                  hi: np.ndarray, atol: float, nominal: tuple[Interval, Interval, Interval] | None = None) -> np.ndarray:
    """(N,) whether every cable leaves the platform's body at every position of each box (module
    doc): ``anchors``, ``arms`` (m, 3) the enclosures of a_i and R b_i, ``normals`` (f, 3) of the
    faces' R n_f, ``faces`` (m, f) which faces hold each attachment; INSIDE, OUTSIDE (some cable
    into the body at every position, by ``nominal``'s enclosures when given) or UNDECIDED."""
    box = Interval(lo, hi)[:, None, :]  # (N, 1, 3)

    def sides(a: Interval, w: Interval, n: Interval) -> tuple[Interval, Interval]:
        toward = a[None] - box - w[None]  # (N, m, 3): t = a_i - p - R b_i
        return (toward[:, :, None, :] * n[None, None]).sum(axis=-1), toward  # n_f . t, (N, m, f)

    side, _ = sides(anchors, arms, normals)
    inside = (np.where(faces[None], side.lo, -np.inf).max(axis=2) >= 0).all(axis=1)
    side, toward = sides(*(nominal or (anchors, arms, normals)))
    reach = up(atol * _norm_upper(toward))  # atol |t| (N, m), rounded up
    outside = (np.where(faces[None], side.hi, -np.inf).max(axis=2) < -reach).any(axis=1)
    return np.where(inside, INSIDE, np.where(outside, OUTSIDE, UNDECIDED))

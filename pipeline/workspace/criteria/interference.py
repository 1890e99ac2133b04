"""Interference criteria (docs/model.md section 5): cables that must not touch each other
(``cable_cable``), enter the platform's body (``cable_platform``) or touch an obstacle of the
cell, nor the platform either (``cable_obstacle``). They read only the pose's geometry, so the
numpy and the compiled kernels evaluate them with the same code (``pipeline.workspace.kernel``)."""

from __future__ import annotations

import numpy as np

from pipeline.model.clearance import segment_distance
from pipeline.model.certificates import OUTSIDE
from pipeline.model.clearance_bounds import box_verdicts, face_verdicts, pair_verdicts, plane_verdicts


def pair_clearances(state) -> np.ndarray:
    """(n, pairs) d_ij / (r_i + r_j) - 1 over the pairs
    :attr:`pipeline.model.geometry.CableRobot.cable_pairs` (pairs sharing an anchor or an
    attachment point meet there by design), d_ij the distance of the straight segments from a_i
    (or where the cable leaves its pulley, ``exits``) to p + R b_i
    (:func:`pipeline.model.clearance.segment_distance`), r the radii of ``robot.cable_diameter``:
    0 when the cables touch, -1 when their axes cross."""
    robot = state.robot
    i, j = robot.cable_pairs
    starts, ends = state.exits, state.attachment_points
    distance = segment_distance(starts[:, i], ends[:, i] - starts[:, i], starts[:, j], ends[:, j] - starts[:, j])
    return distance / (robot.cable_radii[i] + robot.cable_radii[j]) - 1.0


def cable_cable(state, limits) -> np.ndarray:
    """Every two cables at least r_i + r_j apart: margin min(1, min over the pairs of
    :func:`pair_clearances`). The closest pair of each pose goes to ``state.closest_pair`` (an
    index into ``cable_pairs``, column ``closest_cables``)."""
    relative = pair_clearances(state)
    state.closest_pair = relative.argmin(axis=1).astype(np.int16)
    return np.minimum(1.0, relative.min(axis=1))


def cable_platform(state, limits) -> np.ndarray:
    """No cable enters the platform's body (``robot.platform.shape``, convex, every attachment
    b_i on its surface). A segment that leaves a point of a convex body's surface either enters
    the body at once or never does, so cable i is clear exactly when its direction u_i (from b_i
    towards its anchor, platform frame) points out of some face f that holds b_i: n_f . u_i >= 0.
    Margin min_i max_f n_f . u_i, the sine of the angle between the cable and the face it
    clears best: 0 for a cable along a face, -1 for one that leaves straight into the body."""
    robot = state.robot
    toward = state.exits - state.attachment_points  # fixed frame: towards the anchor or the pulley
    local = toward @ state.rotation  # R^T u for each row u: the platform's frame
    unit = local / np.linalg.norm(local, axis=2, keepdims=True).clip(min=np.finfo(float).tiny)
    sines = unit @ robot.platform_shape.normals.T  # (n, m, f)
    return np.where(robot.attachment_faces[None], sines, -np.inf).max(axis=2).min(axis=1)


def cable_obstacle(state, limits) -> np.ndarray:
    """No cable (a segment of radius r_i, 0 without ``robot.cable_diameter``) and not the
    platform (its shape, else the hull of its attachments) touches an obstacle (``obstacles``):
    margin min(1, least clearance / the robot's extent), the clearance exact from a plane's
    half-space and the separating-axis gap from a box (``pipeline.model.clearance``). The
    closest (obstacle, body) of each pose goes to ``state.closest_obstacle`` (an index into
    :func:`obstacle_pairs`, column ``closest_obstacle``)."""
    robot = state.robot
    cables = np.stack([state.exits, state.attachment_points], axis=2)  # (n, m, 2, 3)
    along = state.attachment_points - state.exits
    length = np.linalg.norm(along, axis=2, keepdims=True)
    along = np.divide(along, length, out=np.zeros_like(along), where=length > 0)[:, :, None, :]
    none = np.zeros((*along.shape[:2], 0, 3))
    body = robot.platform_body
    turn = np.swapaxes(state.rotation, -1, -2)
    vertices = state.positions[:, None, :] + body.vertices @ turn
    normals = np.broadcast_to(np.concatenate([body.normals, body.plane]) @ turn,
                              (len(vertices), len(body.normals) + len(body.plane), 3))
    edges = np.broadcast_to(body.edges @ turn, (len(vertices), len(body.edges), 3))
    radii = np.zeros(robot.n_cables) if robot.cable_radii is None else robot.cable_radii
    clearance = np.concatenate([np.column_stack([obstacle.clearance(cables, none, along) - radii,
                                                 obstacle.clearance(vertices, normals, edges)])
                                for obstacle in robot.obstacles], axis=1)  # (n, obstacles x (m + 1))
    state.closest_obstacle = clearance.argmin(axis=1).astype(np.int16)
    return np.minimum(1.0, clearance.min(axis=1) / robot.extent)


def obstacle_pairs(robot) -> list[str]:
    """The names of :func:`cable_obstacle`'s (obstacle, body) pairs, in its order."""
    return [f"{obstacle.name}: {body}" for obstacle in robot.obstacles for body in (*robot.cable_names, "platform")]


def cable_cable_boxes(robot, within, nominal, lo, hi, centre, atol) -> np.ndarray:
    """:func:`cable_cable` proven on boxes of positions (``clearance_bounds.pair_verdicts``)."""
    i, j = robot.cable_pairs
    return pair_verdicts(within.anchors, within.arms, lo, hi, centre, (i, j), robot.cable_radii[i] + robot.cable_radii[j],
                         atol, collide=(nominal.anchors, nominal.arms))


def cable_platform_boxes(robot, within, nominal, lo, hi, centre, atol) -> np.ndarray:
    """:func:`cable_platform` proven on boxes of positions (``clearance_bounds.face_verdicts``)."""
    return face_verdicts(within.anchors, within.arms, within.normals, robot.attachment_faces, lo, hi, atol,
                         nominal=(nominal.anchors, nominal.arms, nominal.normals))


def cable_obstacle_boxes(robot, within, nominal, lo, hi, centre, atol) -> np.ndarray:
    """:func:`cable_obstacle` proven on boxes of positions, for half-space obstacles
    (``clearance_bounds.plane_verdicts``) and axis-aligned boxes (``box_verdicts``)."""
    radii = np.zeros(robot.n_cables) if robot.cable_radii is None else robot.cable_radii
    planes = [(obstacle.point, obstacle.normal) for obstacle in robot.obstacles if obstacle.normal is not None]
    boxes = [(obstacle.lo, obstacle.hi) for obstacle in robot.obstacles if obstacle.normal is None]
    given = (within.anchors, within.arms, within.body, lo, hi)
    enclosures, allowance = (nominal.anchors, nominal.arms, nominal.body), atol * robot.extent
    found = [plane_verdicts(*given, planes, radii, allowance, nominal=enclosures),
             box_verdicts(*given, centre, boxes, radii, allowance, nominal=enclosures)]
    return np.where((found[0] == OUTSIDE) | (found[1] == OUTSIDE), OUTSIDE, np.minimum(*found))

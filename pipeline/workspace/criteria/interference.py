"""Interference criteria: cables that must not touch each other (docs/model.md, "Interference").
They read only the pose's geometry, so the numpy and the compiled kernels evaluate them with
the same code (``pipeline.workspace.kernel``)."""

from __future__ import annotations

import numpy as np

from pipeline.model.clearance import segment_distance


def cable_cable(state, limits) -> np.ndarray:
    """Every two cables i, j (straight segments from a_i to p + R b_i) at least r_i + r_j apart,
    the radii of ``robot.cable_diameter``: margin min(1, d_ij / (r_i + r_j) - 1) over the pairs
    :attr:`pipeline.model.geometry.CableRobot.cable_pairs` (pairs sharing an anchor or an
    attachment point meet there by design), d_ij the segments' distance
    (:func:`pipeline.model.clearance.segment_distance`): 0 when the cables touch, -1 when their
    axes cross. The closest pair of each pose goes to ``state.closest_pair`` (an index into
    ``cable_pairs``, column ``closest_cables``)."""
    robot = state.robot
    i, j = robot.cable_pairs
    anchors, ends = robot.anchors, state.attachment_points
    distance = segment_distance(anchors[i], ends[:, i] - anchors[i], anchors[j], ends[:, j] - anchors[j])
    relative = distance / (robot.cable_radii[i] + robot.cable_radii[j]) - 1.0
    state.closest_pair = relative.argmin(axis=1).astype(np.int16)
    return np.minimum(1.0, relative.min(axis=1))

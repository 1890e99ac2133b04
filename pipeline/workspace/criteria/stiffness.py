"""The stiffness criterion (issue 54 item 2): elastic cables (``robot.cable_ea``) must hold the
platform stiff enough, its least translational stiffness at least ``criteria.stiffness.translational``
(N/m) and its least rotational stiffness at least ``criteria.stiffness.rotational`` (N m/rad), from
K = K_cables + K_geometric (``pipeline.model.stiffness``) at the tensions the tension model gives:
the minimum-norm ones (``pinv``) or those the ``feasible`` model writes (``tension.distribution``),
the least over the required wrenches."""

from __future__ import annotations

import numpy as np

from pipeline.model.stiffness import axial_rates, least_stiffness, stiffness_matrices
from pipeline.workspace.criteria.forces import feasible_model, written_tensions

ROTATIONS = (3, 4, 5)  # the freedoms' indices of the rotations


def required(value) -> str | None:
    """The rule of both keys: a stiffness the platform must at least have."""
    return None if 0 < value < np.inf else "must be > 0 and finite (N/m, N m/rad)"


def stiffness(state, limits, translational: float, rotational: float) -> np.ndarray:
    """Margin min(1, lambda_t / translational - 1, lambda_r / rotational - 1), the lambdas the least
    eigenvalues of the symmetric parts of K's blocks over the robot's freedoms (a point platform:
    the translational only), the least over the required wrenches; -1 where the model gives no
    tensions. The lambdas go to ``state.stiffness_translational`` and ``stiffness_rotational``."""
    robot = state.robot
    if feasible_model(state):
        tensions = state.forces_of(written_tensions(state, limits))
    else:
        tensions = state.tensions_over_set if state.ranges_over_a_set else state.tensions[:, None, :]
    stretched = state.cable_lengths + robot.winch_lengths
    least = [np.full(len(stretched), np.inf), np.full(len(stretched), np.inf)]
    for k in range(tensions.shape[1]):
        rates = axial_rates(robot.cable_ea, stretched, tensions[:, k, :])
        matrix = stiffness_matrices(state.unit, state.arms, state.lengths, tensions[:, k, :], rates)
        for found, value in zip(least, least_stiffness(matrix, robot.dofs)):
            np.minimum(found, value, out=found)  # NaN (no tensions) stays NaN
    state.stiffness_translational, state.stiffness_rotational = least
    ratios = [least[0] / translational - 1.0]
    if any(dof in ROTATIONS for dof in robot.dofs) and robot.attachments.any():
        ratios.append(least[1] / rotational - 1.0)
    margin = np.minimum(1.0, np.min(ratios, axis=0))
    return np.where(np.isnan(margin), -1.0, margin)

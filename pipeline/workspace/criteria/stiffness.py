"""The stiffness criterion (issue 54 item 2): elastic cables (``robot.cable_ea``) must hold the
platform stiff enough, its least translational stiffness at least ``criteria.stiffness.translational``
(N/m), its least rotational stiffness at least ``criteria.stiffness.rotational`` (N m/rad) and its
lowest natural frequency at least ``criteria.stiffness.frequency`` (Hz; 0: a key not required),
from K = K_cables + K_geometric (``pipeline.model.stiffness``) at the tensions the tension model
gives: the minimum-norm ones (``pinv``) or those the ``feasible`` model writes
(``tension.distribution``), the least over the required wrenches. The frequency reads the moving
mass (the platform's and the payload's, ``load``) and the platform's inertia."""

from __future__ import annotations

import numpy as np

from pipeline.model.stiffness import (axial_rates, least_stiffness, lowest_frequency, spatial_inertia,
                                      stiffness_matrices)
from pipeline.workspace.criteria.forces import feasible_model, written_tensions

ROTATIONS = (3, 4, 5)  # the freedoms' indices of the rotations


def required(value) -> str | None:
    """The rule of the keys: what the platform must at least have (0: not required)."""
    return None if 0 <= value < np.inf else "must be >= 0 and finite (N/m, N m/rad, Hz; 0: not required)"


def turns(robot) -> bool:
    """Whether the platform's rotations are freedoms its cables hold (moment arms and rotations)."""
    return any(dof in ROTATIONS for dof in robot.dofs) and bool(robot.attachments.any())


def refuses(spec, robot, keys: dict) -> str | None:
    """Why a problem cannot evaluate a required frequency: no moving mass, or a platform that
    turns without its inertia."""
    if keys["frequency"] > 0 and not spec.load.mass > 0:
        return "frequency needs a moving mass (robot.platform.mass or load.mass)"
    if keys["frequency"] > 0 and turns(robot) and spec.load.inertia is None:
        return "frequency needs the platform's inertia (robot.platform.inertia)"
    if keys["frequency"] > 0 and turns(robot):
        rows = list(robot.dofs)
        mass = spatial_inertia(spec.load.mass, spec.load.com, spec.load.inertia)[np.ix_(rows, rows)]
        if not np.linalg.eigvalsh(mass)[0] > 0:
            return "frequency: the platform's inertia (robot.platform.inertia) gives no inertia about a freedom it turns about"
    return None


def _mass_matrix(state) -> np.ndarray:
    """M about the reference point at the state's rotation(s); a point mass without the inertia."""
    load, rotation = state.spec.load, state.rotation
    inertia = np.zeros((3, 3)) if load.inertia is None else load.inertia
    return spatial_inertia(load.mass, load.com @ np.swapaxes(rotation, -1, -2),
                           rotation @ inertia @ np.swapaxes(rotation, -1, -2))


def stiffness(state, limits, translational: float, rotational: float, frequency: float) -> np.ndarray:
    """Margin min(1, lambda_t / translational - 1, lambda_r / rotational - 1, f / frequency - 1)
    over the keys required, the lambdas the least eigenvalues of the symmetric parts of K's blocks
    over the robot's freedoms (a point platform: the translational only), f the lowest natural
    frequency, each the least over the required wrenches; -1 where the model gives no tensions.
    The values go to ``state.stiffness_translational``, ``stiffness_rotational``,
    ``stiffness_weakest`` (the direction of the least translational stiffness) and ``frequency``
    (when the problem has a mass and, if it turns, an inertia)."""
    robot = state.robot
    if feasible_model(state):
        tensions = state.forces_of(written_tensions(state, limits))
    else:
        tensions = state.tensions_over_set if state.ranges_over_a_set else state.tensions[:, None, :]
    stretched = state.cable_lengths + robot.winch_lengths
    load = state.spec.load
    moving = load.mass > 0 and (load.inertia is not None or not turns(robot))
    mass = _mass_matrix(state) if moving else None
    least = [np.full(len(stretched), np.inf) for _ in range(3)]
    weakest = np.full((len(stretched), 3), np.nan)
    for k in range(tensions.shape[1]):
        rates = axial_rates(robot.cable_ea, stretched, tensions[:, k, :])
        matrix = stiffness_matrices(state.unit, state.arms, state.lengths, tensions[:, k, :], rates)
        along, about, direction = least_stiffness(matrix, robot.dofs)
        lower = ~(along >= least[0])  # this wrench's translational stiffness is the least so far (or NaN)
        weakest[lower] = direction[lower]
        found = [along, about]
        found.append(lowest_frequency(matrix, mass, robot.dofs) if moving else np.full(len(stretched), np.nan))
        for kept, value in zip(least, found):
            np.minimum(kept, value, out=kept)  # NaN (no tensions) stays NaN
    state.stiffness_translational, state.stiffness_rotational = least[:2]
    state.stiffness_weakest = weakest
    state.frequency = least[2] if moving else None
    ratios = [np.full(len(stretched), 1.0)]
    for value, wanted in zip(least, (translational, rotational if turns(robot) else 0.0, frequency)):
        if wanted > 0:
            ratios.append(value / wanted - 1.0)
    margin = np.minimum(1.0, np.min(ratios, axis=0))
    return np.where(np.isnan(margin), -1.0, margin)

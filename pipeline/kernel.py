"""The workspace kernel: a pure function from a chunk of positions to per-criterion margins."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.actuators import ActuatorModel
from pipeline.criteria import CRITERIA
from pipeline.dynamics import MotionSpec, PoseDynamics
from pipeline.geometry import CableRobot


@dataclass(frozen=True)
class WorkspaceProblem:
    """Everything a worker needs, as plain arrays and numbers (no config objects)."""

    robot: CableRobot
    orientation: tuple[float, float, float]
    motion: MotionSpec
    actuator: ActuatorModel
    criteria: tuple[str, ...]


def evaluate_chunk(problem: WorkspaceProblem, positions: np.ndarray) -> dict[str, np.ndarray]:
    """Margins ``margin_<criterion>`` (n,) and ``jacobian_rank`` (n,) for positions (n, 3)."""
    dyn = PoseDynamics(problem.robot, positions, problem.orientation, problem.motion)
    result = {f"margin_{name}": CRITERIA[name](dyn, problem.actuator) for name in problem.criteria}
    result["jacobian_rank"] = dyn.jacobian_rank.astype(np.int8)
    return result


def classify(margins: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Feasibility and the limiting criterion of every pose.

    A pose is feasible when every margin is >= 0. ``limiting`` names the criterion with the
    smallest margin: the most violated one for an infeasible pose, the tightest for a feasible
    one. Each infeasible pose is therefore attributed to exactly one criterion.
    """
    names = list(margins)
    stacked = np.column_stack([margins[name] for name in names])
    if not np.isfinite(stacked).all():
        row = int(np.flatnonzero(~np.isfinite(stacked).all(axis=1))[0])
        raise FloatingPointError(f"non-finite margin at pose index {row}: {stacked[row]}")
    feasible = (stacked >= 0).all(axis=1)
    limiting = np.asarray(names, dtype=object)[stacked.argmin(axis=1)]
    return feasible, limiting

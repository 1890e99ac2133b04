"""The workspace kernel: a pure function from a chunk of positions to per-criterion margins."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.criteria import CRITERIA
from pipeline.geometry import CableRobot

# criteria that, when violated, decide the verdict whatever the others say: a singular structure
# matrix, a wrench out of reach, a cable that would have to push (first listed wins)
GATES = ("singular", "unreachable", "slack")


@dataclass(frozen=True)
class WorkspaceProblem:
    """Everything a worker needs, as plain arrays and numbers (no config objects).

    ``spec`` builds the per-chunk state (``MotionSpec`` -> CPR-WWA dynamics, ``StaticsSpec`` ->
    statics); ``limits`` is what the criteria compare against (an ``ActuatorModel`` or
    ``StaticLimits``). ``orientations`` (k, 3): the pose must satisfy every criterion at every
    one of them (k = 1: constant-orientation workspace; k > 1: total-orientation workspace).
    """

    robot: CableRobot
    orientations: np.ndarray
    spec: Any
    limits: Any
    criteria: tuple[str, ...]

    @property
    def orientation(self) -> tuple[float, float, float]:
        """The nominal (first) orientation, reported with every pose."""
        return tuple(float(a) for a in self.orientations[0])


def evaluate_chunk(problem: WorkspaceProblem, positions: np.ndarray) -> dict[str, np.ndarray]:
    """Margins ``margin_<criterion>`` (n,), the worst over the orientation set, for positions (n, 3)."""
    result = {}
    for orientation in problem.orientations:
        state = problem.spec.state(problem.robot, positions, orientation)
        for name in problem.criteria:
            margin = CRITERIA[name](state, problem.limits)
            key = f"margin_{name}"
            result[key] = margin if key not in result else np.minimum(result[key], margin)
        if hasattr(state, "jacobian_rank"):
            rank = state.jacobian_rank.astype(np.int8)
            result["jacobian_rank"] = np.minimum(result.get("jacobian_rank", rank), rank)
    return result


def classify(margins: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Feasibility and the limiting criterion of every pose.

    A pose is feasible when every margin is >= 0. ``limiting`` names the criterion with the
    smallest margin: the most violated one for an infeasible pose, the tightest for a feasible
    one; a violated gate (``GATES``: singular, unreachable, slack) takes precedence. Each
    infeasible pose is therefore attributed to exactly one criterion.
    """
    names = list(margins)
    stacked = np.column_stack([margins[name] for name in names])
    if not np.isfinite(stacked).all():
        row = int(np.flatnonzero(~np.isfinite(stacked).all(axis=1))[0])
        raise FloatingPointError(f"non-finite margin at pose index {row}: {stacked[row]}")
    feasible = (stacked >= 0).all(axis=1)
    limiting = np.asarray(names, dtype=object)[stacked.argmin(axis=1)]
    for gate in reversed(GATES):  # the first gate listed wins
        if gate in margins:
            limiting[margins[gate] < 0] = gate
    return feasible, limiting

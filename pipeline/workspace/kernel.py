"""The workspace kernel: a pure function from a chunk of positions to per-criterion margins."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.workspace.criteria import REGISTRY
from pipeline.model.geometry import CableRobot
from pipeline.workspace.quantities import cable_quantities

@dataclass(frozen=True)
class WorkspaceProblem:
    """Everything a worker needs, as plain arrays and numbers (no config objects).

    ``spec`` builds the per-chunk state (``MotionSpec`` -> CPR-WWA dynamics, ``StaticsSpec`` ->
    statics); ``limits`` is what the criteria compare against (an ``ActuatorModel`` or
    ``StaticLimits``). ``orientations`` (k, 3): the pose must satisfy every criterion at every
    one of them (k = 1: constant-orientation workspace; k > 1: total-orientation workspace).
    ``margin_atol``: margins within it of zero count as exactly 0 (``pipeline.workspace.verdict``).
    ``cables``: also return the per-pose cable lengths and tensions (``pipeline.workspace.quantities``).
    """

    robot: CableRobot
    orientations: np.ndarray
    spec: Any
    limits: Any
    criteria: tuple[str, ...]
    margin_atol: float = 1e-9
    cables: bool = False

    @property
    def orientation(self) -> tuple[float, float, float]:
        """The nominal (first) orientation, reported with every pose."""
        return tuple(float(a) for a in self.orientations[0])


def evaluate_chunk(problem: WorkspaceProblem, positions: np.ndarray) -> dict[str, np.ndarray]:
    """Margins ``margin_<criterion>`` (n,), the worst over the orientation set, for positions
    (n, 3); with ``problem.cables`` also the cable quantities at the nominal orientation; under
    the feasible tension model ``lp_poses`` (n,): poses whose margins came from the LPs."""
    result = {}
    for number, orientation in enumerate(problem.orientations):
        state = problem.spec.state(problem.robot, positions, orientation)
        if problem.cables and number == 0:
            result.update(cable_quantities(state, problem.limits))
        for name in problem.criteria:
            margin = REGISTRY[name].function(state, problem.limits)
            key = f"margin_{name}"
            result[key] = margin if key not in result else np.minimum(result[key], margin)
        if hasattr(state, "jacobian_rank"):
            rank = state.jacobian_rank.astype(np.int8)
            result["jacobian_rank"] = np.minimum(result.get("jacobian_rank", rank), rank)
        if hasattr(state, "tension_lp"):  # the feasible model's LP fallback (pipeline.model.tensions)
            result["lp_poses"] = result.get("lp_poses", False) | state.tension_lp
    return result

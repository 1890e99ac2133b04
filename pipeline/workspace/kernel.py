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
    ``fused``: evaluate with the compiled kernel of ``pipeline.workspace.fused`` (numpy for the
    poses it leaves unsettled); the job decides (``pipeline.workspace.compute.use_fused``).
    ``nominal``: the orientation as the config gives it, in its convention (``orientation.*``),
    reported with every pose; ``orientations`` are always eq. (9)'s angles.
    """

    robot: CableRobot
    orientations: np.ndarray
    spec: Any
    limits: Any
    criteria: tuple[str, ...]
    margin_atol: float = 1e-9
    cables: bool = False
    fused: bool = False
    nominal: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def orientation(self) -> tuple[float, float, float]:
        """The nominal (first) orientation, reported with every pose."""
        return tuple(float(a) for a in self.orientations[0])


def evaluate_chunk(problem: WorkspaceProblem, positions: np.ndarray) -> dict[str, np.ndarray]:
    """Margins ``margin_<criterion>`` (n,), the worst over the orientation set (also the
    largest payload under ``analysis=payload``), for positions (n, 3); with ``problem.cables``
    also the cable quantities at the nominal orientation; under the feasible tension model
    ``lp_poses`` (n,): poses whose margins came from the LPs."""
    result = {}
    for number, orientation in enumerate(problem.orientations):
        if problem.fused:
            part = _fused(problem, positions, orientation)
        else:
            part = _criteria(problem, positions, orientation, problem.cables and number == 0)
        for key, value in part.items():
            if key not in result:
                result[key] = value
            elif key.startswith("margin_") or key in ("jacobian_rank", "max_payload_kg"):
                result[key] = np.minimum(result[key], value)
            elif key == "lp_poses":
                result[key] = result[key] | value
    return result


def _criteria(problem: WorkspaceProblem, positions: np.ndarray, orientation, cables: bool) -> dict:
    """Every criterion's margins at one orientation, from the chunk state (numpy)."""
    state = problem.spec.state(problem.robot, positions, orientation)
    result = cable_quantities(state, problem.limits) if cables else {}
    for name in problem.criteria:
        result[f"margin_{name}"] = REGISTRY[name].function(state, problem.limits)
    result.update(state.diagnostics())  # the Jacobian's rank, the poses the feasible model's LPs solved
    return result


def _fused(problem: WorkspaceProblem, positions: np.ndarray, orientation) -> dict:
    """:func:`_criteria` by the compiled kernel, numpy for the poses it leaves unsettled."""
    from pipeline.workspace import fused

    result, unsettled = fused.margins(problem, positions, orientation)
    if unsettled.any():
        for key, value in _criteria(problem, positions[unsettled], orientation, False).items():
            result[key][unsettled] = value
    return result

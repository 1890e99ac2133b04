"""The workspace kernel: a pure function from a chunk of positions to per-criterion margins."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from pipeline.workspace.criteria import GEOMETRY, REGISTRY, margins
from pipeline.workspace.criteria.forces import written_tensions
from pipeline.model.geometry import CableRobot, PoseGeometry, rotation_matrices
from pipeline.model.metrics import pose_metrics
from pipeline.workspace.quantities import cable_quantities

@dataclass(frozen=True)
class WorkspaceProblem:
    """Everything a worker needs, as plain arrays and numbers (no config objects).

    ``spec`` builds the per-chunk state (``MotionSpec`` -> CPR-WWA dynamics, ``StaticsSpec`` ->
    statics); ``limits`` is what the criteria compare against (an ``ActuatorModel`` or
    ``StaticLimits``). ``orientations`` (k, 3): the pose must satisfy every criterion at every
    one of them (k = 1: constant-orientation workspace; k > 1: total-orientation workspace).
    ``margin_atol``: margins within it of zero count as exactly 0 (``pipeline.workspace.verdict``).
    ``cables``: also return the per-pose cable lengths and tensions (``pipeline.workspace.quantities``);
    ``metrics``: the per-pose metrics of a static pose (``pipeline.model.metrics``), both at the
    nominal orientation.
    ``fused``: evaluate with the compiled kernel of ``pipeline.workspace.fused`` (numpy for the
    poses it leaves unsettled); the job decides (``pipeline.workspace.dispatch.use_fused``).
    ``nominal``: the orientation as the config gives it, in its convention (``orientation.*``),
    reported with every pose; ``orientations`` are always eq. (9)'s angles. ``settings``: the
    criteria's own keys (``criteria.<name>.<key>``), by criterion. ``angles``: for a
    robot whose reference point a joint holds (``CableRobot.fixed_point``), the convention of
    the grid's rows, which are then orientations (psi, theta, phi) at the frame's origin, one
    verdict each; None: the rows are positions.
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
    angles: str | None = None
    metrics: bool = False
    settings: dict = field(default_factory=dict)

    @property
    def orientation(self) -> tuple[float, float, float]:
        """The nominal (first) orientation, reported with every pose."""
        return tuple(float(a) for a in self.orientations[0])

    def poses(self, rows: np.ndarray) -> list[tuple[np.ndarray, Any]]:
        """(positions (n, 3), orientation) for each orientation the grid's ``rows`` are checked
        at: the rows as positions at each orientation of the set (eq. 9's angles), or, when the
        rows are orientations (``angles``), the frame's origin with one rotation per row."""
        if self.angles is None:
            return [(rows, orientation) for orientation in self.orientations]
        return [(np.zeros_like(rows), rotation_matrices(rows, self.angles))]

    @cached_property
    def fused_arguments(self) -> tuple[tuple, ...]:
        """The compiled kernel's arguments the positions do not change, one tuple per orientation
        of the set (:func:`pipeline.workspace.fused.arguments`), built once a process."""
        from pipeline.workspace import fused

        return fused.arguments(self)


def evaluate_chunk(problem: WorkspaceProblem, rows: np.ndarray) -> dict[str, np.ndarray]:
    """Margins ``margin_<criterion>`` (n,), the worst over the orientation set (also the
    largest payload under ``analysis=payload``), for the grid's rows (n, 3): positions, or
    orientations (:meth:`WorkspaceProblem.poses`); with ``problem.cables``
    also the cable quantities at the nominal orientation; under the feasible tension model
    ``lp_poses`` (n,): poses whose margins came from the LPs; with a wrench set, the vertex that
    limits each pose at its worst orientation (:func:`_limiting_vertex`)."""
    result = {}
    for number, (positions, orientation) in enumerate(problem.poses(rows)):
        if problem.fused:
            part = _fused(problem, positions, orientation, number)
        else:
            part = _criteria(problem, positions, orientation, number == 0)
        worse = {key: part[margin] < result[margin] for key, margin in AT_THE_WORST.items() if key in result}
        for key, value in part.items():
            if key not in result:
                result[key] = value
            elif key in worse:
                result[key] = np.where(worse[key], value, result[key])
            elif key.startswith("margin_") or key in ("jacobian_rank", "max_payload_kg", "limiting_wrench_margin"):
                result[key] = np.minimum(result[key], value)
            elif key == "min_payload_kg":  # the payload every orientation of the set needs
                result[key] = np.maximum(result[key], value)
            elif key in ("sag_max_ratio", "added_length_max"):  # the largest over the orientations proven
                result[key] = np.fmax(result[key], value)
            elif key in ("lp_poses", "catenary_undecided"):
                result[key] = result[key] | value
    return result


# per-pose columns that name what limits a margin: kept from the orientation where it is lowest
AT_THE_WORST = {"limiting_wrench": "limiting_wrench_margin", "closest_pair": "margin_cable_cable",
                "closest_obstacle": "margin_cable_obstacle"}


def _criteria(problem: WorkspaceProblem, positions: np.ndarray, orientation, nominal: bool) -> dict:
    """Every criterion's margins at one orientation, from the chunk state (numpy); at the
    ``nominal`` one also the cable quantities and the metrics the problem asks for."""
    state = problem.spec.state(problem.robot, positions, orientation)
    result = cable_quantities(state, problem.limits) if problem.cables and nominal else {}
    found = margins(problem.criteria, state, problem.limits, problem.settings)
    result.update({f"margin_{name}": value for name, value in found.items()})
    if problem.metrics and nominal:
        held = np.min([result[f"margin_{name}"] for name in problem.criteria], axis=0) >= -problem.margin_atol
        result.update(pose_metrics(state, problem.limits, written_tensions, held))
    result.update(state.diagnostics())  # the Jacobian's rank, the poses the feasible model's LPs solved
    if problem.spec.kind == "statics" and len(problem.spec.wrench_set) > 1:
        result.update(_limiting_vertex(problem, positions, orientation, result))
    return result


def _limiting_vertex(problem: WorkspaceProblem, positions: np.ndarray, orientation, found: dict) -> dict:
    """``limiting_wrench`` (n,): for each pose a required wrench set (``wrench.set``) fails,
    the vertex (1 = the first of the set) whose own least margin is the lowest, each vertex
    evaluated alone by the same criteria on those poses only; 0 where the pose holds the whole
    set. ``limiting_wrench_margin`` (n,): that margin (0 where it holds), to pick the worst
    orientation."""
    least = np.min([found[f"margin_{name}"] for name in problem.criteria], axis=0)
    failing = np.flatnonzero(least < -problem.margin_atol)
    vertex, worst = np.zeros(len(positions), dtype=np.int64), np.zeros(len(positions))
    if len(failing):
        worst[failing] = np.inf
        numbers = problem.spec.vertex_numbers or range(1, len(problem.spec.wrench_set) + 1)
        for number, wrench in zip(numbers, problem.spec.wrench_set):
            alone = replace(problem.spec, wrench_set=wrench[None, :])
            turned = orientation[failing] if np.ndim(orientation) == 3 else orientation  # one rotation per pose
            state = alone.state(problem.robot, positions[failing], turned)
            own = np.min(list(margins(problem.criteria, state, problem.limits, problem.settings).values()), axis=0)
            lower = own < worst[failing]
            vertex[failing[lower]], worst[failing[lower]] = number, own[lower]
    return {"limiting_wrench": vertex, "limiting_wrench_margin": worst}


def _fused(problem: WorkspaceProblem, positions: np.ndarray, orientation, number: int) -> dict:
    """:func:`_criteria` by the compiled kernel at the set's orientation ``number``, numpy for the
    poses it leaves unsettled and for the criteria that read the geometry alone (the same code in
    either kernel)."""
    from pipeline.workspace import fused

    result, unsettled = fused.margins(problem, positions, number)
    geometric = [name for name in problem.criteria if REGISTRY[name].reads == GEOMETRY]
    if geometric:
        state = PoseGeometry(problem.robot, positions, orientation)
        found = margins(geometric, state, problem.limits, problem.settings)
        result.update({f"margin_{name}": value for name, value in found.items()})
        result.update(state.diagnostics())
    if unsettled.any():
        for key, value in _criteria(problem, positions[unsettled], orientation, False).items():
            result[key][unsettled] = value
    return result

"""Each pose's verdict alone, without the margins behind it: what a search over many robots
counts (``pipeline.analyses.layout``), fast where a proof allows.

:func:`feasible_flags` gives, for a chunk of the grid's rows, exactly the verdict of
``verdict.classify(kernel.evaluate_chunk(...))``, up to the tolerance that rule already allows at
a margin of zero. Under the ``feasible`` tension model at rest (statics), the intervals the
registry's criteria put on the cable forces (``criteria.force_families``) are intersected, each
widened by the verdict's tolerance (``margin_atol`` times its scale, as a margin of -atol still
counts), and the compiled null-space test of ``pipeline.model.nullspace`` decides whether one
force vector holds every required wrench within them (a verdict that every nested margin is
>= -atol, without computing them); the criteria that do not bound the forces are evaluated as
always, and the poses the test leaves undecided (rank short, poorly conditioned, a wide null
space) by the whole registry. Every other problem goes through the registry pose by pose
(``criteria.margins``). ``tests/test_feasibility.py`` compares the two pose by pose.
"""

from __future__ import annotations

import numpy as np

from pipeline.model.jit import compiled_loops
from pipeline.workspace.criteria import UNREACHABLE, force_families, margins
from pipeline.workspace.criteria.forces import feasible_model
from pipeline.workspace.kernel import WorkspaceProblem

PIVOT_RTOL = 1e-6  # a pivot of the row-scaled S below it: the exact model decides the pose


def feasible_flags(problem: WorkspaceProblem, rows: np.ndarray) -> np.ndarray:
    """(n,) whether each of the grid's ``rows`` is feasible at every orientation of ``problem``."""
    flags = np.ones(len(rows), dtype=bool)
    for positions, orientation in problem.poses(rows):
        state = problem.spec.state(problem.robot, positions, orientation)
        fast = problem.spec.kind == "statics" and feasible_model(state) and not state.settles
        families = force_families(state, problem.limits) if fast else []
        if not families or not all(_constant(f) for f in families):
            flags &= _registry_flags(problem, state)
            continue
        forces = {f.name for f in families}
        others = [name for name in problem.criteria if name not in forces and name != UNREACHABLE]
        found = margins(others, state, problem.limits, problem.settings)
        held = np.ones(len(positions), dtype=bool)
        for value in found.values():
            held &= value >= -problem.margin_atol
        m = state.structure.shape[2]
        lower = np.max([_per_cable(f.lower - problem.margin_atol * f.scale, m) for f in families], axis=0)
        upper = np.min([_per_cable(f.upper + problem.margin_atol * f.scale, m) for f in families], axis=0)
        verdicts = null_space_verdicts(state.structure, state.balanced_wrenches(families), lower, upper)
        undecided = np.flatnonzero(held & (verdicts < 0))
        held &= verdicts != 0
        if len(undecided):
            turned = orientation[undecided] if np.ndim(orientation) == 3 else orientation
            held[undecided] = _registry_flags(problem, problem.spec.state(problem.robot, positions[undecided], turned))
        flags &= held
    return flags


def null_space_verdicts(structure: np.ndarray, wrenches: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(n,) int8 the compiled null-space test of pulling cables (``pipeline.model.nullspace``) at
    each pose of ``structure`` (n, k, m) for its ``wrenches`` ((n, K, k), or one pose's for all):
    1 every wrench has tensions in [lower, upper] (per cable), 0 one has none, -1 undecided."""
    shape = (len(structure), *np.shape(wrenches)[-2:])
    wrenches = np.array(np.broadcast_to(wrenches, shape), dtype=float, order="C")  # a writable copy, also of one pose
    verdicts = np.empty(len(structure), dtype=np.int8)
    compiled_loops("pipeline.model.nullspace").pulling_verdicts(
        np.ascontiguousarray(structure, dtype=float), wrenches, np.ascontiguousarray(lower, dtype=float),
        np.ascontiguousarray(upper, dtype=float), PIVOT_RTOL, verdicts)
    return verdicts


def _constant(family) -> bool:
    """Whether a family's intervals are the same at every pose and wrench (one value per cable)."""
    return all(np.ndim(value) <= 1 or all(size == 1 for size in np.shape(value)[:-1])
               for value in (family.lower, family.upper, family.scale))


def _per_cable(value, m: int) -> np.ndarray:
    """A constant family's bound as one value per cable (m,)."""
    value = np.asarray(value, dtype=float)
    return np.broadcast_to(value.reshape(value.shape[-1]) if value.ndim > 1 else value, (m,))


def _registry_flags(problem: WorkspaceProblem, state) -> np.ndarray:
    """The verdict from every criterion's margin, as ``verdict.classify`` reads them."""
    found = margins(problem.criteria, state, problem.limits, problem.settings)
    return np.all([value >= -problem.margin_atol for value in found.values()], axis=0)

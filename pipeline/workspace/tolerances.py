"""Build tolerances (``robust.*``) and the build error that loses a pose (issue 57, item 4).

A robust paving (``pipeline.workspace.paving``) proves the boxes where every robot within the
tolerances holds; a box it cannot prove is either lost for real (some robot within them fails in
it) or lost to the enclosures' width. :func:`culprits` tells them apart where one build error
suffices: at each undecided box's centre that the robot as designed holds, every single error
the tolerances allow (one coordinate of one anchor or attachment, the load's mass, one coordinate
of its centre of mass, each at both ends of its interval) is tried with the exact per-pose test
(``pipeline.workspace.feasibility``); a centre that one of them breaks is a pose the robust
workspace certainly loses, and the error that breaks it at the smallest share of its tolerance
(found by bisection, to 1/2^``BISECTIONS``) is named. The robot so perturbed is a counterexample:
it is within the tolerances and the centre fails there. A centre no single error breaks may still
be lost to several at once, or not at all: it is not named.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from pipeline.workspace.feasibility import feasible_flags
from pipeline.workspace.kernel import WorkspaceProblem

BISECTIONS = 6  # halvings of the share of a tolerance that breaks a centre (to 1/64)
AXES = "xyz"


@dataclass(frozen=True)
class Tolerances:
    """Build tolerances (``robust.*``), each a half-width on every coordinate: ``anchors`` and
    ``attachments`` (m), the load's ``mass`` (kg) and centre of mass ``com`` (m)."""

    anchors: float = 0.0
    attachments: float = 0.0
    mass: float = 0.0
    com: float = 0.0

    @property
    def nominal(self) -> bool:
        return not (self.anchors or self.attachments or self.mass or self.com)


NOMINAL = Tolerances()  # the robot as designed


def errors(problem: WorkspaceProblem, tolerances: Tolerances) -> list[tuple[str, Callable[[float], WorkspaceProblem]]]:
    """Every single build error the tolerances allow, by name (``anchor <cable> z+``: the cable's
    anchor moved up; ``attachment``, ``mass``, ``com``), with the problem of the robot built with
    that error at a share s in [0, 1] of its tolerance."""
    robot, spec = problem.robot, problem.spec
    found = []

    def moved(points: str, cable: int, axis: int, step: float):
        def at(share: float) -> WorkspaceProblem:
            changed = getattr(robot, points).astype(float)
            changed[cable, axis] += share * step
            return replace(problem, robot=replace(robot, **{points: changed}))
        return at

    def loaded(mass: float, com: np.ndarray):
        def at(share: float) -> WorkspaceProblem:
            load = replace(spec.load, mass=spec.load.mass + share * mass, com=np.asarray(spec.load.com, float) + share * com)
            return replace(problem, spec=replace(spec, load=load))
        return at

    for points, label, size in (("anchors", "anchor", tolerances.anchors), ("attachments", "attachment", tolerances.attachments)):
        if size:
            for cable, name in enumerate(robot.cable_names):
                for axis in range(3):
                    for sign in (1, -1):
                        found.append((f"{label} {name} {AXES[axis]}{'+-'[sign < 0]}", moved(points, cable, axis, sign * size)))
    if tolerances.mass:
        for sign in (1, -1):
            found.append((f"mass{'+-'[sign < 0]}", loaded(sign * tolerances.mass, np.zeros(3))))
    if tolerances.com:
        for axis in range(3):
            for sign in (1, -1):
                found.append((f"com {AXES[axis]}{'+-'[sign < 0]}", loaded(0.0, sign * tolerances.com * np.eye(3)[axis])))
    return found


def culprits(problem: WorkspaceProblem, tolerances: Tolerances, points: np.ndarray,
             n_jobs: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """For each of ``points`` (n, 3): the name of the single build error within ``tolerances`` that
    breaks it at the smallest share of its tolerance, and that share (a robot with that error is a
    counterexample: the point fails there); None and NaN where the robot as designed fails at the
    point or no single error breaks it (module doc). The errors are tried on ``n_jobs`` threads
    (the exact test's compiled loop and numpy release the GIL) and taken in their order, so that
    of two errors breaking a point at the same share the first is named, whatever the threads."""
    from joblib import Parallel, delayed

    names = np.full(len(points), None, dtype=object)
    shares = np.full(len(points), np.nan)
    held = np.flatnonzero(feasible_flags(problem, points)) if len(points) else np.zeros(0, dtype=int)
    tried = errors(problem, tolerances)
    found = Parallel(n_jobs=n_jobs, backend="threading")(delayed(_breaking)(at, points, held) for _, at in tried)
    for (name, _), (rows, high) in zip(tried, found):
        better = ~(shares[rows] <= high)  # NaN (not named yet) or a larger share
        names[rows[better]], shares[rows[better]] = name, high[better]
    return names, shares


def _breaking(at: Callable[[float], WorkspaceProblem], points: np.ndarray, held: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows of ``held`` whose point one error (``at``: the problem at a share of it) breaks at
    its whole tolerance, and the share that breaks each, bisected to 1/2^BISECTIONS."""
    rows = held[~feasible_flags(at(1.0), points[held])]
    low, high = np.zeros(len(rows)), np.ones(len(rows))  # holds at low, breaks at high
    for _ in range(BISECTIONS):
        middle = (low + high) / 2
        for share in np.unique(middle):  # one problem per share; every row of a step starts with the same
            subset = np.flatnonzero(middle == share)
            broken = ~feasible_flags(at(float(share)), points[rows[subset]])
            high[subset[broken]], low[subset[~broken]] = share, share
    return rows, high

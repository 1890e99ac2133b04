"""The verdict rule: margins to a feasible flag and a limiting criterion, with a stated tolerance.

Every criterion reports a relative margin (>= 0 satisfied). A margin computed in floating point
carries round-off of a few ulps of the quantities behind it, and which way that round-off falls
depends on the BLAS kernel the CPU selects (``OPENBLAS_CORETYPE``): a pose whose exact margin is
0 (a cable with exactly zero tension, a velocity exactly at its limit) would otherwise be
feasible on one machine and not on another. So margins within ``atol`` of zero are set to
exactly 0 and count as satisfied: the boundary belongs to the workspace (closed sets, as the
papers' ``<=`` limits), and the verdict no longer depends on the CPU. ``model.margin_atol``
(default 1e-9, dimensionless like the margins) is that tolerance; 0 restores the raw rule.
"""

from __future__ import annotations

import numpy as np

from pipeline.workspace.criteria import gates  # violated, they decide the verdict (first listed wins)


def snap(margin: np.ndarray, atol: float) -> np.ndarray:
    """``margin`` with every value in [-atol, atol] replaced by exactly 0."""
    margin = np.asarray(margin, dtype=float)
    return np.where(np.abs(margin) <= atol, 0.0, margin)


def classify(
    margins: dict[str, np.ndarray], atol: float
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """Snapped margins, feasibility and the limiting criterion of every pose.

    A pose is feasible when every snapped margin is >= 0. ``limiting`` (int8 codes: positions in
    ``list(margins)``, as ``pandas.Categorical.from_codes`` takes them, no string per pose)
    points at the criterion with the smallest margin: the most violated one for an infeasible
    pose, the tightest for a feasible one (ties: the first criterion listed); a violated gate
    (``gates()``) takes precedence. Each infeasible pose is therefore attributed to exactly one
    criterion.
    """
    names = list(margins)
    snapped = {name: snap(margins[name], atol) for name in names}
    stacked = np.column_stack([snapped[name] for name in names])
    if not np.isfinite(stacked).all():
        row = int(np.flatnonzero(~np.isfinite(stacked).all(axis=1))[0])
        raise FloatingPointError(f"non-finite margin at pose index {row}: {stacked[row]}")
    feasible = (stacked >= 0).all(axis=1)
    limiting = stacked.argmin(axis=1).astype(np.int8)
    for gate in reversed(gates()):  # the first gate listed wins
        if gate in snapped:
            limiting[snapped[gate] < 0] = names.index(gate)
    return snapped, feasible, limiting


class Tally:
    """A job's verdicts counted chunk by chunk (:meth:`add`, with what :func:`classify` returns):
    the feasible poses, the infeasible ones by limiting criterion (``lost``), those one criterion
    alone removes, every other holding there (``alone``: what relaxing it alone would win), and
    each criterion's least margin over the feasible poses (``least``: the headroom kept)."""

    def __init__(self, names):
        self.names = list(names)
        self.n_feasible = 0
        self.lost = np.zeros(len(self.names), dtype=np.int64)
        self.alone = np.zeros(len(self.names), dtype=np.int64)
        self.least = dict.fromkeys(self.names, np.inf)

    def add(self, margins: dict[str, np.ndarray], feasible: np.ndarray, limiting: np.ndarray) -> None:
        self.n_feasible += int(np.count_nonzero(feasible))
        for name in self.names:
            self.least[name] = np.min(margins[name], initial=self.least[name], where=feasible)
        self.lost += np.bincount(limiting[~feasible], minlength=len(self.names))
        violated = np.column_stack([margins[name] < 0 for name in self.names])
        self.alone += violated[violated.sum(axis=1) == 1].sum(axis=0)

    def counts(self, n_points: int) -> dict:
        """The counts ``pipeline.workspace.compute.summarize`` reads."""
        return {"n_points": n_points, "n_feasible": self.n_feasible, "lost": dict(zip(self.names, self.lost.tolist())),
                "alone": dict(zip(self.names, self.alone.tolist())), "least": self.least}

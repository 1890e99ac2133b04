"""What a job says of its degenerate poses once its grid is done (issue 38 item 2, issue 39): where
the structure matrix (J^T of eq. 20, A of the IRPM's eq. 8) lacks a direction of the wrench space,
which direction that is, in words, and which cables collapse (the ``zero_length`` gate)."""

from __future__ import annotations

import logging

import numpy as np

from pipeline.model.geometry import FREEDOMS
from pipeline.workspace.criteria import SINGULAR, UNREACHABLE, ZERO_LENGTH

log = logging.getLogger("pipeline.degeneracy")  # a sweep says each note once (pipeline.app.run)

WORDS = {"x": "force along x", "y": "force along y", "z": "force along z",
         "rx": "moment about x", "ry": "moment about y", "rz": "moment about z"}
SHOWN = 0.1  # components of the missing direction named besides the largest one


class Degeneracy:
    """Collects, chunk by chunk: the ranks of J^T (CPR-WWA, column ``jacobian_rank``) and the
    largest share of the required wrench the forces miss (column ``wrench_residual``); the first
    pose that fails a rank gate (``singular``, ``unreachable``) or whose J^T is short, with the
    rank of its structure matrix and the direction the cables cannot act along (one SVD of one
    pose per chunk, until one is found); the cables of zero length."""

    def __init__(self, problem):
        self.problem = problem
        self.ranks = np.zeros(7, dtype=np.int64)
        self.missed = 0.0
        self.collapsed: set[int] = set()
        self.sample: dict | None = None
        self.point = not problem.robot.attachments.any()  # no moment arms: the moment rows are zero
        self.full = 3 if self.point or getattr(problem.spec, "pinv_columns", "full") == "translational" else 6

    def add(self, positions: np.ndarray, raw: dict, margins: dict) -> None:
        if "jacobian_rank" in raw:
            self.ranks += np.bincount(raw["jacobian_rank"], minlength=7)
        if UNREACHABLE in margins and len(positions):
            limit = self.problem.spec.tension.residual_limit
            self.missed = max(self.missed, float((1.0 - margins[UNREACHABLE]).max()) * limit)
        if ZERO_LENGTH in margins and (margins[ZERO_LENGTH] < 0).any():
            robot, tol = self.problem.robot, self.problem.robot.shortest_cable
            for placed, orientation in self.problem.poses(positions[margins[ZERO_LENGTH] < 0]):
                state = self.problem.spec.state(robot, placed, orientation)
                self.collapsed.update(np.flatnonzero((state.lengths < tol).any(axis=0)).tolist())
        if self.sample is None:
            suspect = np.zeros(len(positions), dtype=bool)
            for gate in (SINGULAR, UNREACHABLE):
                if gate in margins:
                    suspect |= margins[gate] < 0
            if "jacobian_rank" in raw:
                suspect |= raw["jacobian_rank"] < self.full
            if ZERO_LENGTH in margins:
                suspect &= margins[ZERO_LENGTH] >= 0  # a collapsed cable is explained by name
            for index in np.flatnonzero(suspect)[:1]:
                self.sample = self.direction_at(positions[index])

    def direction_at(self, position: np.ndarray) -> dict | None:
        """The rank of the structure matrix at ``position`` (nominal orientation; singular values
        at or below ``model.rank_rtol`` of the largest dropped, as the pseudo-inverse drops them)
        and the first direction its SVD drops; None at full rank."""
        state = self.problem.spec.state(self.problem.robot, *self.problem.poses(position[None, :])[0])
        rows = [k for k, freedom in enumerate(state.rows) if not (self.point and freedom >= 3)]
        left, sigma, _ = np.linalg.svd(state.structure[0][rows])
        rank = int((sigma > self.problem.spec.rank_rtol * sigma[0]).sum()) if sigma[0] > 0 else 0
        if rank == len(rows):
            return None
        direction = left[:, rank] * np.sign(left[np.argmax(np.abs(left[:, rank])), rank])
        shown = [(WORDS[FREEDOMS[state.rows[rows[k]]]], direction[k])
                 for k in np.argsort(-np.abs(direction)) if abs(direction[k]) >= SHOWN]
        words = ", ".join(f"{name} ({value:+.2f})" for name, value in shown)
        vector = np.zeros(len(state.rows))
        vector[rows] = direction
        return {"position": position, "rank": rank, "rows": len(rows), "main": shown[0][0], "words": words,
                "vector": vector}

    def summary(self) -> dict:
        """Summary columns: the rank and the missing direction at the sampled pose, when any."""
        if self.sample is None:
            return {}
        return {"deficient_rank": self.sample["rank"], "missing_direction": self.sample["words"]}

    def explain(self, n_points: int) -> None:
        tension = self.problem.spec.tension
        short = {rank: int(count) for rank, count in enumerate(self.ranks) if count and rank < self.full}
        if short:
            ranks = ", ".join(f"rank {rank} at {count}" for rank, count in short.items())
            log.info("J^T is short of rank %d at %d of %d poses (%s; column jacobian_rank): the cables cannot act "
                     "along every direction of the wrench space there, and the forces miss up to %.2f%% of the "
                     "required wrench (unreachable past tension.%s=%g)", self.full, sum(short.values()), n_points,
                     ranks, 100 * self.missed, "pinv_residual" if tension.model == "pinv" else "residual_rtol",
                     tension.residual_limit)
        if self.sample is not None:
            where = "(psi, theta, phi) = (%g, %g, %g) rad" if self.problem.angles else "(x, y, z) = (%g, %g, %g) m"
            log.info("at " + where + " the structure matrix has rank %d of %d: the cables cannot produce a %s "
                     "there (the missing direction: %s)", *self.sample["position"], self.sample["rank"],
                     self.sample["rows"], self.sample["main"], self.sample["words"])
        if self.collapsed:
            names = ", ".join(self.problem.robot.cable_names[i] for i in sorted(self.collapsed))
            log.warning("cables %s have zero length at some poses (the attachment on its anchor: no "
                        "direction); those poses are infeasible (zero_length)", names)

"""Geometric criteria: no collapsed cable (the zero_length gate, every analysis), a structure
matrix of full rank (the singular gate) and cables no longer than the robot's ``l_max`` (eq. 10
of the IRPM paper), for every analysis."""

from __future__ import annotations

import numpy as np

from pipeline.model.statics import PoseStatics, StaticLimits


def zero_length(state, limits) -> np.ndarray:
    """Every cable must have a length: at a pose where a platform attachment sits on its cable's
    anchor (length below ``CableRobot.shortest_cable``) the cable has no direction (eq. 1), the
    structure matrix no column for it, and no tension there means anything. Margin
    min(1, l_min / tol - 1): 1 at every pose a grid normally holds, -1 for an exactly collapsed
    cable, so such a pose is infeasible whatever the other margins say (a gate)."""
    return np.minimum(1.0, state.lengths.min(axis=1) / state.robot.shortest_cable - 1.0)


def singular(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """The structure matrix must have full rank. With g its gram ratio in [0, 1] the margin is
    (g - rtol) / (1 - rtol) in [0, 1] for a regular pose and g / rtol - 1 in [-1, 0) for a
    singular one (continuous and increasing in g, -1 for an exactly singular pose, so the
    verdict tolerance of ``pipeline.workspace.verdict`` never reaches it). A singular pose has no tensions
    to check (``criteria.gates()``)."""
    g, rtol = st.gram_ratio, lim.rank_rtol
    return np.where(g >= rtol, (g - rtol) / (1.0 - rtol), g / rtol - 1.0)


def length(state, limits) -> np.ndarray:
    """Eq. (10): l_i <= l_max of the robot (``CableRobot.l_max``), in any analysis."""
    return 1.0 - (state.cable_lengths / state.robot.l_max).max(axis=1)

"""Criteria on the cable tensions, in every analysis: a wrench the cables can reach at all
(``feasible`` model), cables that only pull (tensions >= t_min; eq. 10 of the IRPM paper) and
the cable rating t_max (eq. 10: s <= s_max)."""

from __future__ import annotations

import numpy as np

from pipeline.model.tensions import reachability
from pipeline.workspace.criteria.forces import feasible_margins, feasible_model


def unreachable(state, limits) -> np.ndarray:
    """Every required wrench must be in the range of S (J^T or A), within
    |S S^+ w - w| <= rtol |w|, rtol the model's ``residual_limit`` (``tension.residual_rtol``
    or ``tension.pinv_residual``). Margin 1 - residual / (rtol |w|), the worst over the required
    wrenches. Under ``feasible`` from that model's margins; under ``pinv``
    (CPR-WWA, eq. 20) the wrench the minimum-norm forces M = (J^T)^+ F fail to balance: J^T of
    a rank-deficient robot reaches F only in its range (the CPR-8 at the zero orientation,
    rank 5, misses up to 1.4 % of F; a robot with every anchor on one line most of it)."""
    if feasible_model(state):
        return feasible_margins(state, limits)["unreachable"]
    pinv, rank = state.wrench_pinv
    missed = np.zeros(len(rank))  # a full-rank S reaches every wrench: nothing to compute there
    short = rank < state.structure.shape[1]
    if short.any():
        wrenches = state.required_wrenches
        wrenches = wrenches[short] if wrenches.ndim == 3 else wrenches
        missed[short] = reachability(state.structure[short], pinv[short], wrenches)[0].max(axis=1)
    return 1.0 - missed / state.tension.pinv_residual


def slack(state, limits) -> np.ndarray:
    """A cable can only pull: tensions >= t_min (eq. 10 of the IRPM paper: s_i >= 0). Margin
    (min_i s_i - t_min) / scale (``StaticLimits.scale``); under ``feasible`` the best such margin
    over all valid tension distributions (CPR-8: in units of the torque limit)."""
    if feasible_model(state):
        return feasible_margins(state, limits)["slack"]
    return (state.force_range[1] - state.tension.t_min).min(axis=1) / limits.scale


def tension_max(state, limits) -> np.ndarray:
    """Eq. (10): s_i <= s_max (IRPM), or the cable rating ``tension.t_max`` (CPR-8)."""
    if feasible_model(state):
        return feasible_margins(state, limits)["tension_max"]
    return 1.0 - (state.force_range[0] / state.tension.t_max).max(axis=1)  # t_max: scalar or per cable

"""Criteria on the cable tensions, in every analysis: a wrench the cables can reach at all
(``feasible`` model), cables that only pull (tensions >= t_min; eq. 10 of the IRPM paper) and
the cable rating t_max (eq. 10: s <= s_max). The last two bound the ``feasible`` model's force
variables (``*_bounds``); their functions give the minimum-norm model's margins."""

from __future__ import annotations

import numpy as np

from pipeline.model.tensions import reachability
from pipeline.workspace.criteria.forces import feasible_model


def unreachable(state, limits) -> np.ndarray:
    """Every required wrench must be in the range of S (J^T or A), within
    |S S^+ w - w| <= rtol |w|, rtol the model's ``residual_limit`` (``tension.residual_rtol``
    or ``tension.pinv_residual``). Margin 1 - residual / (rtol |w|), the worst over the required
    wrenches. Under ``feasible`` from that model's margins; under ``pinv``
    (CPR-WWA, eq. 20) the wrench the minimum-norm forces M = (J^T)^+ F fail to balance: J^T of
    a rank-deficient robot reaches F only in its range (the CPR-8 at the zero orientation,
    rank 5, misses up to 1.4 % of F; a robot with every anchor on one line most of it)."""
    pinv, rank = state.wrench_pinv
    if feasible_model(state):  # the feasible model's forces reach S S^+ w: its residual at every pose
        return 1.0 - reachability(state.structure, pinv, state.required_wrenches)[0].max(axis=1) / state.tension.residual_rtol
    missed = np.zeros(len(rank))  # a full-rank S reaches every wrench: nothing to compute there
    short = rank < state.structure.shape[1]
    if short.any():
        wrenches = state.required_wrenches
        wrenches = wrenches[short] if wrenches.ndim == 3 else wrenches
        missed[short] = reachability(state.structure[short], pinv[short], wrenches)[0].max(axis=1)
    return 1.0 - missed / state.tension.pinv_residual


def slack(state, limits) -> np.ndarray:
    """A cable can only pull: tensions >= t_min (eq. 10 of the IRPM paper: s_i >= 0). Margin
    (min_i s_i - t_min) / scale (``StaticLimits.scale``) of the minimum-norm tensions."""
    return (state.force_range[1] - state.tension.t_min).min(axis=1) / limits.scale


def slack_bounds(state, limits) -> tuple:
    """Under ``feasible``: x >= t_min in the state's variables, in units of ``limits.scale`` (the
    statics' N, the CPR-8's torque limit): the best slack margin over every valid distribution."""
    return state.variables_of(state.tension.t_min), np.inf, limits.scale


def tension_max(state, limits) -> np.ndarray:
    """Eq. (10): s_i <= s_max (IRPM), or the cable rating ``tension.t_max`` (CPR-8)."""
    return 1.0 - (state.force_range[0] / state.tension.t_max).max(axis=1)  # t_max: scalar or per cable


def tension_max_bounds(state, limits) -> tuple | None:
    """Under ``feasible``: x <= t_max in the state's variables and in its units; none without a
    finite rating."""
    t_max = state.tension.t_max
    if t_max is None or not np.isfinite(t_max).all():
        return None
    rating = state.variables_of(t_max)
    return -np.inf, rating, rating

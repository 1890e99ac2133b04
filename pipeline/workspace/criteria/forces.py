"""The ``feasible`` tension model seen by the criteria: the intervals each criterion puts on the
cable forces (families) and the capacity margins of ``pipeline.model.tensions``, computed once per
chunk and limits and shared by every criterion that reads them (unreachable, slack,
tension_max, torque, voltage)."""

from __future__ import annotations

import numpy as np

from pipeline.model.distribution import min_norm_tensions
from pipeline.model.tensions import feasible_tensions


def feasible_margins(state, limits) -> dict[str, np.ndarray]:
    """(n,) margins of the ``feasible`` tension model, the worst over the required wrenches:
    ``unreachable`` and one per family of the state's ``force_families``, from hyperplane shifting
    (LPs where it falls back, ``pipeline.model.tensions``). Cached on the state per limits: one
    computation serves every criterion that reads it; ``state.tension_lp`` (n,) records the
    poses the LPs solved."""
    cache = state.__dict__.setdefault("_feasible_margins", {})
    key = id(limits)  # the problem's one limits object; arrays inside make it unhashable
    if key not in cache:
        margins, _, by_lp = feasible_tensions(
            state.structure, *state.wrench_pinv, state.required_wrenches,
            state.force_families(limits), state.tension.residual_rtol,
        )
        cache[key] = margins
        state.tension_lp = by_lp
    return cache[key]


def feasible_distribution(state, limits) -> np.ndarray:
    """The cable forces x (n, K, m) the ``feasible`` model chooses: the solution of the last
    family's LP (the best voltage margin once every earlier criterion does its best), or
    x = S^+ w where it is unique."""
    return feasible_tensions(
        state.structure, *state.wrench_pinv, state.required_wrenches,
        state.force_families(limits), state.tension.residual_rtol, distribution=True,
    )[1]


def written_distribution(state, limits) -> np.ndarray:
    """The cable forces x (n, K, m) the ``feasible`` model writes (``output.cables``): with
    ``tension.distribution=min_norm`` the least 2-norm tensions within every family's bounds
    where they admit one (:mod:`pipeline.model.distribution`), else :func:`feasible_distribution`."""
    if state.tension.distribution != "min_norm":
        return feasible_distribution(state, limits)
    weights = state.forces_of(np.ones(state.structure.shape[2]))  # tensions per unit of the variables
    return min_norm_tensions(state.structure, *state.wrench_pinv, state.required_wrenches,
                             state.force_families(limits), weights, state.tension.residual_rtol)


def feasible_model(state) -> bool:
    """Whether the cable forces come from the ``feasible`` model's LPs."""
    return state.tension.model == "feasible"

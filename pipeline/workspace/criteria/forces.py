"""The ``feasible`` tension model seen by the criteria: the intervals each criterion puts on the
cable forces (families) and the capacity margins of ``pipeline.model.tensions``, computed once per
chunk and limits and shared by every criterion that reads them (unreachable, slack,
tension_max, torque, voltage)."""

from __future__ import annotations

import numpy as np

from pipeline.model.tensions import feasible_tensions, min_norm_distribution


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
    where the LPs found a valid distribution (:func:`pipeline.model.tensions.min_norm_distribution`),
    else :func:`feasible_distribution`."""
    chosen = feasible_distribution(state, limits)
    if state.tension.distribution != "min_norm":
        return chosen
    families = state.force_families(limits)
    shape = chosen.shape
    lower = np.max([np.broadcast_to(f.lower, shape) for f in families], axis=0)
    upper = np.min([np.broadcast_to(f.upper, shape) for f in families], axis=0)
    wrenches = np.broadcast_to(state.required_wrenches, (shape[0], *np.shape(state.required_wrenches)[-2:]))
    weights = state.forces_of(np.ones(shape[2]))  # tensions per unit of the variables
    return min_norm_distribution(state.structure, wrenches, lower, upper, weights, chosen, state.tension.residual_rtol)


def feasible_model(state) -> bool:
    """Whether the cable forces come from the ``feasible`` model's LPs."""
    return state.tension.model == "feasible"

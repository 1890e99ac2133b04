"""The ``feasible`` tension model seen by the criteria: the intervals the criteria put on the cable
forces (their ``bounds``, one family each, gathered by ``criteria.force_families``) and the
capacity margins of ``pipeline.model.tensions``, computed once per chunk and limits and shared by
every criterion that reads them."""

from __future__ import annotations

import numpy as np

from pipeline.model.distribution import min_norm_tensions
from pipeline.model.tensions import Family, feasible_tensions
from pipeline.workspace.criteria.registry import force_families


def feasible_margins(state, limits, families: list[Family]) -> dict[str, np.ndarray]:
    """(n,) margins of the ``feasible`` tension model, the worst over the required wrenches: one
    per family (the intervals the registry's criteria put on the forces, ``criteria.force_families``),
    from hyperplane shifting (LPs where it falls back, ``pipeline.model.tensions``). Computed once
    per state and limits (:func:`_solved`): one computation serves every criterion that reads it."""
    return _solved(state, limits, families, distribution=False)[0]


def feasible_distribution(state, limits, families: list[Family]) -> np.ndarray:
    """The cable forces x (n, K, m) the ``feasible`` model chooses: the solution of the last
    family's LP (the best voltage margin once every earlier criterion does its best), or
    x = S^+ w where it is unique; solved with the margins, once (the lines ask for both)."""
    return _solved(state, limits, families, distribution=True)[1]


def _solved(state, limits, families, distribution: bool) -> tuple[dict[str, np.ndarray], np.ndarray | None]:
    """The feasible model's margins and, when asked, its distribution, cached on the state per
    limits (the problem's one limits object, which decides the families; arrays inside make it
    unhashable); a solve with the distribution serves a later call for the margins alone.
    ``state.tension_lp`` (n,) records the poses the LPs solved."""
    cache = state.__dict__.setdefault("_feasible_solved", {})
    found = cache.get(id(limits))
    if found is None or (distribution and found[1] is None):
        margins, _, chosen, by_lp = feasible_tensions(
            state.structure, *state.wrench_pinv, state.balanced_wrenches(families), families, distribution=distribution,
        )
        found = cache[id(limits)] = (margins, chosen)
        state.tension_lp = by_lp
    return found


def written_distribution(state, limits, families: list[Family]) -> np.ndarray:
    """The cable forces x (n, K, m) the ``feasible`` model writes (``output.cables``): with
    ``tension.distribution=min_norm`` the least 2-norm tensions within every family's bounds
    where they admit one (:mod:`pipeline.model.distribution`), else :func:`feasible_distribution`."""
    if state.settles:  # forces that decide their own wrench (sagging cables): the settled ones
        return state.settled_forces(families)
    wrenches = state.balanced_wrenches(families)
    if state.tension.distribution != "min_norm":
        return feasible_distribution(state, limits, families)
    weights = state.forces_of(np.ones(state.structure.shape[2]))  # tensions per unit of the variables
    return min_norm_tensions(state.structure, *state.wrench_pinv, wrenches, families, weights,
                             state.tension.residual_rtol)


def feasible_model(state) -> bool:
    """Whether the cable forces come from the ``feasible`` model's LPs."""
    return state.tension.model == "feasible"


def written_tensions(state, limits) -> np.ndarray:
    """The cable forces (n, K, m) the ``feasible`` model writes within the registry's families
    (``forces.written_distribution``: ``output.cables``, ``output.metrics``)."""
    return written_distribution(state, limits, force_families(state, limits))

"""Capacity margins of the ``feasible`` tension model in closed form: hyperplane shifting.

``pipeline.model.tensions`` defines the margin of a criterion family as the LP

    max_x  s   subject to   S x = w,   L <= x <= U (earlier families),
                            lower + s c <= x <= upper - s c (this family),   s <= 1.

Here the same number, least over the required wrenches (what a criterion reads), is computed
without an LP, one pose at a time in a compiled loop (``pipeline.model.crossings``).

Wrench-space test (the hyperplane-shifting method). Let q be the rank of S (r x m) and work
in its q-dimensional range. For a box B of cable forces (sides possibly infinite) the set S B
is a polyhedron, the Minkowski sum of the segments (rays, lines) [l_i, u_i] S_i; each of its
facets is parallel to q - 1 linearly independent columns S_i, so its normal is one of the
2 C(m, q - 1) vectors ``+-n`` orthogonal to a (q - 1)-subset of columns. Hence w lies in S B
exactly when, for every candidate n,

    n . w  <=  h(n) = sum_i max(a_i l_i, a_i u_i),      a_i = n . S_i,

(a candidate that is not a facet normal only adds a valid, redundant inequality).

Shifting the hyperplanes. With this family shrunk by s and the earlier bounds fixed, the side
of cable i that h reads is min(P_i, Q_i - s c_i): for a_i > 0, P_i = U_i, Q_i = upper_i; for
a_i < 0, P_i = -L_i, Q_i = -lower_i. So h(n, s) = sum_i |a_i| min(P_i, Q_i - s c_i) is concave,
piecewise linear and non-increasing in s, with one breakpoint per cable,
beta_i = (Q_i - P_i) / c_i. The margin is the smallest crossing of h with n . w over the
normals, capped by 1 and by the largest s at which every cable's interval is non-empty (past it
the support formula no longer describes an empty box); each crossing is found exactly by
Newton's method from the right (``pipeline.model.crossings``).

Cost: 2 C(m, q - 1) normals x m cables per (pose, family) and per wrench where a family's bounds
depend on it: 56 x 8 for the CPR-8 with forces only (q = 3), 112 x 8 with moments at a general
orientation (q = 6). The number of normals grows combinatorially; past ``MAX_NORMALS`` the
caller keeps the LP.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

RELAX = 1e-9  # extra relaxation (in units of each family's scale) of earlier families' bounds
MAX_NORMALS = 2000  # 2 C(m, q - 1) candidate normals per pose beyond which the LP is cheaper
BIG = 1e150  # an infinite side: larger than any wrench or bound, and no overflow in a sum


def range_coordinates(structure: np.ndarray, wrenches: np.ndarray, rank: int):
    """``structure`` (n, r, m) and ``wrenches`` (n, K, r) in an orthonormal basis of the range of
    each S when its rank is below r (the wrenches must lie in that range)."""
    if rank == structure.shape[1]:
        return structure, wrenches
    basis = np.linalg.svd(structure, full_matrices=False)[0][:, :, :rank]  # (n, r, q)
    return np.swapaxes(basis, 1, 2) @ structure, wrenches @ basis


def _candidates(structure: np.ndarray):
    """What ``crossings._normals`` builds the candidate normals of ``structure`` (n, q, m) from:
    the (q - 1)-subsets of columns and the other columns of each, and, where it is the cheaper
    route, (S^+)^T and an orthonormal basis of the null space of S per pose ((n, 0, 0) else)."""
    n, q, m = structure.shape
    chosen = list(combinations(range(m), q - 1))  # one empty subset for q = 1: the normal is +-1
    subsets = np.array(chosen, dtype=np.int64).reshape(len(chosen), q - 1)
    others = np.array([[i for i in range(m) if i not in chosen] for chosen in subsets],
                      dtype=np.int64).reshape(len(subsets), m - q + 1)
    spread = null = np.empty((n, 0, 0))
    if m - q + 1 < q:  # the normals through the null space (``crossings._normals``)
        factor, triangle = np.linalg.qr(np.swapaxes(structure, 1, 2), mode="complete")
        null = np.ascontiguousarray(factor[:, :, q:])
        spread = np.linalg.solve(triangle[:, :q, :], np.swapaxes(factor[:, :, :q], 1, 2))
    return subsets, others, spread, null


def ray_reach(structure: np.ndarray, wrench: np.ndarray, directions: np.ndarray, lower: np.ndarray,
              upper: np.ndarray, tolerance: np.ndarray) -> np.ndarray:
    """(n, 2, d) the largest mu >= 0 with w + mu e_j, and w - mu e_j, in S [lower, upper], for
    full-row-rank ``structure`` (n, q, m), ``wrench`` (n, q) and ``directions`` (n, d, q) in the
    same coordinates, cable bounds (m,) (infinite sides allowed): the candidate normals'
    inequalities of hyperplane shifting, each a bound on mu along the ray (the available wrench
    set is their intersection, so the least bound is exact). NaN where w is outside by more than
    ``tolerance`` (n,); inf where no inequality bounds the ray."""
    from pipeline.model.jit import compiled_loops

    subsets, others, spread, null = _candidates(structure)
    n, d = directions.shape[:2]
    reach = np.empty((n, 2, d))
    rays = np.ascontiguousarray(np.concatenate([wrench[:, None], directions], axis=1))  # w, then each e_j
    compiled_loops("pipeline.model.crossings").largest_wrenches(
        np.ascontiguousarray(structure), spread, null, rays, subsets, others,
        np.clip(lower, -BIG, BIG).astype(float), np.clip(upper, -BIG, BIG).astype(float),
        np.ascontiguousarray(tolerance, dtype=float), reach)
    reach[reach >= BIG * 1e-3] = np.inf  # bounded only by an infinite side
    return reach


def shifted_margins(structure: np.ndarray, wrenches: np.ndarray, families) -> tuple[dict, np.ndarray]:
    """Nested capacity margins (n,) per family, least over the K required wrenches, as the LPs
    of ``pipeline.model.tensions`` define them, for full-row-rank ``structure`` (n, q, m) and
    ``wrenches`` (n, K, q); ``families`` are :class:`pipeline.model.tensions.Family`. Also (n,)
    whether a pose needs the LP after all (a crossing search that did not settle). The work per
    pose is compiled (``pipeline.model.crossings``); here the bounds are laid out for it."""
    from pipeline.model.jit import compiled_loops

    n, k, q = wrenches.shape
    m = structure.shape[2]
    subsets, others, spread, null = _candidates(structure)
    # each family's (lower, upper, scale), +-BIG for no side, laid out per pose only if it varies
    sides = [[np.clip(np.asarray(v, dtype=float), -BIG, BIG) for v in (f.lower, f.upper, f.scale)]
             for f in families]
    varies = np.array([any(v.ndim == 3 and v.shape[1] > 1 for v in side) for side in sides])
    per_pose = [any(v.ndim == 3 and v.shape[0] > 1 for v in side) for side in sides]
    fixed = np.empty((3, len(families) - sum(per_pose), k, m))
    posed = np.empty((3, sum(per_pose), n, k, m))
    where = np.empty(len(families), dtype=np.int64)
    for f, side in enumerate(sides):
        where[f] = -1 - sum(per_pose[:f]) if per_pose[f] else f - sum(per_pose[:f])
        for which, values in enumerate(side):
            if per_pose[f]:
                posed[which, -1 - where[f]] = values  # broadcast on assignment
            else:
                fixed[which, where[f]] = values[0] if values.ndim == 3 else values
    found = np.empty((len(families), n))
    least_margins = compiled_loops("pipeline.model.crossings").least_margins
    unsettled = least_margins(np.ascontiguousarray(structure), spread, null, np.ascontiguousarray(wrenches),
                              subsets, others, fixed, posed, where, varies, RELAX, BIG, found)
    return {family.name: found[f] for f, family in enumerate(families)}, unsettled

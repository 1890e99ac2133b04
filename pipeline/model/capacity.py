"""Capacity margins of the ``feasible`` tension model in closed form: hyperplane shifting.

``pipeline.model.tensions`` defines the margin of a criterion family as the LP

    max_x  s   subject to   S x = w,   L <= x <= U (earlier families),
                            lower + s c <= x <= upper - s c (this family),   s <= 1.

Here the same number is computed without an LP: the normals and their products batched over
poses with numpy, the search per pose compiled (``pipeline.model.crossings``).

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
beta_i = (Q_i - P_i) / c_i. Its crossing with n . w is found exactly by Newton's method from
the right (``pipeline.model.crossings``), after an upper bound from one line per normal. The margin is the smallest crossing over
the normals, capped by 1 and by the largest s at which every cable's interval is non-empty
(past it the support formula no longer describes an empty box).

Cost: 2 C(m, q - 1) normals x m cables per (pose, wrench, family): 56 x 8 for the CPR-8 with
forces only (q = 3), 112 x 8 with moments at a general orientation (q = 6). The number of
normals grows combinatorially; past ``MAX_NORMALS`` the caller keeps the LP.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

RELAX = 1e-9  # extra relaxation (in units of each family's scale) of earlier families' bounds
MAX_NORMALS = 2000  # 2 C(m, q - 1) candidate normals per pose beyond which the LP is cheaper
DEPENDENT_RTOL = 1e-9  # |normal| / prod |S_j| below it: the q - 1 columns are dependent
PARALLEL_RTOL = 1e-10  # |n . S_i| below this share of |S_i|: column i lies in the facet
BIG = 1e150  # an infinite side: larger than any wrench or bound, and no overflow in a sum


def candidate_normals(structure: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2 C, q) unit vectors orthogonal to each (q - 1)-subset of the columns of a stack of
    full-row-rank matrices (n, q, m), both signs, and (2 C, m) which columns each one is
    orthogonal to by construction (their n . S_i is exactly 0, not round-off of either sign).
    Subsets of (nearly) dependent columns give zero vectors (harmless: 0 <= h holds)."""
    n, q, m = structure.shape
    subsets = np.array(list(combinations(range(m), q - 1))).reshape(-1, q - 1)  # (C, q - 1)
    members = np.zeros((len(subsets), m), dtype=bool)
    members[np.arange(len(subsets))[:, None], subsets] = True
    if q == 1:
        normals = np.ones((n, 1, 1))
    else:
        columns = np.transpose(structure[:, :, subsets], (0, 2, 1, 3))  # (n, C, q, q - 1)
        if q == 3:
            normals = np.cross(columns[..., 0], columns[..., 1])
        elif q == 2:
            normals = np.stack([-columns[..., 1, 0], columns[..., 0, 0]], axis=-1)
        else:  # cofactors: the generalised cross product of q - 1 vectors in R^q
            rows = np.arange(q)
            normals = np.stack([(-1) ** j * np.linalg.det(columns[:, :, rows != j, :])
                                for j in range(q)], axis=-1)
        size = np.linalg.norm(normals, axis=-1, keepdims=True)
        volume = np.prod(np.linalg.norm(columns, axis=2), axis=-1)[..., None]  # (n, C, 1)
        # (nearly) dependent columns span no facet; their normal would be round-off's direction
        normals = np.divide(normals, size, out=np.zeros_like(normals),
                            where=size > DEPENDENT_RTOL * volume)
    return np.concatenate([normals, -normals], axis=1), np.concatenate([members, members])


def range_coordinates(structure: np.ndarray, wrenches: np.ndarray, rank: int):
    """``structure`` (n, r, m) and ``wrenches`` (n, K, r) in an orthonormal basis of the range of
    each S when its rank is below r (the wrenches must lie in that range)."""
    if rank == structure.shape[1]:
        return structure, wrenches
    basis = np.linalg.svd(structure, full_matrices=False)[0][:, :, :rank]  # (n, r, q)
    return (np.einsum("nrq,nrm->nqm", basis, structure),
            np.einsum("nrq,nkr->nkq", basis, wrenches))


def shifted_margins(structure: np.ndarray, wrenches: np.ndarray, families) -> tuple[dict, np.ndarray]:
    """Nested capacity margins (n, K) per family, as the LPs of ``pipeline.model.tensions`` define
    them, for full-row-rank ``structure`` (n, q, m) and ``wrenches`` (n, K, q); ``families``
    are :class:`pipeline.model.tensions.Family`. Also (n,) whether a pose needs the LP after all
    (a crossing search that did not settle). The search per pose is compiled
    (``pipeline.model.crossings``); the normals and their products are batched here."""
    from pipeline.model.crossings import search

    normals, members = candidate_normals(structure)
    n, k, m = wrenches.shape[0], wrenches.shape[1], structure.shape[2]
    a = normals @ structure
    # exactly 0 for the defining columns and for columns parallel to the facet within round-off
    # (coincident cable directions): a sign from round-off would open or close a facet
    flat = members[None] | (np.abs(a) <= PARALLEL_RTOL * np.linalg.norm(structure, axis=1)[:, None, :])
    a = np.ascontiguousarray(np.where(flat, 0.0, a))
    target = np.ascontiguousarray(np.swapaxes(normals @ np.swapaxes(wrenches, 1, 2), 1, 2))
    bounds = np.empty((3, len(families), n, k, m))  # lower, upper, scale; infinite sides: +-BIG
    varies = np.zeros(len(families), dtype=bool)  # bounds that change with the wrench
    for f, family in enumerate(families):
        for side, values in enumerate((family.lower, family.upper, family.scale)):
            bounds[side, f] = np.clip(values, -BIG, BIG)  # broadcast on assignment
            varies[f] |= np.ndim(values) == 3 and np.shape(values)[1] > 1
    found = np.empty((len(families), n, k))
    unsettled = search(a, target, *bounds, varies, RELAX, found)
    return {family.name: found[f] for f, family in enumerate(families)}, unsettled

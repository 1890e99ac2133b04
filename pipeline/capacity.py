"""Capacity margins of the ``feasible`` tension model in closed form: hyperplane shifting.

``pipeline.tensions`` defines the margin of a criterion family as the LP

    max_x  s   subject to   S x = w,   L <= x <= U (earlier families),
                            lower + s c <= x <= upper - s c (this family),   s <= 1.

Here the same number is computed without an LP, batched over poses with numpy.

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
beta_i = (Q_i - P_i) / c_i. Its crossing with n . w is found exactly from the breakpoints
sorted per normal and cumulative sums (no iteration). The margin is the smallest crossing over
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
FLAT_AT_ONE = 1e-6  # a cable that starts reading its own line within this of s = 1 is read as P
SETTLE_RTOL = 1e-12  # a crossing is found when h is within this share of n . w
BLOCK_ELEMENTS = 200_000  # poses x wrenches x normals x cables per block: fits in cache


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
    """Nested capacity margins (n, K) per family, as the LPs of ``pipeline.tensions`` define
    them, for full-row-rank ``structure`` (n, q, m) and ``wrenches`` (n, K, q); ``families``
    are :class:`pipeline.tensions.Family`. Also (n,) whether a pose needs the LP after all
    (a crossing search that did not settle)."""
    normals, members = candidate_normals(structure)
    n, k, m = wrenches.shape[0], wrenches.shape[1], structure.shape[2]
    step = max(1, BLOCK_ELEMENTS // (k * normals.shape[1] * m))
    margins = {f.name: np.empty((n, k)) for f in families}
    arrays = [(f.name, *(_per_pose(a, n, k, m) for a in (f.lower, f.upper, f.scale)))
              for f in families]
    unsettled = np.zeros(n, dtype=bool)
    for start in range(0, n, step):
        part = slice(start, start + step)
        found, unsettled[part] = _block(
            structure[part], wrenches[part], normals[part], members,
            [(f[0], *(a[:, part] for a in f[1:])) for f in arrays])
        for name, value in found.items():
            margins[name][part] = value
    return margins, unsettled


def _per_pose(values, n: int, k: int, m: int) -> np.ndarray:
    """A family array as (m, n, 1) when it is the same for every wrench, else (m, n, K), cables
    first (every sum over cables adds m contiguous slabs): wrench-independent bounds are then
    searched once per pose, not K times. An infinite side becomes +-BIG, which every sum and
    minimum below treats as infinite, without inf - inf."""
    values = np.clip(np.asarray(values, dtype=float), -BIG, BIG)
    values = values.reshape((1,) * (3 - values.ndim) + values.shape)
    width = 1 if values.shape[1] == 1 else k
    return np.ascontiguousarray(np.moveaxis(np.broadcast_to(values, (n, width, m)), 2, 0))


def _block(structure, wrenches, normals, members, families):
    """:func:`shifted_margins` for one block of poses; arrays are (m, n, K, N): cable, pose,
    wrench, normal."""
    m = structure.shape[2]
    a = np.einsum("ncq,nqm->mnc", normals, structure)
    # exactly 0 for the defining columns and for columns parallel to the facet within round-off
    # (coincident cable directions): a sign from round-off would open or close a facet
    flat = members.T[:, None, :] | (np.abs(a) <= PARALLEL_RTOL * np.linalg.norm(structure, axis=1).T[:, :, None])
    a = np.where(flat, 0.0, a)[:, :, None, :]  # (m, n, 1, N)
    target = np.einsum("ncq,nkq->nkc", normals, wrenches)  # (n, K, N)
    n = structure.shape[0]
    lower_prev, upper_prev = np.full((m, n, 1), -BIG), np.full((m, n, 1), BIG)
    margins, unsettled = {}, np.zeros(n, dtype=bool)
    for name, lower, upper, scale in families:
        room = np.minimum(np.minimum(upper - lower_prev, upper_prev - lower), (upper - lower) / 2)
        bound = np.minimum((room / scale).min(axis=0), 1.0)  # (n, K or 1): non-empty intervals
        s, failed = _margin(a, target, lower_prev, upper_prev, lower, upper, scale, bound)
        margins[name] = s
        unsettled |= failed
        relax = (np.minimum(s, 0.0) - RELAX) * scale if (s < 0).any() else -RELAX * scale
        lower_prev = np.maximum(lower_prev, lower + relax)
        upper_prev = np.minimum(upper_prev, upper - relax)
    return margins, unsettled


def _margin(a, target, lower_prev, upper_prev, lower, upper, scale, bound):
    """(n, K) smallest crossing of h(n, s) with n . w over the normals, at most ``bound``, and
    (n,) poses whose search did not settle.

    Every term of h satisfies min(P_i, Q_i - s c_i) <= P_i and <= Q_i - s c_i, so reading each
    cable's P_i or its line gives a line above h, whose crossing bounds the normal's from
    above; reading P_i where h does at s = 1 (beta_i >= 1) makes it exact near 1. The smallest
    of these crossings, ``start``, bounds the margin from above. Only the normals that may
    cross before it are searched, from ``start`` leftwards (:func:`_descend`): when h is the
    same for every wrench, those whose line is not exact at ``start`` (found once per pose);
    else those with h(start) below n . w."""
    weight, positive = np.abs(a), a > 0
    prev = np.where(positive, upper_prev[..., None], -lower_prev[..., None])  # P_i (m, n, ., N)
    own = np.where(positive, upper[..., None], -lower[..., None])  # Q_i
    rate = scale[..., None]
    turn = (own - prev) / rate  # beta_i
    flat = (turn >= 1.0 - FLAT_AT_ONE) | (own >= BIG)  # h reads P_i on s <= 1
    level = (weight * np.where(flat, prev, own)).sum(axis=0)  # the line: level - s slope
    slope = (weight * np.where(flat, 0.0, rate)).sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        line = np.where(slope > 0, (level - target) / slope,
                        np.where(level >= target, np.inf, -np.inf))
    s = np.minimum(line.min(axis=2), bound)  # (n, K)
    s = np.where(np.isfinite(s), s, -BIG)
    if prev.shape[2] == 1 and own.shape[2] == 1:  # where is each normal's h its line
        used = weight > 0
        lines_from = np.where(used & ~flat, turn, -np.inf).max(axis=0)  # (n, 1, N)
        flat_until = np.where(used & flat & (own < BIG), turn, np.inf).min(axis=0)
        crosses_first = (lines_from > s[..., None]) | (flat_until < s[..., None])
    else:  # h(start) itself
        support = (weight * np.minimum(prev, own - s[..., None] * rate)).sum(axis=0)
        crosses_first = support < target
    pose, wrench, normal = np.nonzero(crosses_first)
    failed = np.zeros(s.shape[0], dtype=bool)
    if len(pose):
        def rows(values):
            return values[:, pose, wrench if values.shape[2] > 1 else 0, normal if values.shape[3] > 1 else 0]

        found, settled = _descend(rows(weight), rows(prev), rows(own), rows(rate),
                                  target[pose, wrench, normal], s[pose, wrench])
        np.minimum.at(s, (pose, wrench), found)
        failed[pose[~settled]] = True
    return s, failed


def _descend(weight, prev, own, rate, target, start):
    """Newton's method from ``start`` (right of the crossing) leftwards on
    h(s) = sum_i w_i min(P_i, Q_i - s c_i), arrays (m, E): h is concave and piecewise linear,
    so each step follows the line of the current piece to the target, never passes the
    crossing, and the piece changes at most m times. Returns the crossings (E,) and whether
    each settled."""
    s = start.copy()
    settled = np.zeros(len(target), dtype=bool)
    active = np.arange(len(target))
    for _ in range(weight.shape[0] + 2):
        value = own[:, active] - s[active] * rate[:, active]
        moving = value < prev[:, active]  # this cable's own bound is the one h reads
        w = weight[:, active]
        h = (w * np.where(moving, value, prev[:, active])).sum(axis=0)
        slope = (w * np.where(moving, rate[:, active], 0.0)).sum(axis=0)
        gap = target[active] - h
        done = gap <= SETTLE_RTOL * np.maximum(np.abs(target[active]), np.abs(h))
        settled[active[done]] = True
        step = np.divide(gap, slope, out=np.full_like(gap, np.inf), where=slope > 0)
        s[active[~done]] -= step[~done]
        active = active[~done & np.isfinite(s[active])]
        if not len(active):
            break
    return s, settled

"""The compiled part of hyperplane shifting (``pipeline.model.capacity``): per pose, the
candidate normals and the least crossing of h(n, s) with n . w, for every criterion family,
over the required wrench set. One small problem per pose, in a loop compiled by numba with the
signature of ``SIGNATURES`` and cached (``pipeline.model.jit.compiled_loops``), used only by the
``feasible`` tension model. ``least_margins`` comes last: numba compiles it where it is
defined, so what it calls must be defined before it.

Per pose and family, with the earlier families' (relaxed) bounds [L_i, U_i] and this family's
[lower_i + s c_i, upper_i - s c_i], the side of cable i that h(n, s) reads is
v+_i(s) = min(U_i, upper_i - s c_i) where a_i = n . S_i > 0 and -v-_i(s) with
v-_i(s) = min(-L_i, -lower_i - s c_i) where a_i < 0, so

    h(n, s) = sum_i max(a_i, 0) v+_i(s) + max(-a_i, 0) v-_i(s)

and h(-n, s) is the same sum with v+ and v- swapped: no branch, one pass for both signs,
vectorised over the normals.

The margin is the least s at which some normal's h falls below its n . w. Search: from an
upper bound ``best`` (the cap, 1 and the largest s leaving every interval non-empty), the
normal that limited the previous pose is followed first by Newton's method (exact on a concave
piecewise linear h after at most m + 1 steps); then every normal is read at that s in one
pass. h is non-increasing in s, so a normal that holds there holds at every smaller s; the
few that do not are followed by Newton's method from the current least.

Only the least margin over the wrench set is needed (the criterion reads it), which saves work
twice: a family whose bounds are the same for every wrench reads one h per normal against
max_k n . w_k; a family whose bounds vary (the voltage) caps each wrench's search by the
running least, starting with the wrench that limited the previous pose. Per-wrench margins are
computed only where the nesting needs them: when a family's least margin is negative, each
wrench's own min(0, margin) relaxes the later families' bounds.
"""

from __future__ import annotations

import numpy as np
from numba import njit

SETTLE_RTOL = 1e-12  # a crossing is found when h is within this share of n . w
DEPENDENT_RTOL = 1e-9  # volume / product of lengths below it: a normal's vectors are dependent
PARALLEL_RTOL = 1e-10  # |n . S_i| below this share of |S_i|: column i lies in the facet
_A = "[:, :, ::1]"  # C-contiguous, three axes
SIGNATURES = {  # the signatures of the functions capacity.shifted_margins and capacity.ray_reach call
    "least_margins": f"b1[::1](f8{_A}, f8{_A}, f8{_A}, f8{_A}, i8[:, ::1], i8[:, ::1], f8[:, :, :, ::1], "
                     f"f8[:, :, :, :, ::1], i8[::1], b1[::1], f8, f8, f8[:, ::1])",
    "largest_wrenches": f"void(f8{_A}, f8{_A}, f8{_A}, f8{_A}, i8[:, ::1], i8[:, ::1], f8[::1], f8[::1], f8[::1], "
                        f"f8{_A})",
}


@njit(cache=True)
def _normals(structure, spread, null, wrenches, subsets, others, vectors, a, target):
    """Per subset c of q - 1 columns, the unit normal n_c orthogonal to them: a[c] = n_c . S_i,
    exactly 0 for the subset's columns and for columns parallel to the facet within
    PARALLEL_RTOL, and target[k, c] = n_c . w_k; zero when the columns are dependent.

    Two equivalent routes, the cheaper one taken: in wrench space, n_c is perpendicular to the
    q - 1 columns (``null`` empty); in cable space, a = S^T n_c is the vector of the row space
    of S that vanishes on the subset, i.e. supported on the d + 1 ``others`` and perpendicular
    there to the d columns of an orthonormal null-space basis ``null`` (m, d), and
    n_c = (S^+)^T a with ``spread`` = (S^+)^T (q, m). For the CPR-8 with moments (q = 6, d = 2)
    that is a 3-D cross product instead of a 6-D one."""
    q, m = structure.shape
    lengths = np.empty(m)
    for i in range(m):
        lengths[i] = np.sqrt(_dot(structure, i, structure, i, q))
    through_null = null.shape[1] > 0
    size = others.shape[1] if through_null else q
    normal = np.empty((q, 1))
    for c in range(subsets.shape[0]):
        for r in range(size):
            for j in range(size - 1):
                vectors[r, j] = null[others[c, r], j] if through_null else structure[r, subsets[c, j]]
        independent = _perpendicular(vectors, size)
        for i in range(m):
            a[c, i] = 0.0
        for d in range(q):
            normal[d, 0] = 0.0
        if through_null and independent:
            for r in range(size):
                for d in range(q):
                    normal[d, 0] += vectors[r, size - 1] * spread[d, others[c, r]]
            length = np.sqrt(_dot(normal, 0, normal, 0, q))
            for r in range(size):
                a[c, others[c, r]] = vectors[r, size - 1] / length
            for d in range(q):
                normal[d, 0] /= length
        elif independent:
            for d in range(q):
                normal[d, 0] = vectors[d, q - 1]
            for i in range(m):
                a[c, i] = _dot(normal, 0, structure, i, q)
            for j in range(q - 1):
                a[c, subsets[c, j]] = 0.0
        for i in range(m):
            if abs(a[c, i]) <= PARALLEL_RTOL * lengths[i]:
                a[c, i] = 0.0  # a sign from round-off would open or close a facet
        for k in range(wrenches.shape[0]):
            value = 0.0
            for d in range(q):
                value += normal[d, 0] * wrenches[k, d]
            target[k, c] = value


@njit(cache=True)
def _perpendicular(vectors, size):
    """Write into column size - 1 of ``vectors`` (rows :size) the unit vector perpendicular to
    its first size - 1 columns (the generalised cross product up to size 4; else Gram-Schmidt,
    twice, then the residual of the axis farthest from their span); False when their volume is
    at most DEPENDENT_RTOL times the product of their lengths (dependent vectors span no facet)."""
    last = size - 1
    if 2 <= size <= 4:  # closed forms: the (generalised) cross product of the columns
        lengths = 1.0
        for j in range(last):
            lengths *= np.sqrt(_dot(vectors, j, vectors, j, size))
        _cross(vectors, size)
        volume = np.sqrt(_dot(vectors, last, vectors, last, size))
        if volume <= DEPENDENT_RTOL * lengths:
            return False
        for d in range(size):
            vectors[d, last] /= volume
        return True
    volume, lengths = 1.0, 1.0
    for j in range(last):
        lengths *= np.sqrt(_dot(vectors, j, vectors, j, size))
        for _ in range(2):
            for prior in range(j):
                _take(vectors, j, _dot(vectors, prior, vectors, j, size), prior, size)
        length = np.sqrt(_dot(vectors, j, vectors, j, size))
        volume *= length
        for d in range(size):
            vectors[d, j] /= length if length > 0.0 else 1.0
    if volume <= DEPENDENT_RTOL * lengths:
        return False
    axis, far = 0, -1.0
    for t in range(size):
        away = 1.0
        for j in range(last):
            away -= vectors[t, j] * vectors[t, j]
        if away > far:
            axis, far = t, away
    for d in range(size):
        vectors[d, last] = 0.0
    vectors[axis, last] = 1.0
    for _ in range(2):
        for prior in range(last):
            _take(vectors, last, _dot(vectors, prior, vectors, last, size), prior, size)
    length = np.sqrt(_dot(vectors, last, vectors, last, size))
    for d in range(size):
        vectors[d, last] /= length
    return True


@njit(cache=True, inline="always")
def _cross(v, size):
    """Into column size - 1 of ``v``, the generalised cross product of its first size - 1
    columns (size 2, 3 or 4): perpendicular to them, its length their volume. Size 4 expands
    the 3 x 3 minors along the first column, with the 2 x 2 minors m_ij of the other two."""
    if size == 2:
        v[0, 1], v[1, 1] = -v[1, 0], v[0, 0]
    elif size == 3:
        x = v[1, 0] * v[2, 1] - v[2, 0] * v[1, 1]
        y = v[2, 0] * v[0, 1] - v[0, 0] * v[2, 1]
        v[2, 2] = v[0, 0] * v[1, 1] - v[1, 0] * v[0, 1]
        v[0, 2], v[1, 2] = x, y
    else:
        m01 = v[0, 1] * v[1, 2] - v[1, 1] * v[0, 2]
        m02 = v[0, 1] * v[2, 2] - v[2, 1] * v[0, 2]
        m03 = v[0, 1] * v[3, 2] - v[3, 1] * v[0, 2]
        m12 = v[1, 1] * v[2, 2] - v[2, 1] * v[1, 2]
        m13 = v[1, 1] * v[3, 2] - v[3, 1] * v[1, 2]
        m23 = v[2, 1] * v[3, 2] - v[3, 1] * v[2, 2]
        v[0, 3] = v[1, 0] * m23 - v[2, 0] * m13 + v[3, 0] * m12
        v[1, 3] = -(v[0, 0] * m23 - v[2, 0] * m03 + v[3, 0] * m02)
        v[2, 3] = v[0, 0] * m13 - v[1, 0] * m03 + v[3, 0] * m01
        v[3, 3] = -(v[0, 0] * m12 - v[1, 0] * m02 + v[2, 0] * m01)


@njit(cache=True, inline="always")
def _dot(x, i, y, j, size):
    """Column i of x . column j of y, their first ``size`` rows."""
    total = 0.0
    for d in range(size):
        total += x[d, i] * y[d, j]
    return total


@njit(cache=True, inline="always")
def _take(x, i, amount, j, size):
    """Column i of x -= amount * column j of x, their first ``size`` rows."""
    for d in range(size):
        x[d, i] -= amount * x[d, j]


@njit(cache=True)
def _crossing(a, positive, negative, high, low, earlier_lo, earlier_up, bounds, k, cap, hint, along,
              against, big):
    """(least s <= cap, settled, the normal that set it) at which h(n, s) >= n . w holds for
    every candidate: n_c against ``high[c]``, -n_c (index C + c) against ``-low[c]``; the
    family's bounds are those of wrench k. The ``hint`` normal is followed first, then every
    normal is read at that s in one pass: one that holds there holds at every smaller s, one
    that does not is followed by Newton's method from the current least."""
    count = a.shape[0]
    lo, up, c = bounds[0][k], bounds[1][k], bounds[2][k]
    best = min(cap, 1.0)
    for i in range(c.shape[0]):  # every cable's interval must stay non-empty
        room = min(min(up[i] - earlier_lo[i], earlier_up[i] - lo[i]), (up[i] - lo[i]) / 2.0) / c[i]
        best = min(best, room)
    row = hint if hint < count else hint - count
    sign = 1.0 if hint < count else -1.0
    goal = high[row] if hint < count else -low[row]
    best, settled = _descend(a[row], sign, goal, earlier_lo, earlier_up, lo, up, c, best)
    if not settled:
        return -big, False, hint
    limiting = hint
    _heights(best, positive, negative, earlier_lo, earlier_up, lo, up, c, along, against)
    for j in range(count):
        for sign, h, goal, index in ((1.0, along[j], high[j], j), (-1.0, against[j], -low[j], count + j)):
            if goal - h <= SETTLE_RTOL * max(abs(goal), abs(h)):
                continue  # also at any smaller s: h does not increase with s
            s, settled = _descend(a[j], sign, goal, earlier_lo, earlier_up, lo, up, c, best)
            if not settled:
                return -big, False, index
            if s < best:
                best, limiting = s, index
    return best, True, limiting


@njit(cache=True)
def _own_margins(a, positive, negative, target, earlier_lo, earlier_up, bounds, along, against,
                 own):
    """min(0, each wrench's margin) into ``own`` (K,) for a family whose bounds and earlier
    bounds are the same for every wrench: h is read once at s = 0 (or the room), then each
    wrench's failing normals are followed as in :func:`_crossing`. False if a search did
    not settle."""
    count = a.shape[0]
    lo, up, c = bounds[0][0], bounds[1][0], bounds[2][0]
    start = 0.0
    for i in range(c.shape[0]):
        room = min(min(up[i] - earlier_lo[i], earlier_up[i] - lo[i]), (up[i] - lo[i]) / 2.0) / c[i]
        start = min(start, room)
    _heights(start, positive, negative, earlier_lo, earlier_up, lo, up, c, along, against)
    for k in range(target.shape[0]):
        own[k] = start
        for j in range(count):
            for sign, h in ((1.0, along[j]), (-1.0, against[j])):
                goal = sign * target[k, j]
                if goal - h <= SETTLE_RTOL * max(abs(goal), abs(h)):
                    continue
                s, settled = _descend(a[j], sign, goal, earlier_lo, earlier_up, lo, up, c, own[k])
                if not settled:
                    return False
                own[k] = min(own[k], s)
    return True


@njit(cache=True)
def _heights(s, positive, negative, earlier_lo, earlier_up, lo, up, c, along, against):
    """h(n_c, s) into ``along`` and h(-n_c, s) into ``against`` for every normal: with the
    sides v+ = min(U, upper - s c), v- = min(-L, -lower - s c) of each cable,
    h(n_c) = sum_i positive_ic v+_i + negative_ic v-_i, h(-n_c) the same with v+ and v-
    swapped. The loop over normals is innermost: independent sums, vectorised by the compiler
    without reordering any of them."""
    along[:] = 0.0
    against[:] = 0.0
    for i in range(c.shape[0]):
        plus = min(earlier_up[i], up[i] - s * c[i])
        minus = min(-earlier_lo[i], -lo[i] - s * c[i])
        for j in range(along.shape[0]):
            along[j] += positive[i, j] * plus + negative[i, j] * minus
            against[j] += positive[i, j] * minus + negative[i, j] * plus


@njit(cache=True)
def _descend(row, sign, goal, earlier_lo, earlier_up, lo, up, c, s):
    """Newton's method from ``s`` (where h is below the goal) leftwards on the normal
    sign * n: (crossing, settled)."""
    for _ in range(row.shape[0] + 2):
        h, slope = 0.0, 0.0
        for i in range(row.shape[0]):
            ai = sign * row[i]
            if ai > 0.0:
                weight, prev, own = ai, earlier_up[i], up[i] - s * c[i]
            elif ai < 0.0:
                weight, prev, own = -ai, -earlier_lo[i], -lo[i] - s * c[i]
            else:
                continue
            if own < prev:
                h += weight * own
                slope += weight * c[i]
            else:
                h += weight * prev
        gap = goal - h
        if gap <= SETTLE_RTOL * max(abs(goal), abs(h)):
            return s, True
        if slope <= 0.0:
            return -np.inf, False
        s -= gap / slope
    return s, False


@njit(SIGNATURES["least_margins"], cache=True, nogil=True)
def least_margins(structure, spread, null, wrenches, subsets, others, fixed, posed, where, varies,
                  relax_rtol, big, margins):
    """Fill ``margins`` (F, n) with each family's nested capacity margin, least over the K
    wrenches, and return (n,) poses whose search did not settle. ``structure`` (n, q, m) of
    full row rank; ``spread`` (n, q, m) (S^+)^T and ``null`` (n, m, d) an orthonormal basis of
    the null space of S, or both (n, 0, 0) (see :func:`_normals`); ``wrenches`` (n, K, q);
    ``subsets`` (C, q - 1) the column subsets whose normals are the candidates (with both
    signs), ``others`` (C, d + 1) the other columns; the families' (lower, upper, scale), +-``big``
    for no side, in ``fixed`` (3, F1, K, m) for those that are the same at every pose and in
    ``posed`` (3, F2, n, K, m) for the others, family f at ``where[f]`` in fixed when >= 0, at
    -1 - where[f] in posed otherwise; ``varies`` (F,): whether a family's bounds change with the
    wrench; ``relax_rtol``: extra relaxation of earlier bounds; ``big``: the caller's infinite side
    (``capacity.BIG``), also returned, negated, by a search that did not settle."""
    n, q, m = structure.shape
    wrench_count = wrenches.shape[1]
    count = subsets.shape[0]
    families = where.shape[0]
    a = np.zeros((count, m))
    positive, negative = np.zeros((m, count)), np.zeros((m, count))  # max(+-a, 0), cable-major
    target = np.zeros((wrench_count, count))
    high, low = np.empty(count), np.empty(count)
    along, against = np.empty(count), np.empty(count)  # h(n_c, s), h(-n_c, s)
    earlier_lo, earlier_up = np.empty((wrench_count, m)), np.empty((wrench_count, m))
    own = np.empty(wrench_count)
    vectors = np.empty((max(q, m - q + 1), max(q, m - q + 1)))
    hint = np.zeros(families, dtype=np.int64)  # the normal (2 C with signs), and the wrench,
    limiting = np.zeros(families, dtype=np.int64)  # that limited the last pose: tried first
    unsettled = np.zeros(n, dtype=np.bool_)
    for p in range(n):
        _normals(structure[p], spread[p], null[p], wrenches[p], subsets, others, vectors, a, target)
        for c in range(count):
            for i in range(m):
                positive[i, c], negative[i, c] = max(a[c, i], 0.0), max(-a[c, i], 0.0)
        earlier_lo[:] = -big
        earlier_up[:] = big
        agree = True  # the earlier bounds are the same for every wrench
        for f in range(families):
            if where[f] >= 0:
                bounds = (fixed[0, where[f]], fixed[1, where[f]], fixed[2, where[f]])
            else:
                bounds = (posed[0, -1 - where[f], p], posed[1, -1 - where[f], p], posed[2, -1 - where[f], p])
            shared = agree and not varies[f]
            if shared:  # one h per normal: the largest n . w_k decides
                high[:], low[:] = target[0], target[0]
                for k in range(1, wrench_count):
                    for c in range(count):
                        high[c], low[c] = max(high[c], target[k, c]), min(low[c], target[k, c])
                least, settled, hint[f] = _crossing(
                    a, positive, negative, high, low, earlier_lo[0], earlier_up[0], bounds, np.int64(0), 1.0,
                    hint[f], along, against, big)
                unsettled[p] |= not settled
            else:  # one h per wrench, each search capped by the running least
                least, first = 1.0, limiting[f]
                for r in range(wrench_count):
                    k = first + r if first + r < wrench_count else first + r - wrench_count
                    value, settled, hint[f] = _crossing(
                        a, positive, negative, target[k], target[k], earlier_lo[k], earlier_up[k],
                        bounds, k, least, hint[f], along, against, big)
                    unsettled[p] |= not settled
                    if value < least:
                        least, limiting[f] = value, k
            margins[f, p] = least
            if f == families - 1:
                break
            own[:] = 0.0  # every wrench's margin is >= least >= 0: the same relaxation
            if least < 0.0 and shared:  # the later families relax by each wrench's own margin
                unsettled[p] |= not _own_margins(a, positive, negative, target, earlier_lo[0],
                                                 earlier_up[0], bounds, along, against, own)
            elif least < 0.0:
                for k in range(wrench_count):
                    own[k], settled, _ = _crossing(
                        a, positive, negative, target[k], target[k], earlier_lo[k], earlier_up[k],
                        bounds, k, 0.0, hint[f], along, against, big)
                    unsettled[p] |= not settled
            for k in range(wrench_count):
                relax = own[k] - relax_rtol
                lo, up, c = bounds[0][k], bounds[1][k], bounds[2][k]
                for i in range(m):
                    earlier_lo[k, i] = max(earlier_lo[k, i], lo[i] + relax * c[i])
                    earlier_up[k, i] = min(earlier_up[k, i], up[i] - relax * c[i])
            agree = agree and not varies[f] and least >= 0.0
    return unsettled


@njit(SIGNATURES["largest_wrenches"], cache=True, nogil=True)
def largest_wrenches(structure, spread, null, wrenches, subsets, others, lower, upper, tolerance, reach):
    """Fill ``reach`` (n, 2, d) with the largest mu >= 0 for which w + mu e_j (``reach[p, 0, j]``)
    and w - mu e_j (``reach[p, 1, j]``) stay in S [lower, upper]: ray shooting against every
    candidate normal's inequality n . w' <= h(n), h(n) = sum_i max(a_i lower_i, a_i upper_i),
    both signs of each normal, mu <= (h(n) - n . w) / (n . e) where n . e > 0. ``structure``
    (n, q, m) of full row rank, ``spread``, ``null``, ``subsets``, ``others`` as for
    :func:`least_margins`; ``wrenches`` (n, 1 + d, q): w, then the d directions e_j (in the same
    coordinates); ``lower``, ``upper`` (m,) the cable bounds (+-big: no side); ``tolerance`` (n,):
    how far w may stand outside an inequality and count as held (round-off). NaN where w is not
    held; a very large mu (about big) where no facet bounds the ray."""
    n, q, m = structure.shape
    count = subsets.shape[0]
    directions = wrenches.shape[1] - 1
    a = np.zeros((count, m))
    target = np.zeros((directions + 1, count))
    vectors = np.empty((max(q, m - q + 1), max(q, m - q + 1)))
    for p in range(n):
        _normals(structure[p], spread[p], null[p], wrenches[p], subsets, others, vectors, a, target)
        held = True
        for j in range(directions):
            reach[p, 0, j] = np.inf
            reach[p, 1, j] = np.inf
        for c in range(count):
            along, against = 0.0, 0.0  # h(n_c), h(-n_c)
            for i in range(m):
                if a[c, i] > 0.0:
                    along += a[c, i] * upper[i]
                    against -= a[c, i] * lower[i]
                elif a[c, i] < 0.0:
                    along += a[c, i] * lower[i]
                    against -= a[c, i] * upper[i]
            room_up = along - target[0, c]  # h(n) - n . w
            room_down = against + target[0, c]  # h(-n) + n . w
            if room_up < -tolerance[p] or room_down < -tolerance[p]:
                held = False
            room_up, room_down = max(room_up, 0.0), max(room_down, 0.0)
            for j in range(directions):
                rate = target[1 + j, c]  # n . e_j
                if rate > 0.0:
                    reach[p, 0, j] = min(reach[p, 0, j], room_up / rate)
                    reach[p, 1, j] = min(reach[p, 1, j], room_down / rate)
                elif rate < 0.0:
                    reach[p, 0, j] = min(reach[p, 0, j], room_down / -rate)
                    reach[p, 1, j] = min(reach[p, 1, j], room_up / -rate)
        if not held:
            for j in range(directions):
                reach[p, 0, j] = np.nan
                reach[p, 1, j] = np.nan

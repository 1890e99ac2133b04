"""The compiled search of hyperplane shifting (``pipeline.model.capacity``): for every pose, criterion
family and required wrench, the smallest crossing of h(n, s) with n . w over the candidate
normals. One small problem per (pose, wrench): a loop compiled by numba (cached on disk after
the first call, imported only by the ``feasible`` tension model) instead of numpy passes over
(pose, wrench, normal, cable) arrays, which cost 5x more here.

Per (pose, wrench, family), with P_i the earlier families' (relaxed) side and Q_i this family's
(``pipeline.model.capacity`` module docstring): a line per normal, reading P_i where its breakpoint
beta_i = (Q_i - P_i) / c_i is at or above 1 and Q_i - s c_i below, bounds the normal's crossing
from above and is exact between the largest beta of its lines and the smallest of its P's. The
smallest line crossing (capped by 1 and by non-empty intervals) is an upper bound ``best`` of the
margin; a normal whose line is exact at ``best`` cannot cross before it, and the others are
searched by Newton's method from ``best`` leftwards, exact on a concave piecewise linear h after
at most m + 1 steps.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pipeline.model.capacity import BIG  # an infinite side: capacity clips +-inf to it

FLAT_AT_ONE = 1e-6  # a cable whose own line starts within this of s = 1 is read as P_i
SETTLE_RTOL = 1e-12  # a crossing is found when h is within this share of n . w


@njit(cache=True)
def search(a, target, lowers, uppers, scales, varies, relax_rtol, margins):
    """Fill ``margins`` (F, n, K) with the nested capacity margins and return (n,) poses whose
    search did not settle. ``a`` (n, N, m): n . S_i per normal, exactly 0 where S_i lies in the
    facet; ``target`` (n, K, N): n . w; ``lowers``, ``uppers``, ``scales`` (F, n, K, m): the
    families in order, +-BIG for no side; ``varies`` (F,): whether a family's bounds change
    with the wrench (else its lines are drawn once per pose while the earlier bounds agree for
    every wrench); ``relax_rtol``: extra relaxation of earlier bounds."""
    n, normals, m = a.shape
    wrenches = target.shape[1]
    unsettled = np.zeros(n, dtype=np.bool_)
    earlier_lo = np.empty((wrenches, m))
    earlier_up = np.empty((wrenches, m))
    level, slope = np.empty(normals), np.empty(normals)
    lines_from, flat_until = np.empty(normals), np.empty(normals)
    for p in range(n):
        earlier_lo[:] = -BIG
        earlier_up[:] = BIG
        agree = True  # the earlier bounds are the same for every wrench
        for f in range(lowers.shape[0]):
            shared = agree and not varies[f]
            for k in range(wrenches):
                lo, up, c = lowers[f, p, k], uppers[f, p, k], scales[f, p, k]
                if k == 0 or not shared:
                    _lines(a[p], earlier_lo[k], earlier_up[k], lo, up, c,
                           level, slope, lines_from, flat_until)
                best = 1.0
                for i in range(m):  # every cable's interval must stay non-empty
                    room = min(min(up[i] - earlier_lo[k, i], earlier_up[k, i] - lo[i]),
                               (up[i] - lo[i]) / 2.0) / c[i]
                    best = min(best, room)
                for j in range(normals):
                    gap = level[j] - target[p, k, j]
                    if slope[j] > 0.0:
                        best = min(best, gap / slope[j])
                    elif gap < 0.0:
                        best = -np.inf
                if not np.isfinite(best):
                    unsettled[p] = True
                    best = -BIG
                for j in range(normals):
                    if lines_from[j] <= best <= flat_until[j]:
                        continue  # h(best) is this normal's line, at or above n . w
                    s, settled = _descend(a[p, j], target[p, k, j], earlier_lo[k], earlier_up[k],
                                          lo, up, c, best)
                    unsettled[p] |= not settled
                    best = min(best, s)
                margins[f, p, k] = best
            for k in range(wrenches):
                relax = min(margins[f, p, k], 0.0) - relax_rtol
                agree = agree and not varies[f] and margins[f, p, k] >= 0.0
                for i in range(m):
                    earlier_lo[k, i] = max(earlier_lo[k, i], lowers[f, p, k, i] + relax * scales[f, p, k, i])
                    earlier_up[k, i] = min(earlier_up[k, i], uppers[f, p, k, i] - relax * scales[f, p, k, i])
    return unsettled


@njit(cache=True, inline="always")
def _side(ai, earlier_lo, earlier_up, lo, up):
    """(|a_i|, P_i, Q_i): the sides of cable i that h(n, s) reads, the upper ones where
    a_i > 0, the negated lower ones where a_i < 0."""
    if ai > 0.0:
        return ai, earlier_up, up
    return -ai, -earlier_lo, -lo


@njit(cache=True)
def _lines(a, earlier_lo, earlier_up, lo, up, c, level, slope, lines_from, flat_until):
    """Per normal j, the line level_j - s slope_j above h(n_j, s), reading P_i for the cables
    whose breakpoint is at or above 1, and where it is exact: [lines_from_j, flat_until_j]."""
    for j in range(a.shape[0]):
        total, rate, start, stop = 0.0, 0.0, -np.inf, np.inf
        for i in range(a.shape[1]):
            if a[j, i] == 0.0:
                continue
            w, prev, own = _side(a[j, i], earlier_lo[i], earlier_up[i], lo[i], up[i])
            turn = (own - prev) / c[i]
            if own >= BIG or turn >= 1.0 - FLAT_AT_ONE:
                total += w * prev
                stop = min(stop, turn)
            else:
                total += w * own
                rate += w * c[i]
                start = max(start, turn)
        level[j], slope[j], lines_from[j], flat_until[j] = total, rate, start, stop


@njit(cache=True)
def _descend(a, target, earlier_lo, earlier_up, lo, up, c, s):
    """Newton's method from ``s`` (where h may be below the target) leftwards on
    h(s) = sum_i |a_i| min(P_i, Q_i - s c_i): (crossing, settled)."""
    for _ in range(a.shape[0] + 2):
        h, slope = 0.0, 0.0
        for i in range(a.shape[0]):
            if a[i] == 0.0:
                continue
            w, prev, own = _side(a[i], earlier_lo[i], earlier_up[i], lo[i], up[i])
            value = own - s * c[i]
            if value < prev:
                h += w * value
                slope += w * c[i]
            else:
                h += w * prev
        gap = target - h
        if gap <= SETTLE_RTOL * max(abs(target), abs(h)):
            return s, True
        if slope <= 0.0:
            return -np.inf, False
        s -= gap / slope
    return s, False

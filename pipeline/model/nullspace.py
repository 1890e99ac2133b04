"""Pulling-cable feasibility by the null space: a verdict per pose without its margin, compiled
(``pipeline.workspace.feasibility`` calls it; issue 58's fast exact test).

Per pose and required wrench, is there x with S x = w and lower <= x <= upper (S r x m of rank
r)? Gauss-Jordan elimination with complete pivoting on the rows of S (each scaled to a largest
entry of 1, which leaves the solutions unchanged) picks r pivot columns P and leaves the
d = m - r others F free: x_F = lam and x_P = c - G lam, so the cable forces are an affine image
of lam in R^d and the question is whether the polyhedron

    Q = {lam : lower_j <= c_j - G_j lam <= upper_j (j in P),  lower_F <= lam <= upper_F}

is empty. Every lower bound is finite (pulling cables), so Q lies in lam >= lower_F and has no
line: when it is non-empty it has a vertex, where d of its hyperplanes with independent normals
meet. The test enumerates those candidates (d cables out of m, each at its lower or upper side:
2^d C(m, d), 112 for eight cables in six freedoms) and stops at the first that satisfies every
bound; none does exactly when Q is empty. d = 0 is the unique x = c; d = 1 an interval.

What it cannot decide it says (-1, the caller's exact model decides those poses): a pivot below
``pivot_rtol`` (S short of rank r, or so poorly conditioned that lam's round-off could cross a
bound), a null space wider than ``MAX_FREE``, an infinite lower bound, or a vertex whose cable
forces miss S x = w by more than ``RESIDUAL_RTOL`` of |S| |x| (checked in the original units, so
a feasible verdict is backed by the forces themselves). The bounds are the caller's, relaxed by
its own tolerance; the candidates are checked with ``CHECK_RTOL`` of the size of each bound and
of the terms that form the force (c_j and each g_jf lam_f) on top, the round-off of a vertex that
lies on them: a force of a few newtons formed from terms of hundreds misses a bound it lies on by
1e-14 N, more than a share of the bound's size alone when the bound is about zero (cables that may
go slack, ``t_min = 0``, whose every vertex then failed: tests/test_feasibility.py).
"""

from __future__ import annotations

import numpy as np
from numba import njit

MAX_FREE = 3  # null spaces up to this dimension are enumerated (2^3 C(m, 3) candidates)
CHECK_RTOL = 1e-12  # a candidate's bound holds within this share of the sizes of the bound and of the force's terms
RESIDUAL_RTOL = 1e-9  # a feasible vertex's |S x - w| against |S| |x| + |w|
SIGNATURES = {
    "pulling_verdicts": "void(f8[:, :, ::1], f8[:, :, ::1], f8[::1], f8[::1], f8, i1[::1])",
}


@njit(cache=True)
def _eliminate(a, b, pivots, pivot_rtol):
    """Gauss-Jordan on ``a`` (r, m) and ``b`` (r,) in place, complete pivoting; ``pivots`` (r,)
    receives the pivot column of each row. False when a pivot falls below ``pivot_rtol``."""
    r, m = a.shape
    used = np.zeros(m, dtype=np.bool_)
    for t in range(r):
        best, row, col = -1.0, -1, -1
        for i in range(t, r):
            for j in range(m):
                if not used[j] and abs(a[i, j]) > best:
                    best, row, col = abs(a[i, j]), i, j
        if best < pivot_rtol:
            return False
        if row != t:
            for j in range(m):
                a[t, j], a[row, j] = a[row, j], a[t, j]
            b[t], b[row] = b[row], b[t]
        pivot = a[t, col]
        for j in range(m):
            a[t, j] /= pivot
        b[t] /= pivot
        for i in range(r):
            if i != t and a[i, col] != 0.0:
                factor = a[i, col]
                for j in range(m):
                    a[i, j] -= factor * a[t, j]
                b[i] -= factor * b[t]
        used[col] = True
        pivots[t] = col
    return True


@njit(cache=True)
def _affine(a, b, pivots, m):
    """x = c + g lam: ``c`` (m,), ``g`` (m, d) from the eliminated system, and the free columns
    ``free`` (d,), whose forces are lam."""
    r = a.shape[0]
    d = m - r
    free = np.empty(d, dtype=np.int64)
    pivotal = np.zeros(m, dtype=np.bool_)
    for t in range(r):
        pivotal[pivots[t]] = True
    k = 0
    for j in range(m):
        if not pivotal[j]:
            free[k] = j
            k += 1
    c = np.zeros(m)
    g = np.zeros((m, d))
    for t in range(r):
        c[pivots[t]] = b[t]
        for f in range(d):
            g[pivots[t], f] = -a[t, free[f]]
    for f in range(d):
        g[free[f], f] = 1.0
    return c, g, free


@njit(cache=True)
def _holds(x, lower, upper):
    """Whether every force lies within its bounds up to ``CHECK_RTOL`` of the bound's size."""
    for j in range(x.shape[0]):
        if x[j] < lower[j] - CHECK_RTOL * (abs(lower[j]) + abs(x[j])):
            return False
        if x[j] > upper[j] + CHECK_RTOL * (abs(upper[j]) + abs(x[j])):
            return False
    return True


@njit(cache=True)
def _solve(matrix, rhs):
    """lam of the d x d system by partial pivoting, and False when it is singular (relative to
    its rows' sizes: hyperplanes that are parallel meet nowhere)."""
    d = rhs.shape[0]
    a = matrix.copy()
    y = rhs.copy()
    for t in range(d):
        row, best = t, abs(a[t, t])
        for i in range(t + 1, d):
            if abs(a[i, t]) > best:
                row, best = i, abs(a[i, t])
        size = 0.0
        for j in range(d):
            size = max(size, abs(a[row, j]))
        if best <= 1e-12 * size or best == 0.0:
            return y, False
        if row != t:
            for j in range(d):
                a[t, j], a[row, j] = a[row, j], a[t, j]
            y[t], y[row] = y[row], y[t]
        for i in range(t + 1, d):
            factor = a[i, t] / a[t, t]
            for j in range(t, d):
                a[i, j] -= factor * a[t, j]
            y[i] -= factor * y[t]
    for t in range(d - 1, -1, -1):
        total = y[t]
        for j in range(t + 1, d):
            total -= a[t, j] * y[j]
        y[t] = total / a[t, t]
    return y, True


@njit(cache=True)
def _vertex(c, g, free, lower, upper):
    """A point of Q (the cable forces x, m) and True, else False: first the box test (each force
    over lam's own box, lower_F <= lam <= upper_F, which holds Q), then the candidates in turn (d
    cables, each at one side), the first that satisfies every bound."""
    m, d = g.shape
    x = c.copy()
    if d == 0:
        return x, _holds(x, lower, upper)
    for j in range(m):  # a force that cannot reach its bounds over lam's box: Q is empty (Q lies in that box)
        least, most, size = c[j], c[j], abs(c[j])
        for f in range(d):
            low, high = lower[free[f]], upper[free[f]]
            if not np.isfinite(high):
                least, most = -np.inf, np.inf
                break
            least += min(g[j, f] * low, g[j, f] * high)
            most += max(g[j, f] * low, g[j, f] * high)
            size += max(abs(g[j, f] * low), abs(g[j, f] * high))
        if (most < lower[j] - CHECK_RTOL * (abs(lower[j]) + size)
                or least > upper[j] + CHECK_RTOL * (abs(upper[j]) + size)):
            return x, False
    chosen = np.arange(d)
    matrix = np.empty((d, d))
    rhs = np.empty(d)
    while True:
        for sides in range(1 << d):
            finite = True
            for k in range(d):
                j = chosen[k]
                bound = upper[j] if (sides >> k) & 1 else lower[j]
                finite = finite and np.isfinite(bound)
                for f in range(d):
                    matrix[k, f] = g[j, f]
                rhs[k] = bound - c[j]
            if not finite:
                continue
            lam, regular = _solve(matrix, rhs)
            if not regular:
                break  # the d cables' hyperplanes are parallel on every side
            holds = True
            for j in range(m):  # each force, stopping at the first out of its bounds
                total, size = c[j], abs(c[j])
                for f in range(d):
                    total += g[j, f] * lam[f]
                    size += abs(g[j, f] * lam[f])
                x[j] = total
                if (total < lower[j] - CHECK_RTOL * (abs(lower[j]) + size)
                        or total > upper[j] + CHECK_RTOL * (abs(upper[j]) + size)):
                    holds = False
                    break
            if holds:
                return x, True
        k = d - 1  # the next d cables in lexicographic order
        while k >= 0 and chosen[k] == m - d + k:
            k -= 1
        if k < 0:
            return x, False
        chosen[k] += 1
        for i in range(k + 1, d):
            chosen[i] = chosen[i - 1] + 1


@njit(SIGNATURES["pulling_verdicts"], cache=True, nogil=True)
def pulling_verdicts(structure, wrenches, lower, upper, pivot_rtol, verdicts):
    """``verdicts`` (n,) of the poses of ``structure`` (n, r, m) holding every wrench of
    ``wrenches`` (n, K, r) with forces in [``lower``, ``upper``] (m,): 1 feasible, 0 not, -1
    undecided (see the module's docstring)."""
    n, r, m = structure.shape
    if m - r > MAX_FREE or m < r:
        verdicts[:] = -1
        return
    for j in range(m):
        if not np.isfinite(lower[j]):
            verdicts[:] = -1
            return
    a = np.empty((r, m))
    b = np.empty(r)
    pivots = np.empty(r, dtype=np.int64)
    for p in range(n):
        verdict = 1
        for k in range(wrenches.shape[1]):
            regular = True
            largest = 0.0
            for i in range(r):
                for j in range(m):
                    largest = max(largest, abs(structure[p, i, j]))
            for i in range(r):
                size = 0.0
                for j in range(m):
                    size = max(size, abs(structure[p, i, j]))
                if size <= pivot_rtol * largest:  # a row of round-off: the rank is the exact model's to judge
                    regular = False
                    break
                for j in range(m):
                    a[i, j] = structure[p, i, j] / size
                b[i] = wrenches[p, k, i] / size
            if not regular or not _eliminate(a, b, pivots, pivot_rtol):
                verdict = -1
                continue
            c, g, free = _affine(a, b, pivots, m)
            x, found = _vertex(c, g, free, lower, upper)
            if not found:
                verdict = 0
                break
            residual, size = 0.0, 0.0
            for i in range(r):
                total, scale = -wrenches[p, k, i], abs(wrenches[p, k, i])
                for j in range(m):
                    total += structure[p, i, j] * x[j]
                    scale += abs(structure[p, i, j] * x[j])
                residual, size = max(residual, abs(total)), max(size, scale)
            if residual > RESIDUAL_RTOL * size:
                verdict = -1
        verdicts[p] = verdict

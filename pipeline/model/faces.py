"""The compiled part of the least-norm distribution (``pipeline.model.distribution``): per
(pose, wrench) pair, the projection of the origin onto the polytope {lambda : lower_i <= y0_i +
N_i lambda <= upper_i} by enumeration of its faces' active sets, in a loop compiled by numba
with the signature of ``SIGNATURES`` and cached (``pipeline.model.jit.compiled_loops``).

For each active set A (at most d bounds, no cable twice, given by the caller), lambda_A is the
least-norm solution of N_A lambda = bound_A - y0_A: lambda_A = N_A^T c with (N_A N_A^T) c =
bound_A - y0_A, solved by Gaussian elimination with partial pivoting and skipped where the rows
N_A are dependent (a pivot below DEPENDENT_RTOL times its row's diagonal) or a bound is
infinite. A candidate no shorter than the best one so far is not checked; the others are kept
when every cable is within its bounds to the pair's tolerance. The shortest kept candidate is
the optimum (the module docstring of ``pipeline.model.distribution``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

DEPENDENT_RTOL = 1e-12  # a pivot below this share of its row's diagonal: the rows N_A are dependent
_A = "[:, :, ::1]"  # C-contiguous, three axes
SIGNATURES = {  # the signature of the function distribution.face_distribution calls
    "least_norm": f"void(f8{_A}, f8{_A}, f8{_A}, f8{_A}, f8[:, ::1], i8[:, ::1], i8[::1], b1[:, ::1], f8{_A}, "
                  f"b1[:, ::1])",
}


@njit(cache=True)
def _solve(gram, rhs, j):
    """Solve gram[:j, :j] c = rhs[:j] in place (rhs becomes c); False where dependent."""
    for col in range(j):
        pivot = col
        for row in range(col + 1, j):
            if abs(gram[row, col]) > abs(gram[pivot, col]):
                pivot = row
        if abs(gram[pivot, col]) <= DEPENDENT_RTOL * max(gram[pivot, pivot], 1e-300):
            return False
        if pivot != col:
            for i in range(j):
                gram[col, i], gram[pivot, i] = gram[pivot, i], gram[col, i]
            rhs[col], rhs[pivot] = rhs[pivot], rhs[col]
        for row in range(col + 1, j):
            factor = gram[row, col] / gram[col, col]
            for i in range(col, j):
                gram[row, i] -= factor * gram[col, i]
            rhs[row] -= factor * rhs[col]
    for col in range(j - 1, -1, -1):
        for i in range(col + 1, j):
            rhs[col] -= gram[col, i] * rhs[i]
        rhs[col] /= gram[col, col]
    return True


@njit(SIGNATURES["least_norm"], cache=True, nogil=True)
def least_norm(y0, basis, lower, upper, tolerance, cables, sizes, sides, out, found):
    """For poses p and wrenches k: out[p, k] the point y0 + N lambda of least |lambda| within
    [lower - tolerance, upper + tolerance] (y0, lower, upper (n, K, m), tolerance (n, K), basis
    N (n, m, d)), over the active sets a (``cables`` (A, d) of which the first ``sizes[a]`` count,
    ``sides`` True at an upper bound); found[p, k] False where no candidate is feasible."""
    n, k, m = y0.shape
    d = basis.shape[2]
    gram = np.empty((d, d))
    rhs = np.empty(d)
    step = np.empty(d)
    point = np.empty(m)
    for p in range(n):
        for w in range(k):
            best = np.inf
            found[p, w] = False
            for a in range(len(sizes)):
                j = sizes[a]
                usable = True
                for r in range(j):
                    c = cables[a, r]
                    bound = upper[p, w, c] if sides[a, r] else lower[p, w, c]
                    if not np.isfinite(bound):
                        usable = False
                        break
                    rhs[r] = bound - y0[p, w, c]
                    for s in range(j):
                        total = 0.0
                        for i in range(d):
                            total += basis[p, c, i] * basis[p, cables[a, s], i]
                        gram[r, s] = total
                if not usable or not _solve(gram, rhs, j):
                    continue
                length = 0.0
                for i in range(d):
                    total = 0.0
                    for r in range(j):
                        total += basis[p, cables[a, r], i] * rhs[r]
                    step[i] = total
                    length += total * total
                if length >= best:
                    continue
                inside = True
                for c in range(m):
                    value = y0[p, w, c]
                    for i in range(d):
                        value += basis[p, c, i] * step[i]
                    if value < lower[p, w, c] - tolerance[p, w] or value > upper[p, w, c] + tolerance[p, w]:
                        inside = False
                        break
                    point[c] = value
                if inside:
                    best = length
                    found[p, w] = True
                    out[p, w, :] = point

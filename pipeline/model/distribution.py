"""The tensions the ``feasible`` model writes under ``tension.distribution=min_norm`` (the
default; ``output.cables``, the tension factor of ``output.metrics``): per (pose, wrench) pair
the cable forces x of least weighted 2-norm |weights x| with S x = w and lower <= x <= upper,
as CASPR and WireX give them. ``weights`` (m,) are the tensions per unit of x (1 for the
statics' tensions, 1 / R_i for the CPR-8's shaft torques, eq. 20).

Exact by enumeration of faces (docs/model.md section 5). With y = weights x, B = S diag(1 /
weights) and the SVD of B, every y balancing w is y0 + N lambda: y0 = B^+ w (least norm) and
the columns of N (m, d) an orthonormal basis of B's null space, so |y|^2 = |y0|^2 + |lambda|^2
and the problem is the projection of the origin onto the polytope {lambda : lower_i <= y0_i +
N_i lambda <= upper_i}. That projection lies in a face, and by Caratheodory it is the least-norm
point of the affine hull of at most d of the face's constraints with independent normals: so
the answer is the feasible candidate of least norm among the least-norm solutions of N_A lambda
= bound_A - y0_A over the active sets A of at most d bounds (no cable twice). 1 + 2m + 4 C(m, 2)
sets for d = 2 (129 for eight cables), in a loop over pairs compiled by numba
(``pipeline.model.faces``) after one batched SVD.

A pair without a feasible candidate (its limits admit no x) or with more than
``MAX_ACTIVE_SETS`` sets to try (a large null space: 2^d C(m, d) grows fast) is solved by the
HiGHS route: the feasible model's LPs give a start, and where that start is a valid
distribution HiGHS's convex QP the least norm (:func:`qp_distribution`); otherwise the LPs' x
(one of their optimal vertices: not unique where the pose is infeasible) is written.
"""

from __future__ import annotations

import functools
import itertools
from math import comb

import numpy as np

from pipeline.model.highs import block_columns, solved
from pipeline.model.tensions import Family, feasible_tensions

MAX_ACTIVE_SETS = 1024  # active sets per pair beyond which HiGHS's QP solves it
FEASIBLE_RTOL = 1e-9  # a value this far outside a bound (times the bounds' scale) is on it


def face_distribution(structure: np.ndarray, wrenches: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                      weights: np.ndarray, rank: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """(x (n, K, m), found (n, K)): the least-norm forces by enumeration of faces (above, the
    loop compiled in ``pipeline.model.faces``), for ``structure`` (n, r, m) of rank ``rank``
    (n,), ``wrenches`` (n, K, r) and bounds (n, K, m). ``found`` is False where no candidate is
    feasible, where the null space is too large, or where x (clipped onto the bounds it meets)
    misses w by more than ``rtol`` |w|; x is NaN there."""
    from pipeline.model.jit import compiled_loops

    n, r, m = structure.shape
    k = wrenches.shape[1]
    lower, upper = (np.broadcast_to(a, (n, k, m)) for a in (lower, upper))
    scaled_lower, scaled_upper = np.ascontiguousarray(lower * weights), np.ascontiguousarray(upper * weights)
    y = np.full((n, k, m), np.nan)
    found = np.zeros((n, k), dtype=bool)
    for d in np.unique(m - rank):
        if _count(m, int(d)) > MAX_ACTIVE_SETS:
            continue
        poses = np.flatnonzero(m - rank == d)
        u, sigma, vt = np.linalg.svd(structure[poses] / weights, full_matrices=True)
        q = m - d
        coords = np.einsum("nri,nkr->nki", u[:, :, :q], wrenches[poses]) / sigma[:, None, :q]
        y0 = np.ascontiguousarray(np.einsum("nim,nki->nkm", vt[:, :q], coords))  # B^+ w
        basis = np.ascontiguousarray(np.swapaxes(vt[:, q:], 1, 2))  # (n_d, m, d)
        scale = np.nan_to_num(np.maximum(np.abs(scaled_lower[poses]), np.abs(scaled_upper[poses])), posinf=0.0)
        tolerance = FEASIBLE_RTOL * np.maximum(np.maximum(scale.max(axis=2), np.abs(y0).max(axis=2)), 1.0)
        chosen, held = np.empty_like(y0), np.empty(y0.shape[:2], dtype=bool)
        compiled_loops("pipeline.model.faces").least_norm(
            y0, basis, scaled_lower[poses], scaled_upper[poses], tolerance, *_active_sets(m, int(d)), chosen, held)
        y[poses], found[poses] = np.where(held[..., None], chosen, np.nan), held
    x = np.clip(y / weights, lower, upper)
    size = np.maximum(np.linalg.norm(wrenches, axis=2), 1.0)
    residual = np.linalg.norm(np.einsum("nrm,nkm->nkr", structure, np.nan_to_num(x)) - wrenches, axis=2) / size
    found &= residual <= rtol
    return np.where(found[..., None], x, np.nan), found


def _count(m: int, d: int) -> int:
    """Active sets of at most d of the 2m bounds, no cable twice."""
    return sum(comb(m, j) * 2**j for j in range(d + 1))


@functools.cache
def _active_sets(m: int, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every active set of at most d bounds, no cable twice: cables (A, d) of which the first
    sizes (A,) count, and sides (A, d), True at an upper bound."""
    rows = [(chosen, side) for j in range(d + 1) for chosen in itertools.combinations(range(m), j)
            for side in itertools.product((False, True), repeat=j)]
    cables, sides = np.zeros((len(rows), max(d, 1)), dtype=np.int64), np.zeros((len(rows), max(d, 1)), dtype=bool)
    for a, (chosen, side) in enumerate(rows):
        cables[a, :len(chosen)], sides[a, :len(side)] = chosen, side
    return cables, np.array([len(c) for c, _ in rows], dtype=np.int64), sides


QP_PAIRS = 64  # (pose, wrench) pairs per HiGHS QP: one block-diagonal problem each


def min_norm_tensions(structure: np.ndarray, pinv: np.ndarray, rank: np.ndarray, wrenches: np.ndarray,
                      families: list[Family], weights: np.ndarray, rtol: float) -> np.ndarray:
    """(n, K, m) the least-norm forces within every family's interval (above): by enumeration of
    faces, and for the pairs it leaves, the feasible model's LPs then HiGHS's QP. ``structure``
    (n, r, m), ``pinv`` and ``rank`` its S^+ and rank, ``wrenches`` (K, r) or (n, K, r)."""
    n, r, m = structure.shape
    wrenches = np.broadcast_to(wrenches, (n, *np.shape(wrenches)[-2:]))
    shape = (n, wrenches.shape[1], m)
    lower = np.max([np.broadcast_to(f.lower, shape) for f in families], axis=0)
    upper = np.min([np.broadcast_to(f.upper, shape) for f in families], axis=0)
    x, found = face_distribution(structure, wrenches, lower, upper, weights, rank, rtol)
    rest = np.flatnonzero(~found.all(axis=1))
    if len(rest):
        start = feasible_tensions(structure[rest], pinv[rest], rank[rest], wrenches[rest],
                                  [f.at(rest, n) for f in families], distribution=True)[2]
        solved = qp_distribution(structure[rest], wrenches[rest], lower[rest], upper[rest], weights, start, rtol)
        x[rest] = np.where(found[rest][..., None], x[rest], solved)
    return x


def qp_distribution(structure: np.ndarray, wrenches: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                    weights: np.ndarray, start: np.ndarray, rtol: float) -> np.ndarray:
    """(n, K, m) the forces of least weighted 2-norm |weights x| with S x = w and lower <= x <=
    upper (a convex QP per (pose, wrench) pair, HiGHS), for the pairs whose ``start`` (the LPs'
    x, (n, K, m)) is a valid distribution (within the bounds and ``rtol`` of balancing w); the
    rest keep ``start``. The result is clipped onto the bounds it meets to solver tolerance, and
    kept only where it still balances w within ``rtol``. ``structure`` (n, r, m), ``wrenches``
    (n, K, r), bounds broadcastable to (n, K, m)."""
    n, k, m = start.shape
    lower, upper = (np.broadcast_to(a, (n, k, m)) for a in (lower, upper))
    size = np.maximum(np.linalg.norm(wrenches, axis=2), 1.0)
    residual = lambda x: np.linalg.norm(np.einsum("nrm,nkm->nkr", structure, x) - wrenches, axis=2) / size  # noqa: E731
    tolerance = FEASIBLE_RTOL * np.maximum(1.0, np.nan_to_num(np.maximum(np.abs(lower), np.abs(upper)), posinf=0.0))
    valid = ((start >= lower - tolerance) & (start <= upper + tolerance)).all(axis=2) & (residual(start) <= rtol)
    out = start.copy()
    pairs = np.argwhere(valid)
    for first in range(0, len(pairs), QP_PAIRS):
        chunk = pairs[first:first + QP_PAIRS]
        solved = _qp_block(structure[chunk[:, 0]], wrenches[chunk[:, 0], chunk[:, 1]],
                           lower[chunk[:, 0], chunk[:, 1]], upper[chunk[:, 0], chunk[:, 1]], weights)
        if solved is None:  # a pair HiGHS declares infeasible at its tolerance: each alone
            solved = np.array([_qp_block(structure[[p]], wrenches[[p], [q]], lower[[p], [q]], upper[[p], [q]],
                                         weights) for p, q in chunk], dtype=object)
            solved = np.array([start[p, q] if x is None else x[0] for x, (p, q) in zip(solved, chunk)])
        out[chunk[:, 0], chunk[:, 1]] = solved
    clipped = np.clip(out, lower, upper)
    keep = residual(clipped) <= rtol
    return np.where(keep[..., None], clipped, start)


def _qp_block(structure, wrenches, lower, upper, weights):
    """min 1/2 |weights x|^2 with S_p x_p = w_p and bounds, block-diagonal over the pairs p
    (structure (P, r, m), wrenches (P, r), bounds (P, m)); (P, m), or None if HiGHS finds it
    infeasible."""
    import highspy

    count, r, m = structure.shape
    unit = float(np.max(np.abs(wrenches))) or 1.0  # forces of the order of the wrench: conditioning
    columns = count * m
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = columns, count * r
    lp.col_cost_ = np.zeros(columns)
    lp.col_lower_ = np.where(np.isfinite(lower), lower / unit, -highspy.kHighsInf).ravel()
    lp.col_upper_ = np.where(np.isfinite(upper), upper / unit, highspy.kHighsInf).ravel()
    lp.row_lower_ = lp.row_upper_ = (wrenches / unit).ravel()
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_ = block_columns(np.zeros((count, r, m)) + structure)
    hessian = highspy.HighsHessian()
    hessian.dim_ = columns
    hessian.format_ = highspy.HessianFormat.kTriangular
    hessian.start_ = np.arange(columns + 1)
    hessian.index_ = np.arange(columns)
    hessian.value_ = np.tile(np.broadcast_to(weights, (m,)) ** 2, count)
    model = highspy.HighsModel()
    model.lp_, model.hessian_ = lp, hessian
    found = solved(model)
    return None if found is None else found.reshape(count, m) * unit

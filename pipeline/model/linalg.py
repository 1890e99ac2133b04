"""Batched small linear algebra shared by the dynamics (eq. 20) and the statics (eq. 7).

Both need, for a stack of n short-and-wide matrices A (r x c, r <= c), the minimum-norm
solution of A x = b. Where A has full row rank this is A^T (A A^T)^-1 b: one r x r solve per
pose, several times cheaper than an SVD. Rank is judged by the gram ratio
det(A A^T) / prod(diag(A A^T)) in [0, 1] (Hadamard's inequality: 1 for orthogonal rows, 0 for
dependent ones) and by the rows' lengths (a row shorter than ``rtol`` times the longest is
dropped by the SVD whatever the ratio); poses below ``rtol`` go through the SVD pseudo-inverse,
which drops singular values at or below ``rtol * sigma_max``.
"""

from __future__ import annotations

import numpy as np


def gram(matrices: np.ndarray) -> np.ndarray:
    """(n, r, r) A A^T of a stack (n, r, c)."""
    return np.einsum("nik,njk->nij", matrices, matrices)


def gram_ratio(grams: np.ndarray) -> np.ndarray:
    """(n,) det(G) / prod(diag(G)) of a stack of Gram matrices, in [0, 1]."""
    scale = np.sqrt(np.einsum("nii->ni", grams))
    scale = np.where(scale > 0, scale, 1.0)  # a zero row keeps a zero row: det 0
    return np.clip(np.linalg.det(grams / scale[:, :, None] / scale[:, None, :]), 0.0, 1.0)


def batched_pinv(matrices: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """Moore-Penrose pseudo-inverse (n, c, r) of a stack (n, r, c) with r <= c, and the
    numerical rank (n,) of each matrix. Never inf or NaN, also for rank-deficient matrices."""
    n, rows, _ = matrices.shape
    grams = gram(matrices)
    diagonal = np.einsum("nii->ni", grams)
    # a row far shorter than the others (|row| <= rtol |longest|) is one the SVD drops, though
    # the gram ratio, blind to row scales, can pass it (the CPR-8's moment row about z at the
    # centre of its frame: 1e-17 against 25)
    full = (gram_ratio(grams) >= rtol) & (diagonal.min(axis=1) > rtol**2 * diagonal.max(axis=1))
    pinv = np.empty((n, matrices.shape[2], rows))
    rank = np.full(n, rows)
    if full.any():
        pinv[full] = np.transpose(np.linalg.solve(grams[full], matrices[full]), (0, 2, 1))
    if (~full).any():
        pinv[~full], rank[~full] = svd_pinv(matrices[~full], rtol)
    return pinv, rank


def svd_pinv(matrices: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pseudo-inverse and rank from an SVD, singular values <= rtol * sigma_max dropped."""
    u, sigma, vt = np.linalg.svd(matrices, full_matrices=False)
    keep = sigma > rtol * sigma[:, :1]
    inverse = np.divide(1.0, sigma, out=np.zeros_like(sigma), where=keep)
    return np.einsum("nki,nk,njk->nij", vt, inverse, u), keep.sum(axis=1)

"""Closed-form clearances between straight cables, the platform and obstacles (docs/model.md,
section "Interference"), vectorised over any leading axes.

A cable is the segment from its anchor a_i to its attachment point p + R b_i (eq. 1 of either
paper): straight, as both papers model it (no sag). Every function returns signed distances in
metres: positive is a gap, zero is contact, and a negative value is how deep one body enters the
other.
"""

from __future__ import annotations

import numpy as np


def segment_distance(p1: np.ndarray, d1: np.ndarray, p2: np.ndarray, d2: np.ndarray) -> np.ndarray:
    """The distance between segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (arrays (..., 3)).

    The closest parameters minimise q(s, t) = |r + s d1 - t d2|^2, r = p1 - p2, a convex quadratic
    with a = d1.d1, b = d1.d2, e = d2.d2, c = d1.r, f = d2.r, over the unit square. Its minimum is
    the least of its candidates: the stationary point s = (b f - c e) / D, t = (a f - b c) / D,
    D = a e - b^2, when it lies in the square, and each edge's own minimum, the other variable
    clamped: t = clamp((b s + f) / e) on s = 0 and s = 1, s = clamp((b t - c) / a) on t = 0 and
    t = 1. Every candidate is a point of both segments, so the least never falls below the
    distance. With n = d1 x d2, Binet-Cauchy's identity gives D = n.n, b f - c e = n.(d2 x r) and
    a f - b c = n.(d1 x r): no difference of nearly equal products, so the stationary point
    keeps its precision for nearly parallel segments (relative round-off eps / sin of their
    angle, where a e - b^2 loses eps / sin^2); parallel ones (D = 0) have their minimum on an
    edge. A segment of zero length is its point."""
    r = p1 - p2
    a, e, b = _dot(d1, d1), _dot(d2, d2), _dot(d1, d2)
    c, f = _dot(d1, r), _dot(d2, r)
    normal = np.cross(d1, d2)
    determinant = _dot(normal, normal)

    def distance(s, t):
        gap = r + s[..., None] * d1 - t[..., None] * d2
        return np.sqrt(_dot(gap, gap))

    with np.errstate(divide="ignore", invalid="ignore"):
        s = _dot(normal, np.cross(d2, r)) / determinant
        t = _dot(normal, np.cross(d1, r)) / determinant
        inside = (determinant > 0) & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
        least = np.where(inside, distance(np.where(inside, s, 0.0), np.where(inside, t, 0.0)), np.inf)
        for side in (np.zeros_like(a), np.ones_like(a)):
            t = np.where(e > 0, np.clip((b * side + f) / e, 0.0, 1.0), 0.0)
            s = np.where(a > 0, np.clip((b * side - c) / a, 0.0, 1.0), 0.0)
            least = np.minimum(least, np.minimum(distance(side, t), distance(s, side)))
    return least



def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...k,...k->...", u, v)

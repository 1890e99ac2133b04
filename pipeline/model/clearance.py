"""Closed-form clearances between straight cables, the platform and obstacles (docs/model.md,
section "Interference"), vectorised over any leading axes.

A cable is the segment from its anchor a_i to its attachment point p + R b_i (eq. 1 of either
paper): straight, as both papers model it (no sag). Every function returns signed distances in
metres: positive is a gap, zero is contact, and a negative value is how deep one body enters the
other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def segment_distance(p1: np.ndarray, d1: np.ndarray, p2: np.ndarray, d2: np.ndarray) -> np.ndarray:
    """The distance between segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (arrays (..., 3)):
    :func:`closest_parameters`' first part."""
    return closest_parameters(p1, d1, p2, d2)[0]


def closest_parameters(p1: np.ndarray, d1: np.ndarray, p2: np.ndarray,
                       d2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distance between segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (arrays (..., 3)),
    and the parameters s, t of its closest points.

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
        best_s, best_t = np.where(inside, s, 0.0), np.where(inside, t, 0.0)
        least = np.where(inside, distance(best_s, best_t), np.inf)
        for side in (np.zeros_like(a), np.ones_like(a)):
            t = np.where(e > 0, np.clip((b * side + f) / e, 0.0, 1.0), 0.0)
            s = np.where(a > 0, np.clip((b * side - c) / a, 0.0, 1.0), 0.0)
            for here_s, here_t in ((side, t), (s, side)):
                found = distance(here_s, here_t)
                closer = found < least
                least, best_s, best_t = (np.where(closer, found, least), np.where(closer, here_s, best_s),
                                         np.where(closer, here_t, best_t))
    return least, best_s, best_t



def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...k,...k->...", u, v)


@dataclass(frozen=True)
class Polytope:
    """A convex body as its vertices (k, 3), the unit outward normals (f, 3) and offsets (f,) of
    its faces (inside: normals . x <= offsets) and the unit directions of its edges (e, 3); a
    flat one (a plate, a segment, a point) has no faces, its separating axes come from its edges
    and its plane's normal (``plane``, (0, 3) or (1, 3))."""

    vertices: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray
    edges: np.ndarray
    plane: np.ndarray

    @classmethod
    def box(cls, lo, hi) -> "Polytope":
        """The axis-aligned box [lo, hi] (m)."""
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        corners = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        axes = np.eye(3)
        return cls(corners, np.vstack([axes, -axes]), np.concatenate([hi, -lo]), axes, np.zeros((0, 3)))

    @classmethod
    def hull(cls, points, tol: float) -> "Polytope":
        """The convex hull of ``points`` (k, 3): its faces and edges (scipy's Qhull), or, for
        points within ``tol`` of one plane, the plate they span (no faces, its outline's edges)."""
        from scipy.spatial import ConvexHull

        points = np.asarray(points, dtype=float)
        centred = points - points.mean(axis=0)
        _, sizes, frame = np.linalg.svd(centred, full_matrices=True)
        if len(points) < 4 or sizes[2] <= tol:  # a plate, a segment or a point
            flat = centred @ frame[:2].T
            if len(points) >= 3 and sizes[1] > tol:
                outline = points[ConvexHull(flat).vertices]
                edges = _unit(np.roll(outline, -1, axis=0) - outline)
                return cls(outline, np.zeros((0, 3)), np.zeros(0), edges, frame[2:3])
            ends = points[[int(np.argmin(flat[:, 0])), int(np.argmax(flat[:, 0]))]]
            edges = _unit(ends[1:] - ends[:1]) if sizes[0] > tol else np.zeros((0, 3))
            return cls(ends, np.zeros((0, 3)), np.zeros(0), edges, np.zeros((0, 3)))
        hull = ConvexHull(points)
        normals, offsets = hull.equations[:, :3], -hull.equations[:, 3]
        pairs = {tuple(sorted((int(a), int(b)))) for simplex in hull.simplices for a, b in zip(simplex, np.roll(simplex, 1))}
        edges = _unit(np.array([points[b] - points[a] for a, b in sorted(pairs)]))
        return cls(points[hull.vertices], normals, offsets, edges, np.zeros((0, 3)))


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def box_separation(vertices: np.ndarray, normals: np.ndarray, edges: np.ndarray, lo: np.ndarray,
                   hi: np.ndarray) -> np.ndarray:
    """The signed separation (m) of convex bodies from the axis-aligned box [lo, hi], by the
    separating axis theorem: the largest gap between their projections over the axes that
    decide two convex polytopes (the box's three axes, the body's face normals and every body
    edge crossed with every box axis). Positive: apart, by at most the true distance; zero:
    touching; negative: the smallest overlap over those axes, the depth of penetration.
    ``vertices`` (..., k, 3), ``normals`` (..., f, 3), ``edges`` (..., e, 3), unit vectors, any
    leading axes (poses, cables) shared by the three."""
    crossed = np.cross(edges[..., :, None, :], np.eye(3)).reshape(*edges.shape[:-2], -1, 3)
    length = np.linalg.norm(crossed, axis=-1, keepdims=True)
    crossed = np.divide(crossed, length, out=np.zeros_like(crossed), where=length > 1e-12)
    axes = np.concatenate([np.broadcast_to(np.eye(3), (*vertices.shape[:-2], 3, 3)), normals, crossed], axis=-2)
    body = np.einsum("...ad,...kd->...ak", axes, vertices)
    centre, half = (hi + lo) / 2.0, (hi - lo) / 2.0
    middle, radius = axes @ centre, np.abs(axes) @ half
    gaps = np.maximum(body.min(axis=-1) - (middle + radius), (middle - radius) - body.max(axis=-1))
    usable = np.linalg.norm(axes, axis=-1) > 0.5  # an edge parallel to a box axis crosses it into nothing
    return np.where(usable, gaps, -np.inf).max(axis=-1)


def plane_clearance(vertices: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The least signed distance (m) of ``vertices`` (..., k, 3) from the plane through ``point``
    with unit ``normal``, positive on the side it points to: a convex body's (or a segment's)
    exact clearance from the half-space behind the plane."""
    return ((vertices - point) @ normal).min(axis=-1)


@dataclass(frozen=True)
class Obstacle:
    """A fixed obstacle of the robot's cell (fixed frame, m): the axis-aligned box [lo, hi], or
    the half-space behind the plane through ``point`` (the side its unit ``normal`` points away
    from; e.g. a floor: point [0, 0, 0], normal [0, 0, 1])."""

    name: str
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None
    point: np.ndarray | None = None
    normal: np.ndarray | None = None

    def clearance(self, vertices: np.ndarray, normals: np.ndarray, edges: np.ndarray) -> np.ndarray:
        """The signed clearance (m) of convex bodies (:func:`box_separation`'s arguments) from it:
        exact for the half-space, the separating-axis gap for the box."""
        if self.normal is not None:
            return plane_clearance(vertices, self.point, self.normal)
        return box_separation(vertices, normals, edges, self.lo, self.hi)

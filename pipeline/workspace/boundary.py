"""The boundary of a feasible set as a triangulated surface, its volume and area, and the mesh as
a file (docs/model.md, "Boundary, volume and surface").

The field is each grid node's least margin (feasible where >= 0, ``pipeline.workspace.verdict``):
marching cubes (``skimage.measure.marching_cubes``) draws its zero level, linearly interpolated
between neighbouring nodes, so the surface lies between the grid's feasible and infeasible nodes
where the margins cross zero rather than on a staircase of cells. Where the feasible set meets
the searched box, the surface closes on the box's face: the grid gets a layer of infeasible
nodes whose margins put the zero crossing there (on the outermost nodes for a grid with nodes on
the faces, half a step beyond them for one of cell centres).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

LEVEL_CLIP = 1.0  # margins are relative; beyond +-1 they only bend the interpolation towards one node
MIN_MARGIN = 1e-12  # a boundary node's margin of exactly 0: its face still gets a crossing beside it
FACE_SHARE = 1e-9  # a face on the outermost nodes: the surface closes within 1e-9 of a step beyond them


def verdict_field(least: np.ndarray, feasible: np.ndarray) -> np.ndarray:
    """The field the boundary is drawn from: each pose's least margin with the sign of its verdict,
    strictly: a feasible pose's at least MIN_MARGIN (a margin of exactly 0 is common, a cable at
    its bound under ``tension=feasible``: a field of zeros has no zero crossing to draw), an
    infeasible one's below 0 even where float32 rounds it."""
    return np.where(feasible, np.maximum(least, MIN_MARGIN), np.minimum(least, -1e-30))


def boundary_mesh(field: np.ndarray, axes: tuple[np.ndarray, np.ndarray, np.ndarray],
                  lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (k, 3) in m, triangles (t, 3) vertex indices, oriented outwards) of the zero
    level of ``field`` (the grid's shape) on the grid of ``axes`` (evenly spaced, at least two
    nodes each) inside the searched box [lo, hi] (m); no feasible node: no triangle."""
    from skimage.measure import marching_cubes  # only a job that draws its boundary pays for the import

    inside = np.clip(np.asarray(field, dtype=float), -LEVEL_CLIP, LEVEL_CLIP)
    if not (inside >= 0).any():
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    steps = [float(axis[1] - axis[0]) for axis in axes]
    padded = np.full(tuple(n + 2 for n in inside.shape), -LEVEL_CLIP)
    padded[1:-1, 1:-1, 1:-1] = inside
    for k, (axis, step) in enumerate(zip(axes, steps)):
        for node, pad, gap in ((1, 0, axis[0] - lo[k]), (-2, -1, hi[k] - axis[-1])):
            # linear interpolation from margin m >= 0 to p crosses zero at m / (m - p) of a step: at the face
            share = min(max(gap / step, 0.0), 0.5)
            edge = np.take(padded, node, axis=k)[tuple(slice(1, -1) for _ in range(2))]
            level = -np.maximum(np.abs(edge), MIN_MARGIN) * (1.0 - share) / max(share, FACE_SHARE)
            index = [slice(1, -1)] * 3
            index[k] = pad
            padded[tuple(index)] = level
    # "ascent": the set of interest is where the field is above the level, so normals point out of it
    vertices, triangles, _, _ = marching_cubes(padded, level=0.0, spacing=steps, gradient_direction="ascent",
                                               allow_degenerate=False)
    origin = np.array([axis[0] - step for axis, step in zip(axes, steps)])
    return vertices + origin, triangles.astype(np.int64)


def enclosed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """The volume a closed, outward-oriented triangle mesh encloses (m^3): the divergence theorem,
    sum over triangles of v0 . (v1 x v2) / 6 (its sign checks the orientation)."""
    v0, v1, v2 = (vertices[triangles[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->", v0, np.cross(v1, v2)) / 6.0)


def surface_area(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """The area of a triangle mesh (m^2): half the norm of each triangle's edge cross product."""
    v0, v1, v2 = (vertices[triangles[:, k]] for k in range(3))
    return float(np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1).sum() / 2.0)


def write_stl(path: Path, vertices: np.ndarray, triangles: np.ndarray, title: str) -> None:
    """Binary STL: an 80-byte header (``title``), the triangle count (uint32), and per triangle its
    unit normal, three vertices (float32 each) and a zero attribute count (uint16)."""
    v0, v1, v2 = (vertices[triangles[:, k]] for k in range(3))
    normals = np.cross(v1 - v0, v2 - v0)
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0)
    record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
    rows = np.zeros(len(triangles), dtype=record)
    rows["normal"] = normals
    rows["vertices"] = np.stack([v0, v1, v2], axis=1)
    header = title.encode("ascii", "replace")[:80].ljust(80, b" ")
    with open(path, "wb") as out:
        out.write(header)
        out.write(np.uint32(len(triangles)).tobytes())
        out.write(rows.tobytes())


def write_ply(path: Path, vertices: np.ndarray, triangles: np.ndarray, title: str) -> None:
    """Binary little-endian PLY: shared vertices (float64 x, y, z) and triangles (a uint8 count and
    three int32 indices each); ``title`` as a comment."""
    header = (f"ply\nformat binary_little_endian 1.0\ncomment {title}\nelement vertex {len(vertices)}\n"
              "property double x\nproperty double y\nproperty double z\n"
              f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n")
    faces = np.zeros(len(triangles), dtype=np.dtype([("count", "u1"), ("indices", "<i4", 3)]))
    faces["count"], faces["indices"] = 3, triangles
    with open(path, "wb") as out:
        out.write(header.encode("ascii"))
        out.write(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
        out.write(faces.tobytes())

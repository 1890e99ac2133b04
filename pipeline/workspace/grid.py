"""Position grids over a robot's search box (section 3: N * N * N points of the geometric workspace).

A grid is its three axes, not its points: ``grid[start:stop]`` gives the positions of one chunk,
so a job holds one chunk's positions at a time whatever the grid's size (10^7 poses held as
axes: a few kB instead of 240 MB of positions and as much again while they were built).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Grid:
    """Positions ordered x-major then y then z: the product of ``axes`` (three 1-D arrays), or
    the listed ``points`` (n, 3) of a user's ``poses``; and the volume each point stands for.
    ``len(grid)`` is the number of points, ``grid[a:b]`` their positions (b - a, 3)."""

    cell_volume: float
    axes: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    points: np.ndarray | None = None

    @property
    def n_points(self) -> int:
        if self.points is not None:
            return len(self.points)
        return int(np.prod([len(axis) for axis in self.axes]))

    def __len__(self) -> int:
        return self.n_points

    def __getitem__(self, span: slice) -> np.ndarray:
        """The positions of the points ``span`` selects (a slice with step 1)."""
        if self.points is not None:
            return self.points[span]
        start, stop, step = span.indices(self.n_points)
        if step != 1:
            raise ValueError("a grid is read in contiguous chunks")
        if start >= stop:
            return np.empty((0, 3))
        ny, nz = len(self.axes[1]), len(self.axes[2])
        first, last = start // nz, -(-stop // nz)  # the (x, y) lines of z points the span touches
        i, j = np.divmod(np.arange(first, last), ny)
        lines = np.empty((last - first, nz, 3))  # a line is written whole: at most 2 nz points more than asked
        lines[..., 0] = self.axes[0][i][:, None]
        lines[..., 1] = self.axes[1][j][:, None]
        lines[..., 2] = self.axes[2]
        return lines.reshape(-1, 3)[start - first * nz:stop - first * nz]


def box_grid(lo: np.ndarray, hi: np.ndarray, n: int, spacing: str = "linspace") -> Grid:
    """n points per axis over the box [lo, hi].

    ``"linspace"``: both box faces included, step (hi - lo)/(n - 1).
    ``"centred"``: the centres of n equal cells, step (hi - lo)/n, faces excluded.
    Each point stands for (box volume)/n^3, so n_feasible * cell_volume is the feasible share of
    the box volume in m^3.
    """
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    if spacing == "linspace":
        axes = [np.linspace(a, b, n) for a, b in zip(lo, hi)]
    elif spacing == "centred":
        axes = [a + (b - a) * (np.arange(n) + 0.5) / n for a, b in zip(lo, hi)]
    else:
        raise ValueError(f"unknown grid spacing {spacing!r}")
    return Grid(cell_volume=float(np.prod(hi - lo)) / n**3, axes=tuple(axes))


def step_grid(lo: np.ndarray, hi: np.ndarray, step: float, spacing: str = "faces") -> Grid:
    """Points lo + k * step on every axis up to hi inclusive (``faces``; IRPM paper, section
    III: the box [-6, 6]^2 x [0, 10] m with step 0.4 m gives 31 x 31 x 26 points), or the
    centres lo + (k + 1/2) step of the cells of side ``step`` that fit in the box
    (``centres``). Each point stands for a cube of side ``step``: volume = n_feasible * step^3;
    a box flat along an axis (a planar robot's plane) has no volume (NaN)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    if spacing == "faces":
        counts, offset = np.floor((hi - lo) / step + 1e-9).astype(int) + 1, 0.0
    elif spacing == "centres":
        counts, offset = np.floor((hi - lo) / step + 1e-9).astype(int), 0.5 * step
    else:
        raise ValueError(f"unknown grid spacing {spacing!r}")
    axes = tuple(a + offset + step * np.arange(k) for a, k in zip(lo, counts))
    return Grid(cell_volume=float(step) ** 3 if (hi > lo).all() else float("nan"), axes=axes)


def listed_grid(points: np.ndarray) -> Grid:
    """The user's own poses (n, 3): no grid cell, no volume."""
    return Grid(cell_volume=float("nan"), points=np.asarray(points, dtype=float))

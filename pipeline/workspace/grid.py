"""Position grids over a robot's search box (section 3: N * N * N points of the geometric workspace)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Grid:
    """Positions (n, 3), ordered x-major then y then z, and the volume each point stands for."""

    positions: np.ndarray
    cell_volume: float

    @property
    def n_points(self) -> int:
        return self.positions.shape[0]


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
    mesh = np.meshgrid(*axes, indexing="ij")
    positions = np.column_stack([m.ravel() for m in mesh])
    return Grid(positions=positions, cell_volume=float(np.prod(hi - lo)) / n**3)


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
    axes = [a + offset + step * np.arange(k) for a, k in zip(lo, counts)]
    mesh = np.meshgrid(*axes, indexing="ij")
    positions = np.column_stack([m.ravel() for m in mesh])
    return Grid(positions=positions, cell_volume=float(step) ** 3 if (hi > lo).all() else float("nan"))

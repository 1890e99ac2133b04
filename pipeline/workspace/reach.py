"""Connected reach: the part of the feasible grid a platform reaches from its home pose without
leaving the workspace, i.e. the connected component of the feasible grid nodes that holds the
home node, neighbours sharing a face (6), also an edge (18) or also a corner (26) of their cells
(``workspace.home``, ``workspace.neighbourhood``). A feasible pose outside it is reachable only
through infeasible poses. ``pipeline.workspace.shape`` collects the grid's verdicts for it.
"""

from __future__ import annotations

import numpy as np

from pipeline.errors import ConfigError
from pipeline.workspace.grid import Grid

RANKS = {6: 1, 18: 2, 26: 3}  # neighbourhood -> scipy.ndimage.generate_binary_structure's connectivity


def connected_component(feasible: np.ndarray, home: tuple[int, int, int], neighbourhood: int) -> np.ndarray:
    """The nodes of ``feasible`` (the grid's shape) connected to the node ``home`` through
    feasible nodes (``scipy.ndimage.label``, four bytes per node); none when ``home`` is
    infeasible."""
    from scipy import ndimage  # only a job with a home pays for its import

    structure = ndimage.generate_binary_structure(3, RANKS[neighbourhood])
    labels = ndimage.label(feasible, structure=structure)[0]
    return labels == labels[home] if labels[home] else np.zeros(feasible.shape, dtype=bool)


def home_node(grid: Grid, home) -> tuple[int, int, int]:
    """The indices of the grid node nearest ``home``; ConfigError for a grid of listed poses
    (no neighbours) or a home outside the grid."""
    if grid.axes is None:
        raise ConfigError("workspace.home: the connected reach needs the robot's grid (poses=... lists poses "
                          "with no neighbours); set workspace.home=null or poses=null")
    return tuple(_nearest(axis, value, key) for axis, value, key in zip(grid.axes, home, "xyz"))


def _nearest(axis: np.ndarray, value: float, key: str) -> int:
    """The index of the node of ``axis`` nearest ``value``; ConfigError when ``value`` lies more
    than half a step outside the axis (for one node: not on it)."""
    step = float(axis[1] - axis[0]) if len(axis) > 1 else 0.0
    if not axis[0] - step / 2 - 1e-9 <= value <= axis[-1] + step / 2 + 1e-9:
        raise ConfigError(f"workspace.home: {key}={value:g} is outside the grid ({key} from {axis[0]:g} to {axis[-1]:g})")
    return int(np.clip(np.rint((value - axis[0]) / step), 0, len(axis) - 1)) if step else 0

"""The feasible set as a whole: what needs every verdict of a grid at once, collected from a job's
chunks as they stream to points.parquet: the boundary mesh with the volume and area it encloses
(``pipeline.workspace.boundary``) and the connected reach (``pipeline.workspace.reach``).

A job keeps five bytes per pose meanwhile (its verdict, and its least margin as float32 with the
verdict's sign), not its table: a grid past ``MESH_MAX_POSES`` keeps no margins and has no mesh
(its summary says NaN) unless the job asks for the mesh file (``output.mesh``).
"""

from __future__ import annotations

import logging

import numpy as np
import pyarrow as pa

from pipeline.workspace.arrow import values
from pipeline.workspace.boundary import boundary_mesh, enclosed_volume, surface_area, verdict_field
from pipeline.workspace.grid import Grid
from pipeline.workspace.reach import connected_component, home_node

log = logging.getLogger("pipeline")

MESH_MAX_POSES = 10_000_000  # 48 MB of margins; the mesh of a larger grid is asked for with output.mesh=true


def meshable(grid: Grid, angles: bool) -> str | None:
    """Why the grid's feasible set has no boundary mesh (None: it has one): listed poses have no
    neighbours, a grid of orientations no volume, a flat grid (a planar robot's) no inside."""
    if grid.axes is None:
        return "the grid is a list of poses (poses=...)"
    if angles:
        return "the grid is of orientations (a robot on a joint), whose boundary has no volume in m^3"
    if min(len(axis) for axis in grid.axes) < 2:
        return "the grid is flat (one node along an axis): its feasible set has no inside"
    return None


class GridShape:
    """Collects a job's verdicts and least margins chunk by chunk (:meth:`watching`); then the
    mesh and the home's component (:meth:`summary`), and the ``connected`` column of each chunk
    (:meth:`label`). ``box``: the searched box (lo, hi), whose feasible set's boundary is
    drawn (None: keep no margins, draw none); ``home``: the pose whose connected component is
    labelled (None: none)."""

    def __init__(self, grid: Grid, box: tuple[np.ndarray, np.ndarray] | None, home=None, neighbourhood: int = 6):
        self.grid, self.box, self.neighbourhood = grid, box, int(neighbourhood)
        self.shape = tuple(len(axis) for axis in grid.axes)
        self.home = home_node(grid, home) if home is not None else None
        self.feasible = np.zeros(grid.n_points, dtype=bool)
        self.field = np.zeros(grid.n_points, dtype=np.float32) if box is not None else None
        self.filled = 0
        self.connected: np.ndarray | None = None
        self.vertices = self.triangles = None

    def watching(self, sink):
        """``sink`` (or nothing, None) that also records each chunk's verdicts and least margins
        (the chunks come in grid order)."""
        def write(table: pa.Table) -> None:
            span = slice(self.filled, self.filled + table.num_rows)
            feasible = values(table.column("feasible"))
            self.feasible[span] = feasible
            if self.field is not None:
                least = np.min([values(table.column(name)) for name in table.column_names
                                if name.startswith("margin_")], axis=0)
                self.field[span] = verdict_field(least, feasible)
            self.filled = span.stop
            if sink is not None:
                sink(table)
        return write

    def summary(self) -> dict:
        """The boundary's ``mesh_volume_m3`` and ``mesh_surface_m2`` (NaN without margins); with a
        home, its grid node (``home_x``, ``home_y``, ``home_z``), ``n_connected``,
        ``connected_pct`` (of the grid's poses, as ``feasible_pct``) and ``connected_volume_m3``."""
        row = {"mesh_volume_m3": float("nan"), "mesh_surface_m2": float("nan")}
        if self.field is not None:
            self.vertices, self.triangles = boundary_mesh(self.field.reshape(self.shape), self.grid.axes, *self.box)
            row.update(mesh_volume_m3=enclosed_volume(self.vertices, self.triangles),
                       mesh_surface_m2=surface_area(self.vertices, self.triangles))
        if self.home is None:
            return row
        self.connected = connected_component(self.feasible.reshape(self.shape), self.home, self.neighbourhood).ravel()
        n_connected = int(np.count_nonzero(self.connected))
        node = [float(axis[i]) for axis, i in zip(self.grid.axes, self.home)]
        shown = ", ".join(f"{v:g}" for v in node)
        if not n_connected:
            log.warning("the home pose's grid node (%s) is not feasible: no pose is connected to it", shown)
        else:
            log.info("connected to the home pose (%s, %d-neighbourhood): %d of %d feasible poses", shown,
                     self.neighbourhood, n_connected, int(np.count_nonzero(self.feasible)))
        return {**row, "home_x": node[0], "home_y": node[1], "home_z": node[2], "n_connected": n_connected,
                "connected_pct": 100.0 * n_connected / self.grid.n_points,
                "connected_volume_m3": n_connected * self.grid.cell_volume}

    def label(self, table: pa.Table, start: int) -> pa.Table:
        """The chunk of rows ``start``.. with its ``connected`` column (after :meth:`summary`)."""
        return table.append_column("connected", pa.array(self.connected[start:start + table.num_rows]))


VOLUME_SPREAD_WARN = 0.05  # the two volumes' disagreement (share of the larger) past which the log says so


def volume_spread(count: float, mesh: float) -> dict:
    """``volume_spread_m3``: how far the cell count and the surface's volume disagree, the grid's
    error estimate for the volume (docs/model.md, "Boundary, volume and surface": measured on
    four robots, the converged volume lay within it of the closer one at every step with about
    ten cells or more across the feasible set); a warning past VOLUME_SPREAD_WARN of the larger."""
    spread = abs(count - mesh)
    if spread > VOLUME_SPREAD_WARN * max(count, mesh):
        log.warning("the volume is %.4g m^3 by cells and %.4g m^3 by the boundary surface, %.0f %% apart: the grid "
                    "is coarse for the volume; a finer step narrows it", count, mesh, 100 * spread / max(count, mesh))
    return {"volume_spread_m3": spread}

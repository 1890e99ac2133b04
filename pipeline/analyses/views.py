"""Interactive 3-D workspace views: a Plotly figure (JSON) beside each cloud PNG, embedded by the
HTML report (``pipeline.analyses.webpage``). Points are coloured by their limiting constraint, with every
margin on hover. A dense grid keeps all its feasible points and an evenly drawn sample of the
infeasible ones (fixed seed), so the view never hides where the workspace ends; the legend
says how many of each are shown. On a full grid the feasible set is also drawn as its boundary
surface, the job's own (``pipeline.workspace.boundary``; the feasible points then start hidden:
the legend shows them). The lost poses start hidden too wherever some pose is feasible (thousands
of their markers buried the feasible set; a click on the legend shows each criterion's), and
the robot is drawn
at one feasible pose (:func:`robot_traces`): its frame, anchors, cables and platform. A robot
whose grid is of orientations (a joint holds its platform) is shown in its angles instead.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from pipeline.model.geometry import attached_points
from pipeline.model.clearance import Polytope
from pipeline.model.pulleys import pulley_exits
from pipeline.workspace.boundary import boundary_mesh, verdict_field
from pipeline.workspace.criteria import CABLE_OBSTACLE, COLOURS, FEASIBLE_COLOUR
from pipeline.app.results import write_text

MAX_POINTS = 6000  # per panel: the page stays light with ~40 views
FEASIBLE_GROUPS = ("feasible", "connected to home", "feasible, not connected")  # the traces of feasible poses


def write_view(panels: list[tuple[pd.DataFrame, str, str | None]], title: str, invert_z: bool,
               path: Path, robot: list[dict] | None = None, box: tuple | None = None) -> Path:
    """Write the view of one cloud figure: ``panels`` as (points, verdict column, panel
    title), one 3-D scene each, side by side; ``robot``: the traces of the robot drawn in each
    scene (:func:`robot_traces`), None for none; ``box``: the searched box (lo, hi), where the
    feasible set's surface closes (None: on the outermost poses)."""
    from plotly.subplots import make_subplots

    axes = pose_axes(panels[0][0])
    fig = make_subplots(rows=1, cols=len(panels), specs=[[{"type": "scene"}] * len(panels)],
                        subplot_titles=[t or "" for _, _, t in panels], horizontal_spacing=0.02)
    for col, (points, column, _) in enumerate(panels, start=1):
        traces = _traces(points, column, legend=col == 1, axes=axes)
        surface = _surface(points, column, axes, box)
        if surface is not None:
            traces[0]["visible"] = "legendonly"  # the feasible points: the surface shows the set
            traces.insert(0, {**surface, "showlegend": col == 1})
        for trace in traces + [{**t, "showlegend": col == 1 and t.get("showlegend", True)} for t in robot or []]:
            fig.add_trace(trace, row=1, col=col)
    unit = "rad" if axes[0] == "psi" else "m"
    scene = {"xaxis_title": f"{axes[0]} ({unit})", "yaxis_title": f"{axes[1]} ({unit})",
             "zaxis_title": f"{axes[2]} ({unit})", "aspectmode": "data",
             "camera": {"eye": {"x": 1.9, "y": 1.9, "z": 1.2}}}  # far enough that no corner is cut
    if invert_z:
        scene["zaxis_autorange"] = "reversed"
    fig.update_scenes(**scene)
    fig.update_layout(title={"text": title, "font": {"size": 13}}, height=560,
                      margin={"l": 10, "r": 10, "t": 60, "b": 30}, legend={"itemsizing": "constant"})
    write_text(path, fig.to_json())
    return path


def pose_axes(points: pd.DataFrame) -> tuple[str, str, str]:
    """The columns a view places the poses by: x, y, z, or the angles psi, theta, phi when every
    pose is at the origin and the orientation varies (a grid of orientations)."""
    at_origin = not points[["x", "y", "z"]].to_numpy().any()
    turning = len(points) > 1 and (points[["psi", "theta", "phi"]].nunique() > 1).any()
    return ("psi", "theta", "phi") if at_origin and turning else ("x", "y", "z")


def _surface(points: pd.DataFrame, column: str, axes, box: tuple | None) -> dict | None:
    """:func:`boundary_of` as a Plotly mesh trace, None where there is none."""
    mesh = boundary_of(points, column, axes, box)
    if mesh is None:
        return None
    vertices, triangles = mesh
    return {"type": "mesh3d", "x": vertices[:, 0].round(5), "y": vertices[:, 1].round(5), "z": vertices[:, 2].round(5),
            "i": triangles[:, 0], "j": triangles[:, 1], "k": triangles[:, 2], "color": FEASIBLE_COLOUR,
            "opacity": 0.45, "hoverinfo": "skip", "name": f"feasible set ({int(points[column].sum())})",
            "legendgroup": "feasible"}


def boundary_of(points: pd.DataFrame, column: str, axes, box: tuple | None):
    """(vertices, triangles) of the boundary of the feasible set on a full grid (two values or
    more on every axis, one pose per node), the surface of the job's summary
    (``pipeline.workspace.boundary``): the zero level of the least margin (of the verdict alone,
    +-0.5, for a panel of other verdicts), closed on ``box``; None otherwise (a plane, a list of
    poses, no feasible pose). The interactive views and the static clouds draw it."""
    feasible = points[column].to_numpy(dtype=bool)
    counts = [points[a].nunique() for a in axes]
    if min(counts) < 2 or int(np.prod(counts)) != len(points) or not feasible.any():
        return None
    margins = [name for name in points.columns if name.startswith("margin_")] if column == "feasible" else []
    least = points[margins].min(axis=1).to_numpy() if margins else None
    field = verdict_field(least, feasible) if margins else np.where(feasible, 0.5, -0.5)
    order = np.lexsort([points[a].to_numpy() for a in reversed(axes)])  # the grid's order: first axis slowest
    nodes = tuple(np.unique(points[a].to_numpy()) for a in axes)
    lo, hi = box if box is not None and axes[0] == "x" else ([n[0] for n in nodes], [n[-1] for n in nodes])
    return boundary_mesh(field[order].reshape(counts), nodes, np.asarray(lo), np.asarray(hi))


def robot_traces(robot, position: np.ndarray, rotation: np.ndarray) -> list[dict]:
    """The robot at one pose (``position`` (3,), ``rotation`` (3, 3)): its frame (the edges of
    the anchors' bounding box), the anchors, the cables to the platform's attachment points, the
    platform (the hull of those points, or their outline when they lie in a plane) and the
    obstacles of its cell (``obstacles``: a box's edges, a plane's patch across the frame)."""
    anchors = np.asarray(robot.anchors, float)
    attached = position + attached_points(robot, rotation)
    starts = anchors if robot.pulleys is None else pulley_exits(anchors, robot.pulleys, attached[None])[0][0]
    lo, hi = anchors.min(axis=0), anchors.max(axis=0)
    traces = [_lines(Polytope.box(lo, hi).vertices, BOX_EDGES, "frame", "#9a9a9a", 2),
              {"type": "scatter3d", "mode": "markers", "name": "anchors", "legendgroup": "robot",
               "x": anchors[:, 0], "y": anchors[:, 1], "z": anchors[:, 2], "text": list(robot.cable_names),
               "marker": {"size": 3, "color": "#222222"}, "hovertemplate": "anchor %{text}<extra></extra>"},
              _lines(np.vstack([starts, attached]), [(i, i + len(anchors)) for i in range(len(anchors))],
                     f"cables at ({', '.join(f'{v:g}' for v in np.round(position, 3))}) m", "#555555", 1.5)]
    centred = attached - attached.mean(axis=0)
    if np.linalg.matrix_rank(centred, tol=1e-9 * max(1.0, float(np.abs(attached).max()))) == 3:
        traces.append({"type": "mesh3d", "x": attached[:, 0], "y": attached[:, 1], "z": attached[:, 2],
                       "alphahull": 0, "color": "#8c6d31", "opacity": 0.6, "name": "platform",
                       "legendgroup": "robot", "showlegend": True, "hoverinfo": "skip"})
    elif len(attached) > 1:
        order = np.argsort(np.arctan2(*(centred @ np.linalg.svd(centred)[2][:2].T).T[::-1]))  # around its centre
        traces.append(_lines(attached, [(int(a), int(b)) for a, b in zip(order, np.roll(order, -1))],
                             "platform", "#8c6d31", 4))
    for obstacle in robot.obstacles:
        if obstacle.normal is None:
            traces.append(_lines(Polytope.box(obstacle.lo, obstacle.hi).vertices, BOX_EDGES, obstacle.name, OBSTACLE_COLOUR, 3))
        else:  # the plane across the frame: its patch over the frame's corners seen along the normal
            basis = np.linalg.svd(obstacle.normal[None, :])[2][1:]  # two unit vectors in the plane
            spread = (Polytope.box(lo, hi).vertices - obstacle.point) @ basis.T
            low, high = spread.min(axis=0), spread.max(axis=0)
            patch = obstacle.point + np.array([[low[0], low[1]], [high[0], low[1]], [high[0], high[1]],
                                               [low[0], high[1]]]) @ basis
            traces.append(_lines(patch, [(0, 1), (1, 2), (2, 3), (3, 0)], obstacle.name, OBSTACLE_COLOUR, 3))
    return traces


BOX_EDGES = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]  # of Polytope.box's corners
OBSTACLE_COLOUR = COLOURS[CABLE_OBSTACLE]



def _lines(points: np.ndarray, pairs: list[tuple[int, int]], name: str, colour: str, width: float) -> dict:
    """One line trace of the segments ``pairs`` (indices into ``points``), gaps between them."""
    xyz = [[], [], []]
    for a, b in pairs:
        for axis in range(3):
            xyz[axis] += [float(points[a, axis]), float(points[b, axis]), None]
    return {"type": "scatter3d", "mode": "lines", "x": xyz[0], "y": xyz[1], "z": xyz[2], "name": name,
            "legendgroup": "robot", "line": {"color": colour, "width": width}, "hoverinfo": "skip"}


def _traces(points: pd.DataFrame, column: str, legend: bool, axes=("x", "y", "z")) -> list[dict]:
    feasible = points[column].to_numpy(dtype=bool)
    limiting = "limiting" + column[len("feasible"):]
    margins = [c for c in points.columns if c.startswith("margin_")]
    groups = [("feasible", points[feasible], FEASIBLE_COLOUR, "circle")]
    if column == "feasible" and "connected" in points:  # workspace.home: its component, the rest hollow
        connected = points["connected"].to_numpy(dtype=bool)
        groups = [("connected to home", points[feasible & connected], FEASIBLE_COLOUR, "circle"),
                  ("feasible, not connected", points[feasible & ~connected], FEASIBLE_COLOUR, "circle-open")]
    infeasible = points[~feasible]
    room = max(MAX_POINTS - int(feasible.sum()), 0)
    if len(infeasible) > room:
        infeasible = infeasible.iloc[np.sort(np.random.default_rng(0).choice(len(infeasible), room, replace=False))]
    if limiting in points:
        groups += [(str(name), group, COLOURS.get(str(name), "#777777"), "diamond")
                   for name, group in infeasible.groupby(limiting, observed=True)]
    else:
        groups.append(("infeasible", infeasible, "#777777", "diamond"))
    total = {name: int(count) for name, count in (
        points.loc[~feasible, limiting].astype(str).value_counts().items() if limiting in points
        else [("infeasible", int((~feasible).sum()))])}
    total.update({name: len(group) for name, group, _, _ in groups[:2] if name in FEASIBLE_GROUPS})
    traces = []
    for name, group, colour, symbol in groups:
        shown = "" if len(group) == total.get(name, len(group)) else f", {len(group)} shown"
        traces.append({
            "type": "scatter3d", "x": group[axes[0]].round(4).to_numpy(), "y": group[axes[1]].round(4).to_numpy(),
            "z": group[axes[2]].round(4).to_numpy(), "mode": "markers",
            "name": f"{name if name in FEASIBLE_GROUPS else 'lost to ' + name} ({total.get(name, len(group))}{shown})",
            "legendgroup": name, "showlegend": legend,
            **({"visible": "legendonly"} if name not in FEASIBLE_GROUPS and feasible.any() else {}),
            "marker": {"size": 2 if symbol == "diamond" else 2.5, "color": colour, "symbol": symbol},
            "customdata": group[margins].round(4).to_numpy(),
            "hovertemplate": (f"{axes[0]} %{{x}}, {axes[1]} %{{y}}, {axes[2]} %{{z}}" if axes[0] == "psi" else
                              "x %{x} m, y %{y} m, z %{z} m") + "<br>" + "<br>".join(
                f"{m[len('margin_'):]} margin %{{customdata[{i}]}}" for i, m in enumerate(margins))
            + f"<extra>{name}</extra>",
        })
    return traces

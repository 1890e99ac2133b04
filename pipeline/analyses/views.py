"""Interactive 3-D workspace views: a Plotly figure (JSON) beside each cloud PNG, embedded by the
HTML report (``pipeline.analyses.webpage``). Points are coloured by their limiting constraint, with every
margin on hover. A dense grid keeps all its feasible points and an evenly drawn sample of the
infeasible ones (fixed seed), so the view never hides where the workspace ends; the legend
says how many of each are shown.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from pipeline.workspace.criteria import COLOURS, FEASIBLE_COLOUR
from pipeline.app.results import write_text

MAX_POINTS = 6000  # per panel: the page stays light with ~40 views


def write_view(panels: list[tuple[pd.DataFrame, str, str | None]], title: str, invert_z: bool,
               path: Path) -> Path:
    """Write the view of one cloud figure: ``panels`` as (points, verdict column, panel
    title), one 3-D scene each, side by side."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    fig = make_subplots(rows=1, cols=len(panels), specs=[[{"type": "scene"}] * len(panels)],
                        subplot_titles=[t or "" for _, _, t in panels], horizontal_spacing=0.02)
    for col, (points, column, _) in enumerate(panels, start=1):
        for trace in _traces(points, column, legend=col == 1):
            fig.add_trace(go.Scatter3d(**trace), row=1, col=col)
    scene = {"xaxis_title": "x (m)", "yaxis_title": "y (m)", "zaxis_title": "z (m)",
             "aspectmode": "data"}
    if invert_z:
        scene["zaxis_autorange"] = "reversed"
    fig.update_scenes(**scene)
    fig.update_layout(title={"text": title, "font": {"size": 13}}, height=520,
                      margin={"l": 0, "r": 0, "t": 60, "b": 0}, legend={"itemsizing": "constant"})
    write_text(path, fig.to_json())
    return path


def _traces(points: pd.DataFrame, column: str, legend: bool) -> list[dict]:
    feasible = points[column].to_numpy(dtype=bool)
    limiting = "limiting" + column[len("feasible"):]
    margins = [c for c in points.columns if c.startswith("margin_")]
    groups = [("feasible", points[feasible], FEASIBLE_COLOUR, "circle")]
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
    total["feasible"] = int(feasible.sum())
    traces = []
    for name, group, colour, symbol in groups:
        shown = "" if len(group) == total.get(name, len(group)) else f", {len(group)} shown"
        traces.append({
            "x": group["x"].round(4).to_numpy(), "y": group["y"].round(4).to_numpy(),
            "z": group["z"].round(4).to_numpy(), "mode": "markers",
            "name": f"{'feasible' if name == 'feasible' else 'lost to ' + name} ({total.get(name, len(group))}{shown})",
            "legendgroup": name, "showlegend": legend,
            "marker": {"size": 2.5 if symbol == "circle" else 2, "color": colour, "symbol": symbol},
            "customdata": group[margins].round(4).to_numpy(),
            "hovertemplate": "x %{x} m, y %{y} m, z %{z} m<br>" + "<br>".join(
                f"{m[len('margin_'):]} margin %{{customdata[{i}]}}" for i, m in enumerate(margins))
            + f"<extra>{name}</extra>",
        })
    return traces

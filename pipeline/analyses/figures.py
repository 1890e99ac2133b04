"""Report figures, drawn only from a study's Parquet results (never from the kernels).

Each figure kind is a function ``(spec, results, out_dir) -> [paths]`` registered in ``KINDS``;
a study declares its figures as :class:`FigureSpec` entries (``studies/*.yaml``). Every figure
uses the shipped style ``pipeline.styles.paper`` and is drawn on a bare matplotlib ``Figure``
(Agg when saved), so reruns give identical PNG files and importing this module leaves a
notebook's pyplot backend alone. matplotlib is imported when a figure is drawn, not with this
module: a study's checks and its errors do not wait for it.
"""

from __future__ import annotations

import importlib.util
import logging
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np
import pandas as pd

from pipeline.workspace.criteria import COLOURS, FEASIBLE_COLOUR, TORQUE, VOLTAGE
from pipeline.app.config import rule
from pipeline.errors import ConfigError, one_line
from pipeline.app.results import write_csv
from pipeline.analyses.views import boundary_of, pose_axes, robot_traces, write_view
from pipeline.analyses.results import StudyResults

STYLE = "pipeline.styles.paper"
MANY_BARS = 10  # a choice bar chart with more actuators turns its labels upright
MANY_ENTRIES, LONG_ENTRY = 6, 24  # a curve's legend with more entries, or a longer one, goes beside the plot
SERIES_DIR = "series"  # beside figures/: the curves' numbers as CSV
PANEL_TITLES = {"feasible_grid": "CPR-WWA grid", "feasible": "simulated lines"}


@dataclass
class FigureSpec:
    """One declared figure. ``file`` and ``title`` may hold ``{column}`` fields (dots written as
    ``_``); ``per`` draws one file per value of a summary column or list of columns (e.g.
    ``case``), ``cloud`` one per job. ``x``, ``y``, ``value`` are summary columns or pandas
    expressions over them (dotted names in backticks); ``select`` keeps the jobs whose columns
    take the listed values; ``hline`` is a number or a summary column; ``invert_z`` draws z
    downwards; ``panels`` the feasibility columns a cloud shows side by side, or, with
    ``panels_from`` (e.g. ``tension.model``), that column's values, one job each per ``per``
    group; ``line`` the simulated line of a time series; ``caption`` what the figure shows and
    what to conclude (``{column}`` fields as in ``title``), printed under it in the report;
    ``bars`` draws a curve's categories (actuator ids) as grouped bars; ``legend`` titles a
    curve's legend (default: the ``hue`` key in words); ``table`` draws from an analysis table
    of the study (e.g. ``exact_drive``: its rows name their jobs) instead of the summary;
    ``slices`` cuts each job's grid across ``axis`` (x, y or z) at ``layers`` evenly spaced
    levels, ``paving`` each certified job's boxes the same way."""

    kind: str = rule(lambda kind: None if kind in KINDS else f"unknown kind {kind!r} (known: {', '.join(KINDS)})")
    file: str = rule(lambda file: file_error(file))
    title: Optional[str] = rule(lambda text: template_error(text), default=None)
    x: Optional[str] = rule(lambda expression: _evaluable(expression), default=None)
    y: Optional[str] = rule(lambda expression: _evaluable(expression), default=None)
    value: Optional[str] = rule(lambda expression: _evaluable(expression), default=None)
    hue: Optional[str] = None
    facet: Optional[str] = None
    hline: Optional[Any] = None
    xlabel: Optional[str] = None
    ylabel: Optional[str] = None
    per: Optional[Any] = None
    invert_z: bool = False
    panels: list[str] = field(default_factory=lambda: ["feasible"])
    panels_from: Optional[str] = None
    line: int = 0
    select: dict[str, Any] = field(default_factory=dict)
    caption: Optional[str] = rule(lambda text: template_error(text), default=None)
    bars: bool = False
    legend: Optional[str] = None
    table: Optional[str] = None
    axis: str = rule(lambda axis: None if axis in ("x", "y", "z") else "slices cut across x, y or z", default="z")
    layers: int = rule(lambda n: None if isinstance(n, int) and n >= 1 else "slices cut at 1 or more layers", default=4)

    @property
    def label(self) -> str:
        """How an error names the figure: its file, where that is one."""
        return "" if file_error(self.file) else self.file

    def check_across(self, where: str) -> None:
        if self.kind == "map" and not self.value:
            raise ConfigError(f"{where}: figures: {self.file}: a map colours the poses by a points column: "
                              "give value (e.g. value: max_payload_kg)")


def render(spec: FigureSpec, results: StudyResults, out_dir: Path) -> list[Path]:
    """Draw one declared figure (one file per ``per`` value) into ``out_dir``; returns the files."""
    import matplotlib.style

    out_dir.mkdir(parents=True, exist_ok=True)
    table = _select(results.summary if spec.table is None else results.table(spec.table), spec.select)
    groups = table.groupby(spec.per, sort=True) if spec.per else [(None, table)]
    written = []
    with matplotlib.style.context(STYLE):
        for _, part in groups:
            written.extend(KINDS[spec.kind](spec, part, results, out_dir))
    repeated = sorted({path.name for path in written if written.count(path) > 1})
    if repeated:  # each drawing replaced the one before: only the last is left
        logging.getLogger("pipeline.study").warning(
            "figures: %s: %d drawings were written to %s, each over the one before; give the file name a field "
            "that tells them apart (a swept key, {case})", spec.file, len(written) - len(set(written)) + len(repeated),
            ", ".join(repeated))
    return sorted(set(written), key=written.index)


def choice_bar(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Fig. 9: feasible share per actuator, accepted ones shaded as in Table 2, x % as a line."""
    choice = results.table("choice").sort_values("actuator")
    many = len(choice) > MANY_BARS  # a user catalogue: upright labels would overlap
    import matplotlib

    width, height = matplotlib.rcParams["figure.figsize"]
    fig = _figure(figsize=(max(width, 0.42 * len(choice)), height + (0.8 if many else 0.0)))
    ax = fig.subplots()
    colours = ["0.45" if ok else "0.82" for ok in choice["accepted"]]
    separator = " " if many else "\n"
    labels = [f"{a}{separator}{p:g} W" for a, p in zip(choice["actuator"], choice["actuator_power_W"])]
    at = np.arange(len(choice))
    bars = ax.bar(at, choice["feasible_pct"], color=colours, edgecolor="black", linewidth=0.6)
    ax.set_xticks(at, labels, rotation=90 if many else 0, fontsize=7 if many else None)
    ax.bar_label(bars, fmt="%.1f" if many else "%.2f", padding=2, fontsize=6 if many else 8,
                 rotation=90 if many else 0)
    required = float(choice["required_pct"].iloc[0])
    ax.axhline(required, color="#D55E00", linestyle="--", label=f"required x = {required:g} %")
    ax.set_ylim(0, 125 if many else 110)  # many: room for upright value labels under the legend
    _labels(ax, spec, "actuator (catalogue power)", "feasible workspace x(i_a) (%)")
    ax.legend(loc="upper right")
    return [_save(fig, spec, out_dir)]


def limiting_bar(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Share of the grid that is feasible and lost to each constraint, stacked per actuator."""
    choice = results.table("choice").sort_values("actuator")
    lost = [c for c in choice.columns if c.startswith("lost_") and c.endswith("_pct")]
    fig = _figure()
    ax = fig.subplots()
    labels = np.arange(len(choice))
    ax.set_xticks(labels, choice["actuator"].astype(str))
    bottom = choice["feasible_pct"].to_numpy()
    ax.bar(labels, bottom, color=FEASIBLE_COLOUR, label="feasible", edgecolor="black", lw=0.4)
    for column in lost:
        name = column[len("lost_"):-len("_pct")]
        share = choice[column].to_numpy()
        if share.any():
            ax.bar(labels, share, bottom=bottom, color=COLOURS.get(name),
                   label=f"lost to {name}", edgecolor="black", lw=0.4)
        bottom = bottom + share
    ax.set_ylim(0, 100)
    _labels(ax, spec, "actuator", "share of the geometric workspace grid (%)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return [_save(fig, spec, out_dir)]


def cloud(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Figs. 4, 5, 8 (CPR-8) and 5-12 (IRPM): one 3D picture per selected job, one panel per
    column of ``panels`` (e.g. the grid and the simulated verdicts side by side), or one picture
    per ``per`` group with one panel per value of ``panels_from`` listed in ``panels``; feasible
    points as dots, infeasible ones as crosses coloured by their limiting constraint when the
    job has one, the searched box outlined."""
    if spec.panels_from:
        values = table[spec.panels_from].astype(str)
        jobs = [table[values == value].iloc[0] for value in spec.panels]
        panels = [(results.points(job["job"]), "feasible",
                   f"{spec.panels_from} = {job[spec.panels_from]}: {job['n_feasible']}/{job['n_points']}")
                  for job in jobs]
        return [_cloud_figure(spec, panels, jobs[0], out_dir, results)]
    written = []
    for _, job in table.iterrows():
        points = results.points(job["job"])
        titles = [PANEL_TITLES.get(c, c) if len(spec.panels) > 1 else None for c in spec.panels]
        panels = [(points, column, title) for column, title in zip(spec.panels, titles)]
        written.append(_cloud_figure(spec, panels, job, out_dir, results))
    return written


def _robot_at_a_feasible_pose(results: StudyResults, job: pd.Series, points: pd.DataFrame, column: str) -> list[dict]:
    """The traces of the job's robot (rebuilt from the config its summary records) at the
    feasible pose nearest the feasible set's centre (any pose when none is feasible), at that
    pose's orientation; none for a grid of orientations, whose view is in angles."""
    from pipeline.app.problem import ROBOTS, surroundings
    from pipeline.model.geometry import rotation_matrices

    if pose_axes(points)[0] != "x":
        return []
    cfg = results.config(job["job"])
    robot = surroundings(cfg, ROBOTS[cfg.robot.name].build(cfg.robot))  # with its obstacles
    chosen = points[points[column].to_numpy(dtype=bool)] if points[column].any() else points
    xyz = chosen[["x", "y", "z"]].to_numpy()
    row = chosen.iloc[int(np.argmin(np.linalg.norm(xyz - xyz.mean(axis=0), axis=1)))]
    angles = row[["psi", "theta", "phi"]].to_numpy(dtype=float)[None, :]
    rotation = rotation_matrices(angles, str(cfg.orientation.convention))[0]
    return robot_traces(robot, row[["x", "y", "z"]].to_numpy(dtype=float), rotation)


def _cloud_figure(spec: FigureSpec, panels: list, job: pd.Series, out_dir: Path, results: StudyResults) -> Path:
    fig = _figure(figsize=(5.6 * len(panels), 4.6))
    robot = _robot_at_a_feasible_pose(results, job, *panels[0][:2])
    box = None
    if all(f"box.{axis}_{end}" in job for axis in "xyz" for end in ("min", "max")):
        box = tuple(np.array([job[f"box.{axis}_{end}"] for axis in "xyz"], dtype=float) for end in ("min", "max"))
    for i, (points, column, title) in enumerate(panels, start=1):
        ax = fig.add_subplot(1, len(panels), i, projection="3d")
        _cloud_panel(ax, points, column, spec.invert_z, box)
        _box(ax, job)
        _draw_robot(ax, robot)
        if title:
            ax.set_title(title, fontsize=9)
    fig.suptitle(_fill(spec.title or "", job), fontsize=10)
    png = _save(fig, spec, out_dir, job)
    if importlib.util.find_spec("plotly") is None:  # the views are the report's: its extra installs plotly
        logging.getLogger("pipeline.study").warning("no interactive view beside %s: plotly is not installed "
                                                    "(pip install 'cdpr-studies[report]')", png.name)
    else:
        write_view(panels, _fill(spec.title or "", job), spec.invert_z, png.with_suffix(".json"), robot, box)
    return png


def _draw_robot(ax, traces: list[dict]) -> None:
    """The robot's traces (:func:`pipeline.analyses.views.robot_traces`) on a matplotlib 3-D axis:
    lines as lines (gaps where the trace has None), the anchors as dots, the platform's
    attachment points as its corners."""
    for trace in traces:
        xyz = [np.array([np.nan if v is None else v for v in trace[axis]], dtype=float) for axis in "xyz"]
        if trace["type"] == "mesh3d":
            ax.scatter(*xyz, s=8, c=trace["color"], depthshade=False)
        elif trace["mode"] == "lines":
            ax.plot(*xyz, color=trace["line"]["color"], linewidth=0.5 * trace["line"]["width"])
        else:
            ax.scatter(*xyz, s=10, c=trace["marker"]["color"], depthshade=False)


def _cloud_panel(ax, points: pd.DataFrame, column: str, invert_z: bool, box: tuple | None = None) -> None:
    axes = pose_axes(points)
    feasible = points[column].to_numpy()
    mesh = boundary_of(points, column, axes, box)
    if mesh is not None:  # the feasible set's boundary, the job's own surface, under its points
        vertices, triangles = mesh
        ax.plot_trisurf(vertices[:, 0], vertices[:, 1], triangles, vertices[:, 2], color=FEASIBLE_COLOUR,
                        alpha=0.18, linewidth=0, shade=False)
    if column == "feasible" and "connected" in points:  # workspace.home: its component filled, the rest hollow
        connected = points["connected"].to_numpy()
        ax.scatter(*(points.loc[connected, c] for c in axes), s=6, c=FEASIBLE_COLOUR,
                   depthshade=False, label=f"connected to home ({connected.sum()})")
        apart = feasible & ~connected
        ax.scatter(*(points.loc[apart, c] for c in axes), s=6, facecolors="none", edgecolors=FEASIBLE_COLOUR,
                   linewidths=0.5, depthshade=False, label=f"feasible, not connected ({apart.sum()})")
    else:
        ax.scatter(*(points.loc[feasible, c] for c in axes), s=6, c=FEASIBLE_COLOUR,
                   depthshade=False, label=f"feasible ({feasible.sum()})")
    infeasible = points.loc[~feasible]
    limiting = "limiting" + column[len("feasible"):]
    if len(infeasible) <= 5000:  # dense grids: draw the feasible set only
        groups = (infeasible.groupby(limiting, observed=True) if limiting in points
                  else [("infeasible", infeasible)])
        for name, group in groups:
            ax.scatter(*(group[c] for c in axes), s=10, marker="x", linewidths=0.7,
                       c=COLOURS.get(name, "0.5"), depthshade=False,
                       label=f"{name} ({len(group)})")
    if invert_z:
        ax.invert_zaxis()
    unit = "rad" if axes[0] == "psi" else "m"
    ax.set_xlabel(f"{axes[0]} ({unit})")
    ax.set_ylabel(f"{axes[1]} ({unit})")
    ax.set_zlabel(f"{axes[2]} ({unit})")
    ax.legend(loc="upper left", fontsize=7, bbox_to_anchor=(0.0, 1.0))


def value_map(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """One 3D picture per selected job, the poses with a positive ``value`` (a points column,
    e.g. ``max_payload_kg`` of ``analysis=payload``) coloured on one scale with its bar, unbounded
    ones (inf) at its top; poses at 0 and without a value (NaN: not even the platform held) as
    small grey crosses, counted in the legend and drawn only on grids of at most 5 000 of them
    (on dense grids they would hide the coloured set); the searched box outlined, the robot drawn
    at the feasible pose nearest the feasible set's centre."""
    written = []
    for _, job in table.iterrows():
        points = results.points(job["job"])
        values = points[spec.value].to_numpy(dtype=float)
        positive, unbounded = values > 0, np.isinf(values)  # NaN compares False
        fig = _figure(figsize=(6.4, 4.8))
        ax = fig.add_subplot(1, 1, 1, projection="3d")
        finite = positive & ~unbounded
        top = float(values[finite].max()) if finite.any() else 1.0
        drawn = ax.scatter(*(points.loc[positive, c] for c in "xyz"), c=np.minimum(values[positive], top), s=8,
                           cmap="viridis", vmin=0.0, vmax=top, depthshade=False,
                           label=f"{label(spec.value)} > 0 ({positive.sum()}" + (
                               f", {unbounded.sum()} unbounded)" if unbounded.any() else ")"))
        for name, rows in (("0", values == 0), ("none", np.isnan(values))):
            if rows.any():
                shown = points.loc[rows] if (~positive).sum() <= 5000 else points.iloc[:0]
                ax.scatter(*(shown[c] for c in "xyz"), s=4, marker="x", linewidths=0.5, c="0.6",
                           depthshade=False, label=f"{name} ({rows.sum()})")
        fig.colorbar(drawn, ax=ax, shrink=0.7, pad=0.12, label=label(spec.value))
        _box(ax, job)
        _draw_robot(ax, _robot_at_a_feasible_pose(results, job, points, "feasible"))
        if spec.invert_z:
            ax.invert_zaxis()
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.legend(loc="upper left", fontsize=7, bbox_to_anchor=(0.0, 1.0))
        fig.suptitle(_fill(spec.title or "", job), fontsize=10)
        written.append(_save(fig, spec, out_dir, job))
    return written


def timeseries(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Fig. 6: shaft speed, load torque and control voltage of every cable along simulated line
    ``line`` (line 0 is O''-F''), with the actuator limits of eqs. (30), (32), (34) dashed."""
    import matplotlib

    written = []
    rows = [("theta_dot", "limit_speed", "shaft speed (rad/s)"),
            (TORQUE, "limit_torque", "load torque (N m)"),
            (VOLTAGE, "limit_voltage", "control voltage (V)")]
    for _, job in table.iterrows():
        samples = results.samples(job["job"])
        line = samples[samples["line"] == spec.line]
        if line.empty:
            raise ConfigError(f"{job['job']}: no samples of line {spec.line} (only line 0 is "
                             "written unless lines.samples=all)")
        cables = sum(c.startswith("theta_dot_") for c in samples.columns)
        fig = _figure(figsize=(6.4, 7.0))
        axes = fig.subplots(3, 1, sharex=True)
        for ax, (quantity, limit, label) in zip(axes, rows):
            for cable in range(1, cables + 1):
                ax.plot(line["t"], line[f"{quantity}_{cable}"], lw=1, label=str(cable),
                        color=matplotlib.colormaps["tab10"](cable - 1))
            for sign in (1, -1):
                ax.axhline(sign * job[limit], color="0.2", linestyle="--", lw=0.9)
            ax.set_ylabel(label)
        axes[0].legend(title="cable", ncol=cables, fontsize=7, loc="lower center",
                       bbox_to_anchor=(0.5, 1.0))
        axes[-1].set_xlabel("t (s)")
        fig.suptitle(_fill(spec.title or "", job), fontsize=10, y=1.02)
        written.append(_save(fig, spec, out_dir, job))
    return written


PATH_PANELS = (("tension", "cable tension (N)", None), (TORQUE, "motor load torque (N m)", "limit_torque"),
               (VOLTAGE, "motor voltage (V)", "limit_voltage"), ("theta_dot", "shaft speed (rad/s)", "limit_speed"))


def path_series(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """A path's samples against time (``analysis=trajectory``), one file per selected job: every
    cable's tension with ``tension.t_min``/``t_max`` dashed and, with an actuator, its motor's
    load torque, voltage and shaft speed with the limits of eqs. (30), (32), (34) dashed; the
    samples that fail shaded, the first one marked with its criterion."""
    import matplotlib

    written = []
    for _, job in table.iterrows():
        samples = results.samples(job["job"])
        if "segment" not in samples:
            raise ConfigError(f"{job['job']}: not a path's samples (kind path draws analysis=trajectory jobs)")
        cables = [c[len("speed_"):] for c in samples.columns if c.startswith("speed_")]
        panels = [panel for panel in PATH_PANELS if f"{panel[0]}_{cables[0]}" in samples]
        fig = _figure(figsize=(6.4, 1.9 * len(panels) + 0.9))
        axes = np.atleast_1d(fig.subplots(len(panels), 1, sharex=True))
        failing = ~samples["feasible"].to_numpy()
        for ax, (quantity, label, limit) in zip(axes, panels):
            for number, cable in enumerate(cables):
                ax.plot(samples["t"], samples[f"{quantity}_{cable}"], lw=1, label=cable,
                        color=matplotlib.colormaps["tab10"](number % 10))
            bounds = ([job[limit], -job[limit]] if limit else
                      [job.get(key) for key in ("tension.t_min", "tension.t_max")])
            for value in bounds:
                if isinstance(value, (int, float)) and np.isfinite(value):
                    ax.axhline(value, color="0.2", linestyle="--", lw=0.9)
            ax.fill_between(samples["t"], 0, 1, where=failing, transform=ax.get_xaxis_transform(),
                            color="#D55E00", alpha=0.12, lw=0)
            if job["first_failure_sample"] >= 0:
                ax.axvline(job["first_failure_t"], color="#D55E00", lw=1.0)
            ax.set_ylabel(label)
        if job["first_failure_sample"] >= 0:
            axes[0].annotate(f"first failure: {job['first_failure_criterion']}", (job["first_failure_t"], 1.0),
                             xycoords=("data", "axes fraction"), xytext=(3, -10), textcoords="offset points",
                             fontsize=7, color="#D55E00")
        axes[0].legend(title="cable", ncol=min(len(cables), 8), fontsize=7, loc="lower center",
                       bbox_to_anchor=(0.5, 1.0))
        axes[-1].set_xlabel("t (s)")
        fig.suptitle(_fill(spec.title or "", job), fontsize=10, y=1.0)
        written.append(_save(fig, spec, out_dir, job))
    return written


def path_view(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """A path inside its robot (``analysis=trajectory``), one 3-D picture per selected job: the
    reference point's path, green where the samples hold and red where they fail, the way-points
    as dots, and the robot (frame, anchors, cables, platform) at the first failing sample (the
    first sample when every one holds)."""
    from pipeline.analyses.views import robot_traces
    from pipeline.app.problem import ROBOTS, surroundings
    from pipeline.model.geometry import rotation_matrices

    written = []
    for _, job in table.iterrows():
        samples = results.samples(job["job"])
        if "segment" not in samples:
            raise ConfigError(f"{job['job']}: not a path's samples (kind path_view draws analysis=trajectory jobs)")
        cfg = results.config(job["job"])
        robot = surroundings(cfg, ROBOTS[cfg.robot.name].build(cfg.robot))
        at = samples.iloc[max(int(job["first_failure_sample"]), 0)]
        rotation = rotation_matrices(at[["psi", "theta", "phi"]].to_numpy(float)[None, :],
                                     str(cfg.orientation.convention))[0]
        fig = _figure(figsize=(6.0, 5.0))
        ax = fig.add_subplot(projection="3d")
        _draw_robot(ax, robot_traces(robot, at[["x", "y", "z"]].to_numpy(float), rotation))
        xyz = samples[["x", "y", "z"]].to_numpy(float)
        held = samples["feasible"].to_numpy()
        for ok, colour, label in ((True, FEASIBLE_COLOUR, "samples that hold"), (False, "#D55E00", "samples that fail")):
            path = np.where((held == ok)[:, None], xyz, np.nan)  # gaps where the other verdict holds
            if not np.isnan(path).all():
                ax.plot(*path.T, color=colour, lw=2.0, label=label)
        ends = samples.drop_duplicates("segment", keep="first")[["x", "y", "z"]].to_numpy(float)
        ax.scatter(*np.vstack([ends, xyz[-1:]]).T, s=18, c="black", depthshade=False, label="way-points")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.legend(loc="upper left", fontsize=7)
        fig.suptitle(_fill(spec.title or "", job), fontsize=10)
        written.append(_save(fig, spec, out_dir, job))
    return written


def paving_slices(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Sections of each selected certified job's boxes (``analysis=certified``) across ``axis`` at
    the middles of ``layers`` equal slabs: each box the level cuts, green where it is proven inside, red
    outside, grey undecided; the areas of the three per level as CSV in ``series/``. A planar
    robot's paving is its plane, one section."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    colours = {"inside": FEASIBLE_COLOUR, "outside": "#D55E00", "undecided": "#BBBBBB"}
    written = []
    across = [a for a in "xyz" if a != spec.axis]
    for _, job in table.iterrows():
        boxes = results.boxes(job["job"])
        low, high = boxes[f"lo_{spec.axis}"].to_numpy(float), boxes[f"hi_{spec.axis}"].to_numpy(float)
        span = high.max() - low.min()  # the levels: the middles of ``layers`` equal slabs (a plane's: its own)
        levels = low.min() + (np.arange(spec.layers) + 0.5) * span / spec.layers if span > 0 else low[:1]
        fig = _figure(figsize=(3.0 * len(levels) + 1.2, 3.3), layout="constrained")
        axes = fig.subplots(1, len(levels), squeeze=False, sharey=True)[0]
        rows = []
        for ax, level in zip(axes, levels):
            cut = boxes[(low <= level) & ((level < high) | (high == low))]
            verdicts = cut["verdict"].astype(str).to_numpy()
            u0, v0 = cut[f"lo_{across[0]}"].to_numpy(float), cut[f"lo_{across[1]}"].to_numpy(float)
            u1, v1 = cut[f"hi_{across[0]}"].to_numpy(float), cut[f"hi_{across[1]}"].to_numpy(float)
            corners = np.stack([np.stack(pair, 1) for pair in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))], 1)
            ax.add_collection(PolyCollection(corners, facecolors=[colours[v] for v in verdicts],
                                             edgecolors="white", linewidths=0.1))
            ax.set_xlim(boxes[f"lo_{across[0]}"].min(), boxes[f"hi_{across[0]}"].max())
            ax.set_ylim(boxes[f"lo_{across[1]}"].min(), boxes[f"hi_{across[1]}"].max())
            ax.set_aspect("equal")
            ax.set_title(f"{spec.axis} = {round(float(level), 3):g} m", fontsize=8)
            ax.set_xlabel(f"{across[0]} (m)")
            areas = (u1 - u0) * (v1 - v0)
            rows.append({spec.axis: float(level), **{f"{v}_m2": float(areas[verdicts == v].sum()) for v in colours}})
        axes[0].set_ylabel(f"{across[1]} (m)")
        fig.legend(handles=[Patch(color=colour, label=verdict) for verdict, colour in colours.items()],
                   loc="outside right center", fontsize=7)
        fig.suptitle(_fill(spec.title or "", job), fontsize=10)
        png = _save(fig, spec, out_dir, job)
        series = out_dir.parent / SERIES_DIR / png.with_suffix(".csv").name
        series.parent.mkdir(parents=True, exist_ok=True)
        write_csv(pd.DataFrame(rows).round(9), series)
        written += [png, series]
    return written


def survival_bar(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Issue 8: per actuator, the minimum-norm (paper) and the physically valid feasible share,
    labelled with the share of the former that survives; one panel per case and wrench rows."""
    data = results.table("survival")
    cases, rows = data["case_label"].unique(), sorted(data["wrench_rows"].unique(), reverse=True)
    fig = _figure(figsize=(4.2 * len(cases), 3.3 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), len(cases), squeeze=False, sharey=True)
    for (row, col), ax in np.ndenumerate(axes):
        part = data[(data["wrench_rows"] == rows[row]) & (data["case_label"] == cases[col])]
        part = part.sort_values("actuator")
        at = np.arange(len(part))
        ax.bar(at - 0.2, part["paper_pct"], 0.4, color="0.7", edgecolor="black", lw=0.4,
               label="pinv (paper, eq. 20)")
        bars = ax.bar(at + 0.2, part["physical_pct"], 0.4, color=FEASIBLE_COLOUR,
                      edgecolor="black", lw=0.4, label="cables only pull")
        ax.bar_label(bars, labels=[f"{v:.0f}%" if np.isfinite(v) else "–" for v in part["survive_pct"]],
                     padding=2, fontsize=7)
        ax.set_xticks(at, part["actuator"].astype(str))
        ax.set_ylim(0, 115)
        ax.set_title(f"{cases[col]}, wrench rows: {rows[row]}", fontsize=9)
        ax.set_xlabel("actuator")
    for ax in axes[:, 0]:
        ax.set_ylabel(spec.ylabel or "feasible share of the grid (%)")
    axes[0, -1].legend(loc="upper right", fontsize=7)
    if spec.title:
        fig.suptitle(spec.title, fontsize=10)
    return [_save(fig, spec, out_dir)]


def curve(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Volume (or share) versus a swept parameter, one line per ``hue`` value (Figs. 13-15)."""
    import seaborn as sns  # with scipy.stats, 0.7 s of a study's start: only where a figure needs it

    data = pd.DataFrame({"x": _column(table, spec.x), "y": _column(table, spec.y)})
    fig = _figure()
    ax = fig.subplots()
    if spec.bars:  # categories on x (actuator ids): grouped bars, no line between them
        if spec.hue:
            data[spec.hue] = table[spec.hue].astype(str).to_numpy()
        sns.barplot(data=data, x="x", y="y", hue=spec.hue, ax=ax, errorbar=None,
                    edgecolor="black", linewidth=0.4)
        ax.set_ylim(0, 1.2 * float(data["y"].max()))  # room for the legend above the bars
    elif spec.hue:  # colour and marker both vary, so coinciding lines stay distinguishable
        data[spec.hue] = table[spec.hue].astype(str).to_numpy()
        sns.lineplot(data=data, x="x", y="y", hue=spec.hue, style=spec.hue, markers=True,
                     dashes=False, ax=ax, errorbar=None)
    else:
        sns.lineplot(data=data, x="x", y="y", marker="o", ax=ax, errorbar=None)
    if spec.hline is not None:
        level = float(table[spec.hline].iloc[0]) if isinstance(spec.hline, str) else spec.hline
        ax.axhline(level, color="0.3", linestyle="--", lw=1, label=f"required {level:g}")
    if spec.hue or spec.hline is not None:
        names = data[spec.hue].unique() if spec.hue else []
        beside = len(names) > MANY_ENTRIES or any(len(str(n)) > LONG_ENTRY for n in names)  # else over the data
        ax.legend(title=spec.legend or (label(spec.hue) if spec.hue else None),
                  **({"loc": "upper left", "bbox_to_anchor": (1.01, 1.0)} if beside else
                     {"loc": "upper center", "ncol": data[spec.hue].nunique()} if spec.bars and spec.hue else {}))
    _labels(ax, spec, spec.x, spec.y, table.iloc[0])
    png = _save(fig, spec, out_dir, table.iloc[0])
    return [png, _series(data, spec, out_dir.parent / SERIES_DIR / png.with_suffix(".csv").name)]


def _series(data: pd.DataFrame, spec: FigureSpec, path: Path) -> Path:
    """A curve's numbers as CSV (``series/`` beside ``figures/``), one x column and one y
    column per ``hue`` value (``actuator_1``, ``robot_gamma_deg_30``): what DVC's plots
    (dvc.yaml) and a spreadsheet read. Column names are plain words, as Vega-Lite reads a dot
    in a field name as nesting."""
    if spec.hue:
        wide = data.pivot_table(index="x", columns=spec.hue, values="y", aggfunc="mean")
        wide.columns = [f"{_field(spec.hue)}_{_field(value)}" for value in wide.columns]
    else:
        wide = data.groupby("x")["y"].mean().to_frame(_field(spec.y))
    path.parent.mkdir(parents=True, exist_ok=True)
    write_csv(wide.rename_axis(_field(spec.x)).reset_index(), path)
    return path


def _field(text) -> str:
    if isinstance(text, str):
        try:
            text = float(text)
        except ValueError:
            return re.sub(r"\W+", "_", text).strip("_")
    return format(text, "g").replace(".", "p").replace("-", "m")


def heatmap(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """``value`` over two swept keys ``x`` and ``y``, one panel per ``facet`` value (Figs. 16-29)."""
    import seaborn as sns  # as in curve

    facets = sorted(table[spec.facet].unique()) if spec.facet else [None]
    fig = _figure(figsize=(2.6 * len(facets) + 0.8, 3.1), layout="constrained")  # no title overlap
    axes = fig.subplots(1, len(facets), squeeze=False, sharey=True)
    values = _column(table, spec.value)
    vmin, vmax = float(values.min()), float(values.max())
    if vmax == vmin:  # one value everywhere (e.g. no pose holds any of these wrenches): one colour
        vmin, vmax = vmin - 0.5, vmax + 0.5
    for ax, facet in zip(axes[0], facets):
        part = table if facet is None else table[table[spec.facet] == facet]
        grid = pd.DataFrame({"x": _column(part, spec.x), "y": _column(part, spec.y),
                             "v": _column(part, spec.value)}).pivot_table(
            index="y", columns="x", values="v", aggfunc="first").sort_index(ascending=False)
        grid = grid.rename(index="{:g}".format, columns="{:g}".format)
        sns.heatmap(grid, ax=ax, vmin=vmin, vmax=vmax, cmap="viridis", annot=True, fmt=".0f",
                    annot_kws={"fontsize": 6}, cbar=ax is axes[0][-1], square=False)
        ax.set_title("" if facet is None else f"{label(spec.facet)} = {facet:g}", fontsize=8)
        ax.set_xlabel(spec.xlabel or spec.x)
        ax.set_ylabel(spec.ylabel or spec.y if ax is axes[0][0] else "")
    if spec.title:
        fig.suptitle(_fill(spec.title, table.iloc[0])
                     + (f" (every value {float(values.iloc[0]):g})" if values.nunique() == 1 else ""),
                     fontsize=10)
    return [_save(fig, spec, out_dir, table.iloc[0])]


def pareto(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """An optimise study's trials (``x``, ``y`` objectives): those that meet the requirement
    coloured by ``hue`` (the actuator), the others as grey crosses, the Pareto front joined."""
    fig = _figure()
    ax = fig.subplots()
    missed = table[~table["meets"]]
    ax.scatter(missed[spec.x], missed[spec.y], marker="x", s=14, color="0.75", lw=0.8,
               label=f"below the requirement ({len(missed)})")
    met = table[table["meets"]]
    for value, part in met.groupby(spec.hue, sort=True):
        ax.scatter(part[spec.x], part[spec.y], s=18, label=f"{label(spec.hue)} {value} ({len(part)})")
    front = met[met["pareto"]].sort_values(spec.x)
    ax.plot(front[spec.x], front[spec.y], color="black", lw=1, drawstyle="steps-post",
            label=f"Pareto front ({len(front)})")
    ax.legend(fontsize=7)
    _labels(ax, spec, spec.x, spec.y)
    return [_save(fig, spec, out_dir)]


def slices(spec: FigureSpec, table: pd.DataFrame, results: StudyResults, out_dir: Path) -> list[Path]:
    """Sections of each selected job's grid across ``axis`` at ``layers`` evenly spaced levels
    (both ends included), side by side: the least margin over the criteria in each cell, green
    where the pose is feasible and red where it is not (clipped to +-1: a margin is a share of its
    limit), and the workspace's boundary, its 0 contour, as a black line; the numbers as CSV in
    ``series/`` (one row per pose of the layers drawn)."""
    written = []
    across = [a for a in "xyz" if a != spec.axis]
    for _, job in table.iterrows():
        points = results.points(job["job"])
        least = points.filter(like="margin_").min(axis=1).clip(-1.0, 1.0)
        levels = np.sort(points[spec.axis].unique())
        picked = levels[np.unique(np.linspace(0, len(levels) - 1, min(spec.layers, len(levels))).round().astype(int))]
        fig = _figure(figsize=(3.0 * len(picked) + 1.2, 3.3), layout="constrained")
        axes = fig.subplots(1, len(picked), squeeze=False, sharey=True)[0]
        rows = []
        for ax, level in zip(axes, picked):
            layer = points.loc[points[spec.axis] == level, across].assign(least_margin=least)
            grid = layer.pivot_table(index=across[1], columns=across[0], values="least_margin", aggfunc="first")
            u, v = np.meshgrid(grid.columns.to_numpy(float), grid.index.to_numpy(float))
            values = grid.to_numpy(float)
            drawn = ax.pcolormesh(u, v, values, shading="nearest", cmap="RdYlGn", vmin=-1.0, vmax=1.0)
            if min(values.shape) >= 2 and np.nanmin(values) < 0 < np.nanmax(values):
                ax.contour(u, v, values, levels=[0.0], colors="black", linewidths=1.0)
            ax.set_title(f"{spec.axis} = {round(float(level), 3):g} m", fontsize=8)  # mm: the grid's own digits
            ax.set_xlabel(f"{across[0]} (m)")
            rows.append(layer.assign(**{spec.axis: level}))
        axes[0].set_ylabel(f"{across[1]} (m)")
        fig.colorbar(drawn, ax=list(axes), label="least margin (feasible > 0)", shrink=0.9)
        fig.suptitle(_fill(spec.title or "", job), fontsize=10)
        png = _save(fig, spec, out_dir, job)
        series = out_dir.parent / SERIES_DIR / png.with_suffix(".csv").name
        series.parent.mkdir(parents=True, exist_ok=True)
        write_csv(pd.concat(rows)[[spec.axis, *across, "least_margin"]].round(9), series)
        written += [png, series]
    return written


KINDS: dict[str, Callable[[FigureSpec, pd.DataFrame, StudyResults, Path], list[Path]]] = {
    "slices": slices,
    "pareto": pareto,
    "choice_bar": choice_bar,
    "limiting_bar": limiting_bar,
    "cloud": cloud,
    "map": value_map,
    "survival_bar": survival_bar,
    "timeseries": timeseries,
    "path": path_series,
    "path_view": path_view,
    "paving": paving_slices,
    "curve": curve,
    "heatmap": heatmap,
}


# Config keys as a reader names them (legend titles, panel titles).
LABELS = {"robot.gamma_deg": "γ (deg)", "robot.r_end": "r_end (m)", "robot.r_base": "r_base (m)",
          "load.mass": "payload (kg)", "robot.platform.mass": "carried mass m (kg)", "motion.v_max": "V_cmax (m/s)",
          "drive.winch_radius": "winch radius R_i (m)", "drive.gear_ratio": "gear ratio N_V",
          "tension.model": "tension model", "max_payload_kg": "largest payload (kg)"}


def _figure(**options):
    """A bare matplotlib ``Figure`` (no pyplot)."""
    from matplotlib.figure import Figure

    return Figure(**options)


def label(key: str) -> str:
    return LABELS.get(key, key)


def _evaluable(expression: str) -> str | None:
    problem = expression and expression_error(expression)
    return f"pandas cannot evaluate it ({problem})" if problem else None


def expression_error(expression: str) -> str | None:
    """Why pandas would refuse ``expression`` (a column or an expression over columns, ``x``,
    ``y``, ``value`` of a figure) whatever the columns hold, None when it evaluates: tried on one
    row whose every name is a number (then a flag), before any job runs. A plain (dotted) name
    is a summary column, taken as it is."""
    if re.fullmatch(r"[\w.]+", expression):
        return None
    names = {name.strip("`") for name in re.findall(r"`[^`]+`|\b[A-Za-z_]\w*\b(?!\s*\()", expression)}
    problem = None
    for value in (1.0, True):
        try:
            pd.DataFrame({name: [value] for name in names}).eval(expression)
            return None
        except Exception as exc:  # pandas' parser and evaluator: syntax, functions, operands
            problem = problem or one_line(exc)
    return problem


def _column(table: pd.DataFrame, expression: str) -> pd.Series:
    return table[expression] if expression in table.columns else table.eval(expression)


def _select(table: pd.DataFrame, select: dict[str, Any]) -> pd.DataFrame:
    keep = np.ones(len(table), dtype=bool)
    for key, wanted in select.items():
        wanted = wanted if isinstance(wanted, (list, tuple)) else [wanted]
        keep &= np.isin(table[key].to_numpy(), wanted)
    return table[keep]


# {{, }}, or a field {name} / {name:spec}
FIELD = re.compile(r"\{\{|\}\}|\{(\w+)(?::([<>^=]?[+\- ]?#?0?\d*[,_]?(?:\.\d+)?[bcdeEfFgGnosxX%]?))?\}")
PLAIN_FILE = re.compile(r"[\w+=,()-][\w.+=,() -]*\.png")  # one file name in the figures folder


def template_error(text: str) -> str | None:
    """Why ``text`` is not a figure template, None when it is: its only fields are ``{column}``
    and ``{column:format}`` (no attribute, index or nested field); ``{{`` and ``}}`` are braces."""
    rest = FIELD.sub("", text)
    if "{" in rest or "}" in rest:
        return "fields are {column} or {column:format} (e.g. {volume_m3:.1f}); write {{ and }} for braces"
    return None


def file_error(template: str) -> str | None:
    """Why a figure's ``file`` template cannot name a PNG in the figures folder, None when it can."""
    return template_error(template) or (None if PLAIN_FILE.fullmatch(FIELD.sub("x", template)) else (
        "a file name ending in .png, with no folder, no leading dot and no '..'"))


def _fill(pattern: str, row: pd.Series) -> str:
    """``pattern`` with each ``{column}`` field replaced by the row's value (dots in a column's
    name written as ``_``); a name the row lacks is a ConfigError naming the columns there are."""
    values = {str(k).replace(".", "_"): v for k, v in row.items()}

    def value(field: re.Match) -> str:
        if field[1] is None:  # {{ or }}
            return field[0][0]
        if field[1] not in values:
            raise ConfigError(f"figure field {{{field[1]}}}: no such column (there are: {', '.join(values)})")
        try:
            return format(values[field[1]], field[2] or "")
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"figure field {field[0]}: {one_line(exc)} (value {values[field[1]]!r})") from None
    return FIELD.sub(value, pattern)


def _labels(ax, spec: FigureSpec, xlabel: str | None, ylabel: str | None, row=None) -> None:
    ax.set_xlabel(spec.xlabel or xlabel or "")
    ax.set_ylabel(spec.ylabel or ylabel or "")
    if spec.title:
        ax.set_title(spec.title if row is None else _fill(spec.title, row))


def _box(ax, row: pd.Series) -> None:
    """Outline the searched box (the geometric workspace) from the summary's box.* columns."""
    lo = np.array([row[f"box.{a}_min"] for a in "xyz"])
    hi = np.array([row[f"box.{a}_max"] for a in "xyz"])
    corners = np.array([[lo[0] if i & 1 == 0 else hi[0], lo[1] if i & 2 == 0 else hi[1],
                         lo[2] if i & 4 == 0 else hi[2]] for i in range(8)])
    for i in range(8):
        for bit in (1, 2, 4):
            if not i & bit:
                edge = corners[[i, i | bit]]
                ax.plot(*edge.T, color="0.4", lw=0.6)


def _save(fig, spec: FigureSpec, out_dir: Path, row: pd.Series | None = None) -> Path:
    """Save as ``spec.file`` (its fields filled from ``row``), with the filled caption as the
    PNG's Description (the report prints it under the figure: :func:`caption`)."""
    fill = (lambda text: text) if row is None else (lambda text: _fill(text, row))
    name = fill(spec.file)
    if not PLAIN_FILE.fullmatch(name):  # a value from the results may hold a separator
        raise ConfigError(f"figures: {spec.file}: fills to {name!r}, not a file name in the figures folder")
    path = out_dir / name
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = {"Software": None}
    if spec.caption:
        meta["Description"] = " ".join(fill(spec.caption).split())
    fig.savefig(path, metadata=meta)
    return path


def caption(png: Path) -> str | None:
    """The caption a figure was saved with (None for a figure without one)."""
    from PIL import Image

    with Image.open(png) as image:
        return image.text.get("Description")

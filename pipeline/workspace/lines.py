"""The paper's experiment set of straight lines (section 3.1.3) and its comparison with CPR-WWA.

Lines run along x and along y through every row of the CPR-WWA position grid, at every z level
(N = 6: 36 x-lines and 36 y-lines), each from one face of the geometric workspace to the
opposite one with the trapezoidal profile of ``motion.*``. Line 0 is O''-F'': the x-line at the
smallest y on the top layer (the corners below the hanging points O and F, Fig. 3).

Rule for a grid point (docs/evidence.md section 3): it belongs to the simulated feasible workspace when every
sample of its x-line and of its y-line within half a grid step of it satisfies eqs. (30),
(32)-(34). A line can therefore belong to the workspace only partly, as O''-F'' at 0.5 rad does.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pandas as pd
from omegaconf import DictConfig

from pipeline.model.dynamics import SampleDynamics
from pipeline.workspace import criteria
from pipeline.workspace.grid import Grid
from pipeline.workspace.kernel import WorkspaceProblem
from pipeline.errors import ConfigError
from pipeline.model.path import MAX_SAMPLES, trapezoid, trapezoid_phases
from pipeline.workspace.trajectory import inverse_dynamics
from pipeline.workspace.verdict import classify
from pipeline.workspace.compute import grid_workspace

log = logging.getLogger("pipeline")
QUANTITIES = ("theta_dot", criteria.TORQUE, criteria.VOLTAGE)
DT = 0.01  # s, time step of the simulated lines


def line_files(cfg: DictConfig, problem: WorkspaceProblem, grid: Grid, files, sweep_pays: bool = False) -> dict:
    """A lines job's files, each written whole: samples.parquet (line O''-F'' only under
    ``lines.samples=first``: the verdicts of every line are in points.parquet) and, with
    ``output.points``, points.parquet; returns the summary (:func:`simulate_lines`)."""
    samples, points, summary = simulate_lines(cfg, problem, grid, sweep_pays)
    if cfg.lines.samples.name == "first":
        samples = samples[samples["line"] == 0].reset_index(drop=True)
    files.write("samples", samples)
    log.info("%d lines, %d samples; simulated %d vs grid %d feasible points, agreement %.1f%%",
             summary["n_lines"], summary["n_samples"], summary["n_feasible"],
             summary["n_feasible_grid"], summary["agreement_pct"])
    if cfg.output.points:
        files.write("points", points)
    return summary


def simulate_lines(cfg: DictConfig, problem: WorkspaceProblem, grid: Grid,
                   sweep_pays: bool = False) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """(samples, points, summary): every line sample, the grid points with both verdicts, and
    the CPR-WWA summary extended with the simulated count, the agreement and, per criterion,
    the smallest margin along line O''-F'' (``line0_margin_*``: Fig. 6's verdict per limit);
    ``problem`` and ``grid``: CPR-WWA's (``pipeline.app.problem.build_problem``); ``sweep_pays``:
    as :func:`pipeline.workspace.compute.grid_workspace`."""
    lines = _lines(grid[:])
    v_max, t_acc, t_dec = cfg.motion.v_max, cfg.motion.t_acc, cfg.motion.t_dec
    profiles = [trapezoid(float(np.linalg.norm(end - start)), v_max, t_acc, t_dec, DT) for _, start, end in lines]
    points, summary = grid_workspace(cfg, problem, grid, sweep_pays=sweep_pays)
    counts = [len(profile.t) for profile in profiles]
    origins = np.repeat([start for _, start, _ in lines], counts, axis=0)  # each sample's line: start, direction
    directions = np.repeat([(end - start) / np.linalg.norm(end - start) for _, start, end in lines], counts, axis=0)
    s, v, a = (np.concatenate([getattr(profile, name) for profile in profiles]) for name in "sva")
    position, velocity, acceleration = origins + s[:, None] * directions, v[:, None] * directions, a[:, None] * directions
    act = problem.limits
    state = SampleDynamics(problem.robot, position, problem.orientation, problem.spec, velocity, acceleration)
    quantities = inverse_dynamics(state, act)
    margins, ok, _ = classify(criteria.margins(problem.criteria, state, act, problem.settings), problem.margin_atol)
    samples = pd.DataFrame({
        "line": np.repeat(np.arange(len(lines)), counts), "axis": np.repeat([axis for axis, _, _ in lines], counts),
        "t": np.concatenate([profile.t for profile in profiles]), "s": s, "v": v, "a": a,
        **{c: position[:, i] for i, c in enumerate("xyz")}, **{f"{c}_dot": velocity[:, i] for i, c in enumerate("xyz")},
        **{f"{c}_ddot": acceleration[:, i] for i, c in enumerate("xyz")},
        **{f"{name}_{cable + 1}": quantities[name][:, cable]
           for name in QUANTITIES for cable in range(problem.robot.n_cables)},
        **{key: quantities[key] for key in ("wrench_residual", "power_cables", "power_load")},
        "ok": ok, **{f"margin_{name}": margins[name] for name in problem.criteria},
    })

    points = points.rename(columns={"feasible": "feasible_grid", "limiting": "limiting_grid"})
    worst = _point_margins(samples, points, problem.criteria)
    _, points["feasible"], limiting = classify(worst, 0.0)  # samples' margins are snapped already
    points["limiting"] = pd.Categorical.from_codes(limiting, categories=list(problem.criteria))
    agree = points["feasible"] == points["feasible_grid"]
    for name in problem.criteria:  # counts of the lines' verdict; the grid's under lost_grid_*, alone_grid_*
        summary[f"lost_grid_{name}"] = summary.pop(f"lost_{name}")
        summary[f"alone_grid_{name}"] = summary.pop(f"alone_{name}")
        summary[f"lost_{name}"] = int(((points["limiting"] == name) & ~points["feasible"]).sum())
    summary.update(
        n_lines=len(lines), n_samples=len(samples),
        n_feasible_grid=summary["n_feasible"], n_feasible=int(points["feasible"].sum()),
        feasible_pct=100.0 * points["feasible"].mean(), agreement_pct=100.0 * agree.mean(),
        limit_speed=act.speed_limit, limit_torque=act.torque_limit,
        limit_acceleration=act.accel_limit, limit_voltage=act.voltage_limit,
        **{f"line0_margin_{name}": float(samples.loc[samples["line"] == 0, f"margin_{name}"].min())
           for name in problem.criteria},
    )
    summary["volume_m3"] = summary["n_feasible"] * grid.cell_volume
    return samples, points, summary


def check_samples(motion: DictConfig, grid: Grid) -> None:
    """ConfigError when the lines through ``grid`` at the motion ``motion`` (``cfg.motion``)
    would take more than MAX_SAMPLES samples (each line's profile counted, not sampled)."""
    lengths, lines = np.unique([np.linalg.norm(end - start) for _, start, end in _lines(grid[:])], return_counts=True)
    count = sum(int(n) * (math.ceil(trapezoid_phases(float(length), motion.v_max, motion.t_acc, motion.t_dec).total / DT) + 1)
                for length, n in zip(lengths, lines))
    if count > MAX_SAMPLES:
        raise ConfigError(f"motion: v_max={motion.v_max:g} m/s, t_acc={motion.t_acc:g} s, t_dec={motion.t_dec:g} s: the "
                          f"{lines.sum()} lines take {count:.3g} samples of {DT:g} s, more than {MAX_SAMPLES:,}; a faster "
                          "motion or a coarser grid")


def _lines(positions: np.ndarray) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """x-lines (line 0 = O''-F'': smallest y, top layer) then y-lines, through the grid rows."""
    xs, ys, zs = (np.unique(positions[:, i]) for i in range(3))
    lines = []
    for z in zs[::-1]:
        for y in ys:
            lines.append(("x", np.array([xs[0], y, z]), np.array([xs[-1], y, z])))
    for z in zs[::-1]:
        for x in xs:
            lines.append(("y", np.array([x, ys[0], z]), np.array([x, ys[-1], z])))
    return lines


def _point_margins(samples: pd.DataFrame, points: pd.DataFrame, names) -> dict[str, np.ndarray]:
    """Per grid point and criterion, the smallest margin over the samples of both its lines
    within half a grid step: the point is feasible when all those samples are, and its limiting
    criterion is the worst one among them."""
    columns = [f"margin_{name}" for name in names]
    key = pd.MultiIndex.from_frame(points[["x", "y", "z"]].round(9))
    worst = None
    for axis in ("x", "y"):
        on = samples[samples["axis"] == axis]
        nodes = np.unique(points[axis].to_numpy())
        nearest = nodes[np.abs(on[axis].to_numpy()[:, None] - nodes[None, :]).argmin(axis=1)]
        per_point = (on.assign(**{axis: nearest})[["x", "y", "z", *columns]].round({c: 9 for c in "xyz"})
                     .groupby(["x", "y", "z"])[columns].min().reindex(key).to_numpy())
        worst = per_point if worst is None else np.minimum(worst, per_point)
    if np.isnan(worst).any():
        raise ValueError("a grid point lies on no simulated line (a flat search box?)")
    return {name: worst[:, i] for i, name in enumerate(names)}

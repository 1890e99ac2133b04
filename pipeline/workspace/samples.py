"""``analysis=trajectory``: the platform along its path (``pipeline.app.paths``), every sample
checked by the registry's criteria as a pose of the statics whose wrench holds the rate of
change of the platform's momentum (``pipeline.model.statics.PathStatics``).

samples.parquet, one row per sample in time order: ``t`` (s), ``segment`` (k: from way-point k
to k + 1, counted from 1), the pose (``x y z`` m, ``psi theta phi`` rad in ``orientation.convention``),
its twist (``x_dot y_dot z_dot`` m/s, ``omega_x omega_y omega_z`` rad/s, fixed axes) and
acceleration (``x_ddot ...`` m/s^2, ``alpha_x ...`` rad/s^2), the wrench the cables balance
(``wrench_fx ... wrench_mz``, N and N m about the reference point: the load's weight and wrench
minus the rate of change of momentum; a ``wrench.set`` is added to it, each wrench), per cable
its length from the anchor (``length_<c>``, m), speed and acceleration (``speed_<c>`` m/s and
``accel_<c>`` m/s^2, paid out > 0) and tension (``tension_<c>``, N: the minimum-norm tensions of
eq. 10 or the feasible model's distribution, ``tension.distribution``; ``tension_min_<c>`` and
``tension_max_<c>`` over a wrench set), the verdict (``feasible``, ``limiting``) and each
criterion's margin. The summary: the counts of the grid analyses over the samples, the path's
duration and, where a sample fails, the first one (``first_failure_t``, ``_sample``,
``_criterion``, ``_margin``), and the peaks of the tensions and of the cables' speeds and
accelerations.
"""

from __future__ import annotations

import logging

import numpy as np
import pandas as pd
from omegaconf import DictConfig

from pipeline.model.path import COORDINATES
from pipeline.workspace import criteria
from pipeline.workspace.compute import summarize
from pipeline.workspace.criteria import REGISTRY
from pipeline.workspace.kernel import WorkspaceProblem
from pipeline.workspace.quantities import cable_quantities
from pipeline.workspace.verdict import Tally, classify

log = logging.getLogger("pipeline")
CHUNK = 4096  # samples a state holds at once: memory bounded by a chunk, whatever the path's length
TWIST = ("x_dot", "y_dot", "z_dot", "omega_x", "omega_y", "omega_z")
ACCELERATION = ("x_ddot", "y_ddot", "z_ddot", "alpha_x", "alpha_y", "alpha_z")
WRENCH = ("wrench_fx", "wrench_fy", "wrench_fz", "wrench_mx", "wrench_my", "wrench_mz")


def path_files(cfg: DictConfig, problem: WorkspaceProblem, files) -> dict:
    """A trajectory job's samples.parquet, written whole (not with ``output.points=false``: the
    summary only); returns the summary (module doc)."""
    table, summary = follow(cfg, problem)
    if cfg.output.points:
        files.write("samples", table)
    if summary["first_failure_sample"] >= 0:
        name = summary["first_failure_criterion"]
        log.warning("the path fails first at sample %d (t = %.4g s, segment %d): %s, margin %.3g; to try next: %s",
                    summary["first_failure_sample"], summary["first_failure_t"], summary["first_failure_segment"],
                    name, summary["first_failure_margin"], REGISTRY[name].remedy)
    else:
        log.info("the whole path holds: %d samples over %.4g s", summary["n_samples"], summary["duration_s"])
    return summary


def follow(cfg: DictConfig, problem: WorkspaceProblem) -> tuple[pd.DataFrame, dict]:
    """(samples, summary) of the path ``problem.spec.samples`` (module doc)."""
    spec, robot, names = problem.spec, problem.robot, list(problem.criteria)
    samples = spec.samples
    total = len(samples.t)
    tally, parts = Tally(names), []
    for start in range(0, total, CHUNK):
        rows = slice(start, min(start + CHUNK, total))
        state = spec.state_of(robot, rows)
        found = criteria.margins(names, state, problem.limits, problem.settings)
        margins, feasible, limiting = classify(found, problem.margin_atol)
        tally.add(margins, feasible, limiting)
        speeds, accelerations = state.rates
        columns = {"t": samples.t[rows], "segment": samples.segment[rows] + 1,
                   **{name: samples.q[rows, k] for k, name in enumerate(COORDINATES)},
                   **{name: state.velocities[:, k] for k, name in enumerate(TWIST)},
                   **{name: state.accelerations[:, k] for k, name in enumerate(ACCELERATION)},
                   **{name: state.full_wrench[:, k] for k, name in enumerate(WRENCH)},
                   **cable_quantities(state, problem.limits)}
        for i, cable in enumerate(robot.cable_names):
            columns[f"speed_{cable}"], columns[f"accel_{cable}"] = speeds[:, i], accelerations[:, i]
        columns["feasible"] = feasible
        columns["limiting"] = pd.Categorical.from_codes(limiting, categories=names)
        columns.update({f"margin_{name}": margins[name] for name in names})
        parts.append(pd.DataFrame(columns))
        if total > CHUNK:
            log.info("path: %d of %d samples checked", rows.stop, total)
    table = pd.concat(parts, ignore_index=True)
    summary = summarize(cfg, tally.counts(total), float("nan"), problem)
    summary.update(_described(table, robot.cable_names, names, samples.t))
    return table, summary


def _described(table: pd.DataFrame, cables, names: list[str], times: np.ndarray) -> dict:
    """The path's duration and samples, its first failing sample and the peaks of its cables."""
    failing = np.flatnonzero(~table["feasible"].to_numpy())
    first = int(failing[0]) if len(failing) else -1
    name = str(table["limiting"].iloc[first]) if first >= 0 else ""
    tensions = [column for column in table if column.startswith("tension_")]
    return {
        "n_samples": len(table), "duration_s": float(times[-1] - times[0]),
        "first_failure_sample": first, "first_failure_t": float(times[first]) if first >= 0 else float("nan"),
        "first_failure_segment": int(table["segment"].iloc[first]) if first >= 0 else -1,
        "first_failure_criterion": name,
        "first_failure_margin": float(table[f"margin_{name}"].iloc[first]) if first >= 0 else float("nan"),
        "tension_peak_N": float(table[tensions].to_numpy().max()) if tensions else float("nan"),
        "cable_speed_peak": float(np.abs(table[[f"speed_{c}" for c in cables]].to_numpy()).max()),
        "cable_accel_peak": float(np.abs(table[[f"accel_{c}" for c in cables]].to_numpy()).max()),
    }

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
accelerations over the samples that hold; with ``actuator``, each winch's drive per sample and the
drive's peaks, energy and limits (``limit_speed``, ``limit_torque``, ``limit_acceleration``,
``limit_voltage``; :func:`drive_columns`).
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
        if spec.winch_radius is not None and not len(spec.wrench_set):
            columns.update(drive_columns(state, problem.limits.drive, columns))
        columns["feasible"] = feasible
        columns["limiting"] = pd.Categorical.from_codes(limiting, categories=names)
        columns.update({f"margin_{name}": margins[name] for name in names})
        parts.append(pd.DataFrame(columns))
        if total > CHUNK:
            log.info("path: %d of %d samples checked", rows.stop, total)
    table = pd.concat(parts, ignore_index=True)
    summary = summarize(cfg, tally.counts(total), float("nan"), problem)
    summary.update(_described(table, robot.cable_names, samples.t))
    drive = problem.limits.drive
    if drive is not None:  # the limits a figure of the path draws
        summary.update(limit_speed=drive.speed_limit, limit_torque=drive.torque_limit,
                       limit_acceleration=drive.accel_limit, limit_voltage=drive.voltage_limit)
    return table, summary


DRIVE = ("theta_dot", "theta_ddot", criteria.TORQUE, criteria.VOLTAGE, "current", "power")  # per cable, with an actuator


def drive_columns(state, act, columns: dict) -> dict:
    """Per cable, each winch's drive at the samples (eqs. 18-22): shaft speed and acceleration
    ``theta_dot_<c>``, ``theta_ddot_<c>`` (rad/s, rad/s^2: the cable's over R), the load torque it
    holds ``torque_<c>`` (M = R t, N m, of the written tension), the voltage ``voltage_<c>`` (V,
    eq. 21), the armature current ``current_<c>`` = (u - C_E theta_dot) / R_r (A) and the
    electrical power ``power_<c>`` = u i (W; < 0: the motor brakes and feeds back)."""
    names = state.robot.cable_names
    speed, accel = state.shaft_speed_range[0], state.shaft_acceleration[:, 0]
    torque = state.spec.winch_radius * np.column_stack([columns[f"tension_{name}"] for name in names])
    voltage = state.voltage_of(act, torque[:, None, :])[:, 0]
    current = (voltage - act.C_E * speed) / act.R_r
    values = dict(zip(DRIVE, (speed, accel, torque, voltage, current, voltage * current)))
    return {f"{quantity}_{name}": values[quantity][:, i] for quantity in DRIVE for i, name in enumerate(names)}


def _drive_summary(table: pd.DataFrame, cables, held: np.ndarray) -> dict:
    """The drive's peaks over the samples that hold (``held``), and the electrical energy the
    motors draw along the path (J, the trapezoidal rule over the samples; negative: more fed
    back than drawn; NaN unless every sample holds)."""
    if f"power_{cables[0]}" not in table:
        return {}

    def peak(quantity):
        return _peak(np.abs(table[[f"{quantity}_{c}" for c in cables]].to_numpy()), held)

    power = table[[f"power_{c}" for c in cables]].to_numpy()
    energy = float(np.trapezoid(power.sum(axis=1), table["t"].to_numpy())) if held.all() else float("nan")
    return {"shaft_speed_peak": peak("theta_dot"), "torque_peak_Nm": peak(criteria.TORQUE),
            "voltage_peak_V": peak(criteria.VOLTAGE), "current_peak_A": peak("current"),
            "power_peak_W": _peak(power, held), "energy_J": energy}


def _peak(values: np.ndarray, held: np.ndarray) -> float:
    """The largest of ``values`` (n, m) over the rows ``held`` (NaN when none)."""
    return float(values[held].max()) if held.any() else float("nan")


def _described(table: pd.DataFrame, cables, times: np.ndarray) -> dict:
    """The path's duration and samples, its first failing sample and the peaks of its cables
    over the samples that hold (NaN when none: a failing sample's forces are not a distribution)."""
    failing = np.flatnonzero(~table["feasible"].to_numpy())
    first = int(failing[0]) if len(failing) else -1
    name = str(table["limiting"].iloc[first]) if first >= 0 else ""
    tensions = [column for column in table if column.startswith("tension_")]
    held = table["feasible"].to_numpy()
    return {
        "n_samples": len(table), "duration_s": float(times[-1] - times[0]),
        "first_failure_sample": first, "first_failure_t": float(times[first]) if first >= 0 else float("nan"),
        "first_failure_segment": int(table["segment"].iloc[first]) if first >= 0 else -1,
        "first_failure_criterion": name,
        "first_failure_margin": float(table[f"margin_{name}"].iloc[first]) if first >= 0 else float("nan"),
        "tension_peak_N": _peak(table[tensions].to_numpy(), held) if tensions else float("nan"),
        "cable_speed_peak": _peak(np.abs(table[[f"speed_{c}" for c in cables]].to_numpy()), held),
        "cable_accel_peak": _peak(np.abs(table[[f"accel_{c}" for c in cables]].to_numpy()), held),
        **_drive_summary(table, cables, held),
    }

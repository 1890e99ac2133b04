"""Design synthesis over the drive train: which motor, winch radius and gear ratio reach the
required workspace at the least motor torque, as a Pareto front (a study's ``optimise`` block).

Each trial is an ordinary workspace job, checked and run as ``python -m pipeline`` would (the
same kernel, files and reuse of a finished job), in ``jobs/trial_NNNN``; Optuna's seeded
sampler proposes the design variables (NSGA-II by default, TPE on request), with the CPR-ACM
requirement x >= ``choice.required_pct`` (section 5.1 of the CPR-8 paper) as its constraint.
The study's summary is one row per trial: the job's summary, the variables and the objectives
(:data:`OBJECTIVES`), ``meets`` (the requirement) and ``pareto`` (not dominated among the trials
that meet it). A rerun with the same seed proposes the same trials and reuses their jobs.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd
from omegaconf import OmegaConf

from pipeline.app.config import rule, sampler_seed
from pipeline.model.catalogue import NUMERIC_COLUMNS, Catalogue, as_number
from pipeline.errors import ConfigError, require

log = logging.getLogger("pipeline.study")
SAMPLERS = ("nsga2", "tpe")


def _demand(row: pd.Series, actuator: dict) -> float:
    """Peak motor torque over the feasible poses: the shaft torque's share of its eq. (32)
    limit times the rated motor torque; the rated torque itself when no pose is feasible."""
    used = 1.0 - row["least_margin_torque"]
    return float(actuator["torque_Nm"] * (used if used == used else 1.0))


def _drive(row: pd.Series, actuator: dict, key: str, column: str) -> float:
    """The drive train's value the job ran with: the override, else the catalogue's."""
    return float(actuator[column] if pd.isna(row.get(key)) else row[key])


# name -> (direction, what it is, value from the job's summary row and its catalogue row)
OBJECTIVES: dict[str, tuple[str, str, Callable[[pd.Series, dict], float]]] = {
    "feasible_pct": ("maximize", "feasible share of the geometric workspace (%)",
                     lambda row, actuator: float(row["feasible_pct"])),
    "motor_torque_demand_Nm": ("minimize", "peak motor torque over the feasible poses (N m)", _demand),
    "motor_power_W": ("minimize", "the catalogue's rated motor power (W)",
                      lambda row, actuator: float(actuator["power_W"])),
    "winch_radius_m": ("minimize", "winch radius R_i (m)",
                       lambda row, actuator: _drive(row, actuator, "drive.winch_radius", "winch_radius_m")),
    "gear_ratio": ("minimize", "gear ratio N_V",
                   lambda row, actuator: _drive(row, actuator, "drive.gear_ratio", "gear_ratio")),
}
CATALOGUE = "catalogue."  # catalogue.COLUMN: minimise a column of the user's catalogue (e.g. a price)


def objective(name: str) -> tuple[str, str, Callable[[pd.Series, dict], float]]:
    """(direction, what it is, value) of an objective: one of :data:`OBJECTIVES`, or
    ``catalogue.COLUMN``, the actuator's value in that column (minimised)."""
    if name in OBJECTIVES:
        return OBJECTIVES[name]
    column = name[len(CATALOGUE):]
    return "minimize", f"{column} (catalogue)", lambda row, actuator: float(actuator[column])


def check_catalogue_objectives(spec: "OptimiseSpec", catalogue: Catalogue) -> None:
    """ConfigError unless every ``catalogue.COLUMN`` objective names a column of ``catalogue``
    holding a finite number for every actuator."""
    for name in spec.objectives:
        if name in OBJECTIVES:
            continue
        column = name[len(CATALOGUE):]
        if column not in catalogue.columns:
            extra = [c for c in catalogue.columns if c not in ("name", *NUMERIC_COLUMNS)]
            raise ConfigError(f"optimise.objectives: {name}: the catalogue has no column {column!r} "
                              f"(its extra columns: {', '.join(extra) or 'none'})")
        for row in catalogue.rows:
            if not np.isfinite(as_number(row[column])):
                raise ConfigError(f"optimise.objectives: {name}: actuator {row['id']}: "
                                  f"{row[column]!r} is not a number")


@dataclass
class OptimiseSpec:
    """``variables``: key -> ``catalogue`` (every id of the configured catalogue, for
    ``actuator``), a list of values, or ``{low, high}`` with an optional ``step`` (a float
    range; integer when low, high and step are integers); ``objectives``: names of
    :data:`OBJECTIVES`; ``budget``: the number of trials; ``seed``: the sampler's seed;
    ``sampler``: ``nsga2`` or ``tpe``."""

    variables: dict[str, Any] = field(default_factory=dict)
    objectives: list[str] = field(default_factory=lambda: ["feasible_pct", "motor_torque_demand_Nm"])
    budget: int = 200
    seed: int = rule(sampler_seed, default=0)
    sampler: str = "nsga2"

    def check_across(self, where: str) -> None:
        """ConfigError naming the first field that cannot be used."""
        if not self.variables:
            raise ConfigError(f"{where}: optimise.variables: none given")
        for key, domain in self.variables.items():
            variable_domain(key, domain, where)
        unknown = [o for o in self.objectives if o not in OBJECTIVES and not (
            o.startswith(CATALOGUE) and len(o) > len(CATALOGUE))]
        if unknown or not self.objectives:
            what = f"unknown {unknown[0]!r}" if unknown else "none given"
            raise ConfigError(f"{where}: optimise.objectives: {what} (known: {', '.join(OBJECTIVES)}, "
                              f"{CATALOGUE}COLUMN)")
        if not 0 < self.budget <= 10_000:
            raise ConfigError(f"{where}: optimise.budget={self.budget}: must be in [1, 10000]")
        if self.sampler not in SAMPLERS:
            raise ConfigError(f"{where}: optimise.sampler={self.sampler!r}: must be one of {', '.join(SAMPLERS)}")


def variable_domain(key: str, domain: Any, where: str, block: str = "optimise") -> Any:
    """A variable's values as ``("choices", list)`` or ``("range", low, high, step)``; errors
    name ``where`` and the study file's ``block`` (optimise or search)."""
    if domain == "catalogue":
        if key != "actuator":
            raise ConfigError(f"{where}: {block}.variables.{key}=catalogue: only 'actuator' takes the catalogue's ids")
        return ("catalogue",)
    if isinstance(domain, (list, tuple)) or OmegaConf.is_list(domain):
        values = list(domain)
        if not values:
            raise ConfigError(f"{where}: {block}.variables.{key}: an empty list of values")
        numbers = [isinstance(v, (int, float)) and not isinstance(v, bool) for v in values]
        bad = [v for v, number in zip(values, numbers) if not (number and math.isfinite(v) or isinstance(v, str))]
        if bad or 0 < sum(numbers) < len(values):  # checked whole: the plan tries the ends only
            what = f"{bad[0]!r}: the values" if bad else "the values"
            raise ConfigError(f"{where}: {block}.variables.{key}: {what} must be finite numbers, or all names")
        return ("choices", values)
    if isinstance(domain, dict) or OmegaConf.is_dict(domain):
        extra = set(domain) - {"low", "high", "step"}
        if extra or not {"low", "high"} <= set(domain):
            raise ConfigError(f"{where}: {block}.variables.{key}: give low and high (and step), not {sorted(domain)}")
        low, high, step = domain["low"], domain["high"], domain.get("step")
        numbers = [v for v in (low, high, step) if v is not None]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in numbers):
            raise ConfigError(f"{where}: {block}.variables.{key}: low, high and step must be finite numbers")
        if not low < high or (step is not None and not 0 < step <= high - low):
            raise ConfigError(f"{where}: {block}.variables.{key}: an empty range "
                              f"[{low}, {high}]{'' if step is None else f' by {step}'}")
        return ("range", low, high, step)
    raise ConfigError(f"{where}: {block}.variables.{key}: catalogue, a list, or {{low, high, step}}")


def corner_overrides(variables: dict[str, Any], ids: list[int]) -> list[list[str]]:
    """The overrides of the lowest and the highest design of ``variables`` (an optimise or
    search block's), for the plan (every value a trial can take lies between them);
    ConfigError for an actuator id not in the catalogue."""
    corners: list[list[str]] = [[], []]
    for key, domain in variables.items():
        kind, *values = variable_domain(key, domain, "")
        options = sorted(ids) if kind == "catalogue" else values[:2] if kind == "range" else (
            sorted(values[0]) if all(isinstance(v, (int, float)) for v in values[0]) else values[0])
        if key == "actuator":
            unknown = [v for v in options if v not in ids]
            if unknown:
                raise ConfigError(f"optimise.variables.actuator: id {unknown[0]} is not in the "
                                  f"catalogue (ids: {', '.join(map(str, sorted(ids)))})")
        corners[0].append(f"{key}={options[0]}")
        corners[1].append(f"{key}={options[-1]}")
    return corners


def optimise(spec: OptimiseSpec, run_trial: Callable[[int, list[str]], dict],
             catalogue: Catalogue, required_pct: float) -> pd.DataFrame:
    """Run ``spec.budget`` trials; ``run_trial(number, overrides)`` runs one job and returns
    its summary. Returns one row per trial (see the module's docstring)."""
    optuna = require("optuna", "design", "an optimise study")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    sampler = (optuna.samplers.NSGAIISampler(seed=spec.seed) if spec.sampler == "nsga2" else
               optuna.samplers.TPESampler(seed=spec.seed))
    study = optuna.create_study(directions=[objective(o)[0] for o in spec.objectives], sampler=sampler)
    rows = []

    def run(trial) -> list[float]:
        overrides = [f"{key}={_suggest(trial, key, domain, catalogue)}" for key, domain in spec.variables.items()]
        row = pd.Series(run_trial(trial.number, overrides))
        actuator = catalogue.row(int(row["actuator"]))
        measured = {name: objective(name)[2](row, actuator) for name in dict.fromkeys([*OBJECTIVES, *spec.objectives])}
        trial.set_constraint("required_pct", float(required_pct - row["feasible_pct"]))  # <= 0: meets x
        rows.append({"trial": trial.number, **row.to_dict(), **measured})
        if (trial.number + 1) % 20 == 0 or trial.number + 1 == spec.budget:
            log.info("optimise: trial %d/%d", trial.number + 1, spec.budget)
        return [measured[o] for o in spec.objectives]

    study.optimize(run, n_trials=spec.budget)
    table = pd.DataFrame(rows)
    table["meets"] = table["feasible_pct"] >= required_pct
    table["pareto"] = pareto_front(table, spec.objectives) & table["meets"]
    return table


def _suggest(trial, key: str, domain: Any, catalogue: Catalogue):
    kind, *values = variable_domain(key, domain, "")
    if kind == "catalogue":
        return trial.suggest_categorical(key, catalogue.ids)
    if kind == "choices":
        return trial.suggest_categorical(key, values[0])
    low, high, step = values
    if all(isinstance(v, int) for v in (low, high)) and (step is None or isinstance(step, int)):
        return trial.suggest_int(key, low, high, step=step or 1)
    return round(trial.suggest_float(key, low, high, step=step), 9)  # a short, exact override text


def pareto_front(table: pd.DataFrame, objectives: list[str]) -> np.ndarray:
    """Rows of ``table`` that meet the requirement and that no other such row dominates (at
    least as good in every objective, better in one)."""
    signs = np.array([1.0 if objective(o)[0] == "minimize" else -1.0 for o in objectives])
    costs = table[objectives].to_numpy(dtype=float) * signs
    meets = table["meets"].to_numpy() if "meets" in table else np.ones(len(table), dtype=bool)
    front = meets.copy()
    for i in np.flatnonzero(meets):
        others = costs[meets]
        dominated = ((others <= costs[i]).all(axis=1) & (others < costs[i]).any(axis=1)).any()
        front[i] = not dominated
    return front


def best_drive(summary: pd.DataFrame) -> pd.DataFrame:
    """Per actuator, the trial that meets the requirement at the least motor torque demand
    (the issue's "smallest drive train"), or a row saying none of its trials did."""
    rows = []
    for actuator, part in summary.groupby("actuator", sort=True):
        meeting = part[part["meets"]]
        if meeting.empty:
            rows.append({"actuator": actuator, "found": False, "trials": len(part),
                         "best_feasible_pct": float(part["feasible_pct"].max())})
            continue
        best = meeting.sort_values(["motor_torque_demand_Nm", "trial"]).iloc[0]
        rows.append({"actuator": actuator, "found": True, "trials": len(part),
                     "best_feasible_pct": float(best["feasible_pct"]), "trial": int(best["trial"]),
                     "winch_radius_m": float(best["winch_radius_m"]), "gear_ratio": float(best["gear_ratio"]),
                     "motor_torque_demand_Nm": float(best["motor_torque_demand_Nm"])})
    return pd.DataFrame(rows)


def trial_folder(jobs_dir: Path, number: int) -> Path:
    return jobs_dir / f"trial_{number:04d}"

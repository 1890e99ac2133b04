"""Exact search over the drive train, to the grid (a study's ``search`` block): per actuator,
the smallest winch radius, gear ratio or motor torque demand that reaches the required share,
or the proof that no design in the stated ranges does.

Two facts of the CPR-WWA model (eqs. 18-22, 30-34, minimum-norm tensions) make it exact; they
hold as well for any robot's drive with minimum-norm tensions, over a static grid in its required
motions (``analysis=statics actuator=ID``, each pose's cable rates and tensions those of its
motions) or along a path (``analysis=trajectory``), whose tension limits do not depend on the drive:

1. **Only the transmission ratio rho = N_V / R_i counts.** The shaft speed and acceleration are
   the cable's divided by R_i and the motor's are N_V times the shaft's; the load torque
   M = R_i t (eq. 20) and its limit M_mot N_V xi (eq. 32); G_v and L_v grow with N_V and S_v
   falls with it (eq. 22), so u = rho (G l'' + L l') + S t / rho. Every margin of a pose, and
   the motor torque demand, is a function of rho alone (tested: (R, N) and (c R, c N) give the
   same margins to 1e-12). A (R_i, N_V) grid is therefore a sorted list of ratios.
2. **Each pose is feasible on one interval of rho.** Each limit reads |alpha rho + beta / rho|
   <= c for every velocity and acceleration of the set, a quasiconvex function of rho > 0
   (convex when alpha and beta share a sign, monotone otherwise); the largest of them is
   quasiconvex, so a pose's least margin is quasiconcave in rho and its feasible set is an
   interval. (The share of the workspace is a sum of such intervals and is *not* monotone:
   actuator 2 without moments goes 85.2, 83.3, 85.2 % as R_i grows; a bisection on the share
   alone would be wrong.) With the ``feasible`` tension model fact 2 is not proven: refused.

The search is a branch and bound on the sorted ratios. A job at ratio g, read with a neighbour
g +- 1, tells for each infeasible pose on which side its interval lies (the neighbour's least
margin is larger on that side); so between two evaluated ratios i < j at most the poses not
known to end before i nor to start after j can be feasible (an upper bound on the share), and
the poses feasible at both i and j are feasible throughout (a lower bound on the torque
demand, which scales as 1 / rho). A stretch is skipped when its bound cannot meet the required
share or beat the best design found; the search ends when no stretch is left, so its answer
equals evaluating every ratio (tested against that, and against random interval data). Every
candidate's row in ``search.parquet`` says whether it was evaluated and, if not, the bounds
that excluded it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pandas as pd

from pipeline.errors import ConfigError
from pipeline.model.catalogue import Catalogue
from pipeline.analyses.optimise import OBJECTIVES as MEASURED, variable_domain

VARIABLES = {"drive.winch_radius": "winch_radius_m", "drive.gear_ratio": "gear_ratio"}
# each minimised among the ratios that reach the required share (defined in pipeline.analyses.optimise)
OBJECTIVES = ("motor_torque_demand_Nm", "winch_radius_m", "gear_ratio")
log = logging.getLogger("pipeline.study")
TIE = 1e-12  # least margins closer than this at neighbouring ratios say nothing about the side
SHARE_ATOL = 1e-9  # % : a bound and a job's share are both counts of poses, rounded differently


@dataclass
class SearchSpec:
    """``variables``: ``drive.winch_radius`` and/or ``drive.gear_ratio``, each a list of values
    or ``{low, high, step}`` (a grid: the answer is exact to it); a variable not given keeps
    the catalogue's value. ``objective``: a name of :data:`OBJECTIVES`. ``actuators``:
    ``catalogue`` (every id) or a list of ids."""

    variables: dict[str, Any] = field(default_factory=dict)
    objective: str = "motor_torque_demand_Nm"
    actuators: Any = "catalogue"

    def check_across(self, where: str) -> None:
        """ConfigError naming the first field that cannot be used."""
        if not self.variables:
            raise ConfigError(f"{where}: search.variables: none given (known: {', '.join(VARIABLES)})")
        sizes = [len(grid_values(key, domain, where)) for key, domain in self.variables.items()]
        if math.prod(sizes) > MAX_CANDIDATES:
            raise ConfigError(f"{where}: search.variables: {' x '.join(map(str, sizes))} = {math.prod(sizes):.3g} "
                              f"designs; at most {MAX_CANDIDATES} (coarser steps)")
        if self.objective not in OBJECTIVES:
            raise ConfigError(f"{where}: search.objective={self.objective!r}: unknown (known: "
                              f"{', '.join(OBJECTIVES)})")

    def ids(self, catalogue: Catalogue) -> list[int]:
        """The actuator ids searched; ConfigError for one not in ``catalogue``."""
        known = catalogue.ids
        if self.actuators == "catalogue":
            return known
        ids = list(self.actuators) if isinstance(self.actuators, (list, tuple)) else [self.actuators]
        if not all(isinstance(i, int) and not isinstance(i, bool) for i in ids):
            raise ConfigError(f"search.actuators={self.actuators!r}: catalogue or a list of ids")
        unknown = [i for i in ids if i not in known]
        if unknown or not ids:
            what = f"id {unknown[0]} is not in the catalogue" if unknown else "an empty list"
            raise ConfigError(f"search.actuators: {what} (ids: {', '.join(map(str, known))})")
        return ids


MAX_VALUES = 10_000  # a variable's grid: values it lists
MAX_CANDIDATES = 1_000_000  # designs of all variables together (one row each before the ratios merge)


def grid_values(key: str, domain: Any, where: str) -> list[float]:
    """A variable's sorted grid: the listed values, or low, low + step, ... <= high."""
    if key not in VARIABLES:
        raise ConfigError(f"{where}: search.variables.{key}: not a drive variable (known: {', '.join(VARIABLES)})")
    kind, *values = variable_domain(key, domain, where, "search")
    if kind == "choices":
        values = values[0]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values):
            raise ConfigError(f"{where}: search.variables.{key}: {values}: every value must be a finite number")
    else:
        low, high, step = values
        if step is None:
            raise ConfigError(f"{where}: search.variables.{key}: give a step (the search is exact to a grid)")
        count = math.floor((high - low) / step + 1e-9) + 1
        if count > MAX_VALUES:
            raise ConfigError(f"{where}: search.variables.{key}: step={step:g} gives {count:.3g} values from {low:g} "
                              f"to {high:g}; at most {MAX_VALUES} (a coarser step)")
        values = [round(low + k * step, 9) for k in range(count)]
    if min(values) <= 0:
        raise ConfigError(f"{where}: search.variables.{key}: {min(values)}: must be positive")
    return sorted(set(float(v) for v in values))


def candidates(spec: SearchSpec, actuator: dict) -> pd.DataFrame:
    """One row per distinct ratio rho = N_V / R_i of the variables' grids (ascending), with the
    design that stands for it: the smallest gear ratio for the ``gear_ratio`` objective, else
    the smallest winch radius (every design of one ratio has the same margins)."""
    grids = {key: grid_values(key, spec.variables[key], "") if key in spec.variables
             else [float(actuator[column])] for key, column in VARIABLES.items()}
    table = pd.DataFrame([(gear / radius, radius, gear) for radius in grids["drive.winch_radius"]
                          for gear in grids["drive.gear_ratio"]],
                         columns=["rho", "winch_radius_m", "gear_ratio"])
    table["rho"] = table["rho"].map(lambda value: float(f"{value:.10g}"))  # 12/0.035 == 24/0.07
    first = ["gear_ratio", "winch_radius_m"] if spec.objective == "gear_ratio" else ["winch_radius_m", "gear_ratio"]
    table = table.sort_values(["rho", *first]).drop_duplicates("rho").reset_index(drop=True)
    table["overrides"] = [[f"{key}={row[column]:.9g}" for key, column in VARIABLES.items() if key in spec.variables]
                          for _, row in table.iterrows()]
    return table


@dataclass(frozen=True)
class Evaluation:
    """One job at one ratio: per pose its verdict, least margin over the criteria and motor
    torque (N m); the job's feasible share (%) and its objective value."""

    feasible: np.ndarray
    margin: np.ndarray
    demand: np.ndarray
    share: float
    value: float


def branch_and_bound(rho: np.ndarray, values: np.ndarray | None, evaluate: Callable[[int], Evaluation],
                     required_pct: float, slack: float = 0.0) -> tuple[dict[int, Evaluation], dict[int, tuple[float, float]]]:
    """The module's search over the ratios ``rho`` (ascending). ``values``: each ratio's
    objective when known beforehand (a design variable), else None (the torque demand, known
    after its job); ``evaluate(g)`` runs ratio g; ``slack`` is subtracted from the demand's
    lower bounds (the margins' snapping tolerance in N m). Returns the evaluations and, for
    every ratio left out, the (share upper bound, objective lower bound) that excluded it."""
    done: dict[int, Evaluation] = {}
    last = len(rho) - 1

    def pair(g: int) -> None:
        for k in (g, g + 1 if g < last else g - 1):
            if 0 <= k <= last and k not in done:
                done[k] = evaluate(k)

    def sides(g: int) -> tuple[np.ndarray, np.ndarray]:
        """(poses feasible only above g, poses feasible only below g), from a neighbour."""
        h = g + 1 if g + 1 in done else g - 1
        rising = (done[h].margin - done[g].margin) * (1 if h > g else -1)
        out = ~done[g].feasible
        return out & (rising > TIE), out & (rising < -TIE)

    def bounds(i: int, j: int) -> tuple[float, float]:
        maybe = ~(sides(i)[1] | sides(j)[0])
        upper = 100.0 * maybe.sum() / maybe.size
        if values is not None:
            return upper, float(values[i + 1:j].min())
        both = done[i].feasible & done[j].feasible
        demand = done[i].demand[both].max() * rho[i] / rho[j - 1] - slack if both.any() else 0.0
        return upper, float(demand)

    pair(0)
    pair(last)
    while True:
        meeting = [(ev.value if values is None else values[g], g) for g, ev in done.items() if ev.share >= required_pct]
        best = min(meeting)[0] if meeting else math.inf
        evaluated = sorted(done)
        gaps = [(i, j, *bounds(i, j)) for i, j in zip(evaluated, evaluated[1:]) if j > i + 1]
        open_ = [gap for gap in gaps if gap[2] >= required_pct - SHARE_ATOL and gap[3] < best]
        if not open_:
            excluded = {g: (upper, lower) for i, j, upper, lower in gaps for g in range(i + 1, j)}
            return done, excluded
        i, j, _, _ = min(open_, key=lambda gap: (gap[3], gap[0]))
        pair((i + j) // 2)


def search(spec: SearchSpec, catalogue: Catalogue, required_pct: float,
           run_job: Callable[[int, list[str]], tuple[dict, pd.DataFrame]], atol: float) -> pd.DataFrame:
    """Search every actuator of ``spec``; ``run_job(actuator, overrides)`` runs one job and
    returns its summary and points. One row per actuator and candidate ratio
    (:func:`candidates`): ``evaluated``, ``feasible_pct``, ``meets``, the ``objective`` and the
    job's whole summary (``job`` its folder); for a ratio left out, ``bound_pct`` and
    ``bound_objective`` (why)."""
    measure = MEASURED[spec.objective][2]
    tables = []
    for actuator_id in spec.ids(catalogue):
        actuator = catalogue.row(actuator_id)
        table = candidates(spec, actuator)
        known = None if spec.objective == "motor_torque_demand_Nm" else table[spec.objective].to_numpy()
        jobs: dict[int, dict] = {}

        def evaluate(g: int) -> Evaluation:
            row, points = run_job(actuator_id, table.at[g, "overrides"])
            jobs[g] = row
            margins = points[[c for c in points.columns if c.startswith("margin_")]].to_numpy()
            return Evaluation(feasible=points["feasible"].to_numpy(dtype=bool), margin=margins.min(axis=1),
                              demand=float(actuator["torque_Nm"]) * (1.0 - points["margin_torque"].to_numpy()),
                              share=float(row["feasible_pct"]), value=measure(pd.Series(row), actuator))

        done, excluded = branch_and_bound(table["rho"].to_numpy(), known, evaluate, required_pct,
                                          slack=2.0 * atol * float(actuator["torque_Nm"]))
        table.insert(0, "actuator", actuator_id)
        table["evaluated"] = [g in done for g in table.index]
        table["feasible_pct"] = [done[g].share if g in done else math.nan for g in table.index]
        table["meets"] = table["feasible_pct"] >= required_pct
        table["objective"] = [done[g].value if g in done else math.nan for g in table.index] \
            if known is None else known
        table["bound_pct"] = [excluded.get(g, (math.nan,))[0] for g in table.index]
        table["bound_objective"] = [excluded.get(g, (math.nan, math.nan))[1] for g in table.index]
        table["objective_name"] = spec.objective
        summaries = pd.DataFrame.from_dict(jobs, orient="index")  # each evaluated job's summary
        table = table.join(summaries[summaries.columns.difference(table.columns, sort=False)])
        tables.append(table.drop(columns="overrides"))
        found = answer(tables[-1])
        log.info("search: actuator %d: %d of %d ratios evaluated; %s", actuator_id, len(done), len(table),
                 "none reaches %g %%" % required_pct if found is None else
                 f"R_i = {found['winch_radius_m']:.9g} m, N_V = {found['gear_ratio']:.9g}, "
                 f"{spec.objective} = {found['objective']:.6g}")
    return pd.concat(tables, ignore_index=True)


def answer(table: pd.DataFrame) -> pd.Series | None:
    """The evaluated candidate that meets the requirement at the least objective (the lowest
    ratio among equals), or None."""
    meeting = table[table["meets"]]
    return None if meeting.empty else meeting.sort_values(["objective", "rho"]).iloc[0]


def exact_drive(search_table: pd.DataFrame, summary: pd.DataFrame | None) -> pd.DataFrame:
    """Per actuator, the search's answer and, when the study also ran the optimiser
    (``summary`` has its trials), the optimiser's best trial for the same objective:
    ``steps_apart`` counts the candidate ratios between the two designs and ``agree`` says they
    are within one grid step (or that neither found a design)."""
    objective = search_table["objective_name"].iloc[0]
    rows = []
    for actuator, table in search_table.groupby("actuator", sort=True):
        found = answer(table)
        row = {"actuator": actuator, "objective_name": objective, "found": found is not None, "candidates": len(table),
               "evaluated": int(table["evaluated"].sum()),
               "best_evaluated_pct": float(table["feasible_pct"].max())}
        if found is not None:  # the answer, with its job's name, counts and box for its picture
            row.update({"rho": found["rho"], "winch_radius_m": found["winch_radius_m"],
                        "gear_ratio": found["gear_ratio"], "feasible_pct": found["feasible_pct"],
                        objective: found["objective"], "job": found["job"],
                        **{key: found[key] for key in found.index if key.startswith(("n_", "box."))}})
        if summary is not None and "trial" in summary:
            trials = summary[(summary["actuator"] == actuator) & summary["meets"]]
            row["optimiser_found"] = not trials.empty
            if not trials.empty:
                best = trials.sort_values([objective, "trial"]).iloc[0]
                row.update({"optimiser_winch_radius_m": best["winch_radius_m"],
                            "optimiser_gear_ratio": best["gear_ratio"],
                            f"optimiser_{objective}": best[objective]})
            if found is not None and not trials.empty:
                rho = table["rho"].to_numpy()
                where = int(np.argmin(np.abs(rho / (best["gear_ratio"] / best["winch_radius_m"]) - 1.0)))
                row["steps_apart"] = abs(where - int(np.flatnonzero(rho == found["rho"])[0]))
                # an optimiser's design better than the exact answer would refute the search
                row["optimiser_better"] = bool(best[objective] < found["objective"] * (1 - 1e-9))
            row["agree"] = bool(row["optimiser_found"] == row["found"] and row.get("steps_apart", 0) <= 1
                                and not row.get("optimiser_better", False))
        rows.append(row)
    table = pd.DataFrame(rows)
    counts = [c for c in table.columns if c.startswith("n_")]
    return table.astype(dict.fromkeys(counts, "Int64"))  # whole numbers, blank where none found

"""The papers' published facts against the model's readings: the ``evidence`` analysis.

A fact is a statement of a paper that the model can check: a number (Table 2's feasible share,
to the grid point), a limit pattern (Fig. 6: which limits line O''-F'' keeps), or a trend (the
IRPM's conclusions on the volume against γ and the radii). For each reading (the values of the
``model.*`` switches that a study's jobs ran with) a fact gives what the model computes,
whether it matches the paper, and how far it is from matching, in its unit: grid points for
counts, comparisons for trends (pairs that go the wrong way), and for limits the margin's
shortfall as a fraction of the limit. A reading's joint score is the facts it matches, then
the grid points it is away on the others (:func:`scores`).

An evidence study names its cases ``SET-READING``: the facts find their jobs by ``SET`` (e.g.
``zero``, ``rot05`` for the CPR-8; ``fig13``, ``fig14``, ``fig15``, ``forces``, ``moments``
for the IRPM) and group them by the ``model.*`` columns, so a reading is what its jobs ran
with, whatever the case is called. The facts of each robot are in :data:`FACTS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pandas as pd

from pipeline.app.readings import SETTINGS, reading_name
from pipeline.errors import ConfigError
from pipeline.analyses.paper import TABLE2_ACCEPTED, TABLE2_FEASIBLE_PCT
from pipeline.workspace.criteria import SPEED, TORQUE, VOLTAGE

POINTS, COMPARISONS, MARGIN, ACTUATORS = "grid points", "comparisons", "of the limit", "actuators"
AGREEMENT_TOLERANCE_PCT = 5.0  # "their matching can be noticed": at most 5 % of the points differ
MUCH_SMALLER_PCT = 90.0  # "much smaller": below the paper's own acceptance level x = 90 %


@dataclass(frozen=True)
class Outcome:
    """What the model gives for a fact: ``value`` in words, whether it ``matches`` the paper,
    and ``distance`` from matching (0 when it matches) in the fact's unit."""

    value: str
    matches: bool
    distance: float


@dataclass(frozen=True)
class Fact:
    """One published statement: ``key``, where it is (``source``), the paper's claim
    (``statement``), the ``unit`` of its distance, and its ``check`` on one reading's jobs."""

    key: str
    source: str
    statement: str
    unit: str
    check: Callable[[pd.DataFrame], Outcome]


def evidence(summary: pd.DataFrame) -> pd.DataFrame:
    """One row per fact and reading: fact, source, statement, reading, value, matches,
    distance, unit, default (the reading is the project's default)."""
    robot = summary["robot.name"].iloc[0]
    if robot not in FACTS:
        raise ConfigError(f"analysis evidence: no published facts for robot={robot} "
                          f"(facts for: {', '.join(FACTS)})")
    if robot == "cpr8" and summary["catalogue"].notna().any():
        raise ConfigError("analysis evidence: Table 2's facts hold for the paper's catalogue "
                          "only (catalogue=null)")
    data = summary.assign(set=summary["case"].str.split("-").str[0])
    switches = [c for c in data.columns if c.startswith("model.") and c[6:] not in SETTINGS]
    rows = []
    for values, jobs in data.groupby(switches, sort=False):
        reading = reading_name(dict(zip(switches, np.atleast_1d(values))))
        for fact in FACTS[robot]:
            outcome = fact.check(jobs)
            rows.append({"fact": fact.key, "source": fact.source, "statement": fact.statement,
                         "reading": reading, "value": outcome.value,
                         "matches": bool(outcome.matches), "distance": float(outcome.distance),
                         "unit": fact.unit, "default": reading == "default"})
    return pd.DataFrame(rows)


def scores(table: pd.DataFrame) -> pd.DataFrame:
    """Per reading: facts matched of all, and the grid points it is away on the count facts
    it misses; best first (more facts, then fewer points; on a tie the default first: a change
    of default needs a better score)."""
    points = table["distance"].where(table["unit"] == POINTS, 0.0)
    score = table.assign(points=points).groupby("reading", sort=False).agg(
        matched=("matches", "sum"), facts=("matches", "size"), points=("points", "sum"),
        default=("default", "any"))
    return score.sort_values(["matched", "points", "default"], ascending=[False, True, False],
                             kind="stable").reset_index()


def sensitivity(table: pd.DataFrame) -> pd.Series:
    """Per fact, the best reading (:func:`scores`) were that fact read the other way: its
    ``matches`` inverted for every reading and its grid points left out. Where this is not the
    best reading of ``table`` the verdict rests on that fact."""
    best = {}
    for fact, rows in table.groupby("fact", sort=False).groups.items():
        flipped = table.copy()
        flipped.loc[rows, "matches"] = ~flipped.loc[rows, "matches"]
        flipped.loc[rows, "distance"] = 0.0
        best[fact] = scores(flipped)["reading"].iloc[0]
    return pd.Series(best, name="best_if_read_the_other_way")


def _one(jobs: pd.DataFrame, set_name: str, **where) -> pd.Series:
    part = jobs[jobs["set"] == set_name]
    for key, value in where.items():
        part = part[part[key] == value]
    if len(part) != 1:
        raise ValueError(f"evidence: {len(part)} jobs for set {set_name} {where} (want one)")
    return part.iloc[0]


# --- CPR-8 (Filipovic & Kevac 2018) -------------------------------------------------------------

def _table2(actuator: int) -> Fact:
    paper_pct = TABLE2_FEASIBLE_PCT[actuator]

    def check(jobs: pd.DataFrame) -> Outcome:
        job = _one(jobs, "zero", actuator=actuator)
        paper = round(paper_pct * job["n_points"] / 100)
        ours = int(job["n_feasible_grid"])
        return Outcome(f"{100 * ours / job['n_points']:.2f} % ({ours})", ours == paper, abs(ours - paper))

    return Fact(f"table2_actuator_{actuator}", "Table 2",
                f"actuator {actuator}: x = {paper_pct:.2f} % of the geometric workspace", POINTS, check)


def _accepted(jobs: pd.DataFrame) -> Outcome:
    zero = jobs[jobs["set"] == "zero"]
    shares = 100 * zero["n_feasible_grid"] / zero["n_points"]
    ours = sorted(int(a) for a in zero.loc[shares >= 90.0, "actuator"])
    wrong = set(ours) ^ set(TABLE2_ACCEPTED)
    return Outcome(", ".join(map(str, ours)) or "none", not wrong, len(wrong))


def _lines_whole(jobs: pd.DataFrame) -> Outcome:
    job = _one(jobs, "zero", actuator=1)
    return Outcome(f"{int(job['n_feasible'])} of {int(job['n_points'])}",
                   job["n_feasible"] == job["n_points"], job["n_points"] - job["n_feasible"])


def _agreement(set_name: str) -> Callable[[pd.DataFrame], Outcome]:
    def check(jobs: pd.DataFrame) -> Outcome:
        job = _one(jobs, set_name, actuator=1)
        differ = round((100 - job["agreement_pct"]) / 100 * job["n_points"])
        allowed = np.floor(AGREEMENT_TOLERANCE_PCT / 100 * job["n_points"])
        return Outcome(f"{job['agreement_pct']:.1f} % agree", differ <= allowed, max(0, differ - allowed))

    return check


def _smaller(jobs: pd.DataFrame) -> Outcome:
    zero, rot = (int(_one(jobs, s, actuator=1)["n_feasible_grid"]) for s in ("zero", "rot05"))
    return Outcome(f"{rot} vs {zero}", rot < zero, max(0, rot - zero + 1))


def _much_smaller(jobs: pd.DataFrame) -> Outcome:
    job = _one(jobs, "rot05", actuator=1)
    most = np.floor(MUCH_SMALLER_PCT / 100 * job["n_points"])
    return Outcome(f"{job['feasible_pct']:.1f} % ({int(job['n_feasible'])})",
                   job["n_feasible"] <= most, max(0, job["n_feasible"] - most))


def _limit(set_name: str, criterion: str, exceeded: bool) -> Callable[[pd.DataFrame], Outcome]:
    def check(jobs: pd.DataFrame) -> Outcome:
        margin = float(_one(jobs, set_name, actuator=1)[f"line0_margin_{criterion}"])
        peak = f"peak {1 - margin:.3f} × limit"
        if exceeded:
            return Outcome(peak, margin < 0, max(0.0, margin))
        return Outcome(peak, margin >= 0, max(0.0, -margin))

    return check


_FIG6 = {SPEED: "eq. (30)", TORQUE: "eq. (32)", VOLTAGE: "eq. (34)"}
CPR8_FACTS = [
    *(_table2(a) for a in TABLE2_FEASIBLE_PCT),
    Fact("table2_accepted", "Table 2, section 5.1",
         f"accepted at x = 90 %: actuators {', '.join(map(str, TABLE2_ACCEPTED))}", ACTUATORS, _accepted),
    Fact("fig4b_lines_whole", "Fig. 4b, section 3.1.3",
         "zero orientation, actuator 1: the lines give the whole geometric workspace", POINTS, _lines_whole),
    Fact("fig4_agreement", "Figs. 4a-4b, section 3.1.1",
         f"zero orientation: lines and grid match (at most {AGREEMENT_TOLERANCE_PCT:g} % of the points differ)",
         POINTS, _agreement("zero")),
    Fact("fig5_smaller", "Fig. 5a, section 3.1.2",
         "0.5 rad, actuator 1: the feasible workspace is smaller than at zero orientation", POINTS, _smaller),
    Fact("fig5b_much_smaller", "Fig. 5b, section 3.1.3",
         f"0.5 rad: the lines' workspace is much smaller than the geometric one (read: at most "
         f"{MUCH_SMALLER_PCT:g} %, the paper's acceptance level)", POINTS, _much_smaller),
    Fact("fig5_agreement", "Figs. 5a-5b, section 3.1.2",
         f"0.5 rad: lines and grid match (at most {AGREEMENT_TOLERANCE_PCT:g} % of the points differ)",
         POINTS, _agreement("rot05")),
    *(Fact(f"fig6a_{name}", f"Fig. 6a, {eq}", f"line O''-F'', zero orientation: {name} within its limit",
           MARGIN, _limit("zero", name, exceeded=False)) for name, eq in _FIG6.items()),
    Fact("fig6b_speed", "Fig. 6b, eq. (30)", "line O''-F'', 0.5 rad: speed within its limit",
         MARGIN, _limit("rot05", SPEED, exceeded=False)),
    Fact("fig6b_torque", "Fig. 6b, eq. (32)", "line O''-F'', 0.5 rad: some load torques beyond the limit",
         MARGIN, _limit("rot05", TORQUE, exceeded=True)),
    Fact("fig6b_voltage", "Fig. 6b, eq. (34)", "line O''-F'', 0.5 rad: control voltage within its limit",
         MARGIN, _limit("rot05", VOLTAGE, exceeded=False)),
]


# --- IRPM (Hamed & Zohoor) ----------------------------------------------------------------------

def _same_count(set_name: str, gamma: float | None) -> Callable[[pd.DataFrame], Outcome]:
    """The count does not change with r_end (at one γ, or the worst γ when ``gamma`` is None)."""
    def check(jobs: pd.DataFrame) -> Outcome:
        part = jobs[jobs["set"] == set_name]
        if gamma is not None:
            part = part[part["robot.gamma_deg"] == gamma]
        if part["n_feasible"].count() < 2:
            raise ValueError(f"evidence: set {set_name} needs two sizes or more to compare")
        spread = part.groupby("robot.gamma_deg")["n_feasible"].agg(lambda n: n.max() - n.min())
        worst = part[part["robot.gamma_deg"] == spread.idxmax()]["n_feasible"]
        at = "" if gamma is not None else f" at γ = {spread.idxmax():g}°"
        return Outcome(f"{worst.min()}-{worst.max()} points{at}", spread.max() == 0, int(spread.max()))

    return check


def _rising(set_name: str, along: str, per: list[str], falling: bool = False) -> Callable[[pd.DataFrame], Outcome]:
    """The count rises strictly with ``along`` (falls, with ``falling``) at every value of the
    ``per`` columns in each of the sets (comma-separated): the distance counts the neighbouring
    pairs that do not."""
    def check(jobs: pd.DataFrame) -> Outcome:
        wrong = total = 0
        missing = set(set_name.split(",")) - set(jobs["set"])
        if missing:
            raise ValueError(f"evidence: no jobs for set {', '.join(sorted(missing))}")
        for _, part in jobs[jobs["set"].isin(set_name.split(","))].groupby(["set", *per]):
            counts = part.sort_values(along)["n_feasible"].to_numpy()
            steps = np.diff(counts) * (-1 if falling else 1)
            wrong, total = wrong + int((steps <= 0).sum()), total + len(steps)
        if total == 0:
            raise ValueError(f"evidence: set {set_name} holds no pair to compare along {along}")
        return Outcome(f"{total - wrong} of {total} pairs", wrong == 0, wrong)

    return check


IRPM_FACTS = [
    *(Fact(f"same_count_gamma_{g:g}", "section III.A, Fig. 13, conclusions 1 and 4",
           f"zero rotation, γ = {g:g}°: the same count for every r_end / r_base", POINTS,
           _same_count("fig13", g)) for g in (0.0, 15.0, 30.0, 45.0)),
    Fact("smaller_gamma_larger", "sections III.A-C, Figs. 13-15",
         "a smaller γ gives a larger workspace (every size of Figs. 13-15)", COMPARISONS,
         _rising("fig13,fig14,fig15", "robot.gamma_deg", ["robot.r_end", "robot.r_base"], falling=True)),
    Fact("grows_with_base", "section III.B, Fig. 14, conclusion 2",
         "the volume grows with r_base (r_end = 1.2 m)", COMPARISONS,
         _rising("fig14", "robot.r_base", ["robot.gamma_deg"])),
    Fact("no_maximum_at_ratio_1", "section III.C, Fig. 15, conclusion 3",
         "no maximum at r_base / r_end = 1: the volume keeps growing beyond it", COMPARISONS,
         _rising("fig15", "robot.r_base", ["robot.gamma_deg"])),
    Fact("forces_no_effect", "section IV.A, Figs. 16-18, conclusion 5",
         "f_x = f_y = 50 kN, no moments: r_end / r_base has no effect on the volume", POINTS,
         _same_count("forces", None)),
    Fact("moments_larger_end", "section IV.D, Figs. 24-25, conclusion 6",
         "forces 100 kN, M_z = 100 kN m: a larger r_end / r_base gives a larger workspace",
         COMPARISONS, _rising("moments", "robot.r_end", ["robot.gamma_deg"])),
]

FACTS = {"cpr8": CPR8_FACTS, "irpm6": IRPM_FACTS}

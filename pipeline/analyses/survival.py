"""How much of the paper's feasible workspace survives when cables may only pull (issue 8).

Input: a study that runs every configuration twice, ``tension.model=pinv`` (the paper's
minimum-norm torques of eq. 20) and ``tension.model=feasible`` (``pipeline.model.tensions``), on the
same grid. Output: one row per (case, actuator, wrench rows ``model.pinv_columns``) with the
minimum-norm count, the physically valid count, the points of the minimum-norm workspace that
survive, the points gained (the LP redistributes tensions where the minimum-norm ones exceed a
limit), and the lost points per limiting criterion of the physical check. With the default
rows (``translational``) the minimum-norm workspace is the paper's (Table 2).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

GROUP = ["case", "actuator", "model.pinv_columns"]


def survival(results) -> pd.DataFrame:
    """The comparison table of a study's ``results`` (``figures.StudyResults``)."""
    summary = results.summary
    rows = []
    for key, group in summary.groupby(GROUP, sort=False):  # in the study's case order
        baseline = group[group["tension.model"] == "pinv"]
        if len(baseline) != 1:
            raise ValueError(f"survival needs one tension.model=pinv job per {GROUP} = {key}, "
                             f"found {len(baseline)}")
        paper_job = baseline.iloc[0]
        paper = results.points(paper_job["job"])
        for _, job in group[group["tension.model"] == "feasible"].iterrows():
            physical = results.points(job["job"])
            rows.append(_compare(paper_job, paper, job, physical))
    return pd.DataFrame(rows)


def _compare(paper_job, paper: pd.DataFrame, job, physical: pd.DataFrame) -> dict:
    if not np.allclose(paper[["x", "y", "z"]], physical[["x", "y", "z"]]):
        raise ValueError(f"jobs {paper_job['job']} and {job['job']} are not on the same grid")
    was, now = paper["feasible"].to_numpy(), physical["feasible"].to_numpy()
    row = {
        "case": job["case"], "case_label": job["case_label"], "actuator": job["actuator"], "actuator_name": job["actuator_name"],
        "wrench_rows": job["model.pinv_columns"], "job": job["job"], "paper_job": paper_job["job"],
        "n_points": len(paper), "n_paper": int(was.sum()), "n_physical": int(now.sum()),
        "n_survive": int((was & now).sum()), "n_gained": int((now & ~was).sum()),
    }
    row["paper_pct"] = 100.0 * row["n_paper"] / row["n_points"]
    row["physical_pct"] = 100.0 * row["n_physical"] / row["n_points"]
    row["survive_pct"] = 100.0 * row["n_survive"] / row["n_paper"] if row["n_paper"] else np.nan
    lost = physical.loc[was & ~now, "limiting"].astype(str).value_counts()
    for name in physical["limiting"].cat.categories:
        row[f"lost_{name}"] = int(lost.get(name, 0))
    return row

"""CPR-ACM, the actuator choice of section 4 (Fig. 7) and its case study (section 5.1, Table 2).

Input: the sweep summary of CPR-WWA over a catalogue (one row per actuator). Output: one row per
actuator with its feasible share x(i_a), whether it is accepted (x(i_a) >= x), its rank, and the
share of the grid lost to each constraint, which is what explains a rejection.
"""

from __future__ import annotations

import pandas as pd

from pipeline.app.results import varying_settings


def choose(summary: pd.DataFrame) -> pd.DataFrame:
    """Rank the actuators of a CPR-WWA sweep summary and accept those with x(i_a) >= x.

    Section 4 writes the test as x(i_a) > x and section 5.1 as x(i_a) >= x; the latter is used
    (``choice.required_pct`` is "at least x %"). Ties in x(i_a) rank by catalogue id.
    """
    if summary["actuator"].duplicated().any():
        raise ValueError(
            "CPR-ACM compares one CPR-WWA result per actuator, but the summary repeats actuator "
            "ids (does the sweep vary another key as well?)"
        )
    table = summary.sort_values(["feasible_pct", "actuator"], ascending=[False, True])
    out = pd.DataFrame({
        "rank": range(1, len(table) + 1),
        "actuator": table["actuator"].to_numpy(),
        "actuator_name": table["actuator_name"].to_numpy(),
        "actuator_power_W": table["actuator_power_W"].to_numpy(),
        "n_points": table["n_points"].to_numpy(),
        "n_feasible": table["n_feasible"].to_numpy(),
        "feasible_pct": table["feasible_pct"].to_numpy(),
        "required_pct": table["choice.required_pct"].to_numpy(),
    })
    out["accepted"] = out["feasible_pct"] >= out["required_pct"]
    lost = [c for c in table.columns if c.startswith("lost_")]  # the jobs' criteria, in order
    for column in lost:
        out[column] = table[column].to_numpy()
        out[f"{column}_pct"] = 100.0 * out[column] / out["n_points"]
    out["rejected_by"] = [
        "" if row.accepted else ", ".join(
            f"{c[5:]} {getattr(row, c)}" for c in lost if getattr(row, c) > 0
        )
        for row in out.itertuples()
    ]
    return out.reset_index(drop=True)


def verdict(choice: pd.DataFrame) -> str:
    """CPR-ACM's answer in one line, from a :func:`choose` table: which actuators are accepted
    at x % and what removes the workspace of the others."""
    accepted = choice[choice["accepted"]]
    rejected = choice[~choice["accepted"]]
    shares = "; ".join(f"{row.actuator} {row.feasible_pct:.2f} %"
                       + (f" (lost to {row.rejected_by})" if row.rejected_by else "")
                       for row in rejected.itertuples())
    return (f"actuator choice at x >= {choice['required_pct'].iloc[0]:g} %: "
            f"accept {', '.join(map(str, accepted['actuator'])) or 'none'}"
            + (f"; reject {shares}" if shares else ""))


def acceptance(summary: pd.DataFrame) -> pd.DataFrame:
    """CPR-ACM repeated for every value of one swept design variable (winch radius, gear ratio,
    mass, v_max): one row per (actuator, value) with x(i_a), the verdict and the main loss."""
    varying = varying_settings({c: summary[c].tolist() for c in summary.columns},
                               ignore=("job", "actuator"))
    if len(varying) != 1:
        raise ValueError(f"acceptance needs exactly one swept design variable, got {varying or 'none'}")
    (parameter,) = varying
    out = choose_each(summary, parameter)
    out.insert(1, "parameter", parameter)
    return out


def choose_each(summary: pd.DataFrame, parameter: str) -> pd.DataFrame:
    """:func:`choose` within each value of ``parameter``, as one long table."""
    parts = []
    for value, group in summary.groupby(parameter, sort=True):
        part = choose(group)
        part.insert(1, "value", value)
        parts.append(part)
    return pd.concat(parts, ignore_index=True).sort_values(["actuator", "value"], ignore_index=True)

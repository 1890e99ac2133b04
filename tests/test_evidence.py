"""The evidence tables (pipeline/analyses/evidence.py): every published fact against each reading, from
the jobs the declared studies evidence_cpr8 and evidence_irpm run (computed here in-process,
one job per case and swept value, as the study would)."""

import copy
import itertools
from pathlib import Path

import pandas as pd
import pytest
from omegaconf import OmegaConf

from golden import values

from pipeline.errors import ConfigError
from pipeline.analyses.evidence import FACTS, MARGIN, POINTS, evidence, scores, sensitivity
from pipeline.app.readings import reading_name
from pipeline.workspace.lines import simulate_lines
from pipeline.study import checked_commands, load_study, sweep_command
from pipeline.app.problem import build_problem
from pipeline.workspace.dispatch import fused_pays
from pipeline.workspace.compute import grid_workspace


def study_summary(name, make_cfg, catalogue, readings=None) -> pd.DataFrame:
    """The summary a run of study ``name`` gathers (``case`` and the job's flattened config),
    for the cases whose reading part is in ``readings`` (all when None)."""
    spec = load_study(name)
    rows = []
    for case, overrides in spec.cases.items():
        if readings is not None and case.split("-", 1)[1] not in readings:
            continue
        fixed = [o for o in overrides if "," not in o]
        swept = [o.strip("'").split("=", 1) for o in overrides if "," in o]
        swept += [(key, "1,2,3,4,5" if values == "catalogue" else values) for key, values in spec.sweep.items()]
        base = make_cfg(*spec.overrides, *fixed)
        keys = [key for key, _ in swept]
        jobs = []
        for setting in itertools.product(*(v.split(",") for _, v in swept)):
            cfg = copy.deepcopy(base)
            for key, value in zip(keys, setting):
                OmegaConf.update(cfg, key, float(value) if "." in value or key.startswith("robot.") else int(value))
            jobs.append((cfg, *build_problem(cfg, catalogue)))
        pays = fused_pays((cfg, problem, grid.n_points) for cfg, problem, grid in jobs)  # the case's sweep, as its plan decides
        for cfg, problem, grid in jobs:
            if cfg.analysis == "lines":
                summary = simulate_lines(cfg, problem, grid, pays)[2]
            else:
                summary = grid_workspace(cfg, problem, grid, sweep_pays=pays)[1]
            rows.append({"case": case, **summary})
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def cpr8_jobs(make_cfg, catalogue):
    return study_summary("evidence_cpr8", make_cfg, catalogue)


@pytest.fixture(scope="module")
def cpr8(cpr8_jobs):
    return evidence(cpr8_jobs)


def cell(table, fact, reading):
    row = table[(table["fact"] == fact) & (table["reading"] == reading)]
    assert len(row) == 1, (fact, reading)
    return row.iloc[0]


def test_cpr8_table_has_every_published_fact_for_every_reading(cpr8):
    assert len(cpr8) == 10 * len(FACTS["cpr8"]) == 10 * 17
    for fact in ("table2_actuator_1", "table2_actuator_2", "table2_actuator_3", "table2_accepted",
                 "fig4b_lines_whole", "fig4_agreement", "fig5_smaller", "fig5_agreement",
                 "fig6a_speed", "fig6a_torque", "fig6a_voltage", "fig6b_speed"):
        for reading in ("default", "pinv_columns=translational"):
            assert cell(cpr8, fact, reading)["matches"], (fact, reading)


@pytest.mark.parametrize("reading, expected", [
    # fact -> (value, matches, distance); the two readings of eq. (20) pull apart here
    ("pinv_columns=translational", {"table2_actuator_4": ("85.19 % (184)", False, 4),
                                    "table2_actuator_5": ("11.11 % (24)", False, 8),
                 "fig5b_much_smaller": ("95.4 % (206)", False, 12), "fig6b_torque": ("peak 0.594 × limit", False, 0.406),
                 "fig6b_voltage": ("peak 0.985 × limit", True, 0)}),
    ("default", {"table2_actuator_4": ("85.19 % (184)", False, 4), "table2_actuator_5": ("0.00 % (0)", False, 16),
                           "fig5b_much_smaller": ("83.3 % (180)", True, 0), "fig6b_torque": ("peak 1.683 × limit", True, 0),
                           "fig6b_voltage": ("peak 0.976 × limit", True, 0)}),
])
def test_where_table2_and_the_other_evidence_pull_apart(cpr8, reading, expected):
    for fact, (value, matches, distance) in expected.items():
        got = cell(cpr8, fact, reading)
        assert (got["value"], got["matches"]) == (value, matches), fact
        assert got["distance"] == pytest.approx(distance, abs=1e-3), fact


def test_the_default_reading_has_the_best_joint_score(cpr8):
    """docs/evidence.md section 1: eq. (20) with all six columns matches 15 of the 17 facts (Table 2
    alone favours the three translational columns: 13 facts). A tie (acceleration_set=colon:
    the same 15 facts and 20 points) keeps the earlier default."""
    score = scores(cpr8).set_index("reading")
    assert score.index[0] == "default"
    assert score.loc["default", ["matched", "points"]].tolist() == [15, 20]
    assert score.loc["pinv_columns=translational", ["matched", "points"]].tolist() == [13, 24]
    assert score.loc["acceleration_set=colon", ["matched", "points"]].tolist() == [15, 20]
    assert score.loc["pinv_columns=translational, xi_in_torque_limit=false", "points"] == 133
    assert (score["facts"] == 17).all()


def test_the_verdict_rests_on_two_facts_read_the_other_way(cpr8):
    """docs/evidence.md section 1: read the other way, Fig. 5b's "much smaller" alone hands the
    best score to the forces-only reading of eq. (20), and Table 2's actuator 2 alone to eq. (32)
    without xi; every other fact, Fig. 6b's torque included (a tie broken by Table 2's grid
    points), leaves the default best."""
    best = sensitivity(cpr8)
    assert best.index.tolist() == [fact.key for fact in FACTS["cpr8"]]
    assert best["fig5b_much_smaller"] == "pinv_columns=translational"
    assert best["table2_actuator_2"] == "xi_in_torque_limit=false"
    assert (best.drop(["fig5b_much_smaller", "table2_actuator_2"]) == "default").all()


# the study's case reading -> its golden case (tests/golden.yaml, the table of docs/evidence.md section 1)
GRID = {f"{pinv}{'_' + reading if reading != 'default' else ''}": f"{pinv}_{reading}"
        for pinv in ("full", "translational") for reading in ("default", "include", "colon", "jdot", "noxi")}


def test_grid_counts_under_each_reading_are_the_golden_numbers(cpr8_jobs):
    got = cpr8_jobs.sort_values("actuator").groupby("case", sort=False)["n_feasible_grid"].apply(list)
    for reading, case in GRID.items():
        assert got[f"zero-{reading}"] == values(f"{case}_zero"), reading
        assert got[f"rot05-{reading}"] == values(f"{case}_rotated"), reading
    assert set(got.index) == {f"{s}-{r}" for s in ("zero", "rot05") for r in GRID}
    for case in GRID.values():  # section 3.1.2: smaller at 0.5 rad, under every reading
        assert sum(values(f"{case}_rotated")) < sum(values(f"{case}_zero"))


def test_irpm_section_iii_conclusions_hold_exactly_under_either_cable_direction(make_cfg, catalogue):
    """docs/evidence.md section 2: under the paper's section III definition (no s_max) the count at
    zero rotation is the same for every r_end under both readings; the centre reading's one
    extra match is section IV.A (f_x = f_y = 50 kN, s_max = 55 kN)."""
    table = evidence(study_summary("evidence_irpm", make_cfg, catalogue, readings={"attachment", "centre"}))
    centre = table[table["reading"] == "cable_direction=centre"].set_index("fact")
    default = table[table["reading"] == "default"].set_index("fact")
    for g, count in ((0, 3675), (15, 2500), (30, 1375), (45, 375)):
        assert centre.loc[f"same_count_gamma_{g}", "value"] == f"{count}-{count} points"
        assert default.loc[f"same_count_gamma_{g}", "value"] == f"{count}-{count} points"
    assert centre.loc["forces_no_effect", "matches"] and not default.loc["forces_no_effect", "matches"]
    assert default.loc["forces_no_effect", "distance"] == 321
    for fact in ("smaller_gamma_larger", "no_maximum_at_ratio_1"):  # the same in both readings
        assert centre.loc[fact, "value"] == default.loc[fact, "value"]
    assert default.loc["smaller_gamma_larger", "value"] == "35 of 39 pairs"
    assert default.loc["moments_larger_end", "value"] == "2 of 4 pairs"
    assert centre.loc["moments_larger_end", "value"] == "3 of 4 pairs"
    score = scores(table).set_index("reading")
    assert score.loc["cable_direction=centre", ["matched", "points"]].tolist() == [6, 0]
    assert score.loc["default", ["matched", "points"]].tolist() == [5, 321]
    assert not centre.loc["no_maximum_at_ratio_1", "matches"]  # gamma = 45: 25 points at ratios 1 and 2
    assert sensitivity(table).to_dict() == {**{fact: "cable_direction=centre" for fact in centre.index},
                                            "forces_no_effect": "default"}


def test_a_fact_without_its_jobs_is_an_error_not_a_match():
    jobs = pd.DataFrame({"case": "fig13-x", "robot.name": "irpm6", "catalogue": None,
                         "model.moment_arm": "platform", "model.cable_direction": "attachment",
                         "robot.gamma_deg": [0.0, 0.0, 15.0, 15.0, 30.0, 30.0, 45.0, 45.0],
                         "robot.r_end": [1.2, 6.0] * 4, "robot.r_base": 6.0, "n_feasible": 10})
    with pytest.raises(ValueError, match="evidence: no jobs for set fig14, fig15"):
        evidence(jobs)
    with pytest.raises(ValueError, match="evidence: set fig13 needs two sizes or more"):
        evidence(jobs.iloc[:-1])
    with pytest.raises(ConfigError, match="no published facts for robot=points"):
        evidence(jobs.assign(**{"robot.name": "points"}))


def test_reading_names_and_units():
    assert reading_name({"model.pinv_columns": "full", "model.jdot": False}) == "default"
    assert reading_name({"model.pinv_columns": "translational"}) == "pinv_columns=translational"
    assert reading_name({"model.jdot": True, "model.acceleration_set": "colon"}) == "jdot=true, acceleration_set=colon"
    units = {fact.unit for facts in FACTS.values() for fact in facts}
    assert {POINTS, MARGIN} <= units


def test_evidence_studies_take_compute_overrides_only():
    with pytest.raises(ConfigError, match="^catalogue=mine.csv: study evidence_cpr8 checks the papers'"):
        checked_commands("evidence_cpr8", ["catalogue=mine.csv"])
    with pytest.raises(ConfigError, match="^model.pinv_columns=full: study evidence_irpm"):
        checked_commands("evidence_irpm", ["compute.n_jobs=1", "model.pinv_columns=full"])


def test_a_case_that_sweeps_names_its_jobs_by_the_swept_key():
    spec = load_study("evidence_irpm")
    command = sweep_command(spec, spec.cases["fig13-centre"], Path("j"))
    excluded = next(c for c in command if c.startswith("hydra.job.config.override_dirname.exclude_keys"))
    assert "robot.r_end" not in excluded and "robot.r_base" in excluded
    assert "model.cable_direction" in excluded

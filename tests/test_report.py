"""The reproduction report is built from study Parquet files only; dvc.yaml covers every study."""

from pathlib import Path

import pandas as pd
import pytest
import yaml

import pipeline.report
from pipeline.choice import choose
from pipeline.figures import StudyResults
from pipeline.survival import survival
from pipeline.lines import simulate_lines
from pipeline.study import available
from pipeline.workspace import compute_workspace

STUDIES = ["actuator_choice", "actuator_choice_pulling", "line_simulation", "irpm_fig13_end_ratio",
           "tension_comparison"]

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture
def studies(tmp_path, make_cfg, catalogue):
    root = tmp_path / "studies"
    for name in STUDIES:
        (root / name / "figures").mkdir(parents=True)
    summary = pd.DataFrame([compute_workspace(make_cfg(f"actuator={a}"), catalogue)[1] for a in range(1, 6)])
    summary.to_parquet(root / "actuator_choice" / "summary.parquet")
    choose(summary).to_parquet(root / "actuator_choice" / "choice.parquet")
    (root / "actuator_choice" / "figures" / "fig9.png").write_bytes(b"\x89PNG fake")
    pulling = pd.DataFrame([compute_workspace(make_cfg("tension=feasible", f"actuator={a}"), catalogue)[1]
                            for a in range(1, 6)])
    pulling.to_parquet(root / "actuator_choice_pulling" / "summary.parquet")
    choose(pulling).to_parquet(root / "actuator_choice_pulling" / "choice.parquet")
    lines = pd.DataFrame([simulate_lines(make_cfg("analysis=lines", f"actuator={a}"), catalogue)[2]
                          for a in (1, 2)]).assign(case="zero")
    lines.to_parquet(root / "line_simulation" / "summary.parquet")
    irpm = pd.DataFrame([compute_workspace(make_cfg("robot=irpm6", f"robot.r_end={r}",
                                                    f"robot.gamma_deg={g}"), catalogue)[1]
                         for r in (1.2, 6.0) for g in (0, 30)])
    irpm.to_parquet(root / "irpm_fig13_end_ratio" / "summary.parquet")
    rows = []
    for model in ("pinv", "feasible"):
        points, row = compute_workspace(make_cfg(f"tension.model={model}"), catalogue)
        (root / "tension_comparison" / "jobs" / model).mkdir(parents=True)
        points.to_parquet(root / "tension_comparison" / "jobs" / model / "points.parquet")
        rows.append({**row, "job": model, "case": "zero"})
    pd.DataFrame(rows).to_parquet(root / "tension_comparison" / "summary.parquet")
    comparison = survival(StudyResults(root / "tension_comparison"))
    comparison.to_parquet(root / "tension_comparison" / "survival.parquet")
    return root


def test_report_compares_paper_and_ours_and_carries_the_figures(studies, tmp_path, monkeypatch):
    monkeypatch.setattr(pipeline.report, "available", lambda: STUDIES)
    index = pipeline.report.build(studies, tmp_path / "report")
    text = index.read_text()
    assert "| 4 | 87.04 | 85.19 | -1.85 | voltage 32 |" in text
    assert "| 2 | 96.30 | 96.30 | +0.00 | torque 8 |" in text
    assert "Accepted at x = 90 %: paper [1, 2], ours [1, 2]." in text
    assert "| 1 | 100.00 | 66.67 | yes → no | slack 72 |" in text  # cables that only pull
    assert "| 5 | 11.11 | 14.81 | no → no | slack 72, torque 112 |" in text
    assert "Accepted at x = 90 % with pulling cables: none." in text
    assert "| translational, zero | 100.00 | 98.15 |" in text
    assert "| 0.2 | 183.2 | 64.8 |" in text
    assert "| translational, zero | 66.7 (216 → 144) |" in text
    assert "![fig9](figures/actuator_choice/fig9.png)" in text
    assert (tmp_path / "report" / "figures" / "actuator_choice" / "fig9.png").read_bytes() == b"\x89PNG fake"


def test_report_names_the_studies_without_results(tmp_path):
    with pytest.raises(FileNotFoundError, match="actuator_choice"):
        pipeline.report.build(tmp_path, tmp_path / "report")
    assert not (tmp_path / "report").exists()


def test_dvc_yaml_has_one_stage_per_study_and_a_report_on_all_of_them():
    dvc = yaml.safe_load((REPO / "dvc.yaml").read_text())
    stages = dvc["stages"]
    assert stages["study"]["foreach"] == available()
    assert stages["study"]["do"]["cmd"] == "python -m pipeline.study ${item}"
    assert {f"outputs/studies/{n}" for n in available()} <= set(stages["report"]["deps"])
    for dep in stages["study"]["do"]["deps"]:
        assert (REPO / dep.replace("${item}", available()[0])).exists()


def test_strings_from_result_files_cannot_break_the_report():
    """A criterion, case or catalogue string in a Parquet file is inert text in the Markdown:
    no table cell break, no link, no code span, no HTML tag."""
    from pipeline.report import md

    assert md("x | <script>alert(1)</script> [a](http://e) `c`") == (
        "x \\| &lt;script&gt;alert(1)&lt;/script&gt; \\[a\\](http://e) \\`c\\`")
    assert md("torque 8, tension_max 3") == "torque 8, tension_max 3"

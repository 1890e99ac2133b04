"""Your own studies, figures and report from your own folder (issue 39): ``--config-dir DIR``
gives the study and report commands the robots of ``DIR/robot/`` and the studies of
``DIR/studies/``, with nothing copied into the package. The documented example folder
(``examples/my_robot``) is run end to end, and its numbers are checked against jobs run alone."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import command, compute_workspace

from pipeline.app.plan import plan
from pipeline.app.resources import STUDIES_DIR
from pipeline.app.results import read_verified
from pipeline.errors import ConfigError
from pipeline.study import available, checked_commands, load_study

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_robot"


def run(cwd, module: str, *args: str) -> subprocess.CompletedProcess:
    """``python -m MODULE ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, module, *args)


@pytest.mark.slow
def test_the_example_folder_gives_its_study_figures_and_report(tmp_path, catalogue):
    folder = tmp_path / "my_robot"
    shutil.copytree(EXAMPLE, folder)
    package = {p.name: p.stat().st_mtime for p in STUDIES_DIR.iterdir()}
    done = run(tmp_path, "pipeline.study", "--config-dir", str(folder), "my_payload")
    assert done.returncode == 0, done.stderr[-3000:]
    out = tmp_path / "outputs" / "studies" / "my_payload"
    summary = read_verified(out / "summary.parquet").to_pandas()
    assert len(summary) == 12 and set(summary["tension.t_max"]) == {100.0, 200.0, 400.0}
    for _, row in summary.sample(3, random_state=0).iterrows():  # each job as the job run alone says
        (job,) = plan(["--config-dir", str(folder), "robot=myrobot", "tension.t_min=1", f"load.mass={row['load.mass']}",
                       f"tension.t_max={row['tension.t_max']}", "compute.n_jobs=1"]).jobs
        _, alone = compute_workspace(job.cfg, job.catalogue)
        assert alone["n_feasible"] == row["n_feasible"]
    share = summary.set_index(["tension.t_max", "load.mass"])["feasible_pct"]
    assert share[(400, 0)] == pytest.approx(40.09, abs=0.005) and share[(400, 20)] == pytest.approx(27.19, abs=0.005)
    assert share[(100, 20)] == 0  # docs/studies.md's numbers
    shares = summary.sort_values("load.mass").groupby("tension.t_max")["feasible_pct"].apply(list)
    for values in shares:  # a heavier payload never holds on more poses
        assert values == sorted(values, reverse=True)
    figures = sorted(p.name for p in (out / "figures").glob("*.png"))
    assert figures == ["feasible_share_vs_payload.png", "workspace_payload10.0_rating200.png"]
    report = run(tmp_path, "pipeline.report", "--config-dir", str(folder))
    assert report.returncode == 0, report.stderr
    text = (tmp_path / "outputs" / "report" / "index.md").read_text()
    assert "My robot: the share of the frame that holds a payload" in text
    assert "Table 2" not in text and "IRPM" not in text  # the papers' sections are the papers' studies
    assert (tmp_path / "outputs" / "report" / "figures" / "my_payload" / "feasible_share_vs_payload.png").exists()
    assert (tmp_path / "outputs" / "report" / "index.html").exists()
    assert package == {p.name: p.stat().st_mtime for p in STUDIES_DIR.iterdir()}  # nothing copied in
    # her jobs as a table (nine images and no table before): each row the summary's, and her robot
    rows = [line for line in text.splitlines() if line.startswith("| ") and line.count("|") == 7]
    assert rows[0] == "| payload (kg) | tension.t_max | poses | feasible (%) | volume (m³) | boundary volume (m³) |"
    table = {(float(r.split("|")[1]), float(r.split("|")[2])): float(r.split("|")[4]) for r in rows[2:]}
    assert len(table) == 12 and table == {(m, t): round(p, 2) for (t, m), p in share.items()}
    assert "Robot `myrobot` (points): robot.anchors: \\[\\[-2, 1.5, 2\\]" in text and "tension.t_min: 1" in text


def test_a_users_studies_are_found_in_her_folder_and_plan_with_her_robots():
    assert available(EXAMPLE / "studies") == ["my_payload"]
    study = load_study("my_payload", config_dir=EXAMPLE)
    assert study.config_dir == str(EXAMPLE)
    (command, planned), = checked_commands("my_payload", [], config_dir=EXAMPLE)
    assert command[:2] == ["--config-dir", str(EXAMPLE)]
    assert len(planned.jobs) == 12 and {job.cfg.robot.name for job in planned.jobs} == {"points"}
    assert {len(job.problem.robot.anchors) for job in planned.jobs} == {8}


def test_a_study_folder_without_studies_and_an_unknown_name_are_one_line(tmp_path):
    with pytest.raises(ConfigError, match=r"--config-dir=.*: no studies folder \(put study files in .*/studies/\)$"):
        load_study("my_payload", config_dir=tmp_path)
    with pytest.raises(ConfigError, match=r"^study 'nope' not found \(available: my_payload\)$"):
        load_study("nope", config_dir=EXAMPLE)
    done = run(tmp_path, "pipeline.study", "--config-dir", str(tmp_path), "x")
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and list(tmp_path.iterdir()) == []


def test_the_papers_studies_still_come_from_the_package():
    assert "actuator_choice" in available()
    assert load_study("actuator_choice").config_dir is None


@pytest.mark.parametrize("diameter, feasible", [(None, 463), (0.004, 461), (0.01, 371)])
def test_the_example_robot_keeps_its_workspace_under_interference(catalogue, diameter, feasible):
    """Issue 53: its crossed upper cables shared planes with their neighbours and met at every
    pose (0 of 1 155 with any diameter); at staggered heights 4 mm cables keep all but 2 of the
    463 poses the statics keep, 10 mm cables 371 (docs/robots.md), and the cables that touch
    are the crossed upper ones."""
    extra = [] if diameter is None else [f"robot.cable_diameter={diameter}"]
    (job,) = plan(["--config-dir", str(EXAMPLE), "robot=myrobot", "tension.t_min=1", "tension.t_max=400",
                   "compute.n_jobs=1", *extra]).jobs
    points, summary = compute_workspace(job.cfg, job.catalogue)
    assert summary["n_points"] == 1155 and summary["n_feasible"] == feasible
    if diameter == 0.01:
        touching = points.loc[points["limiting"] == "cable_cable", "closest_cables"].astype(str)
        assert len(touching) and set(touching) <= {"1-2", "2-3", "3-4", "1-4", "1-3", "2-4"}, set(touching)


def test_each_robot_file_of_a_study_is_named_in_its_summary_and_figure_names(tmp_path):
    """Every user robot reports robot.name = points, so '{robot_name}' in a figure's file wrote one
    file over itself: the summary names each job's robot file (robot_file), which figure names use."""
    folder = tmp_path / "mine"
    shutil.copytree(EXAMPLE, folder)
    text = (folder / "robot" / "myrobot.yaml").read_text()
    (folder / "robot" / "wide.yaml").write_text(text.replace("0.06", "0.08"))
    (folder / "studies" / "two.yaml").write_text(
        "title: t\nsource: s\noverrides: [tension.t_min=1, tension.t_max=400]\nsweep: {robot: 'myrobot,wide'}\n"
        "figures:\n  - {kind: cloud, file: 'cloud_{robot_file}.png'}\n")
    done = run(tmp_path, "pipeline.study", "--config-dir", str(folder), "--out", str(tmp_path / "out"), "two")
    assert done.returncode == 0, done.stderr[-3000:]
    summary = read_verified(tmp_path / "out" / "two" / "summary.parquet").to_pandas()
    assert sorted(summary["robot_file"]) == ["myrobot", "wide"] and set(summary["robot.name"]) == {"points"}
    assert summary.set_index("robot_file").loc["myrobot", "n_feasible"] == 463  # the example's, alone
    figures = sorted(p.name for p in (tmp_path / "out" / "two" / "figures").glob("cloud_*.png"))
    assert figures == ["cloud_myrobot.png", "cloud_wide.png"] and "drawings were written" not in done.stderr


@pytest.mark.slow
def test_the_documented_dvc_stage_of_a_users_study_runs_and_stays_up_to_date(tmp_path):
    """docs/studies.md's stage, as written there, in a repository of the user's: dvc repro runs
    the study, and a second repro has nothing to do (the jobs' records of their absolute paths
    are ignored, as the doc says)."""
    import re
    import sys

    text = (Path(__file__).resolve().parents[1] / "docs" / "studies.md").read_text()
    stage = re.search(r"```yaml\n(stages:\n  my_payload:.*?)```", text, re.S).group(1)
    shutil.copytree(EXAMPLE, tmp_path / "examples" / "my_robot")
    (tmp_path / "dvc.yaml").write_text(stage)
    (tmp_path / ".dvcignore").write_text("hydra.yaml\nmultirun.yaml\npipeline.log\n")
    dvc = [sys.executable, "-m", "dvc"]
    for args in (["init", "--no-scm", "-q"], ["repro", "-q"]):
        done = subprocess.run([*dvc, *args], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "outputs" / "studies" / "my_payload" / "summary.parquet").is_file()
    status = subprocess.run([*dvc, "status"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert status.returncode == 0 and "up to date" in status.stdout, status.stdout

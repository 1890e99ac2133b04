"""DVC as its users work (dvc.yaml): reproduce a study stage, change parameters with
`dvc exp run -S`, compare with `dvc metrics diff`, draw with `dvc plots show`. Runs in a copy of
the working tree made into its own git repository, whose code the stages import."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

pytestmark = pytest.mark.slow
REPO = Path(__file__).resolve().parent.parent
STAGE = "study@actuator_choice"
METRICS = "outputs/studies/actuator_choice/metrics.json"


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    """A committed copy of this working tree, its actuator_choice stage reproduced and the
    stage's lock and metrics committed, as a DVC user's repository would be."""
    root = tmp_path_factory.mktemp("dvc") / "repo"
    shutil.copytree(REPO, root, symlinks=True, ignore=shutil.ignore_patterns(
        ".git", "outputs", "build", "*.egg-info", "__pycache__", ".pytest_cache", ".venv", "tmp", "cache"))
    # this interpreter's DVC (a test extra: missing, the tests fail), and its python for the
    # stages' `python -m pipeline.study`, whether or not its environment is activated
    env = {**os.environ, "PYTHONPATH": str(root),
           "PATH": os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")]),
           "GIT_AUTHOR_NAME": "t", "GIT_AUTHOR_EMAIL": "t@t", "GIT_COMMITTER_NAME": "t",
           "GIT_COMMITTER_EMAIL": "t@t", "DVC_NO_ANALYTICS": "1"}

    def run(*args, check=True):
        if args[0] == "dvc":
            args = (sys.executable, "-m", "dvc", *args[1:])
        done = subprocess.run(args, cwd=root, env=env, capture_output=True, text=True, timeout=600)
        if check:
            assert done.returncode == 0, f"{args}: {done.stdout}\n{done.stderr}"
        return done

    run("git", "init", "-q")
    run("git", "add", "-A")
    run("git", "commit", "-q", "-m", "copy")
    run("dvc", "repro", STAGE)
    run("git", "add", "dvc.lock", METRICS)
    run("git", "commit", "-q", "-m", "reproduced")
    return root, run


def test_repro_writes_the_study_metrics_and_a_lock(project):
    root, run = project
    metrics = json.loads((root / METRICS).read_text())
    assert metrics["accepted"] == "1, 2" and metrics["n_accepted"] == 2
    assert metrics["feasible_pct"] == pytest.approx({"min": 0.0, "median": 85.185185, "max": 100.0})
    assert STAGE in (root / "dvc.lock").read_text()
    status = run("dvc", "status", STAGE)
    assert "up to date" in status.stdout, status.stdout  # no .pyc or link makes it look changed


def test_exp_run_changes_params_yaml_never_conf_and_a_plain_run_after_it_is_unchanged(project, tmp_path):
    """An experiment's parameters go to params.yaml, which the study stages pass as overrides: a
    lighter carrier and a lower required share accept every actuator; conf/ is untouched, so a
    plain command after the experiment still gives Table 2's 85.19 % for actuator 3."""
    root, run = project
    run("dvc", "exp", "run", "-S", "+robot.platform.mass=0.5", "-S", "+choice.required_pct=80", STAGE)
    diff = json.loads(run("dvc", "metrics", "diff", "--json").stdout)
    changed = diff[METRICS]
    assert changed["n_accepted"] == {"old": 2, "new": 5, "diff": 3}
    assert changed["feasible_pct.min"]["old"] == pytest.approx(0.0)
    assert changed["feasible_pct.min"]["new"] == pytest.approx(85.185185)
    params = json.loads(run("dvc", "params", "diff", "--json").stdout)
    mass = params["params.yaml"]["robot.platform.mass"]
    assert (mass["old"], mass["new"]) == (None, 0.5)
    assert "n_accepted" in run("dvc", "exp", "show", "--json").stdout
    assert run("git", "status", "--porcelain", "--", "conf", "pipeline", "studies").stdout == ""
    run(sys.executable, "-m", "pipeline", "actuator=3", f"hydra.run.dir={tmp_path / 'plain'}")
    summary = pq.read_table(tmp_path / "plain" / "summary.parquet").to_pylist()[0]
    assert summary["feasible_pct"] == pytest.approx(85.185185) and summary["robot.platform.mass"] == 2.0


def test_a_plain_rerun_of_a_reproduced_study_leaves_its_stage_up_to_date(project):
    """The study run again outside DVC, at the same code, writes byte-identical results; only the
    jobs' logs (timestamps, in .dvcignore) differ, so DVC has nothing to reproduce."""
    root, run = project
    run("git", "stash", "--include-untracked")  # the experiment's params.yaml, if it ran first
    run("dvc", "checkout", "--force")
    run("dvc", "repro", STAGE)
    run(sys.executable, "-m", "pipeline.study", "actuator_choice", "--params", "params.yaml", "--out", "outputs/studies",
        "--force")
    status = run("dvc", "status", STAGE)
    assert "up to date" in status.stdout, status.stdout


def test_metrics_show_is_one_narrow_table():
    """Every study's metrics.json (committed, from the last `dvc repro`) holds a few keys shared
    by all studies, so `dvc metrics show` is a table one can read (it was 7 880 characters wide)."""
    done = subprocess.run([sys.executable, "-m", "dvc", "metrics", "show"], cwd=REPO, capture_output=True, text=True,
                          timeout=300, env={**os.environ, "DVC_NO_ANALYTICS": "1"})
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 1 + len(list((REPO / "studies").glob("*.yaml"))), done.stdout
    assert max(len(line) for line in lines) < 300, done.stdout


def test_plots_show_renders_the_figures(project):
    root, run = project
    run("dvc", "plots", "show", "-o", "plots_html")
    page = (root / "plots_html" / "index.html").read_text()
    assert "fig9_feasible_share_by_actuator.png" in page
    assert "fig8_workspace_actuator1.png" in page


def test_the_study_stages_read_every_config_file_and_params_yaml():
    """What a study's results depend on: the code, every file of conf/ and the study file are
    the stages' deps, and params.yaml (empty as committed) their parameters."""
    import yaml

    stage = yaml.safe_load((REPO / "dvc.yaml").read_text())["stages"]["study"]["do"]
    assert stage["deps"] == ["pipeline", "conf", "studies/${item}.yaml"]
    assert stage["params"] == [{"params.yaml": None}]
    assert "--params params.yaml" in stage["cmd"]
    assert yaml.safe_load((REPO / "params.yaml").read_text()) == {}

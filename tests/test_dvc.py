"""DVC as its users work (dvc.yaml): reproduce a study stage, change parameters with
`dvc exp run -S`, compare with `dvc metrics diff`, draw with `dvc plots show`. Runs in a copy of
the working tree made into its own git repository, whose code the stages import."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

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
    assert metrics["feasible_pct"]["actuator=3"] == pytest.approx(85.185185)
    assert STAGE in (root / "dvc.lock").read_text()
    status = run("dvc", "status", STAGE)
    assert "up to date" in status.stdout, status.stdout  # no .pyc or link makes it look changed


def test_exp_run_with_changed_parameters_shows_in_metrics_diff(project):
    """conf/config.yaml is a params file DVC can change (Hydra's own settings live in
    conf/hydra_settings.yaml), and so are the robot files: a lighter carrier and a lower x accept
    every actuator."""
    root, run = project
    run("dvc", "exp", "run", "-S", "conf/robot/cpr8.yaml:robot.platform.mass=0.5",
        "-S", "conf/analysis/cpr_wwa.yaml:choice.required_pct=80", STAGE)
    diff = json.loads(run("dvc", "metrics", "diff", "--json").stdout)
    changed = diff[METRICS]
    assert changed["n_accepted"] == {"old": 2, "new": 5, "diff": 3}
    assert changed["feasible_pct.actuator=5"]["old"] == pytest.approx(0.0)
    assert changed["feasible_pct.actuator=5"]["new"] == pytest.approx(85.185185)
    params = json.loads(run("dvc", "params", "diff", "--json").stdout)
    mass = params["conf/robot/cpr8.yaml"]["robot.platform.mass"]
    assert (mass["old"], mass["new"]) == (2.0, 0.5)
    shown = run("dvc", "exp", "show", "--json").stdout
    assert "n_accepted" in shown


def test_plots_show_renders_the_figures(project):
    root, run = project
    run("dvc", "plots", "show", "-o", "plots_html")
    page = (root / "plots_html" / "index.html").read_text()
    assert "fig9_feasible_share_by_actuator.png" in page
    assert "fig8_workspace_actuator1.png" in page


def test_every_key_of_the_tension_files_is_a_dvc_parameter():
    """`dvc params diff` and `dvc exp show` list what a study's results depend on: every key of
    the tension group (tension.pinv_residual was missing when it was added)."""
    import yaml

    listed = {}
    for entry in yaml.safe_load((REPO / "dvc.yaml").read_text())["stages"]["study"]["do"]["params"]:
        listed.update(entry)
    for name in ("pinv", "feasible"):
        path = f"conf/tension/{name}.yaml"
        keys = set(yaml.safe_load((REPO / path).read_text())) - {"defaults"}
        assert keys == set(listed[path]), path

"""A plain (not editable) install runs from any folder: the wheel carries the configs and the
declared studies, and its console scripts work without the repository."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from pipeline.app.results import code_version

pytestmark = pytest.mark.slow
REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel built from this checkout, installed into its own folder (dependencies come
    from the test environment); returns (folder, environment that imports it first)."""
    root = tmp_path_factory.mktemp("install")
    source = root / "source"  # a copy: building writes build/ and *.egg-info beside the sources
    shutil.copytree(REPO, source, symlinks=True, ignore=shutil.ignore_patterns(
        ".git", "outputs", "build", "*.egg-info", "__pycache__", ".pytest_cache", ".venv"))
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w",
                            str(root / "wheel"), str(source)], capture_output=True, text=True, timeout=600)
    assert built.returncode == 0, built.stderr
    (wheel,) = (root / "wheel").glob("cdpr_studies-*.whl")
    target = root / "site"
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target",
                           str(target), str(wheel)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    env = {**os.environ, "PYTHONPATH": str(target)}
    return target, env


def test_the_wheel_carries_configs_and_studies(installed):
    target, _ = installed
    assert (target / "pipeline" / "conf" / "config.yaml").is_file()
    assert not (target / "pipeline" / "conf").is_symlink()
    assert sorted(p.name for p in (target / "pipeline" / "conf" / "robot").glob("*.yaml")) == [
        "cpr8.yaml", "irpm6.yaml", "points.yaml"]
    assert len(list((target / "pipeline" / "studies").glob("*.yaml"))) == len(list((REPO / "studies").glob("*.yaml")))


def test_console_script_runs_the_main_job_from_an_empty_folder(installed, tmp_path):
    target, env = installed
    where = subprocess.run([sys.executable, "-c", "import pipeline; print(pipeline.__file__)"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert where.stdout.strip() == str(target / "pipeline" / "__init__.py")
    done = subprocess.run([str(target / "bin" / "cdpr"), "-m", "actuator=1,2,3,4,5",
                           "hydra.sweep.dir=main"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    table = pd.read_parquet(tmp_path / "main" / "summary.parquet")
    assert table["n_feasible"].tolist() == [216, 208, 184, 184, 0]  # Table 2 of the paper's model
    assert "results in main (5 job folders)" in done.stdout
    listed = subprocess.run([str(target / "bin" / "cdpr-study"), "--list"], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=120)
    assert listed.returncode == 0 and "actuator_choice:" in listed.stdout
    version = subprocess.run([str(target / "bin" / "cdpr"), "--version"], cwd=tmp_path, env=env,
                             capture_output=True, text=True, timeout=120)
    # the version names the package's files, so the installed copy's is this checkout's
    assert version.stdout.startswith(f"cdpr-studies {code_version()} (Hydra ")


def test_bad_input_through_the_console_script_is_one_line_exit_2(installed, tmp_path):
    target, env = installed
    done = subprocess.run([str(target / "bin" / "cdpr"), "actuator=9"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "error: actuator=9: no such id in the catalogue (ids: 1, 2, 3, 4, 5)"]
    assert list(tmp_path.iterdir()) == []

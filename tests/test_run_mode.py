"""A command of run mode (``python -m pipeline key=value ...``) runs its job through the pipeline's
plan and runner: it must write, log and print exactly what Hydra's own application does with the
same command (``--run``, a flag Hydra answers, hands the command to Hydra: pipeline.app.cli)."""

import re
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

STAMP = re.compile(r"^\[\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3}\]", re.MULTILINE)


def outcome(cwd: Path, folder: str, *args: str) -> dict:
    """Everything a run leaves in ``folder`` and prints, with the folder's name and the log's
    time stamps replaced, so two runs into two folders compare."""
    done = subprocess.run([sys.executable, "-m", "pipeline", *args, f"hydra.run.dir={folder}"], cwd=cwd,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]

    def neutral(text: str) -> str:
        return STAMP.sub("[T]", text.replace(str(cwd / folder), "<out>").replace(folder, "<out>"))

    files = {}
    for path in sorted((cwd / folder).rglob("*")):
        if path.is_file() and path.name != ".lock":
            name = str(path.relative_to(cwd / folder))
            files[name] = (pq.read_table(path).to_pylist() if path.suffix == ".parquet"
                           else neutral(path.read_text()))
    return {"files": files, "stdout": neutral(done.stdout), "stderr": neutral(done.stderr)}


@pytest.mark.slow
@pytest.mark.parametrize("args", [
    ["actuator=3", "grid.n=4"],
    ["robot=irpm6", "robot.search.step=1", "robot.gamma_deg=20", "wrench.fx=100", "hydra/job_logging=none"],
    ["tension=feasible", "grid.n=3", "hydra.job.chdir=true", "load.mass=3"],
])
def test_a_command_of_run_mode_does_what_hydras_run_does(tmp_path, args):
    ours, hydras = outcome(tmp_path, "ours", *args), outcome(tmp_path, "hydras", "--run", *args)
    assert ours == hydras
    logged = () if "hydra/job_logging=none" in args else ("pipeline.log",)
    assert {".hydra/config.yaml", ".hydra/hydra.yaml", ".hydra/overrides.yaml", "summary.parquet",
            "points.parquet", *logged} == set(ours["files"])
    assert "mode: RUN" in ours["files"][".hydra/hydra.yaml"]

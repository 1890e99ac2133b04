"""Writers that cannot collide and results verified before reuse (issue 16, items 5 and 6),
end to end through the command line."""

import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from conftest import command
from pipeline.app.job import folder_lock
from pipeline.app.results import read_metadata

pytestmark = pytest.mark.slow


def start(cwd, *args):
    """``python -m pipeline ARGS`` started in a process of its own (writers at once)."""
    return subprocess.Popen([sys.executable, "-m", "pipeline", *args], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def run(cwd, *args):
    """``python -m pipeline ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, "pipeline", *args)


def test_a_second_writer_of_the_same_folder_stops_and_the_first_result_is_intact(tmp_path):
    """While a writer holds a job folder (here this process, with the lock a job takes), a second
    job into it, of another config, stops in one line (exit 2) and leaves every file as it was."""
    assert start(tmp_path, "grid.n=4", "hydra.run.dir=same").wait(timeout=300) == 0
    same = tmp_path / "same"
    before = {path.name: path.read_bytes() for path in same.iterdir() if path.suffix == ".parquet"}
    with folder_lock(same):
        second = start(tmp_path, "grid.n=4", "actuator=2", "hydra.run.dir=same")
        _, err = second.communicate(timeout=300)
    assert second.returncode == 2 and err.strip().splitlines() == [
        f"error: {same}: another run is writing this folder; wait for it or choose "
        "another (hydra.run.dir=...)"]
    assert {path.name: path.read_bytes() for path in same.iterdir() if path.suffix == ".parquet"} == before
    assert "actuator: 1" in read_metadata(same / "points.parquet")["cdpr.config"]
    assert not list(same.glob(".*.tmp"))


def test_default_run_folders_of_the_same_second_differ(tmp_path):
    runs = [start(tmp_path, "grid.n=3") for _ in range(2)]
    for run in runs:
        assert run.wait(timeout=300) == 0
    assert len(list((tmp_path / "outputs" / "runs").iterdir())) == 2


def edit_value(path: Path, column: str, value) -> None:
    """Change one value of a Parquet table as an editing tool would: the file's metadata kept."""
    table = pq.read_table(path)
    index = table.column_names.index(column)
    edited = table.set_column(index, column, pa.array([value] * table.num_rows, table.schema.field(column).type))
    pq.write_table(edited.replace_schema_metadata(table.schema.metadata), path)


@pytest.mark.parametrize("damage", ["truncate_summary", "flip_points", "delete_points", "edit_summary"])
def test_a_damaged_finished_job_is_recomputed_not_reused(tmp_path, damage):
    args = ["grid.n=4", "hydra.run.dir=job"]
    assert run(tmp_path, *args).returncode == 0
    job = tmp_path / "job"
    good = pd.read_parquet(job / "points.parquet")
    if damage == "truncate_summary":
        (job / "summary.parquet").write_bytes((job / "summary.parquet").read_bytes()[:300])
    elif damage == "flip_points":
        data = bytearray((job / "points.parquet").read_bytes())
        data[len(data) // 2] ^= 0xFF
        (job / "points.parquet").write_bytes(bytes(data))
    elif damage == "edit_summary":  # 64 -> 1 feasible, its digests kept: a rerun must not trust it
        edit_value(job / "summary.parquet", "n_feasible", 1)
    else:
        (job / "points.parquet").unlink()
    proc = run(tmp_path, *args)
    assert proc.returncode == 0, proc.stderr
    assert "recomputing" in (job / "pipeline.log").read_text()
    pd.testing.assert_frame_equal(pd.read_parquet(job / "points.parquet"), good)
    assert pd.read_parquet(job / "summary.parquet")["n_points"].tolist() == [64]
    assert pd.read_parquet(job / "summary.parquet")["n_feasible"].tolist() == [good["feasible"].sum()] != [1]


@pytest.fixture(scope="module")
def finished_study(tmp_path_factory):
    """A finished run of the study design_v_max (copied by each test that damages it)."""
    root = tmp_path_factory.mktemp("finished")
    first = command(root, "pipeline.study", "design_v_max", "--out", "out")
    assert first.returncode == 0, first.stderr
    return root / "out"


@pytest.mark.parametrize("damage", ["flip_points", "truncate_summary", "edit_summary"])
def test_figures_only_refuses_a_damaged_job_and_keeps_the_old_figures(tmp_path, finished_study, damage):
    """--figures-only draws from the finished jobs as they are: a job file changed since it
    finished is named (one line, exit 2) before any old figure is removed; a full rerun then
    recomputes it (run for one damage: that each damage is recomputed is
    test_a_damaged_finished_job_is_recomputed_not_reused's, per job)."""
    study = ["design_v_max", "--out", "out"]
    shutil.copytree(finished_study, tmp_path / "out")
    out = tmp_path / "out" / "design_v_max"
    figures = {p.name: p.read_bytes() for p in (out / "figures").iterdir()}
    job = out / "jobs" / "actuator=2,motion.v_max=0.8"
    name = "points.parquet" if damage == "flip_points" else "summary.parquet"
    data = bytearray((job / name).read_bytes())
    if damage == "flip_points":
        data[len(data) // 2] ^= 0xFF
    if damage == "edit_summary":
        edit_value(job / name, "feasible_pct", 100.0)
    else:
        (job / name).write_bytes(bytes(data if damage == "flip_points" else data[:300]))
    redraw = command(tmp_path, "pipeline.study", *study, "--figures-only")
    assert redraw.returncode == 2
    (line,) = redraw.stderr.strip().splitlines()
    assert line.startswith(f"error: out/design_v_max/jobs/actuator=2,motion.v_max=0.8: {name}")
    assert line.endswith("rerun the study without --figures-only to recompute it")
    assert {p.name: p.read_bytes() for p in (out / "figures").iterdir()} == figures
    if damage != "flip_points":
        return
    again = command(tmp_path, "pipeline.study", *study)
    assert again.returncode == 0, again.stderr
    assert {p.name: p.read_bytes() for p in (out / "figures").iterdir()} == figures


def test_a_summary_only_job_writes_no_points_and_is_reused(tmp_path):
    """output.points=false: the summary only (the same counts), recorded as such, so a rerun
    reuses it instead of recomputing; output.cables needs the points table."""
    args = ["robot=irpm6", "robot.search.step=1", "hydra.run.dir=job"]
    assert run(tmp_path, *args, "hydra.run.dir=full").returncode == 0
    assert run(tmp_path, *args, "output.points=false").returncode == 0
    job = tmp_path / "job"
    assert not (job / "points.parquet").exists() and (job / "summary.parquet").exists()
    full = pd.read_parquet(tmp_path / "full" / "summary.parquet").iloc[0]
    lean = pd.read_parquet(job / "summary.parquet").iloc[0]
    assert (lean["n_feasible"], lean["n_points"]) == (full["n_feasible"], full["n_points"])
    assert read_metadata(job / "summary.parquet")["cdpr.digests"] == "{}"
    assert run(tmp_path, *args, "output.points=false").returncode == 0
    assert "reused the finished job" in (job / "pipeline.log").read_text()
    refused = run(tmp_path, "output.points=false", "output.cables=true", "hydra.run.dir=c")
    assert refused.returncode == 2 and refused.stderr.strip().splitlines() == [
        "error: output.cables=true: the cables go into points.parquet, which output.points=false "
        "does not write"]
    assert not (tmp_path / "c").exists()


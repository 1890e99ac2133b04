"""compute.backend=dask: the same chunks on a local Dask distributed cluster, the same results."""

import dataclasses
import subprocess
import sys

import pandas as pd
import pytest

from conftest import compute_workspace

pytestmark = pytest.mark.slow


def test_kernel_chunks_on_a_local_dask_cluster_equal_the_local_result(make_cfg, catalogue):
    overrides = ["actuator=4", "grid.n=10", "compute.chunk_size=200",
                 "orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5"]
    local, _ = compute_workspace(make_cfg(*overrides), catalogue)
    cfg = make_cfg(*overrides, "compute.backend=dask", "compute.n_jobs=2")
    distributed, summary = compute_workspace(cfg, catalogue)
    pd.testing.assert_frame_equal(distributed, local)
    assert summary["n_feasible"] == local["feasible"].sum()


def test_small_study_on_dask_equals_the_local_study(tmp_path):
    """The study command with every job's chunks on a Dask cluster (a catalogue of two of
    Table 1's actuators: one cluster for both) gives the choice the same jobs give computed here
    (the API, one process)."""
    from pipeline import api
    from pipeline.model.catalogue import TABLE1

    pd.read_csv(TABLE1, dtype=str).iloc[[1, 2]].to_csv(tmp_path / "two.csv", index=False)
    catalogue = f"catalogue={tmp_path / 'two.csv'}"
    proc = subprocess.run(
        [sys.executable, "-m", "pipeline.study", "actuator_choice", "--launcher", "serial",
         "--out", "dask", catalogue, "compute.backend=dask", "compute.chunk_size=50"],
        cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    local = api.actuator_choice([catalogue, "compute.n_jobs=1"], folder=tmp_path / "local").table
    dask = pd.read_parquet(tmp_path / "dask" / "actuator_choice" / "choice.parquet")
    shared = [c for c in dask.columns if c in local.columns and not c.startswith("compute.")]
    assert {"actuator", "feasible_pct", "accepted"} <= set(shared)
    pd.testing.assert_frame_equal(dask[shared].reset_index(drop=True), local[shared].reset_index(drop=True))
    assert dask["actuator"].tolist() == [2, 3] and dask["accepted"].tolist() == [True, False]
    clusters = {line.rsplit(" ", 1)[1] for number in (2, 3) for line in (
        tmp_path / "dask" / "actuator_choice" / "jobs" / f"actuator={number}" / "pipeline.log").read_text().splitlines()
        if "chunks on the Dask cluster tcp://" in line}
    assert len(clusters) == 1, clusters


def test_a_local_dask_cluster_is_capped_at_the_cores_like_loky(make_cfg, catalogue, monkeypatch, caplog):
    """compute.backend=dask compute.n_jobs=8 started 10 processes on 2 cores (loky was capped,
    Dask was not): a cluster started here gets at most one worker per core, with the warning."""
    import os

    import dask.distributed

    started = []

    class Refused(Exception):
        """Raised instead of starting the cluster: the test needs only its size."""

    def cluster(n_workers, **_):
        started.append(n_workers)
        raise Refused

    monkeypatch.setattr(dask.distributed, "LocalCluster", cluster)
    cfg = make_cfg("grid.n=10", "compute.chunk_size=100", "compute.backend=dask", "compute.n_jobs=8")
    with caplog.at_level("WARNING"), pytest.raises(Refused):
        compute_workspace(cfg, catalogue)
    assert started == [min(8, os.cpu_count())]
    assert any("capped at the" in r.getMessage() for r in caplog.records) == (os.cpu_count() < 8)


def test_a_sweep_starts_one_cluster_and_only_for_jobs_of_several_chunks(tmp_path, make_cfg, catalogue):
    """Five jobs each split into chunks share one local cluster (a cluster per job cost 1.8 s
    each); five that fit in one chunk each (a chunk on Dask is at least 0.2 s of kernel by the
    cost model: 27 000 fused poses) start none. The tables are those of the same jobs computed
    here, in one process."""
    def sweep(name, n, kernel, *overrides):
        done = subprocess.run([sys.executable, "-m", "pipeline", "-m", "actuator=1,2,3,4,5", f"grid.n={n}",
                               f"compute.kernel={kernel}", f"hydra.sweep.dir={tmp_path / name}", *overrides],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        here = pd.DataFrame([compute_workspace(make_cfg(f"actuator={a}", f"grid.n={n}", f"compute.kernel={kernel}"),
                                               catalogue)[1]
                             for a in range(1, 6)])
        return done.stdout + done.stderr, pd.read_parquet(tmp_path / name / "summary.parquet"), here

    columns = ["actuator", "n_points", "n_feasible", "feasible_pct"]
    # 8 000 poses of the numpy kernel: four chunks a job; 27 000 of the fused one: one chunk
    log, shared, here = sweep("shared", 20, "numpy", "compute.backend=dask", "compute.chunk_size=2000")
    clusters = [line.rsplit(" ", 1)[1] for line in log.splitlines() if "chunks on the Dask cluster" in line]
    assert len(clusters) == 5 and len(set(clusters)) == 1, log
    pd.testing.assert_frame_equal(shared[columns], here[columns])
    log, small, here = sweep("small", 30, "fused", "compute.backend=dask")
    assert "Dask cluster" not in log
    pd.testing.assert_frame_equal(small[columns], here[columns])


def test_a_dask_chunk_holds_at_least_a_fifth_of_a_second_of_kernel(make_cfg, catalogue):
    """By default (compute.chunk_size=null): 20 000 poses, on Dask at least 0.2 s of kernel by
    the cost model (a task's round trip through the scheduler costs milliseconds); a number is
    used as given, and the memory budget bounds both."""
    from pipeline.app.problem import build_problem
    from pipeline.workspace.dispatch import DASK_CHUNK_S, bounded_chunk_size, estimated_seconds

    problem, _ = build_problem(make_cfg("orientation.psi=0.5"), catalogue)
    fused = dataclasses.replace(problem, fused=True)
    assert bounded_chunk_size(fused, None) == 20_000  # compute.chunk_size=null: the cost model's
    size = bounded_chunk_size(fused, None, "dask")
    assert size == 200_000 and estimated_seconds(fused, size) == pytest.approx(DASK_CHUNK_S)
    assert bounded_chunk_size(fused, 500, "dask") == 500  # a number is taken as given
    assert bounded_chunk_size(fused, 10**9) == 4_000_000 // 8  # its (poses x 8 cables) outputs within 32 MB
    # 0.2 s of the numpy kernel would be 30 000 poses; the memory budget (8 cables x 12 extremes) bounds it
    assert bounded_chunk_size(problem, None, "dask") == 500_000 // (8 * 12)
    dense, _ = build_problem(make_cfg("orientation.psi=0.5", "grid.n_vel=60"), catalogue)
    assert bounded_chunk_size(dense, None, "dask") == bounded_chunk_size(dense, 10**9) < 1_000  # memory bounds


def test_a_scheduler_started_as_the_docs_say_gets_the_chunks_and_gives_the_loky_tables(tmp_path):
    """docs/reproduce.md's recipe: `dask scheduler`, `dask worker ADDRESS` (here on this
    machine, two single-threaded workers), then compute.backend=dask compute.scheduler=ADDRESS:
    the job's chunks go there and its points are those of loky."""
    import json
    import time

    from dask.distributed import Client

    info = tmp_path / "scheduler.json"
    cli = [sys.executable, "-m", "distributed.cli.dask_scheduler", "--port", "0", "--no-dashboard",
           "--scheduler-file", str(info)]
    scheduler = subprocess.Popen(cli, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        for _ in range(600):
            if info.exists() and info.read_text().strip():
                break
            time.sleep(0.05)
        address = json.loads(info.read_text())["address"]
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "2",
                                   "--nthreads", "1", "--no-dashboard"], cwd=tmp_path,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)

        def job(name, *overrides):
            done = subprocess.run([sys.executable, "-m", "pipeline", "grid.n=20", "compute.kernel=numpy",
                                   "compute.chunk_size=2000", "orientation.psi=0.3", "actuator=3", f"hydra.run.dir={name}",
                                   *overrides], cwd=tmp_path, capture_output=True, text=True, timeout=600)
            assert done.returncode == 0, done.stderr
            return done.stdout + done.stderr, pd.read_parquet(tmp_path / name / "points.parquet")

        log, remote = job("remote", "compute.backend=dask", f"compute.scheduler={address}")
        assert f"chunks on the Dask cluster {address}" in log
        log, _ = job("one_chunk", "grid.n=4", "compute.backend=dask", f"compute.scheduler={address}")
        assert f"chunks on the Dask cluster {address}" in log  # a named scheduler gets even one chunk
        _, local = job("local")
        pd.testing.assert_frame_equal(remote, local)
        assert 0 < remote["feasible"].sum() < len(remote)
    finally:
        for process in (worker, scheduler):
            if process is not None:
                process.terminate()
                process.wait(timeout=60)


def test_a_named_scheduler_that_does_not_answer_is_one_line_and_nothing_is_written(tmp_path, monkeypatch):
    """It computed here instead, exit 0, with no word (issue 51): nothing listens on the
    loopback's port 9."""
    from conftest import command
    from pipeline.workspace import parallel

    monkeypatch.setattr(parallel, "SCHEDULER_TIMEOUT_S", 1)
    done = command(tmp_path, "pipeline", "compute.backend=dask", "compute.scheduler=tcp://127.0.0.1:9",
                   f"hydra.run.dir={tmp_path / 'run'}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("error: compute.scheduler=tcp://127.0.0.1:9: no Dask scheduler answers there")
    assert not (tmp_path / "run").exists()

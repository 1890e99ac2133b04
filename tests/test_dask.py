"""compute.backend=dask: the same chunks on a local Dask distributed cluster, the same results."""

import subprocess
import sys

import pandas as pd
import pytest

from pipeline.app.problem import compute_workspace

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
    Table 1's actuators: one cluster per job) gives the choice the same jobs give computed here
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
    log = (tmp_path / "dask" / "actuator_choice" / "jobs" / "actuator=2" / "pipeline.log").read_text()
    assert "chunks on the Dask cluster tcp://" in log


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

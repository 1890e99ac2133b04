"""Chunks on worker threads or processes: chosen by the cost model, and giving the result of one process."""

import dataclasses

import pandas as pd
import pytest

from pipeline.workspace import dispatch
from pipeline.workspace.dispatch import worth_workers
from pipeline.app.problem import build_problem
from conftest import compute_workspace


def test_workers_only_when_the_kernel_outlasts_their_start(make_cfg, catalogue):
    problem, _ = build_problem(make_cfg(), catalogue)
    feasible, _ = build_problem(make_cfg("tension=feasible"), catalogue)
    # 2 x 0.4 s of start at 150 000 (pinv) or 20 000 (feasible) poses/s: 120 000 and 16 000 poses
    assert worth_workers(problem, 119_000, 2, "loky") == 1
    assert worth_workers(problem, 121_000, 2, "loky") == 2
    assert worth_workers(feasible, 15_000, 2, "loky") == 1
    assert worth_workers(feasible, 17_000, 2, "loky") == 2
    assert worth_workers(feasible, 17_000, -1, "loky") == -1
    assert worth_workers(problem, 10, 2, "dask") == 2  # a cluster is the user's explicit choice
    orientations = build_problem(make_cfg("orientation.total.bound=0.1", "orientation.total.n=3"), catalogue)[0]
    assert len(orientations.orientations) == 27
    assert worth_workers(orientations, 5_000, 2, "loky") == 2  # 135 000 evaluations
    fused = dataclasses.replace(problem, fused=True)  # FUSED_WORKERS_FROM_S = 1.5 s at 10^6 poses/s
    assert worth_workers(fused, 1_400_000, 2, "loky") == 1
    assert worth_workers(fused, 1_600_000, 2, "loky") == 2
    # threads start for 2 x 0.1 s: 30 000 poses (pinv), 4 000 (feasible), 200 000 (fused)
    assert worth_workers(problem, 29_000, 2, "threading") == 1
    assert worth_workers(problem, 31_000, 2, "threading") == 2
    assert worth_workers(feasible, 3_900, 2, "threading") == 1
    assert worth_workers(feasible, 4_100, 2, "threading") == 2
    assert worth_workers(fused, 190_000, 2, "threading") == 1
    assert worth_workers(fused, 210_000, 2, "threading") == 2


@pytest.mark.parametrize("backend", ["threading", "loky"])
def test_chunks_on_two_workers_equal_one_process(backend, make_cfg, catalogue, monkeypatch):
    serial, serial_summary = compute_workspace(make_cfg("grid.n=12", "compute.chunk_size=300"), catalogue)
    monkeypatch.setattr(dispatch, "WORKER_START_S", 0.0)  # workers even for 1 728 poses
    monkeypatch.setattr(dispatch, "THREAD_START_S", 0.0)
    cfg = make_cfg("grid.n=12", "compute.chunk_size=300", "compute.n_jobs=2", f"compute.backend={backend}")
    parallel, summary = compute_workspace(cfg, catalogue)
    pd.testing.assert_frame_equal(parallel, serial)
    assert summary.pop("compute.n_jobs") == 2 and serial_summary.pop("compute.n_jobs") == 1
    assert summary.pop("compute.backend", backend) == backend  # a setting the summary records where it differs
    serial_summary.pop("compute.backend", None)
    assert summary == serial_summary and summary["n_feasible"] == serial["feasible"].sum() > 0


def test_one_decision_gives_a_job_its_kernel_chunks_and_workers(make_cfg, catalogue):
    """``dispatch.decide`` on its own: the main job's 216 poses stay on numpy in one process;
    60^3 CPR-WWA poses take the compiled kernel (0.4 s of start against 1.4 s of numpy) in
    20 000-pose chunks, and workers only once the fused kernel outlasts 1.5 s (10^6 poses/s);
    the feasible model takes 4 096-pose chunks and workers from 16 000 poses; a sweep that pays
    gives even a small job the compiled kernel."""
    from pipeline.workspace.dispatch import decide

    cfg = make_cfg("compute.n_jobs=2", "compute.backend=loky")
    problem = build_problem(cfg, catalogue)[0]
    small = decide(cfg, problem, 216)
    assert (small.problem.fused, small.chunk_size, small.workers) == (False, 500_000 // (8 * 12), 1)
    large = decide(cfg, problem, 60 ** 3)
    assert (large.problem.fused, large.chunk_size, large.workers) == (True, 20_000, 1)
    assert decide(cfg, problem, 2_000_000).workers == 2
    feasible_cfg = make_cfg("compute.n_jobs=2", "tension=feasible", "compute.backend=loky")
    feasible = decide(feasible_cfg, build_problem(feasible_cfg, catalogue)[0], 17_000)
    assert (feasible.problem.fused, feasible.chunk_size, feasible.workers) == (False, 4096, 2)
    assert decide(cfg, problem, 216, sweep_pays=True).problem.fused
    threads = make_cfg("compute.n_jobs=2")  # the default: threads, which start for 0.1 s
    assert threads.compute.backend == "threading"
    assert decide(threads, problem, 60 ** 3).workers == 2 and decide(threads, problem, 216).workers == 1

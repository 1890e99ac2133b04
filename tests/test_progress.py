"""Progress lines (pipeline.workspace.progress) and the warning before a long job (the cost model)."""

import functools
from pathlib import Path
from dataclasses import replace
import logging
import tracemalloc

import pytest

from pipeline.app.plan import plan
from pipeline.workspace import fused, parallel
from pipeline.workspace.progress import Progress, clock_text
from pipeline.workspace.dispatch import announce_cost, estimated_seconds
from pipeline.app.problem import build_problem
from conftest import compute_workspace

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_robot"


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_chunks_are_reported_at_most_every_interval_and_at_the_end(caplog):
    clock = Clock()
    progress = Progress("chunks", 100, logging.getLogger("t"), every=10.0, clock=clock)
    with caplog.at_level(logging.INFO, logger="t"):
        for _ in range(100):
            clock.now += 1.0  # 1 s per chunk: a line every 10 chunks
            progress.step()
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 10
    assert lines[0] == "chunks 10/100 (10%), 0:10 elapsed, about 1:30 left"
    assert lines[-1] == "chunks 100/100 (100%), 1:40 elapsed"


def test_jobs_are_reported_one_line_each_with_their_result(caplog):
    clock = Clock()
    progress = Progress("jobs", 3, logging.getLogger("t"), clock=clock)
    with caplog.at_level(logging.INFO, logger="t"):
        for result in ("a", "b", "c"):
            clock.now += 20.0
            progress.step(result)
    assert [r.getMessage() for r in caplog.records] == [
        "jobs 1/3 (33%), 0:20 elapsed, about 0:40 left: a",
        "jobs 2/3 (67%), 0:40 elapsed, about 0:20 left: b",
        "jobs 3/3 (100%), 1:00 elapsed: c"]


def test_a_single_step_is_not_reported(caplog):
    with caplog.at_level(logging.INFO, logger="t"):
        Progress("chunks", 1, logging.getLogger("t")).step()
    assert not caplog.records


@pytest.mark.parametrize("seconds, text", [(0, "0:00"), (59.6, "1:00"), (3599, "59:59"), (3723, "1:02:03")])
def test_clock_text(seconds, text):
    assert clock_text(seconds) == text


def test_a_dense_grid_without_n_vel_is_announced_with_the_key_to_change(caplog):
    """100^3 poses with grid.n_vel null, under the feasible model, test the 2 376 extremes of the
    velocity set each: about a minute on 2 cores by the cost model (measured: 10^6 poses in
    0:53 with the minimum-norm model, numpy), so a warning names grid.n_vel; with grid.n_vel=6
    the job is quiet."""
    (job,) = plan(["grid.n=100", "tension=feasible"]).jobs
    cfg, catalogue = job.cfg, job.catalogue
    problem, grid = build_problem(cfg, catalogue)
    assert problem.spec.set_size() == 2376 and len(problem.spec.velocities) > 500_000
    assert estimated_seconds(problem, grid.n_points) == pytest.approx(10**6 * (1 + 0.0007 * (2376 - 12)) / 20_000)
    with caplog.at_level(logging.WARNING, logger="pipeline"):
        announce_cost(cfg, problem, grid.n_points, 2)
    (record,) = caplog.records
    assert record.getMessage().startswith("this job evaluates 1000000 poses x 1 orientations: about 1:06 on 2 cores")
    assert "grid.n_vel is null (grid.n's), so each pose tests 2376 velocities" in record.getMessage()
    caplog.clear()
    quick = plan(["grid.n=100", "grid.n_vel=6", "tension=feasible", "grid.n=40"]).jobs[0].cfg
    problem, grid = build_problem(quick, catalogue)
    with caplog.at_level(logging.WARNING, logger="pipeline"):
        announce_cost(quick, problem, grid.n_points, 2)
    assert not caplog.records


def test_the_build_of_the_compiled_loops_is_not_counted_in_the_first_chunk(make_cfg, catalogue, monkeypatch,
                                                                            caplog):
    """The first fused job on a machine builds the loops (about 45 s): a job loads them before
    its progress clock starts, so no line promises minutes for a job about to end."""
    clock = Clock()
    loaded = fused.compiled_loops

    def building(name):  # the first call takes 15 s (on the progress clock)
        clock.now += 15.0 if not built else 0.0
        built.append(name)
        return loaded(name)

    built = []
    monkeypatch.setattr(fused, "compiled_loops", building)
    monkeypatch.setattr(parallel, "Progress", functools.partial(Progress, clock=clock))
    cfg = make_cfg("compute.kernel=fused", "grid.n=10", "compute.chunk_size=100")
    with caplog.at_level(logging.INFO, logger="pipeline.workspace.parallel"):
        compute_workspace(cfg, catalogue)
    lines = [r.getMessage() for r in caplog.records if r.name == "pipeline.workspace.parallel"]
    assert lines == ["chunks 10/10 (100%), 0:00 elapsed"]
    assert len(built) == 11  # one pose first, then each of the 10 chunks


def test_a_job_holds_its_chunks_not_its_grid(make_cfg, catalogue):
    """2 x 10^6 poses: their positions alone are 48 MB, and were held (and built through as much
    again) for the whole job. The grid is its axes now, each chunk's positions made when it is
    evaluated: what the job allocates at its peak stays far below one copy of the positions."""
    cfg = make_cfg("grid.n=126", "grid.n_vel=6", "compute.kernel=fused")
    compute_workspace(make_cfg("grid.n=2", "compute.kernel=fused"), catalogue)  # the compiled loops, loaded
    tracemalloc.start()
    try:
        _, summary = compute_workspace(cfg, catalogue, sink=lambda chunk: None)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert summary["n_points"] == 126**3 == 2_000_376
    assert peak < 16 * 2**20, peak  # 6 MiB here; the positions: 48 MB


def test_a_large_table_kept_whole_is_announced_with_its_memory(make_cfg, catalogue, caplog, monkeypatch):
    """Whatever this machine's numba cache holds: without it the estimate would add the first
    compile (45 s) and announce the job for its time (the order of the tests decided it)."""
    from pipeline.model import jit

    monkeypatch.setattr(jit, "compile_seconds", lambda name: 0.0)
    (job,) = plan(["grid.n=300", "grid.n_vel=6"]).jobs
    problem, grid = build_problem(job.cfg, job.catalogue)
    problem = replace(problem, fused=True)  # about 14 s on 2 cores: only its memory is large
    with caplog.at_level(logging.WARNING, logger="pipeline"):
        announce_cost(job.cfg, problem, grid.n_points, 2)  # streamed to points.parquet: quiet
        assert not caplog.records
        announce_cost(job.cfg, problem, grid.n_points, 2, keeps_points=True)  # the API's one table
    (record,) = caplog.records
    assert record.getMessage().startswith("this job evaluates 27000000 poses x 1 orientations: about ")
    assert "cores and 3.1 GiB of memory by the cost model" in record.getMessage()  # 14 columns a point


def test_the_cost_model_counts_a_wrench_sets_vertices_and_the_payloads_lp():
    """A 64-vertex wrench set took 10.0 s where the model said 0.75 s (it counted one wrench),
    and the payload map 2.1 s for 0.75 s: each spec's work() now counts them (measured in
    benchmarks/LOG.md, 2026-11-26: estimates 8.7 s and 2.0 s)."""
    robot = ["--config-dir", str(EXAMPLE), "robot=myrobot", "tension.t_min=1", "tension.t_max=100"]
    box = "wrench.set={min:[-10,-10,-10,-1,-1,-1],max:[10,10,10,1,1,1]}"
    plain, with_set, payload = ([*robot, *extra] for extra in ([], [box], ["analysis=payload"]))
    seconds = {}
    for name, args in (("plain", plain), ("set", with_set), ("payload", payload)):
        (job,) = plan(args).jobs
        problem, grid = build_problem(job.cfg, job.catalogue)
        seconds[name] = estimated_seconds(problem, grid.n_points)
        assert problem.spec.set_size() == (64 if name == "set" else 1)
    assert seconds["plain"] == pytest.approx(1155 / 20_000)
    assert seconds["set"] == pytest.approx(seconds["plain"] * (1 + 64 / 6))
    assert seconds["payload"] == pytest.approx(seconds["plain"] * 2.7)


def test_a_job_that_will_compile_numbas_loops_says_so_in_its_estimate(caplog, monkeypatch):
    """On a machine without numba's cache, a long fused job's estimate adds the first compile,
    once, and says so; the feasible model adds its own search's."""
    from pipeline.model import jit

    monkeypatch.setattr(jit, "compile_seconds", lambda name: jit.COMPILE_S[name])
    (job,) = plan(["grid.n=100", "tension=feasible"]).jobs
    problem, grid = build_problem(job.cfg, job.catalogue)
    with caplog.at_level(logging.WARNING, logger="pipeline"):
        announce_cost(job.cfg, problem, grid.n_points, 2)
    (record,) = caplog.records
    assert record.getMessage().startswith("this job evaluates 1000000 poses x 1 orientations: about 1:15 on 2 cores")
    assert record.getMessage().endswith("this includes numba's first compile of the loops it needs, about 9 s, "
                                        "once per machine")
    caplog.clear()
    dense = plan(["grid.n=350", "grid.n_vel=6"]).jobs[0].cfg  # 4.3 x 10^7 poses: about 21 s fused on 2 cores
    fused_job = replace(build_problem(dense, job.catalogue)[0], fused=True)
    with caplog.at_level(logging.WARNING, logger="pipeline"):
        announce_cost(dense, fused_job, 350 ** 3, 2)
    assert "about 45 s, once per machine" in caplog.records[0].getMessage()


def test_the_cost_models_estimate_stands_until_the_rate_is_measured_without_the_first_step(caplog):
    """A 12-minute job's first chunks (a worker's start, a first compile) said 7 h: the time left
    is the cost model's until three chunks are done, then the rate since the first chunk."""
    clock = Clock()
    progress = Progress("chunks", 100, logging.getLogger("t"), clock=clock, estimate=200.0)
    with caplog.at_level(logging.INFO, logger="t"):
        for seconds in [300.0] + [2.0] * 4:  # a slow first chunk, then 2 s each
            clock.now += seconds
            progress.step()
    lines = [r.getMessage() for r in caplog.records]
    assert lines[0] == "chunks 1/100 (1%), 5:00 elapsed, about 3:18 left by the cost model"
    assert lines[1] == "chunks 2/100 (2%), 5:02 elapsed, about 3:16 left by the cost model"
    assert lines[2] == "chunks 3/100 (3%), 5:04 elapsed, about 3:14 left"  # 2 s x 97, not 101 s x 97
    assert lines[4] == "chunks 5/100 (5%), 5:08 elapsed, about 3:10 left"


def test_the_cost_model_counts_the_metrics_and_the_cable_quantities(caplog):
    """output.metrics=true took 33 s unannounced on 112 000 poses of the example robot (the model
    said 6 s), and output.cables=true was not counted at all: their work per pose is measured
    (2026-11-27: 264 us and 126 us against the feasible model's 50 us), and the 33-second job is
    announced, the 3-second one without them is not."""
    robot = ["--config-dir", str(EXAMPLE), "robot=myrobot", "tension.t_min=1", "tension.t_max=400",
             "robot.search.step=0.05", "compute.n_jobs=1"]
    seconds, lines = {}, {}
    for name, extra in (("plain", []), ("metrics", ["output.metrics=true"]), ("cables", ["output.cables=true"])):
        (job,) = plan([*robot, *extra]).jobs
        problem, grid = build_problem(job.cfg, job.catalogue)
        seconds[name] = estimated_seconds(problem, grid.n_points)
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="pipeline"):
            announce_cost(job.cfg, problem, grid.n_points, 1)
        lines[name] = [r.getMessage() for r in caplog.records]
    assert grid.n_points == 112_251 and seconds["plain"] == pytest.approx(112_251 / 20_000)
    assert seconds["metrics"] == pytest.approx(6 * seconds["plain"])
    assert seconds["cables"] == pytest.approx(3.5 * seconds["plain"])
    assert lines["plain"] == [] and lines["cables"] == []  # 2.9 s and 30 s measured
    assert len(lines["metrics"]) == 1 and "this job evaluates 112251 poses x 1 orientations: about 0:34" in lines["metrics"][0]

"""The compiled kernels (pipeline.workspace.fused) against the numpy criteria they replace on large
grids: the same margins, the same Jacobian ranks and the same verdicts, on the paper's robot at
every actuator, both readings of eq. (20), zero and non-zero orientations, on random robots
whose poses include rank-deficient ones that the compiled kernel must leave to numpy, and on
the IRPM's statics (both moment arms and cable directions) and a redundant points robot.

Tolerance: both kernels solve the normal equations (J^T J) x = F (a Cholesky factor here, numpy's
LU there), whose rounding grows with cond(J)^2: margins agree within 1e-13 on well conditioned
poses and within about 1e-8 relative close to the CPR-8's singular zero orientation (0.2 rad
away). Margins are compared within MARGIN_RTOL relative plus MARGIN_ATOL, verdicts outside
that band around zero."""

import dataclasses

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from conftest import command, job_imports, compute_workspace
from pipeline.workspace import fused
from pipeline.workspace.dispatch import fused_pays, fused_unfit, use_fused
from pipeline.app.problem import build_problem, grid_size
from pipeline.workspace.kernel import evaluate_chunk
from pipeline.workspace.verdict import classify

MARGIN_ATOL, MARGIN_RTOL = 1e-9, 1e-6


def both_kernels(problem, positions):
    numpy_result = evaluate_chunk(problem, positions)
    fused_result = evaluate_chunk(dataclasses.replace(problem, fused=True), positions)
    return numpy_result, fused_result


def assert_same(problem, numpy_result, fused_result):
    assert numpy_result.keys() == fused_result.keys()
    # a pose's margins come from one set of torques: their round-off scales with the largest
    # of them (a rank-5 pose that misses its wrench has torques 50 times the rating)
    scale = np.max([np.abs(v) for k, v in numpy_result.items() if k.startswith("margin_")], axis=0, initial=1.0)
    for key in numpy_result:
        atol = MARGIN_ATOL * (scale if key.startswith("margin_") else 1.0)
        gap = np.abs(np.asarray(fused_result[key], dtype=float) - numpy_result[key])
        over = ~(gap <= atol + MARGIN_RTOL * np.abs(numpy_result[key]))
        assert not over.any(), (key, np.flatnonzero(over)[:5], gap[over][:5])
    if "jacobian_rank" in numpy_result:
        np.testing.assert_array_equal(fused_result["jacobian_rank"], numpy_result["jacobian_rank"])
    margins = {n: numpy_result[f"margin_{n}"] for n in problem.criteria}
    clear = np.all([np.abs(v) > MARGIN_ATOL + MARGIN_RTOL * np.abs(v) for v in margins.values()], axis=0)
    verdicts = [classify({n: r[f"margin_{n}"] for n in problem.criteria}, problem.margin_atol)
                for r in (numpy_result, fused_result)]
    np.testing.assert_array_equal(verdicts[0][1][clear], verdicts[1][1][clear])
    np.testing.assert_array_equal(verdicts[0][2][clear], verdicts[1][2][clear])
    assert clear.mean() > 0.9


@pytest.mark.parametrize("columns", ["full", "translational"])
@pytest.mark.parametrize("angle", [0.0, 0.3])
def test_paper_grid_every_actuator_gives_the_numpy_margins(columns, angle, make_cfg, catalogue):
    """Section 3.1's robot on a 12^3 grid, Table 1's five actuators; at the zero orientation
    with all six columns every J^T is one rank short (the compiled kernel's deflated route)."""
    verdicts = []
    for actuator in range(1, 6):
        cfg = make_cfg(f"actuator={actuator}", f"model.pinv_columns={columns}", "grid.n=12",
                       *(f"orientation.{a}={angle}" for a in ("psi", "theta", "phi")))
        problem, grid = build_problem(cfg, catalogue)
        numpy_result, fused_result = both_kernels(problem, grid[:])
        assert_same(problem, numpy_result, fused_result)
        verdicts.append(classify({n: numpy_result[f"margin_{n}"] for n in problem.criteria}, 1e-9)[1])
        if columns == "full" and angle == 0.0:
            assert (numpy_result["jacobian_rank"] == 5).all()
    assert np.concatenate(verdicts).any() and not np.concatenate(verdicts).all()  # both verdicts compared


def test_loads_ratings_lengths_and_total_orientation_give_the_numpy_margins(make_cfg, catalogue):
    """Every term of F in eq. (31) (centre of mass, external wrench, Newton's sign), a rating per
    cable, a cable length limit and a total-orientation set (the worst over 27 orientations)."""
    cfg = make_cfg("actuator=4", "grid.n=10", "robot.platform.com=[0.01,-0.02,0.03]",
                   "load.external=[3,-2,5,0.2,-0.1,0.3]",
                   "tension.t_max=[3000,2500,3000,2800,3000,3000,2600,3000]", "orientation.total.n=3",
                   "orientation.total.bound=0.2")
    problem, grid = build_problem(cfg, catalogue)
    assert {"tension_max", "speed", "torque", "acceleration", "voltage"} <= set(problem.criteria)
    problem = dataclasses.replace(problem, robot=dataclasses.replace(problem.robot, l_max=2.3),
                                  criteria=(*problem.criteria, "length"))
    numpy_result, fused_result = both_kernels(problem, grid[:])
    assert_same(problem, numpy_result, fused_result)
    for name in ("tension_max", "length"):  # both limits bind somewhere, so both are compared
        assert (numpy_result[f"margin_{name}"] < 0).any() and (numpy_result[f"margin_{name}"] > 0).any()


def test_random_robots_with_singular_poses_are_left_to_numpy(make_cfg, catalogue):
    """Random 8-cable robots, a third of them with cables doubled so that only 5 distinct
    cables remain (J^T one rank short everywhere: the deflated route on a geometry unlike the
    CPR-8's), a third with 4 (two short: left to numpy), and zero-length cables; every pose
    equals the numpy kernel."""
    rng = np.random.default_rng(7)
    cfg = make_cfg("actuator=3", "grid.n=4")
    problem, _ = build_problem(cfg, catalogue)
    unsettled_total = short_total = 0
    for number in range(42):
        anchors = rng.uniform(-1.5, 1.5, (8, 3))
        attachments = rng.uniform(-0.1, 0.1, (8, 3))
        distinct = (8, 5, 4)[number % 3]
        anchors[distinct:], attachments[distinct:] = anchors[: 8 - distinct], attachments[: 8 - distinct]
        robot = dataclasses.replace(problem.robot, anchors=anchors, attachments=attachments)
        positions = rng.uniform(-0.5, 0.5, (200, 3))
        positions[:5] = anchors[2] - attachments[2]  # a zero-length cable: no direction
        orientation = rng.uniform(-0.5, 0.5, 3) * (rng.random() < 0.5)
        candidate = dataclasses.replace(problem, robot=robot, orientations=orientation[None, :])
        numpy_result, fused_result = both_kernels(candidate, positions)
        assert_same(candidate, numpy_result, fused_result)
        direct, unsettled = fused.margins(candidate, positions, 0)
        unsettled_total += unsettled.sum()
        short_total += ((direct["jacobian_rank"] == 5) & ~unsettled).sum()
    assert unsettled_total > 1000 and short_total > 1000  # both the fallback and the deflation ran


def _stacked(result: dict) -> np.ndarray:
    """A pose's margins and Jacobian rank as one row."""
    return np.column_stack([result[key] for key in sorted(result)])


def _same_in_any_block(problem, positions: np.ndarray) -> tuple[dict, np.ndarray]:
    """The compiled kernel's margins and unsettled flags of ``positions``, having asserted the
    block law: every pose's are the same doubles with the poses reversed, turned by 37, and cut
    short at sizes around a block's."""
    from pipeline.workspace.fused_loops import BLOCK

    n = len(positions)
    found, unsettled = fused.margins(problem, positions, 0)
    rows = _stacked(found)
    for order in (np.arange(n)[::-1], np.roll(np.arange(n), 37)):
        again, left = fused.margins(problem, positions[order], 0)
        np.testing.assert_array_equal(_stacked(again)[np.argsort(order)], rows)
        np.testing.assert_array_equal(left[np.argsort(order)], unsettled)
    for size in (1, BLOCK - 1, BLOCK, BLOCK + 1, 2 * BLOCK + 5):
        part, left = fused.margins(problem, positions[:size], 0)
        np.testing.assert_array_equal(_stacked(part), rows[:size])
        np.testing.assert_array_equal(left, unsettled[:size])
    return found, unsettled


def test_a_pose_s_margins_do_not_depend_on_the_block_it_is_computed_in(make_cfg, catalogue):
    """The compiled CPR-WWA loop computes ``BLOCK`` poses at a time (each a vector lane) on
    either route, the deflated route's inverse iteration from the same start in every lane.
    Random 8-cable robots, cables 7 and 8 doubling 1 and 2 (J^T of full rank in general), their
    coordinates multiples of 1/64 (so that at a pose where cable 4 has zero length J^T is one
    rank short: the deflated route). Law: a pose's margins, rank and route are the same doubles
    in any block and at any place in it, whatever its neighbours (the poses reversed, turned by
    37, alone, in a short last block, with full-rank poses inserted between them); and all are
    numpy's."""
    from pipeline.workspace.fused_loops import BLOCK

    rng = np.random.default_rng(11)
    problem, _ = build_problem(make_cfg("actuator=3", "grid.n=4"), catalogue)
    on_grid = lambda values: np.round(values * 64) / 64  # noqa: E731
    for _ in range(4):
        anchors, attachments = on_grid(rng.uniform(-1.5, 1.5, (8, 3))), on_grid(rng.uniform(-0.1, 0.1, (8, 3)))
        anchors[6:], attachments[6:] = anchors[:2], attachments[:2]
        candidate = dataclasses.replace(problem, robot=dataclasses.replace(problem.robot, anchors=anchors,
                                                                           attachments=attachments),
                                        orientations=np.zeros((1, 3)))
        n = 3 * BLOCK + 17
        positions = on_grid(rng.uniform(-0.5, 0.5, (n, 3)))
        positions[rng.choice(n, n // 8, replace=False)] = anchors[3] - attachments[3]
        found, unsettled = _same_in_any_block(candidate, positions)
        rows = _stacked(found)
        assert ((found["jacobian_rank"] == 6) & ~unsettled).sum() > n // 2
        assert ((found["jacobian_rank"] == 5) & ~unsettled).sum() >= n // 10
        extra = on_grid(rng.uniform(-0.5, 0.5, (2 * BLOCK, 3)))
        where = np.sort(rng.choice(n + 1, len(extra)))
        widened = np.insert(positions, where, extra, axis=0)
        kept = np.ones(len(widened), dtype=bool)
        kept[where + np.arange(len(extra))] = False
        more, left = fused.margins(candidate, widened, 0)
        assert (more["jacobian_rank"][~kept] == 6).all() and not left[~kept].any()
        np.testing.assert_array_equal(_stacked(more)[kept], rows)
        np.testing.assert_array_equal(left[kept], unsettled)
        assert_same(candidate, *both_kernels(candidate, positions))


def test_a_whole_job_writes_the_same_points_with_either_kernel(make_cfg, catalogue):
    """compute.kernel=numpy and =fused: the same verdicts, limiting criteria and counts."""
    tables = {}
    for kernel in ("numpy", "fused"):
        cfg = make_cfg(f"compute.kernel={kernel}", "grid.n=20", "actuator=3")
        tables[kernel] = compute_workspace(cfg, catalogue)
    (points_numpy, summary_numpy), (points_fused, summary_fused) = tables["numpy"], tables["fused"]
    assert (points_numpy["feasible"] == points_fused["feasible"]).all()
    assert (points_numpy["limiting"] == points_fused["limiting"]).all()
    for key in ("n_feasible", "feasible_pct", *(k for k in summary_numpy if k.startswith("lost_"))):
        assert summary_numpy[key] == summary_fused[key], key
    assert 0 < summary_numpy["n_feasible"] < summary_numpy["n_points"]


def test_auto_uses_the_compiled_kernel_only_where_it_applies_and_pays(make_cfg, catalogue):
    small = make_cfg()
    assert not use_fused(small, build_problem(small, catalogue)[0], 216)  # the main job's grid
    # a sweep that pays as a whole (the plan's decision, pipeline.app.plan)
    assert use_fused(small, build_problem(small, catalogue)[0], 216, sweep_pays=True)
    assert not use_fused(make_cfg("compute.kernel=numpy"), build_problem(small, catalogue)[0], 216, sweep_pays=True)
    feasible = make_cfg("tension=feasible")
    assert not use_fused(feasible, build_problem(feasible, catalogue)[0], 216, sweep_pays=True)
    large = make_cfg("grid.n=60")
    assert use_fused(large, build_problem(large, catalogue)[0], 60 ** 3)
    jdot = make_cfg("grid.n=60", "model.jdot=true")
    jdot_problem = build_problem(jdot, catalogue)[0]
    assert fused_unfit(jdot_problem) and not use_fused(jdot, jdot_problem, 60 ** 3)
    for overrides in (["tension=feasible"], ["robot=irpm6", "tension=feasible"], ["output.cables=true"]):
        assert fused_unfit(build_problem(make_cfg(*overrides), catalogue)[0]), overrides
    for overrides in (["analysis=lines"], ["robot=irpm6"]):
        assert fused_unfit(build_problem(make_cfg(*overrides), catalogue)[0]) is None, overrides


def test_a_sweep_of_many_small_jobs_pays_for_the_compiled_kernel_together(make_cfg, catalogue):
    """An IRPM job (24 986 poses) alone does not pay for numba's start (about 0.17 s of numpy
    kernel by the cost model against 0.4 s); three of them together do, as the main job's five
    216-pose jobs do not, nor jobs the compiled kernels cannot evaluate."""
    def jobs(*overrides):
        cfg = make_cfg(*overrides)
        return cfg, build_problem(cfg, catalogue)[0], grid_size(cfg)

    irpm = jobs("robot=irpm6")
    assert not fused_pays([irpm] * 2) and fused_pays([irpm] * 3)
    assert not fused_pays([jobs(f"actuator={a}") for a in range(1, 6)])
    assert not fused_pays([jobs("robot=irpm6", "tension=feasible")] * 10)
    assert not fused_pays([jobs("robot=irpm6", "compute.kernel=numpy")] * 10)


@pytest.mark.parametrize("overrides", [
    ["robot.gamma_deg=0"], ["robot.gamma_deg=30", "tension.t_min=100", "tension.t_max=60000"],
    ["model.moment_arm=base", "load.mass=0", "wrench.mx=20000"],
    ["model.cable_direction=centre", "orientation.psi=0.2", "wrench.fx=50000"],
])
def test_irpm_statics_give_the_numpy_margins(overrides, make_cfg, catalogue):
    """The IRPM paper's box at each moment arm and cable direction, ratings and floors, an
    orientation: the same singular, slack, rating and length margins; singular poses (about 4 %
    of the box) are left to numpy."""
    problem, grid = build_problem(make_cfg("robot=irpm6", *overrides), catalogue)
    numpy_result, fused_result = both_kernels(problem, grid[:])
    assert_same(problem, numpy_result, fused_result)
    assert (numpy_result["margin_singular"] < 0).any() and (numpy_result["margin_slack"] > 0).any()
    assert fused.margins(problem, grid[:], 0)[1].any()


@pytest.mark.parametrize("overrides", [[], ["model.moment_arm=base", "model.cable_direction=centre", "orientation.psi=0.2"]])
def test_a_pose_s_statics_margins_do_not_depend_on_the_block_it_is_computed_in(overrides, make_cfg, catalogue):
    """The compiled statics loop computes ``BLOCK`` poses at a time (each a vector lane), with
    no memory from pose to pose. Law: every pose's margins and its unsettled flag (a singular
    or doubtful pose, left to numpy) are the same doubles in any block and at any place in it
    (the IRPM paper's box reversed, turned by 37, cut short at sizes around a block's)."""
    problem, grid = build_problem(make_cfg("robot=irpm6", "robot.gamma_deg=15", *overrides), catalogue)
    positions = grid[:]
    n = len(positions)
    unsettled = _same_in_any_block(problem, positions)[1]
    assert 0 < unsettled.sum() < n // 10


def test_a_points_robot_with_eight_cables_gives_the_numpy_statics_margins(make_cfg, catalogue):
    """Minimum-norm tensions of a redundant robot (8 cables: A A^T is 6 x 6, A^T y has 8 rows)."""
    anchors = [[0, 0, 3], [4, 0, 3], [4, 4, 3], [0, 4, 3], [0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]]
    attachments = [[-0.1, -0.1, 0.05], [0.1, -0.1, 0.05], [0.1, 0.1, 0.05], [-0.1, 0.1, 0.05],
                   [-0.1, -0.1, -0.05], [0.1, -0.1, -0.05], [0.1, 0.1, -0.05], [-0.1, 0.1, -0.05]]
    cfg = make_cfg("robot=points", "tension=pinv", f"robot.anchors={anchors}", f"robot.attachments={attachments}",
                   "robot.search.lo=[0.3,0.3,0.3]", "robot.search.hi=[3.7,3.7,2.7]", "robot.search.step=0.2",
                   "robot.l_max=4.5", "tension.t_min=1", "load.mass=30")
    problem, grid = build_problem(cfg, catalogue)
    numpy_result, fused_result = both_kernels(problem, grid[:])
    assert_same(problem, numpy_result, fused_result)
    assert (numpy_result["margin_length"] < 0).any() and (numpy_result["margin_length"] > 0).any()
    assert np.ptp(numpy_result["margin_slack"]) > 0.1  # tensions vary over the box


@pytest.mark.slow
def test_a_sweep_loads_the_compiled_kernel_that_one_small_job_does_not(tmp_path):
    """End to end: one IRPM job runs the numpy kernel, a sweep of four the compiled one (the
    summary's ``kernel`` says which), with the same counts."""
    def summaries(folder, *args):
        done = command(tmp_path, "pipeline", *args, f"hydra.sweep.dir={tmp_path}/sweep", f"hydra.run.dir={tmp_path}/run")
        assert done.returncode == 0, done.stderr
        return [pd.read_parquet(path).iloc[0] for path in sorted((tmp_path / folder).glob("*/summary.parquet"))]

    (one,) = summaries(".", "robot=irpm6", "output.points=false")
    sweep = summaries("sweep", "-m", "robot=irpm6", "output.points=false", "robot.gamma_deg=0,15,30,45")
    assert one["kernel"] == "numpy" and [row["kernel"] for row in sweep] == ["fused"] * 4
    assert int(next(r for r in sweep if r["robot.gamma_deg"] == one["robot.gamma_deg"])["n_feasible"]) == one["n_feasible"]


def test_numba_is_loaded_only_by_the_jobs_that_use_the_compiled_loops(tmp_path):
    """Loading numba and its cache costs a process 0.35-0.4 s (FUSED_START_S): the main job's
    small grids keep the numpy kernel and never import it; a job on the compiled loops does."""
    assert "numba imported: False" in job_imports(tmp_path, "actuator=3", "hydra.run.dir=main")
    assert "numba imported: True" in job_imports(tmp_path, "compute.kernel=fused", "grid.n=10",
                                                 "hydra.run.dir=cpr8")
    assert pq.read_table(tmp_path / "cpr8" / "summary.parquet")["kernel"].to_pylist() == ["fused"]


@pytest.mark.parametrize("robot", [[], ["robot=irpm6", "robot.search.step=2"]])
def test_chunks_joblib_hands_workers_as_read_only_maps_give_the_in_process_margins(robot, make_cfg, catalogue):
    """joblib passes a worker any argument above 1 MB as a read-only memory map: a chunk of
    70 000 poses (1.7 MB) once reached the compiled loops as a type their signature refuses
    (a TypeError that stopped every fused job on workers with compute.chunk_size of 50 000 or
    more). The same margins as each chunk in this process, bit for bit."""
    from pipeline.workspace.parallel import iter_chunks

    problem, _ = build_problem(make_cfg(*robot, "compute.kernel=fused"), catalogue)
    problem = dataclasses.replace(problem, fused=True)
    positions = np.random.default_rng(3).uniform(-1.5, 1.5, size=(140_000, 3)) + [1.6, 1.1, -1.1]
    if robot:
        positions = positions + [-1.6, -1.1, 3.1]
    parts = list(iter_chunks(evaluate_chunk, problem, positions, n_jobs=2, backend="loky", chunk_size=70_000))
    assert [s for s, _ in parts] == [slice(0, 70_000), slice(70_000, 140_000)]
    here = [evaluate_chunk(problem, positions[s]) for s, _ in parts]  # a chunk's first pose starts cold
    for key in here[0]:
        np.testing.assert_array_equal(np.concatenate([part[key] for _, part in parts]),
                                      np.concatenate([part[key] for part in here]), err_msg=key)

"""Degenerate robots and poses (issue 38, item 2): a Jacobian that lacks directions, cables of zero
length. Every verdict is checked against an independent reference: finite differences of the
cable lengths for J, least squares for what the minimum-norm forces miss, and the grid poses that
put an attachment on its anchor."""

from __future__ import annotations

import itertools
import logging

import numpy as np
import pytest

from pipeline.app.problem import build_problem
from conftest import compute_workspace, SPREAD_ANCHORS, command, eq9_rotation
from pipeline.workspace.degeneracy import Degeneracy


# Six anchors on one horizontal line, every cable on one platform point: the cables span the
# plane through that line and the point, so no tension distribution holds the platform off it.
LINE = ["robot=points", "robot.anchors=[[0,0,3],[1,0,3],[2,0,3],[3,0,3],[4,0,3],[5,0,3]]",
        "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
        "robot.platform.mass=2", "robot.search.lo=[0,-1,0]", "robot.search.hi=[5,1,2.5]", "robot.search.step=0.5",
        "analysis=cpr_wwa", "tension=pinv"]


def box_vertices(spec) -> np.ndarray:
    """(8, 3) the corners of the acceleration set (eqs. 27-29 give a box)."""
    lo, hi = spec.accelerations.min(axis=0), spec.accelerations.max(axis=0)
    return np.array([[(lo, hi)[b][k] for k, b in enumerate(bits)] for bits in itertools.product((0, 1), repeat=3)])


def lengths_of(robot, position, angles) -> np.ndarray:
    """Cable lengths |p + R b_i - a_i| written out (eqs. 1-17), R of eq. (9)."""
    arms = robot.attachments @ eq9_rotation(*angles).T
    return np.linalg.norm(position + arms - robot.anchors, axis=1)


def missed_share(problem, position, angles, rows: int, step: float = 1e-6) -> float:
    """The largest share of a required wrench F = m (a - g up) (+ its moment at the centre of
    mass) that J^T cannot reach: J by central differences of the lengths in (x, y, z, psi,
    theta, phi), divided by the winch radius; F's part outside the range of J^T by least squares
    (singular values below 1e-9 of the largest dropped, as eq. 20's pseudo-inverse)."""
    spec, robot = problem.spec, problem.robot
    q = np.concatenate([position, angles])
    jac = np.empty((robot.n_cables, 6))
    for k in range(6):
        dq = np.zeros(6)
        dq[k] = step
        jac[:, k] = (lengths_of(robot, *np.split(q + dq, [3])) - lengths_of(robot, *np.split(q - dq, [3]))) / (2 * step)
    structure = (jac / spec.winch_radius[:, None]).T[:rows]
    load = spec.load
    arm = eq9_rotation(*angles) @ load.com
    worst = 0.0
    for a in box_vertices(spec):
        force = load.mass * (a - load.gravity * robot.up)  # the paper's reading of eq. (31): m (a - g e_z)
        wrench = np.concatenate([force, np.cross(arm, force)])[:rows] + load.external[:rows]
        x, *_ = np.linalg.lstsq(structure, wrench, rcond=1e-9)
        worst = max(worst, np.linalg.norm(structure @ x - wrench) / np.linalg.norm(wrench))
    return worst


def test_a_robot_with_its_anchors_on_one_line_holds_no_pose_under_the_minimum_norm_model(make_cfg, catalogue,
                                                                                         caplog):
    """It was 100 % feasible: M = (J^T)^+ F ignored the wrench it could not balance."""
    cfg = make_cfg(*LINE)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        points, summary = compute_workspace(cfg, catalogue)
    assert "J^T is short of rank 3 at 330 of 330 poses (rank 2 at 330" in caplog.text  # a point: forces only
    assert 0.078 < points["wrench_residual"].min() and points["wrench_residual"].max() == pytest.approx(0.9239, abs=1e-4)
    problem, _ = build_problem(cfg, catalogue)
    assert summary["n_feasible"] == 0 and summary["lost_unreachable"] == summary["n_points"] == 330
    assert (points["jacobian_rank"] == 2).all()  # forces only (a point platform): 3 rows, one plane
    for row in points.sample(12, random_state=3).itertuples():
        share = missed_share(problem, np.array([row.x, row.y, row.z]), np.zeros(3), rows=3)
        assert row.wrench_residual == pytest.approx(share, rel=1e-6)
        assert row.margin_unreachable == pytest.approx(1.0 - share / 0.05, rel=1e-6)


def test_the_tolerance_of_the_minimum_norm_model_is_its_own_key(make_cfg, catalogue):
    """tension.pinv_residual decides, pose by pose, as the independent residual says; the
    feasible model's residual_rtol is not read by it."""
    loose = make_cfg(*LINE, "tension.pinv_residual=0.3", "tension.residual_rtol=1e-12")
    points, _ = compute_workspace(loose, catalogue)
    problem, _ = build_problem(loose, catalogue)
    shares = np.array([missed_share(problem, np.array(p), np.zeros(3), rows=3)
                       for p in points[["x", "y", "z"]].to_numpy()])
    assert ((points["margin_unreachable"] >= 0) == (shares <= 0.3)).all()
    assert 0 < (shares <= 0.3).sum() < len(shares)  # the threshold cuts through this grid


@pytest.mark.parametrize("case", [
    ("zero orientation, the paper's load", [], 5),
    ("off-centre load", ["load.mass=1.5", "load.com=[0.05,-0.03,0.02]"], 5),
    ("tilted", ["orientation.psi=0.3", "orientation.theta=-0.2", "orientation.phi=0.1"], 6),
])
def test_the_cpr8_misses_what_its_jacobian_cannot_reach_and_keeps_table_2(make_cfg, catalogue, case):
    """At the zero orientation J^T has rank 5 (a turn about a vertical axis changes no cable
    length): the forces miss up to 1.4 % of F, below the 5 % of tension.pinv_residual, so the
    paper's verdicts stand; tilted, J^T has full rank and misses nothing."""
    _, overrides, rank = case
    cfg = make_cfg(*overrides)
    points, summary = compute_workspace(cfg, catalogue)
    problem, _ = build_problem(cfg, catalogue)
    assert (points["jacobian_rank"] == rank).all()
    angles = np.array(problem.orientations[0])
    for row in points.iloc[::23].itertuples():
        share = missed_share(problem, np.array([row.x, row.y, row.z]), angles, rows=6)
        assert row.wrench_residual == pytest.approx(share, rel=1e-5, abs=1e-9)
    if rank == 6:
        assert points["wrench_residual"].max() < 1e-9
    else:
        assert 0.01 < points["wrench_residual"].max() < 0.05
    assert summary["lost_unreachable"] == 0
    if not overrides:
        assert summary["n_feasible"] == 216  # Table 2, actuator 1


def test_the_compiled_kernel_reports_the_same_residual(make_cfg, catalogue):
    """The fused kernel's one-short route measures |w . F| / |F| with the direction it drops;
    numpy the least-squares residual of the SVD's pseudo-inverse: the same margins."""
    for extra in ([], ["load.com=[0.05,-0.03,0.02]"], ["orientation.phi=0.4"]):
        numpy_points, _ = compute_workspace(make_cfg("compute.kernel=numpy", "grid.n=9", *extra), catalogue)
        fused_points, summary = compute_workspace(make_cfg("compute.kernel=fused", "grid.n=9", *extra), catalogue)
        assert summary["kernel"] == "fused"
        for column in ("margin_unreachable", "margin_zero_length", "jacobian_rank"):
            np.testing.assert_allclose(fused_points[column], numpy_points[column], rtol=1e-9, atol=1e-12)
        assert (fused_points["feasible"] == numpy_points["feasible"]).all()


def test_the_log_says_which_rank_and_how_much_is_missed(make_cfg, catalogue, caplog):
    with caplog.at_level(logging.INFO, logger="pipeline"):
        compute_workspace(make_cfg(), catalogue)
    assert "J^T is short of rank 6 at 216 of 216 poses (rank 5 at 216" in caplog.text
    assert "miss up to 1.39% of the required wrench (unreachable past tension.pinv_residual=0.05)" in caplog.text


# A square of anchors in a plane and a grid through its corners: at each corner one cable has
# zero length and no direction.
SQUARE = ["robot=points", "robot.anchors=[[0,0,0],[2,0,0],[2,2,0],[0,2,0]]",
          "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.cable_names=[nw,ne,se,sw]",
          "robot.dofs=[x,y]", "robot.search.lo=[0,0,0]", "robot.search.hi=[2,2,0]", "robot.search.step=0.5",
          "wrench.fx=1", "wrench.fy=0.5"]
# Eight anchors at a cube's corners, a small platform: the poses that put an attachment on its
# anchor are the corners minus the attachment, which the grid below holds.
CUBE_ANCHORS = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [0, 0, 2], [2, 0, 2], [2, 2, 2], [0, 2, 2]]
CUBE_PLATFORM = [[0.5 * (c - 1) for c in a] for a in CUBE_ANCHORS]  # a 1 m cube
CUBE = ["robot=points", f"robot.anchors={CUBE_ANCHORS}", f"robot.attachments={CUBE_PLATFORM}",
        "robot.platform.mass=1", "robot.search.lo=[0.5,0.5,0.5]", "robot.search.hi=[1.5,1.5,1.5]",
        "robot.search.step=0.25"]


def collapsed_poses(anchors, attachments, positions) -> np.ndarray:
    """(n,) the positions where some attachment (zero orientation) sits on its anchor."""
    targets = np.asarray(anchors, float) - np.asarray(attachments, float)
    return (np.linalg.norm(positions[:, None, :] - targets[None], axis=2) < 1e-9).any(axis=1)


@pytest.mark.parametrize("robot, extra, others_hold", [  # others_hold: some other pose is feasible
    (SQUARE, ["analysis=statics", "tension=pinv"], False),  # minimum-norm tensions push
    (SQUARE, ["analysis=statics", "tension=feasible"], True),
    (SQUARE, ["analysis=payload"], True),
    (CUBE, ["analysis=statics"], True),
    (CUBE, ["analysis=cpr_wwa", "tension=pinv"], True),
    (CUBE, ["analysis=cpr_wwa", "tension=feasible"], True),
    (CUBE, ["analysis=payload", "tension=pinv"], False),
])
def test_a_pose_that_collapses_a_cable_is_infeasible_in_every_analysis(make_cfg, catalogue, robot, extra,
                                                                       others_hold, caplog):
    """It was reported feasible: the collapsed cable had a zero column and the others held the
    load. Exactly the poses that put an attachment on its anchor fail, by the zero_length gate,
    and the log names their cables."""
    cfg = make_cfg(*robot, *extra)
    with caplog.at_level(logging.WARNING, logger="pipeline"):
        points, summary = compute_workspace(cfg, catalogue)
    anchors, attachments = cfg.robot.anchors, cfg.robot.attachments
    expected = collapsed_poses(anchors, attachments, points[["x", "y", "z"]].to_numpy())
    assert expected.sum() == (4 if robot is SQUARE else 8)
    assert (((points["limiting"] == "zero_length") & ~points["feasible"]) == expected).all()
    assert not points.loc[expected, "feasible"].any()
    assert (points.loc[expected, "margin_zero_length"] == -1.0).all()
    assert (points.loc[~expected, "margin_zero_length"] == 1.0).all()
    assert summary["lost_zero_length"] == expected.sum()
    assert (summary["n_feasible"] > 0) == others_hold  # the other poses are judged as before
    names = "nw, ne, se, sw" if robot is SQUARE else "1, 2, 3, 4, 5, 6, 7, 8"
    assert f"cables {names} have zero length at some poses" in caplog.text
    if "analysis=payload" in extra:
        assert points.loc[expected, "max_payload_kg"].isna().all()


def test_the_compiled_kernels_mark_the_same_collapsed_poses(make_cfg, catalogue):
    for extra in (["analysis=statics", "tension=pinv"], ["analysis=cpr_wwa", "tension=pinv"]):
        by_numpy, _ = compute_workspace(make_cfg(*CUBE, *extra, "compute.kernel=numpy"), catalogue)
        fused, summary = compute_workspace(make_cfg(*CUBE, *extra, "compute.kernel=fused"), catalogue)
        assert summary["kernel"] == "fused"
        np.testing.assert_array_equal(fused["margin_zero_length"], by_numpy["margin_zero_length"])
        assert (fused["limiting"] == by_numpy["limiting"]).all()


# A platform homothetic to its frame (each attachment a tenth of its anchor's offset from the
# frame's centre), cables not crossed: every cable line passes through the centre of the homothety
# that maps the frame onto the platform, at every pose, so the cables produce no moment about it:
# rank 3 (a user's first design in issue 39 was a milder case of this, rank 5).
HOMOTHETIC = ["robot=points", f"robot.anchors={SPREAD_ANCHORS}",
              f"robot.attachments={[[0.1 * x, 0.1 * y, 0.1 * (z - 1)] for x, y, z in SPREAD_ANCHORS]}",
              "robot.search.lo=[-1.5,-1,0.25]", "robot.search.hi=[1.5,1,1.75]", "robot.search.step=0.5",
              "robot.platform.mass=2"]


@pytest.mark.parametrize("extra, gate", [([], "unreachable"), (["tension=pinv"], "singular")])
def test_a_degenerate_design_says_which_wrench_it_cannot_produce(make_cfg, catalogue, caplog, extra, gate):
    """It said only "unreachable"; the user needed her own SVD. The log and the summary now give
    the rank at a failing pose and a direction of the wrench space the cables cannot act along,
    in words: checked against the structure matrix written out here (its rank, and the
    direction orthogonal to every cable's wrench)."""
    cfg = make_cfg(*HOMOTHETIC, *extra)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        points, summary = compute_workspace(cfg, catalogue)
    assert summary[f"lost_{gate}"] >= 136 and summary["n_feasible"] <= 4  # only where the weight's line
    x, y, z = points.loc[~points["feasible"], ["x", "y", "z"]].to_numpy()[0]  # meets the common point
    anchors, platform = np.array(SPREAD_ANCHORS, float), np.array(cfg.robot.attachments, float)
    vectors = np.array([x, y, z]) + platform - anchors
    units = vectors / np.linalg.norm(vectors, axis=1)[:, None]
    structure = np.vstack([units.T, np.cross(platform, units).T])  # [u_i; b_i x u_i], level platform
    sigma = np.linalg.svd(structure, compute_uv=False)
    assert (sigma > 1e-9 * sigma[0]).sum() == summary["deficient_rank"] == 3
    problem, _ = build_problem(cfg, catalogue)
    sample = Degeneracy(problem).direction_at(np.array([x, y, z]))
    assert np.abs(sample["vector"] @ structure).max() < 1e-12 and np.linalg.norm(sample["vector"]) == pytest.approx(1)
    assert summary["missing_direction"] == sample["words"] and sample["main"].startswith("moment about ")
    assert (f"at (x, y, z) = ({x:g}, {y:g}, {z:g}) m the structure matrix has rank 3 of 6: the cables cannot "
            f"produce a {sample['main']} there") in caplog.text


def test_the_cpr8_names_the_yaw_it_cannot_hold_at_the_zero_orientation(make_cfg, catalogue, caplog):
    with caplog.at_level(logging.INFO, logger="pipeline"):
        _, summary = compute_workspace(make_cfg(), catalogue)
    assert summary["deficient_rank"] == 5 and summary["n_feasible"] == 216
    assert summary["missing_direction"].startswith("moment about z (+0.99)")
    assert "the structure matrix has rank 5 of 6: the cables cannot produce a moment about z there" in caplog.text


@pytest.mark.parametrize("overrides, limit, remedy", [
    (["actuator=5"], "torque", "a stronger actuator, a higher drive.gear_ratio or a smaller drive.winch_radius"),
    ([*LINE], "unreachable", "anchors and attachments that give the cables independent directions"),
    ([*SQUARE, "tension=pinv"], "slack", "under tension=pinv, tension=feasible if the cables may not push"),
])
def test_a_job_with_no_feasible_pose_says_what_to_try_next(tmp_path, overrides, limit, remedy):
    """A 0 % result named only its counts; now it names what limited it and the next thing to try
    (each criterion's remedy in the registry)."""
    done = command(tmp_path, "pipeline", *overrides, f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr
    (line,) = [line for line in (done.stdout + done.stderr).splitlines() if "no pose is feasible" in line]
    assert f"are lost to {limit} first; to try next: {remedy}" in line


# A spherical platform (freedoms rx, ry, rz) whose every cable points at its centre: no cable has a
# moment arm, so its structure matrix is zero (rank 0) at the centre.
RADIAL = ["robot=points", "analysis=statics", "tension=feasible", "robot.dofs=[rx,ry,rz]", "robot.cable_names=null",
          "robot.anchors=[[1,0,0],[-1,0,0],[0,1,0],[0,-1,0],[0,0,1],[0,0,-1],[1,1,1]]",
          "robot.attachments=[[0.1,0,0],[-0.1,0,0],[0,0.1,0],[0,-0.1,0],[0,0,0.1],[0,0,-0.1],[0.05,0.05,0.05]]",
          "robot.search.lo=[0,0,0]", "robot.search.hi=[0,0,0]", "robot.search.step=0.1"]


@pytest.mark.parametrize("moment, feasible", [(0.0, True), (1.0, False)])
def test_a_structure_matrix_of_rank_zero_holds_no_wrench_and_the_zero_wrench(make_cfg, catalogue, moment, feasible):
    """Rank 0 (the feasible model's search had a traceback here: a binomial of q - 1 = -1): the
    zero wrench is held by slack cables, a moment about z is unreachable."""
    points, summary = compute_workspace(make_cfg(*RADIAL, f"wrench.mz={moment}"), catalogue)
    assert summary["n_points"] == 1 and bool(points["feasible"].iloc[0]) is feasible
    residual = 1.0 if moment else 0.0  # the share of the wrench missed: all of it, or nothing to miss
    assert points["margin_unreachable"].iloc[0] == pytest.approx(1.0 - residual / 1e-6)  # tension.residual_rtol
    if not feasible:
        assert points["limiting"].iloc[0] == "unreachable"


def test_a_sweep_of_one_robot_says_its_rank_notes_once(tmp_path):
    """The CPR-8's rank-5 notes were printed twice a job (ten lines for the main job): a sweep
    says each once, a job run alone after it says them again, and every job's summary keeps them."""
    import pandas as pd

    from conftest import command

    sweep = command(tmp_path, "pipeline", "-m", "actuator=1,2,3,4,5", f"hydra.sweep.dir={tmp_path / 'sweep'}")
    assert sweep.returncode == 0, sweep.stderr[-2000:]
    text = sweep.stdout + sweep.stderr
    assert text.count("J^T is short of rank 6 at 216 of 216 poses") == 1
    assert text.count("the structure matrix has rank 5 of 6: the cables cannot produce a moment about z") == 1
    summary = pd.read_parquet(tmp_path / "sweep" / "summary.parquet")
    assert (summary["deficient_rank"] == 5).all() and len(summary) == 5
    alone = command(tmp_path, "pipeline", "actuator=2", f"hydra.run.dir={tmp_path / 'alone'}")
    assert (alone.stdout + alone.stderr).count("the structure matrix has rank 5 of 6") == 1

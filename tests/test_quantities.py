"""Per-pose cable quantities (``output.cables=true``) and runs on the user's own poses."""

import numpy as np
import pytest

from pipeline.model.geometry import structure_matrix
from pipeline.app.problem import build_problem
from conftest import compute_workspace


def test_irpm_at_the_centre_holds_the_weight_with_six_equal_tensions(make_cfg, catalogue):
    points, _ = compute_workspace(make_cfg("robot=irpm6", "output.cables=true", "poses=[[0,0,5]]"), catalogue)
    tensions = points.filter(regex="^tension_").to_numpy()[0]
    lengths = points.filter(regex="^length_").to_numpy()[0]
    assert tensions == pytest.approx(np.full(6, tensions[0])) and lengths == pytest.approx(np.full(6, lengths[0]))
    assert 6 * tensions[0] * 5.0 / lengths[0] == pytest.approx(100_000.0)  # vertical parts: f_z


def test_feasible_distribution_balances_the_wrench_within_its_limits(make_cfg, catalogue):
    """IPAnema-like 8 cables, zero wrench, t in [1, 10] N: the chosen tensions are a real
    solution of A t = 0 at every feasible pose."""
    anchors = [[x, y, z] for z in (2, 0) for x, y in ((-2, 1.5), (2, 1.5), (2, -1.5), (-2, -1.5))]
    platform = [[-0.06, 0.06, 0], [0.06, 0.06, 0], [0.06, -0.06, 0], [-0.06, -0.06, 0]] * 2
    poses = [[0, 0, 1], [0.5, -0.3, 0.7], [1.2, 0.4, 1.5], [-1.5, 1.0, 0.3]]
    cfg = make_cfg("robot=points", f"robot.anchors={anchors}", f"robot.attachments={platform}",
                   "robot.search.lo=[-2,-1.5,0]", "robot.search.hi=[2,1.5,2]", "robot.search.step=0.5",
                   "tension.model=feasible", "tension.t_min=1", "tension.t_max=10", "load.mass=0",
                   "output.cables=true", f"poses={poses}")
    points, _ = compute_workspace(cfg, catalogue)
    assert points["feasible"].sum() >= 2
    for _, row in points[points["feasible"]].iterrows():
        t = row.filter(regex="^tension_").to_numpy(dtype=float)
        vectors = row[["x", "y", "z"]].to_numpy(dtype=float) + np.array(platform) - np.array(anchors)
        unit = vectors / np.linalg.norm(vectors, axis=1, keepdims=True)
        a = structure_matrix(unit[None], np.array(platform, float)[None])[0]
        assert np.abs(a @ t).max() < 1e-6 and (t >= 1 - 1e-7).all() and (t <= 10 + 1e-7).all()
        assert row.filter(regex="^length_").to_numpy(dtype=float) == pytest.approx(np.linalg.norm(vectors, axis=1))


@pytest.mark.parametrize("actuator", [3, 5])
def test_cpr8_tension_range_explains_the_torque_margin(make_cfg, catalogue, actuator):
    """|M| <= T of eq. (32): the worst |t| R over the acceleration set is (1 - margin) T."""
    problem, grid = build_problem(make_cfg(f"actuator={actuator}"), catalogue)
    points, _ = compute_workspace(make_cfg(f"actuator={actuator}", "output.cables=true"), catalogue)
    worst = np.maximum(points.filter(regex="^tension_max_").abs().to_numpy(),
                       points.filter(regex="^tension_min_").abs().to_numpy()).max(axis=1)
    radius = problem.spec.winch_radius[0]
    assert worst * radius == pytest.approx((1 - points["margin_torque"]) * problem.limits.torque_limit)


def test_given_poses_get_the_verdicts_and_margins_of_the_same_grid_points(make_cfg, catalogue):
    grid_points, _ = compute_workspace(make_cfg("actuator=4"), catalogue)
    chosen = grid_points.iloc[[0, 37, 100, 215]]
    poses = chosen[["x", "y", "z"]].to_numpy().tolist()
    points, summary = compute_workspace(make_cfg("actuator=4", f"poses={poses}"), catalogue)
    assert points["feasible"].tolist() == chosen["feasible"].tolist()
    np.testing.assert_allclose(points.filter(like="margin_"), chosen.filter(like="margin_"), atol=1e-12)
    assert summary["n_points"] == 4 and np.isnan(summary["volume_m3"])

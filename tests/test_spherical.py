"""Robots whose platform a joint holds at the frame's origin (``robot.dofs`` among rx, ry, rz):
their grid is of orientations, one verdict each. Checked pose by pose against a plain LP written
here from the points (no code of the model), with an off-centre platform whose weight's moment
turns with it, in both angle conventions, and for the largest payload."""

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import eq9_rotation, compute_workspace
from pipeline.app.problem import build_problem
from pipeline.errors import ConfigError

ANCHORS = [[1, 0, 0.5], [-0.5, 0.87, 0.5], [-0.5, -0.87, 0.5], [1, 0, -0.5], [-0.5, 0.87, -0.5], [-0.5, -0.87, -0.5]]
PLATFORM = [[0, 0.2, 0.2], [0.17, -0.1, 0.2], [-0.17, -0.1, 0.2], [0, 0.2, -0.2], [0.17, -0.1, -0.2],
            [-0.17, -0.1, -0.2]]
MASS, COM = 2.0, (0.05, 0.0, 0.1)
GIMBAL = ["robot=points", f"robot.anchors={ANCHORS}", f"robot.attachments={PLATFORM}", "robot.dofs=[rx,ry,rz]",
          f"robot.platform.mass={MASS}", f"robot.platform.com=[{COM[0]},{COM[1]},{COM[2]}]",
          "robot.search.lo=[-0.6,-0.6,-0.6]", "robot.search.hi=[0.6,0.6,0.6]", "robot.search.step=0.15",
          "analysis=statics", "tension=feasible", "tension.t_max=150"]


def xyz_rotation(a: float, b: float, c: float) -> np.ndarray:
    """CASPR's Rx(a) Ry(b) Rz(c), written out."""
    return eq9_rotation(a, 0, 0) @ eq9_rotation(0, b, 0) @ eq9_rotation(0, 0, c)


def moment_rows(rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The three moment rows about the joint (3, m) and the weight's moment (3,) at one rotation."""
    arms = np.asarray(PLATFORM, float) @ rotation.T
    pull = np.asarray(ANCHORS, float) - arms  # a cable pulls its attachment towards its anchor
    pull /= np.linalg.norm(pull, axis=1, keepdims=True)
    weight = np.array([0.0, 0.0, -MASS * 9.81])
    return np.cross(arms, pull).T, np.cross(rotation @ np.asarray(COM), weight)


def lp_verdict(rotation: np.ndarray, t_max: float = 150.0) -> bool:
    rows, moment = moment_rows(rotation)
    done = linprog(np.zeros(len(ANCHORS)), A_eq=rows, b_eq=-moment, bounds=[(0, t_max)] * len(ANCHORS), method="highs")
    return done.status == 0


def lp_payload(rotation: np.ndarray, payload_com, t_max: float = 150.0) -> float:
    """The largest mu (kg) at ``payload_com`` the cables hold with the platform, by one LP."""
    rows, moment = moment_rows(rotation)
    per_kg = np.cross(rotation @ np.asarray(payload_com, float), [0.0, 0.0, -9.81])
    matrix = np.hstack([rows, per_kg[:, None]])  # rows t + mu per_kg = -moment
    done = linprog(np.r_[np.zeros(len(ANCHORS)), -1.0], A_eq=matrix, b_eq=-moment,
                   bounds=[(0, t_max)] * len(ANCHORS) + [(0, 1e6)], method="highs")
    return done.x[-1] if done.status == 0 else np.nan


@pytest.mark.parametrize("convention, rotation", [("zyx", eq9_rotation), ("xyz", xyz_rotation)])
def test_each_orientation_agrees_with_an_independent_lp(make_cfg, catalogue, convention, rotation):
    points, summary = compute_workspace(make_cfg(*GIMBAL, f"orientation.convention={convention}"), catalogue)
    assert summary["n_points"] == len(points) == 9 ** 3 and np.isnan(summary["volume_m3"])
    assert (points[["x", "y", "z"]].to_numpy() == 0).all()
    expected = np.array([lp_verdict(rotation(*row)) for row in points[["psi", "theta", "phi"]].to_numpy()])
    least = points.filter(like="margin_").min(axis=1).to_numpy()
    clear = np.abs(least) > 1e-6  # the LP's own tolerance decides the poses on the boundary
    assert (points["feasible"].to_numpy()[clear] == expected[clear]).all()
    assert 0.3 < expected.mean() < 0.95 and clear.mean() > 0.95  # both verdicts occur, few on the boundary


def test_the_weight_moment_turns_with_the_platform(make_cfg, catalogue):
    """Off centre, the weight's moment about the joint depends on the orientation: the verdicts
    differ from those of a platform whose centre of mass is on the joint."""
    loaded = compute_workspace(make_cfg(*GIMBAL), catalogue)[0]["feasible"]
    centred = compute_workspace(make_cfg(*GIMBAL, "robot.platform.com=[0,0,0]"), catalogue)[0]["feasible"]
    assert centred.all() and not loaded.all()


def test_the_largest_payload_per_orientation_is_the_lps(make_cfg, catalogue):
    cfg = make_cfg(*GIMBAL, "analysis=payload", "load.com=[0,0.1,0.15]", "robot.search.step=0.3")
    points, _ = compute_workspace(cfg, catalogue)
    for row in points.itertuples():
        expected = lp_payload(eq9_rotation(row.psi, row.theta, row.phi), (0, 0.1, 0.15))
        if np.isnan(expected):
            assert np.isnan(row.max_payload_kg)
        else:
            assert row.max_payload_kg == pytest.approx(expected, rel=1e-6, abs=1e-6)


@pytest.mark.parametrize("overrides, message", [
    (["orientation.psi=0.2"], "orientation: robot.dofs=[rx, ry, rz] holds the platform at the origin and its grid is "
                              "of orientations"),
    (["orientation.total.bound=0.1", "orientation.total.n=3"], "orientation.psi, theta, phi and total are not read"),
    (["analysis=cpr_wwa", "tension=pinv"], "robot.dofs=[rx, ry, rz]: the dynamics of eqs. (19)-(31) move a spatial "
                                           "platform"),
])
def test_what_a_platform_held_at_a_point_cannot_mean_is_refused_in_one_line(make_cfg, catalogue, overrides, message):
    with pytest.raises(ConfigError, match=None) as refused:
        build_problem(make_cfg(*GIMBAL, *overrides), catalogue)
    assert message in str(refused.value) and "\n" not in str(refused.value)


def test_an_orientation_grid_has_no_boundary_mesh_to_write(make_cfg, catalogue):
    from pipeline.app.problem import validate

    with pytest.raises(ConfigError) as refused:
        validate(make_cfg(*GIMBAL, "output.mesh=true"), catalogue, typed=True)
    assert str(refused.value) == ("output.mesh=true: the grid is of orientations (a robot on a joint), whose boundary "
                                  "has no volume in m^3, so there is no boundary to write")


def test_interference_turns_with_each_orientation_of_the_grid(make_cfg, catalogue):
    """A robot on a joint with a post beside it and a platform body: the per-pose rotations give
    each orientation's own clearances, as a state built for that orientation alone does."""
    from pipeline.model.geometry import PoseGeometry
    from pipeline.workspace.criteria.interference import cable_obstacle, cable_platform

    extra = ["obstacles=[{name: post, lo: [0.15, -0.05, -0.3], hi: [0.4, 0.05, 0.3]}]", "robot.platform.shape=hull"]
    problem, grid = build_problem(make_cfg(*GIMBAL, *extra), catalogue)
    table = compute_workspace(make_cfg(*GIMBAL, *extra), catalogue)[0]
    rows = grid[:]
    for k in range(0, len(rows), 97):
        rotation = xyz_rotation(*rows[k]) if problem.angles == "xyz" else eq9_rotation(*rows[k])
        state = PoseGeometry(problem.robot, np.zeros((1, 3)), rotation[None])
        assert table["margin_cable_obstacle"].iloc[k] == pytest.approx(cable_obstacle(state, None)[0], abs=1e-12)
        assert table["margin_cable_platform"].iloc[k] == pytest.approx(cable_platform(state, None)[0], abs=1e-12)
    assert (table["margin_cable_obstacle"] < 0).any() and (table["margin_cable_obstacle"] > 0).any()

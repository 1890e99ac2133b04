"""Planar, point and suspended robots (``robot.dofs``): the cables balance the rows of the
platform's freedoms, a joint or a plane takes the others. Each workspace is checked pose by pose
against a plain LP written here from the points (no code of the model), on platforms that are
tilted, loaded off centre, or held by fewer cables than a free body has freedoms."""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import command, eq9_rotation, compute_workspace
from pipeline.app.problem import build_problem
from pipeline.errors import ConfigError

ROWS = {"x": 0, "y": 1, "z": 2, "rx": 3, "ry": 4, "rz": 5}


def points_robot(anchors, attachments, dofs, lo, hi, step, *extra):
    return ["robot=points", f"robot.anchors={anchors}", f"robot.attachments={attachments}",
            f"robot.dofs=[{','.join(dofs)}]", f"robot.search.lo={lo}", f"robot.search.hi={hi}",
            f"robot.search.step={step}", *extra]


def lp_verdicts(positions, anchors, attachments, dofs, bounds, mass=0.0, com=(0, 0, 0), up=(0, 0, 1),
                angles=(0.0, 0.0, 0.0), external=(0, 0, 0, 0, 0, 0)):
    """Whether tensions within ``bounds`` pull the platform into balance with its weight (and
    the weight's moment about the reference point) and an external wrench along the rows
    ``dofs``, pose by pose."""
    r = eq9_rotation(*angles)
    arms = np.asarray(attachments, float) @ r.T
    weight = -mass * 9.81 * np.asarray(up, float)
    load = np.concatenate([weight, np.cross(r @ np.asarray(com, float), weight)]) + np.asarray(external, float)
    rows = [ROWS[d] for d in dofs]
    found = []
    for p in positions:
        pull = np.asarray(anchors, float) - (p + arms)  # a cable pulls its attachment towards its anchor
        pull /= np.linalg.norm(pull, axis=1, keepdims=True)
        matrix = np.vstack([pull.T, np.cross(arms, pull).T])[rows]
        done = linprog(np.zeros(len(anchors)), A_eq=matrix, b_eq=-load[rows], bounds=bounds, method="highs")
        found.append(done.status == 0)
    return np.array(found)


CASES = {
    # a planar point in a vertical plane (gravity along -y): four cables, rows x, y
    "planar point": (points_robot("[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]", "[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
                                  ["x", "y"], "[-0.9,-0.9,0]", "[0.9,0.9,0]", 0.1, "robot.up=[0,1,0]",
                                  "tension.t_min=1", "tension.t_max=30", "load.mass=2"),
                     dict(dofs=["x", "y"], bounds=[(1, 30)] * 4, mass=2.0, up=(0, 1, 0))),
    # a planar body on a horizontal table turned by 0.3 rad, pushed in its plane: rows x, y, rz
    # (the table holds the weight and its moment, which six rows would leave unbalanced)
    "planar body": (points_robot("[[-1.2,-1,0],[-1.2,1,0],[1.2,-1,0],[1.2,1,0]]",
                                 "[[-0.1,0.05,0],[-0.1,-0.05,0],[0.14,0.05,0],[0.14,-0.05,0]]",
                                 ["x", "y", "rz"], "[-0.9,-0.7,0]", "[0.9,0.7,0]", 0.1,
                                 "robot.platform.mass=3", "robot.platform.com=[0.02,0,0]", "orientation.phi=0.3",
                                 "load.external=[12,-8,0,0,0,0.5]", "tension.t_min=1", "tension.t_max=40"),
                    dict(dofs=["x", "y", "rz"], bounds=[(1, 40)] * 4, mass=3.0, com=(0.02, 0, 0),
                         angles=(0.0, 0.0, 0.3), external=(12, -8, 0, 0, 0, 0.5))),
    # a level platform hanging from three cables, its attachments apart (a joint holds its
    # orientation, CASPR's T_XYZ): rows x, y, z, the cables' moments taken by the joint
    "suspended level platform": (points_robot("[[-2,-1.5,3],[2,-1.5,3],[0,2,3]]",
                                              "[[-0.3,-0.2,0.1],[0.3,-0.2,0.1],[0,0.3,0.1]]",
                                              ["x", "y", "z"], "[-1.8,-1.4,0.5]", "[1.8,1.9,2.5]", 0.25,
                                              "tension.t_min=0", "tension.t_max=200", "load.mass=20",
                                              "load.com=[0.1,0,-0.2]"),
                                 dict(dofs=["x", "y", "z"], bounds=[(0, 200)] * 3, mass=20.0, com=(0.1, 0, -0.2))),
    # a free body (six rows) on four cables from above, loaded off centre and tilted: it
    # balances only where the weight's line passes through the cables' pull (a crane's hook)
    "four cables, six freedoms": (points_robot("[[-2,-2,3],[2,-2,3],[2,2,3],[-2,2,3]]",
                                               "[[-0.2,-0.2,0.1],[0.2,-0.2,0.1],[0.2,0.2,0.1],[-0.2,0.2,0.1]]",
                                               ["x", "y", "z", "rx", "ry", "rz"], "[-1,-1,0.5]", "[1,1,2]", 0.25,
                                               "tension.t_min=0", "tension.t_max=400", "load.mass=10",
                                               "load.com=[0.05,0,-0.3]", "orientation.psi=0.1"),
                                  dict(dofs=["x", "y", "z", "rx", "ry", "rz"], bounds=[(0, 400)] * 4, mass=10.0,
                                       com=(0.05, 0, -0.3), angles=(0.1, 0.0, 0.0))),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_freedoms_workspace_agrees_with_an_independent_lp_pose_by_pose(make_cfg, catalogue, case):
    overrides, reference = CASES[case]
    cfg = make_cfg(*overrides, "tension=feasible")
    points, summary = compute_workspace(cfg, catalogue)
    anchors = np.array(eval(overrides[1].split("=", 1)[1]), float)  # noqa: S307 - our own literal
    attachments = np.array(eval(overrides[2].split("=", 1)[1]), float)  # noqa: S307
    expected = lp_verdicts(points[["x", "y", "z"]].to_numpy(), anchors, attachments, **reference)
    assert points["feasible"].to_numpy().tolist() == expected.tolist()
    if case != "four cables, six freedoms":  # the hook balances on a set of no volume here
        assert 0 < summary["n_feasible"] < summary["n_points"], summary["n_feasible"]
    flat = np.asarray(cfg.robot.search.lo)[2] == np.asarray(cfg.robot.search.hi)[2]
    assert np.isnan(summary["volume_m3"]) == flat  # a plane has no volume


def test_a_point_crane_has_a_workspace_under_its_anchors_and_a_free_body_on_it_needs_the_weight_aligned(
        make_cfg, catalogue):
    """Fewer cables than freedoms means something: three cables hold a point mass wherever the
    weight is inside their pull, and four hold a free body with its centre of mass under the
    reference point where the cables meet there (every attachment at one point)."""
    hook = points_robot("[[-2,-2,3],[2,-2,3],[2,2,3],[-2,2,3]]", "[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
                        ["x", "y", "z", "rx", "ry", "rz"], "[-1,-1,0.5]", "[1,1,2]", 0.25,
                        "tension.t_min=0", "tension.t_max=400", "load.mass=10", "tension=feasible")
    points, summary = compute_workspace(make_cfg(*hook), catalogue)
    assert summary["n_feasible"] == summary["n_points"]  # the moments vanish: a point under the frame
    tilted = compute_workspace(make_cfg(*hook, "load.com=[0.1,0,0]"), catalogue)[1]
    assert tilted["n_feasible"] == 0 and tilted["lost_unreachable"] == tilted["n_points"]  # a moment nobody balances


@pytest.mark.parametrize("overrides, message", [
    (["analysis=cpr_wwa", "robot.dofs=[x,y]"],
     "robot.dofs=[x, y]: the dynamics of eqs. (19)-(31) move a spatial platform"),
    (["analysis=cpr_wwa", "robot.dofs=[x,y,z]"], "with model.pinv_columns=translational; use analysis=statics"),
    (["tension=pinv", "robot.dofs=[x,y,z,rx,ry,rz]", "robot.anchors=[[0,0,3],[1,0,3],[0,1,3]]",
      "robot.attachments=[[0,0,0],[0,0,0],[0,0,0]]"],
     "robot: 3 cables; analysis=statics balances forces and moments (6 rows of the structure matrix) and needs "
     ">= 6 cables; tension=feasible finds where fewer cables hold the load"),
    (["robot.dofs=[x,x]"], "robot.dofs=['x', 'x']: must be distinct freedoms among x, y, z, rx, ry, rz"),
    (["robot.dofs=[q]"], "robot.dofs=['q']: must be distinct freedoms"),
    (["robot.dofs=[]"], "robot.dofs=[]: must be distinct freedoms"),
])
def test_a_freedom_an_analysis_cannot_mean_is_refused_in_one_line(make_cfg, catalogue, overrides, message):
    from pipeline.app.problem import validate

    base = points_robot("[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]", "[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
                        ["x", "y"], "[-0.9,-0.9,0]", "[0.9,0.9,0]", 0.1)
    with pytest.raises(ConfigError) as error:
        validate(make_cfg(*base, *overrides), catalogue)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_the_compiled_kernel_leaves_a_robot_with_fewer_freedoms_to_numpy(make_cfg, catalogue):
    from pipeline.workspace.dispatch import fused_unfit

    planar = points_robot("[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]", "[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
                          ["x", "y"], "[-0.9,-0.9,0]", "[0.9,0.9,0]", 0.1, "tension=pinv")
    assert "robot.dofs" in fused_unfit(build_problem(make_cfg(*planar), catalogue)[0])


def test_a_planar_caspr_model_imports_with_its_freedoms_and_its_plane(tmp_path):
    """PLANAR_XY (x, y, rz), attachments relative to the centre of mass: the box is the joint's
    x, y limits in the plane z = 0; on a horizontal table (which holds the 3 kg) and pushed in
    its plane, the verdicts are the LP's on the rows x, y, rz."""
    data = Path(__file__).parent / "data" / "caspr"
    done = command(tmp_path, "pipeline.caspr", str(data / "Quad_planar_cables.xml"), "--bodies",
                   str(data / "Quad_planar_bodies.xml"), "--out", "mine/robot/quad.yaml")
    assert done.returncode == 0, done.stderr
    assert "search box x [-0.9, 0.9], y [-0.7, 0.7], z [0, 0] m from the joint's q_min/q_max" in done.stdout
    import yaml

    robot = yaml.safe_load((tmp_path / "mine" / "robot" / "quad.yaml").read_text())["robot"]
    assert robot["dofs"] == ["x", "y", "rz"] and robot["search"]["spacing"] == "faces"
    ran = command(tmp_path, "pipeline", "--config-dir", "mine", "robot=quad",
                  "load.external=[12,-8,0,0,0,0.5]", "orientation.phi=0.2", "hydra.run.dir=out")
    assert ran.returncode == 0, ran.stderr
    import pandas as pd

    points = pd.read_parquet(tmp_path / "out" / "points.parquet")
    expected = lp_verdicts(points[["x", "y", "z"]].to_numpy(), robot["anchors"], robot["attachments"],
                           ["x", "y", "rz"], [(1, 40)] * 4, mass=3.0, com=(0.02, 0, 0), angles=(0.0, 0.0, 0.2),
                           external=(12, -8, 0, 0, 0, 0.5))
    assert points["feasible"].tolist() == expected.tolist()
    assert 0 < points["feasible"].sum() < len(points)


@pytest.mark.parametrize("t_max, holds", [(20.0, True), (10.0, False)])
def test_a_one_freedom_hoist_holds_its_load_where_newton_says(make_cfg, catalogue, t_max, holds):
    """robot.dofs=[z]: one cable above and one below a 1 kg slider, t in [1, t_max] N. Newton:
    t_up - t_down = 9.81 N with t_down >= 1 needs t_up >= 10.81 N: within 20 N, beyond 10 N.
    (One freedom crashed the feasible model's search, issue 51.) And [rz], two cables on
    a turntable: two parallel cables on either side of its axis twist it opposite ways, 0.1 m
    each: t_1 0.1 = t_2 0.1 holds with equal tensions; both on one side cannot balance."""
    hoist = points_robot("[[0,0,3],[0,0,-3]]", "[[0,0,0],[0,0,0]]", ["z"], "[0,0,-1]", "[0,0,1]", 0.25,
                         "tension=feasible", "tension.t_min=1", f"tension.t_max={t_max}", "load.mass=1")
    points, summary = compute_workspace(make_cfg(*hoist), catalogue)
    assert summary["n_points"] == 9 and summary["n_feasible"] == (9 if holds else 0)
    for attachments, balanced in (("[[0,0.1,0],[0,-0.1,0]]", True), ("[[0,0.1,0],[0,0.1,0]]", False)):
        turntable = points_robot("[[1,0.1,0],[1,-0.1,0]]", attachments, ["rz"], "[0,0,0]", "[0,0,0]", 0.25,
                                 "tension=feasible", "tension.t_min=1", "tension.t_max=5")
        assert compute_workspace(make_cfg(*turntable), catalogue)[1]["n_feasible"] == balanced

"""Required wrench sets (``wrench.set``, Gouttefarde's wrench-feasible workspace): a pose is
feasible when the cables balance every wrench of a box or a list of vertices added to the
platform's load. Checked against a plain LP per pose and per vertex written here, for pulling
cables and for the minimum-norm tensions, on a tilted platform with its centre of mass off centre."""

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import SPREAD_ANCHORS, SPREAD_PLATFORM, SPREAD_ROBOT, eq9_rotation, compute_workspace
from pipeline.app.problem import validate
from pipeline.errors import ConfigError

ROBOT = [*SPREAD_ROBOT, "robot.search.step=0.5",
         "robot.platform.mass=3", "robot.platform.com=[0.02,0,-0.03]", "orientation.theta=0.12",
         "tension.t_min=2", "tension.t_max=300"]
BOX = {"min": [-10, 0, -5, 0, -1, 0], "max": [10, 0, 5, 0, 1, 0]}  # f_x, f_z, m_y: 8 vertices
BOX_OVERRIDE = "wrench.set={min:[-10,0,-5,0,-1,0],max:[10,0,5,0,1,0]}"


def balance(position):
    """M (6, m) with M t the wrench the cables exert, and the platform's load wrench."""
    r = eq9_rotation(0.0, 0.12, 0.0)
    arms = np.array(SPREAD_PLATFORM, float) @ r.T
    pull = np.array(SPREAD_ANCHORS, float) - (position + arms)
    pull /= np.linalg.norm(pull, axis=1, keepdims=True)
    weight = np.array([0.0, 0.0, -3 * 9.81])
    return np.vstack([pull.T, np.cross(arms, pull).T]), np.concatenate([weight, np.cross(r @ [0.02, 0, -0.03], weight)])


def vertices_of(box):
    """The box's vertices in the documented order: itertools' product of each coordinate's
    sorted distinct min and max."""
    return [np.array(v, float) for v in itertools.product(*(sorted({a, b}) for a, b in zip(box["min"], box["max"])))]


def lp_holds(position, wrench):
    matrix, load = balance(position)
    done = linprog(np.zeros(8), A_eq=matrix, b_eq=-(load + wrench), bounds=[(2, 300)] * 8, method="highs")
    return done.status == 0


def pinv_holds(position, wrench):
    matrix, load = balance(position)
    tensions = np.linalg.pinv(matrix) @ -(load + wrench)
    return bool(((tensions >= 2) & (tensions <= 300)).all())


@pytest.mark.parametrize("model, holds", [("feasible", lp_holds), ("pinv", pinv_holds)])
def test_a_pose_is_feasible_when_every_vertex_of_the_box_is(make_cfg, catalogue, model, holds):
    points, summary = compute_workspace(make_cfg(*ROBOT, f"tension={model}", BOX_OVERRIDE), catalogue)
    vertices = vertices_of(BOX)
    assert len(vertices) == 8 and summary["n_wrenches"] == 8
    expected = [all(holds(p, v) for v in vertices) for p in points[["x", "y", "z"]].to_numpy()]
    assert points["feasible"].tolist() == expected
    alone = compute_workspace(make_cfg(*ROBOT, f"tension={model}"), catalogue)[1]
    assert summary["n_feasible"] < alone["n_feasible"]  # the set costs poses
    if model == "feasible":
        assert summary["n_feasible"] > 0


def test_a_list_of_vertices_is_the_same_set_as_the_box(make_cfg, catalogue):
    listed = "wrench.set=[" + ",".join("[" + ",".join(f"{x:g}" for x in v) + "]" for v in vertices_of(BOX)) + "]"
    box = compute_workspace(make_cfg(*ROBOT, "tension=feasible", BOX_OVERRIDE), catalogue)[0]
    vertices = compute_workspace(make_cfg(*ROBOT, "tension=feasible", listed), catalogue)[0]
    assert box["feasible"].tolist() == vertices["feasible"].tolist()


@pytest.mark.parametrize("overrides, message", [
    (["wrench.set={min:[0,0,0,0,0,0]}"], "a box needs min and max, 6 numbers each"),
    (["wrench.set={min:[1,0,0,0,0,0],max:[0,0,0,0,0,0]}"],
     "wrench.set.min=[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]: must be <= wrench.set.max"),
    (["wrench.set={min:[0,0,0,0,0,.nan],max:[0,0,0,0,0,1]}"], "wrench.set.min"),
    (["wrench.set=[[1,2,3]]"], "wrench.set: vertex 1=[1, 2, 3]: needs 6 values (fx fy fz mx my mz, N and N m)"),
    (["wrench.set=[]"], "wrench.set=[]: no vertices"),
    (["wrench.set=[[1e12,0,0,0,0,0]]"],
     "wrench.set: vertex 1=[1000000000000.0, 0, 0, 0, 0, 0]: every value must be at most 1e+09 in magnitude"),
    (["wrench.set=3"], "wrench.set=3: a box {min: [6], max: [6]} or a list of [fx, fy, fz, mx, my, mz]"),
    (["analysis=cpr_wwa", "wrench.set=[[1,0,0,0,0,0]]"], "wrench.set: analysis=cpr_wwa balances its acceleration set"),
])
def test_a_wrench_set_that_means_nothing_is_refused_in_one_line(make_cfg, catalogue, overrides, message):
    with pytest.raises(ConfigError) as error:
        validate(make_cfg(*ROBOT, *overrides), catalogue)
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("model, holds", [("feasible", lp_holds), ("pinv", pinv_holds)])
def test_each_failing_pose_names_a_vertex_it_cannot_hold(make_cfg, catalogue, model, holds):
    """``limiting_wrench``: 0 where the whole set holds, else the 1-based vertex (the box's in
    itertools order of each coordinate's sorted min and max) with the lowest margin of its own,
    which the pose cannot hold alone (unless a singular structure matrix, the same for every
    vertex, is what limits it); the vertices are not all named alike."""
    points, _ = compute_workspace(make_cfg(*ROBOT, f"tension={model}", BOX_OVERRIDE), catalogue)
    vertices = vertices_of(BOX)
    named = points["limiting_wrench"].to_numpy()
    assert (named[points["feasible"].to_numpy()] == 0).all()
    failing = points.loc[~points["feasible"]]
    for (_, row), vertex in zip(failing.iterrows(), named[~points["feasible"].to_numpy()]):
        assert 1 <= vertex <= 8
        if row["limiting"] != "singular":
            assert not holds(row[["x", "y", "z"]].to_numpy(dtype=float), vertices[vertex - 1])
    alone = compute_workspace(make_cfg(*ROBOT, f"tension={model}"), catalogue)[0]
    by_set = named[alone["feasible"].to_numpy() & ~points["feasible"].to_numpy()]  # lost to the set itself
    assert len(set(by_set)) > 1


def test_repeated_vertices_are_solved_once_and_named_as_the_user_numbered_them(make_cfg, catalogue):
    """A list of 2 000 vertices that repeats the box's 8 (issue 51: unbounded work with no
    output) is the box's 8 wrenches, the same verdicts, and ``limiting_wrench`` numbers each
    vertex by its first place in the user's list (here the list is the box's, reversed, 250 times)."""
    vertices = vertices_of(BOX)[::-1]
    listed = "wrench.set=[" + ",".join("[" + ",".join(f"{x:g}" for x in v) + "]" for v in vertices * 250) + "]"
    repeated, summary = compute_workspace(make_cfg(*ROBOT, "tension=feasible", listed), catalogue)
    box = compute_workspace(make_cfg(*ROBOT, "tension=feasible", BOX_OVERRIDE), catalogue)[0]
    assert summary["n_wrenches"] == 8
    assert repeated["feasible"].tolist() == box["feasible"].tolist()
    named = repeated["limiting_wrench"].to_numpy()
    in_box = box["limiting_wrench"].to_numpy()
    assert (named[in_box > 0] == 9 - in_box[in_box > 0]).all() and (named[in_box == 0] == 0).all()

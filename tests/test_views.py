"""The report's 3-D views (pipeline/analyses/views.py): the feasible set as its boundary surface on a
full grid, the robot drawn where a written-out pose puts it, a grid of orientations shown in its
angles."""

import base64
import json

import numpy as np

from conftest import eq9_rotation, compute_workspace
from pipeline.analyses.views import pose_axes, robot_traces, write_view
import pytest

from pipeline.api import workspace
from pipeline.app.problem import build_problem
from pipeline.workspace.boundary import enclosed_volume


def array(value) -> np.ndarray:
    """An array of a Plotly JSON figure: a list, or numpy's bytes in base64 (plotly >= 6)."""
    if isinstance(value, dict):
        return np.frombuffer(base64.b64decode(value["bdata"]), dtype=value["dtype"])
    return np.asarray(value, dtype=float)


def test_a_full_grid_shows_its_feasible_set_as_a_surface_and_the_robot_at_a_pose(make_cfg, catalogue, tmp_path):
    """The surface is the job's own boundary: the volume it encloses, read back from the view's
    JSON, is the summary's mesh_volume_m3 (computed as the job streamed its chunks)."""
    cfg = make_cfg("actuator=2", "orientation.psi=0.2")
    done = workspace(["actuator=2", "orientation.psi=0.2"], tmp_path / "job")
    points, summary = done.points, done.summary
    robot = build_problem(cfg, catalogue)[0].robot
    position = np.array([1.0, 0.9, -1.1])
    traces = robot_traces(robot, position, eq9_rotation(0.2, 0.0, -0.3))  # a tilted, turned carrier
    box = tuple(np.array([summary[f"box.{a}_{end}"] for a in "xyz"]) for end in ("min", "max"))
    view = json.loads(write_view([(points, "feasible", None)], "t", False, tmp_path / "v.json", traces, box).read_text())
    by_name = {trace["name"]: trace for trace in view["data"]}
    surface = by_name[f"feasible set ({summary['n_feasible']})"]
    assert surface["type"] == "mesh3d" and 0 < summary["n_feasible"] < 216
    vertices = np.column_stack([array(surface[a]) for a in "xyz"])
    triangles = np.column_stack([array(surface[k]) for k in "ijk"]).astype(int)
    assert enclosed_volume(vertices, triangles) == pytest.approx(summary["mesh_volume_m3"], rel=1e-4)
    assert (vertices >= box[0] - 1e-4).all() and (vertices <= box[1] + 1e-4).all()  # closed on the box
    assert by_name[f"feasible ({summary['n_feasible']})"]["visible"] == "legendonly"  # the surface shows them
    lost = [trace for name, trace in by_name.items() if name.startswith("lost to ")]
    assert lost and all(trace["visible"] == "legendonly" for trace in lost)  # they buried the feasible set
    anchors = by_name["anchors"]
    assert np.array_equal(np.column_stack([array(anchors[a]) for a in "xyz"]), robot.anchors) and robot.n_cables == 8
    cables = next(t for name, t in by_name.items() if name.startswith("cables at (1, 0.9, -1.1) m"))
    ends = np.array([cables[axis][1::3] for axis in "xyz"], dtype=float).T  # anchor, end, gap per cable
    written_out = position + np.asarray(robot.attachments) @ eq9_rotation(0.2, 0.0, -0.3).T
    assert np.allclose(ends, written_out, atol=1e-12)
    assert by_name["platform"]["type"] == "mesh3d"  # the carrier's eight corners span a volume
    assert view["layout"]["scene"]["camera"]["eye"]["x"] > 1.5


def test_a_plane_a_list_and_an_empty_set_have_no_surface_and_a_flat_platform_an_outline(tmp_path):
    import pandas as pd

    grid = pd.DataFrame([(x, y, 0.0) for x in range(3) for y in range(3)], columns=list("xyz"))
    grid = grid.assign(psi=0.0, theta=0.0, phi=0.0, feasible=True, limiting="slack", margin_slack=1.0)
    view = json.loads(write_view([(grid, "feasible", None)], "t", False, tmp_path / "v.json").read_text())
    assert [t["type"] for t in view["data"]] == ["scatter3d"]  # a plane: points only

    class Flat:  # four attachments in one plane, four anchors
        anchors = np.array([[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
        attachments = np.array([[0.1, 0.1, 0], [-0.1, -0.1, 0], [0.1, -0.1, 0], [-0.1, 0.1, 0]], float)
        cable_names = ("a", "b", "c", "d")
        obstacles = ()
        pulleys = None
    outline = [t for t in robot_traces(Flat, np.zeros(3), np.eye(3)) if t["name"] == "platform"][0]
    corners = {(x, y) for x, y in zip(outline["x"], outline["y"]) if x is not None}
    assert outline["type"] == "scatter3d" and corners == {(0.1, 0.1), (-0.1, -0.1), (0.1, -0.1), (-0.1, 0.1)}
    segments = [(outline["x"][i], outline["y"][i], outline["x"][i + 1], outline["y"][i + 1]) for i in range(0, 12, 3)]
    assert all(abs(x0 - x1) + abs(y0 - y1) < 0.21 for x0, y0, x1, y1 in segments)  # around, not across


def test_a_grid_of_orientations_is_shown_in_its_angles(make_cfg, catalogue, tmp_path):
    gimbal = ["robot=points", "robot.anchors=[[1,0,0.5],[-0.5,0.87,0.5],[-0.5,-0.87,0.5],[1,0,-0.5],[-0.5,0.87,-0.5],"
              "[-0.5,-0.87,-0.5]]", "robot.attachments=[[0,0.2,0.2],[0.17,-0.1,0.2],[-0.17,-0.1,0.2],[0,0.2,-0.2],"
              "[0.17,-0.1,-0.2],[-0.17,-0.1,-0.2]]", "robot.dofs=[rx,ry,rz]", "robot.platform.mass=2",
              "robot.platform.com=[0.05,0,0.1]", "robot.search.lo=[-0.6,-0.6,-0.6]", "robot.search.hi=[0.6,0.6,0.6]",
              "robot.search.step=0.3", "analysis=statics", "tension=feasible", "tension.t_max=150"]
    points, _ = compute_workspace(make_cfg(*gimbal), catalogue)
    assert pose_axes(points) == ("psi", "theta", "phi")
    view = json.loads(write_view([(points, "feasible", None)], "t", False, tmp_path / "v.json").read_text())
    assert view["layout"]["scene"]["xaxis"]["title"]["text"] == "psi (rad)"
    assert view["data"][0]["type"] == "mesh3d"


def test_the_obstacles_are_drawn_where_the_config_puts_them(make_cfg, catalogue):
    """A box's twelve edges at its corners; a plane's patch lies in the plane and spans the frame."""
    cfg = make_cfg("obstacles=[{name: table, lo: [1, 0.5, -2.5], hi: [2, 1.5, -1.6]},"
                   "{name: wall, point: [0, 0, -3], normal: [0, 0.2, 1]}]")
    problem, _ = build_problem(cfg, catalogue)
    by_name = {t["name"]: t for t in robot_traces(problem.robot, np.array([1.5, 1.0, -1.0]), np.eye(3))}
    table = np.array([by_name["table"][a] for a in "xyz"], dtype=float).T
    table = table[~np.isnan(table).any(axis=1)]
    assert len(table) == 24 and {tuple(p) for p in table} == {
        (x, y, z) for x in (1, 2) for y in (0.5, 1.5) for z in (-2.5, -1.6)}
    wall = np.array([by_name["wall"][a] for a in "xyz"], dtype=float).T
    wall = wall[~np.isnan(wall).any(axis=1)]
    normal = np.array([0, 0.2, 1]) / np.linalg.norm([0, 0.2, 1])
    assert np.allclose((wall - [0, 0, -3]) @ normal, 0, atol=1e-12)
    anchors = problem.robot.anchors
    assert np.ptp(wall[:, 0]) >= np.ptp(anchors[:, 0]) - 1e-9


def test_a_view_with_a_home_shows_the_connected_poses_apart_from_the_others(tmp_path):
    import pandas as pd

    grid = pd.DataFrame([(x, y, z) for x in range(3) for y in range(3) for z in range(2)], columns=list("xyz"), dtype=float)
    feasible = (grid["x"] != 1).to_numpy()  # two slabs apart
    grid = grid.assign(psi=0.0, theta=0.0, phi=0.0, feasible=feasible, connected=feasible & (grid["x"] == 0).to_numpy(),
                       limiting=pd.Categorical(np.where(feasible, "slack", "tension_max")), margin_slack=1.0)
    view = json.loads(write_view([(grid, "feasible", None)], "t", False, tmp_path / "v.json").read_text())
    by_name = {t["name"]: t for t in view["data"]}
    assert by_name["connected to home (6)"]["marker"]["symbol"] == "circle"
    assert by_name["feasible, not connected (6)"]["marker"]["symbol"] == "circle-open"
    assert "lost to tension_max (6)" in by_name
    assert by_name["connected to home (6)"]["visible"] == "legendonly"  # the surface shows the feasible set


def test_with_no_feasible_pose_the_lost_poses_are_shown(tmp_path):
    """The lost poses start hidden only where the feasible set has something to show."""
    import pandas as pd

    grid = pd.DataFrame([(x, y, z) for x in range(2) for y in range(2) for z in range(2)], columns=list("xyz"))
    grid = grid.assign(psi=0.0, theta=0.0, phi=0.0, feasible=False, limiting="slack", margin_slack=-1.0)
    view = json.loads(write_view([(grid, "feasible", None)], "t", False, tmp_path / "v.json").read_text())
    lost = [t for t in view["data"] if t["name"].startswith("lost to slack")]
    assert len(lost) == 1 and "visible" not in lost[0]


def test_a_static_cloud_draws_the_jobs_boundary_surface(tmp_path):
    """The PNG clouds showed points only: on a full grid they now draw the same boundary the view
    and the summary have (its enclosed volume is the summary's mesh_volume_m3)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from pipeline.analyses.figures import _cloud_panel
    from pipeline.analyses.views import boundary_of

    done = workspace(["actuator=3", "orientation.psi=0.3"], tmp_path / "job")
    box = tuple(np.array([done.summary[f"box.{a}_{end}"] for a in "xyz"]) for end in ("min", "max"))
    vertices, triangles = boundary_of(done.points, "feasible", ("x", "y", "z"), box)
    assert enclosed_volume(vertices, triangles) == pytest.approx(done.summary["mesh_volume_m3"], rel=1e-4)
    ax = plt.figure().add_subplot(projection="3d")
    _cloud_panel(ax, done.points, "feasible", False, box)
    ax.figure.canvas.draw()  # a 3-D collection projects its faces when drawn
    surfaces = [c for c in ax.collections if isinstance(c, Poly3DCollection)]
    assert len(surfaces) == 1 and len(surfaces[0].get_paths()) == len(triangles)
    plt.close("all")

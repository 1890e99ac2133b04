"""Impossible designs caught before the grid runs (issue 53), each in one line naming the
culprits: crossed cables that touch at the box's centre (a warning: cables crossing in one
plane touch at every pose), an anchor on or in an obstacle (refused: every pose would lose its
cable), a frame and a platform of sizes no cable robot has (refused: a unit typed wrong)."""

import pytest

from conftest import command
from test_zero_cause import CROSSING

EXAMPLE = ["--config-dir", "examples/my_robot", "robot=myrobot", "tension.t_min=1", "tension.t_max=400"]


def run(tmp_path, *args):
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    args = [str(root / a) if a.startswith("examples/") else a for a in args]
    tmp_path.mkdir(parents=True, exist_ok=True)
    return command(tmp_path, "pipeline", *args, f"hydra.run.dir={tmp_path / 'run'}")


def warnings_of(done) -> list[str]:
    return [line for line in (done.stdout + done.stderr).splitlines() if "touch at the centre" in line]


def test_crossed_cables_in_one_plane_are_named_before_the_grid_runs(tmp_path):
    done = run(tmp_path, *CROSSING, "robot.cable_diameter=0.004")
    assert done.returncode == 0, done.stderr[-2000:]
    (warning,) = warnings_of(done)
    assert "cables 1-2, 1-4, 2-3, 3-4 touch at the centre of the search box" in warning
    staggered = run(tmp_path / "staggered", *EXAMPLE, "robot.cable_diameter=0.004")
    assert staggered.returncode == 0 and not warnings_of(staggered)
    assert not warnings_of(run(tmp_path / "none", *CROSSING))  # no diameter: cables are lines


@pytest.mark.parametrize("obstacle, extra, refused", [
    ("{name: floor, point: [0, 0, 0], normal: [0, 0, 1]}", ["robot.cable_diameter=0.004"],
     "obstacles[0] (floor): anchor 5 [-2.0, 1.5, 0.0] is within its cable's radius (0.002 m) of it"),
    ("{name: floor, point: [0, 0, 0.001], normal: [0, 0, 1]}", [],
     "obstacles[0] (floor): anchor 5 [-2.0, 1.5, 0.0] is inside it"),
    ("{name: post, lo: [1.9, 1.4, -0.1], hi: [2.1, 1.6, 0.1]}", [],
     "obstacles[0] (post): anchor 6 [2.0, 1.5, 0.0] is inside it"),
    ("{name: floor, point: [0, 0, 0], normal: [0, 0, 1]}", [], None),  # on it, cables of no thickness: clear
    ("{name: floor, point: [0, 0, -0.003], normal: [0, 0, 1]}", ["robot.cable_diameter=0.004"], None),
])
def test_an_anchor_on_or_in_an_obstacle_is_refused_before_the_work(tmp_path, obstacle, extra, refused):
    done = run(tmp_path, *EXAMPLE, f"obstacles=[{obstacle}]", *extra)
    if refused is None:
        assert done.returncode == 0, done.stderr[-2000:]
        return
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and refused in lines[0], lines
    assert not (tmp_path / "run").exists()


def test_a_frame_in_millimetres_with_a_platform_in_metres_is_refused(tmp_path):
    anchors = ("[[-2000,1500,2000],[2000,1500,2000],[2000,-1500,2000],[-2000,-1500,2000],"
               "[-2000,1500,0],[2000,1500,0],[2000,-1500,0],[-2000,-1500,0]]")
    done = run(tmp_path, *EXAMPLE, f"robot.anchors={anchors}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, lines
    assert "robot: the anchors span 4000 m and the attachments reach 0.09849 m" in lines[0]
    assert "are both in metres (robot.anchors, robot.attachments)?" in lines[0]
    small = "[[0.0005,0,0],[0,0.0005,0],[-0.0005,0,0],[0,-0.0005,0],[0.0005,0,0],[0,0.0005,0],[-0.0005,0,0],[0,-0.0005,0]]"
    assert run(tmp_path / "small", *EXAMPLE, f"robot.attachments={small}").returncode == 0  # 8 000 times: a tiny platform

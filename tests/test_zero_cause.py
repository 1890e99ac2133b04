"""What zeroed a workspace (issue 53): per criterion, the poses it alone removes (every other
criterion holding there), and a warning that names the one removing the most and its remedy,
not the first gate most poses fail."""

import numpy as np

from conftest import command, compute_workspace

# the example robot as it shipped: each upper cable coplanar with its neighbours and crossing
# them, so with any cable diameter every pose has touching cables
CROSSING = ["robot=points",
            "robot.anchors=[[-2,1.5,2],[2,1.5,2],[2,-1.5,2],[-2,-1.5,2],[-2,1.5,0],[2,1.5,0],[2,-1.5,0],[-2,-1.5,0]]",
            "robot.attachments=[[0.06,-0.06,0.05],[-0.06,-0.06,0.05],[-0.06,0.06,0.05],[0.06,0.06,0.05],"
            "[-0.06,0.06,-0.05],[0.06,0.06,-0.05],[0.06,-0.06,-0.05],[-0.06,-0.06,-0.05]]",
            "robot.platform.mass=3", "robot.search.lo=[-1.75,-1.25,0.25]", "robot.search.hi=[1.75,1.25,1.75]",
            "robot.search.step=0.25", "tension.t_min=1", "tension.t_max=100"]


def test_alone_counts_are_the_poses_where_only_that_criterion_fails(make_cfg, catalogue):
    """Recounted from the per-pose margins: a pose counts for a criterion when its margin is
    the only negative one. The crossing robot loses every pose, most to the slack gate first,
    while the statics keep the poses cable_cable alone removes."""
    points, summary = compute_workspace(make_cfg(*CROSSING, "robot.cable_diameter=0.004"), catalogue)
    names = [c[len("margin_"):] for c in points.columns if c.startswith("margin_")]
    negative = np.column_stack([points[f"margin_{n}"].to_numpy() < 0 for n in names])
    only = negative.sum(axis=1) == 1
    for i, name in enumerate(names):
        assert summary[f"alone_{name}"] == int((only & negative[:, i]).sum()), name
    assert summary["n_feasible"] == 0 and summary["alone_cable_cable"] > 0
    assert summary["lost_slack"] > summary["lost_cable_cable"]
    without = compute_workspace(make_cfg(*CROSSING), catalogue)[1]
    assert without["n_feasible"] == summary["alone_cable_cable"]  # relaxing it alone wins exactly these


def test_a_zeroed_workspace_names_what_alone_removed_it_and_its_remedy(tmp_path):
    done = command(tmp_path, "pipeline", *CROSSING, "robot.cable_diameter=0.004", f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    warning = [line for line in (done.stdout + done.stderr).splitlines() if "no pose is feasible" in line]
    assert len(warning) == 1 and "are lost to slack first, but cable_cable alone removes" in warning[0], warning
    assert "to try next: thinner cables (robot.cable_diameter)" in warning[0]


def test_without_a_sole_culprit_the_first_criterion_and_its_remedy_are_named():
    from pipeline.app.job import zero_cause

    summary = {"n_points": 10, "lost_torque": 7, "lost_voltage": 3, "alone_torque": 0, "alone_voltage": 0}
    assert zero_cause(summary).startswith("7 of 10 are lost to torque first; to try next: a stronger actuator")
    summary.update(alone_voltage=2)
    assert zero_cause(summary).startswith("7 of 10 are lost to torque first, but voltage alone removes 2")

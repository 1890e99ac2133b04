"""Swivelling pulleys at the anchors (issue 54 item 1, pipeline.model.pulleys).

Oracles: the geometry's own laws (the exit point on the pulley's rim, the free cable tangent to
it, the pulley's plane through its axis and the attachment point), the length's derivative
along the cable's direction by finite differences (Pott 2012: dl/dB = u), a second
parametrisation of the same pulley (the frame rotations of Tempel's inverse kinematics,
iswunistuttgart/matlab-tooling algoInverseKinematics_Pulley, written here from its published
steps), and the platform's equilibrium with the written tensions along those directions."""

import numpy as np
import pandas as pd
import pytest

from pipeline.app.problem import build_problem
from pipeline.model.pulleys import Pulleys, pulley_exits
from conftest import command, compute_workspace


def random_pulleys(rng, n=200, m=6):
    """Anchors on a 6 m frame, random swivel axes, radii of 2-12 cm, attachment points inside."""
    anchors = rng.uniform(-3, 3, (m, 3))
    axes = rng.normal(size=(m, 3))
    pulleys = Pulleys(axes / np.linalg.norm(axes, axis=1, keepdims=True), rng.uniform(0.02, 0.12, m))
    points = rng.uniform(-1.5, 1.5, (n, m, 3))
    return anchors, pulleys, points


def tempel(anchor, axis, radius, point):
    """Exit point and cable length by Tempel's steps: a frame K_A whose z axis is the swivel
    axis, the pulley turned about it by gamma = atan2(y, x) of the cable's end, the centre M on
    the turned x axis, the tangent's angle atan(L / r) added to that of M->B, the wrap angle
    between M->P and M->C by arccos (the entry point P is the anchor)."""
    z = axis
    x = np.cross(z, [0.3, 0.5, 0.8])
    x /= np.linalg.norm(x)
    frame = np.column_stack([x, np.cross(z, x), z])  # K_A -> world
    b = frame.T @ (point - anchor)
    gamma = np.arctan2(b[1], b[0])
    turn = np.array([[np.cos(gamma), -np.sin(gamma), 0], [np.sin(gamma), np.cos(gamma), 0], [0, 0, 1]])
    b_p = turn.T @ b
    m2b = b_p - radius * np.array([1.0, 0, 0])
    free = np.sqrt(m2b @ m2b - radius**2)
    angle = np.arctan(free / radius) + np.arctan2(m2b[2], m2b[0])
    m2c = radius * np.array([np.cos(angle), 0, np.sin(angle)])
    wrap = np.arccos(np.clip(np.dot([-radius, 0, 0], m2c) / radius**2, -1, 1))
    exit_point = anchor + frame @ (turn @ (radius * np.array([1.0, 0, 0]) + m2c))
    return exit_point, np.linalg.norm(point - exit_point) + radius * wrap


def test_the_cable_leaves_the_rim_tangent_in_the_plane_of_the_axis_and_its_end():
    rng = np.random.default_rng(3)
    anchors, pulleys, points = random_pulleys(rng)
    exits, wrapped = pulley_exits(anchors, pulleys, points)
    axes, radii = pulleys.axes, pulleys.radii
    radial = points - anchors - np.einsum("nmk,mk->nm", points - anchors, axes)[..., None] * axes
    toward = radial / np.linalg.norm(radial, axis=2, keepdims=True)
    centres = anchors + radii[:, None] * toward
    rim = exits - centres
    np.testing.assert_allclose(np.linalg.norm(rim, axis=2), np.broadcast_to(radii, rim.shape[:2]), rtol=1e-12)
    free = points - exits
    assert np.abs(np.einsum("nmk,nmk->nm", rim, free)).max() < 1e-11  # tangent: C - M normal to B - C
    normal = np.cross(axes, toward)  # the pulley's plane holds its axis and B
    assert np.abs(np.einsum("nmk,nmk->nm", exits - anchors, normal)).max() < 1e-12
    assert ((wrapped >= 0) & (wrapped < 2 * np.pi * radii)).all()


def test_the_length_grows_along_the_cable_by_finite_differences():
    """dl/dB = u = (B - C) / |B - C| (Pott 2012): the wrap's change cancels the exit point's."""
    rng = np.random.default_rng(5)
    anchors, pulleys, points = random_pulleys(rng, n=50)

    def total(at):
        exits, wrapped = pulley_exits(anchors, pulleys, at)
        return np.linalg.norm(at - exits, axis=2) + wrapped

    exits, _ = pulley_exits(anchors, pulleys, points)
    unit = (points - exits) / np.linalg.norm(points - exits, axis=2, keepdims=True)
    h = 1e-6
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        slope = (total(points + step) - total(points - step)) / (2 * h)
        np.testing.assert_allclose(slope, unit[..., k], atol=1e-7)


def test_a_second_parametrisation_gives_the_same_exit_points_and_lengths():
    rng = np.random.default_rng(7)
    anchors, pulleys, points = random_pulleys(rng, n=40)
    exits, wrapped = pulley_exits(anchors, pulleys, points)
    lengths = np.linalg.norm(points - exits, axis=2) + wrapped
    compared = 0
    for n in range(points.shape[0]):
        for i in range(len(anchors)):
            if wrapped[n, i] >= np.pi * pulleys.radii[i]:  # Tempel's arccos gives the wrap up to pi only
                continue
            theirs, length = tempel(anchors[i], pulleys.axes[i], pulleys.radii[i], points[n, i])
            np.testing.assert_allclose(exits[n, i], theirs, atol=1e-12)
            assert lengths[n, i] == pytest.approx(length, rel=1e-12)
            compared += 1
    assert compared > 0.5 * lengths.size


def test_radius_zero_is_the_fixed_anchor_and_small_radii_converge_to_it():
    rng = np.random.default_rng(9)
    anchors, pulleys, points = random_pulleys(rng, n=30)
    exits, wrapped = pulley_exits(anchors, Pulleys(pulleys.axes, np.zeros(len(anchors))), points)
    assert (exits == anchors).all() and (wrapped == 0).all()
    straight = np.linalg.norm(points - anchors, axis=2)
    for radius in (1e-3, 1e-5):
        exits, wrapped = pulley_exits(anchors, Pulleys(pulleys.axes, np.full(len(anchors), radius)), points)
        error = np.abs(np.linalg.norm(points - exits, axis=2) + wrapped - straight).max()
        assert error < 4 * radius  # the wrap adds at most pi r, the offset centre moves the free end by r
    assert error > 0


def test_the_cable_along_the_axis_wraps_nothing():
    """B straight ahead on the swivel axis (any pulley plane): no wrap, the cable leaves at the
    anchor and its length is the distance."""
    anchors = np.zeros((1, 3))
    pulleys = Pulleys(np.array([[0.0, 0.0, -1.0]]), np.array([0.05]))
    exits, wrapped = pulley_exits(anchors, pulleys, np.array([[[0.0, 0.0, -2.0]]]))
    np.testing.assert_allclose(exits[0, 0], [0, 0, 0], atol=1e-15)
    assert wrapped[0, 0] == pytest.approx(0.0, abs=1e-15)


def test_the_robots_structure_matrix_balances_along_the_pulleys_cables(make_cfg, catalogue, tmp_path):
    """The IRPM with pulleys: its written tensions (output.cables) times the directions from the
    second parametrisation's exit points balance the applied wrench, forces and moments; the
    directions from the anchors would miss it by about r / l."""
    pulleys = "robot.pulleys={axis: [0.3, -0.2, 1], radius: 0.1}"
    cfg = make_cfg("robot=irpm6", "robot.search.step=2", "robot.gamma_deg=20", pulleys, "output.cables=true")
    points, _ = compute_workspace(cfg, catalogue)
    problem, grid = build_problem(cfg, catalogue)
    robot, spec = problem.robot, problem.spec
    rotation = np.eye(3) if not any(problem.orientation) else None
    assert rotation is not None
    tensions = points[[f"tension_{name}" for name in robot.cable_names]].to_numpy()
    solved = np.isfinite(tensions).all(axis=1)
    worst = off = 0.0
    for position, t in zip(grid[:][solved][:60], tensions[solved][:60]):
        ends = position + robot.attachments
        wrench, straight = np.zeros(6), np.zeros(6)
        for i, end in enumerate(ends):
            exit_point, _ = tempel(robot.anchors[i], robot.pulleys.axes[i], robot.pulleys.radii[i], end)
            for start, total in ((exit_point, wrench), (robot.anchors[i], straight)):
                u = (end - start) / np.linalg.norm(end - start)
                total += t[i] * np.r_[u, np.cross(robot.attachments[i], u)]
        applied = spec.load.external - np.r_[spec.load.mass * spec.load.gravity * robot.up, 0, 0, 0]
        scale = np.abs(t).max()
        worst = max(worst, np.abs(wrench - applied).max() / scale)
        off = max(off, np.abs(straight - applied).max() / scale)
    assert worst < 1e-9 and off > 1e-4
    for i, name in enumerate(robot.cable_names):  # output.cables: the exit points and wrap angles
        ends = grid[:] + robot.attachments[i]
        theirs = np.array([tempel(robot.anchors[i], robot.pulleys.axes[i], 0.1, end)[0] for end in ends])
        written = points[[f"exit_{axis}_{name}" for axis in "xyz"]].to_numpy()
        np.testing.assert_allclose(written, theirs, atol=1e-12)
        free = np.linalg.norm(ends - theirs, axis=1)
        np.testing.assert_allclose(points[f"wrap_{name}"] * 0.1, points[f"length_{name}"] - free, atol=1e-12)


@pytest.mark.parametrize("value, message", [
    ("{axis: [0, 0, 0], radius: 0.05}", "robot.pulleys.axis=[0.0, 0.0, 0.0]: must not be zero"),
    ("{axis: [0, 0, 1], radius: -0.05}", "robot.pulleys.radius=-0.05: must be a number from 0"),
    ("{axis: [0, 0, 1], radius: 50}", "robot.pulleys.radius=50: must be a number from 0"),
    ("{axis: [0, 0, 1], radius: nan}", "robot.pulleys.radius=nan"),
    ("{axis: [0, 0, 1]}", "robot.pulleys={'axis': [0, 0, 1]}: a mapping {axis: [x, y, z], radius: m}"),
    ("[{axis: [0, 0, 1], radius: 0.05},{axis: [0, 0, 1], radius: 0.05}]", "robot.pulleys: 2 pulleys for 8 cables"),
    ("{axis: [0, 0, inf], radius: 0.05}", "robot.pulleys.axis=[0, 0, inf]"),
    ("0.05", "robot.pulleys=0.05: a mapping"),
])
def test_a_pulley_it_cannot_mean_is_refused_in_one_line(tmp_path, value, message):
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", "grid.n=3", f"robot.pulleys={value}", f"hydra.run.dir={run}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], lines
    assert not run.exists()


def test_the_fused_kernel_is_refused_and_the_length_limit_reads_the_wrapped_cable(make_cfg, catalogue, tmp_path):
    pulleys = "robot.pulleys={axis: [0, 0, -1], radius: 0.1}"
    done = command(tmp_path, "pipeline", "grid.n=3", pulleys, "compute.kernel=fused", f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 2 and "robot.pulleys" in done.stderr
    cfg = make_cfg("robot=irpm6", "robot.search.step=2", pulleys, "robot.l_max=12", "output.cables=true")
    points, _ = compute_workspace(cfg, catalogue)
    problem, grid = build_problem(cfg, catalogue)
    robot = problem.robot
    lengths = np.array([[tempel(robot.anchors[i], robot.pulleys.axes[i], robot.pulleys.radii[i], p + robot.attachments[i])[1]
                         for i in range(robot.n_cables)] for p in grid[:]])
    np.testing.assert_allclose(points[[f"length_{name}" for name in robot.cable_names]].to_numpy(), lengths, rtol=1e-12)
    np.testing.assert_allclose(points["margin_length"], 1 - lengths.max(axis=1) / 12, atol=1e-12)
    assert isinstance(points, pd.DataFrame)


def test_the_robots_picture_draws_each_cable_from_where_it_leaves_its_pulley(make_cfg, catalogue):
    from pipeline.analyses.views import robot_traces

    problem, _ = build_problem(make_cfg("robot=irpm6", "robot.pulleys={axis: [0, 0, 1], radius: 0.3}"), catalogue)
    robot, position = problem.robot, np.array([0.5, -0.3, 6.0])
    cables = [t for t in robot_traces(robot, position, np.eye(3)) if t["name"].startswith("cables")][0]
    starts = np.column_stack([cables[k][0::3] for k in "xyz"]).astype(float)  # each segment: start, end, gap
    exits, _ = pulley_exits(robot.anchors, robot.pulleys, (position + robot.attachments)[None])
    np.testing.assert_allclose(starts, exits[0], atol=1e-12)
    assert np.linalg.norm(starts - robot.anchors, axis=1).min() > 0.01


def test_a_vanishing_pulley_gives_the_anchors_verdicts_and_directions(make_cfg, catalogue):
    """Radius 1e-9 m on every cable: the same verdicts as no pulleys, and margins within 1e-6 where
    they are a share of their limit (in [-1, 1]) at the poses whose wrench the cables reach (in the
    base plane every cable lies flat: there the unreachable gate decides, and the later families'
    relaxed LPs amplify the nanometre)."""
    base = ["robot=irpm6", "robot.search.step=1", "robot.gamma_deg=20", "tension=feasible"]
    plain, _ = compute_workspace(make_cfg(*base), catalogue)
    tiny, _ = compute_workspace(make_cfg(*base, "robot.pulleys={axis: [0.3, -0.2, 1], radius: 1e-9}"), catalogue)
    np.testing.assert_array_equal(plain["feasible"], tiny["feasible"])
    for column in [c for c in plain.columns if c.startswith("margin_")]:
        reached = plain["margin_unreachable"] >= 0
        assert reached.mean() > 0.9
        np.testing.assert_allclose(tiny[column].clip(-1, 1)[reached], plain[column].clip(-1, 1)[reached], atol=1e-6)

"""The dynamic workspace of any robot (``platform_motion``, issue 56 item 2): the poses where the
cables hold the platform in every acceleration of a set, at an angular velocity.

Oracles: the platform as point masses whose accelerations come from finite differences of their
positions along a motion (Newton-Euler's wrench, independently); an LP per pose and acceleration
with the wrench written here from the point masses' sums; the statics at rest."""

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import SPREAD_ANCHORS, SPREAD_PLATFORM, SPREAD_ROBOT, command, compute_workspace, eq9_rotation
from pipeline.model.dynamics import Load, inertial_wrenches

G = 9.81


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def body(seed, n=9):
    """Point masses (kg) at body positions (m), their mass, centre of mass and inertia about it."""
    rng = np.random.default_rng(seed)
    masses, points = rng.uniform(0.2, 2.0, n), rng.normal(scale=0.3, size=(n, 3)) + [0.05, -0.02, 0.1]
    mass = masses.sum()
    com = masses @ points / mass
    r = points - com
    inertia = sum(m * (v @ v * np.eye(3) - np.outer(v, v)) for m, v in zip(masses, r))
    return masses, points, mass, com, inertia


def inertial_by_points(masses, points, rotation, acceleration, omega, dt=1e-4):
    """-[sum m_k p_k''; sum (p_k - O) x m_k p_k''] along O(t) = a t^2 / 2 and R(t) = exp([omega t +
    alpha t^2 / 2]x) R (the same motion to second order), p_k'' by central differences."""
    def positions(t):
        turn = omega * t + acceleration[3:] * t * t / 2
        angle = np.linalg.norm(turn)
        k = skew(turn / angle) if angle > 0 else np.zeros((3, 3))
        turned = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k  # Rodrigues
        return acceleration[:3] * t * t / 2 + points @ (turned @ rotation).T

    second = (positions(dt) - 2 * positions(0.0) + positions(-dt)) / dt ** 2
    arms = positions(0.0)
    force = -(masses[:, None] * second).sum(axis=0)
    moment = -np.cross(arms, masses[:, None] * second).sum(axis=0)
    return np.concatenate([force, moment])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_newton_euler_against_a_body_of_point_masses(seed):
    """Every acceleration, at a turning angular velocity and a tilted platform: the wrench of
    ``inertial_wrenches`` is the point masses' (rtol 1e-6 of its size)."""
    masses, points, mass, com, inertia = body(seed)
    rotation = eq9_rotation(0.3, -0.2, 0.7)
    rng = np.random.default_rng(10 + seed)
    accelerations, omega = rng.normal(scale=2.0, size=(5, 6)), rng.normal(scale=1.5, size=3)
    found = inertial_wrenches(Load(mass, G, com, np.zeros(6), inertia), rotation, accelerations, omega)
    for acceleration, wrench in zip(accelerations, found):
        exact = inertial_by_points(masses, points, rotation, acceleration, omega)
        assert np.allclose(wrench, exact, atol=1e-6 * np.abs(exact).max())
    per_pose = inertial_wrenches(Load(mass, G, com, np.zeros(6), inertia), np.stack([rotation] * 2), accelerations, omega)
    assert np.allclose(per_pose, found[None])


MOVING = [*SPREAD_ROBOT, "robot.search.step=0.25", "tension=feasible", "tension.t_min=1", "tension.t_max=300",
          "robot.platform.mass=1", "robot.platform.com=[0.02,-0.01,0.03]",
          "robot.platform.inertia=[0.004,0.005,0.006,0.0005,0,0]", "orientation.psi=0.1", "orientation.theta=-0.05"]


def test_at_rest_the_dynamic_workspace_is_the_static_one(catalogue):
    """A zero acceleration and angular velocity give the statics' verdicts and margins."""
    from conftest import make_cfg

    still, _ = compute_workspace(make_cfg(*MOVING), catalogue)
    zero, summary = compute_workspace(make_cfg(*MOVING, "platform_motion.acceleration=[[0,0,0,0,0,0]]"), catalogue)
    assert (still.feasible == zero.feasible).all() and still.feasible.any()
    margins = [c for c in still.columns if c.startswith("margin_")]
    assert np.allclose(still[margins], zero[margins], rtol=0, atol=1e-12)
    assert summary["n_wrenches"] == 1


def test_every_acceleration_against_an_lp_per_pose(catalogue):
    """A box of linear and angular accelerations (16 vertices) at an angular velocity: the verdicts
    are an LP's per pose and vertex (pulling cables in [1, 300] N balancing the weight and the
    point masses' inertial wrench, written here); bigger boxes hold fewer poses, each within."""
    from conftest import make_cfg

    box = "platform_motion.acceleration={min:[-1,0,-0.5,-3,0,0],max:[1,0,0.5,3,0,2]}"
    spin = "platform_motion.angular_velocity=[0,0,1.5]"
    points, summary = compute_workspace(make_cfg(*MOVING, box, spin), catalogue)
    assert summary["n_wrenches"] == 16 and 0 < points.feasible.sum() < len(points)
    rotation = eq9_rotation(0.1, -0.05, 0.0)
    com, inertia = rotation @ [0.02, -0.01, 0.03], rotation @ np.array(
        [[0.004, 0.0005, 0], [0.0005, 0.005, 0], [0, 0, 0.006]]) @ rotation.T
    omega = np.array([0.0, 0.0, 1.5])
    arms = np.array(SPREAD_PLATFORM) @ rotation.T
    corners = [np.array([ax, 0, az, rx, 0, rz]) for ax in (-1, 1) for az in (-0.5, 0.5) for rx in (-3, 3) for rz in (0, 2)]
    wrenches = []
    for a in corners:  # what the cables balance: the weight and -(d/dt) of the momentum, moments about O
        centre = a[:3] + np.cross(a[3:], com) + np.cross(omega, np.cross(omega, com))
        force = np.array([0.0, 0.0, -G]) - centre
        wrenches.append(np.concatenate([force, np.cross(com, force) - inertia @ a[3:] - np.cross(omega, inertia @ omega)]))
    rng = np.random.default_rng(4)
    for row in rng.choice(len(points), 250, replace=False):
        pose = points.iloc[row]
        vectors = pose[["x", "y", "z"]].to_numpy(float) + arms - np.array(SPREAD_ANCHORS)
        pulls = -vectors / np.linalg.norm(vectors, axis=1)[:, None]
        structure = np.vstack([pulls.T, np.cross(arms, pulls).T])
        held = all(linprog(np.zeros(8), A_eq=structure, b_eq=-w, bounds=[(1, 300)] * 8, method="highs").status == 0
                   for w in wrenches)
        assert held == pose.feasible, pose
    bigger, _ = compute_workspace(make_cfg(*MOVING, box.replace("-1,", "-2,").replace("max:[1,", "max:[2,"), spin),
                                  catalogue)
    assert bigger.feasible.sum() < points.feasible.sum() and not (bigger.feasible & ~points.feasible).any()


def test_listed_angular_velocities_are_each_required(catalogue):
    """Two angular velocities listed: a pose holds them when it holds each one (the jobs of one
    velocity each, and in between: their product of wrenches, 2 x 4 here)."""
    from conftest import make_cfg

    box = "platform_motion.acceleration={min:[-1,0,0,0,0,0],max:[1,0,0,0,0,2]}"
    first, second = "[0,0,2]", "[1.5,0,0]"
    both, summary = compute_workspace(make_cfg(*MOVING, box, f"platform_motion.angular_velocity=[{first},{second}]"),
                                      catalogue)
    alone = [compute_workspace(make_cfg(*MOVING, box, f"platform_motion.angular_velocity={w}"), catalogue)[0]
             for w in (first, second)]
    assert summary["n_wrenches"] == 8
    assert (both.feasible == (alone[0].feasible & alone[1].feasible)).all()
    assert (alone[0].feasible != alone[1].feasible).any() and both.feasible.any()


BAD = {
    "listed velocity nan": ("platform_motion.angular_velocity=[[0,0,1],[0,nan,1]]", "platform_motion.angular_velocity"),
    "min above max": ("platform_motion.acceleration={min:[1,0,0,0,0,0],max:[0,0,0,0,0,0]}",
                      "platform_motion.acceleration.min=[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]: must be <="),
    "five numbers": ("platform_motion.acceleration=[[1,2,3,4,5]]", "platform_motion.acceleration: vertex 1"),
    "nan": ("platform_motion.acceleration=[[nan,0,0,0,0,0]]", "platform_motion.acceleration: vertex 1"),
    "huge": ("platform_motion.acceleration=[[1e9,0,0,0,0,0]]", "at most 10000"),
    "not a set": ("platform_motion.acceleration=3", "platform_motion.acceleration=3: a box"),
    "no inertia": ("platform_motion.angular_velocity=[0,0,1]", "robot.platform.inertia"),
    "velocity nan": ("platform_motion.angular_velocity=[0,nan,1]", "platform_motion.angular_velocity"),
    "metrics": ("output.metrics=true", "output.metrics=true"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_motion_it_cannot_mean_is_one_line(tmp_path, case):
    override, named = BAD[case]
    extra = ["platform_motion.acceleration=[[1,0,0,0,0,0]]"] if case == "metrics" else []
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *SPREAD_ROBOT, "robot.search.step=0.5", "tension=feasible",
                   "robot.platform.mass=1", override, *extra, f"hydra.run.dir={run}")
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], lines
    assert not run.exists()


@pytest.mark.parametrize("analysis", ["cpr_wwa", "payload", "lines"])
def test_other_analyses_have_no_platform_motion(tmp_path, analysis):
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", f"analysis={analysis}", "grid.n=3",
                   "platform_motion.acceleration=[[1,0,0,0,0,0]]", f"hydra.run.dir={run}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "platform_motion" in lines[0], lines
    assert not run.exists()


def test_a_ball_of_accelerations_is_held_by_the_icosahedron_around_it(catalogue):
    """``{linear: r, angular: r}``: each ball by 12 vertices whose hull contains it (its support
    function is at least r in 20 000 random directions) and touches it (at least one direction
    within 1e-9 of r: the faces are tangent); the job holds fewer poses than at rest and every
    pose it holds holds the box's corners along the axes too (the ball contains them)."""
    from conftest import make_cfg
    from pipeline.app.problem import ball_vertices
    from omegaconf import OmegaConf

    vertices = ball_vertices(OmegaConf.create({"linear": 2.0, "angular": 3.0}))
    assert vertices.shape == (144, 6)
    rng = np.random.default_rng(0)
    directions = rng.normal(size=(20000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    for part, radius in ((vertices[:, :3], 2.0), (vertices[:, 3:], 3.0)):
        support = (directions @ part.T).max(axis=1)
        assert support.min() >= radius * (1 - 1e-12)
        normals = np.array([np.cross(b - a, c - a) for a, b, c in _faces(part)])
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        assert np.allclose(np.abs((normals[:, None, :] * part[None, :, :]).sum(-1)).max(axis=1), radius)
    ball = ["platform_motion.acceleration={linear: 1.5}"]
    moving, _ = compute_workspace(make_cfg(*MOVING, *ball), catalogue)
    still, _ = compute_workspace(make_cfg(*MOVING), catalogue)
    axes = "platform_motion.acceleration=[[1.5,0,0,0,0,0],[-1.5,0,0,0,0,0],[0,1.5,0,0,0,0],[0,-1.5,0,0,0,0]," \
           "[0,0,1.5,0,0,0],[0,0,-1.5,0,0,0]]"
    along, _ = compute_workspace(make_cfg(*MOVING, axes), catalogue)
    assert moving.feasible.sum() < still.feasible.sum()
    assert not (moving.feasible & ~along.feasible).any()


def _faces(points):
    from scipy.spatial import ConvexHull

    hull = ConvexHull(points)
    return [points[simplex] for simplex in hull.simplices]


@pytest.mark.parametrize("value", ["{linear: -1}", "{linear: abc}", "{angular: 1e9}"])
def test_a_ball_it_cannot_mean_is_one_line(tmp_path, value):
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *SPREAD_ROBOT, "robot.search.step=0.5", "tension=feasible",
                   "robot.platform.mass=1", "robot.platform.inertia=[0.01,0.01,0.01]",
                   f"platform_motion.acceleration={value}", f"hydra.run.dir={run}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "platform_motion.acceleration." in lines[0], lines
    assert not run.exists()

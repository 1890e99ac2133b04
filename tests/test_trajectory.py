"""The platform along a path in time (``analysis=trajectory``, issue 56 item 3).

Oracles, each from a law or a second method: the time laws' own closed forms and scipy's
evaluation of the polynomials; finite differences of rotations (angular velocity and
acceleration) and of cable lengths along the path (the cables' speeds and accelerations, with
swivelling pulleys too); the platform as point masses moved along the path (the wrench its
cables balance); the statics job at the samples' poses (a path whose motion asks nothing of the
cables gives the static verdicts bit for bit); a CASPR model with its trajectory file against a
QP per sample written here from the robot's points (tensions) and an LP (verdicts)."""

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.interpolate import BPoly, PPoly
from scipy.optimize import linprog, minimize
from scipy.spatial.transform import Rotation

from conftest import CROSSED_ROBOT, SPREAD_ANCHORS, SPREAD_ROBOT, command, eq9_rotation
from pipeline.model.dynamics import Load
from pipeline.model.geometry import CableRobot, PoseGeometry, euler_rate_axes
from pipeline.model.path import angular_motion, hermite, rest_to_rest, spline, trapezoid, trapezoidal
from pipeline.model.pulleys import Pulleys
from pipeline.model.statics import PathSpec, StaticsSpec

DATA = Path(__file__).parent / "data" / "caspr"
G = 9.81
ROBOT = [*SPREAD_ROBOT, "robot.search.step=0.25"]  # its search box is not read by a path
POINTS = np.array([[0.0, 0.0, 1.0, 0.1, -0.2, 0.3], [0.5, -0.3, 1.2, 0.4, 0.1, -0.2], [-0.4, 0.2, 0.8, -0.3, 0.2, 0.5]])


def curve(path) -> PPoly:
    """scipy's own evaluation of a path's pieces (a second method for Horner's scheme)."""
    return PPoly(path.coefficients, path.breaks)


def paths():
    return {"quintic": rest_to_rest(POINTS, [1.3, 0.9]), "spline": spline(POINTS, [1.3, 0.9]),
            "trapezoid": trapezoidal(POINTS, 0.8, 0.4, 0.5),
            "hermite": hermite(POINTS, [1.3, 0.9], [np.array([np.zeros(6), np.full(6, 0.2), np.zeros(6)]),
                                                    np.array([np.zeros(6), np.full(6, -0.1), np.zeros(6)])])}


@pytest.mark.parametrize("law", ["quintic", "spline", "trapezoid", "hermite"])
def test_the_samples_and_their_derivatives_are_the_polynomials(law):
    """Horner's value, rate and acceleration at every sample against scipy's PPoly (1e-12), each
    piece's samples inside it, in time order, at most dt apart."""
    path = paths()[law]
    samples = path.sample(0.01)
    ppoly = curve(path)
    inside = np.clip(samples.t, path.breaks[0], path.breaks[-1])
    for nu, found in enumerate((samples.q, samples.q_dot, samples.q_ddot)):
        reference = ppoly(inside, nu)
        jumps = np.isclose(samples.t[:, None], path.breaks[None, 1:-1], atol=1e-12).any(axis=1)  # one-sided there
        np.testing.assert_allclose(found[~jumps], reference[~jumps], rtol=1e-10, atol=1e-10)
    assert (np.diff(samples.t) >= -1e-12).all() and np.diff(samples.t).max() <= 0.01 + 1e-12
    np.testing.assert_allclose(samples.q[0], POINTS[0], atol=1e-12)
    np.testing.assert_allclose(samples.q[-1], POINTS[-1], atol=1e-9)


def test_a_segment_shorter_than_the_step_is_still_checked_where_it_accelerates(tmp_path):
    """A rest-to-rest segment of 1 ms sampled at the default 10 ms: at rest at both ends, it
    accelerates at up to 5.77 dq / T^2 inside; its samples must see that (a 30 kg platform whose
    cables cannot follow 15 cm in 20 ms, 2 165 m/s^2 at the peak), not only the two ends at rest."""
    samples = rest_to_rest(POINTS[:2], [1e-3]).sample(0.01)
    assert len(samples.t) >= 11 and np.abs(samples.q_ddot).max() > 0.9 * 5.77 * np.abs(POINTS[1] - POINTS[0]).max() / 1e-6
    done = command(tmp_path, "pipeline", "robot=irpm6", "analysis=trajectory", "wrench.fz=0", "robot.platform.mass=30",
                   "tension=feasible", "trajectory.points=[[0,0,4],[0.1,0.05,4.1]]", "trajectory.times=0.02",
                   f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    summary = pd.read_parquet(tmp_path / "run" / "summary.parquet").iloc[0]
    assert summary["n_samples"] >= 11 and 0 < summary["first_failure_sample"]


def test_the_quintic_law_is_rest_to_rest_and_scipys_hermite_polynomial():
    """q_i + (10 s^3 - 15 s^4 + 6 s^5) dq, written here, and BPoly.from_derivatives with zero rates."""
    path = rest_to_rest(POINTS, [1.3, 0.9])
    samples = path.sample(0.005)
    start = np.where(samples.segment == 0, 0.0, 1.3)
    duration = np.where(samples.segment == 0, 1.3, 0.9)
    s = (samples.t - start) / duration
    delta = POINTS[samples.segment + 1] - POINTS[samples.segment]
    law = 10 * s**3 - 15 * s**4 + 6 * s**5
    rate = (30 * s**2 - 60 * s**3 + 30 * s**4) / duration
    accel = (60 * s - 180 * s**2 + 120 * s**3) / duration**2
    np.testing.assert_allclose(samples.q, POINTS[samples.segment] + law[:, None] * delta, atol=1e-12)
    np.testing.assert_allclose(samples.q_dot, rate[:, None] * delta, atol=1e-11)
    np.testing.assert_allclose(samples.q_ddot, accel[:, None] * delta, atol=1e-10)
    scipys = BPoly.from_derivatives([0, 1.3, 2.2], [[p, np.zeros(6), np.zeros(6)] for p in POINTS])
    np.testing.assert_allclose(samples.q, scipys(samples.t), atol=1e-12)


def test_the_spline_passes_every_way_point_at_rest_at_both_ends_with_continuous_accelerations():
    points = np.random.default_rng(4).normal(size=(7, 6))
    times = np.array([0.5, 1.0, 0.7, 0.3, 1.1, 0.6])
    samples = spline(points, times).sample(0.01)
    at = np.concatenate([[0.0], np.cumsum(times)])
    for k, t in enumerate(at):
        rows = np.flatnonzero(np.isclose(samples.t, t, atol=1e-12))
        assert len(rows) == (1 if k in (0, len(at) - 1) else 2)  # each piece's both ends
        np.testing.assert_allclose(samples.q[rows], points[[k] * len(rows)], atol=1e-12)
        np.testing.assert_allclose(samples.q_ddot[rows], samples.q_ddot[rows[:1]].repeat(len(rows), 0), atol=1e-9)
    np.testing.assert_allclose(samples.q_dot[[0, -1]], 0.0, atol=1e-12)


def test_the_trapezoidal_law_is_the_papers_profile_along_each_segment_and_samples_both_sides_of_its_jumps():
    """Each segment's distance covered, speed and acceleration against ``trapezoid`` (the straight
    lines' profile, section 3.1.3) at the lines' own times; a jump of acceleration sampled on both sides."""
    points = np.array([[0.0, 0.0, 1.0], [1.5, 0.4, 1.2], [1.6, 0.5, 1.2]])  # long (cruise) then short (triangle)
    full = np.hstack([points, np.zeros((3, 3))])
    path = trapezoidal(full, 1.3, 0.6, 0.8)
    ppoly, start = curve(path), 0.0
    for i in range(2):
        distance = float(np.linalg.norm(points[i + 1] - points[i]))
        direction = (points[i + 1] - points[i]) / distance
        profile = trapezoid(distance, 1.3, 0.6, 0.8, 0.01)
        times = start + profile.t[:-1]
        np.testing.assert_allclose(ppoly(times)[:, :3], points[i] + profile.s[:-1, None] * direction, atol=1e-12)
        np.testing.assert_allclose(ppoly(times, 1)[:, :3], profile.v[:-1, None] * direction, atol=1e-12)
        np.testing.assert_allclose(ppoly(times, 2)[:, :3], profile.a[:-1, None] * direction, atol=1e-12)
        start += profile.t[-1]
    assert path.duration == pytest.approx(start, rel=1e-12)
    samples = path.sample(0.01)
    both = np.flatnonzero(np.isclose(samples.t, 0.6, atol=1e-12))  # v_max reached after t_acc: the cruise begins
    assert len(both) == 2 and samples.q_ddot[both[0], 0] > 0 and samples.q_ddot[both[1], 0] == pytest.approx(0.0)
    with pytest.raises(ValueError, match="same position"):
        trapezoidal(np.vstack([full[:1], full[:1]]), 1.0, 0.5, 0.5)


def test_a_speed_too_large_for_a_double_squared_gives_the_triangle_of_its_accelerations():
    """v_max = 1e200 m/s reached in 1e200 s: 1 m/s^2 up and down, a profile v_max never limits; over
    d = 2.25 m the triangle peaks at sqrt(d) = 1.5 m/s after 1.5 s and stops at 3 s (d = a T^2 / 4),
    where v_max^2 alone would overflow a double."""
    profile = trapezoid(2.25, 1e200, 1e200, 1e200, 0.01)
    assert profile.t[-1] == pytest.approx(3.0, rel=1e-12) and profile.v.max() == pytest.approx(1.5, rel=1e-12)
    np.testing.assert_allclose(profile.s, np.where(profile.t < 1.5, profile.t**2 / 2, 2.25 - (3 - profile.t) ** 2 / 2),
                               atol=1e-12)


@pytest.mark.parametrize("convention", ["zyx", "xyz"])
def test_angular_velocity_and_acceleration_against_finite_differences_of_the_rotations(convention):
    """omega = axial(R' R^T) and alpha = omega' by central differences of the path's rotations
    (h = 1e-5 s); for eq. (9)'s angles also omega = E q' with ``euler_rate_axes``."""
    path = spline(POINTS, [1.3, 0.9])
    ppoly, h = curve(path), 1e-5
    t = np.linspace(0.05, 2.15, 23)
    q, q_dot, q_ddot = ppoly(t), ppoly(t, 1), ppoly(t, 2)
    rotation, omega, alpha = angular_motion(q[:, 3:], q_dot[:, 3:], q_ddot[:, 3:], convention)

    def spin(at):
        still = np.zeros((len(at), 3))
        r_plus = angular_motion(ppoly(at + h)[:, 3:], still, still, convention)[0]
        r_minus = angular_motion(ppoly(at - h)[:, 3:], still, still, convention)[0]
        rate = (r_plus - r_minus) / (2 * h) @ np.swapaxes(angular_motion(ppoly(at)[:, 3:], still, still, convention)[0], 1, 2)
        return np.stack([rate[:, 2, 1], rate[:, 0, 2], rate[:, 1, 0]], axis=1)

    np.testing.assert_allclose(omega, spin(t), atol=1e-8)
    np.testing.assert_allclose(alpha, (spin(t + 1e-4) - spin(t - 1e-4)) / 2e-4, atol=2e-5)
    if convention == "zyx":
        np.testing.assert_allclose(rotation[3], eq9_rotation(*q[3, 3:]), atol=1e-14)
        np.testing.assert_allclose(omega, np.einsum("nij,nj->ni", np.array([euler_rate_axes(*a) for a in q[:, 3:]]),
                                                    q_dot[:, 3:]), atol=1e-12)
    else:
        np.testing.assert_allclose(rotation[3], Rotation.from_euler("XYZ", q[3, 3:]).as_matrix(), atol=1e-14)


def robot_with(pulleys: bool, seed: int = 1) -> CableRobot:
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(8, 3))
    guided = Pulleys(axes / np.linalg.norm(axes, axis=1, keepdims=True), rng.uniform(0.05, 0.15, 8)) if pulleys else None
    return CableRobot("t", np.array(SPREAD_ANCHORS, float), rng.uniform(-0.15, 0.15, (8, 3)), np.zeros(3), np.ones(3),
                      tuple("abcdefgh"), pulleys=guided)


@pytest.mark.parametrize("pulleys", [False, True])
@pytest.mark.parametrize("convention", ["zyx", "xyz"])
def test_the_cables_speeds_and_accelerations_are_the_derivatives_of_their_lengths_along_the_path(pulleys, convention):
    """Central differences (h = 1e-5 s) of every cable's length from its anchor, the arc around
    its swivelling pulley included, along a turning path: speed within 1e-8 m/s, acceleration
    within 2e-4 m/s^2 (the pulley's own term is up to 0.06 m/s^2 here)."""
    robot, path = robot_with(pulleys), spline(POINTS, [1.3, 0.9])
    ppoly, h = curve(path), 1e-5
    t = np.linspace(0.05, 2.15, 29)

    def state(at, rates=True):
        q, q_dot, q_ddot = ppoly(at), ppoly(at, 1), ppoly(at, 2)
        rotation, omega, alpha = angular_motion(q[:, 3:], q_dot[:, 3:], q_ddot[:, 3:], convention)
        return PoseGeometry(robot, q[:, :3], rotation), (q_dot[:, :3], omega, q_ddot[:, :3], alpha)

    here, motion = state(t)
    speed, accel = here.cable_rates(*motion)
    plus, minus = state(t + h)[0].cable_lengths, state(t - h)[0].cable_lengths
    np.testing.assert_allclose(speed, (plus - minus) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(accel, (plus - 2 * here.cable_lengths + minus) / h**2, atol=2e-4)


def body(seed=3, n=7):
    rng = np.random.default_rng(seed)
    masses, points = rng.uniform(0.3, 1.5, n), rng.normal(scale=0.2, size=(n, 3)) + [0.03, -0.02, 0.05]
    mass = masses.sum()
    com = masses @ points / mass
    r = points - com
    return masses, points, mass, com, sum(m * (v @ v * np.eye(3) - np.outer(v, v)) for m, v in zip(masses, r))


@pytest.mark.parametrize("convention", ["zyx", "xyz"])
def test_the_wrench_the_cables_balance_is_the_point_masses_weight_minus_their_momentums_rate(convention):
    """The platform as point masses moved along the path: sum m_k (g - p_k''), and its moment
    about the platform's reference point, with p_k'' by central differences of their positions
    (h = 1e-4 s), against ``PathStatics.full_wrench`` (rtol 1e-6 of its size)."""
    masses, points, mass, com, inertia = body()
    path = spline(POINTS, [1.3, 0.9])
    samples = path.sample(0.05)
    spec = PathSpec(load=Load(mass, G, com, np.zeros(6), inertia), samples=samples, convention=convention)
    robot = robot_with(False)
    found = spec.state_of(robot, slice(None)).full_wrench
    ppoly, h = curve(path), 1e-4
    inside = np.clip(samples.t, h, path.duration - h)  # the path's ends: one-sided, left out below

    def placed(at):
        q = ppoly(at)
        rotation = angular_motion(q[:, 3:], q[:, 3:] * 0, q[:, 3:] * 0, convention)[0]
        return q[:, None, :3] + np.einsum("nij,kj->nki", rotation, points)

    second = (placed(inside + h) - 2 * placed(inside) + placed(inside - h)) / h**2
    arms = placed(inside) - ppoly(inside)[:, None, :3]
    force = masses[None, :, None] * (np.array([0, 0, -G]) - second)
    exact = np.concatenate([force.sum(axis=1), np.cross(arms, force).sum(axis=1)], axis=1)
    keep = (samples.t > h) & (samples.t < path.duration - h) & ~np.isclose(samples.t, 1.3)  # a knot: one-sided
    scale = np.abs(exact).max()
    np.testing.assert_allclose(found[keep], exact[keep], atol=1e-6 * scale)


def test_a_path_whose_motion_asks_nothing_of_the_cables_gives_the_statics_verdicts_bit_for_bit(tmp_path):
    """A massless platform under an applied wrench moving along a path: the inertial wrench is
    zero, so every sample's margins are the statics job's at the same poses, exactly; with
    mass they are not (the motion is felt)."""
    common = [*ROBOT, "tension=feasible", "tension.t_min=5", "tension.t_max=300", "wrench.fz=-60",
              "wrench.mx=3", "robot.l_max=3.2"]
    path = ["analysis=trajectory", "trajectory.points=[[0,-0.6,0.5],[0,0.5,1.3],[0,0.9,0.4]]",
            "trajectory.times=[0.6,0.5]", "trajectory.dt=0.02"]
    moving = command(tmp_path, "pipeline", *common, *path, f"hydra.run.dir={tmp_path / 'path'}")
    assert moving.returncode == 0, moving.stderr[-2000:]
    samples = pd.read_parquet(tmp_path / "path" / "samples.parquet")
    assert samples[["x_ddot", "y_ddot", "z_ddot"]].abs().to_numpy().max() > 5  # it moves briskly
    poses = samples[["x", "y", "z"]].to_numpy().tolist()
    still = command(tmp_path, "pipeline", *common, "analysis=statics", f"poses={poses}", "output.cables=true",
                    f"hydra.run.dir={tmp_path / 'still'}")
    assert still.returncode == 0, still.stderr[-2000:]
    points = pd.read_parquet(tmp_path / "still" / "points.parquet")
    margins = [c for c in points if c.startswith("margin_")]
    assert margins and set(margins) <= set(samples.columns)
    for column in (*margins, "feasible"):
        np.testing.assert_array_equal(samples[column].to_numpy(), points[column].to_numpy())
    assert 0 < samples["feasible"].mean() < 1
    heavy = command(tmp_path, "pipeline", *common, *path, "robot.platform.mass=3",
                    "robot.platform.inertia=[0.05,0.05,0.08]", f"hydra.run.dir={tmp_path / 'heavy'}")
    assert heavy.returncode == 0, heavy.stderr[-2000:]
    felt = pd.read_parquet(tmp_path / "heavy" / "samples.parquet")
    moved = felt[["x_ddot", "y_ddot", "z_ddot"]].abs().to_numpy().max(axis=1) > 1
    forces = ["wrench_fx", "wrench_fy", "wrench_fz"]
    change = felt[forces].to_numpy() - samples[forces].to_numpy()
    np.testing.assert_allclose(change[:, :2], -3 * felt[["x_ddot", "y_ddot"]].to_numpy(), atol=1e-9)  # -m a
    assert moved.any() and (np.abs(change[moved]).max(axis=1) > 3).all()


@pytest.fixture(scope="module")
def octo(tmp_path_factory):
    """CASPR's format: the 8-cable test robot imported with its bodies file, its trajectories beside it."""
    root = tmp_path_factory.mktemp("octo")
    for name in ("Octo_cables.xml", "Octo_bodies.xml", "Octo_trajectories.xml"):
        (root / name).write_text((DATA / name).read_text())
    done = command(root, "pipeline.caspr", "Octo_cables.xml", "--bodies", "Octo_bodies.xml", "--out",
                   "mine/robot/octo.yaml")
    assert done.returncode == 0, done.stderr
    return root


def octo_job(root, *overrides, run="run"):
    return command(root, "pipeline", "--config-dir", "mine", "robot=octo", "analysis=trajectory",
                   "trajectory.file=Octo_trajectories.xml", *overrides, f"hydra.run.dir={root / run}")


def independent_quintic(q, rates, durations, t):
    """CASPR's quintic per segment, solved here: the 6 x 6 system of each end's q, q', q''."""
    starts = np.concatenate([[0.0], np.cumsum(durations)])
    segment = np.minimum(np.searchsorted(starts, t, side="right") - 1, len(durations) - 1)
    out = np.zeros((3, len(t), q.shape[1]))
    for i, T in enumerate(durations):
        rows = segment == i
        system = np.array([[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 2, 0, 0, 0],
                           [1, T, T**2, T**3, T**4, T**5], [0, 1, 2 * T, 3 * T**2, 4 * T**3, 5 * T**4],
                           [0, 0, 2, 6 * T, 12 * T**2, 20 * T**3]])
        known = np.stack([q[i], rates[0][i], rates[1][i], q[i + 1], rates[0][i + 1], rates[1][i + 1]])
        c = np.linalg.solve(system, known)  # (6 powers, coordinates)
        tau = t[rows] - starts[i]
        powers = np.stack([tau**k for k in range(6)], axis=1)
        out[0, rows] = powers @ c
        out[1, rows] = np.stack([k * tau ** max(k - 1, 0) for k in range(6)], axis=1) @ c
        out[2, rows] = np.stack([k * (k - 1) * tau ** max(k - 2, 0) for k in range(6)], axis=1) @ c
    return out


def test_a_caspr_model_with_its_trajectory_file_against_a_qp_per_sample(octo):
    """Octo (8 cables, 12.5 kg with its inertia tensor; its cables crossed, for a workspace that
    the path enters and leaves) along the file's quintic spline "tour"
    (rates at its middle point, tilted): the path is CASPR's quintic solved here; per sample the
    wrench from Newton-Euler written here (scipy's XYZ rotations, angular velocity and
    acceleration by differences of them) and the least-norm tensions of a QP (SLSQP) within
    [t_min, t_max] where an LP finds the sample feasible, against samples.parquet."""
    crossed = [[0.1, 0.08, 0.05], [-0.1, 0.08, 0.05], [-0.1, -0.08, 0.05], [0.1, -0.08, 0.05],
               [0.1, 0.08, -0.05], [-0.1, 0.08, -0.05], [-0.1, -0.08, -0.05], [0.1, -0.08, -0.05]]
    done = octo_job(octo, "trajectory.name=tour", "tension=feasible", "tension.t_min=1", f"robot.attachments={crossed}")
    assert done.returncode == 0, done.stderr[-2000:]
    samples = pd.read_parquet(octo / "run" / "samples.parquet")
    assert np.diff(samples["t"]).max() <= 0.02 + 1e-12  # the file's time_step
    q = np.array([[-0.8, -0.4, 1.2, 0.1, -0.05, 0.2], [0.6, 0.3, 1.6, -0.1, 0.1, -0.15], [1.0, -0.5, 1.0, 0.15, 0.1, 0.3]])
    rates = [np.array([np.zeros(6), [0.4, 0.2, 0.1, -0.05, 0.05, 0.1], np.zeros(6)]),
             np.array([np.zeros(6), [0.5, -0.3, 0.2, 0.1, 0.0, -0.1], np.zeros(6)])]
    rows = np.arange(3, len(samples) - 3, 4)
    t = samples["t"].to_numpy()[rows]
    value, rate, accel = independent_quintic(q, rates, [1.5, 1.2], t)
    np.testing.assert_allclose(samples[["x", "y", "z", "psi", "theta", "phi"]].to_numpy()[rows], value, atol=1e-9)
    np.testing.assert_allclose(samples[["x_dot", "y_dot", "z_dot"]].to_numpy()[rows], rate[:, :3], atol=1e-9)
    anchors = np.array([[-3, 2, 3], [3, 2, 3], [3, -2, 3], [-3, -2, 3], [-3, 2, 0], [3, 2, 0], [3, -2, 0], [-3, -2, 0]], float)
    platform = np.array(crossed)
    mass, com, inertia = 12.5, np.array([0.01, -0.02, 0.03]), np.diag([0.8, 0.9, 1.1])
    t_max = np.array([600.0] * 4 + [400.0] * 4)
    h, checked = 1e-5, 0

    def turn(at):
        return Rotation.from_euler("XYZ", independent_quintic(q, rates, [1.5, 1.2], at)[0][:, 3:]).as_matrix()

    def spin(at):
        rate_ = (turn(at + h) - turn(at - h)) / (2 * h) @ np.swapaxes(turn(at), 1, 2)
        return np.stack([rate_[:, 2, 1], rate_[:, 0, 2], rate_[:, 1, 0]], axis=1)

    omega, alpha = spin(t), (spin(t + 1e-4) - spin(t - 1e-4)) / 2e-4
    for k, row in enumerate(rows):
        rotation = turn(t[k:k + 1])[0]
        arms = platform @ rotation.T
        vectors = value[k, :3] + arms - anchors
        unit = vectors / np.linalg.norm(vectors, axis=1, keepdims=True)
        structure = np.vstack([unit.T, np.cross(arms, unit).T])
        c = rotation @ com
        a_c = accel[k, :3] + np.cross(alpha[k], c) + np.cross(omega[k], np.cross(omega[k], c))
        inertia_fixed = rotation @ inertia @ rotation.T
        force = mass * (np.array([0, 0, -G]) - a_c)
        moment = np.cross(c, force) - inertia_fixed @ alpha[k] - np.cross(omega[k], inertia_fixed @ omega[k])
        wrench = np.concatenate([force, moment])
        np.testing.assert_allclose(samples[[f"wrench_{c_}" for c_ in ("fx", "fy", "fz", "mx", "my", "mz")]].to_numpy()[row],
                                   wrench, atol=2e-4 * np.abs(wrench).max())
        bounds = list(zip(np.ones(8), t_max))
        lp = linprog(np.zeros(8), A_eq=structure, b_eq=wrench, bounds=bounds, method="highs")
        assert bool(samples["feasible"].iloc[row]) == (lp.status == 0), (row, lp.status)
        if lp.status != 0:
            continue
        scale = 100.0  # N: the QP in hundreds of newtons, well conditioned
        qp = minimize(lambda x: x @ x, lp.x / scale, jac=lambda x: 2 * x, method="SLSQP",
                      bounds=[(lo / scale, hi / scale) for lo, hi in bounds],
                      constraints=[{"type": "eq", "fun": lambda x: structure @ x - wrench / scale, "jac": lambda x: structure}],
                      options={"ftol": 1e-14, "maxiter": 500})
        assert qp.success, qp.message
        found = samples[[f"tension_cable {i}" for i in range(1, 9)]].to_numpy()[row]
        np.testing.assert_allclose(found, qp.x * scale, atol=1e-3 * t_max.max())
        checked += 1
    assert checked >= 5 and checked < len(rows)  # feasible samples compared, and some infeasible ones too


def test_a_caspr_cubic_spline_is_its_hermite_cubic_and_a_linear_one_is_refused(octo):
    done = octo_job(octo, "trajectory.name=lift", run="lift")
    assert done.returncode == 0, done.stderr[-2000:]
    samples = pd.read_parquet(octo / "lift" / "samples.parquet")
    at_knot = samples[np.isclose(samples["t"], 1.0)]
    np.testing.assert_allclose(at_knot[["x", "y", "z", "theta"]].to_numpy(), [[0.2, 0.1, 1.4, 0.1]] * len(at_knot), atol=1e-12)
    np.testing.assert_allclose(at_knot[["x_dot", "z_dot"]].to_numpy(), [[0.1, 0.5]] * len(at_knot), atol=1e-12)
    assert samples["t"].iloc[-1] == pytest.approx(2.5)  # absolute times
    refused = octo_job(octo, "trajectory.name=jerky", run="jerky")
    assert refused.returncode == 2 and "linear spline" in refused.stderr and not (octo / "jerky").exists()


def test_a_csv_of_timed_way_points_is_the_same_path_as_the_listed_points(tmp_path):
    # as a spreadsheet saves it: a byte-order mark, CRLF line ends, a blank last line
    (tmp_path / "path.csv").write_bytes("\ufefft,x,y,z\r\n0,-0.5,0.3,0.7\r\n0.8,0.4,-0.2,1.2\r\n1.5,0.6,0.5,0.9\r\n\r\n"
                                        .encode("utf-8"))
    common = [*CROSSED_ROBOT, "analysis=trajectory", "trajectory.law=spline", "robot.platform.mass=2", "tension.t_max=40"]
    by_file = command(tmp_path, "pipeline", *common, "trajectory.file=path.csv", f"hydra.run.dir={tmp_path / 'a'}")
    listed = command(tmp_path, "pipeline", *common, "trajectory.points=[[-0.5,0.3,0.7],[0.4,-0.2,1.2],[0.6,0.5,0.9]]",
                     "trajectory.times=[0.8,0.7]", f"hydra.run.dir={tmp_path / 'b'}")
    assert by_file.returncode == 0 and listed.returncode == 0, by_file.stderr[-2000:] + listed.stderr[-2000:]
    a, b = (pd.read_parquet(tmp_path / run / "samples.parquet") for run in "ab")
    pd.testing.assert_frame_equal(a, b)
    summary = pd.read_parquet(tmp_path / "a" / "summary.parquet").iloc[0]
    assert summary["n_samples"] == len(a) and summary["duration_s"] == pytest.approx(1.5)
    held = a["feasible"].to_numpy()
    assert 0 < held.sum() < len(a)  # the peaks are over the samples that hold
    speeds = np.abs(a[[c for c in a if c.startswith("speed_")]].to_numpy())
    assert summary["cable_speed_peak"] == pytest.approx(speeds[held].max())
    tensions = a[[c for c in a if c.startswith("tension_")]].to_numpy()
    assert summary["tension_peak_N"] == pytest.approx(tensions[held].max())
    assert summary["tension_peak_N"] <= 40 < tensions.max()


def test_the_first_failing_sample_is_named_with_its_criterion_and_remedy(tmp_path):
    """A path that leaves the cables' reach on its way (a tension rating exceeded while it
    accelerates hard, in 0.3 s): the summary and the log name the first failing sample, its time
    and criterion; the same path in 0.5 s holds throughout."""
    path = [*ROBOT, "analysis=trajectory", "tension=feasible", "tension.t_min=5", "tension.t_max=100",
            "robot.platform.mass=4", "trajectory.points=[[0,0,1],[0,0.6,1]]"]
    slow = command(tmp_path, "pipeline", *path, "trajectory.times=0.5", f"hydra.run.dir={tmp_path / 'slow'}")
    assert slow.returncode == 0 and "the whole path holds" in (tmp_path / "slow" / "pipeline.log").read_text()
    assert pd.read_parquet(tmp_path / "slow" / "summary.parquet").iloc[0]["first_failure_sample"] == -1
    done = command(tmp_path, "pipeline", *path, "trajectory.times=0.3", f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    samples = pd.read_parquet(tmp_path / "run" / "samples.parquet")
    summary = pd.read_parquet(tmp_path / "run" / "summary.parquet").iloc[0]
    first = int(np.flatnonzero(~samples["feasible"].to_numpy())[0])
    assert samples["feasible"].iloc[0] and first > 0  # at rest it holds; moving, it does not
    assert summary["first_failure_sample"] == first and summary["first_failure_t"] == samples["t"].iloc[first]
    assert summary["first_failure_criterion"] == samples["limiting"].iloc[first] == "tension_max"
    assert summary["first_failure_margin"] == samples["margin_tension_max"].iloc[first] < 0
    log = (tmp_path / "run" / "pipeline.log").read_text()
    assert f"the path fails first at sample {first} (t = " in log and "stronger cables" in log
    assert summary["n_points"] == len(samples) and summary["feasible_pct"] == pytest.approx(100 * samples["feasible"].mean())


BAD = [  # (overrides, what the one line names)
    ([], "trajectory.points"),
    (["trajectory.points=[[0,0,1]]", "trajectory.times=1"], "trajectory.points"),
    (["trajectory.points=[[0,0,1],[0,1]]", "trajectory.times=1"], "trajectory.points"),
    (["trajectory.points=[[0,0],[0,1]]", "trajectory.times=1"], "trajectory.points"),
    (["trajectory.points=[[0,0,1],[0,.nan,1]]", "trajectory.times=1"], "trajectory.points"),
    (["trajectory.points=[[0,0,1],[0,1e9,1]]", "trajectory.times=1"], "trajectory.points"),
    (["trajectory.points=[[0,0,1],[0,1,1]]"], "trajectory.times"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=[1,2]"], "trajectory.times"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=-1"], "trajectory.times"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=.inf"], "trajectory.times"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1e-200"], "trajectory.times: the path accelerates at inf"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=0.001"], "trajectory.times: the path accelerates at 5.7"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "trajectory.v_max=1"], "trajectory.v_max"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.law=trapezoid"], "error: trajectory.v_max: trajectory.law=trap"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.law=trapezoid", "trajectory.v_max=1", "trajectory.t_acc=1",
      "trajectory.t_dec=1", "trajectory.times=1"], "trajectory.times"),
    (["trajectory.points=[[0,0,1,0,0,0],[0,0,1,0.5,0,0]]", "trajectory.law=trapezoid", "trajectory.v_max=1",
      "trajectory.t_acc=1", "trajectory.t_dec=1"], "trajectory.points"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "trajectory.v_max=-1"], "trajectory.v_max"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "trajectory.dt=0"], "trajectory.dt"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1000", "trajectory.dt=1e-6"], "trajectory.dt"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=20000", "trajectory.dt=0.01"], "1,000,000"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1e300"], "1e+302 samples"),  # counted in floats
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "trajectory.dt=1e-300"], "trajectory.dt=1e-300"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.law=trapezoid", "trajectory.v_max=1e300", "trajectory.t_acc=1",
      "trajectory.t_dec=1"], "trajectory.t_acc=1: v_max / t_acc = 1e+300 m/s^2"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.law=trapezoid", "trajectory.v_max=1e-300",
      "trajectory.t_acc=1e300", "trajectory.t_dec=1e300"], "trajectory.t_acc=1e+300: v_max / t_acc = 0 m/s^2"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.law=trapezoid", "trajectory.v_max=5e-324",
      "trajectory.t_acc=1", "trajectory.t_dec=1"], "inf samples"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=2", "compute.max_poses=100"], "compute.max_poses=100"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "trajectory.law=straight"], "trajectory.law"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "trajectory.name=tour"], "trajectory.name"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.file=path.csv"], "trajectory.points"),
    (["trajectory.file=missing.csv"], "trajectory.file"),
    (["trajectory.file=path.txt"], "trajectory.file"),
    (["trajectory.file=header.csv"], "trajectory.file"),
    (["trajectory.file=backwards.csv"], "trajectory.file"),
    (["trajectory.file=words.csv"], "trajectory.file"),
    (["trajectory.file=empty.csv"], "trajectory.file"),
    (["trajectory.file=path.csv", "trajectory.times=1"], "trajectory.times"),
    (["trajectory.file=path.csv", "trajectory.law=trapezoid", "trajectory.v_max=1", "trajectory.t_acc=1",
      "trajectory.t_dec=1"], "trajectory.v_max"),
    (["trajectory.file=broken.xml"], "broken.xml"),
    (["trajectory.file=two.xml"], "trajectory.name"),
    (["trajectory.file=two.xml", "trajectory.name=third"], "trajectory.name"),
    (["trajectory.file=two.xml", "trajectory.name=first", "trajectory.law=spline"], "trajectory.law"),
    (["trajectory.file=two.xml", "trajectory.name=short"], "short"),
    (["trajectory.file=operational.xml"], "no joint trajectory"),
    (["trajectory.file=generic.xml"], "<trajectory>"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "platform_motion.acceleration=[[1,0,0,0,0,0]]"],
     "platform_motion"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "orientation.total.n=3",
      "orientation.total.bound=0.1"], "orientation.total"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "poses=[[0,0,1]]"], "poses"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "workspace.home=[0,0,1]"], "workspace.home"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "output.mesh=true"], "output.mesh"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "output.metrics=true"], "output.metrics"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "compute.kernel=fused"], "compute.kernel"),
    (["trajectory.points=[[0,0,1],[0,1,1]]", "trajectory.times=1", "robot.cable_mass=0.05", "robot.catenary=0.05",
      "tension=feasible"], "robot.catenary"),
]


@pytest.mark.parametrize("overrides, key", BAD, ids=[" ".join(o) or "nothing" for o, _ in BAD])
def test_what_a_path_cannot_mean_is_refused_in_one_line_with_nothing_written(tmp_path, overrides, key):
    (tmp_path / "path.csv").write_text("t,x,y,z\n0,0,0,1\n1,0,1,1\n")
    (tmp_path / "path.txt").write_text("t,x,y,z\n0,0,0,1\n1,0,1,1\n")
    (tmp_path / "header.csv").write_text("time,x,y,z\n0,0,0,1\n1,0,1,1\n")
    (tmp_path / "backwards.csv").write_text("t,x,y,z\n0,0,0,1\n1,0,1,1\n1,0,0.5,1\n")
    (tmp_path / "words.csv").write_text("t,x,y,z\n0,0,0,1\n1,zero,1,1\n")
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "broken.xml").write_text("<trajectories><quintic_spline_trajectory")
    (tmp_path / "two.xml").write_text(
        "<trajectories><joint_trajectories>"
        "<quintic_spline_trajectory id='first'><points><point><q>0 0 1 0 0 0</q></point>"
        "<point time='1'><q>0 1 1 0 0 0</q></point></points></quintic_spline_trajectory>"
        "<quintic_spline_trajectory id='short'><points><point><q>0 0 1 0 0 0</q></point></points>"
        "</quintic_spline_trajectory></joint_trajectories></trajectories>")
    points = "<points><point><q>0 0 1 0 0 0</q></point><point time='1'><q>0 1 1 0 0 0</q></point></points>"
    (tmp_path / "operational.xml").write_text(  # CASPR's operational space: not the joint's coordinates
        f"<trajectories><operational_trajectories><quintic_spline_trajectory id='o'>{points}"
        "</quintic_spline_trajectory></operational_trajectories></trajectories>")
    (tmp_path / "generic.xml").write_text(f"<joint_trajectories><trajectory id='t'>{points}</trajectory></joint_trajectories>")
    done = command(tmp_path, "pipeline", *ROBOT, "analysis=trajectory", *overrides,
                   f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and key in lines[0], lines
    assert not (tmp_path / "run").exists()


def test_a_robot_on_a_joint_follows_a_path_of_orientations(tmp_path):
    """A spherical robot (the joint holds the reference point): way-points are angles; the
    platform's own weight off the joint and its inertia give the wrench; positions stay 0."""
    anchors = [[0.5, 0.5, 0.6], [-0.5, 0.5, 0.6], [-0.5, -0.5, 0.6], [0.5, -0.5, 0.6], [0, 0, -0.8]]
    attachments = [[0.1, 0.1, 0.2], [-0.1, 0.1, 0.2], [-0.1, -0.1, 0.2], [0.1, -0.1, 0.2], [0, 0, -0.1]]
    done = command(tmp_path, "pipeline", "robot=points", f"robot.anchors={anchors}", f"robot.attachments={attachments}",
                   "robot.dofs=[rx,ry,rz]", "analysis=trajectory", "tension=feasible", "robot.platform.mass=1",
                   "robot.platform.com=[0,0,0.1]", "robot.platform.inertia=[0.01,0.01,0.02]",
                   "trajectory.points=[[0,0,0],[0.3,-0.2,0.5]]", "trajectory.times=0.8",
                   f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    samples = pd.read_parquet(tmp_path / "run" / "samples.parquet")
    assert (samples[["x", "y", "z", "x_ddot"]].to_numpy() == 0).all()
    assert samples["phi"].iloc[-1] == pytest.approx(0.5) and samples["omega_z"].abs().max() > 0.5
    bad = command(tmp_path, "pipeline", "robot=points", f"robot.anchors={anchors}", f"robot.attachments={attachments}",
                  "robot.dofs=[rx,ry,rz]", "analysis=trajectory", "trajectory.points=[[0,0,0,0,0,0],[0,0,0,0.3,0,0]]",
                  "trajectory.times=0.8", f"hydra.run.dir={tmp_path / 'bad'}")
    assert bad.returncode == 2 and "[psi, theta, phi]" in bad.stderr


def test_pulleys_elastic_and_heavy_cables_are_checked_along_the_path(tmp_path):
    """The statics' other criteria hold at every sample: a pulley robot's wrapped lengths and
    speeds, stiffness and the heavy cables' rules, each with a margin column."""
    done = command(tmp_path, "pipeline", *ROBOT, "analysis=trajectory", "tension=feasible", "tension.t_min=5",
                   "robot.platform.mass=2", "robot.pulleys={axis: [0, 0, 1], radius: 0.05}",
                   "robot.cable_mass=0.02", "+criteria.cable_frequency={hz: 1}",
                   "trajectory.points=[[-0.5,0,0.8],[0.5,0.2,1.1]]", "trajectory.times=1",
                   f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    samples = pd.read_parquet(tmp_path / "run" / "samples.parquet")
    assert {"wrap_1", "margin_cable_frequency", "speed_1", "accel_1"} <= set(samples.columns)
    lengths = samples["length_1"].to_numpy()
    inside = (samples["segment"] == 1).to_numpy()
    gradient = np.gradient(lengths[inside], samples["t"].to_numpy()[inside])
    np.testing.assert_allclose(gradient[2:-2], samples["speed_1"].to_numpy()[inside][2:-2], atol=2e-3)
    stiff = command(tmp_path, "pipeline", *ROBOT, "analysis=trajectory", "tension=feasible", "tension.t_min=5",
                    "robot.cable_ea=2e5", "+criteria.stiffness={translational: 2000, rotational: 10, frequency: 0}",
                    "trajectory.points=[[-0.5,0,0.8],[0.5,0.2,1.1]]", "trajectory.times=1",
                    f"hydra.run.dir={tmp_path / 'stiff'}")
    assert stiff.returncode == 0, stiff.stderr[-2000:]
    assert pd.read_parquet(tmp_path / "stiff" / "samples.parquet")["margin_stiffness"].notna().all()


def test_the_statics_spec_fields_all_reach_the_path_spec():
    """PathSpec is the statics' spec with the samples: no field of StaticsSpec is lost on the way."""
    assert {f.name for f in dataclasses.fields(StaticsSpec)} < {f.name for f in dataclasses.fields(PathSpec)}


def test_the_help_page_lists_a_paths_keys_before_any_way_point_is_given(tmp_path):
    done = command(tmp_path, "pipeline", "--help", "analysis=trajectory", "robot=points")
    assert done.returncode == 0, done.stderr[-2000:]
    assert "trajectory.points = null" in done.stdout and "trajectory.law = quintic" in done.stdout
    assert "actuator = null" in done.stdout

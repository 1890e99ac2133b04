"""The inertial force of eq. (31) from Newton's law, in every path that computes tensions.

The oracle is the law, not the code's reading: a translating rigid body of mass m with its
centre of mass at R com from the platform's reference point, pulled by each cable along the
unit vector from its platform point towards its anchor, satisfies

    sum_i t_i (a_i - p_i) / |a_i - p_i| + m g_vec = m a                    (forces)
    sum_i (R b_i) x t_i (a_i - p_i) / |a_i - p_i| + (R com) x (m g_vec - m a) = 0   (moments)

with g_vec = (0, 0, -9.81), z up (the CPR-8's frame). The cable directions are written here from
the anchors and attachment points; only the tensions come from the package. A reversed inertial
force (m (a - g e_z) taken as the cables' wrench, the mix the default had before) fails every test
of this module, and the separation test shows by how much.
"""

from dataclasses import replace

import numpy as np
import pytest

from conftest import shaft_torque
from pipeline.app.problem import build_problem
from pipeline.model.dynamics import PoseDynamics
from pipeline.model.geometry import rotation_matrix
from pipeline.model.dynamics import SampleDynamics
from pipeline.workspace.trajectory import inverse_dynamics

G_VEC = np.array([0.0, 0.0, -9.81])
OFF_CENTRE_LOAD = ("load.mass=1.5", "load.com=[0.05,-0.03,0.02]")  # 3.5 kg with the carrier, com off the reference point
TILTED = ("orientation.psi=0.3", "orientation.theta=-0.2", "orientation.phi=0.4")


def pull_directions(robot, position, orientation):
    """(m, 3) unit vectors from each platform point towards its anchor, and the arms R b_i."""
    arms = robot.attachments @ rotation_matrix(*orientation).T
    towards = robot.anchors - (position + arms)
    return towards / np.linalg.norm(towards, axis=1, keepdims=True), arms


def newton_residual(robot, mass, com, position, orientation, tensions, acceleration):
    """The force and moment equations above, left side minus right side (N, N m)."""
    pulls, arms = pull_directions(robot, position, orientation)
    forces = tensions[:, None] * pulls
    arm = rotation_matrix(*orientation) @ com
    force = forces.sum(axis=0) + mass * G_VEC - mass * acceleration
    moment = np.cross(arms, forces).sum(axis=0) + np.cross(arm, mass * G_VEC - mass * acceleration)
    return force, moment


def grid_tensions(problem, position, accelerations):
    """The minimum-norm tensions t = M / R of eq. (20) that the grid criteria check, one row per
    acceleration."""
    spec = replace(problem.spec, accelerations=np.asarray(accelerations, dtype=float))
    state = PoseDynamics(problem.robot, np.array([position]), problem.orientation, spec)
    return shaft_torque(state)[0].T / spec.winch_radius


@pytest.mark.parametrize("a_z,pull", [(0.714, 21.048), (-0.714, 18.192)])
def test_a_level_carrier_hoisted_at_constant_acceleration_is_pulled_with_m_times_g_plus_a(make_cfg, catalogue, a_z, pull):
    """Issue 51's smallest case: CPR-8, actuator 1, level carrier (2 kg) at (1.6, 1.1, -1.1)
    accelerating up (down) at 0.714 m/s^2: the cables' vertical pull is m (g + a) = 21.05 N
    (m (g - 0.714) = 18.19 N), written by hand; the reversed force gave 18.19 N going up."""
    problem, _ = build_problem(make_cfg("actuator=1"), catalogue)
    position, orientation = np.array([1.6, 1.1, -1.1]), (0.0, 0.0, 0.0)
    tensions = grid_tensions(problem, position, [[0.0, 0.0, a_z]])[0]
    pulls, _ = pull_directions(problem.robot, position, orientation)
    assert (tensions >= 0).all()
    assert (tensions * pulls[:, 2]).sum() == pytest.approx(pull, abs=5e-3)
    assert (tensions * pulls[:, 2]).sum() == pytest.approx(2.0 * (9.81 + a_z), rel=1e-9)


@pytest.mark.parametrize("columns", ["full", "translational"])
def test_tilted_off_centre_load_under_an_asymmetric_acceleration_obeys_newton(make_cfg, catalogue, columns):
    """A tilted carrier (J of rank 6) carrying an off-centre load at off-centre positions, for the
    corners of an asymmetric acceleration box (t_dec = 0.91 s): the grid's tensions satisfy both
    equations of the module docstring (forces only: the force equation)."""
    problem, _ = build_problem(make_cfg("actuator=2", f"model.pinv_columns={columns}", "motion.t_dec=0.91",
                                        *OFF_CENTRE_LOAD, *TILTED), catalogue)
    mass = problem.spec.load.mass
    assert mass == pytest.approx(3.5) and (np.ptp(problem.spec.accelerations, axis=0) > 0).all()
    assert not np.allclose(problem.spec.accelerations.max(axis=0), -problem.spec.accelerations.min(axis=0))
    for position in np.random.default_rng(3).uniform([0.5, 0.4, -1.8], [2.7, 1.8, -0.4], (6, 3)):
        for a, tensions in zip(problem.spec.accelerations, grid_tensions(problem, position, problem.spec.accelerations)):
            force, moment = newton_residual(problem.robot, mass, problem.spec.load.com, position,
                                            problem.orientation, tensions, a)
            np.testing.assert_allclose(force, 0.0, atol=1e-9 * mass * 9.81)
            if columns == "full":
                np.testing.assert_allclose(moment, 0.0, atol=1e-9 * mass * 9.81)


@pytest.mark.parametrize("tension", ["tension.model=pinv", "tension.model=feasible"])
@pytest.mark.parametrize("a_z", [1.2, -0.7])
def test_the_lines_inverse_dynamics_obey_newton_while_hoisting_and_lowering(make_cfg, catalogue, tension, a_z):
    """The line simulations' tensions (minimum norm, or the LP's distribution) on a tilted carrier
    with an off-centre load, moving up and down with an acceleration that also has a sideways part."""
    problem, _ = build_problem(make_cfg("actuator=1", "analysis=lines", tension, *OFF_CENTRE_LOAD, *TILTED), catalogue)
    positions = np.array([[1.1, 0.9, z] for z in np.linspace(-1.5, -0.6, 5)])
    velocities = np.tile([0.1, 0.0, 0.4 * np.sign(a_z)], (len(positions), 1))
    accelerations = np.tile([0.3, -0.2, a_z], (len(positions), 1))
    out = inverse_dynamics(SampleDynamics(problem.robot, positions, problem.orientation, problem.spec,
                                          velocities, accelerations), problem.limits)
    mass = problem.spec.load.mass
    for position, a, torque in zip(positions, accelerations, out["torque"]):
        force, moment = newton_residual(problem.robot, mass, problem.spec.load.com, position, problem.orientation,
                                        torque / problem.spec.winch_radius, a)
        np.testing.assert_allclose(np.concatenate([force, moment]), 0.0, atol=1e-6 * mass * 9.81)


def test_the_reversed_inertial_force_is_far_outside_these_tolerances(make_cfg, catalogue):
    """The tests above separate the two signs: tensions balancing m (a - g e_z) instead of the
    law's wrench leave a force residual of 2 m |a| (here 2 x 3.5 kg x |a|), some 1e9 times the
    tolerance."""
    problem, _ = build_problem(make_cfg("actuator=2", "motion.t_dec=0.91", *OFF_CENTRE_LOAD, *TILTED), catalogue)
    position, mass = np.array([1.3, 0.8, -1.0]), problem.spec.load.mass
    for a in problem.spec.accelerations:
        right = grid_tensions(problem, position, [a])[0]
        reversed_ = grid_tensions(problem, position, [-a])[0]  # the wrench of +m a instead of -m a
        assert np.abs(newton_residual(problem.robot, mass, problem.spec.load.com, position, problem.orientation,
                                      right, a)[0]).max() < 1e-8
        force = newton_residual(problem.robot, mass, problem.spec.load.com, position, problem.orientation, reversed_, a)[0]
        np.testing.assert_allclose(force, -2 * mass * a, atol=1e-8)


def test_every_rigid_body_of_point_masses_has_an_inertia_the_check_accepts_and_no_other():
    """The inertia of a body of point masses about its centre of mass, sum m (|r|^2 I - r r^T),
    is accepted for random bodies (a rod, a flat plate at the triangle's equality, clouds);
    moments past the triangle inequality by more than its 1 % tolerance, or negative, are not,
    except a planar platform's Izz alone."""
    from pipeline.model.dynamics import inertia_fault, inertia_tensor

    rng = np.random.default_rng(7)

    def body(points, masses):
        r = points - np.average(points, axis=0, weights=masses)
        return np.einsum("k,kij->ij", masses, np.einsum("ki,ki->k", r, r)[:, None, None] * np.eye(3)
                         - np.einsum("ki,kj->kij", r, r))

    rod = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    plate = rng.normal(size=(50, 3)) * [1.0, 2.0, 0.0]
    for points in (rod, plate, *(rng.normal(size=(n, 3)) * rng.uniform(0.01, 5, 3) for n in (3, 4, 10, 200))):
        masses = rng.uniform(0.1, 3.0, len(points))
        turned = body(points, masses)
        assert inertia_fault(turned) is None, np.linalg.eigvalsh(turned)
    flat = body(plate, np.ones(len(plate)))
    assert abs(np.trace(flat) - 2 * flat[2, 2]) < 1e-9 * flat[2, 2]  # a plate: Izz = Ixx + Iyy exactly
    assert "the largest more than the sum" in inertia_fault(inertia_tensor(1.0, 1.0, 2.03))
    assert "the largest more than the sum" in inertia_fault(inertia_tensor(0.0, 0.2, 0.05, xy=0.0, yz=0.01))
    assert inertia_fault(inertia_tensor(1.0, 1.0, 2.0 * 1.0099)) is None  # within the printed values' rounding
    assert inertia_fault(inertia_tensor(0.0, 0.0, 0.05)) is None  # a planar platform's Izz alone
    assert "negative principal moment" in inertia_fault(inertia_tensor(1.0, 1.0, 1.0, xy=1.5))
    assert inertia_fault(inertia_tensor(1.0, np.inf, 1.0)) == "must be finite"

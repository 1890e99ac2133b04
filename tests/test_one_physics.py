"""One physics for every robot and analysis: one structure matrix, gravity from the robot, the
load's weight and centre-of-mass moment in the statics (issue 15)."""

import numpy as np
import pytest

from pipeline.model.geometry import euler_rate_axes, rotation_matrix, rotation_partials
from pipeline.app.problem import build_problem
from conftest import compute_workspace
from pipeline.workspace.kernel import evaluate_chunk


@pytest.mark.parametrize("angles", [(0.0, 0.0, 0.0), (0.5, 0.5, 0.5), (-0.3, 1.2, 2.0)])
def test_euler_rate_axes_generate_the_rotation_partials(angles):
    """dR/dq = [e_q]x R for each Euler angle q of eq. (9)."""
    axes, r = euler_rate_axes(*angles), rotation_matrix(*angles)
    for q, partial in enumerate(rotation_partials(*angles)):
        e = axes[:, q]
        skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
        np.testing.assert_allclose(skew @ r, partial, atol=1e-14)


def test_cpr8_jacobian_is_the_structure_matrix_through_euler_rates_and_winches(make_cfg, catalogue):
    """J^T = blockdiag(I, E^T) A diag(1 / R_i) (docs/model.md, conventions)."""
    problem, grid = build_problem(make_cfg("orientation.psi=0.4", "orientation.phi=-0.7",
                                           "model.pinv_columns=full"), catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientation)
    blocks = np.eye(6)
    blocks[3:, 3:] = euler_rate_axes(*problem.orientation).T
    expected = np.einsum("ij,njm->nim", blocks, state.structure_matrix) / problem.spec.winch_radius
    np.testing.assert_allclose(state.structure, expected, atol=1e-13)


def test_irpm_under_cpr_wwa_hangs_its_load_with_pulling_cables(make_cfg, catalogue):
    """The IRPM's Z axis points down: gravity comes from its robot.up, so at the centre of its
    box the minimum-norm torques holding 20 kg at rest all pull. Before gravity was robot data,
    cpr_wwa took z as up for every robot and these torques all pushed."""
    problem, _ = build_problem(make_cfg("robot=irpm6", "analysis=cpr_wwa", "load.mass=20"), catalogue)
    state = problem.spec.state(problem.robot, np.array([[0.0, 0.0, 5.0]]), problem.orientation)
    _, at_rest = state.torque_affine
    assert (at_rest > 0).all()
    assert problem.robot.up == pytest.approx([0, 0, -1])


@pytest.mark.parametrize("phi", [0.0, 0.4])  # (pi / 2 is the 3-3 arrangement's singularity)
def test_statics_balance_the_weight_and_its_moment_about_the_reference_point(make_cfg, catalogue, phi):
    """An off-centre centre of mass: w = [m g (-up); (R com) x m g (-up)] plus the applied wrench,
    and the minimum-norm tensions balance it (IRPM, Z down, 1000 kg at 0.3 m along the platform
    x axis, rotated with the platform)."""
    mass, g = 1000.0, 9.81
    problem, _ = build_problem(make_cfg("robot=irpm6", f"load.mass={mass}", "load.com=[0.3,0,0]",
                                        "wrench.fx=500", f"orientation.phi={phi}"), catalogue)
    state = problem.spec.state(problem.robot, np.array([[0.5, -0.2, 6.0]]), problem.orientation)
    weight = np.array([0.0, 0.0, mass * g])
    arm = rotation_matrix(0.0, 0.0, phi) @ np.array([0.3, 0.0, 0.0])
    expected = np.concatenate([weight, np.cross(arm, weight)]) + [500, 0, 100_000, 0, 0, 0]
    np.testing.assert_allclose(state.wrench, expected, atol=1e-9)
    balanced = np.einsum("nkm,nm->nk", state.structure_matrix, state.tensions)[0]
    np.testing.assert_allclose(balanced, expected, rtol=1e-9, atol=1e-6)


def test_per_cable_tension_limits_equal_to_a_scalar_give_the_same_workspace(make_cfg, catalogue):
    scalar = compute_workspace(make_cfg("robot=irpm6"), catalogue)[1]["n_feasible"]
    listed = compute_workspace(make_cfg("robot=irpm6", "tension.t_max=[55000,55000,55000,55000,55000,55000]"),
                               catalogue)[1]["n_feasible"]
    assert scalar == listed == 2862


@pytest.mark.parametrize("model", ["pinv", "feasible"])
def test_one_weak_cable_only_removes_poses_and_is_what_limits_them(make_cfg, catalogue, model):
    """Cable C6D6 rated 1 kN instead of 55 kN: every pose feasible with it is feasible without
    it, and the square IRPM gives the same verdicts under both tension models (36 poses)."""
    strong, _ = compute_workspace(make_cfg("robot=irpm6"), catalogue)
    weak, summary = compute_workspace(make_cfg("robot=irpm6", f"tension.model={model}",
                                               "tension.t_max=[55000,55000,55000,55000,55000,1000]"), catalogue)
    assert summary["n_feasible"] == 36
    assert not (weak["feasible"] & ~strong["feasible"]).any()
    assert (weak.loc[strong["feasible"] & ~weak["feasible"], "limiting"] == "tension_max").all()


def test_wirex_structure_matrix_is_ours_with_the_opposite_sign(make_cfg, catalogue):
    """docs/model.md's conventions table: WireX builds A^T column by column with u_i from the
    platform point to the anchor and solves A^T f + w = 0; ours is A t = w with u_i from the
    anchor. Written here from WireX's description, pose by pose, on a tilted IRPM."""
    problem, grid = build_problem(make_cfg("robot=irpm6", "robot.gamma_deg=30",
                                           "orientation.theta=0.2"), catalogue)
    positions = grid[:][::97]
    state = problem.spec.state(problem.robot, positions, problem.orientation)
    rotation = rotation_matrix(*problem.orientation)
    for n, r in enumerate(positions):
        columns = []
        for a, b in zip(problem.robot.anchors, problem.robot.attachments):
            p = rotation @ b
            u = (a - r - p) / np.linalg.norm(a - r - p)
            columns.append(np.concatenate([u, np.cross(p, u)]))
        np.testing.assert_allclose(np.stack(columns, axis=1), -state.structure_matrix[n], atol=1e-14)


@pytest.mark.parametrize("robot", [[], ["analysis=statics", "tension.t_max=1000"],
                                   ["robot=irpm6", "robot.search.step=2", "wrench.fz=0", "tension.t_max=2000"]])
def test_the_payload_adds_to_the_robot_s_own_platform_mass_at_its_centre_of_mass(make_cfg, catalogue, robot):
    """The platform's mass and centre of mass belong to the robot (``robot.platform``), the
    payload is the load (``load.mass`` at ``load.com``, platform frame): a 1 kg payload 0.1 m off
    centre on the CPR-8's 2 kg carrier is a 3 kg platform with its centre of mass at the
    mass-weighted point, and the wrench on a tilted platform is that weight and its moment
    about the reference point (worked out here from the rotation, not from the model)."""
    combined = make_cfg(*robot, "robot.platform.mass=2", "robot.platform.com=[0,0.05,0]",
                        "load.mass=1", "load.com=[0.1,0,-0.03]", "orientation.psi=0.2", "orientation.theta=-0.3")
    single = make_cfg(*robot, "robot.platform.mass=3", f"robot.platform.com=[{0.1 / 3!r},{0.1 / 3!r},-0.01]",
                      "orientation.psi=0.2", "orientation.theta=-0.3")
    (problem, grid), (reference, _) = build_problem(combined, catalogue), build_problem(single, catalogue)
    assert problem.spec.load.mass == 3.0
    assert problem.spec.load.com == pytest.approx(reference.spec.load.com, abs=1e-15)
    state = problem.spec.state(problem.robot, grid[:][:5], problem.orientation)
    psi, theta = 0.2, -0.3  # eq. (9): R = Rz(phi) Ry(theta) Rx(psi), phi = 0
    rx = np.array([[1, 0, 0], [0, np.cos(psi), -np.sin(psi)], [0, np.sin(psi), np.cos(psi)]])
    ry = np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])
    weight = -3.0 * 9.81 * problem.robot.up
    arm = ry @ rx @ np.array([0.1 / 3, 0.1 / 3, -0.01])
    if problem.spec.kind == "statics":
        assert state.wrench == pytest.approx(np.concatenate([weight, np.cross(arm, weight)]), abs=1e-9)
    for key in ("margin_" + name for name in problem.criteria):
        np.testing.assert_allclose(evaluate_chunk(problem, grid[:])[key],
                                   evaluate_chunk(reference, grid[:])[key], rtol=0, atol=1e-12, err_msg=key)

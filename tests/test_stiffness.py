"""The platform's stiffness with elastic cables and the criterion on it (issue 54 item 2).

Oracles: the wrench the cables balance, A(x) t(x) with t = t0 + k (l(x) - l(x0)), differenced
numerically over a small translation and a small rotation about fixed axes (its Jacobian is K
by definition), written here from the anchors and attachment points alone; the closed form of a
point held by six orthogonal cables; and the job's own columns and verdicts against that
numerical K at the tensions the job writes."""

import numpy as np
import pytest
from scipy.linalg import eigh
from scipy.spatial.transform import Rotation

from pipeline.model.stiffness import least_stiffness, stiffness_matrices
from conftest import command, compute_workspace


def cable_wrench(anchors, attachments, position, rotation, tensions0, rates, lengths0):
    """A t at a pose: columns [u; (R b) x u], tensions stretched by the change of length."""
    arms = attachments @ rotation.T
    vectors = position + arms - anchors
    lengths = np.linalg.norm(vectors, axis=1)
    unit = vectors / lengths[:, None]
    tensions = tensions0 + rates * (lengths - lengths0)
    return np.concatenate([unit, np.cross(arms, unit)], axis=1).T @ tensions


def numerical_stiffness(anchors, attachments, position, rotation, tensions, rates, h=1e-6):
    """K by central differences: dp along each axis, then a rotation h about each fixed axis."""
    lengths0 = np.linalg.norm(position + attachments @ rotation.T - anchors, axis=1)
    columns = []
    for j in range(6):
        sides = []
        for sign in (1.0, -1.0):
            step = np.zeros(6)
            step[j] = sign * h
            turned = Rotation.from_rotvec(step[3:]).as_matrix() @ rotation
            sides.append(cable_wrench(anchors, attachments, position + step[:3], turned, tensions, rates, lengths0))
        columns.append((sides[0] - sides[1]) / (2 * h))
    return np.column_stack(columns)


def random_robot(rng):
    """Eight cables between random anchors and attachment points, a random pose (tilted), random
    tensions and rates, and our K of it."""
    anchors = rng.uniform(-3, 3, (8, 3))
    attachments = rng.uniform(-0.3, 0.3, (8, 3))
    position, rotation = rng.uniform(-0.5, 0.5, 3), Rotation.from_rotvec(rng.uniform(-0.5, 0.5, 3)).as_matrix()
    tensions, rates = rng.uniform(10, 500, 8), rng.uniform(1e3, 1e5, 8)
    arms = attachments @ rotation.T
    vectors = position + arms - anchors
    lengths = np.linalg.norm(vectors, axis=1)
    ours = stiffness_matrices((vectors / lengths[:, None])[None], arms[None], lengths[None], tensions[None],
                              rates[None])[0]
    return anchors, attachments, position, rotation, tensions, rates, ours


def test_the_stiffness_matrix_is_the_derivative_of_the_cables_wrench():
    rng = np.random.default_rng(2)
    for _ in range(20):
        anchors, attachments, position, rotation, tensions, rates, ours = random_robot(rng)
        numeric = numerical_stiffness(anchors, attachments, position, rotation, tensions, rates)
        np.testing.assert_allclose(ours, numeric, atol=1e-5 * np.abs(numeric).max())
        assert np.abs(ours - ours.T).max() > 1e-3  # the tension term turns the moments: not symmetric


def test_a_point_held_by_six_orthogonal_cables_has_the_closed_form():
    """Cables along +-x, +-y, +-z, each of length l, tension t, rate k: K = (2 k + 4 t / l) I."""
    length, tension, rate = 2.0, 300.0, 5e4
    unit = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)[None]
    matrix = stiffness_matrices(unit, np.zeros_like(unit), np.full((1, 6), length), np.full((1, 6), tension),
                                np.full((1, 6), rate))
    np.testing.assert_allclose(matrix[0, :3, :3], (2 * rate + 4 * tension / length) * np.eye(3), rtol=1e-14)
    translational, rotational, _ = least_stiffness(matrix, (0, 1, 2))
    assert translational[0] == pytest.approx(2 * rate + 4 * tension / length) and np.isnan(rotational[0])


@pytest.mark.parametrize("tension", ["pinv", "feasible"])
def test_the_jobs_stiffness_columns_and_verdicts_are_the_numerical_ones(make_cfg, catalogue, tension):
    """The IRPM with 10^5 N cables and 2 m of cable to each winch, a 20 kg platform with its centre
    off the reference point and its inertia: at the tensions the job writes, the numerical K's
    least eigenvalues are its columns, its lowest natural frequency the generalized eigenproblem
    with the mass matrix of the kinetic energy (M = J' diag(m, m, m, I_c) J, J the centre's
    velocity map; scipy's eigh), and the verdicts follow them."""
    required = {"translational": 8000.0, "rotational": 1500.0, "frequency": 2.0}
    com, inertia = np.array([0.05, -0.02, 0.1]), np.array([[0.8, 0.05, 0.0], [0.05, 0.9, 0.02], [0.0, 0.02, 1.2]])
    cfg = make_cfg("robot=irpm6", "robot.search.step=1.5", f"tension={tension}", "robot.cable_ea=1e5",
                   "robot.winch_length=2", "output.cables=true", "robot.platform.mass=20",
                   "robot.platform.com=[0.05,-0.02,0.1]", "robot.platform.inertia=[0.8,0.9,1.2,0.05,0.0,0.02]",
                   "+criteria.stiffness={translational: 8000, rotational: 1500, frequency: 2}")
    points, summary = compute_workspace(cfg, catalogue)
    from pipeline.app.problem import build_problem

    problem, grid = build_problem(cfg, catalogue)
    robot = problem.robot
    names = robot.cable_names
    tensions = points[[f"tension_{n}" for n in names]].to_numpy()
    checked = 0
    for row, position in enumerate(grid[:]):
        if not np.isfinite(tensions[row]).all():  # no tensions written where the feasible model finds none
            continue
        lengths = np.linalg.norm(position + robot.attachments - robot.anchors, axis=1)
        numeric = numerical_stiffness(robot.anchors, robot.attachments, position, np.eye(3), tensions[row],
                                      (1e5 + tensions[row]) / (lengths + 2.0))  # dt/dL = EA / L0
        least = [np.linalg.eigvalsh((b + b.T) / 2)[0] for b in (numeric[:3, :3], numeric[3:, 3:])]
        velocity = np.block([[np.eye(3), -np.cross(np.eye(3), com)], [np.zeros((3, 3)), np.eye(3)]])  # v_c = v + w x c
        body = np.block([[20 * np.eye(3), np.zeros((3, 3))], [np.zeros((3, 3)), inertia]])
        lowest = eigh((numeric + numeric.T) / 2, velocity.T @ body @ velocity, eigvals_only=True)[0]
        least.append(np.sqrt(max(lowest, 0.0)) / (2 * np.pi))
        scale = np.abs(numeric).max()
        assert points["stiffness_translational_N_per_m"].iloc[row] == pytest.approx(least[0], abs=1e-5 * scale)
        direction = np.linalg.eigh((numeric[:3, :3] + numeric[:3, :3].T) / 2)[1][:, 0]
        written = points[["stiffness_weakest_x", "stiffness_weakest_y", "stiffness_weakest_z"]].to_numpy()[row]
        assert abs(abs(direction @ written) - 1) < 1e-4 and abs(written).max() == written.max()  # same axis, sign fixed
        assert points["stiffness_rotational_Nm_per_rad"].iloc[row] == pytest.approx(least[1], abs=1e-5 * scale)
        ours = (2 * np.pi * points["stiffness_frequency_Hz"].iloc[row]) ** 2  # omega^2: the eigenvalue itself
        assert ours == pytest.approx(max(lowest, 0.0), rel=1e-5, abs=1e-5 * scale)
        margin = min(1.0, least[0] / required["translational"] - 1, least[1] / required["rotational"] - 1,
                     least[2] / required["frequency"] - 1)
        assert points["margin_stiffness"].iloc[row] == pytest.approx(margin, abs=1e-4)
        checked += 1
    assert checked > 100
    stiff = points["margin_stiffness"] >= 0
    assert 0 < stiff.mean() < 1 and (points.loc[points["feasible"], "margin_stiffness"] >= 0).all()
    assert summary["kernel"] == "numpy"


REQUIRED = "+criteria.stiffness={translational: 1000, rotational: 10, frequency: 0}"


@pytest.mark.parametrize("overrides, message", [
    (["robot.cable_ea=0"], "robot.cable_ea=0: must be > 0 (N)"),
    (["robot.cable_ea=inf"], "robot.cable_ea=inf: must be finite"),
    (["robot.cable_ea=1e5", "robot.winch_length=nan"], "robot.winch_length=nan: must be finite"),
    (["robot.cable_ea=1e12"], "robot.cable_ea=1000000000000.0: must be at most 1e+09 N"),
    (["robot.cable_ea=[1e5, 1e5]"], "robot.cable_ea=[100000.0, 100000.0]: 2 values for 8 cables"),
    (["robot.cable_ea=1e5", "robot.winch_length=-1"], "robot.winch_length=-1: must be >= 0 (m)"),
    (["analysis=statics", "robot.cable_ea=1e5", "robot.pulleys={axis: [0, 0, 1], radius: 0.05}",
      REQUIRED], "criteria.stiffness: analysis=statics does not check it"),
    ([REQUIRED], "criteria.stiffness: analysis=cpr_wwa does not check it"),
    (["analysis=statics", "+criteria.stiffness={translational: 1000, rotational: 10, frequency: 0}"],
     "criteria.stiffness: analysis=statics does not check it"),
    (["analysis=statics", "robot.cable_ea=1e5", "+criteria.stiffness={translational: -5, rotational: 10, frequency: 0}"],
     "criteria.stiffness.translational=-5: must be >= 0"),
    (["robot=irpm6", "robot.cable_ea=1e5", "+criteria.stiffness={translational: 0, rotational: 0, frequency: 5}"],
     "criteria.stiffness: frequency needs a moving mass"),
    (["analysis=statics", "robot.cable_ea=1e5", "robot.platform.mass=3",
      "+criteria.stiffness={translational: 0, rotational: 0, frequency: 5}"], "frequency needs the platform's inertia"),
    (["analysis=statics", "robot.platform.mass=3", "robot.platform.inertia=[1, 1, -1]"],
     "robot.platform.inertia=[1, 1, -1]: has a negative principal moment"),
    (["analysis=statics", "robot.platform.mass=3", "robot.platform.inertia=[1e300, 1, 1]"],  # no rigid body's
     "robot.platform.inertia=[1e+300, 1, 1]: has principal moments 1, 1, 1e+300 kg m^2, the largest more than"),
    (["analysis=statics", "robot.cable_ea=1e5", "robot.platform.mass=3", "robot.platform.inertia=[0, 0, 0.05]",
      "+criteria.stiffness={translational: 0, rotational: 0, frequency: 5}"], "gives no inertia about a freedom"),
    (["robot=irpm6", "robot.platform.inertia=[1, 1, 1]"], "a platform with an inertia needs its mass"),
    (["analysis=statics", "robot.platform.mass=3", "robot.platform.inertia=5"], "robot.platform.inertia=5: [Ixx, Iyy, Izz]"),
])
def test_elastic_cables_it_cannot_mean_are_refused_in_one_line(tmp_path, overrides, message):
    run = tmp_path / "run"
    size = ["robot.search.step=2"] if "robot=irpm6" in overrides else ["grid.n=3"]
    done = command(tmp_path, "pipeline", *size, *overrides, f"hydra.run.dir={run}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], lines
    assert not run.exists()


def test_a_collapsed_cable_or_missing_tensions_give_no_stiffness_not_an_error():
    unit = np.array([[[1.0, 0, 0], [0, 1, 0], [0, 0, 1]], [[1.0, 0, 0], [0, 1, 0], [0, 0, 1]]])
    lengths = np.array([[1.0, 1.0, 1.0], [0.0, 1.0, 1.0]])
    tensions = np.array([[10.0, np.nan, 10.0], [10.0, 10.0, 10.0]])
    matrix = stiffness_matrices(unit, np.zeros_like(unit), lengths, tensions, np.full((2, 3), 1e3))
    translational, _, _ = least_stiffness(matrix, (0, 1, 2))
    assert np.isnan(translational).all()


def test_a_cables_rate_and_unstrained_length_follow_its_spring_law():
    """t = EA (L - L0) / L0: the unstrained length recovered from (L, t), and dt/dL by central
    differences at fixed L0."""
    from pipeline.model.stiffness import axial_rates, unstrained_lengths

    ea, unstrained = np.array([2e4, 1e5, 5e5]), np.array([[1.5, 3.0, 7.0]])
    stretched = unstrained * np.array([[1.01, 1.002, 1.0004]])

    def tension(length):
        return ea * (length - unstrained) / unstrained

    np.testing.assert_allclose(unstrained_lengths(ea, stretched, tension(stretched)), unstrained, rtol=1e-14)
    h = 1e-7
    slope = (tension(stretched + h) - tension(stretched - h)) / (2 * h)
    np.testing.assert_allclose(axial_rates(ea, stretched, tension(stretched)), slope, rtol=1e-6)


def test_the_job_writes_the_unstrained_length_each_winch_pays_out(make_cfg, catalogue):
    points, _ = compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1.5", "robot.cable_ea=1e5",
                                           "robot.winch_length=2", "output.cables=true"), catalogue)
    for name in ("C1D1", "C4D4"):
        stretched = points[f"length_{name}"] + 2.0
        law = stretched / (1 + points[f"tension_{name}"] / 1e5)
        np.testing.assert_allclose(points[f"unstrained_{name}"], law, rtol=1e-14)
        assert (points[f"unstrained_{name}"] < stretched)[points[f"tension_{name}"] > 1].all()  # 1 N: 1e-5 of EA


def test_a_point_mass_between_six_orthogonal_cables_rings_at_the_closed_form():
    """f = sqrt((2 k + 4 t / l) / m) / (2 pi) along every axis."""
    from pipeline.model.stiffness import lowest_frequency, spatial_inertia

    length, tension, rate, mass = 2.0, 300.0, 5e4, 7.0
    unit = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)[None]
    matrix = stiffness_matrices(unit, np.zeros_like(unit), np.full((1, 6), length), np.full((1, 6), tension),
                                np.full((1, 6), rate))
    found = lowest_frequency(matrix, spatial_inertia(mass, np.zeros(3), np.zeros((3, 3))), (0, 1, 2))
    assert found[0] == pytest.approx(np.sqrt((2 * rate + 4 * tension / length) / mass) / (2 * np.pi), rel=1e-13)


def wirelib_stiffness(anchors, attachments, position, rotation, forces, rates):
    """WireLib's CStiffness::StiffnessMatrixMain, ported here from its steps: K_c = AT Linv AT'
    (Verhoeven's eq. 3.29, AT's columns [u; b x u] with u towards the base) and K_g(i, j) -=
    dAT(j, i) f for each cable, dAT by the quotient rule on l = base - r - R b under a unit
    translation or a unit angular velocity."""
    structure, geometric = np.zeros((6, len(anchors))), np.zeros((6, 6))
    for i, (base, point) in enumerate(zip(anchors, attachments)):
        arm = rotation @ point
        cable = base - position - arm
        length = np.linalg.norm(cable)
        unit = cable / length
        structure[:, i] = np.r_[unit, np.cross(arm, unit)]
        derivative = np.zeros((6, 6))
        for j in range(6):
            twist = np.zeros(6)
            twist[j] = 1.0
            moved = -twist[:3] if j < 3 else -np.cross(twist[3:], arm)
            rate = cable @ moved / length
            turned = (moved * length - cable * rate) / length ** 2
            derivative[:3, j] = turned
            derivative[3:, j] = np.cross(arm, turned) + (np.cross(np.cross(twist[3:], arm), unit) if j >= 3 else 0.0)
        geometric -= derivative.T * forces[i]
    return structure @ np.diag(rates) @ structure.T, geometric


def test_the_stiffness_matrix_is_wirelibs_with_its_geometric_term_transposed():
    """WireLib (WireX) writes K_g with the derivative's transpose: ours is K_c + K_g', and both
    have the same symmetric part, which the criterion reads."""
    rng = np.random.default_rng(4)
    for _ in range(10):
        anchors, attachments, position, rotation, tensions, rates, ours = random_robot(rng)
        elastic, geometric = wirelib_stiffness(anchors, attachments, position, rotation, tensions, rates)
        np.testing.assert_allclose(ours, elastic + geometric.T, atol=1e-9 * np.abs(ours).max())
        total = elastic + geometric
        np.testing.assert_allclose((ours + ours.T) / 2, (total + total.T) / 2, atol=1e-9 * np.abs(ours).max())

"""The ``feasible`` tension model (issue 8): analytic cases, agreement with the papers' own
criterion where it must agree, independent checks of the LPs, and the comparison study."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import nnls

from pipeline.model.actuators import ActuatorModel
from pipeline.workspace.criteria import margins as evaluate
from pipeline.workspace.criteria import force_families
from conftest import command, shaft_torque, compute_workspace
from pipeline.model.dynamics import Load, MotionSpec, load_wrenches
from pipeline.analyses.figures import caption
from pipeline.model.geometry import CableRobot
from pipeline.workspace.kernel import WorkspaceProblem, evaluate_chunk
from pipeline.workspace.verdict import classify
from pipeline.model.tensions import TensionSpec, feasible_tensions
from pipeline.app.problem import build_problem

FORCES = "model.pinv_columns=translational"  # forces only: the paper's reading of eq. (20) for Table 2

MASS, GRAVITY, HALF, RADIUS = 2.0, 9.81, 1.0, 0.05
ACTUATOR = ActuatorModel(id=0, name="test", power=1.0, G_v=0.0, L_v=0.0, S_v=2.0, R_r=1.0, C_E=0.0,
                         speed_limit=10.0, torque_limit=1.0, accel_limit=100.0,
                         voltage_limit=12.0, winch_radius=RADIUS)
FEASIBLE_CPR_WWA = ("unreachable", "slack", "speed", "torque", "acceleration", "voltage")


def square_robot() -> CableRobot:
    """Four cables from the corners (+-HALF, +-HALF, 0) to one point (a point mass), z up."""
    corners = np.array([[HALF, HALF, 0.0], [-HALF, HALF, 0.0], [-HALF, -HALF, 0.0], [HALF, -HALF, 0.0]])
    return CableRobot("square4", corners, np.zeros((4, 3)), np.full(3, -3.0), np.full(3, 3.0),
                      tuple("abcd"))


def hanging_motion(t_min=0.0) -> MotionSpec:
    still = np.zeros((1, 3))
    return MotionSpec(velocities=still, accelerations=still, load=Load(MASS, GRAVITY),
                      winch_radius=np.full(4, RADIUS), tension=TensionSpec("feasible", t_min))


def test_symmetric_four_cable_point_mass_gets_the_analytic_tensions():
    depth = 2.0
    motion = hanging_motion()
    state = motion.state(square_robot(), np.array([[0.0, 0.0, -depth]]), (0.0, 0.0, 0.0))
    length = np.sqrt(2 * HALF**2 + depth**2)
    tension = MASS * GRAVITY * length / (4 * depth)  # each cable carries a quarter of the weight
    margins, _, chosen, _ = feasible_tensions(state.structure, *state.wrench_pinv, state.required_wrenches,
                                              force_families(state, ACTUATOR), distribution=True)
    assert chosen[0, 0] / RADIUS == pytest.approx(np.full(4, tension), rel=1e-7)
    torque = RADIUS * tension
    assert margins["slack"][0] == pytest.approx(torque / ACTUATOR.torque_limit, rel=1e-7)
    found = evaluate(["torque", "voltage", "unreachable"], state, ACTUATOR)
    assert found["torque"][0] == pytest.approx(1 - torque / ACTUATOR.torque_limit)
    assert found["voltage"][0] == pytest.approx(1 - ACTUATOR.S_v * torque / ACTUATOR.voltage_limit)
    assert found["unreachable"][0] == pytest.approx(1.0)


def test_minimum_tension_raises_every_cable_and_is_reported_as_slack_when_out_of_reach():
    state = hanging_motion(t_min=10.0).state(square_robot(), np.array([[0.0, 0.0, -2.0]]), (0, 0, 0))
    # a quarter of the weight along each cable is 6.02 N < 10 N, and the null space of four
    # cables to a point cannot raise all four at once: the floor cannot be met
    assert evaluate(["slack"], state, ACTUATOR)["slack"][0] < 0


def verdicts(problem, positions):
    raw = evaluate_chunk(problem, positions)
    _, feasible, codes = classify({name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)
    return feasible, np.asarray(problem.criteria)[codes]


def test_a_pose_that_needs_a_pushing_cable_is_slack_never_feasible():
    robot = square_robot()
    positions = np.array([[0.0, 0.0, 1.0], [0.3, -0.2, 0.5], [0.0, 0.0, -2.0]])  # above, above, below
    problem = WorkspaceProblem(robot, np.zeros((1, 3)), hanging_motion(), ACTUATOR, FEASIBLE_CPR_WWA)
    feasible, limiting = verdicts(problem, positions)
    assert feasible.tolist() == [False, False, True]
    assert limiting[:2].tolist() == ["slack", "slack"]
    # the paper's model accepts the first two: its torques are small, only their sign is wrong
    pinv = replace(hanging_motion(), tension=TensionSpec("pinv"))
    paper = WorkspaceProblem(robot, np.zeros((1, 3)), pinv, ACTUATOR, FEASIBLE_CPR_WWA[2:])
    assert verdicts(paper, positions)[0].tolist() == [True, True, True]
    state = pinv.state(robot, positions[:1], (0, 0, 0))
    assert (shaft_torque(state) < 0).all()


def test_irpm_feasible_model_is_the_papers_criterion(make_cfg, catalogue):
    """Six cables, square structure matrix: x = A^-1 f is the only candidate, so the LP model
    and s = A^-1 f with 0 <= s <= s_max (eq. 10) agree pose by pose."""
    for gamma in (0, 30):
        paper, _ = compute_workspace(make_cfg("robot=irpm6", f"robot.gamma_deg={gamma}"), catalogue)
        ours, _ = compute_workspace(
            make_cfg("robot=irpm6", f"robot.gamma_deg={gamma}", "tension.model=feasible"), catalogue)
        assert ours["feasible"].sum() == paper["feasible"].sum() > 0
        assert (ours["feasible"] == paper["feasible"]).all()
        regular = paper["margin_singular"] >= 0
        assert (ours.loc[~regular, "limiting"] == "unreachable").all()
        for name in ("slack", "tension_max"):
            expected = np.minimum(paper.loc[regular, f"margin_{name}"], 1.0)
            assert ours.loc[regular, f"margin_{name}"].to_numpy() == pytest.approx(expected, abs=1e-9)


def test_cpr8_lp_never_loses_a_pose_whose_minimum_norm_torques_are_valid(make_cfg, catalogue):
    """Where the paper's torques pull (M >= 0 at every acceleration) and keep every limit, they
    are one candidate of the LP: the pose stays feasible and its margins can only grow."""
    for orientation in (0.0, 0.5):
        angles = [f"orientation.{a}={orientation}" for a in ("psi", "theta", "phi")]
        for actuator in (1, 5):
            cfg = [f"actuator={actuator}", *angles, FORCES]
            problem, grid = build_problem(make_cfg(*cfg), catalogue)
            state = problem.spec.state(problem.robot, grid[:], problem.orientations[0])
            pulling = (shaft_torque(state) >= 0).all(axis=(1, 2))
            paper, _ = compute_workspace(make_cfg(*cfg), catalogue)
            ours, _ = compute_workspace(make_cfg(*cfg, "tension.model=feasible"), catalogue)
            valid = pulling & paper["feasible"].to_numpy()
            assert valid.sum() > 20, (orientation, actuator)
            assert ours.loc[valid, "feasible"].all()
            for name in ("torque", "voltage"):
                assert (ours.loc[valid, f"margin_{name}"] >= paper.loc[valid, f"margin_{name}"] - 1e-9).all()
            # both models see the same motion: speed and shaft acceleration are identical
            for name in ("speed", "acceleration"):
                assert ours[f"margin_{name}"].to_numpy() == pytest.approx(paper[f"margin_{name}"])


@pytest.mark.parametrize("columns,orientation", [("translational", 0.0), ("full", 0.5)])
def test_slack_agrees_with_an_independent_nonnegative_least_squares(columns, orientation, make_cfg, catalogue):
    """Slack margin < 0 exactly where scipy's NNLS finds no x >= 0 with J^T x = F."""
    angles = [f"orientation.{a}={orientation}" for a in ("psi", "theta", "phi")]
    problem, grid = build_problem(make_cfg(f"model.pinv_columns={columns}", "tension.model=feasible",
                                           *angles), catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientations[0])
    margins, *_ = feasible_tensions(state.structure, *state.wrench_pinv, state.required_wrenches,
                                   force_families(state, problem.limits))
    wrenches = state.required_wrenches
    residual = np.array([max(nnls(s, w)[1] / np.linalg.norm(w) for w in wrenches) for s in state.structure])
    clear = np.abs(margins["slack"]) > 1e-6
    assert clear.mean() > 0.95
    assert ((margins["slack"] < 0) == (residual > 1e-9))[clear].all()
    assert (margins["slack"] < 0).any()


def test_the_box_vertices_decide_every_acceleration_inside_it(make_cfg, catalogue):
    """The capacity margin is concave in the wrench: at random accelerations inside the box it
    is never below its minimum over the eight vertices (tested for slack, the first family)."""
    problem, grid = build_problem(make_cfg("tension.model=feasible", FORCES), catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientations[0])
    slack = force_families(state, problem.limits)[:1]
    vertices, *_ = feasible_tensions(state.structure, *state.wrench_pinv, state.required_wrenches, slack)
    rng = np.random.default_rng(0)
    box = state.wrench_accelerations
    inside = box.min(axis=0) + rng.random((12, 3)) * (box.max(axis=0) - box.min(axis=0))
    wrenches = load_wrenches(problem.spec, inside, problem.robot.up, problem.orientation)[:, :3]
    interior, *_ = feasible_tensions(state.structure, *state.wrench_pinv, wrenches, slack)
    assert (interior["slack"] >= vertices["slack"] - 1e-9).all()


def test_zero_orientation_with_moment_rows_is_unreachable_as_the_rank_5_jacobian_says(make_cfg, catalogue):
    points, summary = compute_workspace(
        make_cfg("tension.model=feasible", "model.pinv_columns=full"), catalogue)
    assert summary["lost_unreachable"] == 216
    assert (points["limiting"] == "unreachable").all()
    assert points["wrench_residual"].min() > 1e-3  # a relative residual, far above 1e-6
    forces, _ = compute_workspace(make_cfg("tension.model=feasible", FORCES), catalogue)
    assert forces["wrench_residual"].max() < 1e-12


def test_lines_use_the_lp_torques_and_keep_the_points_the_grids_box_loses(make_cfg, catalogue):
    """Pulling cables, forces only, actuator 1: the grid loses the outer ring of the lower layers
    (72 points) to the corners of its acceleration box (all three axes at once, either way); on
    the lines a point moves along one axis, and near an end only accelerates away from it
    (starting, or braking when coming in): every point holds, and each line's torques pull."""
    from pipeline.workspace.lines import simulate_lines

    cfg = make_cfg("analysis=lines", "tension.model=feasible", FORCES)
    samples, points, summary = simulate_lines(cfg, *build_problem(cfg, catalogue))
    assert summary["n_feasible_grid"] == 144 and summary["lost_grid_slack"] == 72
    assert summary["n_feasible"] == 216 and summary["agreement_pct"] == pytest.approx(100 * 144 / 216)
    ok = samples[samples["margin_slack"] >= 0]
    torques = ok[[f"torque_{i}" for i in range(1, 9)]].to_numpy()
    assert torques.min() >= -1e-7  # every chosen torque pulls wherever pulling is possible
    assert ok["wrench_residual"].max() < 1e-8
    assert ok["power_cables"].to_numpy() == pytest.approx(ok["power_load"].to_numpy(), abs=1e-7)


@pytest.mark.slow
def test_comparison_study_reports_the_surviving_share_per_actuator_and_orientation(tmp_path):
    proc = command(tmp_path, "pipeline.study", "tension_comparison")
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "outputs" / "studies" / "tension_comparison"
    table = pd.read_parquet(out / "survival.parquet").set_index(["wrench_rows", "case", "actuator"])
    expected = {  # (case, actuator): (paper, physical, survive, gained), docs/model.md section 4
        ("zero", 1): (216, 144, 144, 0), ("zero", 2): (208, 136, 136, 0),
        ("zero", 3): (184, 112, 112, 0), ("zero", 4): (184, 112, 112, 0),
        ("zero", 5): (24, 32, 24, 8), ("rot05", 1): (207, 161, 157, 4),
        ("rot05", 2): (193, 153, 144, 9), ("rot05", 3): (183, 135, 134, 1),
        ("rot05", 4): (183, 134, 134, 0), ("rot05", 5): (24, 32, 24, 8),
    }
    forces = table.loc["translational"]
    for key, counts in expected.items():
        assert tuple(forces.loc[key, ["n_paper", "n_physical", "n_survive", "n_gained"]]) == counts, key
    assert forces.loc[("zero", 1), "survive_pct"] == pytest.approx(66.67, abs=0.01)
    moments = table.loc["full"]
    assert (moments["n_physical"] == 0).all()
    assert moments.loc["zero", "n_paper"].tolist() == [216, 208, 184, 184, 0]
    assert moments.loc["rot05", "n_paper"].tolist() == [182, 120, 30, 9, 0]
    assert (moments.loc["zero", "lost_unreachable"] == moments.loc["zero", "n_paper"]).all()
    assert (moments.loc["rot05", "lost_slack"] == moments.loc["rot05", "n_paper"]).all()
    losses = table[[c for c in table if c.startswith("lost_")]].sum(axis=1)
    assert (losses == table["n_paper"] - table["n_survive"]).all()
    figures = sorted(p.name for p in (out / "figures").iterdir())
    assert figures == sorted(["survival_by_actuator.png"] + [
        f"tension_{case}_actuator{a}.{kind}" for case in ("zero", "rot05") for a in range(1, 6)
        for kind in ("png", "json")])  # each cloud with its interactive view
    assert caption(out / "figures" / "tension_rot05_actuator2.png") == (
        "Actuator 2, ψ = θ = φ = 0.5 rad, forces only: the feasible points with the paper's "
        "minimum-norm torques (left) and with pulling cables (right).")
    assert set(table["case_label"]) == {"zero orientation", "ψ = θ = φ = 0.5 rad"}


def test_forces_only_loses_the_outer_ring_of_the_lower_layers_to_slack(make_cfg, catalogue):
    points, summary = compute_workspace(make_cfg("tension.model=feasible", FORCES), catalogue)
    lost = points[~points["feasible"]]
    assert summary["lost_slack"] == len(lost) == 72
    xs, ys = np.unique(points["x"]), np.unique(points["y"])
    ring = lost["x"].isin(xs[[0, -1]]) | lost["y"].isin(ys[[0, -1]])
    assert ring.all()
    assert lost.groupby(lost["z"].round(3)).size().tolist() == [20, 20, 20, 12]  # lowest first
    assert lost["margin_slack"].min() == pytest.approx(-0.0025, abs=1e-4)  # just short
    assert lost["margin_slack"].max() == pytest.approx(-0.0007, abs=1e-4)


@pytest.mark.parametrize("orientation,hanging", [(0.0, 68), (0.5, 0)])
def test_with_moment_balance_few_or_no_poses_can_even_hang_still(orientation, hanging, make_cfg, catalogue):
    """NNLS, independent of the LPs: poses where the carrier can hang at rest (F = -m g e_z, no
    moment) with pulling cables, at zero orientation and at 0.5 rad about every axis."""
    angles = [f"orientation.{a}={orientation}" for a in ("psi", "theta", "phi")]
    problem, grid = build_problem(make_cfg("model.pinv_columns=full", *angles), catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientations[0])
    weight = load_wrenches(problem.spec, np.zeros((1, 3)), problem.robot.up, problem.orientation)[0]
    residual = np.array([nnls(s, weight)[1] for s in state.structure]) / np.linalg.norm(weight)
    assert (residual < 1e-9).sum() == hanging


def test_verdicts_do_not_depend_on_how_poses_are_chunked_or_batched(make_cfg, catalogue, monkeypatch):
    import pipeline.model.tensions

    whole, _ = compute_workspace(make_cfg("tension.model=feasible", "actuator=3", FORCES), catalogue)
    monkeypatch.setattr(pipeline.model.tensions, "LP_BLOCKS", 40)
    split, _ = compute_workspace(make_cfg("tension.model=feasible", "actuator=3", FORCES,
                                          "compute.chunk_size=37"), catalogue)
    assert (whole["feasible"] == split["feasible"]).all() and whole["feasible"].any()
    for name in ("slack", "torque", "voltage"):
        assert split[f"margin_{name}"].to_numpy() == pytest.approx(whole[f"margin_{name}"], abs=1e-7)


@pytest.mark.parametrize("a_z", [1.0, -1.0])
def test_accelerating_up_or_down_needs_m_times_g_plus_a(a_z):
    """Four symmetric cables accelerate the point mass vertically at a_z: Newton's law needs
    m (g + a_z) of vertical pull, shared by the four cables (l / depth of it each, over 4)."""
    depth = 2.0
    motion = replace(hanging_motion(), accelerations=np.array([[0.0, 0.0, a_z]]))
    state = motion.state(square_robot(), np.array([[0.0, 0.0, -depth]]), (0.0, 0.0, 0.0))
    length = np.sqrt(2 * HALF**2 + depth**2)
    expected = MASS * (GRAVITY + a_z) * length / (4 * depth)
    assert shaft_torque(state)[0, :, 0] / RADIUS == pytest.approx(np.full(4, expected))


@pytest.mark.parametrize("model", ["pinv", "feasible"])
def test_an_external_force_adds_to_the_weight(model):
    """load.external: a constant downward pull of m g on the hanging point mass doubles every
    tension, under both tension models, in the grid criteria and in F of eq. (31)."""
    robot, at = square_robot(), np.array([[0.0, 0.0, -2.0]])
    plain = replace(hanging_motion(), tension=TensionSpec(model))
    pulled = replace(plain, load=replace(plain.load, external=np.array([0, 0, -MASS * GRAVITY, 0, 0, 0])))
    heavy = replace(plain, load=replace(plain.load, mass=2 * MASS))
    rest, up = np.zeros((1, 3)), robot.up
    assert load_wrenches(pulled, rest, up, (0, 0, 0)) == pytest.approx(load_wrenches(heavy, rest, up, (0, 0, 0)))
    for name in ("torque", "voltage"):
        got, heavier, alone = (evaluate([name], motion.state(robot, at, (0, 0, 0)), ACTUATOR)[name]
                               for motion in (pulled, heavy, plain))
        assert got == pytest.approx(heavier)
        assert got < alone


def test_statics_code_path_finds_the_same_68_hanging_poses(make_cfg, catalogue):
    """analysis=statics on CPR-8 (geometric structure matrix A of eq. 8, not J): the carrier's
    weight alone, pulling cables, moment balance: the same 68 poses as NNLS on J^T above."""
    _, summary = compute_workspace(make_cfg("analysis=statics", "tension.model=feasible",
                                            "tension.t_max=1000"), catalogue)
    assert summary["n_feasible"] == 68 and summary["lost_slack"] == 148

"""The 6-cable IRPM of Hamed & Zohoor through the generic model: statics invariants, the paper's
conclusions where the model supports them, and the documented disagreements (docs/evidence.md)."""

import numpy as np
import pytest

from pipeline.errors import ConfigError
from pipeline.app.problem import validate
from pipeline.workspace.kernel import evaluate_chunk
from pipeline.app.problem import build_problem
from conftest import compute_workspace
from golden import values


@pytest.fixture(scope="module")
def irpm(make_cfg, catalogue):
    def run(*overrides):
        return compute_workspace(make_cfg("robot=irpm6", *overrides), catalogue)
    return run


def volume(irpm, *overrides):
    return irpm(*overrides)[1]["volume_m3"]


SECTION_3 = "tension.t_max=null"  # the paper's definition of its section III workspace: no s_max


def section3(irpm, *overrides):
    """The statically reachable combined workspace's volume (section III, the abstract): every
    cable in tension and no longer than l_max; s_max belongs to section IV (docs/evidence.md)."""
    return volume(irpm, SECTION_3, *overrides)


def test_paper_search_box_is_31_by_31_by_26_points_of_0_4_m(irpm):
    points, summary = irpm()
    assert summary["n_points"] == 31 * 31 * 26
    assert summary["volume_m3"] == pytest.approx(summary["n_feasible"] * 0.4**3)
    assert not points.isna().any().any()


def test_tensions_balance_the_wrench_at_every_regular_pose(make_cfg, catalogue):
    problem, grid = build_problem(make_cfg("robot=irpm6", "robot.gamma_deg=30",
                                           "orientation.psi=0.2", "wrench.mx=20000"), catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientation)
    regular = ~state.singular
    assert state.wrench == pytest.approx([0, 0, 100_000, 20_000, 0, 0])  # massless platform, f_ext
    residual = np.einsum("nkm,nm->nk", state.structure_matrix, state.tensions) - state.wrench
    assert regular.sum() > 20000
    assert np.abs(residual[regular]).max() < 1e-6 * np.abs(state.wrench).max()
    exact = np.linalg.solve(state.structure_matrix[regular][:50], state.wrench)
    np.testing.assert_allclose(state.tensions[regular][:50], exact, rtol=1e-8, atol=1e-6)


def test_cables_towards_the_centre_make_the_tensions_independent_of_r_end(make_cfg, catalogue):
    """model.cable_direction=centre: u_i does not depend on r_end and the moment rows of A scale
    with it, so with no applied moment the tensions and the gram ratio are the same for every
    r_end (docs/evidence.md section 2); towards the attachment points they are not."""
    states = {}
    for direction in ("centre", "attachment"):
        for r_end in (1.2, 6.0):
            problem, grid = build_problem(make_cfg("robot=irpm6", f"robot.r_end={r_end}", "robot.gamma_deg=15",
                                                   f"model.cable_direction={direction}",
                                                   "wrench.fx=30000"), catalogue)
            states[direction, r_end] = problem.spec.state(problem.robot, grid[:][1000:3000],
                                                          problem.orientation)
    small, large = states["centre", 1.2], states["centre", 6.0]
    np.testing.assert_allclose(small.tensions, large.tensions, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(small.gram_ratio, large.gram_ratio, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(large.structure_matrix[:, 3:] / 6.0, small.structure_matrix[:, 3:] / 1.2,
                               atol=1e-12)
    assert np.abs(states["attachment", 1.2].tensions - states["attachment", 6.0].tensions).max() > 1e3


def test_base_plane_layer_is_reported_singular_never_nan(irpm):
    points, summary = irpm()
    top = points["z"] == 0.0
    assert (points.loc[top, "limiting"] == "singular").all() and not points.loc[top, "feasible"].any()
    assert summary["lost_singular"] == 31 * 31
    assert np.isfinite(points.filter(like="margin_").to_numpy()).all()


def test_workspace_is_mirror_symmetric_about_the_xz_plane(irpm):
    points, _ = irpm("robot.gamma_deg=15")
    grid = points.set_index(["x", "y", "z"])["feasible"]
    mirrored = points.assign(y=-points["y"]).set_index(["x", "y", "z"])["feasible"]
    assert grid.sum() > 1000
    assert (grid.sort_index().to_numpy() == mirrored.sort_index().to_numpy()).all()


def test_volume_grows_with_the_tension_limit(irpm):
    volumes = [volume(irpm, f"tension.t_max={s}") for s in (40e3, 55e3, 80e3)]
    assert volumes[0] < volumes[1] < volumes[2]


def test_volume_decreases_as_gamma_grows(irpm):
    """Sections III.A-C: "reduction in angle gamma results in the increase of workspace"."""
    for r_end in (1.2, 2.4, 3.6, 4.8, 6.0):
        volumes = [section3(irpm, f"robot.r_end={r_end}", f"robot.gamma_deg={g}") for g in (0, 15, 30, 45)]
        assert volumes == sorted(volumes, reverse=True) and volumes[0] > 4 * volumes[3], r_end
    for r_base in (2, 3, 4, 5, 6, 7, 8):  # Fig. 14
        volumes = [section3(irpm, f"robot.r_base={r_base}", f"robot.gamma_deg={g}") for g in (0, 15, 30, 45)]
        assert volumes == sorted(volumes, reverse=True), r_base
    at_default = values("irpm_section3_gamma", "volume_m3")  # gamma = 0, 15, 30, 45 (the golden file's)
    assert at_default == sorted(at_default, reverse=True) and at_default[0] > 9 * at_default[3]


def test_volume_grows_with_the_base_radius_conclusion_2(irpm):
    """At r_base = 4 and 8 m, 50 poses on y = 0 have one cable at exactly zero tension: inside
    eq. (10)'s 0 <= s, so counted (``pipeline.workspace.verdict``) on every CPU."""
    volumes = values("irpm_section3_base_radius", "volume_m3")  # r_base = 2, 4, 6, 8 m
    assert all(b > 1.5 * a for a, b in zip(volumes, volumes[1:]))
    assert section3(irpm, "robot.r_end=1.2", "robot.r_base=4") == volumes[1]  # the zero-tension poses counted


def test_no_maximum_at_base_ratio_1_conclusion_3():
    volumes = values("irpm_section3_small_platform", "volume_m3")  # r_base = 0.6, 1.2, 3, 6 m at r_end = 0.6 m
    assert all(b > 2 * a for a, b in zip(volumes, volumes[1:]))


@pytest.mark.parametrize("direction", ["attachment", "centre"])
def test_end_ratio_independence_conclusions_1_and_4_hold_exactly_under_the_papers_definition(irpm, direction):
    """Conclusions 1, 4: at zero rotation and zero moments the volume does not depend on
    r_end / r_base. Under section III's definition (no s_max) it does not, under both readings
    of the cable directions, and the same points are feasible (docs/evidence.md section 2 proves it):
    3675, 2500, 1375, 375 points = 147, 100, 55, 15 per layer on all 25 layers below the base."""
    for gamma, count in ((0, 3675), (15, 2500), (30, 1375), (45, 375)):
        tables = [irpm(SECTION_3, f"model.cable_direction={direction}", f"robot.gamma_deg={gamma}",
                       f"robot.r_end={r}")[0] for r in (1.2, 3.6, 6.0)]
        for table in tables:
            assert table["feasible"].sum() == count
            assert (table["feasible"].to_numpy() == tables[0]["feasible"].to_numpy()).all()
        per_layer = tables[0].groupby("z")["feasible"].sum()
        assert per_layer.iloc[0] == 0 and (per_layer.iloc[1:] == count // 25).all()


def test_the_section_iv_rating_makes_the_volume_depend_on_r_end(irpm):
    """With s_max = 55 kN (section IV's wrench analyses, and the robot file's rating) the
    tensions' size matters, and it depends on r_end: 8.1 % apart at gamma = 0 (175.0 to
    189.1 m^3), 21 % apart at gamma = 30 (64.8 to 78.3 m^3), within 20 % under lateral forces."""
    at_0 = values("irpm_rating_end_radius", "volume_m3")  # r_end = 1.2, 2.4, 3.6, 4.8, 6 m
    at_30 = values("irpm_rating_end_radius_gamma_30", "volume_m3")
    assert 1.05 < max(at_0) / min(at_0) < 1.09 and 1.2 < max(at_30) / min(at_30) < 1.21
    lateral = [volume(irpm, "wrench.fx=50000", f"robot.r_end={r}") for r in (3.6, 4.8, 6.0)]
    assert max(lateral) / min(lateral) < 1.2


def test_the_section_iii_prism_is_the_linear_programs_answer(irpm, make_cfg, catalogue):
    """docs/evidence.md section 2: under a vertical force through O_M, a pose at zero rotation is
    statically reachable exactly when its horizontal position is sum_i lambda_i C_i for weights
    lambda >= 0 summing to 1 with sum_i lambda_i d_i = 0 and sum_i lambda_i (C_i x d_i)_z = 0
    (d_i the platform directions): a polygon of the base's geometry, the same at every depth and
    every r_end. An LP (scipy's HiGHS) per pose of one layer, gamma = 15 deg, against the model."""
    from scipy.optimize import linprog

    problem, _ = build_problem(make_cfg("robot=irpm6", SECTION_3, "robot.gamma_deg=15"), catalogue)
    base, platform = problem.robot.anchors[:, :2], problem.robot.attachments[:, :2]
    directions = platform / np.linalg.norm(platform, axis=1)[:, None]
    moment = base[:, 0] * directions[:, 1] - base[:, 1] * directions[:, 0]
    equalities = np.vstack([directions.T, moment, base.T, np.ones(6)])
    for r_end in (1.2, 6.0):
        points = irpm(SECTION_3, "robot.gamma_deg=15", f"robot.r_end={r_end}")[0]
        layer = points[np.isclose(points["z"], 4.0)]
        reachable = [linprog(np.zeros(6), A_eq=equalities, b_eq=[0, 0, 0, x, y, 1], bounds=(0, None),
                             method="highs").status == 0 for x, y in layer[["x", "y"]].to_numpy()]
        assert layer["feasible"].tolist() == reachable
        assert 50 < sum(reachable) < len(layer) - 50


def test_under_moments_larger_platform_is_not_larger_workspace_section_iv_d(irpm):
    """Section IV.D says a larger r_end / r_base enlarges the workspace under moments; at
    M_x = M_y = 0, M_z = 100 kN m, forces 100 kN, gamma = 0 the model says the opposite."""
    at_36, at_6 = values("irpm_moments_end_radius", "volume_m3")  # r_end = 3.6 and 6 m under that load
    assert 0 < at_6 < 0.7 * at_36


def test_fig15_at_ratio_2_gamma_0_and_15_tie():
    """The one place of Figs. 13-15 where a smaller gamma does not give a strictly larger
    workspace (besides the 25-point plateau at ratios <= 1): r_base / r_end = 2."""
    at = values("irpm_section3_ratio_2", "volume_m3")  # gamma = 0, 15, 30, 45
    assert at[0] == at[1] > at[2] > at[3] > 0


def test_moment_arm_reading_about_the_base_makes_r_end_dominant(irpm):
    """Eq. (9) read literally (moments about O_F) is far from conclusion 1."""
    small, large = values("irpm_section3_moment_arm_base", "volume_m3")  # r_end = 0.6 and 6 m
    assert large > 100 * small and large == values("irpm_section3_small_platform", "volume_m3")[3]  # r_end = 0.6 m, about O_M


def test_total_orientation_workspace_is_a_subset(irpm):
    constant, _ = irpm("robot.gamma_deg=15")
    total, summary = irpm("robot.gamma_deg=15", "orientation.total.bound=0.1", "orientation.total.n=3")
    assert summary["n_orientations"] == 27
    assert (total["feasible"] <= constant["feasible"]).all()
    assert 0 < total["feasible"].sum() < constant["feasible"].sum()


def test_short_cables_make_everything_infeasible(irpm):
    points, summary = irpm("robot.l_max=0.5")
    assert summary["n_feasible"] == 0 and summary["lost_length"] > 0
    assert not points.isna().any().any()


@pytest.mark.parametrize("override, message", [
    ("robot.r_end=0", "robot.r_end=0"),
    ("tension.t_max=-55000", "tension.t_max=-55000"),
    ("robot.gamma_deg=130", "robot.gamma_deg=130"),
    ("robot.search.step=0", "robot.search.step=0"),
    ("robot.search.lo=[7,-6,0]", "x from 7"),
])
def test_bad_irpm_values_are_named(make_cfg, catalogue, override, message):
    with pytest.raises(ConfigError) as info:
        validate(make_cfg("robot=irpm6", override), catalogue)
    assert message in str(info.value)


def test_cpr8_goes_through_the_same_statics(make_cfg, catalogue):
    """The generic statics on the 8-cable CPR-8 (weight of the carrier, robot.platform.mass = 2 kg, z up): rank 5 at zero
    orientation (the singular gate); at 0.5 rad the minimum-norm tensions balance the weight,
    and every grid pose needs at least one pushing cable (the finding behind issue 8)."""
    overrides = ["analysis=statics", "tension.t_max=1000"]  # the weight comes from robot.platform.mass
    _, flat = compute_workspace(make_cfg(*overrides), catalogue)
    assert flat["lost_singular"] == 216
    problem, grid = build_problem(make_cfg(*overrides, "orientation.psi=0.5",
                                           "orientation.theta=0.5", "orientation.phi=0.5"), catalogue)
    margins = evaluate_chunk(problem, grid[:])
    assert (margins["margin_singular"] > 0).all()
    state = problem.spec.state(problem.robot, grid[:], problem.orientation)
    assert state.wrench == pytest.approx([0, 0, -2.0 * 9.81, 0, 0, 0])  # the carrier's 2 kg, z up
    residual = np.einsum("nkm,nm->nk", state.structure_matrix, state.tensions) - state.wrench
    assert np.abs(residual).max() < 1e-9
    assert (margins["margin_slack"] < 0).all()

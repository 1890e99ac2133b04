"""Criteria are first-class (one registry) and every robot x analysis combination runs on the
same physics (issue 15)."""

import contextlib
import numpy as np
import pytest
from omegaconf import OmegaConf

from pipeline.workspace.criteria import COLOURS, DYNAMICS, GEOMETRY, REGISTRY, STATICS, Criterion, gates, register
from pipeline.workspace.verdict import classify
from pipeline.app.problem import build_problem
from conftest import compute_workspace

SMALL_POINTS = ["robot=points",  # six cables: the fewest a wrench with moments needs
                "robot.anchors=[[-1,-1,2],[1,-1,2],[1,1,2],[-1,1,2],[0,-1.5,2],[0,1.5,2]]",
                "robot.attachments=[[-0.1,-0.1,0],[0.1,-0.1,0],[0.1,0.1,0],[-0.1,0.1,0],[0,-0.1,0.05],[0,0.1,0.05]]",
                "robot.search.lo=[-0.5,-0.5,0.5]", "robot.search.hi=[0.5,0.5,1.5]", "robot.search.step=0.25"]
COMBINATIONS = [
    (["robot=cpr8"], "cpr_wwa"), (["robot=cpr8"], "statics"),
    (["robot=irpm6", "robot.search.step=1"], "cpr_wwa"), (["robot=irpm6", "robot.search.step=1"], "statics"),
    (SMALL_POINTS, "cpr_wwa"), (SMALL_POINTS, "statics"), (SMALL_POINTS, "lines"),
]


@pytest.mark.parametrize("robot, analysis", COMBINATIONS)
def test_every_robot_runs_every_analysis_with_criteria_it_can_read(make_cfg, catalogue, robot, analysis):
    problem, _ = build_problem(make_cfg(*robot, f"analysis={analysis}"), catalogue)
    reads = {REGISTRY[name].reads for name in problem.criteria}
    assert reads <= ({"any", DYNAMICS} if analysis != "statics" else {"any", STATICS})
    _, summary = compute_workspace(make_cfg(*robot, f"analysis={analysis}"), catalogue)
    assert summary["n_points"] == summary["n_feasible"] + sum(
        summary[f"lost_{name}"] for name in problem.criteria)


def test_gates_come_from_the_registry_in_priority_order():
    assert gates() == ("zero_length", "singular", "unreachable", "slack")
    margins = {"voltage": np.array([-5.0]), "slack": np.array([-0.1]), "unreachable": np.array([-0.2])}
    assert [list(margins)[code] for code in classify(margins, 1e-9)[2]] == ["unreachable"]  # a gate wins


def test_the_cable_length_limit_is_checked_in_cpr_wwa_too(make_cfg, catalogue):
    """The IRPM's l_max = 15 m is robot data: under CPR-WWA its length criterion is there, equal
    to 1 - max_i l_i / l_max, and with l_max = 5 m it removes every pose it should."""
    cfg = make_cfg("robot=irpm6", "analysis=cpr_wwa", "load.mass=20", "robot.l_max=5")
    problem, grid = build_problem(cfg, catalogue)
    assert "length" in problem.criteria
    points, summary = compute_workspace(cfg, catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientation)
    np.testing.assert_allclose(points["margin_length"], 1 - state.lengths.max(axis=1) / 5.0, atol=1e-12)
    too_long = state.lengths.max(axis=1) > 5.0 + 1e-9
    assert too_long.any() and not points.loc[too_long, "feasible"].any()


def test_a_job_has_only_the_keys_of_its_robot_and_analysis(make_cfg, catalogue):
    """The IRPM's statics summary carries no motion or CPR-8 grid, and no actuator unless one is
    given (the statics' drive, actuator=null); the CPR-8's no moment-arm reading; each gets its
    own analysis' keys (conf/analysis/)."""
    _, irpm = compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1"), catalogue)
    _, cpr8 = compute_workspace(make_cfg(), catalogue)
    assert not any(k.startswith(("motion.", "grid.", "model.pinv_columns")) for k in irpm)
    assert irpm["actuator"] is None and "actuator_name" not in irpm
    assert irpm["model.moment_arm"] == "platform" and "model.moment_arm" not in cpr8
    assert cpr8["actuator"] == 1 and cpr8["grid.n"] == 6 and "wrench.fz" in cpr8 and "wrench.fz" in irpm
    assert not any(k.startswith("robot.r_") for k in cpr8)


@pytest.mark.parametrize("analysis, extra, needs", [
    ("statics", ["tension=pinv"], 6), ("statics", [], 3), ("cpr_wwa", [], 3),
    ("cpr_wwa", ["model.pinv_columns=translational"], 3),
    ("cpr_wwa", ["robot.attachments=[[0.1,0,0],[0,0,0],[0,0,0],[0,0,0]]"], 6)])
def test_fewer_cables_than_the_analysis_balances_are_refused(make_cfg, catalogue, analysis, extra, needs):
    """Four cables to a point: under the minimum-norm model the statics' six wrench rows would
    make every pose singular (pulling cables, ``tension=feasible``, find where four hold it);
    CPR-WWA balances forces only there (its moment rows vanish at a point platform, whatever
    model.pinv_columns says). Four cables to a platform with moment arms cannot balance six."""
    from pipeline.app.problem import validate
    from pipeline.errors import ConfigError

    four = ["robot=points", "robot.anchors=[[-1,-1,2],[1,-1,2],[1,1,2],[-1,1,2]]",
            "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.search.lo=[-0.5,-0.5,0.5]",
            "robot.search.hi=[0.5,0.5,1.5]", "robot.search.step=0.25", f"analysis={analysis}", *extra]
    if needs == 3:
        validate(make_cfg(*four), catalogue)
        return
    with pytest.raises(ConfigError, match=f"robot: 4 cables; analysis={analysis} .* needs >= 6 cables"):
        validate(make_cfg(*four), catalogue)


def test_a_point_platform_gets_the_same_verdicts_with_and_without_moment_rows(make_cfg, catalogue):
    four = ["robot=points", "robot.anchors=[[-1,-1,2],[1,-1,2],[1,1,2],[-1,1,2]]",
            "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.search.lo=[-0.5,-0.5,0.5]",
            "robot.search.hi=[0.5,0.5,1.5]", "robot.search.step=0.25", "analysis=cpr_wwa", "load.mass=0.5"]
    full, _ = compute_workspace(make_cfg(*four), catalogue)
    forces, _ = compute_workspace(make_cfg(*four, "model.pinv_columns=translational"), catalogue)
    assert full["feasible"].tolist() == forces["feasible"].tolist() and full["feasible"].any()
    assert full["limiting"].tolist() == forces["limiting"].tolist()


def test_tension_is_a_config_group_that_sets_its_own_keys_only(make_cfg):
    """``tension=feasible`` (conf/tension/) is ``tension.model=feasible``; the robot's rating
    (irpm6: 55 kN) survives the choice, and the group carries no other key."""
    for robot in ("cpr8", "irpm6"):
        by_group = make_cfg(f"robot={robot}", "tension=feasible")
        by_key = make_cfg(f"robot={robot}", "tension.model=feasible")
        assert OmegaConf.to_container(by_group) == OmegaConf.to_container(by_key)
    assert make_cfg("robot=irpm6", "tension=feasible").tension.t_max == 55_000
    keys = {"model", "t_min", "t_max", "residual_rtol", "distribution", "pinv_residual"}
    assert set(make_cfg("tension=feasible").tension) == keys


def test_an_unknown_tension_option_is_refused_before_anything_runs():
    from pipeline.errors import ConfigError
    from pipeline.app.plan import plan

    with pytest.raises(ConfigError, match="tension=lp"):
        plan(["-m", "tension=pinv,lp"])


def test_a_job_builds_its_robot_once_from_its_kind_and_runs_that_problem(tmp_path, monkeypatch):
    """The plan validates each job by building its problem (``problem.validate``); the job
    runs that problem: one robot built per job, none by the run, and an unknown analysis
    named by a robot file is refused in one line."""
    from dataclasses import replace

    from pipeline.app import problem as kinds
    from pipeline.app.job import execute
    from pipeline.app.plan import plan
    from pipeline.errors import ConfigError

    built = []
    cpr8 = kinds.ROBOTS["cpr8"]
    monkeypatch.setitem(kinds.ROBOTS, "cpr8", replace(cpr8, build=lambda rc: built.append(1) or cpr8.build(rc)))
    jobs = plan(["-m", "actuator=1,2", f"hydra.sweep.dir={tmp_path}"]).jobs
    assert len(built) == 2 and [job.problem.limits.described()["actuator_name"] for job in jobs] == [
        row["name"] for row in jobs[0].catalogue.rows[:2]]
    summaries = [execute(job) for job in jobs]
    assert len(built) == 2 and [s["n_feasible"] for s in summaries] == [216, 208]  # Table 2: 100, 96.30 %
    (tmp_path / "conf" / "robot").mkdir(parents=True)
    (tmp_path / "conf" / "robot" / "odd.yaml").write_text("# @package _global_\ndefaults: [cpr8, _self_]\nanalysis: dynamics\n")
    known = r"\(cpr_wwa, statics, lines, payload, trajectory, certified\)"
    with pytest.raises(ConfigError, match=rf"^analysis=dynamics: unknown analysis {known}$"):
        plan(["--config-dir", str(tmp_path / "conf"), "robot=odd"])


FLOOR_DEG = 10.0  # the floor-angle criterion below: every cable at least this steep
FLOOR_KEY = f"+criteria.floor_angle.min_deg={FLOOR_DEG}"  # its one YAML line, as an override


def floor_angle(state, limits, min_deg: float) -> np.ndarray:
    """A criterion written as a user would, outside the package: the smallest angle of a cable to
    the floor plane, relative to its own key ``criteria.floor_angle.min_deg`` (>= 0: every cable
    steep enough)."""
    steep = np.degrees(np.arcsin(np.clip(np.abs(state.unit[..., 2]), 0.0, 1.0))).min(axis=1)
    return steep / min_deg - 1.0


def law_floor_margin(robot, positions, orientation) -> np.ndarray:
    """The same margin from the points: the cables from each anchor to its attachment point."""
    from pipeline.model.geometry import rotation_matrix

    ends = positions[:, None, :] + robot.attachments @ rotation_matrix(*orientation).T
    cables = ends - robot.anchors
    slope = np.abs(cables[..., 2]) / np.linalg.norm(cables, axis=2)
    return np.degrees(np.arcsin(slope)).min(axis=1) / FLOOR_DEG - 1.0


@pytest.fixture
def floor_registered():
    """The floor-angle criterion registered from outside for one test (the registry is the
    process's: taken out again after it)."""
    from pipeline.app.config import positive

    register(Criterion("floor_angle", floor_angle, GEOMETRY, None, "#117733",
                       "anchors higher above the workspace", lambda analysis, spec, robot: True,
                       keys={"min_deg": positive}))
    try:
        yield
    finally:
        del REGISTRY["floor_angle"], COLOURS["floor_angle"]


@pytest.mark.parametrize("robot, analysis, kernel", [
    (["robot=cpr8", "orientation.psi=0.2"], "cpr_wwa", "numpy"), (["robot=cpr8", "orientation.psi=0.2"], "cpr_wwa", "fused"),
    (["robot=cpr8"], "lines", "auto"), (["robot=irpm6", "robot.search.step=1"], "statics", "fused"),
    (SMALL_POINTS, "statics", "numpy"), (SMALL_POINTS, "payload", "numpy")])
def test_a_criterion_registered_from_outside_is_evaluated_by_every_analysis(
        make_cfg, catalogue, floor_registered, robot, analysis, kernel):
    """Issue 52's extension API: one function, one register() call and its key's one YAML line,
    and the grid (numpy and compiled kernels), the lines, the statics and the payload map all
    check it, with margins equal to the law computed here from the points, and poses lost to it
    counted; without its key no analysis checks it."""
    from pipeline.workspace.lines import simulate_lines

    cfg = make_cfg(*robot, f"analysis={analysis}", f"compute.kernel={kernel}", FLOOR_KEY)
    problem, grid = build_problem(cfg, catalogue)
    assert problem.criteria[-1] == "floor_angle"
    assert "floor_angle" not in build_problem(make_cfg(*robot, f"analysis={analysis}"), catalogue)[0].criteria
    if analysis == "lines":
        samples, points, summary = simulate_lines(cfg, problem, grid)
        at = samples[["x", "y", "z"]].to_numpy()
        np.testing.assert_allclose(samples["margin_floor_angle"], law_floor_margin(problem.robot, at, problem.orientation),
                                   rtol=0, atol=1e-9)
    else:
        points, summary = compute_workspace(cfg, catalogue)
        assert summary["kernel"] == ("fused" if kernel == "fused" else "numpy")
        at = points[["x", "y", "z"]].to_numpy()
        np.testing.assert_allclose(points["margin_floor_angle"], law_floor_margin(problem.robot, at, problem.orientation),
                                   rtol=0, atol=1e-9)
    assert "lost_floor_angle" in summary
    assert summary["n_points"] == summary["n_feasible"] + sum(summary[f"lost_{name}"] for name in problem.criteria)


def test_the_floor_angle_decides_poses_on_the_cpr8(make_cfg, catalogue, floor_registered):
    """Its verdict is the law's: the CPR-8's upper cables are nearly level near the top of the
    frame, so the poses there are lost to the floor angle, and only there."""
    points, summary = compute_workspace(make_cfg("actuator=1", FLOOR_KEY), catalogue)
    problem, _ = build_problem(make_cfg("actuator=1", FLOOR_KEY), catalogue)
    steep = law_floor_margin(problem.robot, points[["x", "y", "z"]].to_numpy(), (0, 0, 0)) >= 0
    assert 0 < summary["lost_floor_angle"] and (points["feasible"].to_numpy() <= steep).all()
    assert (points.loc[~steep, "limiting"] == "floor_angle").all()


def test_a_steeper_floor_angle_from_its_key_removes_more_poses(make_cfg, catalogue, floor_registered):
    """The key reaches the margin: 20 degrees keeps fewer of the CPR-8's poses than 10, and the
    kept ones are exactly those the law keeps at 20."""
    _, at_10 = compute_workspace(make_cfg("actuator=1", FLOOR_KEY), catalogue)
    points, at_20 = compute_workspace(make_cfg("actuator=1", "+criteria.floor_angle.min_deg=20"), catalogue)
    problem, _ = build_problem(make_cfg("actuator=1", FLOOR_KEY), catalogue)
    steep = law_floor_margin(problem.robot, points[["x", "y", "z"]].to_numpy(), (0, 0, 0)) * FLOOR_DEG / 20 + (
        FLOOR_DEG / 20 - 1) >= -1e-12
    assert at_20["lost_floor_angle"] > at_10["lost_floor_angle"] and (points["feasible"].to_numpy() <= steep).all()


@pytest.mark.parametrize("override, message", [
    ("+criteria.floor_angle.min_deg=-3", r"^criteria.floor_angle.min_deg=-3: must be > 0 and finite$"),
    ("+criteria.floor_angle.min_deg=abc", r"^criteria.floor_angle.min_deg=abc: not a value this key takes$"),
    ("+criteria.floor_angle.max_deg=3", r"^criteria.floor_angle=\{'max_deg': 3\}: its keys are min_deg$"),
    ("+criteria.floor_angel.min_deg=3",
     r"^criteria.floor_angel: no criterion with keys of its own is called that "
     r"\(stiffness, sag, cable_contraction, cable_frequency, floor_angle\)$"),
    ("+criteria.torque.limit=3", r"^criteria.torque: no criterion with keys of its own")])
def test_a_criterions_keys_are_checked_by_the_rules_it_declares(make_cfg, catalogue, floor_registered, override, message):
    from pipeline.app.problem import validate
    from pipeline.errors import ConfigError
    from pipeline.workspace.criteria import checked_settings

    with pytest.raises(ConfigError, match=message):
        validate(make_cfg(override), catalogue)
    with pytest.raises(ConfigError, match=r"^criteria=\[1, 2\]: a mapping of criterion names"):
        checked_settings([1, 2])  # a file's criteria: [1, 2]


def test_keys_of_a_criterion_the_analysis_does_not_check_are_refused(make_cfg, catalogue):
    """A criterion with keys that applies to the dynamics only: its keys under analysis=statics
    are refused in one line, not ignored; null keys mean not checked."""
    from pipeline.app.config import positive
    from pipeline.app.problem import validate
    from pipeline.errors import ConfigError

    register(Criterion("winch_turns", floor_angle, GEOMETRY, None, "#117733", "longer drums",
                       lambda analysis, spec, robot: analysis in ("cpr_wwa", "lines"), keys={"min_deg": positive}))
    try:
        assert "winch_turns" in validate(make_cfg("+criteria.winch_turns.min_deg=5"), catalogue)[1].criteria
        with pytest.raises(ConfigError, match=r"^criteria.winch_turns: analysis=statics does not check it"):
            validate(make_cfg("analysis=statics", "+criteria.winch_turns.min_deg=5"), catalogue)
        assert "winch_turns" not in validate(make_cfg("+criteria.winch_turns.min_deg=null"), catalogue)[1].criteria
    finally:
        del REGISTRY["winch_turns"], COLOURS["winch_turns"]


def test_the_criterions_one_yaml_line_in_a_users_robot_file_runs_it_through_the_api(tmp_path, catalogue, floor_registered):
    """The extension as a user writes it: the registered criterion, and its key as one line of
    their own robot file (``criteria: {floor_angle: {min_deg: 10}}``), run by the API as the
    command line runs a job; the summary counts the poses it removes and records the key."""
    from pipeline import api

    (tmp_path / "conf" / "robot").mkdir(parents=True)
    (tmp_path / "conf" / "robot" / "steep.yaml").write_text(
        "# @package _global_\ndefaults: [cpr8, _self_]\ncriteria: {floor_angle: {min_deg: 10}}\n")
    ws = api.workspace(["robot=steep", "actuator=1"], folder=tmp_path / "job", config_dir=tmp_path / "conf")
    assert ws.summary["lost_floor_angle"] > 0 and ws.summary["criteria.floor_angle.min_deg"] == 10
    assert (ws.points["limiting"] == "floor_angle").sum() == ws.summary["lost_floor_angle"]


FLOOR_N = 150.0  # the registered force floor below (N): every cable pulls at least this much


def force_floor(state, limits, floor: float = FLOOR_N) -> np.ndarray:
    """The minimum-norm model's margin of a floor on every cable's tension, written as a user
    would; under ``tension=feasible`` its ``bounds`` decide instead."""
    return (state.force_range[1] - floor).min(axis=1) / limits.scale


@contextlib.contextmanager
def floor_registered_at(floor: float):
    """A force floor registered from outside with its interval on the forces (``bounds``)."""
    from pipeline.workspace.criteria import ANY

    register(Criterion("force_floor", lambda state, limits: force_floor(state, limits, floor), ANY, None, "#117733",
                       "stronger anchors", lambda analysis, spec, robot: analysis in ("statics", "cpr_wwa"),
                       bounds=lambda state, limits: (state.variables_of(floor), np.inf, limits.scale)))
    try:
        yield
    finally:
        del REGISTRY["force_floor"], COLOURS["force_floor"]


@pytest.fixture
def floor_bounded():
    with floor_registered_at(FLOOR_N):
        yield


@pytest.mark.parametrize("robot, floor", [(["robot=irpm6", "robot.search.step=1"], FLOOR_N),
                                          (["robot=cpr8", "analysis=statics", "load.mass=5"], 20.0),
                                          (["robot=cpr8", "wrench.fx=20", "orientation.psi=0.2"], 5.0)])
def test_a_registered_bound_on_the_forces_is_nested_by_the_feasible_model(make_cfg, catalogue, robot, floor):
    """Issue 52: a criterion that bounds the forces is one entry with ``bounds``. Its verdicts are
    those of tension.t_min = floor (the built-in slack family, a second way to say the same), on
    the CPR-8's eight cables too, where the feasible tensions are not the minimum-norm ones (its
    function's margin alone would lose every pose there), in the statics and in CPR-WWA."""
    robot = [*robot, "tension=feasible"]
    with floor_registered_at(floor):
        floored, summary = compute_workspace(make_cfg(*robot), catalogue)
    raised, _ = compute_workspace(make_cfg(*robot, f"tension.t_min={floor}"), catalogue)
    assert summary["kernel"] == "numpy" and (floored["margin_force_floor"] < 0).any() and floored["feasible"].any()
    np.testing.assert_array_equal(floored["feasible"], raised["feasible"])


def test_a_registered_bound_gives_the_best_distributions_margin_by_an_lp(make_cfg, catalogue):
    """On the CPR-8's eight cables the floor's margin is that of the best tensions, not of the
    minimum-norm ones: max s subject to A x = w, x >= t_min (the earlier slack family, where it
    holds) and x_i - floor >= s scale, by scipy's linprog pose by pose (the second method)."""
    from scipy.optimize import linprog

    floor, cfg = 20.0, make_cfg("robot=cpr8", "analysis=statics", "load.mass=5", "tension=feasible")
    with floor_registered_at(floor):
        floored, _ = compute_workspace(cfg, catalogue)
    problem, grid = build_problem(cfg, catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientation)
    scale, m = problem.limits.scale, problem.robot.n_cables
    held = np.flatnonzero(floored["margin_slack"].to_numpy() >= 0)
    best = []
    for pose in held:  # variables (x, s): maximise s
        found = linprog(np.r_[np.zeros(m), -1.0], A_ub=np.c_[-np.eye(m), np.full(m, scale)], b_ub=np.full(m, -floor),
                        A_eq=np.c_[state.structure[pose], np.zeros(len(state.structure[pose]))],
                        b_eq=state.required_wrenches[0], bounds=[(0, None)] * m + [(None, None)])
        best.append(min(-found.fun, 1.0))
    assert len(held) > 20 and min(best) < 0 < max(best)
    np.testing.assert_allclose(floored["margin_force_floor"].to_numpy()[held], best, atol=1e-7)


def test_a_registered_bound_gives_the_law_on_a_square_structure_matrix(make_cfg, catalogue, floor_bounded):
    """The IRPM's A is square, so the tensions are unique, s = A^-1 w (numpy's solve, the law):
    the floor's margin is (min s - floor) / scale (at most 1) at every pose of full rank."""
    cfg = make_cfg("robot=irpm6", "robot.search.step=1", "tension=feasible")
    floored, _ = compute_workspace(cfg, catalogue)
    problem, grid = build_problem(cfg, catalogue)
    state = problem.spec.state(problem.robot, grid[:], problem.orientation)
    solvable = np.linalg.cond(state.structure) < 1e8
    wrench = np.broadcast_to(state.required_wrenches[0], (solvable.sum(), 6))  # one wrench, every pose
    tensions = np.linalg.solve(state.structure[solvable], wrench[..., None])[..., 0]
    law = np.minimum((tensions.min(axis=1) - FLOOR_N) / problem.limits.scale, 1.0)
    assert solvable.mean() > 0.9
    np.testing.assert_allclose(floored["margin_force_floor"].to_numpy()[solvable], law, atol=1e-9)


def test_a_registered_criterion_the_fused_kernel_does_not_compile_sends_the_job_to_numpy(
        make_cfg, catalogue, floor_bounded):
    """The fused kernel evaluates what it compiles and the geometric criteria; a registered one
    that reads the forces is evaluated by numpy, whose margins it then gets (not dropped)."""
    points, summary = compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1", "compute.kernel=auto"), catalogue)
    assert summary["kernel"] == "numpy" and "margin_force_floor" in points
    with pytest.raises(Exception, match="force_floor"):
        compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1", "compute.kernel=fused"), catalogue)


def test_no_criterion_is_spelled_in_more_than_three_product_modules():
    """Issue 52: a criterion is referred to by the registry's constants, not by its name retyped
    across the product (a renamed criterion would silently miss the modules that spell it). Every
    string literal of every product module, read by Python's own parser (docstrings and comments
    are not code); today the registry, the module of its family and one more at most."""
    import ast
    from pathlib import Path

    import pipeline

    spelled = {name: set() for name in REGISTRY}
    for path in Path(pipeline.__file__).parent.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in spelled:
                spelled[node.value].add(str(path.relative_to(Path(pipeline.__file__).parent)))
    crowded = {name: sorted(modules) for name, modules in spelled.items() if len(modules) > 3}
    assert not crowded, crowded

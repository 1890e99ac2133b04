"""Layout synthesis (issue 58): the search's best against a brute force by another method, a
symmetric optimum recovered, the quadrant family against IPAnema 1's published anchors, and a
layout study from a user's own folder (its best layout run again as a robot file)."""

import itertools
import re
from dataclasses import replace

import joblib
import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import command
from pipeline.analyses.layout import (Box, LayoutSpec, best_trial, check_robot, cheapest_drive, designed, drives, evaluate,
                                      placed, prove_required, search_layouts)
from pipeline.app.problem import build_problem
from pipeline.errors import ConfigError
from pipeline.workspace.feasibility import feasible_flags
from pipeline.workspace.kernel import evaluate_chunk
from pipeline.workspace.verdict import classify

PLANAR = ["robot=points", "robot.dofs=[x,y]", "robot.anchors=[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]",
          "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.search.lo=[-0.9,-0.9,0]",
          "robot.search.hi=[0.9,0.9,0]", "robot.search.step=0.15", "tension=feasible", "tension.t_min=1",
          "tension.t_max=10"]
IPANEMA_CASE = ["robot=points", "robot.anchors=[[-2,1.5,2],[2,1.5,2],[2,-1.5,2],[-2,-1.5,2],[-2,1.5,0],[2,1.5,0],"
                "[2,-1.5,0],[-2,-1.5,0]]", "robot.attachments=[[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],"
                "[-0.06,-0.06,0],[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0]]",
                "robot.search.lo=[-2,-1.5,0]", "robot.search.hi=[2,1.5,2]", "robot.search.spacing=centres",
                "tension=feasible", "tension.t_min=1", "tension.t_max=10"]
IPANEMA_ANCHORS = [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2], [-2, 1.5, 0], [2, 1.5, 0], [2, -1.5, 0],
                   [-2, -1.5, 0]]


def registry_count(problem, positions) -> int:
    """Feasible poses by the registry's margins (hyperplane shifting and LPs): the second method."""
    raw = evaluate_chunk(problem, positions)
    return int(classify({name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)[1].sum())


def moved(problem, anchors, attachments=None):
    robot = replace(problem.robot, anchors=np.asarray(anchors, dtype=float),
                    attachments=problem.robot.attachments if attachments is None else np.asarray(attachments, dtype=float))
    return replace(problem, robot=robot)


def test_an_exhaustive_lattice_search_finds_the_brute_force_best(make_cfg, catalogue):
    """Three cables of a planar point robot, each anchor on a 3 x 3 lattice of the frame (729
    layouts), the platform pulled down by 3 N: the search (budget = the lattice) tries every layout
    once, and its best count is the best of a brute force counted by the registry's margins."""
    problem, grid = build_problem(make_cfg(*PLANAR, "robot.anchors=[[-1,-1,0],[1,-1,0],[0,1,0]]",
                                           "robot.attachments=[[0,0,0],[0,0,0],[0,0,0]]", "wrench.fy=-3"), catalogue)
    positions = grid[0:len(grid)]
    required = Box([-0.3, 0.6, 0], [0.3, 0.9, 0])  # the top middle of the grid must hold
    spec = LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0]), step=1.0, objectives=["feasible_pct"], budget=729,
                      required=required)
    spec.check_across("test")
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=1)
    keys = [f"anchor{c}_{axis}" for c in (1, 2, 3) for axis in "xy"]
    assert len(table) == 729 and not table.duplicated(keys).any()
    corner = required.contains(positions)
    counts, meeting = {}, {}
    for point in itertools.product([-1.0, 0.0, 1.0], repeat=6):
        moved_problem = moved(problem, np.c_[np.reshape(point, (3, 2)), np.zeros(3)])
        raw = evaluate_chunk(moved_problem, positions)
        flags = classify({n: raw[f"margin_{n}"] for n in problem.criteria}, problem.margin_atol)[1]
        counts[point], meeting[point] = int(flags.sum()), bool(flags[corner].all())
    best = max(counts.values())
    assert 0 < best < len(positions)
    assert table["n_feasible"].max() == best
    searched = table.set_index(keys)
    assert all(searched.loc[point, "n_feasible"] == count for point, count in list(counts.items())[::37])
    assert searched["meets"].sum() == sum(meeting.values()) > 0
    best_meeting = max(count for point, count in counts.items() if meeting[point])
    assert best_meeting < best  # the requirement costs poses: a real constraint
    assert best_trial(table, spec)["n_feasible"] == best_meeting


def test_a_search_without_symmetry_recovers_the_symmetric_optimum(make_cfg, catalogue):
    """Four anchors each at a corner of the square frame (256 layouts), no wrench: the frame is
    mirror-symmetric, and the best layouts are exactly those with one anchor at every corner,
    a set the mirrors x -> -x and y -> -y keep."""
    problem, grid = build_problem(make_cfg(*PLANAR), catalogue)
    spec = LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0]), step=2.0, objectives=["feasible_pct"], budget=256)
    table = search_layouts(spec, problem, grid[0:len(grid)], grid.cell_volume, n_jobs=2)
    assert len(table) == 256
    best = table[table["n_feasible"] == table["n_feasible"].max()]
    for _, row in best.iterrows():
        corners = {(row[f"anchor{c}_x"], row[f"anchor{c}_y"]) for c in range(1, 5)}
        assert corners == {(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)}
        assert corners == {(-x, y) for x, y in corners} == {(x, -y) for x, y in corners}
    assert len(best) == 24  # the 4! ways to put the four cables at the four corners


def test_quadrants_mirror_one_designed_cable_into_ipanema_1(make_cfg, catalogue):
    """IPAnema 1's anchors are one top and one bottom anchor mirrored by the planes x = 0 and
    y = 0 in its cable order: two designed anchors give its eight."""
    problem, _ = build_problem(make_cfg("robot=points", f"robot.anchors={np.zeros((8, 3)).tolist()}",
                                        f"robot.attachments={np.zeros((8, 3)).tolist()}", "robot.search.lo=[-1,-1,0.5]",
                                        "robot.search.hi=[1,1,1.5]", "robot.search.step=0.5"), catalogue)
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), symmetry="quadrants")
    assert set(spec.ranges(8)) == {f"anchor{c}_{a}" for c in (2, 6) for a in "xyz"}
    assert spec.ranges(8)["anchor2_x"] == (0.0, 2.0)
    values = {"anchor2_x": 2, "anchor2_y": 1.5, "anchor2_z": 2, "anchor6_x": 2, "anchor6_y": 1.5, "anchor6_z": 0}
    anchors, attachments = placed(spec, problem.robot, values)
    np.testing.assert_array_equal(anchors, IPANEMA_ANCHORS)
    np.testing.assert_array_equal(attachments, np.zeros((8, 3)))


def test_the_robots_own_layout_is_the_first_trial(make_cfg, catalogue):
    """The search starts from the robot the overrides build, so its best is never worse."""
    problem, grid = build_problem(make_cfg(*PLANAR), catalogue)
    positions = grid[0:len(grid)]
    spec = LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0]), objectives=["feasible_pct"], budget=6, sampler="tpe")
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=1)
    every = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=-1)  # joblib's -1: every core
    pd.testing.assert_frame_equal(every, search_layouts(spec, problem, positions, grid.cell_volume,
                                                        n_jobs=joblib.effective_n_jobs(-1)))
    first = table.iloc[0]
    own = np.asarray(problem.robot.anchors)
    assert [first[f"anchor{c + 1}_{a}"] for c in range(4) for a in "xyz"] == own.ravel().tolist()
    assert first["n_feasible"] == registry_count(problem, positions) == table["n_feasible"].max()
    assert table["best_so_far"].is_monotonic_increasing and (table["best_so_far"] == table["feasible_pct"].max()).all()


def test_the_longest_cable_and_the_required_box(make_cfg, catalogue):
    """The longest cable over the feasible poses against the lengths computed here, and a
    required box: its failing poses counted, and a layout that fails it does not meet it."""
    problem, grid = build_problem(make_cfg(*PLANAR), catalogue)
    positions = grid[0:len(grid)]
    found = evaluate(problem, positions, grid.cell_volume, np.all(np.abs(positions) <= 0.3, axis=1))
    raw = evaluate_chunk(problem, positions)
    feasible = classify({n: raw[f"margin_{n}"] for n in problem.criteria}, problem.margin_atol)[1]
    lengths = np.linalg.norm(problem.robot.anchors[None] - positions[feasible][:, None], axis=2)
    assert found["longest_cable_m"] == pytest.approx(lengths.max(), rel=1e-12)
    assert found["required_failing"] == 0 and found["n_feasible"] == feasible.sum()
    shrunk = evaluate(moved(problem, np.array(problem.robot.anchors) * 0.3), positions, grid.cell_volume,
                      np.all(np.abs(positions) <= 0.3, axis=1))
    assert shrunk["required_failing"] > 0


def test_the_largest_payload_is_the_payload_analysis_least_over_the_required_box(make_cfg, catalogue):
    """Two methods: the bisection of largest_payload (the exact verdict at each mass) against
    analysis=payload's LP per pose (the largest payload it holds), least over the required box's
    poses; on IPAnema 1 with an off-centre load, tilted, and on the planar robot."""
    from pipeline.analyses.layout import PAYLOAD_RTOL, largest_payload

    off_centre = [0.02, -0.01, 0.03]
    cases = [([*IPANEMA_CASE, "robot.search.step=0.2", "tension.t_max=40", f"load.com={off_centre}",
               "orientation.psi=0.1", "orientation.theta=-0.05"], off_centre,
              lambda p: np.all(np.abs(p - [0.3, 0.2, 1.0]) <= 0.5, axis=1)),
             ([*PLANAR, "robot.up=[0,1,0]"], [0, 0, 0], lambda p: np.all(np.abs(p[:, :2] - [0.1, 0.2]) <= 0.35, axis=1))]
    for overrides, com, inside in cases:
        problem, grid = build_problem(make_cfg(*overrides), catalogue)
        positions = grid[0:len(grid)]
        required = positions[inside(positions)]
        found = largest_payload(problem, required, 0.0, np.array(com, dtype=float))
        payload, _ = build_problem(make_cfg(*overrides, "analysis=payload"), catalogue)
        least = evaluate_chunk(payload, required)["max_payload_kg"].min()
        assert 0.5 < found < 100 and len(required) >= 8
        assert found == pytest.approx(least, rel=10 * PAYLOAD_RTOL), (found, least)
        assert found <= least * (1 + 1e-9)  # what the bisection returns holds


def test_a_payload_search_maximises_what_the_required_box_carries(make_cfg, catalogue):
    """payload_kg as the objective: every trial's payload holds its required box and 1 % more
    does not (the verdicts of the registry, a second method), the best trial carries the most."""
    from pipeline.analyses.layout import largest_payload

    problem, grid = build_problem(make_cfg(*PLANAR, "robot.up=[0,1,0]"), catalogue)
    positions = grid[0:len(grid)]
    spec = LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0]), objectives=["payload_kg", "feasible_pct"], budget=20,
                      required=Box([-0.2, -0.2, 0], [0.2, 0.2, 0]))
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=1, payload=(0.0, np.zeros(3)))
    required = spec.required.contains(positions)
    met = table[table["meets"]]
    assert len(met) >= 3 and table.loc[~table["meets"], "payload_kg"].isna().all()
    for _, row in met.head(4).iterrows():
        anchors, _ = placed(spec, problem.robot, row.to_dict())
        trial = moved(problem, anchors)
        for share, holds in ((1.0, True), (1.01, False)):
            load = replace(trial.spec.load, mass=trial.spec.load.mass + share * row["payload_kg"])
            assert (registry_count(replace(trial, spec=replace(trial.spec, load=load)), positions[required])
                    == required.sum()) == holds
    assert best_trial(table, spec)["payload_kg"] == met["payload_kg"].max()
    own = largest_payload(problem, positions[required], 0.0, np.zeros(3))
    assert own == table.iloc[0]["payload_kg"]  # trial 0: the robot as given


def swept_tension_factor(structure: np.ndarray, directions: int = 20_000) -> float:
    """Pham et al.'s tension factor of one 6 x 8 structure matrix by a second method: its null space
    (two-dimensional) swept, h = N [cos a, sin a] at ``directions`` angles, the best min h / max h
    among the strictly positive h (a lower bound, within the sweep's step of the exact value)."""
    import scipy.linalg

    null = scipy.linalg.null_space(structure)
    assert null.shape[1] == 2
    angles = np.linspace(0.0, 2 * np.pi, directions, endpoint=False)
    h = null @ np.stack([np.cos(angles), np.sin(angles)])
    positive = (h > 0).all(axis=0)
    return float((h.min(axis=0)[positive] / h.max(axis=0)[positive]).max()) if positive.any() else 0.0


def test_the_least_tension_factor_against_the_null_space_swept(make_cfg, catalogue):
    """objective tension_factor: the least over a required box off the centre of IPAnema 1, tilted,
    against the null space swept (no LP); 1 at the centre of the untilted robot, whose mirrored
    cables hold nothing with equal tensions (A 1 = 0, worked out by hand)."""
    from pipeline.analyses.layout import least_tension_factor

    problem, grid = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.2", "orientation.psi=0.1",
                                           "orientation.theta=-0.05"), catalogue)
    positions = grid[0:len(grid)]
    required = positions[np.all(np.abs(positions - [0.3, 0.2, 1.0]) <= 0.3, axis=1)]
    found = least_tension_factor(problem, required)
    ((at, orientation),) = problem.poses(required)
    structures = problem.spec.state(problem.robot, at, orientation).structure
    swept = min(swept_tension_factor(a) for a in structures)
    assert len(required) >= 8 and 0.05 < found < 0.95
    assert swept - 1e-9 <= found <= swept + 1e-3
    level, _ = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.2"), catalogue)
    assert least_tension_factor(level, np.array([[0.0, 0.0, 1.0]])) == pytest.approx(1.0, abs=1e-9)
    assert least_tension_factor(level, np.array([[0.5, 0.0, 1.0]])) < 1 - 1e-3


def test_a_search_trading_workspace_for_frame(make_cfg, catalogue):
    """objectives [volume_m3, frame_m3] on IPAnema 1 with quadrants on a lattice: every trial's
    frame_m3 is the bounding box of its placed anchors (measured here), the front's trials are not
    dominated by any (checked pair by pair), and the largest frame gives the largest volume; with
    tension_factor second, the required box's least tension factor is reported for the trials that
    hold it."""
    problem, grid = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.25"), catalogue)
    positions = grid[0:len(grid)]
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), symmetry="quadrants", step=0.5,
                      objectives=["volume_m3", "frame_m3"], budget=30, sampler="nsga2")
    spec.check_across("test")
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=2)
    for _, row in table.iterrows():
        anchors, _ = placed(spec, problem.robot, row.to_dict())
        extent = anchors.max(axis=0) - anchors.min(axis=0)
        assert row["frame_m3"] == pytest.approx(extent[0] * extent[1] * extent[2], rel=1e-12)
    front = table[table["pareto"]]
    assert len(front) >= 2
    for _, row in front.iterrows():
        better = (table["volume_m3"] >= row["volume_m3"]) & (table["frame_m3"] <= row["frame_m3"])
        strictly = (table["volume_m3"] > row["volume_m3"]) | (table["frame_m3"] < row["frame_m3"])
        assert not (better & strictly).any()
    assert table.iloc[0]["frame_m3"] == 24.0  # trial 0: IPAnema 1's own 4 x 3 x 2 m frame
    required = Box([-0.5, -0.5, 0.75], [0.5, 0.5, 1.25])
    spec = replace(spec, objectives=["volume_m3", "tension_factor"], required=required, budget=6)
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=1)
    met = table[table["meets"]]
    assert len(met) >= 1 and table.loc[~table["meets"], "tension_factor"].isna().all()
    assert ((met["tension_factor"] > 0) & (met["tension_factor"] <= 1)).all()
    cpr8, cpr8_grid = build_problem(make_cfg(), catalogue)  # CPR-WWA: a platform in motion, J's pseudo-inverse
    with pytest.raises(ConfigError, match="tension_factor is of a static pose's structure matrix"):
        check_robot(spec, cpr8, cpr8_grid)


PRICES = {1: 900, 2: 400, 3: 100, 4: 150, 5: 60}  # price_EUR of Table 1's actuators in the user's catalogue


def priced_catalogue(path, prices=PRICES):
    """Table 1 with the user's own column price_EUR (text to the catalogue reader, as users write it)."""
    from pipeline.model.catalogue import TABLE1

    lines = TABLE1.read_text().strip().splitlines()
    path.write_text("\n".join([lines[0] + ",price_EUR", *(f"{line},{prices[int(line.split(',')[0])]}" for line in lines[1:])])
                    + "\n")
    return path


def rest_cap_by_hand(row: dict) -> float:
    """The largest tension (N) a catalogue row holds at rest, from its columns and the laws: the
    torque behind the gearbox M = tau N_V eta <= torque_Nm N_V eta (eq. 32); at rest the armature
    draws i = M / (k_t N_V eta) at u = R i <= U (eq. 34 without speed terms); M = R_w t."""
    behind = float(row["gear_ratio"]) * float(row["efficiency"])
    torque = float(row["torque_Nm"]) * behind
    voltage = float(row["voltage_V"]) * float(row["torque_constant_Nm_per_A"]) * behind / float(row["resistance_ohm"])
    return min(torque, voltage) / float(row["winch_radius_m"])


def planar_lp_holds(anchors, position, force, lower, upper) -> bool:
    """Whether tensions in [lower, upper] balance ``force`` on a planar point at ``position``:
    unit vectors toward the anchors written from the law, HiGHS's LP, no code of the package."""
    from scipy.optimize import linprog

    toward = anchors[:, :2] - position[:2]
    unit = toward / np.linalg.norm(toward, axis=1, keepdims=True)
    return linprog(np.zeros(len(anchors)), A_eq=unit.T, b_eq=-np.asarray(force), bounds=[(lower, u) for u in upper],
                   method="highs").status == 0


def test_the_rest_cap_of_table_1_from_its_columns():
    """rest_tension_cap against the laws written from the catalogue's columns; actuator 4 is held
    by its voltage at rest (55.58 N) before its torque (55.65 N), the others by their torque."""
    from pipeline.model.actuators import actuator_model, rest_tension_cap
    from pipeline.model.catalogue import load_catalogue

    rows = load_catalogue().rows
    caps = {row["id"]: rest_tension_cap(actuator_model(row)) for row in rows}
    for row in rows:
        assert caps[row["id"]] == pytest.approx(rest_cap_by_hand(row), rel=1e-12)
    assert caps[4] == pytest.approx(24 * 0.0352 * 30 * 0.7 / 3.99 / 0.08, rel=1e-12)  # 55.58 N: its voltage at rest
    assert caps[4] < 0.212 * 30 * 0.7 / 0.08  # 55.65 N: its torque
    assert caps[1] == pytest.approx(0.6 * 30 * 0.6 / 0.08, rel=1e-12)  # 135 N: its torque


def test_the_cheapest_actuator_holds_the_required_box_and_no_cheaper_one_does(make_cfg, catalogue, tmp_path):
    """Objective actuator_cost with the user's prices, on every layout of a lattice of a planar
    robot pulled off-centre (8 N sideways, 40 N down): for every layout, the brute force over the
    catalogue (each row's cap written from its columns, an LP per required pose with tensions in
    [t_min, cap]: the cables have no rating of their own) finds the same cheapest actuator, or none; the costs are the price
    times the four cables, and the best trial is the cheapest. Two cables holding a load under
    tension=pinv (the registry's margins, not the null-space test): their tensions, solved here,
    decide."""
    from pipeline.model.catalogue import load_catalogue

    user = load_catalogue(priced_catalogue(tmp_path / "motors.csv"))
    problem, grid = build_problem(make_cfg(*PLANAR[:-1], "wrench.fx=8", "wrench.fy=-40"), catalogue)
    positions = grid[0:len(grid)]
    spec = LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0]), symmetry="quadrants", step=0.25, budget=25,
                      objectives=["actuator_cost", "feasible_pct"], required=Box([-0.3, -0.3, 0], [0.3, 0.3, 0]),
                      catalogue=str(tmp_path / "motors.csv"), cost="price_EUR")  # every layout of the lattice
    spec.check_across("test")
    check_robot(spec, problem, grid)
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=1)
    required = positions[spec.required.contains(positions)]
    caps = {row["id"]: rest_cap_by_hand(row) for row in user.rows}
    chosen = []
    for _, row in table.iterrows():
        anchors, _ = placed(spec, problem.robot, row.to_dict())
        holds = {k: all(planar_lp_holds(anchors, p, [8, -40], 1.0, [cap] * 4) for p in required)  # no rating of its own
                 for k, cap in caps.items()} if row["meets"] else {}
        cheapest = min((PRICES[k], k) for k, held in holds.items() if held) if any(holds.values()) else None
        if cheapest is None:
            assert np.isnan(row["actuator"]) and np.isnan(row["actuator_cost"])
        else:
            assert (row["actuator"], row["actuator_cost"]) == (cheapest[1], 4 * cheapest[0])
        chosen.append(None if cheapest is None else cheapest[1])
    assert len({c for c in chosen if c is not None}) >= 3, chosen  # the layout decides the actuator
    crane, _ = build_problem(make_cfg(*PLANAR[:2], "robot.anchors=[[-1,1,0],[1,1,0]]", "robot.attachments=[[0,0,0],[0,0,0]]",
                                      *PLANAR[4:7], "tension=pinv", "tension.t_min=1", "wrench.fy=-40"), catalogue)
    found = set()
    for corner in ([-0.2, -0.4], [0.3, 0.5], [0.0, 0.6], [0.0, 0.75], [0.2, 0.8]):  # up to 28, 52, 70, 135, 193 N
        poses = np.array([[x, y, 0.0] for x in (corner[0], corner[0] + 0.1) for y in (corner[1], corner[1] + 0.1)])
        toward = crane.robot.anchors[None, :, :2] - poses[:, None, :2]
        unit = toward / np.linalg.norm(toward, axis=2, keepdims=True)
        tensions = np.linalg.solve(np.transpose(unit, (0, 2, 1)), np.tile([0.0, 40.0], (len(poses), 1))[..., None])[..., 0]
        held = [k for k in caps if ((tensions >= 1) & (tensions <= caps[k])).all()]
        drive = cheapest_drive(crane, poses, drives(spec, 2))
        assert (None if drive is None else drive.id) == (min(held, key=PRICES.get) if held else None), (corner, tensions)
        found.add(None if drive is None else drive.id)
    assert found == {3, 4, 2, 1, None}, found
    assert best_trial(table, spec)["actuator_cost"] == table.loc[table["meets"], "actuator_cost"].min()


@pytest.mark.parametrize("fields, message", [
    ({"anchors": {"lo": [0, 0, 0], "hi": [-1, 1, 1]}}, "exceeds hi"),
    ({"anchors": {"lo": [0, 0], "hi": [1, 1, 1]}}, "three finite coordinates"),
    ({"anchors": {"lo": [-1, 0, 0], "hi": [2, 1, 1]}, "symmetry": "quadrants"}, "symmetric about x = 0"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "step": 0.3}, "not a whole number of steps"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "objectives": ["speed"]}, "one or two of"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "budget": 0}, "budget=0"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "symmetry": "radial"}, "symmetry='radial'"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "anchors_on": "walls"}, "anchors_on='walls'"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "anchors_on": "faces", "step": 0.5}, "anchors on its faces"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [0, 0, 1]}, "anchors_on": "edges"}, "has no edges"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "refine": 1.0}, "refine=1.0"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "refine": 0.5, "step": 0.5}, "refine takes continuous"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "objectives": ["actuator_cost"]}, "cost=None: objective actuator_cost"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "cost": "price_EUR"}, "cost=price_EUR: objective actuator_cost"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "catalogue": "m.csv"}, "catalogue=m.csv: read for objective"),
    ({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "frame_scale": [0.5, 1]}, "anchors_on: faces or edges"),
    *[({"anchors": {"lo": [0, 0, 0], "hi": [1, 1, 1]}, "anchors_on": "edges", "frame_scale": scale},
       re.escape(f"frame_scale={scale}: [lo, hi]")) for scale in ([0, 1], [0.5, 1.2], [0.9, 0.5], [float("nan"), 1], [0.5], [])],
])
def test_a_layout_block_that_cannot_be_searched_is_refused(fields, message):
    spec = LayoutSpec(anchors=Box(**fields.pop("anchors")), **fields)
    with pytest.raises(ConfigError, match=message):
        spec.check_across("study")


@pytest.mark.parametrize("seed", [-1, 2**32])
def test_a_seed_the_samplers_cannot_take_is_refused_with_the_blocks_rules(seed):
    """A seed outside numpy's and Optuna's [0, 2^32 - 1] ended in Optuna's ValueError after the
    study had started; the block's declared rule refuses it when the file is read."""
    from pipeline.app.config import check_declared

    with pytest.raises(ConfigError, match=re.escape(f"seed={seed}: must be an integer in [0, 2^32 - 1]")):
        check_declared(LayoutSpec(anchors=Box(lo=[0, 0, 0], hi=[1, 1, 1]), seed=seed), "study", "layout: ")


STUDY = {
    "title": "My frame", "source": "mine",
    "overrides": [*PLANAR[:-3], "tension=feasible", "tension.t_min=1", "tension.t_max=10", "wrench.fy=-2"],
    "layout": {"anchors": {"lo": [-1, -1, 0], "hi": [1, 1, 0]}, "symmetry": "quadrants",
               "objectives": ["feasible_pct", "longest_cable_m"], "budget": 10, "sampler": "nsga2",
               "required": {"lo": [-0.1, -0.1, 0], "hi": [0.1, 0.1, 0]}},
    "analyses": ["best_layout"],
    "figures": [{"kind": "cloud", "table": "best_layout", "file": "best.png", "title": "best {n_feasible}"}],
}


def write_study(folder, study=STUDY, name="mylayout"):
    (folder / "studies").mkdir(parents=True, exist_ok=True)
    (folder / "studies" / f"{name}.yaml").write_text(yaml.safe_dump(study))


def run_study(tmp_path, study=STUDY):
    """The layout study ``study`` from the user's folder ``myconf``: its folder, summary and best row."""
    write_study(tmp_path / "myconf", study)
    done = command(tmp_path, "pipeline.study", "--config-dir", "myconf", "mylayout", "--out", "out")
    assert done.returncode == 0, done.stderr[-3000:]
    out = tmp_path / "out" / "mylayout"
    summary = pd.read_parquet(out / "summary.parquet")
    assert (summary["job"] == "best").sum() == 1
    return out, summary, summary[summary["job"] == "best"].iloc[0]


def test_a_layout_study_from_a_users_folder_writes_a_robot_file_that_runs(tmp_path):
    out, summary, best = run_study(tmp_path)
    assert len(summary) == 10
    assert best["feasible_pct"] == summary.loc[summary["meets"], "feasible_pct"].max()
    assert best["required_proven_pct"] > 50 and summary["required_proven_pct"].notna().sum() == 1
    assert (out / "figures" / "best.png").stat().st_size > 0
    front = summary[summary["pareto"]]
    files = sorted((out / "layouts").glob("*.yaml"))
    assert [f.name for f in files] == [f"trial_{int(t):04d}.yaml" for t in sorted(front["trial"])] and len(files) >= 1
    for path in files:  # each the trial's own points: eight columns of the summary mirrored into the robot's cables
        row = front[front["trial"] == int(path.stem[6:])].iloc[0]
        written = yaml.safe_load(path.read_text())
        assert written["defaults"] == ["points", "_self_"] and written["dofs"] == ["x", "y"]
        assert written["anchors"][1][:2] == [row["anchor2_x"], row["anchor2_y"]]
        assert written["anchors"][3][:2] == [-row["anchor2_x"], -row["anchor2_y"]]  # (-x, -y) mirrors (+x, +y)
    robot = tmp_path / "myconf" / "robot"
    robot.mkdir()
    (robot / "layout_best.yaml").write_text((out / "layout_best.yaml").read_text())
    again = command(tmp_path, "pipeline", "--config-dir", "myconf", "robot=layout_best", "tension=feasible",
                    "tension.t_min=1", "tension.t_max=10", "wrench.fy=-2", "hydra.run.dir=again")
    assert again.returncode == 0, again.stderr[-3000:]
    assert pd.read_parquet(tmp_path / "again" / "summary.parquet")["n_feasible"].iloc[0] == best["n_feasible"]


def test_a_frame_sized_by_the_study_is_in_its_robot_file(tmp_path):
    """layout.frame_scale from a user's folder on the planar robot (its plane the x-y one, up +z):
    the summary's frame_x, frame_y in [0.6, 1] and no frame_z (the plane is flat in z), each Pareto
    layout's robot file with its four anchors on the sides of its own frame (the square of side
    2 frame_x by 2 frame_y about the origin, written here from those words)."""
    study = {**STUDY, "overrides": [*PLANAR[:2], "robot.anchors=[[-1,1,0],[1,1,0],[1,-1,0],[-1,-1,0]]", *PLANAR[3:],
                                    "tension=feasible", "tension.t_min=1", "tension.t_max=10", "wrench.fy=-2"],
             "layout": {**STUDY["layout"], "anchors_on": "faces", "frame_scale": [0.6, 1.0], "budget": 8}}
    out, summary, best = run_study(tmp_path, study)
    assert "frame_z" not in summary and summary["frame_x"].between(0.6, 1).all() and summary["frame_y"].between(0.6, 1).all()
    assert summary.iloc[0][["frame_x", "frame_y"]].tolist() == [1.0, 1.0]  # the robot as given: its own square
    for path in sorted((out / "layouts").glob("*.yaml")):
        row = summary[summary["trial"] == int(path.stem[6:])].iloc[0]
        anchors = np.array(yaml.safe_load(path.read_text())["anchors"])
        half = np.array([row["frame_x"], row["frame_y"]])
        assert (np.abs(anchors[:, :2]) <= half + 1e-12).all() and np.allclose(anchors[:, 2], 0)
        assert np.isclose(np.abs(anchors[:, :2]), half, rtol=0, atol=1e-12).any(axis=1).all(), (anchors, half)


def test_a_payload_study_counts_the_payload_at_load_com_on_top_of_load_mass(tmp_path, make_cfg, catalogue):
    """From the command line: objective payload_kg with the job's own 0.3 kg at an off-centre
    load.com; the best trial's payload is analysis=payload's least over the required box for the
    best robot file (its max_payload_kg counts load.mass in)."""
    study = {**STUDY, "overrides": [*STUDY["overrides"][:-1], "robot.dofs=[x,y,rz]",
                                    "robot.attachments=[[-0.1,0.1,0],[0.1,0.1,0],[0.1,-0.1,0],[-0.1,-0.1,0]]",
                                    "robot.up=[0,1,0]", "load.mass=0.3", "load.com=[0.03,0,0]"],
             "layout": {**STUDY["layout"], "objectives": ["payload_kg"], "budget": 6, "sampler": "tpe"}}
    out, summary, best = run_study(tmp_path, study)
    assert best["payload_kg"] == summary.loc[summary["meets"], "payload_kg"].max() > 0.3
    anchors = yaml.safe_load((out / "layout_best.yaml").read_text())["anchors"]
    payload, grid = build_problem(make_cfg(*study["overrides"], f"robot.anchors={anchors}", "analysis=payload"), catalogue)
    positions = grid[0:len(grid)]
    required = positions[np.all(np.abs(positions[:, :2]) <= 0.1 + 1e-9, axis=1)]
    assert best["payload_kg"] == pytest.approx(evaluate_chunk(payload, required)["max_payload_kg"].min(), rel=1e-5)


def test_a_cost_study_names_the_actuator_to_buy_in_its_robot_file(tmp_path, make_cfg, catalogue):
    """From the command line with the user's catalogue and prices: the best trial is the cheapest
    one that holds the required box, its robot file names its actuator, and run as a job with the
    cables rated at that actuator's cap (written here from the catalogue's columns) every required
    pose holds, while the catalogue's next smaller cap loses one."""
    from pipeline.model.catalogue import load_catalogue

    priced_catalogue(tmp_path / "motors.csv")
    overrides = [*PLANAR[:-3], "tension=feasible", "tension.t_min=1", "wrench.fx=8", "wrench.fy=-40"]
    study = {**STUDY, "overrides": overrides,
             "layout": {**STUDY["layout"], "objectives": ["actuator_cost", "feasible_pct"], "step": 0.25, "budget": 25,
                        "sampler": "tpe", "required": {"lo": [-0.3, -0.3, 0], "hi": [0.3, 0.3, 0]},
                        "catalogue": "motors.csv", "cost": "price_EUR"}}
    out, summary, best = run_study(tmp_path, study)
    assert best["actuator_cost"] == summary.loc[summary["meets"], "actuator_cost"].min() == 4 * PRICES[int(best["actuator"])]
    header = (out / "layout_best.yaml").read_text().splitlines()[0]
    said = f"actuator {int(best['actuator'])} of the catalogue on every cable (price_EUR {best['actuator_cost']:g} in all)"
    assert said in header, header
    anchors = yaml.safe_load((out / "layout_best.yaml").read_text())["anchors"]
    caps = sorted(rest_cap_by_hand(row) for row in load_catalogue(tmp_path / "motors.csv").rows)
    own = rest_cap_by_hand(load_catalogue(tmp_path / "motors.csv").row(int(best["actuator"])))
    lower = max(cap for cap in caps if cap < own)
    for rating, holds in ((own, True), (lower, False)):
        problem, grid = build_problem(make_cfg(*overrides, f"robot.anchors={anchors}", f"tension.t_max={rating}"), catalogue)
        positions = grid[0:len(grid)]
        required = positions[np.all(np.abs(positions[:, :2]) <= 0.3 + 1e-9, axis=1)]
        assert (registry_count(problem, required) == len(required)) == holds


@pytest.mark.parametrize("change, message", [
    ({"overrides": ["robot=cpr8"]}, "robot=cpr8: study mylayout moves the anchors"),
    ({"overrides": [*PLANAR, "analysis=certified"]}, "analysis=certified: study mylayout counts a grid"),
    ({"overrides": [*PLANAR[:2], "robot.anchors=[[-1,-1,0],[1,-1,0],[1,1,0]]",
                    "robot.attachments=[[0,0,0],[0,0,0],[0,0,0]]", *PLANAR[4:]]}, "the robot has 3 cables"),
    ({"sweep": {"load.mass": "1,2"}}, "a study either sweeps or optimises"),
    ({"overrides": [*PLANAR, "robot.dofs=[x,y,rz]", "robot.platform.shape={lo:[-0.1,-0.1,-0.05],hi:[0.1,0.1,0.05]}",
                    "robot.attachments=[[-0.1,0.1,0],[0.1,0.1,0],[0.1,-0.1,0],[-0.1,-0.1,0]]"],
      "layout": {**STUDY["layout"], "attachments": {"lo": [-0.1, -0.1, 0], "hi": [0.1, 0.1, 0]}}},
     "layout.attachments: the robot's platform has a shape"),
    ({"overrides": [*PLANAR[:3], "robot.attachments=[[0.1,0,0],[0,0,0],[0,0,0],[0,0,0]]", *PLANAR[4:]]},
     "the robot's attachments, which the search keeps, are not mirrored"),
    ({"layout": {"anchors": {"lo": [-1, -1, 0], "hi": [1, 1, 0]}, "budget": -1}}, "budget=-1"),
    ({"layout": {**STUDY["layout"], "frame_scale": [0.5, 1]}}, "frame_scale=[0.5, 1.0]: sizes the frame whose faces"),
    ({"layout": {**STUDY["layout"], "anchors_on": "edges", "frame_scale": "big"}}, "frame_scale"),
    ({"layout": {"anchors": {"lo": [-1, -1, 0], "hi": [1, 1, 0]}, "objectives": ["volume_m3"]}},
     "volume_m3: the grid has no volume"),
    ({"layout": {"anchors": {"lo": [-1, -1, 0], "hi": [1, 1, 0]}, "objectives": ["payload_kg"]}},
     "payload_kg is the largest payload the required box holds; give layout.required"),
    ({"layout": {"anchors": {"lo": [-1, -1, 0], "hi": [1, 1, 0]}, "objectives": ["tension_factor"]}},
     "tension_factor is the least over the required box; give layout.required"),
    ({"layout": {**STUDY["layout"], "objectives": ["payload_kg"], "required": {"lo": [0.01, 0.01, 0], "hi": [0.02, 0.02, 0]}}},
     "layout.required: the box [0.01, 0.01, 0.0]..[0.02, 0.02, 0.0] holds no pose of the grid"),
    ({"layout": {"anchors": {"lo": [-1, -1, 0], "hi": [1, 1, 0]}, "objectives": ["feasible_pct", "frame_m3"]}},
     "frame_m3 is the anchors' bounding volume"),
    ({"overrides": [*STUDY["overrides"], "platform_motion.acceleration=[[0.5,0,0,0,0,0]]"],
      "layout": {**STUDY["layout"], "objectives": ["payload_kg"]}}, "payload_kg adds mass to a platform at rest"),
    ({"overrides": [*PLANAR[:4], "robot.dofs=[x,y,z]", "robot.anchors=[[-1,-1,1],[1,-1,1],[1,1,1],[-1,1,1]]",
                    "poses=[[0,0,0.5],[0.2,0,0.5]]", *PLANAR[7:]],
      "layout": {"anchors": {"lo": [-1, -1, 1], "hi": [1, 1, 1]}, "objectives": ["volume_m3"]}},
     "volume_m3: the grid has no volume"),
    ({"layout": {**STUDY["layout"], "objectives": ["actuator_cost"], "cost": "price_EUR", "required": None,
                 "catalogue": "motors.csv"}}, "actuator_cost is the cheapest catalogue actuator that holds the required box"),
    ({"layout": {**STUDY["layout"], "objectives": ["actuator_cost"], "cost": "price_USD", "catalogue": "motors.csv"}},
     "layout.cost=price_USD: not a numeric column of catalogue=motors.csv (its columns: power_W, "),
    ({"layout": {**STUDY["layout"], "objectives": ["actuator_cost"], "cost": "price_EUR", "catalogue": "quoted.csv"}},
     "layout.cost=price_EUR: catalogue=quoted.csv, actuator 3: 'on request' is not a price"),
    ({"layout": {**STUDY["layout"], "objectives": ["actuator_cost"], "cost": "price_EUR", "catalogue": "inf.csv"}},
     "layout.cost=price_EUR: catalogue=inf.csv, actuator 3: '1e308' is not a price"),
    ({"layout": {**STUDY["layout"], "objectives": ["actuator_cost"], "cost": "price_EUR", "catalogue": "none.csv"}},
     "catalogue=none.csv"),
    ({"overrides": [*STUDY["overrides"], "actuator=2"],
      "layout": {**STUDY["layout"], "objectives": ["actuator_cost"], "cost": "power_W"}},
     "actuator_cost chooses the actuator from layout.catalogue; leave the job's own actuator=null"),
    ({"overrides": [*IPANEMA_CASE[:6], "analysis=cpr_wwa", "robot.search.step=0.5"],
      "layout": {"anchors": {"lo": [-2, -1.5, 0], "hi": [2, 1.5, 2]}, "objectives": ["actuator_cost"], "cost": "power_W",
                 "required": {"lo": [-0.5, -0.5, 0.5], "hi": [0.5, 0.5, 1.5]}}},
     "actuator_cost holds a platform at rest (analysis=statics without platform_motion)"),
])
def test_a_layout_study_it_cannot_run_exits_2_in_one_line_and_writes_nothing(tmp_path, change, message):
    priced_catalogue(tmp_path / "motors.csv")
    priced_catalogue(tmp_path / "quoted.csv", {**PRICES, 3: "on request"})
    priced_catalogue(tmp_path / "inf.csv", {**PRICES, 3: "1e308"})  # finite, not times four cables
    write_study(tmp_path / "myconf", {**STUDY, **change})
    done = command(tmp_path, "pipeline.study", "--config-dir", "myconf", "mylayout", "--out", "out")
    assert done.returncode == 2 and message in done.stderr, done.stderr[-2000:]
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def lp_holds(anchors, attachments, position, lower, upper) -> bool:
    """Whether tensions in [lower, upper] hold a massless platform at ``position`` (zero
    orientation): the structure matrix written from the law (unit vectors from the attachments to
    the anchors, their moments about the platform's centre) and HiGHS's LP, no code of the package."""
    from scipy.optimize import linprog

    toward = anchors - (position + attachments)
    unit = toward / np.linalg.norm(toward, axis=1, keepdims=True)
    structure = np.vstack([unit.T, np.cross(attachments, unit).T])
    found = linprog(np.zeros(len(anchors)), A_eq=structure, b_eq=np.zeros(6), bounds=[(lower, upper)] * len(anchors),
                    method="highs")
    return found.status == 0


def test_a_platform_shaped_like_its_frame_beats_ipanema_1(make_cfg, catalogue):
    """Issue 58 asks for a layout in IPAnema 1's frame with a larger workspace than its 9.752 m^3
    ([1, 10] N, 0.1 m grid). The search with the anchors on the frame's edges found one (TPE, 300
    trials: 10.58 m^3): the attachments drawn in along y. Its principle, the platform a scaled
    copy of the 4 x 3 m frame: the same anchors with the attachments at (+-0.06, +-0.045, 0),
    inside the platform's own 0.12 m square, hold 10 920 poses (10.92 m^3), by the fast flags and
    by the registry's margins alike; an LP written here from the law agrees pose by pose on 300
    random poses of the grid."""
    problem, grid = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.1"), catalogue)
    positions = grid[0:len(grid)]
    attachments = np.array([[-0.06, 0.045, 0], [0.06, 0.045, 0], [0.06, -0.045, 0], [-0.06, -0.045, 0]] * 2)
    scaled = moved(problem, problem.robot.anchors, attachments)
    fast = evaluate(scaled, positions, grid.cell_volume, None)
    assert fast["n_feasible"] == registry_count(scaled, positions) == 10920
    assert fast["volume_m3"] == pytest.approx(10.92) and fast["volume_m3"] > 9.752
    raw = evaluate_chunk(scaled, positions)
    flags = classify({n: raw[f"margin_{n}"] for n in scaled.criteria}, scaled.margin_atol)[1]
    rng = np.random.default_rng(58)
    for row in rng.choice(len(positions), 300, replace=False):
        assert lp_holds(problem.robot.anchors, attachments, positions[row], 1.0, 10.0) == flags[row], positions[row]


def test_anchors_on_the_frames_faces_and_edges():
    """A frame's walls and ceiling (faces) or its posts and beams (edges): 6 and 12 of a box, 4 and
    5 of the quarter with quadrants (its parts on the mirror planes are not the frame's), and a
    planar robot's rectangle has 4 sides and 4 corners."""
    frame = Box([-2, -1.5, 0], [2, 1.5, 2])
    counts = {(on, symmetry): len(LayoutSpec(anchors=frame, anchors_on=on, symmetry=symmetry).pieces())
              for on in ("faces", "edges") for symmetry in ("none", "quadrants")}
    assert counts == {("faces", "none"): 6, ("edges", "none"): 12, ("faces", "quadrants"): 4, ("edges", "quadrants"): 5}
    plane = Box([-1, -1, 0], [1, 1, 0])
    assert len(LayoutSpec(anchors=plane, anchors_on="faces").pieces()) == 4
    corners = {tuple(origin) for origin, spans in LayoutSpec(anchors=plane, anchors_on="edges").pieces()}
    assert corners == {(-1.0, -1.0, 0.0), (-1.0, 1.0, 0.0), (1.0, -1.0, 0.0), (1.0, 1.0, 0.0)}


@pytest.mark.parametrize("on, held", [("edges", 2), ("faces", 1)])
def test_a_search_on_the_frame_keeps_every_anchor_on_it(make_cfg, catalogue, on, held):
    """Every trial's eight anchors hold at least ``held`` coordinates at the frame's bounds (an
    edge: two, a face: one); IPAnema 1's corners are on both, so it is the first trial."""
    problem, grid = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.5"), catalogue)
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), symmetry="quadrants", anchors_on=on, budget=12,
                      objectives=["volume_m3"])
    spec.check_across("test")
    table = search_layouts(spec, problem, grid[0:len(grid)], grid.cell_volume, n_jobs=1)
    assert table.iloc[0]["n_feasible"] == registry_count(problem, grid[0:len(grid)])
    bounds = np.array([[-2, -1.5, 0], [2, 1.5, 2]])
    for _, row in table.iterrows():
        anchors, _ = placed(spec, problem.robot, row.to_dict())
        at_bounds = (np.isclose(anchors[:, None, :], bounds[None]).any(axis=1)).sum(axis=1)
        assert (at_bounds >= held).all(), anchors
        assert np.allclose(anchors[1], [row["anchor2_x"], row["anchor2_y"], row["anchor2_z"]])
    np.testing.assert_array_equal(placed(spec, problem.robot, table.iloc[0].to_dict())[0], problem.robot.anchors)


@pytest.mark.parametrize("on, held", [("edges", 2), ("faces", 1)])
def test_a_frame_of_designed_size_holds_its_anchors_on_its_own_edges_and_faces(make_cfg, catalogue, on, held):
    """frame_scale: every trial's anchors on the edges (faces) of its own frame, the installation box
    4 x 3 x 2 m scaled by the trial's frame_x, frame_y, frame_z about its centre in x and y and its
    floor z = 0 (written here from those words); trial 0 is IPAnema 1's own frame (sides 1.0); each
    trial's count equals the registry's margins' for its anchors; the front trades frame for volume."""
    problem, grid = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.5"), catalogue)
    positions = grid[0:len(grid)]
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), symmetry="quadrants", anchors_on=on, budget=16,
                      objectives=["volume_m3", "frame_m3"], sampler="nsga2", frame_scale=[0.5, 1.0])
    spec.check_across("test")
    table = search_layouts(spec, problem, positions, grid.cell_volume, n_jobs=2)
    assert table.iloc[0][["frame_x", "frame_y", "frame_z"]].tolist() == [1.0, 1.0, 1.0]
    assert table.iloc[0]["frame_m3"] == 24.0
    for number, row in table.iterrows():
        assert 0.5 <= row["frame_x"] <= 1 and 0.5 <= row["frame_y"] <= 1 and 0.5 <= row["frame_z"] <= 1
        lo = np.array([-2 * row["frame_x"], -1.5 * row["frame_y"], 0.0])
        hi = np.array([2 * row["frame_x"], 1.5 * row["frame_y"], 2 * row["frame_z"]])
        anchors, _ = placed(spec, problem.robot, row.to_dict())
        assert ((anchors >= lo - 1e-12) & (anchors <= hi + 1e-12)).all(), (anchors, lo, hi)
        at_bounds = (np.isclose(anchors[:, None, :], np.stack([lo, hi])[None], rtol=0, atol=1e-12)).any(axis=1).sum(axis=1)
        assert (at_bounds >= held).all(), anchors
        if number < 4:
            assert row["n_feasible"] == registry_count(moved(problem, anchors), positions)
    front = table[table["pareto"]]
    assert (front["frame_m3"] < 24.0 - 1e-9).any() and len(front) >= 2


def test_a_frame_scaled_alike_on_every_side_scales_a_point_platforms_workspace(make_cfg, catalogue):
    """The law a frame's size obeys: a point platform's cable directions, and so its verdict under
    a force, do not change when its anchors and the point are scaled alike about one point. So the
    pose P of the installation box's frame holds exactly when pivot + s (P - pivot) holds in the
    frame of sides s (pivot: the box's centre in x and y, its floor in z). Random poses, both frames'
    verdicts by the exact test; a frame grown from its centre (z too) fails it."""
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), symmetry="quadrants", anchors_on="edges",
                      frame_scale=[0.5, 1.0])
    point = ["robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.dofs=[x,y,z]",
             "wrench.fx=1", "wrench.fz=-5", "robot.search.step=0.5"]
    problem, _ = build_problem(make_cfg(*IPANEMA_CASE[:2], *IPANEMA_CASE[3:], *point), catalogue)
    values = designed(spec, problem.robot)
    rng = np.random.default_rng(7)
    poses = rng.uniform([-1.9, -1.4, 0.1], [1.9, 1.4, 1.9], size=(3000, 3))
    whole = feasible_flags(problem, poses)
    assert 0.2 < whole.mean() < 0.8
    pivot = np.array([0.0, 0.0, 0.0])
    for s in (0.55, 0.8):
        anchors, _ = placed(spec, problem.robot, {**values, "frame_x": s, "frame_y": s, "frame_z": s})
        scaled = feasible_flags(moved(problem, anchors), pivot + s * (poses - pivot))
        np.testing.assert_array_equal(scaled, whole)
        about_centre = feasible_flags(moved(problem, anchors), np.array([0, 0, 1.0]) + s * (poses - [0, 0, 1.0]))
        assert (about_centre != whole).sum() > 30


def test_the_best_layouts_required_box_is_proven_where_the_certificates_speak(make_cfg, catalogue):
    """The required box of the best layout paved as analysis=certified paves a search box: a box
    well inside the workspace of the square frame mostly proven; a robot with a criterion the
    certificates cannot bound (the sag of heavy cables) says so instead of a number."""
    problem, _ = build_problem(make_cfg(*PLANAR), catalogue)
    compute = make_cfg(*PLANAR).compute
    spec = LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0]), required=Box([-0.3, -0.3, 0], [0.3, 0.3, 0]))
    share, said = prove_required(spec, problem, compute)
    assert share > 90.0 and "of the required box proven feasible" in said
    positions = np.random.default_rng(3).uniform([-0.3, -0.3, 0], [0.3, 0.3, 0], (500, 3))
    assert registry_count(problem, positions) == 500  # the grid agrees: it holds everywhere sampled
    sagging, _ = build_problem(make_cfg(*PLANAR, "robot.cable_mass=0.05", "+criteria.sag={ratio: 0.02}"), catalogue)
    assert prove_required(spec, sagging, compute) == (None, "the required box is not proven: criterion sag "
                                                            "has no certified bound")
    assert prove_required(LayoutSpec(anchors=Box([-1, -1, 0], [1, 1, 0])), problem, compute) == (None, "no required box")


def test_refinement_steps_around_the_best_and_is_reproducible(make_cfg, catalogue):
    """``refine``: the last share of the budget is spent around the best trial so far: each of
    those trials keeps the best's edge, moves its continuous variables by bounded normal steps
    inside their ranges, and the step shrinks after batches that do not improve; a rerun with the
    same seed gives the same trials."""
    problem, grid = build_problem(make_cfg(*IPANEMA_CASE, "robot.search.step=0.5"), catalogue)
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), attachments=Box([-0.06, -0.06, 0], [0.06, 0.06, 0]),
                      symmetry="quadrants", anchors_on="edges", budget=24, refine=0.5, objectives=["volume_m3"])
    spec.check_across("test")
    table = search_layouts(spec, problem, grid[0:len(grid)], grid.cell_volume, n_jobs=2)
    again = search_layouts(spec, problem, grid[0:len(grid)], grid.cell_volume, n_jobs=2)
    pd.testing.assert_frame_equal(table, again)
    ranges = spec.ranges(8)
    for number in range(12, 24):
        row, before = table.iloc[number], table.iloc[:number - number % 2]  # a batch of two sees the trials before it
        best = before.loc[before["volume_m3"].idxmax()]
        assert row["anchor2_piece"] == best["anchor2_piece"] and row["anchor6_piece"] == best["anchor6_piece"]
        for key, (lo, hi) in ranges.items():
            assert lo <= row[key] <= hi
            assert abs(row[key] - best[key]) <= 0.5 * 6 * (hi - lo) + 1e-12  # at most six of the largest steps


def test_the_refinement_rule():
    from pipeline.analyses.layout import Steps

    steps = Steps(0)
    steps.adapt(False)
    assert steps.size == pytest.approx(0.04)
    for _ in range(20):
        steps.adapt(True)
    assert steps.size == Steps.LARGEST
    for _ in range(200):
        steps.adapt(False)
    assert steps.size == Steps.SMALLEST
    moved = steps.nearby({"a": 0.5, "p": 3}, {"a": (0.0, 1.0)})
    assert moved["p"] == 3 and 0.0 <= moved["a"] <= 1.0

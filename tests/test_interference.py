"""Cable-cable interference: the closed-form distance of two segments against a dense sampling
and against the enumeration of the quadratic's candidate minima; the criterion, pose by pose,
against that enumeration on a tilted CPR-8; the numpy and compiled kernels give the same
margins; the closest pair is the one at the worst orientation."""

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

from pipeline.api import workspace
from pipeline.app.problem import build_problem, validate
from conftest import compute_workspace
from pipeline.model.clearance import segment_distance
from pipeline.model.geometry import CableRobot, PoseGeometry
from pipeline.workspace.criteria.interference import cable_cable
from pipeline.workspace.kernel import evaluate_chunk


def sampled_distance(p1, d1, p2, d2, n=801):
    """The least distance between n points spread evenly on each segment; at most
    (|d1| + |d2|) / (2 (n - 1)) above the segments' distance."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    a, b = p1 + s * d1, p2 + s * d2
    return np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)).min()


def exact_distance(p1, d1, p2, d2) -> float:
    """The distance of two segments (3-vectors) in exact rational arithmetic: the minimum of the
    quadratic q(s, t) = |p1 + s d1 - p2 - t d2|^2 over [0, 1]^2 by the Karush-Kuhn-Tucker
    conditions, each solved exactly: either a corner, a point of an edge where q's derivative
    along it vanishes, or the interior point where its gradient does."""
    p1, d1, p2, d2 = ([Fraction(float(x)) for x in v] for v in (p1, d1, p2, d2))

    def dot(u, v):
        return sum(x * y for x, y in zip(u, v))

    r = [x - y for x, y in zip(p1, p2)]
    a, e, b, c, f = dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r)

    def q(s, t):
        gap = [x + s * y - t * z for x, y, z in zip(r, d1, d2)]
        return dot(gap, gap)

    points = [(Fraction(s), Fraction(t)) for s in (0, 1) for t in (0, 1)]
    for side in (Fraction(0), Fraction(1)):
        if e:
            points.append((side, (b * side + f) / e))  # dq/dt = 0 on the edge s = side
        if a:
            points.append(((b * side - c) / a, side))  # dq/ds = 0 on the edge t = side
    if a * e - b * b:
        points.append(((b * f - c * e) / (a * e - b * b), (a * f - b * c) / (a * e - b * b)))
    return float(min(q(s, t) for s, t in points if 0 <= s <= 1 and 0 <= t <= 1)) ** 0.5


X, Y, Z = np.eye(3)
NEARLY_X = np.array([np.cos(1e-5), np.sin(1e-5), 0.0])
CASES = {  # p1, d1, p2, d2, the distance
    "crossing": (-X, 2 * X, -Y, 2 * Y, 0.0),
    "parallel side by side": (0 * X, X, 0.5 * X + Y, X, 1.0),
    "collinear apart": (0 * X, X, 3 * X, X, 2.0),
    "antiparallel overlapping": (0 * X, X, 2 * X + 0.3 * Y, -1.5 * X, 0.3),
    "touching at an end": (0 * X, X, X, Y + Z, 0.0),
    "a T short of touching": (0 * X, X, 0.5 * X + 0.2 * Y, Y, 0.2),
    "skew, closest beyond both": (0 * X, X, 3 * X - Y + Z, 2 * Y, np.sqrt(5.0)),
    "a point and a segment": (0.5 * X + 2 * Z, 0 * X, 0 * X, X, 2.0),
    "two points": (X, 0 * X, Y, 0 * X, np.sqrt(2.0)),
    # 5 m cables crossing at 1e-5 rad, 0.1 um apart: a e - b^2 would lose the crossing to round-off
    "nearly parallel, crossing": (-2.5 * X, 5 * X, -2.5 * NEARLY_X + 1e-7 * Z, 5 * NEARLY_X, 1e-7),
}


@pytest.mark.parametrize("case", CASES)
def test_closed_form_distance_of_known_pairs(case):
    p1, d1, p2, d2, expected = CASES[case]
    assert segment_distance(p1, d1, p2, d2) == pytest.approx(expected, rel=1e-9, abs=1e-15)
    assert segment_distance(p2, d2, p1, d1) == pytest.approx(expected, rel=1e-9, abs=1e-15)  # symmetric
    assert exact_distance(p1, d1, p2, d2) == pytest.approx(expected, rel=1e-9, abs=1e-15)


def test_closed_form_distance_against_exact_arithmetic_and_dense_sampling():
    rng = np.random.default_rng(7)
    p1, d1, p2, d2 = rng.normal(size=(4, 300, 3))
    d2[:40] = d1[:40] * rng.uniform(-2, 2, size=(40, 1))  # parallel and antiparallel pairs
    d2[40:80] = d1[40:80] + 1e-9 * rng.normal(size=(40, 3))  # all but parallel
    p2[80:120] = p1[80:120] + d1[80:120] * rng.uniform(0, 1, size=(40, 1))  # touching: a point of one on the other
    closed = segment_distance(p1, d1, p2, d2)
    exact = [exact_distance(*pair) for pair in zip(p1, d1, p2, d2)]
    np.testing.assert_allclose(closed, exact, rtol=1e-12, atol=1e-12)
    assert closed[80:120] == pytest.approx(0, abs=1e-12)
    for k in range(0, 300, 3):
        sampled = sampled_distance(p1[k], d1[k], p2[k], d2[k])
        bound = (np.linalg.norm(d1[k]) + np.linalg.norm(d2[k])) / (2 * 800)
        assert closed[k] - 1e-12 <= sampled <= closed[k] + bound


def _square_robot(radius: float) -> CableRobot:
    """Four cables from the corners of a square at height 2 to the corners of a 0.2 m platform,
    the two front ones crossed (each to the opposite side's attachment)."""
    anchors = np.array([[-1, -1, 2], [1, -1, 2], [1, 1, 2], [-1, 1, 2]], dtype=float)
    attachments = np.array([[0.1, -0.1, 0], [-0.1, -0.1, 0], [0.1, 0.1, 0], [-0.1, 0.1, 0]])
    return CableRobot("square", anchors, attachments, np.zeros(3), np.ones(3), ("a", "b", "c", "d"),
                      cable_radii=np.full(4, radius))


def test_crossed_cables_have_margin_minus_one_and_name_their_pair():
    robot = _square_robot(0.005)
    state = PoseGeometry(robot, np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.999]]), (0.0, 0.0, 0.0))
    margin = cable_cable(state, None)
    assert margin[0] == pytest.approx(-1.0, abs=1e-12)  # the crossed pair's axes meet in the plane x = 0
    i, j = robot.cable_pairs
    assert (robot.cable_names[i[state.closest_pair[0]]], robot.cable_names[j[state.closest_pair[0]]]) == ("a", "b")
    # just below the anchors the crossed front cables are still crossed, the other pairs far apart
    assert margin[1] == pytest.approx(-1.0, abs=1e-9)


def test_pairs_sharing_an_anchor_or_an_attachment_are_not_checked():
    robot = _square_robot(0.01)
    robot = replace(robot, anchors=robot.anchors[[0, 0, 2, 3]], attachments=robot.attachments[[0, 1, 2, 2]])
    i, j = robot.cable_pairs
    pairs = set(zip(i.tolist(), j.tolist()))
    assert (0, 1) not in pairs and (2, 3) not in pairs and len(pairs) == 4


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.3, -0.2, 0.4)])
def test_criterion_equals_the_exact_distances_pose_by_pose(make_cfg, catalogue, orientation):
    psi, theta, phi = orientation
    cfg = make_cfg("robot.cable_diameter=[0.01,0.02,0.01,0.02,0.03,0.01,0.02,0.01]", "grid.n=5",
                   f"orientation.psi={psi}", f"orientation.theta={theta}", f"orientation.phi={phi}")
    cfg, problem = validate(cfg, catalogue, typed=True)
    problem, grid = build_problem(cfg, catalogue)
    robot, positions = problem.robot, grid[:]
    state = PoseGeometry(robot, positions, problem.orientation)
    margin = cable_cable(state, None)
    ends = state.attachment_points
    radii = robot.cable_radii
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8)]
    relative = np.array([[
        exact_distance(robot.anchors[i], ends[k, i] - robot.anchors[i], robot.anchors[j], ends[k, j] - robot.anchors[j])
        / (radii[i] + radii[j]) - 1.0 for i, j in pairs] for k in range(len(positions))])
    np.testing.assert_allclose(margin, np.minimum(1.0, relative.min(axis=1)), rtol=0, atol=1e-12)
    i, j = robot.cable_pairs
    assert len(i) == 28  # no two CPR-8 cables share an anchor or an attachment point
    assert [(i[k], j[k]) for k in state.closest_pair] == [pairs[k] for k in relative.argmin(axis=1)]
    assert (margin < 0).any() and (margin > 0).any()  # the check decides something on this grid


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.5, 0.5, 0.5)])
def test_numpy_and_compiled_kernels_give_the_same_interference(make_cfg, catalogue, orientation):
    psi, theta, phi = orientation
    tables = {}
    for kernel in ("numpy", "fused"):
        cfg = make_cfg("robot.cable_diameter=0.02", "grid.n=12", f"compute.kernel={kernel}",
                       f"orientation.psi={psi}", f"orientation.theta={theta}", f"orientation.phi={phi}")
        cfg, _ = validate(cfg, catalogue, typed=True)
        tables[kernel] = compute_workspace(cfg, catalogue)[0]
    numpy_table, fused_table = tables["numpy"], tables["fused"]
    assert (numpy_table["limiting"] == "cable_cable").any()
    np.testing.assert_array_equal(numpy_table["margin_cable_cable"], fused_table["margin_cable_cable"])
    assert numpy_table["closest_cables"].tolist() == fused_table["closest_cables"].tolist()
    assert numpy_table["feasible"].tolist() == fused_table["feasible"].tolist()


def test_the_closest_pair_is_the_one_at_the_worst_orientation(make_cfg, catalogue):
    cfg = make_cfg("robot.cable_diameter=0.02", "grid.n=8", "orientation.total.bound=0.3", "orientation.total.n=2")
    cfg, problem = validate(cfg, catalogue, typed=True)
    grid = build_problem(cfg, catalogue)[1]
    positions = grid[:]
    merged = evaluate_chunk(problem, positions)
    per_orientation = []
    for orientation in problem.orientations:
        state = PoseGeometry(problem.robot, positions, orientation)
        per_orientation.append((cable_cable(state, None), state.closest_pair))
    margins = np.array([m for m, _ in per_orientation])
    worst = margins.argmin(axis=0)
    np.testing.assert_array_equal(merged["margin_cable_cable"], margins.min(axis=0))
    expected = np.array([per_orientation[w][1][k] for k, w in enumerate(worst)])
    np.testing.assert_array_equal(merged["closest_pair"], expected)
    assert len(set(worst.tolist())) > 1  # the worst orientation differs between poses


@pytest.mark.parametrize("bound, diameter, feasible, lost", [(0.0, 0.04, 3593, 29), (0.2, 0.02, 2509, 437)])
def test_the_cogiro_study_gives_the_numbers_its_docs_state(tmp_path, bound, diameter, feasible, lost):
    """docs/studies.md quotes these jobs of the study interference_cogiro, run from its own
    overrides: every surviving pose is connected to home."""
    from pipeline.study import load_study

    overrides = [o.strip('"') for o in load_study("interference_cogiro").overrides]
    summary = workspace([*overrides, f"orientation.total.bound={bound}", f"robot.cable_diameter={diameter}",
                         "output.points=false"], tmp_path).summary
    assert (summary["n_feasible"], summary["n_points"], summary["lost_cable_cable"]) == (feasible, 5040, lost)
    assert summary["n_connected"] == feasible


# --- cable-obstacle and cable-platform ---------------------------------------------------------

def point_box_distance(points, lo, hi):
    """Each point's distance from the box (0 inside) and its depth inside (0 outside)."""
    outside = np.linalg.norm(np.maximum(np.maximum(lo - points, points - hi), 0.0), axis=-1)
    depth = np.minimum(points - lo, hi - points).min(axis=-1).clip(min=0.0)
    return outside, depth


def test_separating_axes_of_a_segment_and_a_box_against_dense_sampling():
    """Apart, the gap is positive and at most the sampled distance; crossing, it is negative;
    along a face it is that face's distance exactly."""
    from pipeline.model.clearance import box_separation

    rng = np.random.default_rng(11)
    lo, hi = np.array([-0.5, -0.3, -0.2]), np.array([0.4, 0.6, 0.3])
    starts, ends = rng.uniform(-1.5, 1.5, size=(2, 400, 3))
    segments = np.stack([starts, ends], axis=1)
    direction = (ends - starts) / np.linalg.norm(ends - starts, axis=1, keepdims=True)
    gaps = box_separation(segments, np.zeros((400, 0, 3)), direction[:, None, :], lo, hi)
    s = np.linspace(0, 1, 4001)[:, None, None]
    outside, depth = point_box_distance(starts + s * (ends - starts), lo, hi)
    nearest, deepest = outside.min(axis=0), depth.max(axis=0)
    step = np.linalg.norm(ends - starts, axis=1) / 4000
    apart, crossing = nearest > step, deepest > step
    assert apart.sum() > 100 and crossing.sum() > 50
    assert (gaps[apart] > 0).all() and (gaps[apart] <= nearest[apart] + 1e-12).all()
    assert (gaps[crossing] < 0).all()
    along = np.array([[[-1.0, 0.9, 0.0], [1.0, 0.9, 0.0]]])  # parallel to the face y = 0.6, 0.3 above it
    assert box_separation(along, np.zeros((1, 0, 3)), np.array([[[1.0, 0, 0]]]), lo, hi)[0] == pytest.approx(0.3)


def test_separating_axes_of_turned_cubes_and_a_box_against_a_linear_program():
    """A convex body and a box intersect exactly when some convex combination of the body's
    vertices lies in the box (a linear feasibility problem, solved by scipy's HiGHS)."""
    from scipy.optimize import linprog

    from conftest import eq9_rotation
    from pipeline.model.clearance import Polytope, box_separation

    rng = np.random.default_rng(5)
    cube = Polytope.hull(np.array([[x, y, z] for x in (0, 0.4) for y in (0, 0.3) for z in (0, 0.2)]) - 0.1, 1e-12)
    lo, hi = np.zeros(3), np.array([1.0, 0.5, 0.7])
    verdicts = []
    for _ in range(150):
        turn = eq9_rotation(*rng.uniform(-np.pi, np.pi, 3))
        at = rng.uniform(-0.5, 1.5, 3)
        vertices = at + cube.vertices @ turn.T
        gap = box_separation(vertices, cube.normals @ turn.T, cube.edges @ turn.T, lo, hi)
        k = len(vertices)
        lp = linprog(np.zeros(k), A_ub=np.vstack([vertices.T, -vertices.T]), b_ub=np.concatenate([hi, -lo]),
                     A_eq=np.ones((1, k)), b_eq=[1.0], bounds=[(0, None)] * k, method="highs")
        if abs(gap) > 1e-9:
            verdicts.append((gap < 0, lp.status == 0))
    assert all(sat == lp for sat, lp in verdicts) and 20 < sum(sat for sat, _ in verdicts) < len(verdicts) - 20


def _cpr8_with(make_cfg, catalogue, *overrides):
    cfg = make_cfg(*overrides)
    cfg, problem = validate(cfg, catalogue, typed=True)
    return problem, build_problem(cfg, catalogue)[1]


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.5, -0.4, 0.6)])
def test_cable_platform_against_sampled_cables(make_cfg, catalogue, orientation):
    """A cable enters the carrier (its box, the attachments at its corners) exactly when points
    of it just past its attachment lie inside the box."""
    from pipeline.workspace.criteria.interference import cable_platform

    psi, theta, phi = orientation
    problem, grid = _cpr8_with(make_cfg, catalogue, "robot.platform.shape=hull", "grid.n=8", f"orientation.psi={psi}",
                               f"orientation.theta={theta}", f"orientation.phi={phi}")
    robot = problem.robot
    state = PoseGeometry(robot, grid[:], problem.orientation)
    margin = cable_platform(state, None)
    half = np.abs(robot.attachments).max(axis=0)
    local = (robot.anchors[None] - state.attachment_points) @ state.rotation  # platform frame, from b_i
    t = np.geomspace(1e-6, 1.0, 200)[:, None, None, None]
    inside = (np.abs(robot.attachments[None, None] + t * local[None]) < half - 1e-9).all(axis=-1).any(axis=(0, 2))
    assert np.array_equal(margin < 0, inside)
    assert inside.any() == (orientation != (0.0, 0.0, 0.0))  # level, every cable leaves the carrier outwards


def test_cable_obstacle_against_sampled_cables_and_the_platforms_corners(make_cfg, catalogue):
    """A tilted floor under the tilted CPR-8 carrier: the margin is the exact least clearance of
    the cables (less their radius) and the carrier's corners, over the robot's extent. A table
    beside it: every pose where sampled points of a cable lie inside it has a negative margin,
    the table named as the closest obstacle."""
    from pipeline.workspace.criteria.interference import cable_obstacle, obstacle_pairs

    floor = "{name: floor, point: [0, 0, -1.9], normal: [0, 0.1, 1]}"
    table = "{name: table, lo: [1.2, 0.6, -3], hi: [2.2, 1.4, -1.5]}"
    common = ["grid.n=7", "orientation.psi=0.3", "orientation.theta=-0.2", "robot.cable_diameter=0.02",
              "robot.platform.shape=hull"]
    problem, grid = _cpr8_with(make_cfg, catalogue, *common, f"obstacles=[{floor}]")
    robot = problem.robot
    state = PoseGeometry(robot, grid[:], problem.orientation)
    margin = cable_obstacle(state, None)
    plane = robot.obstacles[0]
    ends = np.stack([np.broadcast_to(robot.anchors, state.attachment_points.shape), state.attachment_points])
    cables = ((ends - plane.point) @ plane.normal).min(axis=0) - 0.01  # a segment is lowest at an end
    corners = state.positions[:, None, :] + robot.attachments @ state.rotation.T
    exact = np.minimum(cables.min(axis=1), ((corners - plane.point) @ plane.normal).min(axis=1)) / robot.extent
    np.testing.assert_allclose(margin, np.minimum(exact, 1.0), rtol=0, atol=1e-12)
    assert (margin < 0).any() and (margin > 0).any()
    # a lower cable ends at a lower corner of the carrier, one radius nearer the floor than the corner itself
    assert {obstacle_pairs(robot)[k] for k in state.closest_obstacle} <= {"floor: k'", "floor: h'", "floor: m'", "floor: n'"}

    problem, grid = _cpr8_with(make_cfg, catalogue, *common, f"obstacles=[{floor}, {table}]")
    robot = problem.robot
    state = PoseGeometry(robot, grid[:], problem.orientation)
    margin = cable_obstacle(state, None)
    s = np.linspace(0, 1, 2001)[:, None, None, None]
    points = robot.anchors[None, None] + s * (state.attachment_points - robot.anchors)[None]  # (s, n, m, 3)
    depth = point_box_distance(points, robot.obstacles[1].lo, robot.obstacles[1].hi)[1].max(axis=0)
    hits = (depth > 1e-3).any(axis=1)
    assert hits.sum() > 10 and (margin[hits] < 0).all()
    named = [obstacle_pairs(robot)[k] for k in state.closest_obstacle[hits]]
    assert all(name.startswith("table: ") or margin[hits][i] <= exact[hits][i] for i, name in enumerate(named))


@pytest.mark.parametrize("extra", [["robot.platform.shape=hull", "robot.cable_diameter=0.01",
                                    "obstacles=[{name: table, lo: [1, 0.5, -2.5], hi: [2, 1.5, -1.6]}]"]])
@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.5, 0.5, 0.5)])
def test_numpy_and_compiled_kernels_give_the_same_platform_and_obstacle_margins(make_cfg, catalogue, extra,
                                                                                  orientation):
    psi, theta, phi = orientation
    tables = {}
    for kernel in ("numpy", "fused"):
        cfg = make_cfg(*extra, "grid.n=10", f"compute.kernel={kernel}", f"orientation.psi={psi}",
                       f"orientation.theta={theta}", f"orientation.phi={phi}")
        cfg, _ = validate(cfg, catalogue, typed=True)
        tables[kernel] = compute_workspace(cfg, catalogue)[0]
    for column in ("margin_cable_platform", "margin_cable_obstacle", "closest_obstacle", "limiting", "feasible"):
        assert tables["numpy"][column].tolist() == tables["fused"][column].tolist()
    assert (tables["numpy"]["limiting"] == "cable_obstacle").any()


def test_the_irpm_plate_cables_and_a_floor(make_cfg, catalogue):
    """The IRPM (Z down from the base): at gamma = 0 its cables share anchors and attachments in
    pairs, which are not compared (9 of 15 pairs left); a plate below the attachments (towards +Z)
    lets every cable leave it upwards, one above them (towards the base) is crossed by all of them;
    a floor at Z = 9 m (normal up, -Z) removes the poses whose platform reaches past it."""
    common = ["robot=irpm6", "robot.gamma_deg=0", "robot.cable_diameter=0.05", "robot.search.step=1",
              "obstacles=[{name: floor, point: [0, 0, 9], normal: [0, 0, -1]}]"]
    tables = {}
    for side, (lo, hi) in {"below": (0, 0.1), "above": (-0.1, 0)}.items():
        cfg, problem = validate(make_cfg(*common, f"robot.platform.shape={{lo:[-1.3,-1.3,{lo}],hi:[1.3,1.3,{hi}]}}"),
                                catalogue, typed=True)
        tables[side] = compute_workspace(cfg, catalogue)[0]
    assert len(problem.robot.cable_pairs[0]) == 9
    level = tables["below"]["z"] < 1e-9  # in the base's plane the cables run along the plate: margin 0
    assert (tables["below"]["margin_cable_platform"] >= 0).all()
    assert (tables["below"].loc[~level, "margin_cable_platform"] > 0).all()
    assert (tables["above"].loc[~level, "margin_cable_platform"] < 0).all()
    below = tables["below"]
    reaches = below["z"] > 9 - 1e-9  # the plate's lowest face is 0.1 m below the reference point
    assert (below.loc[reaches, "margin_cable_obstacle"] < 0).all() and (below.loc[~reaches & (below["z"] < 8.5),
                                                                                  "margin_cable_obstacle"] > 0).all()

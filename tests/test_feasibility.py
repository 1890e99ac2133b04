"""The fast verdict (issue 58): the null-space test against an independent LP, and
``feasible_flags`` against the registry's verdicts pose by pose."""

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import CROSSED_ROBOT, SPREAD_ROBOT
from pipeline.app.problem import build_problem
from pipeline.workspace.feasibility import feasible_flags, null_space_verdicts
from pipeline.workspace.kernel import evaluate_chunk
from pipeline.workspace.verdict import classify


def lp_margin(structure, wrench, lower, upper):
    """max s with S x = w, lower + s <= x <= upper - s (an LP of its own: HiGHS), or -inf."""
    r, m = structure.shape
    a_ub = np.block([[-np.eye(m), np.ones((m, 1))], [np.eye(m), np.ones((m, 1))]])
    b_ub = np.concatenate([-lower, upper])
    result = linprog(np.r_[np.zeros(m), -1.0], A_ub=a_ub, b_ub=b_ub, A_eq=np.c_[structure, np.zeros(r)], b_eq=wrench,
                     bounds=[(None, None)] * m + [(None, 10.0)], method="highs")
    return -result.fun if result.status == 0 else -np.inf


@pytest.mark.parametrize("t_min", [1.0, 0.0])
@pytest.mark.parametrize("r, m", [(6, 6), (6, 7), (6, 8), (6, 9), (3, 4), (3, 5), (2, 4)])
def test_the_null_space_verdict_equals_an_lp_on_random_structure_matrices(r, m, t_min):
    """Random S with unit columns and moment rows at the platform's scale, random wrenches: the
    verdict of every decided pose is the LP's (poses within 1e-7 of the boundary excluded, where
    either may round), and about half the poses are feasible, so both answers are exercised; with
    forces in [1, 10] and in [0, 10] (a vertex on a zero bound misses it by its round-off)."""
    rng = np.random.default_rng(r * 10 + m)
    n = 600
    structure = rng.normal(size=(n, r, m))
    structure[:, r // 2:] *= 0.1
    spread = rng.uniform(0.0, 14.0, (n, m)) - rng.uniform(0.0, 4.0, (n, 1))  # forces some of them outside [1, 10]
    wrenches = np.einsum("nrm,nm->nr", structure, spread)[:, None, :]
    lower, upper = np.full(m, t_min), np.full(m, 10.0)
    verdicts = null_space_verdicts(structure, wrenches, lower, upper)
    margin = np.array([lp_margin(structure[p], wrenches[p, 0], lower, upper) for p in range(n)])
    clear = np.abs(margin) > 1e-7
    decided = verdicts >= 0
    assert decided.mean() > 0.99
    assert 0.05 < (margin >= 0).mean() < 0.95
    np.testing.assert_array_equal(verdicts[clear & decided] == 1, margin[clear & decided] >= 0)


def test_rank_short_and_wide_null_spaces_are_left_to_the_exact_model():
    rng = np.random.default_rng(3)
    short = rng.normal(size=(5, 6, 8))
    short[:, 5] = short[:, 4]  # two equal rows: rank 5 of 6
    wide = rng.normal(size=(5, 3, 7))  # null space of dimension 4
    for structure in (short, wide):
        verdicts = null_space_verdicts(structure, np.zeros((5, 1, structure.shape[1])), np.ones(structure.shape[2]),
                                       np.full(structure.shape[2], 10.0))
        assert (verdicts == -1).all()


def registry_verdicts(problem, rows):
    raw = evaluate_chunk(problem, rows)
    return classify({name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)[1]


IPANEMA = ["robot=points", "robot.anchors=[[-2,1.5,2],[2,1.5,2],[2,-1.5,2],[-2,-1.5,2],[-2,1.5,0],[2,1.5,0],"
           "[2,-1.5,0],[-2,-1.5,0]]", "robot.attachments=[[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0],"
           "[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0]]", "robot.search.lo=[-2,-1.5,0]",
           "robot.search.hi=[2,1.5,2]", "robot.search.step=0.1", "robot.search.spacing=centres",
           "tension=feasible", "tension.t_min=1", "tension.t_max=10"]
CASES = {
    "IPAnema 1, [1, 10] N": IPANEMA,
    "off-centre payload, tilted": [*IPANEMA, "robot.search.step=0.25", "orientation.psi=0.3", "orientation.theta=-0.2",
                                   "load.mass=0.2", "load.com=[0.02,-0.01,0]", "tension.t_max=30"],
    "orientation set and wrench box": [*IPANEMA, "robot.search.step=0.4", "orientation.total.bound=0.1",
                                       "orientation.total.n=2", "wrench.set={min:[-1,-1,-2,0,0,0],max:[1,1,1,0,0,0]}",
                                       "tension.t_max=40"],
    "crossed, 50 kg, per-cable limits": [*CROSSED_ROBOT, "tension=feasible", "load.mass=50",
                                         "tension.t_min=[10,10,10,10,20,20,20,20]", "tension.t_max=800"],
    "spread, length and cable diameter": [*SPREAD_ROBOT, "tension=feasible", "load.mass=5", "tension.t_max=300",
                                          "robot.l_max=4", "robot.cable_diameter=0.02", "robot.search.step=0.25"],
    "planar point": ["robot=points", "robot.dofs=[x,y]", "robot.anchors=[[0,0,0],[3,0,0],[3,2,0],[0,2,0]]",
                     "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.search.lo=[0,0,0]",
                     "robot.search.hi=[3,2,0]", "robot.search.step=0.1", "tension=feasible", "tension.t_min=1",
                     "tension.t_max=10", "wrench.fy=-3"],
    "collinear anchors: a freedom of round-off": [  # rows of 1e-16 at x = 0, which scaling would inflate
        "robot=points", "robot.dofs=[x,y]", "robot.anchors=[[0,1,0],[0,0,0],[0,-1,0]]",
        "robot.attachments=[[0,0,0],[0,0,0],[0,0,0]]", "robot.search.lo=[-0.9,-0.9,0]", "robot.search.hi=[0.9,0.9,0]",
        "robot.search.step=0.15", "tension=feasible", "tension.t_min=1", "tension.t_max=10", "wrench.fy=-3"],
    "cables that may go slack (t_min = 0), tilted, off-centre payload": [  # a vertex on a zero bound: its round-off
        *CROSSED_ROBOT, "tension=feasible", "tension.t_min=0", "tension.t_max=150", "load.mass=3",
        "load.com=[0.04,-0.03,0.02]", "orientation.psi=0.1", "orientation.theta=-0.08", "orientation.phi=0.25",
        "robot.search.step=0.1"],
    "minimum-norm forces (the registry alone)": [*SPREAD_ROBOT, "robot.search.step=0.25", "load.mass=5",
                                                 "tension.t_max=300"],
}


@pytest.mark.parametrize("case", CASES)
def test_fast_flags_equal_the_registry_verdicts_pose_by_pose(make_cfg, catalogue, case):
    problem, grid = build_problem(make_cfg(*CASES[case]), catalogue)
    rows = grid[0:len(grid)]
    expected = registry_verdicts(problem, rows)
    np.testing.assert_array_equal(feasible_flags(problem, rows), expected)
    assert 0 < expected.sum() < len(rows)


@pytest.mark.parametrize("case", ["IPAnema 1, [1, 10] N", "orientation set and wrench box"])
def test_one_pose_at_a_time_gets_the_registry_verdict(make_cfg, catalogue, case):
    """A chunk of one pose (a broadcast wrench is then a read-only view the compiled test must not get)."""
    problem, grid = build_problem(make_cfg(*CASES[case]), catalogue)
    rows = grid[0:len(grid)]
    expected = registry_verdicts(problem, rows)
    held, failed = np.flatnonzero(expected), np.flatnonzero(~expected)
    assert len(held) and len(failed)
    picked = np.concatenate([found[np.linspace(0, len(found) - 1, min(30, len(found))).astype(int)] for found in (held, failed)])
    assert [bool(feasible_flags(problem, rows[k:k + 1])[0]) for k in picked] == expected[picked].tolist()


def test_ipanema_fast_count_is_the_readme_count(make_cfg, catalogue):
    problem, grid = build_problem(make_cfg(*IPANEMA), catalogue)
    assert int(feasible_flags(problem, grid[0:len(grid)]).sum()) == 9752


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_fast_flags_equal_the_registry_on_random_robots(make_cfg, catalogue, seed):
    """Random 7- to 9-cable robots (anchors in a 4 m cube, attachments on a 0.3 m platform), a
    random load at a random tilt, random per-cable limits: the same verdict pose by pose."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(7, 10))
    anchors = np.round(rng.uniform(-2, 2, (m, 3)) + [0, 0, 2], 3).tolist()
    attachments = np.round(rng.uniform(-0.15, 0.15, (m, 3)), 3).tolist()
    angles = np.round(rng.uniform(-0.3, 0.3, 3), 3)
    problem, grid = build_problem(make_cfg(
        "robot=points", f"robot.anchors={anchors}", f"robot.attachments={attachments}", "robot.search.lo=[-1,-1,1]",
        "robot.search.hi=[1,1,3]", "robot.search.step=0.2", "tension=feasible",
        f"tension.t_min={np.round(rng.uniform(0.5, 5, m), 2).tolist()}", f"tension.t_max={float(rng.uniform(150, 600)):.1f}",
        f"load.mass={float(rng.uniform(1, 20)):.2f}", f"load.com={np.round(rng.uniform(-0.05, 0.05, 3), 3).tolist()}",
        f"orientation.psi={angles[0]}", f"orientation.theta={angles[1]}", f"orientation.phi={angles[2]}"), catalogue)
    rows = grid[0:len(grid)]
    expected = registry_verdicts(problem, rows)
    np.testing.assert_array_equal(feasible_flags(problem, rows), expected)
    assert 0 < expected.sum() < len(rows)


KEYS = {  # a key of the statics each: the fast flags meet it through the registry's families and margins
    "acceleration box": ["robot.platform.mass=2", "platform_motion.acceleration={min:[-2,-2,-2,0,0,0],max:[2,2,2,0,0,0]}"],
    "spinning platform": ["robot.platform.mass=2", "robot.platform.inertia=[0.1,0.1,0.2]",
                          "platform_motion.acceleration=[[1,0,0,0,0,3]]", "platform_motion.angular_velocity=[0,0,2]"],
    "sag rule": ["robot.cable_mass=0.05", "+criteria.sag={ratio: 0.02}", "load.mass=3"],
    "stiffness": ["robot.cable_ea=1e4", "+criteria.stiffness={translational: 5000, rotational: 10, frequency: 0}",
                  "load.mass=3"],
    "cable length": ["robot.l_max=3.0", "wrench.fz=-20"],
    "pulleys": ["robot.pulleys={axis: [0,0,-1], radius: 0.05}", "load.mass=3"],
}


@pytest.mark.parametrize("key", KEYS)
def test_fast_flags_meet_every_statics_key(make_cfg, catalogue, key):
    problem, grid = build_problem(make_cfg(*CROSSED_ROBOT, "tension=feasible", "tension.t_min=1", "tension.t_max=300",
                                           *KEYS[key]), catalogue)
    rows = grid[0:len(grid)]
    expected = registry_verdicts(problem, rows)
    np.testing.assert_array_equal(feasible_flags(problem, rows), expected)
    assert 0 < expected.sum() < len(rows)

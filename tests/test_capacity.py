"""Hyperplane shifting (pipeline.model.capacity) against the LPs it replaces (issue 17): the same
capacity margins, hence the same verdicts, on the paper's grid, on the IRPM and on a fuzz of
random robots, poses and limits; the LP fallback where the structure is poorly conditioned.

Tolerance: margins agree within MARGIN_ATOL (dimensionless, in units of each family's scale);
HiGHS's own primal feasibility tolerance (1e-7) is the larger of the two errors. Verdicts are
compared outside that band around zero."""

import logging

import numpy as np
import pytest

from pipeline.model.capacity import shifted_margins
from pipeline.model.geometry import structure_matrix
from pipeline.model.linalg import batched_pinv
from pipeline.model.tensions import Family, capacity_margins, reachability
from pipeline.app.problem import build_problem
from pipeline.workspace.criteria import force_families
from conftest import compute_workspace

MARGIN_ATOL = 1e-6


def both_ways(structure, wrenches, families, rtol=1e-9):
    """(fast margins, LP margins, poses the fast path sent to the LP)."""
    pinv, rank = batched_pinv(structure, rtol)
    _, projected = reachability(structure, pinv, wrenches)
    fast, _, by_lp = capacity_margins(structure, pinv, rank, projected, families)
    exact, _, _ = capacity_margins(structure, pinv, rank, projected, families, distribution=True)
    return fast, exact, by_lp


def assert_same(fast, exact):
    for name in exact:
        np.testing.assert_allclose(fast[name], exact[name], rtol=0, atol=MARGIN_ATOL, err_msg=name)
    clear = np.all([np.abs(v) > MARGIN_ATOL for v in exact.values()], axis=0)
    verdict = np.all([v >= 0 for v in exact.values()], axis=0)
    assert (np.all([v >= 0 for v in fast.values()], axis=0) == verdict)[clear].all()


@pytest.mark.parametrize("columns", ["translational", "full"])
@pytest.mark.parametrize("angle", [0.0, 0.5])
def test_paper_grid_every_actuator_gives_the_lp_margins(columns, angle, make_cfg, catalogue):
    """Section 3.1's 6^3 grid, Table 1's five actuators, both readings of eq. (20)'s columns,
    zero and 0.5 rad about every axis: every family's margin at every acceleration vertex."""
    fallbacks = total = 0
    for actuator in range(1, 6):
        cfg = make_cfg("tension=feasible", f"actuator={actuator}", f"model.pinv_columns={columns}",
                       *(f"orientation.{a}={angle}" for a in ("psi", "theta", "phi")))
        problem, grid = build_problem(cfg, catalogue)
        state = problem.spec.state(problem.robot, grid[:], problem.orientation)
        fast, exact, by_lp = both_ways(state.structure, state.required_wrenches,
                                       force_families(state, problem.limits))
        assert_same(fast, exact)
        fallbacks, total = fallbacks + by_lp.sum(), total + len(by_lp)
    assert fallbacks <= 0.01 * total


@pytest.mark.parametrize("gamma", [0.0, 30.0])
def test_irpm_six_normals_per_pose_give_its_closed_form(gamma, make_cfg, catalogue):
    """The IRPM's A (6 x 6) has a unique x = A^-1 w: the capacity margins are closed forms.
    The general method on the same poses (q = 6: 12 normals from 5 x 5 cofactors) agrees."""
    problem, grid = build_problem(make_cfg("robot=irpm6", f"robot.gamma_deg={gamma}",
                                           "tension=feasible", "tension.t_min=100"), catalogue)
    state = problem.spec.state(problem.robot, grid[:][::7], problem.orientation)
    bounded = force_families(state, problem.limits)
    pinv, rank = batched_pinv(state.structure, 1e-9)
    full = rank == 6
    assert full.mean() > 0.9
    _, projected = reachability(state.structure, pinv, state.required_wrenches)
    closed, _, _ = capacity_margins(state.structure[full], pinv[full], rank[full], projected[full],
                                    bounded)
    shifted, unsettled = shifted_margins(state.structure[full], projected[full], bounded)
    assert not unsettled.any()
    assert_same(shifted, closed)
    assert (closed["slack"] < 0).any() and (closed["slack"] > 0).any()


def random_problems(rng, rows, cables, count, k=3):
    """``count`` random robots and poses with ``cables`` cables, their structure matrices
    (count, rows, cables), required wrenches (count, k, rows) and three nested families:
    slack t >= t_min > 0, a finite rating, and a symmetric motor box |t| <= T."""
    anchors = rng.uniform(-2.0, 2.0, (count, cables, 3))
    attachments = rng.uniform(-0.3, 0.3, (count, cables, 3))
    positions = rng.uniform(-0.8, 0.8, (count, 1, 3))
    vectors = positions + attachments - anchors
    unit = vectors / np.linalg.norm(vectors, axis=2, keepdims=True)
    structure = structure_matrix(unit, attachments)[:, :rows]
    t_min = rng.uniform(0.1, 1.0, (count, 1, cables))
    t_max = t_min + rng.uniform(1.0, 20.0, (count, 1, 1))
    motor = t_max * rng.uniform(0.5, 2.0, (count, 1, 1))
    wrenches = rng.normal(size=(count, k, rows)) * rng.uniform(0.0, 0.5 * cables, (count, 1, 1))
    families = [Family("slack", t_min, np.inf, t_max), Family("tension_max", -np.inf, t_max, t_max),
                Family("torque", -motor, motor, motor)]
    return structure, wrenches, families


def test_fuzz_of_random_robots_poses_and_limits_gives_the_lp_margins():
    """1 080 random robots (4 to 10 cables, forces only or forces and moments), each at a random
    pose with three random wrenches and random per-cable limits (t_min > 0, finite t_max)."""
    rng = np.random.default_rng(17)
    cases = [(3, m) for m in range(4, 11)] + [(6, m) for m in (7, 8, 9)]
    feasible = total = 0
    for rows, cables in cases:
        structure, wrenches, families = random_problems(rng, rows, cables, 108)
        fast, exact, by_lp = both_ways(structure, wrenches, families)
        assert_same(fast, exact)
        assert by_lp.mean() < 0.05
        feasible += np.all([v >= 0 for v in exact.values()], axis=0).sum()
        total += exact["slack"].size
    assert 0.1 < feasible / total < 0.9  # the fuzz reaches both verdicts


def test_wrench_dependent_bounds_and_coincident_cables_give_the_lp_margins():
    """The compiled search's other paths, against the LPs: a middle family whose bounds change
    with the wrench (like the voltage's), so the later one is searched wrench by wrench and
    infeasible poses relax it by each wrench's own margin; and robots whose first two cables
    coincide (their subsets span no facet). Forces only (normals in wrench space, or through
    the null space for 4 cables) and forces and moments (through the null space)."""
    rng = np.random.default_rng(29)
    verdicts = []
    for rows, cables in [(3, 4), (3, 6), (3, 8), (6, 8), (6, 9)]:
        structure, wrenches, (slack, rating, _) = random_problems(rng, rows, cables, 120)
        structure[::2, :, 1] = structure[::2, :, 0]
        motor = rating.upper * rng.uniform(0.3, 2.0, (120, 3, 1))  # one box per wrench
        families = [slack, Family("torque", -motor, motor, motor), rating]
        fast, exact, by_lp = both_ways(structure, wrenches, families)
        assert_same(fast, exact)
        assert by_lp.mean() < 0.05
        verdicts += [np.all([v >= 0 for v in exact.values()], axis=0)]
        assert (exact["slack"] < 0).any() and (exact["torque"] < 0).any()
    assert 0.05 < np.concatenate(verdicts).mean() < 0.95


def test_poorly_conditioned_poses_go_to_the_lp_and_are_counted(make_cfg, catalogue, caplog):
    """Nearly dependent rows: the structure matrix keeps its rank (gram ratio 1.5e-8 to 2.5e-7,
    above model.rank_rtol) but its zonotope is nearly flat, below tensions.HSM_MIN_GRAM, so
    the LP decides and agrees; the job's log counts such poses."""
    rng = np.random.default_rng(3)
    structure, wrenches, families = random_problems(rng, 3, 5, 40)
    structure[:20, 2] = structure[:20, 0] + 3e-4 * structure[:20, 2]
    fast, exact, by_lp = both_ways(structure, wrenches, families)
    assert by_lp[:20].all() and not by_lp[20:].any()
    assert_same(fast, exact)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        compute_workspace(make_cfg("tension=feasible", "model.pinv_columns=full"), catalogue)
    assert any("poses by LP" in record.getMessage() for record in caplog.records)


def test_a_pose_the_lp_cannot_solve_keeps_its_hyperplane_shifting_margins(monkeypatch):
    """HiGHS has declared such LPs infeasible (rows dependent to 1e-4 give some). The LPs are
    then solved one pose at a time; a pose whose own LP fails keeps its hyperplane-shifting
    margins, is not counted as solved by LP, and the job goes on. Here HiGHS is made to fail
    on one chosen pose, so that the path is taken on every machine."""
    import pipeline.model.tensions as tensions

    rng = np.random.default_rng(3)
    structure, wrenches, families = random_problems(rng, 3, 5, 40)
    structure[:20, 2] = structure[:20, 0] + 3e-4 * structure[:20, 2]
    pinv, rank = batched_pinv(structure, 1e-9)
    _, projected = reachability(structure, pinv, wrenches)
    reference, _, _ = capacity_margins(structure, pinv, rank, projected, families, distribution=True)
    solve = tensions._nested_lps

    def failing(part, *args):
        if any(np.array_equal(s, structure[7]) for s in part):
            raise RuntimeError("tension LP for 'slack' failed: The problem is infeasible.")
        return solve(part, *args)

    monkeypatch.setattr(tensions, "_nested_lps", failing)
    fast, _, by_lp = capacity_margins(structure, pinv, rank, projected, families)
    assert not by_lp[7] and by_lp[:20].sum() >= 15 and not by_lp[20:].any()
    assert_same(fast, reference)  # pose 7's shifted margins included
    with pytest.raises(RuntimeError, match="infeasible"):  # no margins to keep: the failure shows
        capacity_margins(structure, pinv, rank, projected, families, distribution=True)


@pytest.mark.parametrize("rows", [1, 2])
def test_one_and_two_freedom_platforms_give_the_lp_margins(rows):
    """A platform of one freedom (robot.dofs=[z] or [rz]: one row, the normals are +-1 from the
    empty subset of columns) crashed the search ("cannot reshape array of size 0"); one and two
    rows against the LPs on random robots of 2 to 5 cables."""
    rng = np.random.default_rng(41 + rows)
    verdicts = []
    for cables in range(2, 6):
        structure, wrenches, families = random_problems(rng, rows, cables, 60)
        fast, exact, by_lp = both_ways(structure, wrenches, families)
        assert_same(fast, exact)
        assert by_lp.mean() < 0.05
        verdicts.append(np.all([v >= 0 for v in exact.values()], axis=0))
    assert 0.05 < np.concatenate(verdicts).mean() < 0.95

"""The tensions a user reads (``output.cables=true`` under ``tension=feasible``): by default the
least 2-norm distribution within the limits (``tension.distribution=min_norm``, as CASPR and
WireX give them), on a tilted, off-centre loaded platform: within the limits exactly, balancing
the load, and optimal by an independent certificate (multipliers of the KKT conditions found by
an LP); ``lp`` keeps the LPs' vertex."""

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import SPREAD_ROBOT
from pipeline.app.problem import build_problem, compute_workspace

ROBOT = [*SPREAD_ROBOT, "robot.search.step=0.25",
         "robot.platform.mass=4", "robot.platform.com=[0.02,-0.01,-0.04]", "orientation.psi=0.05",
         "orientation.phi=-0.1", "tension=feasible", "tension.t_min=1", "tension.t_max=250", "output.cables=true"]
NAMES = [f"tension_{i}" for i in range(1, 9)]


@pytest.fixture(scope="module")
def runs(make_cfg, catalogue):
    return {d: compute_workspace(make_cfg(*ROBOT, f"tension.distribution={d}"), catalogue) for d in ("min_norm", "lp")}


def test_the_written_tensions_are_the_least_norm_ones_within_the_limits(runs, make_cfg, catalogue):
    points, _ = runs["min_norm"]
    problem, _ = build_problem(make_cfg(*ROBOT), catalogue)
    feasible = points[points["feasible"]]
    assert len(feasible) >= 10
    state = problem.spec.state(problem.robot, feasible[["x", "y", "z"]].to_numpy(), problem.orientation)
    tensions = feasible[NAMES].to_numpy()
    assert (tensions >= 1).all() and (tensions <= 250).all()  # exactly, no tolerance
    balance = np.einsum("nrm,nm->nr", state.structure_matrix, tensions) - state.wrench
    assert np.abs(balance).max() < 1e-6 * np.linalg.norm(state.wrench)
    for a, t in zip(state.structure_matrix, tensions):
        assert kkt_holds(a, t, 1.0, 250.0)


def kkt_holds(a, t, low, high, tolerance=1e-6):
    """t minimises |t|^2 / 2 over A t = w, low <= t <= high iff t = A^T l + v for some l with
    v_i >= 0 where t_i is at its lower bound, v_i <= 0 at its upper bound, v_i = 0 between (the
    problem is convex): an LP in (l, v) decides whether such multipliers exist."""
    rows, m = a.shape
    scale = max(1.0, np.abs(t).max())
    at_low, at_high = t <= low + tolerance * scale, t >= high - tolerance * scale
    bounds = [(None, None)] * rows + [(0, None) if lo else (None, 0) if hi else (-tolerance * scale, tolerance * scale)
                                      for lo, hi in zip(at_low, at_high)]
    found = linprog(np.zeros(rows + m), A_eq=np.hstack([a.T, np.eye(m)]), b_eq=t, bounds=bounds, method="highs")
    return found.status == 0


def test_the_lps_vertex_is_another_valid_distribution_with_a_larger_norm_and_the_same_verdicts(runs):
    least, _ = runs["min_norm"]
    vertex, _ = runs["lp"]
    assert least["feasible"].tolist() == vertex["feasible"].tolist()
    held = least["feasible"].to_numpy()
    norms = np.linalg.norm(least.loc[held, NAMES].to_numpy(), axis=1)
    other = np.linalg.norm(vertex.loc[held, NAMES].to_numpy(), axis=1)
    assert (norms <= other * (1 + 1e-6)).all() and (norms < other * (1 - 1e-3)).any()  # HiGHS's QP tolerance


def test_the_certificate_rejects_a_valid_distribution_that_is_not_the_least(runs, make_cfg, catalogue):
    """The LPs' vertex balances the load within the limits but, where its norm is larger, the
    KKT certificate says it is not the least (so the check above can fail)."""
    least, _ = runs["min_norm"]
    vertex, _ = runs["lp"]
    held = least["feasible"].to_numpy()
    larger = held & (np.linalg.norm(vertex[NAMES], axis=1) > np.linalg.norm(least[NAMES], axis=1) * (1 + 1e-3))
    problem, _ = build_problem(make_cfg(*ROBOT), catalogue)
    poses = vertex.loc[larger, ["x", "y", "z"]].to_numpy()
    state = problem.spec.state(problem.robot, poses, problem.orientation)
    verdicts = [kkt_holds(a, t, 1.0, 250.0) for a, t in zip(state.structure_matrix, vertex.loc[larger, NAMES].to_numpy())]
    assert len(verdicts) > 0 and not any(verdicts)

"""The tensions a user reads (``output.cables=true`` under ``tension=feasible``): by default the
least 2-norm distribution within the limits (``tension.distribution=min_norm``, as CASPR and
WireX give them), on a tilted, off-centre loaded platform: within the limits exactly, balancing
the load, and optimal by an independent certificate (multipliers of the KKT conditions found by
an LP); ``lp`` keeps the LPs' vertex."""

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import SPREAD_ROBOT, compute_workspace
from pipeline.app.problem import build_problem
from pipeline.model import distribution
from pipeline.model.distribution import face_distribution, min_norm_tensions, qp_distribution
from pipeline.model.linalg import batched_pinv
from pipeline.model.tensions import Family, feasible_tensions

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


@pytest.mark.parametrize("m, r, dependent", [(4, 3, False), (5, 3, False), (6, 3, False), (8, 6, False), (9, 6, False),
                                             (8, 6, True), (4, 2, False)])
def test_the_enumeration_of_faces_is_the_qp_optimum_and_finds_a_distribution_where_the_lps_do(m, r, dependent):
    """Random structure matrices with null spaces of 1 to 3 dimensions (3 where a dependent row
    drops the rank), two wrenches a pose, some cables without a rating, non-unit weights (the
    CPR-8's torques): the enumeration (pipeline.model.faces) against HiGHS's convex QP from the
    LPs' start, and its verdict against the LPs' margins."""
    rng = np.random.default_rng(m * 10 + r + dependent)
    n = 200
    structure = rng.normal(size=(n, r, m))
    if dependent:
        structure[:, -1] = structure[:, 0] - 2 * structure[:, 1]
    inside = rng.uniform(1.2, 2.3, size=(n, 2, m))
    wrenches = np.einsum("nrm,nkm->nkr", structure, inside) * rng.uniform(0.8, 1.6, size=(n, 2, 1))
    lower, upper = np.ones((n, 2, m)), np.full((n, 2, m), 2.5)
    upper[: n // 4] = np.inf
    weights = rng.uniform(0.5, 2.0, size=m)
    pinv, rank = batched_pinv(structure, 1e-9)
    assert (rank == r - dependent).all()
    x, found = face_distribution(structure, wrenches, lower, upper, weights, rank, 1e-6)
    families = [Family("slack", lower, np.inf, 1.0), Family("tension_max", -np.inf, upper, 1.0)]
    margins, residual, start, _ = feasible_tensions(structure, pinv, rank, wrenches, families, distribution=True)
    reference = qp_distribution(structure, wrenches, lower, upper, weights, start, 1e-6)
    holds = np.all([margins[name] >= -1e-9 for name in ("slack", "tension_max")], axis=0) & (residual <= 1e-6)
    assert 0.1 < found.all(axis=1).mean() < 0.9
    assert (found.all(axis=1) == holds).all()
    ours, theirs = (np.linalg.norm(t * weights, axis=2)[found] for t in (x, reference))
    assert (ours <= theirs * (1 + 1e-9)).all()
    assert np.abs(x - reference)[found].max() < 1e-6 * np.abs(reference[found]).max()
    assert ((x >= lower) & (x <= upper))[found].all()
    assert np.isnan(x[~found]).all()


def test_a_pose_beyond_the_enumeration_gets_the_same_tensions_from_highs(monkeypatch):
    """With no active set allowed, every pair goes the HiGHS route (the LPs' start, then the
    QP): the same least-norm tensions; where the limits admit none, both write the LPs' x (of
    those poses: an LP's optimal vertex is not unique, so it is compared on the same batch)."""
    rng = np.random.default_rng(7)
    n, r, m = 60, 3, 5
    structure = rng.normal(size=(n, r, m))
    wrenches = np.einsum("nrm,nm->nr", structure, rng.uniform(1.2, 2.3, size=(n, m)))[:, None] * rng.uniform(
        0.8, 1.6, size=(n, 1, 1))
    families = [Family("slack", 1.0, np.inf, 1.0), Family("tension_max", -np.inf, 2.5, 2.5)]
    pinv, rank = batched_pinv(structure, 1e-9)
    weights = np.ones(m)
    enumerated = min_norm_tensions(structure, pinv, rank, wrenches, families, weights, 1e-6)
    held = face_distribution(structure, wrenches, 1.0, 2.5, weights, rank, 1e-6)[1][:, 0]
    monkeypatch.setattr(distribution, "MAX_ACTIVE_SETS", 0)
    solved = min_norm_tensions(structure, pinv, rank, wrenches, families, weights, 1e-6)
    rest = ~held
    lps = feasible_tensions(structure, pinv, rank, wrenches, families, distribution=True)[2]
    lps_rest = feasible_tensions(structure[rest], pinv[rest], rank[rest], wrenches[rest], families,
                                 distribution=True)[2]
    assert 0 < held.sum() < n
    assert np.abs(enumerated - solved)[held].max() < 1e-6
    assert np.array_equal(enumerated[rest], lps_rest) and np.array_equal(solved[rest], lps[rest])


@pytest.mark.parametrize("lower, upper", [(np.inf, 10.0), (0.0, -np.inf), ([[[0.0, np.inf, 1.0, 1.0]]], np.inf)])
def test_a_bound_no_tension_meets_is_refused_not_read_as_no_side(lower, upper):
    """The LP rows keep a family's finite sides only: a least tension that overflowed to +inf
    (criteria.cable_frequency at 1e300 Hz) read as no floor, and 39.6 % of IPAnema 1's poses
    held it. The family refuses such a bound where it is made."""
    with pytest.raises(ValueError, match="criterion floor: a tension bound of"):
        Family("floor", np.asarray(lower), np.asarray(upper), 1.0)

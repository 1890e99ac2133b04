"""Per-pose metrics (output.metrics=true): the largest wrench along each freedom against a plain LP
written here from the points (cables that only pull), against the minimum-norm tensions pushed to
their limits (pinv), and the tension factor against the tensions the job writes."""

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog

from pipeline.app.problem import validate
from conftest import compute_workspace
from pipeline.errors import ConfigError

ANCHORS = np.array([[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2], [-2, 1.5, 0], [2, 1.5, 0], [2, -1.5, 0],
                    [-2, -1.5, 0]], dtype=float)
PLATFORM = np.array([[-0.1, 0.1, 0.05], [0.1, 0.1, -0.05], [0.1, -0.1, 0.05], [-0.1, -0.1, -0.05],
                     [-0.1, 0.1, -0.05], [0.1, 0.1, 0.05], [0.1, -0.1, -0.05], [-0.1, -0.1, 0.05]])
MASS, COM = 3.0, (0.02, -0.01, 0.03)
ROBOT = ["robot=points", f"robot.anchors={ANCHORS.tolist()}", f"robot.attachments={PLATFORM.tolist()}",
         f"robot.platform.mass={MASS}", f"robot.platform.com=[{COM[0]},{COM[1]},{COM[2]}]",
         "robot.search.lo=[-1.5,-1,0.3]", "robot.search.hi=[1.5,1,1.7]", "robot.search.step=0.35",
         "robot.search.spacing=centres", "tension.t_min=5", "tension.t_max=150", "output.metrics=true"]
NAMES = ("fx", "fy", "fz", "mx", "my", "mz")


SIX = [0, 1, 2, 3, 5, 7]  # six of the cables: a square A, minimum-norm tensions all positive at 43 poses
ROBOT6 = [o for o in ROBOT if not o.startswith(("robot.anchors", "robot.attachments"))] + [
    f"robot.anchors={ANCHORS[SIX].tolist()}", f"robot.attachments={PLATFORM[SIX].tolist()}"]


def structure(position: np.ndarray, cables=slice(None)) -> np.ndarray:
    """A (6, m) of the level platform at ``position``, written out: columns [u; b x u] with u
    the unit vector from the attachment towards its anchor (a tension pulls that way), so that
    A t balances the external wrench the cables must hold, the platform's weight."""
    pull = ANCHORS[cables] - (position + PLATFORM[cables])
    pull /= np.linalg.norm(pull, axis=1, keepdims=True)
    return np.vstack([pull.T, np.cross(PLATFORM[cables], pull).T])


def weight() -> np.ndarray:
    force = np.array([0.0, 0.0, -MASS * 9.81])
    return -np.concatenate([force, np.cross(COM, force)])  # what the cables must supply


def lp_reach(a: np.ndarray, direction: np.ndarray) -> float:
    """max mu with A t = weight - mu direction (an extra external wrench mu direction on the
    platform: the cables supply its opposite), t in [5, 150] N; NaN where the weight alone
    (mu = 0) is not held, although a push along the direction might help."""
    alone = linprog(np.zeros(8), A_eq=a, b_eq=weight(), bounds=[(5, 150)] * 8, method="highs")
    if alone.status != 0:
        return np.nan
    cost = np.zeros(9)
    cost[8] = -1.0
    done = linprog(cost, A_eq=np.hstack([a, direction[:, None]]), b_eq=weight(),
                   bounds=[(5, 150)] * 8 + [(0, None)], method="highs")
    return done.x[8]


def test_the_largest_wrenches_of_pulling_cables_equal_a_plain_lp(make_cfg, catalogue):
    cfg, _ = validate(make_cfg(*ROBOT, "tension=feasible"), catalogue, typed=True)
    points = compute_workspace(cfg, catalogue)[0]
    assert 0 < points["feasible"].sum() < len(points)
    rng = np.random.default_rng(2)
    for k in rng.choice(len(points), size=25, replace=False):
        row = points.iloc[k]
        a = structure(row[["x", "y", "z"]].to_numpy(dtype=float))
        for j, name in enumerate(NAMES):
            for sign, column in ((1, f"wrench_max_{name}"), (-1, f"wrench_min_{name}")):
                unit = np.zeros(6)
                unit[j] = sign
                expected = lp_reach(a, unit)
                if np.isnan(expected):
                    assert np.isnan(row[column]) and not row["feasible"], (k, column)
                else:
                    assert sign * row[column] == pytest.approx(expected, rel=1e-6, abs=1e-6), (k, column)


def test_pinv_wrenches_push_the_minimum_norm_tensions_exactly_to_a_limit(make_cfg, catalogue):
    cfg, problem = validate(make_cfg(*ROBOT6, "tension=pinv", "tension.t_min=0"), catalogue, typed=True)
    points = compute_workspace(cfg, catalogue)[0]
    held = points[points["feasible"]]
    assert len(held) == 43 and points.loc[~points["feasible"], "wrench_max_fx"].isna().all()
    for _, row in held.iloc[::3].iterrows():
        a = structure(row[["x", "y", "z"]].to_numpy(dtype=float), SIX)
        pinv = np.linalg.pinv(a)
        for j, name in enumerate(NAMES):
            for sign, column in ((1, f"wrench_max_{name}"), (-1, f"wrench_min_{name}")):
                mu = sign * row[column]
                unit = np.zeros(6)
                unit[j] = sign
                at = pinv @ (weight() - mu * unit)  # the extra external wrench: the cables supply its opposite
                beyond = pinv @ (weight() - mu * (1 + 1e-6) * unit)
                assert (at >= -1e-6).all() and (at <= 150 + 1e-6).all()
                assert (beyond < -1e-9).any() or (beyond > 150 + 1e-9).any()


@pytest.mark.parametrize("tension", ["pinv", "feasible"])
def test_the_tension_ratio_is_that_of_the_tensions_the_job_writes(make_cfg, catalogue, tension):
    cfg, _ = validate(make_cfg(*ROBOT, f"tension={tension}", "tension.t_min=0", "output.cables=true"), catalogue,
                      typed=True)
    points = compute_workspace(cfg, catalogue)[0]
    cables = [c for c in points.columns if c.startswith("tension_") and c not in ("tension_factor", "tension_ratio")]
    tensions = points[cables].to_numpy()
    expected = tensions.min(axis=1) / tensions.max(axis=1)
    known = np.isfinite(points["tension_ratio"].to_numpy())
    assert known.sum() > 10
    np.testing.assert_allclose(points["tension_ratio"].to_numpy()[known], expected[known], rtol=1e-12)


def caspr_tension_factor(a: np.ndarray) -> float:
    """CASPR's TensionFactorMetric without its condition-number factor: min h / max h of the
    vertex of min sum h, A h = 0, h >= 1e-6 (0 where no such h), written here with h >= 1 (the
    problem is homogeneous; at 1e-6 HiGHS's 1e-7 feasibility tolerance swamps A h = 0)."""
    done = linprog(np.ones(a.shape[1]), A_eq=a, b_eq=np.zeros(a.shape[0]), bounds=[(1, None)] * a.shape[1],
                   method="highs")
    return done.x.min() / done.x.max() if done.status == 0 else 0.0


def best_tension_factor(a: np.ndarray) -> float:
    """The largest min h / max h over internal forces, searched over the null space directly:
    max s with h = N c, s <= h <= 1 (N an orthonormal basis of the null space, from an SVD)."""
    basis = np.linalg.svd(a)[2][np.linalg.matrix_rank(a):].T  # (m, d)
    m, d = basis.shape
    cost = np.zeros(d + 1)
    cost[d] = -1.0
    rows = np.vstack([np.hstack([basis, np.zeros((m, 1))]), np.hstack([-basis, np.ones((m, 1))])])
    done = linprog(cost, A_ub=rows, b_ub=np.concatenate([np.ones(m), np.zeros(m)]),
                   bounds=[(None, None)] * d + [(0, 1)], method="highs")
    return done.x[d]


def test_the_tension_factor_is_pham_et_als_internal_force_ratio(make_cfg, catalogue):
    """Load-independent: the same at every load; against the LP over the null space written here,
    and against CASPR's LP: never above ours, equal with seven cables (a one-dimensional null
    space, one internal force up to scale). On the IPAnema-like robot, far from the loaded
    tensions' ratio, which least norm drives to t_min / t_max."""
    cfg, _ = validate(make_cfg(*ROBOT, "tension=feasible"), catalogue, typed=True)
    points = compute_workspace(cfg, catalogue)[0]
    heavy = compute_workspace(validate(make_cfg(*ROBOT, "tension=feasible", "load.mass=4"), catalogue,
                                       typed=True)[0], catalogue)[0]
    np.testing.assert_allclose(heavy["tension_factor"], points["tension_factor"], rtol=0, atol=1e-7)
    factor = points["tension_factor"].to_numpy()
    for position, got in zip(points[["x", "y", "z"]].to_numpy(), factor):
        a = structure(position)
        assert got == pytest.approx(best_tension_factor(a), abs=1e-7)
        assert caspr_tension_factor(a) <= got + 1e-7
    assert 0.1 < np.median(factor) < 0.9 and 0.5 < (factor > 0).mean() < 1  # 0: not wrench-closed there
    held = points["feasible"].to_numpy()
    assert np.median(points["tension_ratio"][held]) < 0.2 < np.median(factor[held])
    seven = [0, 1, 2, 3, 4, 5, 7]
    robot7 = [o for o in ROBOT if not o.startswith(("robot.anchors", "robot.attachments"))] + [
        f"robot.anchors={ANCHORS[seven].tolist()}", f"robot.attachments={PLATFORM[seven].tolist()}"]
    points7 = compute_workspace(validate(make_cfg(*robot7, "tension=feasible"), catalogue, typed=True)[0], catalogue)[0]
    for position, got in zip(points7[["x", "y", "z"]].to_numpy(), points7["tension_factor"].to_numpy()):
        assert got == pytest.approx(caspr_tension_factor(structure(position, seven)), abs=1e-6)
    assert (points7["tension_factor"] > 0).any() and (points7["tension_factor"] == 0).any()


@pytest.mark.parametrize("overrides, message", [
    (["analysis=cpr_wwa", "tension=pinv", "tension.t_min=0"], "analysis=cpr_wwa is not"),
    (["analysis=payload"], "analysis=payload is not"),
    (["wrench.set=[[0,0,1,0,0,0],[0,0,-1,0,0,0]]"], "a wrench set or a platform's motion has several loads"),
])
def test_metrics_where_they_mean_nothing_are_refused_in_one_line(make_cfg, catalogue, overrides, message):
    with pytest.raises(ConfigError) as refused:
        validate(make_cfg(*ROBOT, *overrides), catalogue, typed=True)
    assert message in str(refused.value) and str(refused.value).startswith("output.metrics=true: ")


def hull_distance(a: np.ndarray, wrench: np.ndarray, low: float, high: float) -> float:
    """The capacity margin by brute force: the zonotope {A t : low <= t <= high} as the convex
    hull (qhull) of the images of the box's 2^m corners, and the least distance from the wrench
    to its facets' planes (qhull: normal . x + offset <= 0 inside, unit normals)."""
    from scipy.spatial import ConvexHull

    corners = np.array(list(itertools.product((low, high), repeat=a.shape[1])))
    hull = ConvexHull(corners @ a.T)
    return float(-(hull.equations[:, :-1] @ wrench + hull.equations[:, -1]).max())


@pytest.mark.parametrize("cables, dofs", [([0, 1, 2, 3, 4, 5, 7], "x,y,z,rx,ry,rz"), (list(range(8)), "x,y,z")])
def test_the_capacity_margin_is_the_distance_to_the_available_wrench_sets_facets(make_cfg, catalogue, cables, dofs):
    """Guay et al.'s capacity margin against a brute-force facet enumeration of the zonotope:
    seven cables of the tilted-attachment robot with all six wrench rows (2^7 corners in 6-D),
    and the eight as a point platform, forces only (2^8 corners in 3-D). NaN where the load is
    not held; the distance is in N (forces only) or N and N m together."""
    rows = [NAMES.index(f"{'f' if d in 'xyz' else 'm'}{d[-1]}") for d in dofs.split(",")]
    point = dofs == "x,y,z"
    attachments = np.zeros_like(PLATFORM) if point else PLATFORM
    robot = [o for o in ROBOT if not o.startswith(("robot.anchors", "robot.attachments", "robot.platform.com"))] + [
        f"robot.anchors={ANCHORS[cables].tolist()}", f"robot.attachments={attachments[cables].tolist()}",
        f"robot.dofs=[{dofs}]", "robot.platform.com=[0,0,0]" if point else f"robot.platform.com=[{COM[0]},{COM[1]},{COM[2]}]"]
    points = compute_workspace(validate(make_cfg(*robot, "tension=feasible"), catalogue, typed=True)[0], catalogue)[0]
    margin = points["capacity_margin"].to_numpy()
    held = points["feasible"].to_numpy()
    assert np.isnan(margin[~held]).all() and held.sum() > 10
    for position, got in zip(points[["x", "y", "z"]].to_numpy()[held], margin[held]):
        pull = ANCHORS[cables] - (position + attachments[cables])
        pull /= np.linalg.norm(pull, axis=1, keepdims=True)
        a = np.vstack([pull.T, np.cross(attachments[cables], pull).T])[rows]
        force = np.array([0.0, 0.0, -MASS * 9.81])
        load = -np.concatenate([force, np.cross((0, 0, 0) if point else COM, force)])[rows]
        assert got == pytest.approx(hull_distance(a, load, 5.0, 150.0), rel=1e-7, abs=1e-7)
    assert margin[held].min() >= -1e-9

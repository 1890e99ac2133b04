"""Per-pose metrics (output.metrics=true): the largest wrench along each freedom against a plain LP
written here from the points (cables that only pull), against the minimum-norm tensions pushed to
their limits (pinv), and the tension factor against the tensions the job writes."""

import numpy as np
import pytest
from scipy.optimize import linprog

from pipeline.app.problem import compute_workspace, validate
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
def test_the_tension_factor_is_that_of_the_tensions_the_job_writes(make_cfg, catalogue, tension):
    cfg, _ = validate(make_cfg(*ROBOT, f"tension={tension}", "tension.t_min=0", "output.cables=true"), catalogue,
                      typed=True)
    points = compute_workspace(cfg, catalogue)[0]
    tensions = points[[c for c in points.columns if c.startswith("tension_") and c != "tension_factor"]].to_numpy()
    expected = tensions.min(axis=1) / tensions.max(axis=1)
    known = np.isfinite(points["tension_factor"].to_numpy())
    assert known.sum() > 10
    np.testing.assert_allclose(points["tension_factor"].to_numpy()[known], expected[known], rtol=1e-12)


@pytest.mark.parametrize("overrides, message", [
    (["analysis=cpr_wwa", "tension=pinv", "tension.t_min=0"], "analysis=cpr_wwa is not"),
    (["analysis=payload"], "analysis=payload is not"),
    (["wrench.set=[[0,0,1,0,0,0],[0,0,-1,0,0,0]]"], "a wrench set has several loads"),
])
def test_metrics_where_they_mean_nothing_are_refused_in_one_line(make_cfg, catalogue, overrides, message):
    with pytest.raises(ConfigError) as refused:
        validate(make_cfg(*ROBOT, *overrides), catalogue, typed=True)
    assert message in str(refused.value) and str(refused.value).startswith("output.metrics=true: ")

"""Payload maps (``analysis=payload``): the largest payload at ``load.com`` each pose holds on top
of the robot's platform within the tension limits, exact: against a plain LP written here from
the points (pulling cables), the minimum-norm tensions' closed form worked out here (``pinv``),
and the statics analysis run just below and just above the answer."""

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import SPREAD_ANCHORS, SPREAD_PLATFORM, SPREAD_ROBOT, eq9_rotation, compute_workspace
from pipeline.errors import ConfigError

ROBOT = [*SPREAD_ROBOT, "robot.search.step=0.5",
         "robot.platform.mass=5", "robot.platform.com=[0,0,0.02]", "load.com=[0.03,-0.02,-0.15]",
         "orientation.psi=0.1", "orientation.theta=-0.05", "tension.t_min=5", "tension.t_max=400",
         "analysis=payload"]


def pulls_and_loads(position):
    """The pose's matrix M (6, m) with M t = the wrench the cables exert, the platform's load
    wrench and the load wrench of 1 kg of payload at load.com (eq. 9 rotation, g 9.81 along -z)."""
    r = eq9_rotation(0.1, -0.05, 0.0)
    arms = np.array(SPREAD_PLATFORM, float) @ r.T
    pull = np.array(SPREAD_ANCHORS, float) - (position + arms)
    pull /= np.linalg.norm(pull, axis=1, keepdims=True)
    matrix = np.vstack([pull.T, np.cross(arms, pull).T])
    weight = np.array([0.0, 0.0, -9.81])
    platform = np.concatenate([5 * weight, np.cross(r @ [0, 0, 0.02], 5 * weight)])
    per_kg = np.concatenate([weight, np.cross(r @ [0.03, -0.02, -0.15], weight)])
    return matrix, platform, per_kg


def lp_payload(position, t_min=5.0, t_max=400.0):
    """(least, largest) mu >= 0 with M t = -(platform + mu per_kg), t_min <= t <= t_max: two
    LPs; NaN, NaN where no payload is held."""
    matrix, platform, per_kg = pulls_and_loads(position)
    found = []
    for sense in (1.0, -1.0):
        cost = np.zeros(9)
        cost[8] = sense
        done = linprog(cost, A_eq=np.hstack([matrix, per_kg[:, None]]), b_eq=-platform,
                       bounds=[(t_min, t_max)] * 8 + [(0, None)], method="highs")
        found.append(done.x[8] if done.status == 0 else np.nan)
    return tuple(found)


def pinv_payload(position, t_min=5.0, t_max=400.0):
    """The minimum-norm tensions are linear in the payload: t = t0 + mu s; the interval of mu >= 0
    keeping every t_i in [t_min, t_max], each cable bounding mu from one side or the other;
    (NaN, NaN) where it is empty."""
    matrix, platform, per_kg = pulls_and_loads(position)
    inverse = np.linalg.pinv(matrix)
    t0, s = inverse @ -platform, inverse @ -per_kg
    least, largest = 0.0, np.inf
    for a, b in zip(t0, s):
        if b > 0:
            least, largest = max(least, (t_min - a) / b), min(largest, (t_max - a) / b)
        elif b < 0:
            least, largest = max(least, (t_max - a) / b), min(largest, (t_min - a) / b)
        elif not t_min <= a <= t_max:
            return np.nan, np.nan
    return (least, largest) if least <= largest else (np.nan, np.nan)


@pytest.fixture(scope="module")
def feasible_map(make_cfg, catalogue):
    return compute_workspace(make_cfg(*ROBOT, "tension=feasible"), catalogue)


def test_the_payloads_of_each_pose_are_the_lps(feasible_map):
    """The largest and the least payload each pose holds; a 5 kg platform with cables at >= 5 N
    needs a payload's weight at some poses to pull every cable taut (least > 0: not feasible
    without one, although it holds some payloads)."""
    points, summary = feasible_map
    ours = points["max_payload_kg"].to_numpy()
    least, expected = np.array([lp_payload(p) for p in points[["x", "y", "z"]].to_numpy()]).T
    assert np.array_equal(np.isnan(ours), np.isnan(expected))
    held = ~np.isnan(expected)
    np.testing.assert_allclose(ours[held], expected[held], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(points["min_payload_kg"].to_numpy()[held], least[held], rtol=1e-6, atol=1e-6)
    needs = held & (least > 1e-6)
    assert needs.sum() >= 3 and not points["feasible"].to_numpy()[needs].any()
    assert held.sum() > 10 and np.ptp(expected[held]) > 5  # a map, not a constant
    assert summary["max_payload_kg_min"] == pytest.approx(np.nanmin(ours))
    assert summary["max_payload_kg_median"] == pytest.approx(np.nanmedian(ours))
    assert summary["max_payload_kg_max"] == pytest.approx(np.nanmax(ours))
    # load.mass is the payload required: the default 0 kg, held wherever the platform alone is
    assert points["feasible"].tolist() == (held & (least <= 1e-6)).tolist()


def test_a_pose_holds_just_less_than_its_payload_and_not_just_more(feasible_map, make_cfg, catalogue):
    """The statics analysis with that payload as load.mass, another code path (hyperplane
    shifting and LPs of the feasible model), agrees on both sides of the answer."""
    points, _ = feasible_map
    held = points.dropna(subset=["max_payload_kg"])
    held = held[held["min_payload_kg"] < 0.999 * held["max_payload_kg"]]
    chosen = held.iloc[np.linspace(0, len(held) - 1, 4).astype(int)]
    for _, row in chosen.iterrows():
        pose = f"poses=[[{row.x},{row.y},{row.z}]]"
        below = make_cfg(*ROBOT, "tension=feasible", "analysis=statics", pose, f"load.mass={row.max_payload_kg * 0.999}")
        above = make_cfg(*ROBOT, "tension=feasible", "analysis=statics", pose, f"load.mass={row.max_payload_kg * 1.01}")
        assert compute_workspace(below, catalogue)[1]["n_feasible"] == 1
        assert compute_workspace(above, catalogue)[1]["n_feasible"] == 0


def test_the_required_payload_decides_the_verdict_and_the_limiting_criterion(feasible_map, make_cfg, catalogue):
    points, _ = feasible_map
    required = float(np.nanmedian(points["max_payload_kg"]))
    heavy, summary = compute_workspace(make_cfg(*ROBOT, "tension=feasible", f"load.mass={required}"), catalogue)
    np.testing.assert_allclose(heavy["max_payload_kg"], points["max_payload_kg"])  # the map does not move
    assert heavy["feasible"].tolist() == ((points["min_payload_kg"] <= required)
                                          & (points["max_payload_kg"] >= required)).tolist()
    assert set(heavy.loc[~heavy["feasible"], "limiting"]) == {"payload"}
    assert summary["lost_payload"] == (~heavy["feasible"]).sum()


def test_under_the_minimum_norm_model_the_payload_is_the_closed_form(make_cfg, catalogue):
    points, _ = compute_workspace(make_cfg(*ROBOT, "tension=pinv"), catalogue)
    expected = np.array([pinv_payload(p) for p in points[["x", "y", "z"]].to_numpy()])
    for column, values in zip(("min_payload_kg", "max_payload_kg"), expected.T):
        ours = points[column].to_numpy()
        assert np.array_equal(np.isnan(ours), np.isnan(values))
        np.testing.assert_allclose(ours[~np.isnan(ours)], values[~np.isnan(values)], rtol=1e-9, atol=1e-9)
    assert (~np.isnan(points["max_payload_kg"])).sum() > 0


def test_a_payload_the_cables_never_carry_is_unlimited(make_cfg, catalogue):
    """A body on a table (robot.dofs x, y, rz): the table holds any weight."""
    table = ["robot=points", "robot.anchors=[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]",
             "robot.attachments=[[-0.1,-0.1,0],[0.1,-0.1,0],[0.1,0.1,0],[-0.1,0.1,0]]", "robot.dofs=[x,y,rz]",
             "robot.search.lo=[-0.5,-0.5,0]", "robot.search.hi=[0.5,0.5,0]", "robot.search.step=0.25",
             "robot.search.spacing=faces", "tension.t_min=1", "tension.t_max=50", "analysis=payload", "tension=feasible"]
    points, summary = compute_workspace(make_cfg(*table), catalogue)
    assert np.isinf(points["max_payload_kg"]).all() and summary["max_payload_kg_max"] == np.inf


def test_the_payload_analysis_refuses_what_it_cannot_mean(make_cfg, catalogue):
    from pipeline.app.problem import validate

    with pytest.raises(ConfigError, match="^load.gravity=0.0: analysis=payload weighs the payload; needs gravity > 0$"):
        validate(make_cfg(*ROBOT, "load.gravity=0"), catalogue)


def test_the_irpm_workspace_is_where_its_payload_map_holds_the_papers_weight(make_cfg, catalogue):
    """The IRPM paper's load, f_ext = 100 kN of weight, as a payload of 100 kN / g on the massless
    platform: the payload map's verdict is the statics workspace pose for pose (2 862 of 24 986
    poses at the paper's s_max), through another code path (the compiled statics kernel)."""
    statics, reference = compute_workspace(make_cfg("robot=irpm6", "compute.kernel=fused"), catalogue)
    payload, summary = compute_workspace(make_cfg("robot=irpm6", "analysis=payload", "wrench.fz=0",
                                                  f"load.mass={100_000 / 9.81!r}"), catalogue)
    assert reference["n_feasible"] == summary["n_feasible"] == 2862
    assert payload["feasible"].tolist() == statics["feasible"].tolist()
    held = payload["max_payload_kg"].to_numpy()
    assert ((held >= 100_000 / 9.81) == statics["feasible"].to_numpy())[~np.isnan(held)].all()


@pytest.mark.parametrize("required", [0.0, 3.0])
def test_the_payload_verdict_is_the_statics_verdict_with_that_payload(feasible_map, make_cfg, catalogue, required):
    """Another code path (hyperplane shifting): the statics analysis with the payload as
    load.mass holds exactly the poses whose payload interval holds it, including the poses that
    hold some payloads but not the platform alone (once counted feasible without a payload)."""
    payload, _ = compute_workspace(make_cfg(*ROBOT, "tension=feasible", f"load.mass={required}"), catalogue)
    statics, _ = compute_workspace(make_cfg(*ROBOT, "tension=feasible", "analysis=statics", f"load.mass={required}"),
                                   catalogue)
    assert payload["feasible"].tolist() == statics["feasible"].tolist()
    if required == 0.0:
        points, _ = feasible_map
        assert (points["max_payload_kg"].notna() & ~payload["feasible"]).any()  # such poses exist here

"""A designer's own robot, given by its points in her own YAML file (issue 15): IPAnema 1
(frame anchors at x = +-2, y = +-1.5, z = 0 and 2 m, a 0.12 m square platform; the geometry
public in CASPR), run through the command line with no Python."""


import numpy as np
import pandas as pd
import pytest

from conftest import command
from scipy.optimize import linprog

from pipeline.model.geometry import rotation_matrix, structure_matrix

pytestmark = pytest.mark.slow

CORNERS = [[-2, 1.5], [2, 1.5], [2, -1.5], [-2, -1.5]]
PLATFORM = [[-0.06, 0.06, 0], [0.06, 0.06, 0], [0.06, -0.06, 0], [-0.06, -0.06, 0]]
ANCHORS = [[x, y, z] for z in (2, 0) for x, y in CORNERS]
ATTACHMENTS = PLATFORM * 2
IPANEMA1 = f"""defaults: [points, _self_]
anchors: {ANCHORS}
attachments: {ATTACHMENTS}
search: {{lo: [-2, -1.5, 0], hi: [2, 1.5, 2], step: 0.1, spacing: centres}}
"""
WRENCH_FEASIBLE = ["tension.model=feasible", "tension.t_min=1", "tension.t_max=10", "load.mass=0"]


def run(cwd, *args):
    """``python -m pipeline --config-dir CWD/conf ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, "pipeline", "--config-dir", str(cwd / "conf"), *args)


@pytest.fixture(scope="module")
def ipanema(tmp_path_factory):
    root = tmp_path_factory.mktemp("designer")
    (root / "conf" / "robot").mkdir(parents=True)
    (root / "conf" / "robot" / "ipanema1.yaml").write_text(IPANEMA1)
    done = run(root, "robot=ipanema1", *WRENCH_FEASIBLE, "hydra.run.dir=out")
    assert done.returncode == 0, done.stderr
    return root, pd.read_parquet(root / "out" / "points.parquet"), pd.read_parquet(root / "out" / "summary.parquet")


def test_ipanema1_wrench_feasible_workspace_for_tensions_1_to_10_n(ipanema):
    """40 x 30 x 20 cell centres of 0.1 m; zero wrench, massless platform: 9752 poses (40.63 %)
    where pulling tensions in [1, 10] N hold the platform (docs/model.md)."""
    _, points, summary = ipanema
    row = summary.iloc[0]
    assert row["robot.name"] == "points" and row["analysis"] == "statics"
    assert row["n_points"] == 24000 and row["n_feasible"] == 9752
    assert points["x"].min() == pytest.approx(-1.95) and points["z"].max() == pytest.approx(1.95)
    assert row["lost_slack"] + row["lost_tension_max"] + row["lost_unreachable"] == 24000 - 9752


def test_verdicts_agree_with_a_plain_feasibility_lp_per_pose(ipanema):
    """Independent reference: per pose, is there t in [1, 10]^8 with A t = 0 (scipy linprog)?"""
    _, points, _ = ipanema
    clear = points[(points.filter(like="margin_").abs() > 1e-6).all(axis=1)]
    sample = clear.sample(300, random_state=0)
    anchors, attachments = np.array(ANCHORS, float), np.array(ATTACHMENTS, float)
    vectors = sample[["x", "y", "z"]].to_numpy()[:, None, :] + attachments @ rotation_matrix(0, 0, 0).T - anchors
    unit = vectors / np.linalg.norm(vectors, axis=2, keepdims=True)
    a = structure_matrix(unit, np.broadcast_to(attachments, unit.shape))
    found = [linprog(np.zeros(8), A_eq=m, b_eq=np.zeros(6), bounds=[(1, 10)] * 8, method="highs").status == 0
             for m in a]
    assert np.array(found).tolist() == sample["feasible"].tolist()
    assert 50 < sum(found) < 250


@pytest.mark.parametrize("args, message", [
    (["robot=ipanema1", "+robot.foo=1"], "robot.foo: not a key of PointsConfig"),
    (["+robot.anchors=[[0,0,0]]"], "robot.anchors: not a key of Cpr8Config"),
    (["robot=ipanema1", "robot.attachments=[[0,0,0],[1,1,1]]"], "robot.attachments: 2 points for 8 anchors"),
    (["robot=ipanema1", "robot.anchors=[[0,0],[1,1,1]]"], "robot.anchors[0]=[0, 0]"),
    (["robot=ipanema1", "robot.anchors=[[0,0,nan],[1,1,1]]"], "robot.anchors[0]"),
    (["robot=ipanema1", "robot.anchors=[[0,0,0]]", "robot.attachments=[[0,0,0]]"], "needs >= 2"),
    (["robot=ipanema1", "robot.up=[0,0,0]"], "robot.up="),
    (["robot=ipanema1", "robot.cable_names=[a,b]"], "robot.cable_names"),
    (["robot=ipanema1", "robot.search.step=0"], "robot.search.step=0"),
    (["robot=ipanema1", "tension.t_min=20", "tension.t_max=10"], "tension.t_max=10"),
])
def test_bad_robot_input_is_one_line_exit_2_and_writes_nothing(ipanema, args, message):
    root, _, _ = ipanema
    done = run(root, *args, "hydra.run.dir=bad")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert not (root / "bad").exists()


@pytest.mark.parametrize("study, bound, feasible", [("wrench_closure", None, 21280), ("total_orientation", 0.1, 672)])
def test_the_points_robot_studies_give_the_numbers_their_docs_state(make_cfg, catalogue, study, bound, feasible):
    """docs/studies.md and the README quote these: IPAnema 1's wrench-closure workspace (88.67 %)
    and its total-orientation workspace at +-0.1 rad (2.80 %), from the studies' own overrides."""
    from conftest import compute_workspace
    from pipeline.study import load_study

    overrides = [o.strip('"') for o in load_study(study).overrides]
    extra = [] if bound is None else [f"orientation.total.bound={bound}"]
    summary = compute_workspace(make_cfg(*overrides, *extra), catalogue)[1]
    assert (summary["n_feasible"], summary["n_points"]) == (feasible, 24000)


def test_the_readme_s_drive_numbers(ipanema):
    """The README's row for a catalogue actuator on the own robot: a 2 kg platform in [1, 100] N,
    61.55 % without a drive; actuator 4 48.02 % (its voltage), 3 29.93 % (its torque), 5 none."""
    root, _, _ = ipanema
    found = {}
    for actuator in (None, 4, 3, 5):
        extra = [] if actuator is None else [f"actuator={actuator}"]
        done = run(root, "robot=ipanema1", "tension.model=feasible", "tension.t_min=1", "tension.t_max=100",
                   "robot.platform.mass=2", *extra, f"hydra.run.dir=drive{actuator}")
        assert done.returncode == 0, done.stderr
        found[actuator] = pd.read_parquet(root / f"drive{actuator}" / "summary.parquet").iloc[0]
    assert [round(found[a]["feasible_pct"], 2) for a in (None, 4, 3, 5)] == [61.55, 48.02, 29.93, 0.0]
    assert found[4]["lost_voltage"] > 0 == found[4]["lost_torque"] and found[3]["lost_torque"] > 0 == found[3]["lost_voltage"]


def test_the_readme_s_payload_and_wrench_set_numbers(ipanema):
    """The README's own-robot commands with cables in [1, 100] N: the payload map (median 4.6 kg,
    at most 25.3 kg, 83.60 % of the box holds the platform alone, as the statics analysis says;
    536 more poses hold some payloads but not the massless platform, whose cables need a
    payload's weight to reach 1 N) and the box of wrenches +-10 N in x
    and y (53.13 %)."""
    root, _, _ = ipanema
    limits = ["tension.t_min=1", "tension.t_max=100"]
    payload = run(root, "robot=ipanema1", *limits, "analysis=payload", "load.com=[0,0,-0.2]", "hydra.run.dir=pay")
    boxed = run(root, "robot=ipanema1", *limits, "wrench.set={min:[-10,-10,0,0,0,0],max:[10,10,0,0,0,0]}",
                "hydra.run.dir=set")
    assert payload.returncode == 0 and boxed.returncode == 0, payload.stderr + boxed.stderr
    row = pd.read_parquet(root / "pay" / "summary.parquet").iloc[0]
    assert row["n_feasible"] == 20064 and row["max_payload_kg_median"] == pytest.approx(4.633, abs=1e-3)
    assert row["max_payload_kg_max"] == pytest.approx(25.324, abs=1e-3)
    row = pd.read_parquet(root / "set" / "summary.parquet").iloc[0]
    assert (row["n_feasible"], row["n_wrenches"]) == (12752, 4)

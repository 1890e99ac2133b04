"""CPR-ACM (section 4, Table 2): the accepted set, ranking and the explanation of rejections."""

import pandas as pd
import pytest

from pipeline.analyses.choice import acceptance, choose
from conftest import compute_workspace


@pytest.fixture(scope="module")
def summary(make_cfg, catalogue):
    rows = [compute_workspace(make_cfg(f"actuator={a}"), catalogue)[1] for a in catalogue.ids]
    return pd.DataFrame(rows)


def test_table1_at_90_pct_accepts_exactly_actuators_1_and_2(summary):
    choice = choose(summary)
    assert sorted(choice.loc[choice["accepted"], "actuator"]) == [1, 2]
    assert choice["actuator"].tolist() == [1, 2, 3, 4, 5]  # rank order; 3 and 4 tie, id decides
    assert choice["rank"].tolist() == [1, 2, 3, 4, 5]


def test_losses_add_up_to_the_infeasible_count(summary):
    choice = choose(summary)
    lost = [f"lost_{c}" for c in ("speed", "torque", "acceleration", "voltage")]
    assert (choice[lost].sum(axis=1) == choice["n_points"] - choice["n_feasible"]).all()
    shares = choice[[f"{c}_pct" for c in lost]].sum(axis=1) + choice["feasible_pct"]
    assert shares.to_numpy() == pytest.approx(100.0)


def test_rejections_are_explained_20w_loses_to_voltage_50w_to_torque(summary):
    reasons = choose(summary).set_index("actuator")["rejected_by"]
    assert reasons.to_dict() == {1: "", 2: "", 3: "torque 32", 4: "voltage 32", 5: "torque 216"}


def test_required_share_moves_the_verdict(summary):
    lower = choose(summary.assign(**{"choice.required_pct": 85.0}))
    assert sorted(lower.loc[lower["accepted"], "actuator"]) == [1, 2, 3, 4]


def test_one_result_per_actuator_is_required(summary):
    with pytest.raises(ValueError, match="repeats actuator ids"):
        choose(pd.concat([summary, summary]))


def test_acceptance_over_a_design_variable(make_cfg, catalogue):
    rows = [compute_workspace(make_cfg(f"actuator={a}", f"robot.platform.mass={m}"), catalogue)[1]
            for a in (3, 4) for m in (0.5, 2.0)]
    table = acceptance(pd.DataFrame(rows))
    assert (table["parameter"] == "robot.platform.mass").all()
    verdict = table.set_index(["actuator", "value"])["accepted"].to_dict()
    assert verdict == {(3, 0.5): True, (3, 2.0): False, (4, 0.5): True, (4, 2.0): False}

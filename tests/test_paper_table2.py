"""Table 2 of Filipovic & Kevac (2018): feasible share of the geometric workspace per actuator,
psi = theta = phi = 0, N = 6 (216 grid points), default readings of docs/evidence.md, and the
forces-only reading of eq. (20) that fits Table 2 alone best (docs/evidence.md section 1)."""

import pytest

from golden import values

from pipeline.analyses.paper import TABLE2_FEASIBLE_PCT
from conftest import compute_workspace

PAPER = TABLE2_FEASIBLE_PCT
OURS = dict(zip(PAPER, values("full_default_zero")))  # feasible grid points of 216 (tests/golden.yaml)
FORCES_ONLY = dict(zip(PAPER, values("translational_default_zero")))  # model.pinv_columns=translational
TOLERANCE_PP = 4.0


@pytest.fixture(scope="module")
def results(make_cfg, catalogue):
    return {a: compute_workspace(make_cfg(f"actuator={a}"), catalogue) for a in PAPER}


@pytest.fixture(scope="module")
def table2(results):
    return {a: summary for a, (_, summary) in results.items()}


@pytest.fixture(scope="module")
def forces_only(make_cfg, catalogue):
    return {a: compute_workspace(make_cfg(f"actuator={a}", "model.pinv_columns=translational"),
                                 catalogue)[1] for a in PAPER}


@pytest.mark.parametrize("actuator", sorted(PAPER))
def test_feasible_points_and_their_distance_to_table2(table2, forces_only, actuator):
    """Within 4 points of Table 2 under both readings, except actuator 5 with all six columns:
    0 % against 7.41 % (the forces-only reading: 11.11 %), the documented disagreement."""
    assert table2[actuator]["n_points"] == 216
    assert table2[actuator]["n_feasible"] == OURS[actuator]
    assert forces_only[actuator]["n_feasible"] == FORCES_ONLY[actuator]
    assert forces_only[actuator]["feasible_pct"] == pytest.approx(PAPER[actuator], abs=TOLERANCE_PP)
    if actuator != 5:
        assert table2[actuator]["feasible_pct"] == pytest.approx(PAPER[actuator], abs=TOLERANCE_PP)
    else:
        assert PAPER[5] - table2[5]["feasible_pct"] == pytest.approx(7.41)


def test_actuators_1_2_3_match_table2_to_its_printed_digits(table2):
    for actuator in (1, 2, 3):
        assert round(table2[actuator]["feasible_pct"], 2) == pytest.approx(PAPER[actuator], abs=0.01)


def test_catalogue_power_is_not_the_criterion(table2):
    """Actuator 4 (20 W) is not below actuator 3 (50 W), the paper's 'illogical' result."""
    assert table2[4]["feasible_pct"] >= table2[3]["feasible_pct"]
    assert table2[3]["actuator_power_W"] > table2[4]["actuator_power_W"]


def test_each_lost_point_is_attributed_to_one_constraint(table2):
    for row in table2.values():
        lost = sum(row[f"lost_{c}"] for c in ("speed", "torque", "acceleration", "voltage"))
        assert lost == row["n_points"] - row["n_feasible"]
    assert [table2[a]["lost_torque"] for a in PAPER] == values("full_default_zero", "lost_torque")
    assert [table2[a]["lost_voltage"] for a in PAPER] == values("full_default_zero", "lost_voltage")


def test_shaft_acceleration_limit_never_binds_for_table1(results):
    """Eq. (33): smallest margins over the grid, as stated in docs/evidence.md."""
    smallest = [results[a][0]["margin_acceleration"].min() for a in sorted(PAPER)]
    assert smallest == pytest.approx([0.7233, 0.8534, 0.9444, 0.9901, 0.9876], abs=1e-4)

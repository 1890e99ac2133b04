"""Physics invariants of the CPR-8 model: equilibrium, symmetry, monotonicity."""

from dataclasses import replace

import numpy as np
import pytest

from pipeline.model.dynamics import PoseDynamics
from conftest import shaft_accel_from_acceleration, shaft_torque, wrenches, compute_workspace
from pipeline.app.problem import build_problem


def _dyn(make_cfg, catalogue, *overrides):
    problem, grid = build_problem(make_cfg(*overrides), catalogue)
    return PoseDynamics(problem.robot, grid[:], problem.orientation, problem.spec)


def _residual(dyn, columns):
    return np.einsum("nmc,nma->nca", dyn.jacobian[:, :, :columns], shaft_torque(dyn)) - wrenches(dyn)[:, :columns].T


def test_translational_pinv_balances_the_force_exactly(make_cfg, catalogue):
    dyn = _dyn(make_cfg, catalogue, "model.pinv_columns=translational")
    assert np.abs(_residual(dyn, 3)).max() < 1e-10  # J_t^T M = F (eq. 20, forces of eq. 31)


def test_full_pinv_balances_the_whole_wrench_where_j_has_full_rank(make_cfg, catalogue):
    dyn = _dyn(make_cfg, catalogue, "model.pinv_columns=full", "orientation.psi=0.5",
               "orientation.theta=0.5", "orientation.phi=0.5")
    assert (dyn.jacobian_rank == 6).all()
    assert np.abs(_residual(dyn, 6)).max() < 1e-8


def test_full_pinv_at_rank_5_balances_wrenches_in_the_range_only(make_cfg, catalogue):
    """At zero orientation J^T has rank 5: a vertical force (weight, vertical acceleration) lies in
    its range and is balanced exactly; a horizontal force generally is not (least squares)."""
    dyn = _dyn(make_cfg, catalogue, "model.pinv_columns=full")
    residual = np.linalg.norm(_residual(dyn, 6), axis=1)  # (n, k_a)
    vertical = np.abs(wrenches(dyn)[:, :2]).sum(axis=1) == 0
    assert not vertical.any()  # the corner set always has a horizontal part
    pure_weight = dyn.jacobian[:, :, :6]
    m = np.einsum("nmc,c->nm", np.linalg.pinv(np.transpose(pure_weight, (0, 2, 1)), rtol=1e-9),
                  [0, 0, -2 * 9.81, 0, 0, 0])
    weight_residual = np.einsum("nmc,nm->nc", pure_weight, m) - [0, 0, -2 * 9.81, 0, 0, 0]
    assert np.abs(weight_residual).max() < 1e-9
    assert residual.max() > 1e-3


@pytest.mark.parametrize("actuator", [1, 2, 3, 4, 5])
def test_feasible_set_mirror_symmetric_about_frame_mid_planes(make_cfg, catalogue, actuator):
    points, _ = compute_workspace(make_cfg(f"actuator={actuator}"), catalogue)
    feasible = points["feasible"].to_numpy().reshape(6, 6, 6)
    margin = points["margin_voltage"].to_numpy().reshape(6, 6, 6)
    np.testing.assert_array_equal(feasible, feasible[::-1, :, :])  # x -> d - x
    np.testing.assert_array_equal(feasible, feasible[:, ::-1, :])  # y -> s - y
    np.testing.assert_allclose(margin, margin[::-1, ::-1, :], rtol=1e-9)


@pytest.mark.parametrize("column", ["torque_Nm", "voltage_V", "speed_rpm"])
@pytest.mark.parametrize("actuator", [2, 3, 4, 5])
def test_stronger_motor_never_shrinks_the_workspace(make_cfg, catalogue, column, actuator):
    cfg = make_cfg(f"actuator={actuator}", "orientation.psi=0.5", "orientation.theta=0.5",
                   "orientation.phi=0.5")
    base, _ = compute_workspace(cfg, catalogue)
    stronger = replace(catalogue, rows=tuple(
        {**row, column: row[column] * 1.5} if row["id"] == actuator else row for row in catalogue.rows))
    better, _ = compute_workspace(cfg, stronger)
    assert (better["feasible"] >= base["feasible"]).all()
    assert better["feasible"].sum() >= base["feasible"].sum()
    margin = f"margin_{ {'torque_Nm': 'torque', 'voltage_V': 'voltage', 'speed_rpm': 'speed'}[column] }"
    assert (better[margin] > base[margin]).all()


def test_centripetal_term_dominates_shaft_acceleration_on_the_paper_grid(make_cfg, catalogue):
    """docs/model.md: J-dot p-dot reaches 157 rad/s^2 near the top corners, J p-ddot 15.5."""
    dyn = _dyn(make_cfg, catalogue, "model.jdot=true")
    assert dyn.shaft_accel_from_velocity.min() >= 0  # |v|^2 >= (u.v)^2
    assert dyn.shaft_accel_from_velocity.max() == pytest.approx(156.76, abs=0.01)
    assert np.abs(shaft_accel_from_acceleration(dyn)).max() == pytest.approx(15.464, abs=0.001)

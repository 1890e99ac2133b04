"""The separable maxima used by the criteria equal the enumerated velocity x acceleration set."""

import numpy as np
import pytest

from pipeline.criteria import acceleration, max_abs_sum, voltage
from pipeline.workspace import build_problem
from pipeline.dynamics import PoseDynamics


def test_max_abs_sum_identity_against_enumeration():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(40, 8, 17)), rng.normal(size=(40, 8, 5))
    enumerated = np.abs(a[..., :, None] + b[..., None, :]).max(axis=(-2, -1))
    np.testing.assert_allclose(max_abs_sum(a, b), enumerated, rtol=0, atol=1e-15)


@pytest.mark.parametrize("actuator", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.5, 0.5, 0.5)])
def test_voltage_and_acceleration_margins_equal_literal_enumeration(make_cfg, catalogue, actuator, orientation):
    psi, theta, phi = orientation
    cfg = make_cfg(f"actuator={actuator}", "model.jdot=true", f"orientation.psi={psi}",
                   f"orientation.theta={theta}", f"orientation.phi={phi}")
    problem, grid = build_problem(cfg, catalogue)
    dyn = PoseDynamics(problem.robot, grid.positions, problem.orientation, problem.spec)
    act = problem.limits
    # every (velocity k_v, acceleration k_a) combination, eq. (21)
    thdd = dyn.shaft_accel_from_velocity[:, :, :, None] + dyn.shaft_accel_from_acceleration[:, :, None, :]
    u = act.G_v * thdd + act.L_v * dyn.shaft_speed[:, :, :, None] + act.S_v * dyn.shaft_torque[:, :, None, :]
    u_margin = 1 - np.abs(u).max(axis=(1, 2, 3)) / act.voltage_limit
    a_margin = 1 - np.abs(thdd).max(axis=(1, 2, 3)) / act.accel_limit
    np.testing.assert_allclose(voltage(dyn, act), u_margin, rtol=0, atol=1e-12)
    np.testing.assert_allclose(acceleration(dyn, act), a_margin, rtol=0, atol=1e-12)

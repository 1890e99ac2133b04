"""The separable maxima used by the criteria equal the enumerated velocity x acceleration set."""

import numpy as np
import pytest

from pipeline.workspace.criteria.actuator import acceleration, max_abs_sum, voltage
from pipeline.workspace.compute import build_problem
from pipeline.model.dynamics import PoseDynamics


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
    u = act.G_v * thdd + act.L_v * dyn.shaft_speed[:, :, :, None] - act.S_v * dyn.shaft_torque[:, :, None, :]
    u_margin = 1 - np.abs(u).max(axis=(1, 2, 3)) / act.voltage_limit
    a_margin = 1 - np.abs(thdd).max(axis=(1, 2, 3)) / act.accel_limit
    np.testing.assert_allclose(voltage(dyn, act), u_margin, rtol=0, atol=1e-12)
    np.testing.assert_allclose(acceleration(dyn, act), a_margin, rtol=0, atol=1e-12)


@pytest.mark.parametrize("reading", ["corners", "colon", "scattered"])
def test_acceleration_range_closed_form_equals_enumeration(make_cfg, catalogue, reading):
    """On a product set the range of an affine function of a is c.centre +- |c|.half-width;
    a set that is not a product (here random accelerations) is enumerated."""
    from dataclasses import replace

    cfg = make_cfg("orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5",
                   f"model.acceleration_set={'colon' if reading == 'colon' else 'corners'}")
    problem, grid = build_problem(cfg, catalogue)
    motion = problem.spec
    if reading == "scattered":
        motion = replace(motion, accelerations=np.random.default_rng(3).uniform(-1, 1, (11, 3)))
    dyn = PoseDynamics(problem.robot, grid.positions, problem.orientation, motion)
    assert (dyn._acceleration_box is None) == (reading == "scattered")
    high, low = dyn.acceleration_range(*dyn.torque_affine)
    np.testing.assert_allclose(high, dyn.shaft_torque.max(axis=2), rtol=0, atol=1e-12)
    np.testing.assert_allclose(low, dyn.shaft_torque.min(axis=2), rtol=0, atol=1e-12)
    high, low = dyn.acceleration_range(dyn.jacobian[:, :, :3], 0.0)
    np.testing.assert_allclose(high, dyn.shaft_accel_from_acceleration.max(axis=2), rtol=0, atol=1e-12)

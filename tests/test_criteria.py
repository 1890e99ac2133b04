"""The separable maxima used by the criteria equal the enumerated velocity x acceleration set."""

import numpy as np
import pytest

from pipeline.workspace.criteria import margins
from pipeline.workspace.criteria import force_families
from pipeline.workspace.criteria.actuator import acceleration, max_abs_sum_of_ranges, voltage
from pipeline.app.problem import build_problem
from pipeline.model.dynamics import PoseDynamics
from conftest import shaft_accel_from_acceleration, shaft_torque


def test_max_abs_sum_identity_against_enumeration():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(40, 8, 17)), rng.normal(size=(40, 8, 5))
    enumerated = np.abs(a[..., :, None] + b[..., None, :]).max(axis=(-2, -1))
    ranges = [(x.max(axis=-1), x.min(axis=-1)) for x in (a, b)]
    np.testing.assert_allclose(max_abs_sum_of_ranges(*ranges), enumerated, rtol=0, atol=1e-15)


@pytest.mark.parametrize("actuator", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.5, 0.5, 0.5)])
def test_voltage_and_acceleration_margins_equal_literal_enumeration(make_cfg, catalogue, actuator, orientation):
    psi, theta, phi = orientation
    cfg = make_cfg(f"actuator={actuator}", "model.jdot=true", f"orientation.psi={psi}",
                   f"orientation.theta={theta}", f"orientation.phi={phi}")
    problem, grid = build_problem(cfg, catalogue)
    dyn = PoseDynamics(problem.robot, grid[:], problem.orientation, problem.spec)
    act = problem.limits
    # every (velocity k_v, acceleration k_a) combination, eq. (21)
    thdd = dyn.shaft_accel_from_velocity[:, :, :, None] + shaft_accel_from_acceleration(dyn)[:, :, None, :]
    u = act.G_v * thdd + act.L_v * dyn.shaft_speed[:, :, :, None] - act.S_v * shaft_torque(dyn)[:, :, None, :]
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
    dyn = PoseDynamics(problem.robot, grid[:], problem.orientation, motion)
    assert (dyn._acceleration_box is None) == (reading == "scattered")
    high, low = dyn.acceleration_range(*dyn.torque_affine)
    np.testing.assert_allclose(high, shaft_torque(dyn).max(axis=2), rtol=0, atol=1e-12)
    np.testing.assert_allclose(low, shaft_torque(dyn).min(axis=2), rtol=0, atol=1e-12)
    high, low = dyn.acceleration_range(dyn.jacobian[:, :, :3], 0.0)
    np.testing.assert_allclose(high, shaft_accel_from_acceleration(dyn).max(axis=2), rtol=0, atol=1e-12)


@pytest.mark.parametrize("tension", ["pinv", "feasible"])
def test_both_chunk_states_offer_the_criteria_one_interface(make_cfg, catalogue, tension):
    """A CPR-WWA chunk (PoseDynamics) and a statics chunk (PoseStatics) answer the same
    questions, so no criterion asks which it was given: the cable tensions' range over the
    wrench set (enumerated here for the CPR-8, off-centre load and tilted platform: M / R of
    eq. 20 at every acceleration), the forces of the feasible model's variables, its families,
    and the per-pose diagnostics."""
    cpr8 = make_cfg("actuator=3", "orientation.psi=0.3", "orientation.theta=-0.2",
                    "robot.platform.com=[0.03,-0.02,0.01]", f"tension={tension}", "grid.n=3")
    irpm = make_cfg("robot=irpm6", "robot.search.step=2", "wrench.fx=300", "tension.t_max=50000", f"tension={tension}")
    for cfg, kind in ((cpr8, "cpr_wwa"), (irpm, "statics")):
        problem, grid = build_problem(cfg, catalogue)
        state = problem.spec.state(problem.robot, grid[:], problem.orientation)
        assert problem.spec.kind == kind and state.tension is problem.spec.tension
        high, low = state.force_range
        if kind == "cpr_wwa":
            forces = shaft_torque(state) / problem.spec.winch_radius[None, :, None]
            np.testing.assert_allclose(high, forces.max(axis=2), rtol=0, atol=1e-9)
            np.testing.assert_allclose(low, forces.min(axis=2), rtol=0, atol=1e-9)
            assert state.ranges_over_a_set and set(state.diagnostics()) == {"jacobian_rank"}
            np.testing.assert_array_equal(state.forces_of(problem.spec.winch_radius * high), high)
        else:
            assert high is low is state.tensions and not state.ranges_over_a_set
            assert state.diagnostics() == {}
        names = [family.name for family in force_families(state, problem.limits)]
        assert names == (["slack", "torque", "voltage"] if kind == "cpr_wwa" else ["slack", "tension_max"])
        for name in problem.criteria:  # every registered criterion evaluates on either state
            assert margins([name], state, problem.limits)[name].shape == (len(grid[:]),)
        if tension == "feasible":
            assert "lp_poses" in state.diagnostics()

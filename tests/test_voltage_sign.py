"""The sign of the load term of eq. (21), checked from the motor and drum equations.

With eq. (18)'s convention (theta > 0 pays the cable out) a pulling cable drives the drum
forwards; the motor holds it back. At the output shaft (eq. 22's quantities from the catalogue):

    drum:      J_r theta_ddot = C_M i - B_C theta_dot + M        (M = R t, eq. 20)
    armature:  u = R_r i + C_E theta_dot

The oracles below solve these two equations for u themselves, from the catalogue row (no G_v,
L_v, S_v of the package), so they pass only with the physical sign u = ... - S_v M. Flipping the
sign of ``ActuatorModel.load_gain`` (tried: +S_v) fails every test of this module.
"""

from dataclasses import replace

import numpy as np
import pytest

from pipeline.model.geometry import rotation_matrix
from pipeline.app.problem import build_problem
from pipeline.model.actuators import voltage_interval
from pipeline.workspace.kernel import evaluate_chunk
from pipeline.model.dynamics import SampleDynamics
from pipeline.workspace.trajectory import inverse_dynamics

ASYMMETRIC = ("motion.t_dec=0.91",)  # braking twice as hard as accelerating (t_acc = 1.82 s)
TILTED = ("orientation.psi=0.3", "orientation.theta=-0.2", "orientation.phi=0.4")


def drive(row: dict) -> dict:
    """The output-shaft constants of section 3 written from the catalogue row: N_M = N_V xi,
    C_E = C_e N_V, C_M = C_m N_M, B_C = B_c N_V N_M, J_r = J_M N_V N_M (SI units)."""
    n_v = row["gear_ratio"]
    n_m = n_v * row["efficiency"]
    return {"C_E": row["back_emf_V_per_rad_s"] * n_v, "C_M": row["torque_constant_Nm_per_A"] * n_m,
            "B_C": row["viscous_friction_Nm_per_rad_s"] * n_v * n_m,
            "J_r": row["inertia_g_cm2"] * 1e-7 * n_v * n_m, "R_r": row["resistance_ohm"]}


def current_and_voltage(d: dict, theta_dot, theta_ddot, load_torque):
    """The drum's torque balance solved for the current, then the armature equation."""
    current = (d["J_r"] * theta_ddot + d["B_C"] * theta_dot - load_torque) / d["C_M"]
    return current, d["R_r"] * current + d["C_E"] * theta_dot


def lengths(robot, position, orientation):
    """Cable lengths (m,) of eqs. (10)-(17): |position + R(q) b_i - a_i|."""
    points = position + robot.attachments @ rotation_matrix(*orientation).T
    return np.linalg.norm(points - robot.anchors, axis=1)


def oracle_voltage_margin(problem, positions, row, inertial_sign=-1.0):
    """Eq. (34)'s margin pose by pose: J by central differences of the lengths (eqs. 18-19), M by
    eq. (20) for the force of Newton's law at every acceleration of the set (the cables must
    balance the weight and the inertial force -m a; ``inertial_sign=+1`` reverses it), u from
    :func:`current_and_voltage` at every velocity of the set."""
    robot, spec, q0 = problem.robot, problem.spec, np.array(problem.orientation)
    d, mass, h = drive(row), spec.load.mass, 1e-6
    out = []
    for position in positions:
        jac = np.empty((robot.n_cables, 6))
        for k in range(6):
            step = np.zeros(6)
            step[k] = h
            plus = lengths(robot, position + step[:3], q0 + step[3:])
            minus = lengths(robot, position - step[:3], q0 - step[3:])
            jac[:, k] = (plus - minus) / (2 * h) / spec.winch_radius
        worst = 0.0
        for a in spec.accelerations:
            force = np.concatenate([mass * (inertial_sign * a - np.array([0.0, 0.0, 9.81])), np.zeros(3)])
            torque = np.linalg.pinv(jac.T) @ force
            for v in spec.velocities:
                _, u = current_and_voltage(d, jac[:, :3] @ v, jac[:, :3] @ a, torque)
                worst = max(worst, np.abs(u).max())
        out.append(1.0 - worst / row["voltage_V"])
    return np.array(out)


@pytest.mark.parametrize("actuator", [1, 4])
def test_grid_voltage_margin_equals_the_motor_equations_for_an_asymmetric_profile(
        make_cfg, catalogue, actuator):
    """Off-centre poses of a tilted carrier (rank 6), t_acc != t_dec: the numpy kernel against
    the oracle (its central differences are good to ~1e-9), the compiled one against numpy."""
    problem, _ = build_problem(make_cfg(f"actuator={actuator}", *ASYMMETRIC, *TILTED), catalogue)
    positions = np.random.default_rng(7).uniform([0.4, 0.4, -1.9], [2.8, 1.8, -0.3], (25, 3))
    expected = oracle_voltage_margin(problem, positions, catalogue.row(actuator))
    numpy_margin = evaluate_chunk(problem, positions)["margin_voltage"]
    fused_margin = evaluate_chunk(replace(problem, fused=True), positions)["margin_voltage"]
    np.testing.assert_allclose(numpy_margin, expected, rtol=0, atol=1e-6)
    np.testing.assert_allclose(fused_margin, numpy_margin, rtol=1e-12, atol=1e-12)


def test_the_asymmetric_profile_separates_both_reversed_signs(make_cfg, catalogue):
    """The voltage's load term reversed (+S_v M), or the inertial force reversed in the oracle,
    gives margins far from the physical ones here, so the test above could pass with neither
    (on a symmetric set the two reversals together would give u(v, a) = -u_physical(-v, -a))."""
    problem, _ = build_problem(make_cfg("actuator=4", *ASYMMETRIC, *TILTED), catalogue)
    positions = np.random.default_rng(7).uniform([0.4, 0.4, -1.9], [2.8, 1.8, -0.3], (25, 3))
    physical = evaluate_chunk(problem, positions)["margin_voltage"]
    flipped = replace(problem.limits, S_v=-problem.limits.S_v)  # load_gain = +S_v
    other = evaluate_chunk(replace(problem, limits=flipped), positions)["margin_voltage"]
    assert np.abs(physical - other).max() > 1e-2  # 1e4 x the oracle test's tolerance
    reversed_inertia = oracle_voltage_margin(problem, positions, catalogue.row(4), inertial_sign=1.0)
    assert np.abs(physical - reversed_inertia).max() > 1e-2


def lowering_and_hoisting(make_cfg, catalogue, speed):
    """Inverse dynamics of the carrier moving straight down (speed < 0) or up at constant
    speed, tilted and off-centre, actuator 1: the quantities and the oracle's current and voltage."""
    cfg = make_cfg("actuator=1", "analysis=lines", *TILTED)
    problem, _ = build_problem(cfg, catalogue)
    positions = np.array([[1.1, 0.9, z] for z in np.linspace(-1.6, -0.5, 12)])
    velocities = np.tile([0.0, 0.0, speed], (len(positions), 1))
    out = inverse_dynamics(SampleDynamics(problem.robot, positions, problem.orientation, problem.spec,
                                          velocities, np.zeros_like(positions)), problem.limits)
    d = drive(catalogue.row(1))
    current, voltage = current_and_voltage(d, out["theta_dot"], out["theta_ddot"], out["torque"])
    return out, d, current, voltage


@pytest.mark.parametrize("speed", [-0.6, 0.6])
def test_line_voltage_is_the_motor_equations_and_the_energy_balances(make_cfg, catalogue, speed):
    """Per sample and cable at constant speed: the simulated voltage is the oracle's, and the
    power balances. The armature takes u i = R_r i^2 + C_E theta_dot i; the motor turns
    C_E theta_dot i of it into C_M theta_dot i at the shaft (eq. 22's gearbox efficiency is in
    C_M), where it and the cable's power M theta_dot go into friction B_C theta_dot^2. So
    u i = R_r i^2 + (C_E / C_M) (B_C theta_dot^2 - M theta_dot): the cable's power lowers the
    electrical power (paying out under tension) or raises it (hoisting)."""
    out, d, current, voltage = lowering_and_hoisting(make_cfg, catalogue, speed)
    np.testing.assert_allclose(out["voltage"], voltage, rtol=1e-12, atol=1e-9)
    theta_dot = out["theta_dot"]
    shaft = d["B_C"] * theta_dot**2 - out["torque"] * theta_dot
    np.testing.assert_allclose(out["voltage"] * current, d["R_r"] * current**2 + d["C_E"] / d["C_M"] * shaft,
                               rtol=1e-9, atol=1e-9)


def test_paying_out_under_tension_brakes_and_hoisting_motors(make_cfg, catalogue):
    """Lowering, a cable that pays out (theta_dot > 0) against a load torque beyond friction
    (M > B_C theta_dot) has its terminal voltage below the back-EMF (its current runs backwards);
    raising, a cable that reels in under tension needs more than the back-EMF, and draws power."""
    out, d, current, _ = lowering_and_hoisting(make_cfg, catalogue, -0.6)
    u, theta_dot, torque = out["voltage"], out["theta_dot"], out["torque"]
    braking = (theta_dot > 0) & (torque > d["B_C"] * theta_dot)
    assert braking.sum() >= 12  # several cables at every sample
    assert (u[braking] < d["C_E"] * theta_dot[braking]).all()
    assert (current[braking] < 0).all()
    out, d, current, _ = lowering_and_hoisting(make_cfg, catalogue, 0.6)
    u, theta_dot, torque = out["voltage"], out["theta_dot"], out["torque"]
    hoisting = (theta_dot < 0) & (torque > 0)
    assert hoisting.sum() >= 12
    assert (np.abs(u[hoisting]) > d["C_E"] * np.abs(theta_dot[hoisting])).all()
    assert (u[hoisting] * current[hoisting] > 0).all()


def test_feasible_models_voltage_interval_is_the_motor_equations(catalogue, make_cfg):
    """``tension=feasible`` bounds M by an interval per cable: M lies in it exactly when the
    oracle's |u| <= U for both ends of the velocity part (random M, random velocity parts)."""
    problem, _ = build_problem(make_cfg("actuator=3", "tension=feasible"), catalogue)
    act, row = problem.limits, catalogue.row(3)
    d = drive(row)
    rng = np.random.default_rng(11)
    n = 4000
    theta_dot = rng.uniform(-30, 30, (n, 1, 8, 2))  # two velocities per cable
    theta_ddot = rng.uniform(-20, 20, (n, 1, 8, 1))
    other = act.G_v * theta_ddot + act.L_v * theta_dot
    high, low = other.max(axis=-1), other.min(axis=-1)
    lower, upper, _ = voltage_interval(act, high, low)
    torque = rng.uniform(-3 * act.torque_limit, 3 * act.torque_limit, (n, 1, 8))
    inside = (torque >= lower) & (torque <= upper)
    _, u = current_and_voltage(d, theta_dot, theta_ddot, torque[..., None])
    holds = (np.abs(u) <= row["voltage_V"]).all(axis=-1)
    assert 0.1 < inside.mean() < 0.9
    np.testing.assert_array_equal(inside, holds)



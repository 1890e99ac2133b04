"""Straight-line simulation experiments (section 3.1.3 of Filipovic & Kevac 2018): the carrier
moves along a straight segment at constant orientation with a trapezoidal speed profile
(``pipeline.model.path.trapezoid``), and the actuator quantities of eqs. (19)-(21) are computed
at every time sample. This is the paper's second, independent path to the feasible workspace
(Figs. 4b, 5b, 6).
"""

from __future__ import annotations

import numpy as np

from pipeline.model.actuators import ActuatorModel
from pipeline.model.dynamics import SampleDynamics
from pipeline.workspace.criteria import TORQUE, VOLTAGE, force_families
from pipeline.workspace.criteria.forces import feasible_distribution, feasible_model


def inverse_dynamics(state: SampleDynamics, actuator: ActuatorModel) -> dict[str, np.ndarray]:
    """Per-sample actuator quantities (n, m) of a trajectory's samples (each pose with its own
    velocity and acceleration, constant orientation): shaft speed theta_dot = J p_dot (eq. 19),
    shaft acceleration J p_ddot (+ J-dot p_dot when ``motion.jdot``), load torque M = (J^T)^+ F
    with F the generalized force of w = m g (-up) - m p_ddot, the weight and inertial force the
    cables balance (eqs. 20, 31 read by Newton's law, :func:`pipeline.model.dynamics.load_wrenches`),
    voltage u = G_v theta_ddot + L_v theta_dot - S_v M (eq. 21). Also the wrench residual
    |J^T M - F| and both sides of the power balance, sum_i M_i theta_dot_i and F . p_dot (n,).
    Under ``tension.model=feasible`` M is the LP's choice (``pipeline.model.tensions``) for each
    sample's own wrench, speed and acceleration. The samples' margins are the registry's
    (``criteria.margins`` of the same state)."""
    theta_dot = state.shaft_speed[..., 0]
    theta_ddot = state.acceleration_range(state.jacobian[:, :, :3], state.shaft_accel_from_velocity[..., 0])[0]
    wrench = state.required_wrenches[:, 0, :]
    if feasible_model(state):
        torque = feasible_distribution(state, actuator, force_families(state, actuator))[:, 0, :]
    else:
        torque = np.einsum("nmc,nc->nm", state.wrench_pinv[0], wrench)
    reached = np.einsum("ncm,nm->nc", state.structure, torque)
    return {
        "theta_dot": theta_dot,
        "theta_ddot": theta_ddot,
        TORQUE: torque,  # the per-sample quantities the criteria of the same names read
        VOLTAGE: actuator.G_v * theta_ddot + actuator.L_v * theta_dot + actuator.load_gain * torque,
        "wrench_residual": np.linalg.norm(reached - wrench, axis=1),
        "power_cables": np.einsum("nm,nm->n", torque, theta_dot),
        "power_load": np.einsum("nj,nj->n", wrench[:, :3], state.velocities),
    }

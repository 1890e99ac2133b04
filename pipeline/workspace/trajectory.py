"""Straight-line simulation experiments (section 3.1.3 of Filipovic & Kevac 2018): the carrier
moves along a straight segment at constant orientation with a trapezoidal speed profile, and the
actuator quantities of eqs. (19)-(21) are computed at every time sample. This is the paper's
second, independent path to the feasible workspace (Figs. 4b, 5b, 6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.model.actuators import ActuatorModel
from pipeline.model.actuators import actuator_families
from pipeline.model.dynamics import MotionSpec, PoseDynamics, centripetal, load_wrenches
from pipeline.model.geometry import CableRobot
from pipeline.model.linalg import remembered_pinv
from pipeline.model.tensions import feasible_tensions
from pipeline.workspace.criteria import REGISTRY
from pipeline.workspace.criteria.geometry import zero_length


@dataclass(frozen=True)
class Profile:
    """Path coordinate s(t) (m), speed v(t) (m/s) and acceleration a(t) (m/s^2) at times t (s)."""

    t: np.ndarray
    s: np.ndarray
    v: np.ndarray
    a: np.ndarray


def trapezoid(distance: float, v_max: float, t_acc: float, t_dec: float, dt: float) -> Profile:
    """Trapezoidal speed profile over ``distance``: accelerate at v_max / t_acc, cruise at v_max,
    decelerate at v_max / t_dec (section 3, assumption 1). A segment too short to reach v_max
    gets the triangular profile with the same accelerations and a lower peak speed."""
    acc, dec = v_max / t_acc, v_max / t_dec
    ramps = v_max**2 / (2 * acc) + v_max**2 / (2 * dec)
    if distance >= ramps:
        peak, cruise = v_max, (distance - ramps) / v_max
    else:
        peak, cruise = math.sqrt(2 * distance * acc * dec / (acc + dec)), 0.0
    t1 = peak / acc
    t2 = t1 + cruise
    total = t2 + peak / dec
    t = np.linspace(0.0, total, max(math.ceil(total / dt), 2) + 1)
    accelerating, cruising = t < t1, (t >= t1) & (t < t2)
    decelerating = ~(accelerating | cruising)
    v = np.where(accelerating, acc * t, np.where(cruising, peak, peak - dec * (t - t2)))
    a = np.where(accelerating, acc, np.where(cruising, 0.0, -dec))
    s_t2 = peak * t1 / 2 + peak * cruise
    s = np.where(
        accelerating, acc * t**2 / 2,
        np.where(cruising, peak * t1 / 2 + peak * (t - t1),
                 s_t2 + peak * (t - t2) - dec * (t - t2) ** 2 / 2),
    )
    v[decelerating] = np.maximum(v[decelerating], 0.0)
    return Profile(t=t, s=np.minimum(s, distance), v=v, a=a)


def inverse_dynamics(
    robot: CableRobot, positions: np.ndarray, velocities: np.ndarray, accelerations: np.ndarray,
    orientation, motion: MotionSpec, actuator: ActuatorModel, geometric: tuple[str, ...] = (),
) -> dict[str, np.ndarray]:
    """Per-sample actuator quantities (n, m) for poses (n, 3) with their own velocity and
    acceleration (constant orientation): shaft speed theta_dot = J p_dot (eq. 19), shaft
    acceleration J p_ddot (+ J-dot p_dot when ``motion.jdot``), load torque M = (J^T)^+ F with F
    the generalized force of w = m g (-up) - m p_ddot, the weight and inertial force the cables
    balance (eqs. 20, 31 read by Newton's law, :func:`pipeline.model.dynamics.load_wrenches`),
    voltage u = G_v theta_ddot + L_v theta_dot - S_v M (eq. 21). Also the wrench residual
    |J^T M - F| and both sides of the power balance, sum_i M_i theta_dot_i and F . p_dot (n,).
    Under ``tension.model=feasible`` M is the LP's choice (``pipeline.model.tensions``) for each
    sample's own wrench, speed and acceleration, and ``margins`` holds that model's margins;
    under ``pinv`` ``margins`` has the share of the wrench M misses (``unreachable``), and
    always the ``zero_length`` gate's margin; ``geometric``: criteria of the registry that read
    the pose alone (interference), evaluated at every sample as the grid evaluates them."""
    state = PoseDynamics(robot, positions, orientation, motion)
    jt = state.jacobian[:, :, :3]
    theta_dot = np.einsum("nmj,nj->nm", jt, velocities)
    theta_ddot = np.einsum("nmj,nj->nm", jt, accelerations)
    if motion.jdot:
        along = np.einsum("nmj,nj->nm", state.unit, velocities)
        speed2 = np.einsum("nj,nj->n", velocities, velocities)[:, None]
        theta_ddot = theta_ddot + centripetal(speed2, along, state.lengths, motion.winch_radius)
    wrench = load_wrenches(motion, accelerations, robot.up, orientation)[:, : state.structure.shape[1]]
    pinv = remembered_pinv(state.structure, motion.rank_rtol)  # the same for every actuator
    margins = {}
    if motion.tension.model == "feasible":
        other = (actuator.G_v * theta_ddot + actuator.L_v * theta_dot)[:, None, :]
        families = actuator_families(motion.tension, motion.winch_radius, actuator, other, other)
        margins, chosen, _ = feasible_tensions(state.structure, *pinv, wrench[:, None, :],
                                               families, motion.tension.residual_rtol, distribution=True)
        torque = chosen[:, 0, :]
    else:
        torque = np.einsum("nmc,nc->nm", pinv[0], wrench)
    if motion.tension.t_max is not None and "tension_max" not in margins:  # pinv: the rating
        margins["tension_max"] = 1.0 - (torque / motion.winch_radius / motion.tension.t_max).max(axis=1)
    if robot.l_max is not None:
        margins["length"] = 1.0 - (state.lengths / robot.l_max).max(axis=1)
    margins["zero_length"] = zero_length(state, None)
    for name in geometric:
        margins[name] = REGISTRY[name].function(state, actuator)
    reached = np.einsum("ncm,nm->nc", state.structure, torque)
    if "unreachable" not in margins:  # pinv: the share of each sample's wrench M misses
        size = np.linalg.norm(wrench, axis=1)
        missed = np.linalg.norm(reached - wrench, axis=1) / np.where(size > 0, size, 1.0)
        margins["unreachable"] = 1.0 - missed / motion.tension.pinv_residual
    return {
        "theta_dot": theta_dot,
        "theta_ddot": theta_ddot,
        "torque": torque,
        "voltage": actuator.G_v * theta_ddot + actuator.L_v * theta_dot + actuator.load_gain * torque,
        "wrench_residual": np.linalg.norm(reached - wrench, axis=1),
        "power_cables": np.einsum("nm,nm->n", torque, theta_dot),
        "power_load": np.einsum("nj,nj->n", wrench[:, :3], velocities),
        "margins": margins,
    }


def sample_margins(quantities: dict[str, np.ndarray], act: ActuatorModel) -> dict[str, np.ndarray]:
    """Relative margins of every sample, as the CPR-WWA criteria define them (eqs. 30, 32-34);
    under the ``feasible`` model its own (incl. ``unreachable`` and ``slack``) replace them, and
    the cable rating and length margins come with them when those limits are given."""
    worst = {
        "speed": (quantities["theta_dot"], act.speed_limit),
        "torque": (quantities["torque"], act.torque_limit),
        "acceleration": (quantities["theta_ddot"], act.accel_limit),
        "voltage": (quantities["voltage"], act.voltage_limit),
    }
    margins = {name: 1.0 - np.abs(values).max(axis=1) / limit for name, (values, limit) in worst.items()}
    return {**margins, **quantities["margins"]}

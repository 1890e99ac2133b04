"""CPR-WWA's actuator criteria, eqs. (30), (32)-(34) of Filipovic & Kevac (2018): shaft speed,
load torque, shaft acceleration and control voltage against an :class:`ActuatorModel`.

Each margin is 1 - (worst value over cables and the velocity/acceleration set) / limit. Under
the ``feasible`` tension model torque and voltage bound the load torques M (``*_bounds``) and
read the capacity margins of ``criteria.forces``.
"""

from __future__ import annotations

import numpy as np

from pipeline.model.actuators import ActuatorModel
from pipeline.model.dynamics import PoseDynamics


def max_abs_sum_of_ranges(a: tuple, b: tuple) -> np.ndarray:
    """max over (j, k) of |a_j + b_k| from the (max, min) of each term over its own set, without
    forming the j x k product: max(max_j a_j + max_k b_k, -(min_j a_j + min_k b_k)), because
    |x| = max(x, -x) and a maximum of a sum of independent terms is the sum of maxima."""
    return np.maximum(a[0] + b[0], -(a[1] + b[1]))


def _ranges(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(max, min) over the last axis (the velocity or acceleration set)."""
    return values.max(axis=-1), values.min(axis=-1)


def _margin(worst: np.ndarray, limit: float) -> np.ndarray:
    """Worst (n, m) value per cable -> (n,) relative margin."""
    return 1.0 - worst.max(axis=1) / limit


def speed(dyn: PoseDynamics, act: ActuatorModel) -> np.ndarray:
    """Eq. (30): |theta_dot_i| <= omega_mot / (9.5493 N_V) for every velocity of the set."""
    high, low = dyn.shaft_speed_range
    return _margin(np.maximum(high, -low), act.speed_limit)


def torque(dyn: PoseDynamics, act: ActuatorModel) -> np.ndarray:
    """Eq. (32): |M_i| <= M_mot N_M for every acceleration of the set, M from eq. (20)."""
    high, low = dyn.acceleration_range(*dyn.torque_affine)
    return _margin(np.maximum(high, -low), act.torque_limit)


def torque_bounds(dyn: PoseDynamics, act: ActuatorModel) -> tuple:
    """Under ``feasible``: |M| <= M_mot N_M (eq. 32) on the load torques themselves."""
    return -act.torque_limit, act.torque_limit, act.torque_limit


def acceleration(dyn: PoseDynamics, act: ActuatorModel) -> np.ndarray:
    """Eq. (33): |theta_ddot_i| <= M_mot N_M / J_r over every (velocity, acceleration) pair."""
    from_velocity = _ranges(dyn.shaft_accel_from_velocity) if dyn.motion.jdot else (0.0, 0.0)
    from_acceleration = dyn.acceleration_range(dyn.jacobian[:, :, :3], 0.0)
    return _margin(max_abs_sum_of_ranges(from_velocity, from_acceleration), act.accel_limit)


def voltage(dyn: PoseDynamics, act: ActuatorModel) -> np.ndarray:
    """Eq. (34) with u of eq. (21): |G_v theta_ddot + L_v theta_dot - S_v M| <= U_mot over every
    (velocity, acceleration) pair (the motor holds the load torque M: ``ActuatorModel.load_gain``);
    the velocity part and the acceleration part are separable.
    Without J-dot the velocity part is L_v theta_dot (L_v >= 0), whose range is L_v times the
    range of theta_dot, already known from eq. (30)."""
    torque_coefficients, torque_offset = dyn.torque_affine
    from_acceleration = dyn.acceleration_range(  # G_v J a - S_v M, affine in a
        act.G_v * dyn.jacobian[:, :, :3] + act.load_gain * torque_coefficients, act.load_gain * torque_offset
    )
    return _margin(max_abs_sum_of_ranges(dyn.voltage_from_velocity(act), from_acceleration),
                   act.voltage_limit)

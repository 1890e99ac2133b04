"""CPR-WWA's actuator criteria, eqs. (30), (32)-(34) of Filipovic & Kevac (2018): shaft speed,
load torque, shaft acceleration and control voltage against an :class:`ActuatorModel`.

Each margin is 1 - (worst value over cables and the state's set) / limit. A state that drives
its cables offers the worst values (``shaft_speed_range``, ``torque_range``,
``shaft_acceleration_worst``, ``voltage_worst``): CPR-WWA's over its velocity and acceleration
sets (``pipeline.model.dynamics.PoseDynamics``), a path's at each sample
(``pipeline.model.statics.PathStatics`` with a drive). Under the ``feasible`` tension model torque
and voltage bound the state's force variables (``torque_bounds``, ``voltage_bounds``) and read
the capacity margins of ``criteria.forces``.
"""

from __future__ import annotations

import numpy as np

from pipeline.model.actuators import ActuatorModel
from pipeline.model.dynamics import max_abs_sum_of_ranges

__all__ = ["acceleration", "max_abs_sum_of_ranges", "speed", "torque", "torque_bounds", "voltage"]


def _margin(worst: np.ndarray, limit: float) -> np.ndarray:
    """Worst (n, m) value per cable -> (n,) relative margin."""
    return 1.0 - worst.max(axis=1) / limit


def speed(dyn, act: ActuatorModel) -> np.ndarray:
    """Eq. (30): |theta_dot_i| <= omega_mot / (9.5493 N_V) for every velocity of the set."""
    high, low = dyn.shaft_speed_range
    return _margin(np.maximum(high, -low), act.speed_limit)


def torque(dyn, act: ActuatorModel) -> np.ndarray:
    """Eq. (32): |M_i| <= M_mot N_M for every acceleration of the set, M from eq. (20)."""
    high, low = dyn.torque_range
    return _margin(np.maximum(high, -low), act.torque_limit)


def torque_bounds(dyn, act: ActuatorModel) -> tuple:
    """Under ``feasible``: |M| <= M_mot N_M (eq. 32) on the state's force variables."""
    return dyn.torque_bounds(act)


def acceleration(dyn, act: ActuatorModel) -> np.ndarray:
    """Eq. (33): |theta_ddot_i| <= M_mot N_M / J_r over every (velocity, acceleration) pair."""
    return _margin(dyn.shaft_acceleration_worst, act.accel_limit)


def voltage(dyn, act: ActuatorModel) -> np.ndarray:
    """Eq. (34) with u of eq. (21): |G_v theta_ddot + L_v theta_dot - S_v M| <= U_mot over every
    (velocity, acceleration) pair (the motor holds the load torque M: ``ActuatorModel.load_gain``)."""
    return _margin(dyn.voltage_worst(act), act.voltage_limit)

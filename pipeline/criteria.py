"""Workspace criteria: each maps a chunk of poses to a relative margin per pose.

margin = 1 - (worst value over cables and the velocity/acceleration set) / limit, so a pose
satisfies a criterion when its margin is >= 0, and margins of different criteria are comparable.
Criteria are independent functions ``(state, limits) -> (n,) margins``; an analysis composes
them by name (``CRITERIA``). CPR-WWA criteria read a :class:`PoseDynamics` and an
:class:`ActuatorModel`; static criteria read a :class:`PoseStatics` and :class:`StaticLimits`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from pipeline.actuators import ActuatorModel
from pipeline.dynamics import PoseDynamics
from pipeline.statics import PoseStatics

Criterion = Callable[[Any, Any], np.ndarray]


@dataclass(frozen=True)
class StaticLimits:
    """Eq. (10) of the IRPM paper: tensions in [0, s_max] (N), lengths <= l_max (m); a pose is
    singular when the gram ratio of the structure matrix is below ``rank_rtol``."""

    s_max: float
    l_max: float
    rank_rtol: float


def max_abs_sum(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """max over (j, k) of |a[..., j] + b[..., k]| without forming the j x k product.

    Identity: max_{j,k} |a_j + b_k| = max(max_j a_j + max_k b_k, -(min_j a_j + min_k b_k)),
    because |x| = max(x, -x) and a maximum of a sum of independent terms is the sum of maxima.
    """
    return max_abs_sum_of_ranges((a.max(axis=-1), a.min(axis=-1)), (b.max(axis=-1), b.min(axis=-1)))


def max_abs_sum_of_ranges(a: tuple, b: tuple) -> np.ndarray:
    """:func:`max_abs_sum` from the (max, min) of each term over its own set."""
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


def acceleration(dyn: PoseDynamics, act: ActuatorModel) -> np.ndarray:
    """Eq. (33): |theta_ddot_i| <= M_mot N_M / J_r over every (velocity, acceleration) pair."""
    from_velocity = _ranges(dyn.shaft_accel_from_velocity) if dyn.motion.jdot else (0.0, 0.0)
    from_acceleration = dyn.acceleration_range(dyn.jacobian[:, :, :3], 0.0)
    return _margin(max_abs_sum_of_ranges(from_velocity, from_acceleration), act.accel_limit)


def voltage(dyn: PoseDynamics, act: ActuatorModel) -> np.ndarray:
    """Eq. (34) with u of eq. (21): |G_v theta_ddot + L_v theta_dot + S_v M| <= U_mot over every
    (velocity, acceleration) pair; the velocity part and the acceleration part are separable.
    Without J-dot the velocity part is L_v theta_dot (L_v >= 0), whose range is L_v times the
    range of theta_dot, already known from eq. (30)."""
    if dyn.motion.jdot:
        from_velocity = _ranges(act.L_v * dyn.shaft_speed + act.G_v * dyn.shaft_accel_from_velocity)
    else:
        high, low = dyn.shaft_speed_range
        from_velocity = (act.L_v * high, act.L_v * low)
    torque_coefficients, torque_offset = dyn.torque_affine
    from_acceleration = dyn.acceleration_range(  # G_v J a + S_v M, affine in a
        act.G_v * dyn.jacobian[:, :, :3] + act.S_v * torque_coefficients, act.S_v * torque_offset
    )
    return _margin(max_abs_sum_of_ranges(from_velocity, from_acceleration), act.voltage_limit)


def singular(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """The structure matrix must have full rank: margin (g - rtol) / (1 - rtol) in [-rtol, 1]
    with g its gram ratio; a singular pose has no tensions to check (``kernel.GATES``)."""
    return (st.gram_ratio - lim.rank_rtol) / (1.0 - lim.rank_rtol)


def tension_min(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """Eq. (10): s_i >= 0, a cable can only pull. Margin min_i s_i / s_max."""
    return st.tensions.min(axis=1) / lim.s_max


def tension_max(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """Eq. (10): s_i <= s_max."""
    return _margin(st.tensions, lim.s_max)


def length(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """Eq. (10): l_i <= l_max."""
    return _margin(st.lengths, lim.l_max)


CRITERIA: dict[str, Criterion] = {
    "speed": speed,
    "torque": torque,
    "acceleration": acceleration,
    "voltage": voltage,
    "singular": singular,
    "tension_min": tension_min,
    "tension_max": tension_max,
    "length": length,
}

"""Workspace criteria: each maps a chunk of poses to a relative margin per pose.

margin = 1 - (worst value over cables and the velocity/acceleration set) / limit, so a pose
satisfies a criterion when its margin is >= 0, and margins of different criteria are comparable.
Criteria are independent functions ``(state, limits) -> (n,) margins``; an analysis composes
them by name (``CRITERIA``). CPR-WWA criteria read a :class:`PoseDynamics` and an
:class:`ActuatorModel`; static criteria read a :class:`PoseStatics` and :class:`StaticLimits`.
Under the ``feasible`` tension model the criteria on cable forces (unreachable, slack,
tension_max, torque, voltage) read the nested capacity margins of ``pipeline.tensions``,
computed once per chunk and limits (:func:`feasible_solution`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from pipeline.actuators import ActuatorModel
from pipeline.dynamics import PoseDynamics
from pipeline.statics import PoseStatics
from pipeline.tensions import Family, feasible_tensions

Criterion = Callable[[Any, Any], np.ndarray]


@dataclass(frozen=True)
class StaticLimits:
    """Eq. (10) of the IRPM paper: tensions in [t_min, s_max] (N; s_max = ``tension.t_max``,
    inf = no rating), lengths <= l_max (m); a pose is singular when the gram ratio of the
    structure matrix is below ``rank_rtol``. ``scale`` (N) is the unit of the slack margin:
    s_max, or without a rating the magnitude of the force the cables balance (at least 1 N)."""

    s_max: float
    l_max: float
    rank_rtol: float
    scale: float


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
    if _feasible_model(dyn):
        return feasible_margins(dyn, act)["torque"]
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
    if _feasible_model(dyn):
        return feasible_margins(dyn, act)["voltage"]
    torque_coefficients, torque_offset = dyn.torque_affine
    from_acceleration = dyn.acceleration_range(  # G_v J a + S_v M, affine in a
        act.G_v * dyn.jacobian[:, :, :3] + act.S_v * torque_coefficients, act.S_v * torque_offset
    )
    return _margin(max_abs_sum_of_ranges(_voltage_from_velocity(dyn, act), from_acceleration),
                   act.voltage_limit)


def _voltage_from_velocity(dyn: PoseDynamics, act: ActuatorModel) -> tuple[np.ndarray, np.ndarray]:
    """(max, min) (n, m) of the velocity part of eq. (21), L_v theta_dot (+ G_v J-dot p-dot)."""
    if dyn.motion.jdot:
        return _ranges(act.L_v * dyn.shaft_speed + act.G_v * dyn.shaft_accel_from_velocity)
    high, low = dyn.shaft_speed_range
    return act.L_v * high, act.L_v * low


def singular(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """The structure matrix must have full rank. With g its gram ratio in [0, 1] the margin is
    (g - rtol) / (1 - rtol) in [0, 1] for a regular pose and g / rtol - 1 in [-1, 0) for a
    singular one (continuous and increasing in g, -1 for an exactly singular pose, so the
    verdict tolerance of ``pipeline.verdict`` never reaches it). A singular pose has no tensions
    to check (``verdict.GATES``)."""
    g, rtol = st.gram_ratio, lim.rank_rtol
    return np.where(g >= rtol, (g - rtol) / (1.0 - rtol), g / rtol - 1.0)


def unreachable(state, limits) -> np.ndarray:
    """``feasible`` model: every required wrench must be in the range of S (J^T or A), within
    |S S^+ w - w| <= residual_rtol |w|. Margin 1 - residual / (residual_rtol |w|)."""
    return feasible_margins(state, limits)["unreachable"]


def slack(state, limits) -> np.ndarray:
    """A cable can only pull: tensions >= t_min (eq. 10 of the IRPM paper: s_i >= 0). Margin
    (min_i s_i - t_min) / scale (``StaticLimits.scale``); under ``feasible`` the best such margin
    over all valid tension distributions (CPR-8: in units of the torque limit)."""
    if _feasible_model(state):
        return feasible_margins(state, limits)["slack"]
    return (state.tensions - state.spec.tension.t_min).min(axis=1) / limits.scale


def tension_max(state, limits) -> np.ndarray:
    """Eq. (10): s_i <= s_max (IRPM), or the cable rating ``tension.t_max`` (CPR-8)."""
    if _feasible_model(state):
        return feasible_margins(state, limits)["tension_max"]
    if isinstance(state, PoseStatics):
        return 1.0 - (state.tensions / limits.s_max).max(axis=1)  # s_max: scalar or per cable
    high, _ = state.acceleration_range(*state.torque_affine)  # largest M_i = R_i t_i over the set
    return 1.0 - (high / state.motion.winch_radius / state.motion.tension.t_max).max(axis=1)


def length(st: PoseStatics, lim: StaticLimits) -> np.ndarray:
    """Eq. (10): l_i <= l_max."""
    return _margin(st.lengths, lim.l_max)


CRITERIA: dict[str, Criterion] = {
    "speed": speed,
    "torque": torque,
    "acceleration": acceleration,
    "voltage": voltage,
    "singular": singular,
    "unreachable": unreachable,
    "slack": slack,
    "tension_max": tension_max,
    "length": length,
}


def feasible_margins(state, limits) -> dict[str, np.ndarray]:
    """(n,) margins of the ``feasible`` tension model, the worst over the required wrenches:
    ``unreachable`` and one per family of :func:`tension_families`."""
    return feasible_solution(state, limits)[0]


def feasible_solution(state, limits) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:func:`feasible_margins` and the cable forces x (n, K, m) the LPs chose. Cached on the
    state per limits: one set of LPs serves every criterion that reads it."""
    cache = state.__dict__.setdefault("_feasible_solution", {})
    key = id(limits)  # the problem's one limits object; arrays inside make it unhashable
    if key not in cache:
        margins, chosen = feasible_tensions(
            state.structure, *state.wrench_pinv, state.required_wrenches,
            tension_families(state, limits), _tension(state).residual_rtol,
        )
        cache[key] = ({name: value.min(axis=1) for name, value in margins.items()}, chosen)
    return cache[key]


def tension_families(state, limits) -> list[Family]:
    """The intervals on the cable forces x, in gate order. CPR-8 (x = M = R t, per required
    acceleration a_k, :func:`actuator_families`): the voltage must hold for every velocity of
    the set, |G_v J a_k + L_v theta_dot + S_v M| <= U (eqs. 21, 34). IRPM (x = s): slack
    s >= t_min and s <= s_max (eq. 10), in units of ``StaticLimits.scale`` and s_max."""
    tension = _tension(state)
    if isinstance(state, PoseStatics):
        slack = Family("slack", tension.t_min, np.inf, limits.scale)
        if not np.isfinite(limits.s_max).all():
            return [slack]
        return [slack, Family("tension_max", -np.inf, limits.s_max, limits.s_max)]
    high, low = _voltage_from_velocity(state, limits)  # (n, m)
    accel = limits.G_v * np.einsum("nmj,kj->nkm", state.jacobian[:, :, :3], state.wrench_accelerations)
    return actuator_families(tension, state.motion.winch_radius, limits,
                             accel + high[:, None, :], accel + low[:, None, :])


def actuator_families(tension, radius, act: ActuatorModel, high, low) -> list[Family]:
    """CPR-8 families on x = M = R t: slack M >= R t_min, the cable rating M <= R t_max, torque
    |M| <= T (eq. 32), voltage -U <= other + S_v M <= U (eqs. 21, 34), where ``other`` (the
    G_v theta_ddot + L_v theta_dot part) ranges in [low, high] (n, K, m)."""
    torque_limit = act.torque_limit
    families = [Family("slack", radius * tension.t_min, np.inf, torque_limit)]
    if tension.t_max is not None:
        rating = radius * tension.t_max
        families.append(Family("tension_max", -np.inf, rating, rating))
    families.append(Family("torque", -torque_limit, torque_limit, torque_limit))
    volts, s_v = act.voltage_limit, act.S_v
    families.append(Family("voltage", (-volts - low) / s_v, (volts - high) / s_v, volts / s_v))
    return families


def _tension(state):
    return state.spec.tension if isinstance(state, PoseStatics) else state.motion.tension


def _feasible_model(state) -> bool:
    return _tension(state).model == "feasible"

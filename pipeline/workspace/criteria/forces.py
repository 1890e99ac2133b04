"""The ``feasible`` tension model seen by the criteria: the intervals each criterion puts on the
cable forces (families) and the capacity margins of ``pipeline.model.tensions``, computed once per
chunk and limits and shared by every criterion that reads them (unreachable, slack,
tension_max, torque, voltage)."""

from __future__ import annotations

import numpy as np

from pipeline.model.actuators import ActuatorModel
from pipeline.model.statics import PoseStatics
from pipeline.model.tensions import Family, feasible_tensions


def feasible_margins(state, limits) -> dict[str, np.ndarray]:
    """(n,) margins of the ``feasible`` tension model, the worst over the required wrenches:
    ``unreachable`` and one per family of :func:`tension_families`, from hyperplane shifting
    (LPs where it falls back, ``pipeline.model.tensions``). Cached on the state per limits: one
    computation serves every criterion that reads it; ``state.tension_lp`` (n,) records the
    poses the LPs solved."""
    cache = state.__dict__.setdefault("_feasible_margins", {})
    key = id(limits)  # the problem's one limits object; arrays inside make it unhashable
    if key not in cache:
        margins, _, by_lp = feasible_tensions(
            state.structure, *state.wrench_pinv, state.required_wrenches,
            tension_families(state, limits), tension_spec(state).residual_rtol,
        )
        cache[key] = margins
        state.tension_lp = by_lp
    return cache[key]


def feasible_distribution(state, limits) -> np.ndarray:
    """The cable forces x (n, K, m) the ``feasible`` model chooses: the solution of the last
    family's LP (the best voltage margin once every earlier criterion does its best), or
    x = S^+ w where it is unique."""
    return feasible_tensions(
        state.structure, *state.wrench_pinv, state.required_wrenches,
        tension_families(state, limits), tension_spec(state).residual_rtol, distribution=True,
    )[1]


def tension_families(state, limits) -> list[Family]:
    """The intervals on the cable forces x, in gate order. CPR-8 (x = M = R t, per required
    acceleration a_k, :func:`actuator_families`): the voltage must hold for every velocity of
    the set, |G_v J a_k + L_v theta_dot - S_v M| <= U (eqs. 21, 34). IRPM (x = s): slack
    s >= t_min and s <= s_max (eq. 10), in units of ``StaticLimits.scale`` and s_max."""
    tension = tension_spec(state)
    if isinstance(state, PoseStatics):
        slack = Family("slack", tension.t_min, np.inf, limits.scale)
        if not np.isfinite(limits.s_max).all():
            return [slack]
        return [slack, Family("tension_max", -np.inf, limits.s_max, limits.s_max)]
    high, low = voltage_from_velocity(state, limits)  # (n, m)
    accel = limits.G_v * np.einsum("nmj,kj->nkm", state.jacobian[:, :, :3], state.wrench_accelerations)
    return actuator_families(tension, state.motion.winch_radius, limits,
                             accel + high[:, None, :], accel + low[:, None, :])


def actuator_families(tension, radius, act: ActuatorModel, high, low) -> list[Family]:
    """CPR-8 families on x = M = R t: slack M >= R t_min, the cable rating M <= R t_max, torque
    |M| <= T (eq. 32), voltage -U <= other - S_v M <= U (eqs. 21, 34; the motor holds M,
    ``ActuatorModel.load_gain``), where ``other`` (the G_v theta_ddot + L_v theta_dot part)
    ranges in [low, high] (n, K, m): (high - U) / S_v <= M <= (low + U) / S_v."""
    torque_limit = act.torque_limit
    families = [Family("slack", radius * tension.t_min, np.inf, torque_limit)]
    if tension.t_max is not None:
        rating = radius * tension.t_max
        families.append(Family("tension_max", -np.inf, rating, rating))
    families.append(Family("torque", -torque_limit, torque_limit, torque_limit))
    volts, s_v = act.voltage_limit, act.S_v
    families.append(Family("voltage", (high - volts) / s_v, (low + volts) / s_v, volts / s_v))
    return families


def voltage_from_velocity(dyn, act: ActuatorModel) -> tuple[np.ndarray, np.ndarray]:
    """(max, min) (n, m) of the velocity part of eq. (21), L_v theta_dot (+ G_v J-dot p-dot)."""
    if dyn.motion.jdot:
        values = act.L_v * dyn.shaft_speed + act.G_v * dyn.shaft_accel_from_velocity
        return values.max(axis=-1), values.min(axis=-1)
    high, low = dyn.shaft_speed_range
    return act.L_v * high, act.L_v * low


def tension_spec(state):
    """The chunk's :class:`TensionSpec` (statics or CPR-WWA)."""
    return state.spec.tension if isinstance(state, PoseStatics) else state.motion.tension


def feasible_model(state) -> bool:
    """Whether the cable forces come from the ``feasible`` model's LPs."""
    return tension_spec(state).model == "feasible"

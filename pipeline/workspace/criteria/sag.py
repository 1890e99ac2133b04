"""The sag criterion (issue 55 item 4): a heavy cable (``robot.cable_mass``, mu kg/m) must pull hard
enough that its sag stays within ``criteria.sag.ratio`` of its chord. An approximation, labelled
so: the parabolic (small-sag) rule of a taut string under its own weight, the load across the
chord mu g cos(theta) per length (theta the chord's angle to the horizontal) over the chord l,
whose mid-span sag is mu g cos(theta) l^2 / (8 t) at the tension t of its lower end; a cable's
tension grows by mu g per metre it rises, so the platform's end, when it is the upper one, must
pull mu g h more (h its height above the anchor):

    t >= mu g (l cos(theta) / (8 ratio) + max(0, h))

(``PoseGeometry.sag_tensions``). The cable is still a straight line to every other criterion.
With sagging cables (``robot.catenary``) the tensions are the catenary's own, exact. Against Irvine's inextensible
catenary (tests/test_sag.py, docs/model.md section 8) the rule is safe for inclined cables and
underestimates a level cable's sag by up to 2.5 % of it at ratio 0.05 (0.4 % at 0.02)."""

from __future__ import annotations

import numpy as np


def ratio(value) -> str | None:
    """The rule of the key: the sag allowed, a share of the chord."""
    return None if 0 < value <= 0.05 else "must be in (0, 0.05]: the parabolic rule holds for small sag only"


def sag(state, limits, ratio: float) -> np.ndarray:
    """Margin min_i (t_i - t_sag,i) / scale of the minimum-norm tensions (the slack margin's
    units, ``StaticLimits.scale`` or the torque limit); under ``feasible`` its bounds decide."""
    return (state.force_range[1] - state.sag_tensions(ratio)).min(axis=1) / limits.scale


def sag_bounds(state, limits, ratio: float) -> tuple:
    """Under ``feasible``: x >= the least tensions in the state's variables, per pose and cable."""
    return state.variables_of(state.sag_tensions(ratio))[:, None, :], np.inf, limits.scale

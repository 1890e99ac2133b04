"""Heavy cables' rules (issue 55 item 4), each a criterion for users who want the quick answer and
each an approximation, labelled so and measured against the full catenary (tests/test_sag.py,
docs/model.md section 8). A cable (``robot.cable_mass``, mu kg/m) must pull hard enough that

- ``sag``: its sag stays within ``criteria.sag.ratio`` of its chord: the parabolic (small-sag)
  rule of a taut string under its own weight, the load across the chord mu g cos(theta) per
  length (theta the chord's angle to the horizontal) over the chord l, whose mid-span sag is
  mu g cos(theta) l^2 / (8 t) at the tension t of its lower end;
- ``cable_contraction``: the cable it needs beyond its chord stays within
  ``criteria.cable_contraction.share`` of the chord: the parabola's arc exceeds its chord by
  8 d^2 / (3 l), d its sag, so t >= mu g l cos(theta) / sqrt(24 share) at the lower end (WireX's
  contraction rule, in the parabola's closed form);
- ``cable_frequency``: its first transverse natural frequency stays above
  ``criteria.cable_frequency.hz``: a taut string's, f = sqrt(t / mu) / (2 l), so
  t >= 4 mu l^2 f^2 (WireX's eigenfrequency rule);

and a cable's tension grows by mu g per metre it rises, so the platform's end, when it is the
upper one, must pull mu g h more (h its height above the anchor). With ``sag``:

    t >= mu g (l cos(theta) / (8 ratio) + max(0, h))

(``PoseGeometry.sag_tensions``). The cable is still a straight line to every other criterion.
With sagging cables (``robot.catenary``) the sag's tensions are the catenary's own, exact, and
the other two rules are not checked (the catenary gives each cable's length: ``added_length_<c>``).
Against Irvine's inextensible catenary the sag rule is safe for inclined cables and
underestimates a level cable's sag by up to 2.5 % of it at ratio 0.05 (0.4 % at 0.02)."""

from __future__ import annotations

import numpy as np


# Each key's smallest (largest) value keeps the least tension it asks for finite and below 1e17 N
# for any cable the robot keys allow (100 kg/m, 1e4 m, gravity 1e4 m/s^2): beyond, the LPs'
# bounds overflow and a pose's verdict is no longer the rule's.


def ratio(value) -> str | None:
    """The rule of the key: the sag allowed, a share of the chord."""
    return None if 1e-6 <= value <= 0.05 else ("must be in [1e-6, 0.05]: the parabolic rule holds for small sag only, "
                                               "and no hanging cable is straighter")


def share(value) -> str | None:
    """The rule of ``cable_contraction``'s key: the cable allowed beyond the chord, a share of it."""
    return None if 1e-12 <= value <= 0.01 else ("must be in [1e-12, 0.01]: the parabolic rule holds for small sag only, "
                                                "and no hanging cable is straighter")


def hertz(value) -> str | None:
    """The rule of ``cable_frequency``'s key: the least first natural frequency, Hz."""
    return None if 0 < value <= 1e3 else "must be > 0 and at most 1000 (Hz)"


def sag(state, limits, ratio: float) -> np.ndarray:
    """Margin min_i (t_i - t_sag,i) / scale of the minimum-norm tensions (the slack margin's
    units, ``StaticLimits.scale`` or the torque limit); under ``feasible`` its bounds decide."""
    return _floor_margin(state, limits, state.sag_tensions(ratio))


def sag_bounds(state, limits, ratio: float) -> tuple:
    """Under ``feasible``: x >= the least tensions in the state's variables, per pose and cable."""
    return _floor_bounds(state, limits, state.sag_tensions(ratio))


def contraction(state, limits, share: float) -> np.ndarray:
    """The contraction rule's margin, as :func:`sag`'s."""
    return _floor_margin(state, limits, _contraction_tensions(state, share))


def contraction_bounds(state, limits, share: float) -> tuple:
    return _floor_bounds(state, limits, _contraction_tensions(state, share))


def frequency(state, limits, hz: float) -> np.ndarray:
    """The eigenfrequency rule's margin, as :func:`sag`'s."""
    return _floor_margin(state, limits, _frequency_tensions(state, hz))


def frequency_bounds(state, limits, hz: float) -> tuple:
    return _floor_bounds(state, limits, _frequency_tensions(state, hz))


def _contraction_tensions(state, share: float) -> np.ndarray:
    """(n, m) mu g (l cos(theta) / sqrt(24 share) + max(0, h))."""
    return _least(state, state.lengths * _across(state) / np.sqrt(24.0 * share))


def _frequency_tensions(state, hz: float) -> np.ndarray:
    """(n, m) mu (4 l^2 f^2 + g max(0, h))."""
    return _least(state, 4.0 * (state.lengths * hz) ** 2 / state.load.gravity)


def _across(state) -> np.ndarray:
    """(n, m) cos(theta) of each chord."""
    return np.sqrt(np.clip(1.0 - (state.unit @ state.robot.up) ** 2, 0.0, 1.0))


def _least(state, span: np.ndarray) -> np.ndarray:
    """(n, m) mu g (span + max(0, h)): a rule's least tension at the lower end, ``span`` in metres
    of the cable's weight, plus the rise of the platform's end when it is the upper one."""
    rise = state.lengths * np.maximum(state.unit @ state.robot.up, 0.0)
    return state.robot.cable_mass * state.load.gravity * (span + rise)


def _floor_margin(state, limits, least: np.ndarray) -> np.ndarray:
    return (state.force_range[1] - least).min(axis=1) / limits.scale


def _floor_bounds(state, limits, least: np.ndarray) -> tuple:
    return state.variables_of(least)[:, None, :], np.inf, limits.scale

"""Per-pose metrics of a static pose (``output.metrics=true``, ``analysis=statics``), from the
tensions the checked model uses (docs/model.md section 8):

- ``tension_factor``: min_i t_i / max_i t_i of the pose's cable tensions (1: evenly loaded,
  0: a slack cable, negative: one pushes), the minimum-norm tensions of eq. (10) (``pinv``) or
  the distribution the ``feasible`` model writes (``tension.distribution``: by default the
  least-norm one, ``pipeline.model.distribution``), at the feasible poses only: elsewhere none
  is valid;
- ``wrench_max_<w>`` and ``wrench_min_<w>`` for each freedom w of the robot (fx, fy, fz in N, mx,
  my, mz in N m): the largest external wrench along +w and -w the pose holds on top of its load
  within the tension limits (``wrench_min_`` as a negative number). Under ``pinv`` the tensions
  t + mu A^+ e stay minimum-norm, so each cable's limits bound mu in closed form; under
  ``feasible`` it is max mu with A t = w + mu e, t in [t_min, t_max], by ray shooting against
  hyperplane shifting's inequalities (:func:`pipeline.model.tensions.wrench_reach`). inf where no
  limit binds, NaN where the pose does not hold its load (or is singular).

The capacity margin (how far the tensions can shrink into their limits) is every criterion's
own margin, ``margin_slack`` and ``margin_tension_max``.
"""

from __future__ import annotations

import numpy as np

from pipeline.model.geometry import FREEDOMS
from pipeline.model.tensions import ray_interval, wrench_reach

NAMES = {"x": "fx", "y": "fy", "z": "fz", "rx": "mx", "ry": "my", "rz": "mz"}  # a freedom's wrench
WORK = {"pinv": 0.3, "feasible": 0.6}  # a pose's metrics against its statics (the cost model's unit)


def pose_metrics(state, limits, distribution, held: np.ndarray) -> dict[str, np.ndarray]:
    """The metrics (n,) of a chunk's ``PoseStatics`` (one wrench) and its ``StaticLimits``;
    ``distribution``: the ``feasible`` model's written tensions (n, K, m) (its criteria module),
    computed at the ``held`` poses only (every margin satisfied: elsewhere no distribution is
    valid, and the tension factor is NaN)."""
    spec = state.spec
    t_min = np.broadcast_to(np.asarray(spec.tension.t_min, dtype=float), (state.robot.n_cables,))
    t_max = np.broadcast_to(np.asarray(limits.s_max, dtype=float), (state.robot.n_cables,))
    structure = state.structure
    wrench = np.broadcast_to(state.wrench, (len(structure), structure.shape[1]))
    pinv, rank = state.wrench_pinv
    if spec.tension.model == "pinv":
        tensions = state.tensions
        held = ~state.singular & (tensions >= t_min - TOL * limits.scale).all(axis=1) & (
            tensions <= t_max + TOL * limits.scale).all(axis=1)
    else:
        tensions = np.full(state.lengths.shape, np.nan)
        if held.any():
            turned = state.orientation[held] if isinstance(state.orientation, np.ndarray) else state.orientation
            tensions[held] = distribution(spec.state(state.robot, state.positions[held], turned), limits)[:, 0, :]
        reach = wrench_reach(structure, pinv, rank, wrench, spec.tension.t_min, spec.tension.t_max)
    top = tensions.max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        columns = {"tension_factor": np.where(top > 0, tensions.min(axis=1) / top, np.nan)}
    for row, freedom in enumerate(state.rows):
        name = NAMES[FREEDOMS[freedom]]
        for side, sign, key in ((0, 1.0, f"wrench_max_{name}"), (1, -1.0, f"wrench_min_{name}")):
            if spec.tension.model == "pinv":
                largest = ray_interval(tensions, sign * pinv[:, :, row], t_min, t_max)[1]
                mu = np.where(held, np.maximum(largest, 0.0), np.nan)
            else:
                mu = reach[:, side, row]
            columns[key] = sign * mu
    return columns


TOL = 1e-9  # a tension within TOL x the limits' scale of its limit holds it (the margins' atol)

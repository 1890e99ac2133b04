"""Per-pose metrics of a static pose (``output.metrics=true``, ``analysis=statics``), from the
tensions the checked model uses (docs/model.md section 5):

- ``tension_factor``: Pham et al.'s tension factor (Pham, Yeo, Yang, Chen, "Workspace analysis
  of fully restrained cable-driven manipulators", Robotics and Autonomous Systems 57, 2009;
  CASPR's ``TensionFactorMetric``): min_i h_i / max_i h_i of an internal force h, a positive
  vector of the structure matrix's null space (A h = 0: tensions that hold nothing and keep
  every cable taut), load-independent; 1 for evenly tensed cables, 0 where no strictly positive
  h exists (the cables do not close the platform's wrenches) or A lacks a rank. Here h is the
  internal force that maximises the ratio (an LP: max s, s <= h_i <= 1, A h = 0), so the value
  is unique; CASPR takes the vertex of min sum h, h >= 1e-6, which can only be lower or equal,
  and is the same wherever the null space is one-dimensional (m = rows + 1 cables);
- ``tension_ratio``: min_i t_i / max_i t_i of the pose's cable tensions under its load (1:
  evenly loaded, 0: a slack cable, negative: one pushes), the minimum-norm tensions of eq. (10)
  (``pinv``) or the distribution the ``feasible`` model writes (``tension.distribution``: by
  default the least-norm one, ``pipeline.model.distribution``), at the feasible poses only;
- ``capacity_margin``: Guay, Cardou, Cruz-Ruiz and Caro's capacity margin ("Measuring how well
  a structure supports varying external wrenches", 2014; CASPR's ``CapacityMarginMetric``,
  ARACHNIS): the distance from the required wrench (the load's) to the boundary of the
  available wrench set {A t : t_min <= t <= t_max}, a zonotope, in the units of the robot's
  wrench rows (N for forces only; with moments, the Euclidean norm of N and N m together, as
  the published metric): min over its facets of (h(n) - n . w) / |n|. Exact by hyperplane
  shifting's candidate normals (``pipeline.model.capacity``): every facet's normal is among them,
  and any other unit direction's supporting plane lies at least as far. NaN where the pose
  does not hold its load (outside the set the facet formula is no distance) or A lacks a rank;
  inf where no tension bound is met (t_max null);
- ``wrench_max_<w>`` and ``wrench_min_<w>`` for each freedom w of the robot (fx, fy, fz in N, mx,
  my, mz in N m): the largest external wrench along +w and -w the pose holds on top of its load
  within the tension limits (``wrench_min_`` as a negative number). Under ``pinv`` the tensions
  t + mu A^+ e stay minimum-norm, so each cable's limits bound mu in closed form; under
  ``feasible`` it is max mu with A t = w + mu e, t in [t_min, t_max], by ray shooting against
  hyperplane shifting's inequalities (:func:`pipeline.model.tensions.wrench_reach`). inf where no
  limit binds, NaN where the pose does not hold its load (or is singular).

How far each tension sits inside its own limits is every criterion's own margin,
``margin_slack`` and ``margin_tension_max``.
"""

from __future__ import annotations

import numpy as np

from itertools import combinations

from pipeline.model.geometry import FREEDOMS
from pipeline.model.tensions import LP_BLOCKS, block_matrix, ray_interval, wrench_reach

NAMES = {"x": "fx", "y": "fy", "z": "fz", "rx": "mx", "ry": "my", "rz": "mz"}  # a freedom's wrench
# A pose's metrics against the cost model's unit pose of its tension model (2026-11-27, one core,
# whole process less the job without them: the CPR-8's statics 70 us a pose under pinv, 78 us
# under feasible, the example robot's 8 cables 264 us under feasible; the upper ends, so that a
# long job is announced: 0.3 and 0.6 had a 112 000-pose job run 33 s unannounced)
WORK = {"pinv": 10.0, "feasible": 5.0}


def pose_metrics(state, limits, distribution, held: np.ndarray) -> dict[str, np.ndarray]:
    """The metrics (n,) of a chunk's ``PoseStatics`` (one wrench) and its ``StaticLimits``;
    ``distribution``: the ``feasible`` model's written tensions (n, K, m) (its criteria module),
    computed at the ``held`` poses only (every margin satisfied: elsewhere no distribution is
    valid, and the tension factor is NaN)."""
    spec = state.spec
    t_min = np.broadcast_to(np.asarray(spec.tension.t_min, dtype=float), (state.robot.n_cables,))
    t_max = np.broadcast_to(np.asarray(limits.t_max, dtype=float), (state.robot.n_cables,))
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
    full = rank == structure.shape[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        columns = {"tension_factor": np.where(full, tension_factor(structure), 0.0),
                   "tension_ratio": np.where(top > 0, tensions.min(axis=1) / top, np.nan)}
    margin = np.full(len(structure), np.nan)
    holds = held & full
    if holds.any():
        margin[holds] = capacity_margin(structure[holds], wrench[holds], t_min, t_max)
    columns["capacity_margin"] = margin
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


def tension_factor(structure: np.ndarray) -> np.ndarray:
    """(n,) Pham et al.'s tension factor of each structure matrix (n, r, m): the largest
    min_i h_i / max_i h_i over internal forces h (A h = 0, h >= 0), by the LP max s subject to
    A h = 0, s <= h_i <= 1 (always feasible: h = 0, s = 0), block-diagonal over poses."""
    from scipy.optimize import linprog

    n, r, m = structure.shape
    out = np.empty(n)
    width = m + 1  # h, then s
    for start in range(0, n, LP_BLOCKS):
        blocks = structure[start:start + LP_BLOCKS]
        count = len(blocks)
        equality = np.concatenate([blocks, np.zeros((count, r, 1))], axis=2)
        below = np.concatenate([-np.eye(m), np.ones((m, 1))], axis=1)  # s - h_i <= 0
        cost = np.zeros((count, width))
        cost[:, m] = -1.0
        done = linprog(cost.ravel(), A_ub=block_matrix(np.broadcast_to(below, (count, m, width)), width),
                       b_ub=np.zeros(count * m), A_eq=block_matrix(equality, width), b_eq=np.zeros(count * r),
                       bounds=(0.0, 1.0), method="highs")
        if done.status != 0:
            raise RuntimeError(f"tension factor LP failed: {done.message}")
        out[start:start + count] = done.x.reshape(count, width)[:, m]
    return np.clip(out, 0.0, 1.0) + 0.0  # no -0.0


def capacity_margin(structure: np.ndarray, wrench: np.ndarray, t_min, t_max) -> np.ndarray:
    """(n,) the distance from ``wrench`` (n, r) to the boundary of {A t : t_min <= t <= t_max}
    for full-row-rank structure matrices (n, r, m) whose set holds the wrench: the least over
    the candidate facet normals n (unit vectors orthogonal to r - 1 columns, both signs) of
    h(n) - n . w, h(n) = sum_i max(a_i t_min_i, a_i t_max_i) with a_i = n . A_i."""
    n, r, m = structure.shape
    lower = np.broadcast_to(np.asarray(t_min, dtype=float), (m,))
    upper = np.broadcast_to(np.inf if t_max is None else np.asarray(t_max, dtype=float), (m,))
    subsets = list(combinations(range(m), r - 1))
    if r == 1:
        normals = np.ones((n, 1, 1))
    else:
        chosen = np.swapaxes(structure[:, :, list(subsets)], 1, 2)  # (n, k, r, r - 1): columns of each subset
        normals = np.linalg.svd(np.swapaxes(chosen, 2, 3))[2][..., -1, :]  # (n, k, r): orthogonal to them
    normals = np.concatenate([normals, -normals], axis=1)
    along = normals @ structure  # (n, k, m): a_i
    with np.errstate(invalid="ignore"):  # 0 x inf: a cable the normal does not see
        support = np.where(along > 0, along * upper, along * lower)
    support = np.where(along == 0, 0.0, support).sum(axis=2)
    return (support - np.einsum("nkr,nr->nk", normals, wrench)).min(axis=1)

"""The criteria of the ``pinv`` tension model fused into one loop over poses, compiled by numba
(issue 18's fused kernels), one per analysis:

- CPR-WWA (Filipovic & Kevac 2018): per pose, the cable vectors and lengths (eqs. 1-17), the
  shaft Jacobian J (eqs. 18-19), M = (J^T)^+ F affine in the acceleration (eqs. 20, 31) and the
  margins of eqs. (30), (32)-(34), the cable rating and the longest cable;
- statics (Hamed & Zohoor): the structure matrix A of eq. (8) (either moment arm, either cable
  direction), its gram ratio (the singular gate), the tensions s = A^T (A A^T)^-1 f of eqs.
  (7), (10) and the slack, rating and length margins;

in registers: no (poses x cables x set) arrays, no LAPACK call per pose. They compute what the
criteria of ``pipeline.workspace.criteria`` compute from ``PoseDynamics`` and ``PoseStatics``, in
the same order of operations where it matters, and are tested against them (tests/test_fused.py).

The pseudo-inverse of J^T (c x m, c = 3 or 6 rows; A for the statics) takes one of two routes,
each used only where numpy's route (``pipeline.model.linalg.batched_pinv``) is beyond doubt the
same:

- full row rank, gram ratio >= ``BAND`` x rtol: (J^T)^+ F = J G^-1 F with G = J^T J, from the
  Cholesky factor of G scaled to unit diagonal (whose squared diagonal product is the gram
  ratio);
- one short, gram ratio < rtol / ``BAND`` (CPR-WWA only): the CPR-8 with all six columns at the
  zero orientation (a turn about a vertical axis, a different one per pose, changes no cable
  length). Two steps of inverse iteration on G + mu I give the unit w with w^T J^T ~ 0; with
  J'^T = (I - w w^T) J^T, the matrix whose pseudo-inverse the SVD returns when it drops that
  direction, (J'^T)^+ = J' (J'^T J' + s^2 w w^T)^-1. Taken only when |w^T J^T| is at most
  ``DROPPED`` x rtol x sigma_max / ``BAND`` (the SVD surely drops it) and the completed matrix
  passes the full-rank test (the SVD surely keeps the rest).

Every other pose (rank two short, a singular statics pose, or a ratio within a factor ``BAND``
of rtol) is returned as unsettled, and ``pipeline.workspace.kernel`` evaluates it with numpy.

They apply to the ``pinv`` tension model (CPR-WWA: without J-dot, on the extreme velocities and
a product acceleration set, both readings of eqs. 27-29), without per-pose cable quantities
(``pipeline.workspace.compute.fused_unfit``); a job uses them when the cost model says they pay
for numba's import (``compute.kernel=auto``, ``pipeline.workspace.compute.use_fused``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pipeline.model.dynamics import MotionSpec, acceleration_box, inertia_sign, load_wrench_terms
from pipeline.model.geometry import euler_rate_axes, rotation_matrix
from pipeline.model.jit import call_compiled

CRITERIA = ("speed", "torque", "acceleration", "voltage", "tension_max", "length")  # columns of _kernel
STATICS_CRITERIA = ("singular", "slack", "tension_max", "length")  # columns of _statics
BAND = 2.0  # a gram ratio within this factor of rtol is left to numpy, as is a doubtful drop
DROPPED = 0.1  # |w^T J^T| / (rtol sigma_max) below which the SVD surely drops the direction w
SHIFT = 1e-14  # mu / trace(G) of the inverse iteration


def margins(problem, positions: np.ndarray, orientation) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """``margin_<criterion>`` (n,) (and CPR-WWA's ``jacobian_rank``) at one orientation, and
    (n,) the poses left unsettled (their entries are NaN: evaluate them with numpy)."""
    if isinstance(problem.spec, MotionSpec):
        return _cpr_wwa_margins(problem, positions, orientation)
    return _statics_margins(problem, positions, orientation)


def _statics_margins(problem, positions: np.ndarray, orientation):
    spec, lim, robot = problem.spec, problem.limits, problem.robot
    rotation = rotation_matrix(*orientation)
    wrench = load_wrench_terms(spec.load, 0.0, robot.up, rotation)[1]
    m = robot.n_cables
    n = len(positions)
    out = np.empty((n, len(STATICS_CRITERIA)))
    unsettled = np.zeros(n, dtype=np.bool_)
    call_compiled(_statics, np.ascontiguousarray(positions, dtype=float),
                  np.ascontiguousarray(robot.anchors, dtype=float), np.ascontiguousarray(robot.attachments @ rotation.T),
                  spec.cable_direction == "centre", spec.moment_arm == "base",
                  np.ascontiguousarray(wrench[:, None]), float(spec.rank_rtol), float(lim.rank_rtol),
                  np.array(np.broadcast_to(spec.tension.t_min, (m,)), dtype=float),  # writable copies
                  np.array(np.broadcast_to(lim.s_max, (m,)), dtype=float), float(lim.scale),
                  np.inf if robot.l_max is None else float(robot.l_max), out, unsettled)
    return {f"margin_{name}": out[:, STATICS_CRITERIA.index(name)] for name in problem.criteria}, unsettled


def _cpr_wwa_margins(problem, positions: np.ndarray, orientation):
    spec, act, robot = problem.spec, problem.limits, problem.robot
    rotation = rotation_matrix(*orientation)
    rows = 3 if spec.pinv_columns == "translational" else 6
    slope, at_rest = load_wrench_terms(spec.load, inertia_sign(spec), robot.up, rotation)
    loads = np.ascontiguousarray(np.column_stack([slope[:rows], at_rest[:rows]]))
    centre, half = acceleration_box(spec.accelerations)
    m = robot.n_cables
    t_max = np.array(np.broadcast_to(np.inf if spec.tension.t_max is None else spec.tension.t_max, (m,)),
                     dtype=float)  # a writable copy: a read-only array is another type to numba
    l_max = np.inf if robot.l_max is None else float(robot.l_max)
    n = len(positions)
    out = np.empty((n, len(CRITERIA)))
    rank = np.zeros(n, dtype=np.int8)
    unsettled = np.zeros(n, dtype=np.bool_)
    call_compiled(_kernel, np.ascontiguousarray(positions, dtype=float),
                  np.ascontiguousarray(robot.anchors, dtype=float), np.ascontiguousarray(robot.attachments @ rotation.T),
                  np.ascontiguousarray(euler_rate_axes(*orientation)), np.ascontiguousarray(spec.winch_radius, dtype=float),
                  rows, np.ascontiguousarray(spec.velocity_extremes, dtype=float), centre, half, loads,
                  float(spec.rank_rtol), np.array([act.speed_limit, act.torque_limit, act.accel_limit,
                                                   act.voltage_limit], dtype=float),
                  np.array([act.G_v, act.L_v, act.S_v], dtype=float), t_max,
                  l_max, out, rank, unsettled)
    result = {f"margin_{name}": out[:, CRITERIA.index(name)] for name in problem.criteria}
    result["jacobian_rank"] = rank
    return result, unsettled


@njit(cache=True)
def _kernel(positions, anchors, arms, rate_axes, radius, rows, extremes, centre, half, loads, rtol,
            limits, gains, t_max, l_max, out, rank, unsettled):
    """Fill ``out`` (n, 6) with the margins of ``CRITERIA``, ``rank`` and ``unsettled``."""
    n, m = positions.shape[0], anchors.shape[0]
    jac = np.empty((m, 6))
    deflated = np.empty((m, 6))
    lengths = np.empty(m)
    gram = np.empty((rows, rows))
    factor = np.empty((rows, rows))
    scale = np.empty(rows)
    solved = np.empty((rows, 4))
    w = np.empty(rows)
    along = np.empty(m)
    scratch = np.empty((rows, rows))  # G + mu I, then the completed matrix
    iterate, step = np.empty((rows, 1)), np.empty((rows, 1))  # the inverse iteration
    projected = np.empty(rows)  # G w
    warm = np.bool_(False)  # w holds the previous pose's direction (a good start for the next)
    inverse_radius = 1.0 / radius
    torque = np.empty((m, 4))  # C (3 columns) and d of M = C a + d, per cable
    speed_limit, torque_limit, accel_limit, voltage_limit = limits[0], limits[1], limits[2], limits[3]
    g_v, l_v, s_v = gains[0], gains[1], gains[2]
    for p in range(n):
        for i in range(m):  # eqs. (1)-(19): J row i = [u_i, ((R b_i) x u_i) . E] / R_i
            lengths[i], ux, uy, uz = _cable(positions, p, anchors, arms, i, True)
            mx = arms[i, 1] * uz - arms[i, 2] * uy
            my = arms[i, 2] * ux - arms[i, 0] * uz
            mz = arms[i, 0] * uy - arms[i, 1] * ux
            r = inverse_radius[i]
            jac[i, 0], jac[i, 1], jac[i, 2] = ux * r, uy * r, uz * r
            for q in range(3):
                jac[i, 3 + q] = (mx * rate_axes[0, q] + my * rate_axes[1, q] + mz * rate_axes[2, q]) * r
        _gram(jac, rows, m, gram)
        ratio = _scaled_cholesky(gram, rows, factor, scale)
        source = jac
        if ratio >= BAND * rtol:
            _scaled_solve(factor, scale, loads, rows, solved)
            rank[p] = rows
        elif ratio < rtol / BAND and _drop_one(jac, gram, rows, m, rtol, factor, scale, w, warm, along,
                                              deflated, solved, loads, scratch, iterate, step, projected):
            source = deflated
            rank[p] = rows - 1
            warm = True
        else:
            warm = False
            unsettled[p] = True
            for k in range(out.shape[1]):
                out[p, k] = np.nan
            continue
        for i in range(m):  # eqs. (20), (31): M_i = C_i . a + d_i
            for k in range(4):
                total = 0.0
                for r in range(rows):
                    total += source[i, r] * solved[r, k]
                torque[i, k] = total
        worst_speed = worst_torque = worst_accel = worst_voltage = -np.inf
        worst_rating = worst_length = -np.inf
        for i in range(m):
            high, low = -np.inf, np.inf
            for v in range(extremes.shape[0]):  # eq. (30) on the extreme velocities
                value = jac[i, 0] * extremes[v, 0] + jac[i, 1] * extremes[v, 1] + jac[i, 2] * extremes[v, 2]
                high, low = max(high, value), min(low, value)
            worst_speed = max(worst_speed, max(high, -low))
            middle = spread = 0.0  # eq. (33): J a over the acceleration box
            t_middle, t_spread = torque[i, 3], 0.0  # eq. (32): C a + d
            v_middle, v_spread = s_v * torque[i, 3], 0.0  # eq. (34): (G_v J + S_v C) a + S_v d
            for k in range(3):
                middle += jac[i, k] * centre[k]
                spread += abs(jac[i, k]) * half[k]
                t_middle += torque[i, k] * centre[k]
                t_spread += abs(torque[i, k]) * half[k]
                coefficient = g_v * jac[i, k] + s_v * torque[i, k]
                v_middle += coefficient * centre[k]
                v_spread += abs(coefficient) * half[k]
            worst_accel = max(worst_accel, max(middle + spread, -(middle - spread)))
            worst_torque = max(worst_torque, max(t_middle + t_spread, -(t_middle - t_spread)))
            worst_rating = max(worst_rating, (t_middle + t_spread) / radius[i] / t_max[i])
            worst_voltage = max(worst_voltage, max(l_v * high + (v_middle + v_spread),
                                                   -(l_v * low + (v_middle - v_spread))))
            worst_length = max(worst_length, lengths[i] / l_max)
        out[p, 0] = 1.0 - worst_speed / speed_limit
        out[p, 1] = 1.0 - worst_torque / torque_limit
        out[p, 2] = 1.0 - worst_accel / accel_limit
        out[p, 3] = 1.0 - worst_voltage / voltage_limit
        out[p, 4] = 1.0 - worst_rating
        out[p, 5] = 1.0 - worst_length


@njit(cache=True)
def _statics(positions, anchors, arms, centre, base, wrench, rtol, singular_rtol, t_min, s_max, scale,
             l_max, out, unsettled):
    """Fill ``out`` (n, 4) with the margins of ``STATICS_CRITERIA`` and ``unsettled``."""
    n, m = positions.shape[0], anchors.shape[0]
    six = np.int64(6)  # not the literal 6, which numba would compile its callees for once more
    columns = np.empty((m, 6))  # A^T: row i = [u_i; a_i x u_i] (eq. 8)
    lengths = np.empty(m)
    gram = np.empty((6, 6))
    factor = np.empty((6, 6))
    scale_rows = np.empty(6)
    solved = np.empty((6, 1))
    for p in range(n):
        for i in range(m):
            lengths[i], ux, uy, uz = _cable(positions, p, anchors, arms, i, not centre)
            ax, ay, az = arms[i, 0], arms[i, 1], arms[i, 2]
            if base:  # moments about the base centre (eq. 9): a_i = r + R d_i
                ax, ay, az = ax + positions[p, 0], ay + positions[p, 1], az + positions[p, 2]
            columns[i, 0], columns[i, 1], columns[i, 2] = ux, uy, uz
            columns[i, 3] = ay * uz - az * uy
            columns[i, 4] = az * ux - ax * uz
            columns[i, 5] = ax * uy - ay * ux
        _gram(columns, six, m, gram)
        ratio = _scaled_cholesky(gram, six, factor, scale_rows)
        if ratio < BAND * rtol:  # singular or in doubt: numpy's SVD
            unsettled[p] = True
            for k in range(out.shape[1]):
                out[p, k] = np.nan
            continue
        _scaled_solve(factor, scale_rows, wrench, six, solved)
        lowest, worst_rating, worst_length = np.inf, -np.inf, -np.inf
        for i in range(m):
            tension = 0.0  # s = A^T (A A^T)^-1 f (eqs. 7, 10)
            for r in range(6):
                tension += columns[i, r] * solved[r, 0]
            lowest = min(lowest, tension - t_min[i])
            worst_rating = max(worst_rating, tension / s_max[i])
            worst_length = max(worst_length, lengths[i] / l_max)
        if ratio >= singular_rtol:
            out[p, 0] = (ratio - singular_rtol) / (1.0 - singular_rtol)
        else:
            out[p, 0] = ratio / singular_rtol - 1.0
        out[p, 1] = lowest / scale
        out[p, 2] = 1.0 - worst_rating
        out[p, 3] = 1.0 - worst_length


@njit(cache=True, inline="always")
def _cable(positions, p, anchors, arms, i, to_attachment):
    """Length and unit vector (0 for a zero length) of cable i at pose p, from its anchor to its
    attachment point (eq. 1; ``arms``: R b_i) or, without ``to_attachment``, to the platform's
    reference point; the operations in ``geometry.cable_vectors``' order."""
    vx, vy, vz = positions[p, 0], positions[p, 1], positions[p, 2]
    if to_attachment:
        vx, vy, vz = vx + arms[i, 0], vy + arms[i, 1], vz + arms[i, 2]
    vx, vy, vz = vx - anchors[i, 0], vy - anchors[i, 1], vz - anchors[i, 2]
    length = np.sqrt(vx * vx + vy * vy + vz * vz)
    inverse = 1.0 / length if length > 0 else 0.0
    return length, vx * inverse, vy * inverse, vz * inverse


@njit(cache=True, inline="always")
def _gram(jac, rows, m, gram):
    """G = J^T J over the first ``rows`` columns of J (m x 6)."""
    for r in range(rows):
        for s in range(r + 1):
            total = 0.0
            for i in range(m):
                total += jac[i, r] * jac[i, s]
            gram[r, s] = gram[s, r] = total


@njit(cache=True)
def _scaled_cholesky(gram, rows, factor, scale):
    """Lower Cholesky factor L of D^-1 G D^-1 into ``factor``, its diagonal stored as 1 / L_jj,
    with D^-1 = ``scale`` (1 / sqrt of diag G, 1 where 0); returns det(D^-1 G D^-1), the gram
    ratio in [0, 1] (0 when a pivot is not positive). Reciprocals: no division per entry."""
    for i in range(rows):
        scale[i] = 1.0 / np.sqrt(gram[i, i]) if gram[i, i] > 0 else 1.0
    det = 1.0
    for j in range(rows):
        for i in range(j, rows):
            total = gram[i, j] * scale[i] * scale[j]
            for k in range(j):
                total -= factor[i, k] * factor[j, k]
            if i == j:
                if total <= 0.0:
                    return 0.0
                det *= total
                factor[j, j] = 1.0 / np.sqrt(total)
            else:
                factor[i, j] = total * factor[j, j]
    return min(det, 1.0)


@njit(cache=True)
def _scaled_solve(factor, scale, loads, rows, solved):
    """``solved`` = G^-1 ``loads`` (rows x k) from the factor and scale of :func:`_scaled_cholesky`."""
    for k in range(loads.shape[1]):
        for i in range(rows):  # forward: L y = D^-1 b
            total = loads[i, k] * scale[i]
            for j in range(i):
                total -= factor[i, j] * solved[j, k]
            solved[i, k] = total * factor[i, i]
        for i in range(rows - 1, -1, -1):  # backward: L^T x = y, then D^-1 x
            total = solved[i, k]
            for j in range(i + 1, rows):
                total -= factor[j, i] * solved[j, k]
            solved[i, k] = total * factor[i, i]
        for i in range(rows):
            solved[i, k] *= scale[i]


@njit(cache=True)
def _drop_one(jac, gram, rows, m, rtol, factor, scale, w, warm, along, deflated, solved, loads, scratch,
              iterate, step, projected):
    """The one-short route of the module docstring: ``deflated`` J', ``w`` and ``solved`` =
    (J'^T J' + s^2 w w^T)^-1 ``loads``; False when the SVD's choice is in doubt. ``warm``: ``w``
    holds the previous pose's direction, one step from it is tried first."""
    trace = 0.0
    for r in range(rows):
        trace += gram[r, r]
    if not trace > 0.0:
        return False
    for r in range(rows):
        for c in range(rows):
            scratch[r, c] = gram[r, c]
        scratch[r, r] += SHIFT * trace
    if _scaled_cholesky(scratch, rows, factor, scale) <= 0.0:
        return False
    bound = DROPPED * rtol * np.sqrt(trace / rows) / BAND
    found = False
    for attempt in range(2):
        if attempt == 0 and not warm:
            continue
        for r in range(rows):
            iterate[r, 0] = w[r] if attempt == 0 else 1.0 + r / max(rows - 1, 1)  # any start not orthogonal to w
        for _ in range(1 if attempt == 0 else 2):
            _scaled_solve(factor, scale, iterate, rows, step)
            norm = 0.0
            for r in range(rows):
                norm += step[r, 0] * step[r, 0]
            norm = 1.0 / np.sqrt(norm)
            for r in range(rows):
                w[r] = iterate[r, 0] = step[r, 0] * norm
        size = 0.0
        for i in range(m):
            total = 0.0
            for r in range(rows):
                total += w[r] * jac[i, r]
            along[i] = total
            size += total * total
        if np.sqrt(size) <= bound:
            found = True
            break
    if not found:
        return False
    for i in range(m):
        for r in range(rows):
            deflated[i, r] = jac[i, r] - along[i] * w[r]
    curvature = 0.0  # w^T G w
    for r in range(rows):
        total = 0.0
        for c in range(rows):
            total += gram[r, c] * w[c]
        projected[r] = total
        curvature += w[r] * total
    for r in range(rows):  # J'^T J' = (I - w w^T) G (I - w w^T), plus s^2 w w^T
        for c in range(rows):
            scratch[r, c] = (gram[r, c] - w[r] * projected[c] - projected[r] * w[c]
                             + (curvature + trace / rows) * w[r] * w[c])
    if _scaled_cholesky(scratch, rows, factor, scale) < BAND * rtol:
        return False
    _scaled_solve(factor, scale, loads, rows, solved)
    return True

"""The loops of ``pipeline.workspace.fused``, compiled by numba: ``cpr_wwa`` and ``statics``,
one pass over the poses each, and their helpers (the routes they take are in that module's
docstring).

numba compiles them with the signatures of ``SIGNATURES`` (the types ``fused`` passes) when the
module is first imported on a machine, and caches them (``pipeline.model.jit.compiled_loops``).
numba keys that cache by this file: the compiled code uses nothing but numpy and this file
(``tests/test_jit.py`` checks the imports). The two entry points come last: numba compiles them
where they are defined, so what they call must be defined before them.

Both loops take ``BLOCK`` poses at a time: every array of a block holds its poses innermost,
so that each step is one loop over the poses, which the compiler turns into vector
instructions (a pose a lane; with fewer than 64 poses it unrolls the loops whole and vectorises
none of them). The helpers are inlined (``inline="always"``, numba's own inlining) and the
CPR-WWA loop is compiled once for each number of rows of the pseudo-inverse (3 or 6, a
constant), so the compiler sees every small loop's trip count. Each lane does one pose's
operations in one pose's order (no fast-math), so the margins are the doubles of a loop over
single poses (the git history's, tested bit for bit when the blocks came). In the CPR-WWA loop
(:func:`_cpr_wwa`): the geometry, G, its factor and the route's test, the full-rank solve and
torques, the deflated route's (:func:`_block_drop_one`, every lane's inverse iteration from the
same start, so a pose's margins depend on that pose alone), then every settled pose's margins.
Against one pose at a time: CPR-WWA x2.2 at full rank, x1.6-1.7 on the deflated route, the
statics x3.4 (benchmarks/LOG.md, 2026-11-30).
"""

from __future__ import annotations

import numpy as np
from numba import njit

BAND = 2.0  # a gram ratio within this factor of rtol is left to numpy, as is a doubtful drop
BLOCK = 64  # poses a block of a loop holds, each a lane of the vector registers
DROPPED = 0.1  # |w^T J^T| / (rtol sigma_max) below which the SVD surely drops the direction w
SHIFT = 1e-14  # mu / trace(G) of the inverse iteration
FULL, DEFLATED, UNSETTLED = 0, 1, 2  # a pose's route through the CPR-WWA loop

_M, _V, _F = "f8[:, ::1]", "f8[::1]", "f8"  # a C-contiguous matrix, vector, a float
SIGNATURES = {  # name -> its one signature
    "cpr_wwa": f"void({_M}, {_M}, {_M}, {_M}, {_V}, i8, {_M}, {_V}, {_V}, {_M}, {_F}, {_V}, {_V}, {_V}, {_F}, "
               f"{_F}, {_F}, {_M}, i1[::1], b1[::1])",
    "statics": f"void({_M}, {_M}, {_M}, b1, b1, {_M}, {_F}, {_F}, {_V}, {_V}, {_F}, {_F}, {_F}, {_M}, b1[::1])",
}


@njit(cache=True, inline="always")
def _vertices(loads, rows, centre, half, corners, sizes):
    """The 8 corners of the acceleration box into ``corners`` (8, 3) and |F| = |C a + d| at each
    into ``sizes`` (``loads``: C and d, the same at every pose of a chunk)."""
    for vertex in range(8):
        for k in range(3):
            sign = 1.0 if (vertex >> (2 - k)) & 1 else -1.0
            corners[vertex, k] = centre[k] + sign * half[k]
        size = 0.0
        for r in range(rows):
            force = loads[r, 3]
            for k in range(3):
                force += loads[r, k] * corners[vertex, k]
            size += force * force
        sizes[vertex] = np.sqrt(size)


@njit(cache=True, inline="always")
def _unit(vx, vy, vz):
    """Length and unit vector of (vx, vy, vz), the zero vector for a zero length (a cable from
    its anchor, eq. 1: no direction when it has none)."""
    length = np.sqrt(vx * vx + vy * vy + vz * vz)
    inverse = 1.0 / length if length > 0 else 0.0
    return length, vx * inverse, vy * inverse, vz * inverse


@njit(cache=True, inline="always")
def _zero_length(shortest, tol):
    """The zero-length gate's margin min(1, l_min / tol - 1) from a pose's shortest cable
    (``criteria.geometry.zero_length``; NaN stays NaN, as numpy's minimum)."""
    value = shortest / tol - 1.0
    return 1.0 if value > 1.0 else value


@njit(cache=True, inline="always")
def _block_cholesky(gram, rows, factor, scale, det, dead):
    """The lower Cholesky factor of D^-1 G D^-1 for a block of poses (the last axis of every
    array), its diagonal stored as 1 / L_jj (reciprocals: no division per entry), D^-1 =
    ``scale`` (1 / sqrt of diag G, 1 where 0), the product of the pivots ``det`` (the gram ratio,
    where none is ``dead``: not positive)."""
    lanes = BLOCK
    for i in range(rows):
        for b in range(lanes):
            scale[i, b] = 1.0 / np.sqrt(gram[i, i, b]) if gram[i, i, b] > 0 else 1.0
    for b in range(lanes):
        det[b], dead[b] = 1.0, False
    for j in range(rows):  # the pivot first, then its column below
        for b in range(lanes):
            total = gram[j, j, b] * scale[j, b] * scale[j, b]
            for k in range(j):
                total -= factor[j, k, b] * factor[j, k, b]
            dead[b] = dead[b] | (total <= 0.0)
            det[b] *= total
            factor[j, j, b] = 1.0 / np.sqrt(total)
        for i in range(j + 1, rows):
            for b in range(lanes):
                total = gram[i, j, b] * scale[i, b] * scale[j, b]
                for k in range(j):
                    total -= factor[i, k, b] * factor[j, k, b]
                factor[i, j, b] = total * factor[j, j, b]


@njit(cache=True, inline="always")
def _block_factor(jac, rows, m, gram, factor, scale, det, dead):
    """G = J^T J over the first ``rows`` columns of J (``jac`` (m, rows, lanes)) for a block of
    poses, and its :func:`_block_cholesky`."""
    lanes = BLOCK
    for r in range(rows):  # G, each entry from 0 over the cables in order
        for s in range(r + 1):
            for b in range(lanes):
                gram[r, s, b] = 0.0
            for i in range(m):
                for b in range(lanes):
                    gram[r, s, b] += jac[i, r, b] * jac[i, s, b]
            for b in range(lanes):
                gram[s, r, b] = gram[r, s, b]
    _block_cholesky(gram, rows, factor, scale, det, dead)


@njit(cache=True, inline="always")
def _block_ratios(gram, rows, det, dead, ratio, lean):
    """Each pose's gram ratio det(D^-1 G D^-1) (0 where a pivot is not positive) and ``lean``,
    min / max of the diagonal of G: the squared length of the shortest row of J^T against the
    longest; below rtol^2 the SVD drops the short row whatever the gram ratio says
    (``pipeline.model.linalg.batched_pinv``)."""
    for b in range(BLOCK):
        ratio[b] = 0.0 if dead[b] else min(det[b], 1.0)
        least, most = np.inf, 0.0
        for r in range(rows):
            least, most = min(least, gram[r, r, b]), max(most, gram[r, r, b])
        lean[b] = least / most if most > 0.0 else 0.0


@njit(cache=True, inline="always")
def _block_solve(factor, scale, loads, rows, columns, solved, rhs):
    """:func:`_block_solve_lanes` of right-hand sides every pose of a block shares: ``solved``
    (rows, columns, lanes) = G^-1 ``loads`` (rows, columns), each column copied into the lanes
    of the scratch ``rhs`` (rows, lanes) first."""
    for k in range(columns):
        for i in range(rows):
            for b in range(BLOCK):
                rhs[i, b] = loads[i, k]
        _block_solve_lanes(factor, scale, rhs, rows, solved[:, k, :])


@njit(cache=True, inline="always")
def _block_solve_lanes(factor, scale, rhs, rows, solved):
    """G^-1 ``rhs`` (rows, lanes) into ``solved`` (rows, lanes), one right-hand side per pose,
    from :func:`_block_cholesky`'s factor of D^-1 G D^-1: x = D^-1 (L L^T)^-1 D^-1 b."""
    lanes = BLOCK
    for i in range(rows):  # forward: L y = D^-1 b
        for b in range(lanes):
            total = rhs[i, b] * scale[i, b]
            for j in range(i):
                total -= factor[i, j, b] * solved[j, b]
            solved[i, b] = total * factor[i, i, b]
    for i in range(rows - 1, -1, -1):  # backward: L^T x = y, then D^-1 x
        for b in range(lanes):
            total = solved[i, b]
            for j in range(i + 1, rows):
                total -= factor[j, i, b] * solved[j, b]
            solved[i, b] = total * factor[i, i, b]
    for i in range(rows):
        for b in range(lanes):
            solved[i, b] *= scale[i, b]


@njit(cache=True, inline="always")
def _block_drop_one(jac, gram, rows, m, rtol, short, loads, corners, sizes, shifted, factor, scale, det, dead,
                    lane, w, step, along, deflated, projected, solved, torque, residual):
    """The one-short route of the module docstring for the poses of a block marked ``short``,
    which stay marked where it settles them: w from two steps of inverse iteration on G + mu I
    (from a start not orthogonal to it), J' = J - (J w) w^T into ``deflated``, (J'^T J' + s^2 w
    w^T)^-1 ``loads`` into ``solved``, the torques J' solved into ``torque`` and |w . F| / |F|,
    the worst over the acceleration box's corners (``corners``, |F| there: ``sizes``), into
    ``residual``. ``lane`` (5, lanes): scratch, the trace, the bound on |w^T J^T|, a norm, its
    size and w^T G w."""
    lanes = BLOCK
    trace, bound, norm, size, curvature = lane[0], lane[1], lane[2], lane[3], lane[4]
    for b in range(lanes):
        trace[b] = 0.0
    for r in range(rows):
        for b in range(lanes):
            trace[b] += gram[r, r, b]
    for r in range(rows):
        for c in range(rows):
            for b in range(lanes):
                shifted[r, c, b] = gram[r, c, b]
        for b in range(lanes):
            shifted[r, r, b] += SHIFT * trace[b]
    _block_cholesky(shifted, rows, factor, scale, det, dead)
    for b in range(lanes):
        short[b] = short[b] and trace[b] > 0.0 and not dead[b] and min(det[b], 1.0) > 0.0
        bound[b] = DROPPED * rtol * np.sqrt(trace[b] / rows) / BAND
    for r in range(rows):
        for b in range(lanes):
            w[r, b] = 1.0 + r / max(rows - 1, 1)  # any start not orthogonal to w
    for _ in range(2):
        _block_solve_lanes(factor, scale, w, rows, step)
        for b in range(lanes):
            norm[b] = 0.0
        for r in range(rows):
            for b in range(lanes):
                norm[b] += step[r, b] * step[r, b]
        for b in range(lanes):
            norm[b] = 1.0 / np.sqrt(norm[b])
        for r in range(rows):
            for b in range(lanes):
                w[r, b] = step[r, b] * norm[b]
    for b in range(lanes):
        size[b] = 0.0
    for i in range(m):
        for b in range(lanes):
            total = 0.0
            for r in range(rows):
                total += w[r, b] * jac[i, r, b]
            along[i, b] = total
            size[b] += total * total
    for b in range(lanes):
        short[b] = short[b] and np.sqrt(size[b]) <= bound[b]
    for i in range(m):
        for r in range(rows):
            for b in range(lanes):
                deflated[i, r, b] = jac[i, r, b] - along[i, b] * w[r, b]
    for b in range(lanes):
        curvature[b] = 0.0  # w^T G w
    for r in range(rows):
        for b in range(lanes):
            total = 0.0
            for c in range(rows):
                total += gram[r, c, b] * w[c, b]
            projected[r, b] = total
            curvature[b] += w[r, b] * total
    for r in range(rows):  # J'^T J' = (I - w w^T) G (I - w w^T), plus s^2 w w^T
        for c in range(rows):
            for b in range(lanes):
                shifted[r, c, b] = (gram[r, c, b] - w[r, b] * projected[c, b] - projected[r, b] * w[c, b]
                                    + (curvature[b] + trace[b] / rows) * w[r, b] * w[c, b])
    _block_cholesky(shifted, rows, factor, scale, det, dead)
    for b in range(lanes):  # the completed matrix must pass the full-rank test
        short[b] = short[b] and (0.0 if dead[b] else min(det[b], 1.0)) >= BAND * rtol
    _block_solve(factor, scale, loads, rows, 4, solved, step)  # step: scratch once w is found
    for i in range(m):  # eqs. (20), (31) with J' for J
        for k in range(4):
            for b in range(lanes):
                total = 0.0
                for r in range(rows):
                    total += deflated[i, r, b] * solved[r, k, b]
                if short[b]:
                    torque[i, k, b] = total
    for b in range(lanes):  # w . F = (w^T C) a + w^T d
        slope0 = slope1 = slope2 = offset = 0.0
        for r in range(rows):
            slope0 += w[r, b] * loads[r, 0]
            slope1 += w[r, b] * loads[r, 1]
            slope2 += w[r, b] * loads[r, 2]
            offset += w[r, b] * loads[r, 3]
        worst = 0.0
        for vertex in range(8):
            if sizes[vertex] > 0.0:
                along_f = slope0 * corners[vertex, 0] + slope1 * corners[vertex, 1] + slope2 * corners[vertex, 2] + offset
                worst = max(worst, abs(along_f) / sizes[vertex])
        if short[b]:
            residual[b] = worst


@njit(cache=True, inline="always")
def _cpr_wwa(positions, anchors, arms, rate_axes, radius, rows, extremes, centre, half, loads, rtol,
             limits, gains, t_max, l_max, shortest_tol, residual_limit, out, rank, unsettled):
    """The loop of :func:`cpr_wwa`, inlined there with ``rows`` a constant: ``BLOCK`` poses at a
    time, the poses of a block innermost in every array (each a lane of the vector registers,
    with one pose's operations in one pose's order), on either route (the module docstrings)."""
    n, m = positions.shape[0], anchors.shape[0]
    lanes = BLOCK
    at = np.empty((3, lanes))
    jac = np.empty((m, rows, lanes))
    lengths = np.empty((m, lanes))
    gram = np.empty((rows, rows, lanes))
    factor = np.empty((rows, rows, lanes))
    scale = np.empty((rows, lanes))
    solved, rhs = np.empty((rows, 4, lanes)), np.empty((rows, lanes))
    torque = np.empty((m, 4, lanes))
    det, ratio, lean, residual = np.empty(lanes), np.empty(lanes), np.empty(lanes), np.empty(lanes)
    dead, route = np.empty(lanes, np.bool_), np.empty(lanes, np.int8)  # route: FULL, DEFLATED or UNSETTLED
    high, low = np.empty(lanes), np.empty(lanes)
    worst = np.empty((6, lanes))  # speed, torque, acceleration, voltage, rating, length
    inverse_radius = 1.0 / radius
    speed_limit, torque_limit, accel_limit, voltage_limit = limits[0], limits[1], limits[2], limits[3]
    g_v, l_v, load_gain = gains[0], gains[1], gains[2]
    c0, c1, c2, h0, h1, h2 = centre[0], centre[1], centre[2], half[0], half[1], half[2]
    short, shifted, lane = np.empty(lanes, np.bool_), np.empty((rows, rows, lanes)), np.empty((5, lanes))  # the
    w, step, along = np.empty((rows, lanes)), np.empty((rows, lanes)), np.empty((m, lanes))  # one-short route's
    deflated, projected = np.empty((m, rows, lanes)), np.empty((rows, lanes))
    corners, sizes = np.empty((8, 3)), np.empty(8)  # the acceleration box's corners and |F| there
    _vertices(loads, rows, centre, half, corners, sizes)
    for start in range(0, n, lanes):
        for b in range(lanes):  # a short last block repeats its last pose (not written)
            p = min(start + b, n - 1)
            at[0, b], at[1, b], at[2, b] = positions[p, 0], positions[p, 1], positions[p, 2]
        for i in range(m):  # eqs. (1)-(19): J row i = [u_i, ((R b_i) x u_i) . E] / R_i (u_i 0 for a zero length)
            ax, ay, az = arms[i, 0], arms[i, 1], arms[i, 2]
            nx, ny, nz = anchors[i, 0], anchors[i, 1], anchors[i, 2]
            r = inverse_radius[i]
            for b in range(lanes):
                lengths[i, b], ux, uy, uz = _unit(at[0, b] + ax - nx, at[1, b] + ay - ny, at[2, b] + az - nz)
                jac[i, 0, b], jac[i, 1, b], jac[i, 2, b] = ux * r, uy * r, uz * r
                if rows == 6:
                    mx = ay * uz - az * uy
                    my = az * ux - ax * uz
                    mz = ax * uy - ay * ux
                    for q in range(3):
                        jac[i, 3 + q, b] = (mx * rate_axes[0, q] + my * rate_axes[1, q] + mz * rate_axes[2, q]) * r
        _block_factor(jac, rows, m, gram, factor, scale, det, dead)
        _block_ratios(gram, rows, det, dead, ratio, lean)
        any_full = False
        for b in range(lanes):  # the full-rank route's test (the module docstring)
            route[b] = FULL if ratio[b] >= BAND * rtol and lean[b] >= BAND * rtol * rtol else UNSETTLED
            residual[b] = 0.0  # |w . F| / |F|, the worst over the acceleration box's vertices: 0 at full rank
            any_full = any_full or route[b] == FULL
        if any_full:
            _block_solve(factor, scale, loads, rows, 4, solved, rhs)
            for i in range(m):  # eqs. (20), (31)
                for k in range(4):
                    for b in range(lanes):
                        total = 0.0
                        for r in range(rows):
                            total += jac[i, r, b] * solved[r, k, b]
                        torque[i, k, b] = total
        any_short = False
        for b in range(lanes):  # the one-short route's test (the module docstring)
            short[b] = route[b] != FULL and (ratio[b] < rtol / BAND or lean[b] < rtol * rtol / BAND)
            any_short = any_short or short[b]
        if any_short:
            _block_drop_one(jac, gram, rows, m, rtol, short, loads, corners, sizes, shifted, factor, scale, det, dead,
                            lane, w, step, along, deflated, projected, solved, torque, residual)
        any_settled = any_full
        for b in range(lanes):
            if short[b]:
                route[b], any_settled = DEFLATED, True
        if any_settled:
            for k in range(6):
                for b in range(lanes):
                    worst[k, b] = -np.inf
            for i in range(m):
                for b in range(lanes):
                    high[b], low[b] = -np.inf, np.inf
                for v in range(extremes.shape[0]):  # eq. (30)
                    e0, e1, e2 = extremes[v, 0], extremes[v, 1], extremes[v, 2]
                    for b in range(lanes):
                        value = jac[i, 0, b] * e0 + jac[i, 1, b] * e1 + jac[i, 2, b] * e2
                        high[b], low[b] = max(high[b], value), min(low[b], value)
                for b in range(lanes):
                    j0, j1, j2 = jac[i, 0, b], jac[i, 1, b], jac[i, 2, b]
                    t0, t1, t2, t3 = torque[i, 0, b], torque[i, 1, b], torque[i, 2, b], torque[i, 3, b]
                    worst[0, b] = max(worst[0, b], max(high[b], -low[b]))
                    middle = 0.0 + j0 * c0 + j1 * c1 + j2 * c2
                    spread = 0.0 + abs(j0) * h0 + abs(j1) * h1 + abs(j2) * h2
                    t_middle = t3 + t0 * c0 + t1 * c1 + t2 * c2
                    t_spread = 0.0 + abs(t0) * h0 + abs(t1) * h1 + abs(t2) * h2
                    k0, k1, k2 = g_v * j0 + load_gain * t0, g_v * j1 + load_gain * t1, g_v * j2 + load_gain * t2
                    v_middle = load_gain * t3 + k0 * c0 + k1 * c1 + k2 * c2
                    v_spread = 0.0 + abs(k0) * h0 + abs(k1) * h1 + abs(k2) * h2
                    worst[2, b] = max(worst[2, b], max(middle + spread, -(middle - spread)))
                    worst[1, b] = max(worst[1, b], max(t_middle + t_spread, -(t_middle - t_spread)))
                    worst[4, b] = max(worst[4, b], (t_middle + t_spread) / radius[i] / t_max[i])
                    worst[3, b] = max(worst[3, b], max(l_v * high[b] + (v_middle + v_spread),
                                                       -(l_v * low[b] + (v_middle - v_spread))))
                    worst[5, b] = max(worst[5, b], lengths[i, b] / l_max)
        for b in range(min(lanes, n - start)):
            p = start + b
            if route[b] == UNSETTLED:
                unsettled[p] = True
                for k in range(out.shape[1]):
                    out[p, k] = np.nan
                continue
            rank[p] = rows if route[b] == FULL else rows - 1
            out[p, 0] = 1.0 - worst[0, b] / speed_limit
            out[p, 1] = 1.0 - worst[1, b] / torque_limit
            out[p, 2] = 1.0 - worst[2, b] / accel_limit
            out[p, 3] = 1.0 - worst[3, b] / voltage_limit
            out[p, 4] = 1.0 - worst[4, b]
            out[p, 5] = 1.0 - worst[5, b]
            shortest = np.inf
            for i in range(m):
                shortest = min(shortest, lengths[i, b])
            out[p, 6] = _zero_length(shortest, shortest_tol)
            out[p, 7] = 1.0 - residual[b] / residual_limit


# numpy's error model: a block's lanes off the full-rank route (and a short block's repeated
# pose) may divide by zero in its steps (inf or NaN, never written), where Python's would raise
@njit(SIGNATURES["cpr_wwa"], cache=True, nogil=True, error_model="numpy")
def cpr_wwa(positions, anchors, arms, rate_axes, radius, rows, extremes, centre, half, loads, rtol,
            limits, gains, t_max, l_max, shortest_tol, residual_limit, out, rank, unsettled):
    """Fill ``out`` (n, 8) with the margins of ``fused.CRITERIA`` (the zero-length gate's from a
    cable shorter than ``shortest_tol``, the unreachable gate's from the share ``residual_limit``),
    ``rank`` and ``unsettled``: :func:`_cpr_wwa` with its number of rows (3 or 6) as a constant."""
    if rows == 6:
        _cpr_wwa(positions, anchors, arms, rate_axes, radius, 6, extremes, centre, half, loads, rtol,
                 limits, gains, t_max, l_max, shortest_tol, residual_limit, out, rank, unsettled)
    elif rows == 3:
        _cpr_wwa(positions, anchors, arms, rate_axes, radius, 3, extremes, centre, half, loads, rtol,
                 limits, gains, t_max, l_max, shortest_tol, residual_limit, out, rank, unsettled)
    else:
        raise ValueError("the pseudo-inverse has 3 or 6 rows")


@njit(SIGNATURES["statics"], cache=True, nogil=True, error_model="numpy")
def statics(positions, anchors, arms, centre, base, wrench, rtol, singular_rtol, t_min, s_max, scale,
            l_max, shortest_tol, out, unsettled):
    """Fill ``out`` (n, 5) with the margins of ``fused.STATICS_CRITERIA`` and ``unsettled``:
    ``BLOCK`` poses at a time, as :func:`_cpr_wwa` (numpy's error model for the same reason)."""
    n, m = positions.shape[0], anchors.shape[0]
    lanes = BLOCK
    at = np.empty((3, lanes))
    columns = np.empty((m, 6, lanes))  # A^T: row i = [u_i; a_i x u_i] (eq. 8)
    lengths = np.empty((m, lanes))
    gram, factor = np.empty((6, 6, lanes)), np.empty((6, 6, lanes))
    scale_rows, solved, rhs = np.empty((6, lanes)), np.empty((6, 1, lanes)), np.empty((6, lanes))
    det, ratio, lean = np.empty(lanes), np.empty(lanes), np.empty(lanes)
    dead = np.empty(lanes, np.bool_)
    lowest, worst_rating, worst_length, shortest = np.empty(lanes), np.empty(lanes), np.empty(lanes), np.empty(lanes)
    for start in range(0, n, lanes):
        for b in range(lanes):  # a short last block repeats its last pose (not written)
            p = min(start + b, n - 1)
            at[0, b], at[1, b], at[2, b] = positions[p, 0], positions[p, 1], positions[p, 2]
        for i in range(m):  # each cable from its anchor to its attachment point or (centre) the reference point
            ax, ay, az = arms[i, 0], arms[i, 1], arms[i, 2]
            nx, ny, nz = anchors[i, 0], anchors[i, 1], anchors[i, 2]
            for b in range(lanes):
                vx, vy, vz = at[0, b], at[1, b], at[2, b]
                if not centre:
                    vx, vy, vz = vx + ax, vy + ay, vz + az
                lengths[i, b], ux, uy, uz = _unit(vx - nx, vy - ny, vz - nz)
                bx, by, bz = ax, ay, az
                if base:  # moments about the base centre (eq. 9): a_i = r + R d_i
                    bx, by, bz = bx + at[0, b], by + at[1, b], bz + at[2, b]
                columns[i, 0, b], columns[i, 1, b], columns[i, 2, b] = ux, uy, uz
                columns[i, 3, b] = by * uz - bz * uy
                columns[i, 4, b] = bz * ux - bx * uz
                columns[i, 5, b] = bx * uy - by * ux
        _block_factor(columns, 6, m, gram, factor, scale_rows, det, dead)
        _block_ratios(gram, 6, det, dead, ratio, lean)
        _block_solve(factor, scale_rows, wrench, 6, 1, solved, rhs)
        for b in range(lanes):
            lowest[b], worst_rating[b], worst_length[b], shortest[b] = np.inf, -np.inf, -np.inf, np.inf
        for i in range(m):
            for b in range(lanes):
                tension = 0.0  # s = A^T (A A^T)^-1 f (eqs. 7, 10)
                for r in range(6):
                    tension += columns[i, r, b] * solved[r, 0, b]
                lowest[b] = min(lowest[b], tension - t_min[i])
                worst_rating[b] = max(worst_rating[b], tension / s_max[i])
                worst_length[b] = max(worst_length[b], lengths[i, b] / l_max)
                shortest[b] = min(shortest[b], lengths[i, b])
        for b in range(min(lanes, n - start)):
            p = start + b
            if ratio[b] < BAND * rtol or lean[b] < BAND * rtol * rtol:  # singular or in doubt: numpy's SVD
                unsettled[p] = True
                for k in range(out.shape[1]):
                    out[p, k] = np.nan
                continue
            if ratio[b] >= singular_rtol:
                out[p, 0] = (ratio[b] - singular_rtol) / (1.0 - singular_rtol)
            else:
                out[p, 0] = ratio[b] / singular_rtol - 1.0
            out[p, 1] = lowest[b] / scale
            out[p, 2] = 1.0 - worst_rating[b]
            out[p, 3] = 1.0 - worst_length[b]
            out[p, 4] = _zero_length(shortest[b], shortest_tol)

"""Certified verdicts on boxes of positions: every pose of a box feasible, or none (issue 57).

Gouttefarde, Daney and Merlet (IEEE T-RO 27(1), 2011) certify boxes of poses inside or outside
the wrench-feasible workspace by interval analysis. Here, for a box B of platform positions at
one orientation, with pulling cables t in [t_min, t_max] that must balance every wrench w_k of
the required set (A(p) t = w_k, ``pipeline.model.statics``):

- the structure matrix over the box is enclosed by the mean-value form
  u(p) in u(c) + J(B) (B - c), J = (I - u u^T) / l the derivative of the unit vector u = d / |d|
  of a cable's vector d = p + R b_i - a_i, c the box's centre (:func:`structure_enclosure`),
  and any product of A(p) with a vector by Taylor's form to second order, through A(c),
  dA/dp at c and d2A/dp2 over the box (:meth:`BoxEnclosure.times`), which keeps the cables'
  cancellations to second order;
- **inside** (:func:`inside`): tensions t0 feasible at the centre, their first-order motion D
  (A(c) D_l = -(dA/dp_l) t0) and a right inverse K of A(c) give, for every p in B, the tensions
  t = t0 + D (p - c) + K e with (A(p) K) e = w - A(p) (t0 + D (p - c)) =: -r(p), r of second
  order in the box's width. With M = A(B) K - I, every such e lies in [-beta v, beta v],
  beta = |r|_v / (1 - |M|_v) (a contraction when |M|_v < 1, in the norm weighted by v, the
  Perron vector of |M|), and in -r - M [-beta v, beta v]; if t stays in [t_min, t_max] for all
  of them, every pose of the box is feasible: the tensions are exhibited;
- **outside** (:func:`outside`): Farkas' lemma for a box of tensions: no t in [t_min, t_max]
  gives A t = w when some y has y.w > sum_i max(a_i t_min_i, a_i t_max_i), a_i = y.A_i; the y
  that separates best over the whole box to first order (an LP, :func:`robust_separators`) and
  still separates over the enclosure proves every pose of the box infeasible.

Cable lengths are enclosed exactly (the nearest and farthest points of a box from a point):
inside needs every cable between the collapse length and ``l_max``, outside one cable longer
than ``l_max`` everywhere.

Everything is computed in :mod:`pipeline.model.intervals` (outward rounding), from the anchors,
attachments and tension limits as given (doubles, exact), the rotation enclosed from its angles,
and the required wrenches as the statics forms them, widened by ``WRENCH_RTOL`` of the terms
that form them (their round-off is a few units in the last place of those). The floats chosen
at the centre (t0, D, K, y) need no rigour: the interval tests check them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.model.highs import block_columns, solved

from pipeline.model.intervals import Interval, cross, down, stack, up

WRENCH_RTOL = 1e-12  # the required wrenches' enclosure, relative to the size of the terms forming them
INSIDE, OUTSIDE, UNDECIDED = 1, -1, 0  # a box's verdict


@dataclass(frozen=True)
class BoxStatics:
    """What the certificates read at one orientation: ``offsets`` (m, 3) the enclosure of
    R b_i - a_i (or -a_i when every cable runs to the reference point, ``cable_direction=centre``),
    so that a cable's vector is p + offset; ``arms`` (m, 3) the enclosure of R b_i; ``rows`` the
    freedoms the cables balance (``CableRobot.dofs``); ``wrenches`` (K, k) the required wrenches'
    enclosure; ``lower`` and ``upper`` (m,) the tension limits (N, upper may be inf); ``l_max``
    (m, or inf) and ``shortest`` (m): a cable must be between them; ``anchors`` (m, 3) and ``body``
    (k, 3), the enclosures of a_i and of the platform's vertices R v_k (its shape's, else its
    attachments' hull), ``normals`` (f, 3) of its shape's faces' normals R n_f (none without a
    shape): what the interference criteria's bounds read (``pipeline.model.clearance_bounds``)."""

    offsets: Interval
    arms: Interval
    rows: tuple[int, ...]
    wrenches: Interval
    lower: np.ndarray
    upper: np.ndarray
    l_max: float
    shortest: float
    anchors: Interval
    body: Interval
    normals: Interval


PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # the second derivatives d2/dp_a dp_b, a <= b


@dataclass(frozen=True)
class BoxEnclosure:
    """The enclosures over N boxes: ``centre`` (N, k, m) of A(c) at each box's centre point c;
    ``gradient`` (N, 3, k, m) of dA/dp_l at c; ``slopes`` (N, 3, k, m) of dA/dp_l over the box;
    ``curvature`` (N, 6, k, m) of d2A/dp_a dp_b over the box (a <= b, ``PAIRS``); ``step``
    (N, 3) of B - c, so that A(p) - A(c) lies in sum_l slopes_l step_l (the mean-value theorem,
    entry by entry) and in the second-order Taylor form of :meth:`times`, where a product of A(p)
    with a vector keeps the cables' cancellations to second order; ``structure`` (N, k, m) of
    A(p) entry by entry; ``unit`` (N, m, 3) of the cables' unit vectors u_i over the box; ``lengths``
    (N, m) of the cables' lengths; ``regular`` (N,) whether no
    cable can collapse in the box (where one can, the structure's enclosures are not valid and
    only the lengths decide)."""

    centre: Interval
    gradient: Interval
    slopes: Interval
    curvature: Interval
    step: Interval
    structure: Interval
    unit: Interval
    lengths: Interval
    regular: np.ndarray

    def rows(self, index) -> BoxEnclosure:
        return BoxEnclosure(*(part[index] for part in (self.centre, self.gradient, self.slopes, self.curvature, self.step,
                                                        self.structure, self.unit, self.lengths)), self.regular[index])

    def products(self) -> list[Interval]:
        """(N, 3) each of ``PAIRS``' (p_a - c_a)(p_b - c_b) over the box, halved where a = b
        (the Taylor form's 1/2 of the two equal terms; its square's enclosure, from 0)."""
        return [self.step[:, a].square() * 0.5 if a == b else self.step[:, a] * self.step[:, b] for a, b in PAIRS]

    def times(self, points: np.ndarray, combine) -> Interval:
        """An enclosure of ``combine(A(p), points)`` over the box for a product ``combine``
        linear in A, by Taylor's theorem to second order about c (entry by entry, the remainder's
        point in the box): ``combine(A(c)) + sum_l combine(dA/dp_l(c)) (p_l - c_l)
        + 1/2 sum_ab combine(d2A/dp_a dp_b (B)) (p_a - c_a)(p_b - c_b)``, intersected with the
        mean-value form ``combine(A(c)) + sum_l combine(dA/dp_l(B)) (p_l - c_l)``. On small boxes
        Taylor's form halves the second-order term, and more where a square keeps its sign (at
        level 15 of IPAnema 1's paving 60 % of the boxes the mean-value form left undecided outside
        are proven, benchmarks/LOG.md); on boxes as large as the cables' lengths the mean-value
        form is the tighter."""
        centre = combine(self.centre, points)
        def per_box(factor: Interval) -> Interval:
            return factor[(slice(None),) + (None,) * (centre.lo.ndim - 1)]
        taylor, mean_value = centre, centre
        for axis in range(3):
            taylor = taylor + combine(self.gradient[:, axis], points) * per_box(self.step[:, axis])
            mean_value = mean_value + combine(self.slopes[:, axis], points) * per_box(self.step[:, axis])
        for pair, product in enumerate(self.products()):
            taylor = taylor + combine(self.curvature[:, pair], points) * per_box(product)
        return taylor.intersect(mean_value)


@dataclass(frozen=True)
class BuildErrors:
    """Build errors followed by the tensions to first order, as the positions are (:func:`inside`):
    P parameters delta_j, each within +-``tolerances``_j, each moving every cable's vector
    d_i = p + R b_i - a_i by ``moves``_ji delta_j and its arm R b_i by ``arms``_ji delta_j ((P, m, 3)
    enclosures: an anchor's coordinate a_il moves d_i by -e_l and no arm, an attachment's b_il moves
    both by R e_l). ``nominal``: the enclosure of the robot as designed (any other tolerance kept);
    ``centre``: the enclosure over the tolerances at each box's centre point alone (a box of zero
    width, :func:`errors_residual`); ``rates`` (N, K, m, P): E_j, the tensions' motion per parameter
    at the box's centre, A(c) E_j = -(dA/ddelta_j)(c) t0 (:func:`error_slopes`)."""

    nominal: BoxEnclosure
    centre: BoxEnclosure
    rates: np.ndarray
    moves: Interval
    arms: Interval
    tolerances: np.ndarray

    def rows(self, index) -> BuildErrors:
        return BuildErrors(self.nominal.rows(index), self.centre.rows(index), self.rates[index], self.moves, self.arms,
                           self.tolerances)


def error_slopes(statics: BoxStatics, slopes: Interval, unit: Interval, moves: Interval, arms: Interval,
                 parameter: int, cables=slice(None)) -> Interval:
    """(N, k, m) dA/ddelta_j from dA/dp_l (``slopes`` (N, 3, k, m)) and the unit vectors u_i
    (``unit`` (N, m, 3)), over a box or at its centre: column i is sum_l moves_jil (dA/dp_l)_i
    plus [0; arms_ji x u_i] (the arm's own motion), on the rows of the robot's freedoms; only the
    columns ``cables`` (an index of the cables: the others are zero where delta_j moves no more)."""
    total = None
    moving, turning = moves[parameter][cables], arms[parameter][cables]  # (c, 3)
    for axis in range(3):
        term = slopes[:, axis][..., cables] * moving[None, None, :, axis]
        total = term if total is None else total + term
    moment = cross(turning[None], unit[:, cables])  # (N, c, 3)
    zero = np.zeros(moment.shape)
    rows = list(statics.rows)
    return total + Interval(np.swapaxes(np.concatenate([zero, moment.lo], axis=-1), 1, 2)[:, rows],
                            np.swapaxes(np.concatenate([zero, moment.hi], axis=-1), 1, 2)[:, rows])


def structure_enclosure(statics: BoxStatics, lo: np.ndarray, hi: np.ndarray, centre: np.ndarray) -> BoxEnclosure:
    """Enclosures of A(p), its derivatives and the lengths over the boxes [lo, hi] (N, 3), by
    the mean-value form about ``centre`` (N, 3), a point of each box, for every offset R b_i - a_i
    in ``statics.offsets`` (a robot within build tolerances: the unit vectors at the centre by the
    same form about the offsets' midpoints)."""
    box = Interval(lo, hi)[:, None, :]  # (N, 1, 3)
    vectors, lengths, unit = _directions(box + statics.offsets, statics.shortest)  # over B: d(B), |d(B)|, d/|d|
    regular = (lengths.lo > statics.shortest).all(axis=1)
    middle = (statics.offsets.lo + statics.offsets.hi) / 2  # (m, 3), doubles
    unit_centre = _directions(Interval.point(centre)[:, None, :] + Interval.point(middle), statics.shortest)[2]
    _, reach, near = _directions(Interval.point(centre)[:, None, :] + statics.offsets, statics.shortest)
    change = None
    for axis, column in enumerate(_unit_slopes(near, reach)):
        term = column * (statics.offsets[..., axis:axis + 1] - middle[..., axis:axis + 1])
        change = term if change is None else change + term
    unit_centre = (unit_centre + change).intersect(near)
    step = Interval(down(lo - centre), up(hi - centre))  # B - c, (N, 3)
    for _ in range(2):  # the derivative's enclosure from the unit vectors', then again from the tighter ones
        slopes, change = [], None
        for axis, column in enumerate(_unit_slopes(unit, lengths)):
            slopes.append(_columns(statics, column))
            term = column * step[:, None, axis:axis + 1]
            change = term if change is None else change + term
        unit = (unit_centre + change).intersect(unit)
    gradient = [_columns(statics, column) for column in _unit_slopes(unit_centre, reach)]
    curvature = [_columns(statics, column) for column in _unit_curvatures(unit, lengths)]
    return BoxEnclosure(_columns(statics, unit_centre), stack(gradient, axis=1), stack(slopes, axis=1),
                        stack(curvature, axis=1), step, _columns(statics, unit), unit, lengths, regular)


def _directions(vectors: Interval, shortest: float) -> tuple[Interval, Interval, Interval]:
    """The cable vectors d, their lengths |d| (at least ``shortest``: a cable that may collapse
    makes its box irregular) and the naive enclosure of d / |d| within [-1, 1]."""
    lengths = vectors.square().sum(axis=-1).sqrt()
    safe = Interval(np.maximum(lengths.lo, shortest), np.maximum(lengths.hi, shortest))
    unit = (vectors / safe[..., None]).intersect(Interval(np.full(vectors.shape, -1.0), np.full(vectors.shape, 1.0)))
    return vectors, safe, unit


def _unit_slopes(unit: Interval, lengths: Interval) -> list[Interval]:
    """du/dd_axis = (e_axis - u u_axis) / l, per axis, from enclosures of u and l (N, m)."""
    columns = []
    for axis in range(3):
        column = -(unit * unit[..., axis:axis + 1])
        own = -(unit[..., axis].square())
        column = Interval(column.lo.copy(), column.hi.copy())
        column.lo[..., axis], column.hi[..., axis] = own.lo, own.hi
        columns.append((column + np.eye(3)[axis]) / lengths[..., None])
    return columns


def _unit_curvatures(unit: Interval, lengths: Interval) -> list[Interval]:
    """d2u/dd_a dd_b = (3 u u_a u_b - e_a u_b - e_b u_a - delta_ab u) / l^2 for each of ``PAIRS``,
    from enclosures of u and l (N, m) (u_a^2 by its square's enclosure where a = b)."""
    columns = []
    squared = lengths.square()[..., None]
    for a, b in PAIRS:
        if a == b:
            value = unit * unit[..., a:a + 1].square() * 3.0 - unit
            terms = ((a, unit[..., a] * 2.0),)
        else:
            value = unit * unit[..., a:a + 1] * unit[..., b:b + 1] * 3.0
            terms = ((a, unit[..., b]), (b, unit[..., a]))
        lo, hi = value.lo.copy(), value.hi.copy()
        for axis, term in terms:
            entry = value[..., axis] - term
            lo[..., axis], hi[..., axis] = entry.lo, entry.hi
        columns.append(Interval(lo, hi) / squared)
    return columns


def _columns(statics: BoxStatics, unit: Interval) -> Interval:
    """(N, k, m) the structure matrix's rows of the freedoms from the cables' unit vectors (N, m, 3)
    (or their derivatives: the arms are fixed): columns [u_i; arm_i x u_i]."""
    moment = cross(statics.arms, unit)
    rows = list(statics.rows)
    return Interval(np.swapaxes(np.concatenate([unit.lo, moment.lo], axis=-1), 1, 2)[:, rows],
                    np.swapaxes(np.concatenate([unit.hi, moment.hi], axis=-1), 1, 2)[:, rows])


def _matmul(a: Interval, points: np.ndarray) -> Interval:
    """a (..., r, j) @ points (..., j, c), an interval matrix times doubles, rounded outward."""
    total = None
    for j in range(a.shape[-1]):
        term = a[..., :, j:j + 1] * Interval.point(points[..., j:j + 1, :])
        total = term if total is None else total + term
    return total


def _matvec(points: np.ndarray, a: Interval) -> Interval:
    """points (..., r, c) @ a (..., c), doubles times an interval vector, rounded outward."""
    total = None
    for c in range(points.shape[-1]):
        term = Interval.point(points[..., :, c]) * a[..., c:c + 1]
        total = term if total is None else total + term
    return total


def _upper_row_sums(values: np.ndarray) -> np.ndarray:
    """Upper bounds of the row sums (last axis) of non-negative doubles."""
    return Interval(values, values).sum(axis=-1).hi


def inside(statics: BoxStatics, enclosure: BoxEnclosure, wrenches: Interval, tensions: np.ndarray, rates: np.ndarray,
           right_inverse: np.ndarray, errors: BuildErrors | None = None) -> np.ndarray:
    """(N,) whether every pose of each box is proven feasible: for every required wrench k (every
    wrench of its enclosure ``wrenches`` (N, K, k): ``statics.wrenches`` per box, or a moving
    platform's own), the tensions t0 + K e of the module's argument stay within the limits. ``tensions`` (N, K, m):
    t0 per box and wrench (any doubles; good ones have room to both limits), ``right_inverse``
    (N, m, k): K with A(c) K close to I (the pseudo-inverse at the centre). With ``errors`` (a
    robot within build tolerances) the tensions also follow each error to first order,
    t = t0 + D (p - c) + E delta + K e, and r(p, delta) is r(p, 0) (over ``errors.nominal``) plus
    sum_j (dr/ddelta_j)(B, Delta) delta_j, dr/ddelta_j = (dA/ddelta_j) t + A E_j, zero at the centre:
    the errors' part of r is of second order, where the enclosure of A over the tolerances alone
    leaves it of first order (:func:`errors_residual`)."""
    n_rows = enclosure.centre.shape[1]
    size = (enclosure.times(right_inverse, _matmul) - np.eye(n_rows)).magnitude()  # |M|, M = A(B) K - I, (N, k, k)
    weights = _perron(size)  # (N, k) > 0: |M| contracts in the norm max_i |x_i| / v_i when (|M| v)_i < v_i
    contraction = up(_upper_row_sums(up(size * weights[:, None, :])) / weights).max(axis=-1)  # (N,)
    moved, residual = followed(statics, enclosure, wrenches, tensions, rates, errors)
    room = down(1.0 - contraction)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        scaled = up(residual.magnitude() / weights[:, None, :]).max(axis=-1)  # |r|_v, (N, K)
        beta = np.where(room[:, None] > 0, up(scaled / np.where(room > 0, room, 1.0)[:, None]), np.inf)  # |e|_v <= beta
        bound = up(beta[..., None] * weights[:, None, :])  # |e_i| <= beta v_i, (N, K, k)
        spread = _upper_row_sums(up(size[:, None] * bound[:, :, None, :]))  # |M| |e|, (N, K, k)
    solution = (-residual + Interval(-spread, spread)).intersect(Interval(-bound, bound))
    change = _matvec(right_inverse[:, None], solution)  # K e, (N, K, m)
    reached = moved + change
    held = (reached.lo >= statics.lower) & (reached.hi <= statics.upper)
    return enclosure.regular & (contraction < 1.0) & np.isfinite(beta).all(axis=1) & held.all(axis=(1, 2)) \
        & (enclosure.lengths.lo > statics.shortest).all(axis=1) & (enclosure.lengths.hi <= statics.l_max).all(axis=1)


def residual_enclosure(enclosure: BoxEnclosure, wrenches: Interval, tensions: np.ndarray, rates: np.ndarray) -> Interval:
    """(N, K, k) an enclosure of r(p) = A(p) (t0 + D (p - c)) - w over each box and every wrench w
    of ``wrenches``, for ``tensions`` t0 (N, K, m) and ``rates`` D (N, K, m, 3), s = p - c:

        r(B) in [A(c) t0 - w] + sum_l [(dA/dp_l)(c) t0 + A(c) D_l] s_l
                + 1/2 sum_ab (d2A/dp_a dp_b)(B) t0 s_a s_b + sum_ab (dA/dp_b)(B) D_a s_a s_b

    (Taylor's form of :meth:`BoxEnclosure.times` for A(p) t0, and A(p) - A(c) in sum_b
    (dA/dp_b)(B) s_b for A(p) D s), intersected with the mean-value form
    [A(c) t0 - w] + sum_l [(dA/dp_l)(B) t0 + A(B) D_l] s_l (the tighter on large boxes, as in
    :meth:`BoxEnclosure.times`). With A(c) D_l = -(dA/dp_l)(c) t0 the first-order term vanishes
    but for rounding: r is of second order in the box's width."""
    residual = mean_value = _tension_wrench(enclosure.centre, tensions) - wrenches
    for axis in range(3):
        rate = (_tension_wrench(enclosure.gradient[:, axis], tensions)
                + _tension_wrench(enclosure.centre, rates[..., axis]))
        residual = residual + rate * enclosure.step[:, None, None, axis]
        rate = (_tension_wrench(enclosure.slopes[:, axis], tensions)
                + _tension_wrench(enclosure.structure, rates[..., axis]))
        mean_value = mean_value + rate * enclosure.step[:, None, None, axis]
    for pair, ((a, b), product) in enumerate(zip(PAIRS, enclosure.products())):
        # per product (1/2 s_a^2, or s_a s_b): d2A/dp_a dp_b t0, and 2 slopes_a D_a, or slopes_b D_a + slopes_a D_b
        term = _tension_wrench(enclosure.curvature[:, pair], tensions)
        if a == b:
            term = term + _tension_wrench(enclosure.slopes[:, a], rates[..., a]) * 2.0
        else:
            term = (term + _tension_wrench(enclosure.slopes[:, b], rates[..., a])
                    + _tension_wrench(enclosure.slopes[:, a], rates[..., b]))
        residual = residual + term * product[:, None, None]
    return residual.intersect(mean_value)


def followed(statics: BoxStatics, enclosure: BoxEnclosure, wrenches: Interval, tensions: np.ndarray, rates: np.ndarray,
             errors: BuildErrors | None = None) -> tuple[Interval, Interval]:
    """The tensions t0 + D (p - c) (+ E delta with ``errors``) over each box (and the errors'
    tolerances), (N, K, m), and the enclosure of their residual r = A t - w there, (N, K, k)
    (:func:`residual_enclosure`, :func:`errors_residual`)."""
    moved = Interval.point(tensions)
    for axis in range(3):
        moved = moved + Interval.point(rates[..., axis]) * enclosure.step[:, None, None, axis]
    if errors is None:
        return moved, residual_enclosure(enclosure, wrenches, tensions, rates)
    reach = _upper_row_sums(up(np.abs(errors.rates) * errors.tolerances))  # sum_j |E_j| tolerance_j, (N, K, m)
    moved = moved + Interval(-reach, reach)
    still = Interval(tensions, tensions) + Interval(-reach, reach)  # t at the centre point over the tolerances
    return moved, residual_enclosure(errors.nominal, wrenches, tensions, rates) + errors_residual(
        statics, enclosure, errors, moved, still, rates)


def errors_residual(statics: BoxStatics, enclosure: BoxEnclosure, errors: BuildErrors, tensions: Interval,
                    still: Interval, rates: np.ndarray) -> Interval:
    """(N, K, k) an enclosure of r(p, delta) - r(p, 0) over each box and every error within the
    tolerances, by the mean-value theorem in delta: sum_j g_j(p, xi) delta_j, g_j = dr/ddelta_j
    enclosed twice by :func:`error_gradients`, the two enclosures intersected."""
    total = None
    for tolerance, ranged, centred in error_gradients(statics, enclosure, errors, tensions, still, rates):
        term = ranged.intersect(centred) * Interval(np.array(-tolerance), np.array(tolerance))
        total = term if total is None else total + term
    return total


def error_gradients(statics: BoxStatics, enclosure: BoxEnclosure, errors: BuildErrors, tensions: Interval,
                    still: Interval, rates: np.ndarray):
    """For each parameter j of the build errors, its tolerance and two enclosures (N, K, k) of
    g_j = dr/ddelta_j = (dA/ddelta_j) t + A E_j over each box and every error within the
    tolerances (zero at the centre but for E's rounding), one parameter at a time (a generator:
    the memory of one): ``enclosure`` over the box and the tolerances, ``tensions`` (N, K, m) t over
    both and ``still`` t at the centre point c over the tolerances (:func:`followed`). Its range over
    the box and the tolerances (of first order in the box's width), and its centred form
    g_j(c, Delta) + sum_l (dg_j/dp_l)(B, Delta) (p_l - c_l), dg_j/dp_l = (d2A/ddelta_j dp_l) t
    + (dA/ddelta_j) D_l + (dA/dp_l) E_j (``rates`` D (N, K, m, 3)), whose second part is of second
    order in the box and the tolerances together; d2A/ddelta_j dp_l is :func:`error_slopes` of
    the curvature d2A/dp_a dp_l and of du/dp_l (the moves and arms do not depend on p)."""
    slopes_u = _unit_slopes(enclosure.unit, enclosure.lengths)  # du/dp_l over the box and the tolerances
    pair = {(a, b): k for k, (a, b) in enumerate(PAIRS)}
    curvatures = [stack([enclosure.curvature[:, pair[min(a, l), max(a, l)]] for a in range(3)], axis=1) for l in range(3)]
    centre, moves, arms = errors.centre, errors.moves, errors.arms
    touched = ((moves.lo != 0) | (moves.hi != 0) | (arms.lo != 0) | (arms.hi != 0)).any(axis=-1)  # (P, m)
    for parameter, tolerance in enumerate(errors.tolerances):
        # an anchor's or attachment's coordinate moves one cable: dA/ddelta_j is that column alone
        cables = np.flatnonzero(touched[parameter])
        cables = cables if 0 < len(cables) < touched.shape[1] else slice(None)
        slope = error_slopes(statics, enclosure.slopes, enclosure.unit, moves, arms, parameter, cables)  # (N, k, c)
        rate = errors.rates[..., parameter]
        moved = tensions[..., cables]
        ranged = _tension_wrench(enclosure.structure, rate) + _times(slope, moved)
        centred = _tension_wrench(centre.structure, rate) + _times(
            error_slopes(statics, centre.slopes, centre.unit, moves, arms, parameter, cables), still[..., cables])
        for axis in range(3):
            mixed = error_slopes(statics, curvatures[axis], slopes_u[axis], moves, arms, parameter, cables)
            term = (_times(mixed, moved) + _tension_wrench(slope, rates[..., cables, axis])
                    + _tension_wrench(enclosure.slopes[:, axis], rate))
            centred = centred + term * enclosure.step[:, None, None, axis]
        yield tolerance, ranged, centred


def _times(structure: Interval, tensions: Interval) -> Interval:
    """An interval A (N, k, m) times interval tensions (N, K, m): (N, K, k)."""
    total = None
    for cable in range(structure.shape[-1]):
        term = structure[:, None, :, cable] * tensions[..., cable:cable + 1]
        total = term if total is None else total + term
    return total


def _perron(size: np.ndarray, rounds: int = 12) -> np.ndarray:
    """(N, k) positive weights v near the Perron vector of each non-negative |M| (N, k, k), by
    power iteration from ones: the weighted norm in which |M| contracts best (any positive v is
    sound: the contraction is then computed, with upward rounding, in that norm)."""
    weights = np.ones(size.shape[:2])
    for _ in range(rounds):
        weights = np.einsum("nij,nj->ni", size, weights) + 1e-3 * weights.max(axis=1, keepdims=True)
        weights /= weights.max(axis=1, keepdims=True)
    return weights


def _tension_wrench(structure: Interval, tensions: np.ndarray) -> Interval:
    """A(B) t0 per wrench: (N, k, m) times (N, K, m) -> (N, K, k)."""
    total = None
    for i in range(structure.shape[-1]):
        term = structure[:, None, :, i] * Interval.point(tensions[:, :, None, i])
        total = term if total is None else total + term
    return total


def outside(statics: BoxStatics, enclosure: BoxEnclosure, wrenches: Interval, separators: np.ndarray) -> np.ndarray:
    """(N,) whether every pose of each box is proven infeasible: a cable longer than ``l_max``
    over the whole box, or a required wrench k whose ``separators`` y (N, K, k) separate every
    wrench of its enclosure ``wrenches`` (N, K, k) from the cable wrenches at every A in the
    enclosure (Farkas), a_i = y.A_i bounded as below."""
    too_long = (enclosure.lengths.lo > statics.l_max).any(axis=1)
    lower, upper = statics.lower, statics.upper
    a = enclosure.times(separators, _separated)  # y.A_i over the box, (N, K, m)
    rising, falling = a.lo > 0, a.hi < 0
    blocked = (np.isinf(upper) & ~falling).any(axis=-1)  # an unrated cable that may pull along y: no bound
    # max(a t_min, a t_max) = a t_min + (t_max - t_min) max(a, 0), and on [a_lo, a_hi] the convex
    # (t_max - t_min) max(a, 0) lies under the line c a + nu through its values at both ends (the
    # secant; c = t_max - t_min where a > 0 throughout, 0 where a < 0): the sum over the cables is
    # then y.A(p) t_min + y.A(p) c + sum nu, linear in A, and its enclosure keeps the cancellations
    finite_upper = np.where(np.isinf(upper), lower, upper)
    spare = Interval.point(finite_upper) - lower  # t_max - t_min, (m,)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(rising, 1.0, np.where(falling, 0.0, a.hi / (a.hi - a.lo)))
    slope = share * (finite_upper - lower)  # c, any doubles: nu makes the line a bound
    ends = [Interval.point(np.maximum(end, 0.0)) * spare - Interval.point(slope) * end for end in (a.lo, a.hi)]
    offset = np.maximum(ends[0].hi, ends[1].hi)  # nu >= (t_max - t_min) max(e, 0) - c e at both ends e
    pulled = (enclosure.times((separators, np.broadcast_to(lower, slope.shape)), _pulled)
              + enclosure.times((separators, slope), _pulled) + Interval(offset, offset).sum(axis=-1))
    reach = (wrenches * Interval.point(separators)).sum(axis=-1).lo  # lower bound of y.w
    separated = ~blocked & (down(reach - pulled.hi) > 0)
    return too_long | (enclosure.regular & separated.any(axis=1))


def _separated(structure: Interval, separators: np.ndarray) -> Interval:
    """y.A_i: (N, k, m) with (N, K, k) -> (N, K, m)."""
    total = None
    for row in range(structure.shape[1]):
        term = structure[:, None, row, :] * Interval.point(separators[:, :, row:row + 1])
        total = term if total is None else total + term
    return total


def _pulled(structure: Interval, given: tuple[np.ndarray, np.ndarray]) -> Interval:
    """y.(A T): (N, k, m) with y (N, K, k) and T (N, K, m) -> (N, K)."""
    separators, limit = given
    return (_tension_wrench(structure, limit) * Interval.point(separators)).sum(axis=-1)


# The floats a certificate tries, chosen for the whole box to first order (any doubles are sound:
# the interval tests above check them). Each is a small LP per box and wrench, solved by HiGHS as
# one block-diagonal LP per ``LP_BLOCKS`` of them, passed to HiGHS directly (through scipy's
# ``linprog`` the wrapper's own work cost half as much again as the solve, and HiGHS's time grows
# faster than linearly with the blocks: 16 at once cost a third of 256 through ``linprog``,
# benchmarks/LOG.md).

LP_BLOCKS = 16


def robust_separators(structure: np.ndarray, slopes: np.ndarray, half: np.ndarray, wrenches: np.ndarray,
                      lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, K, k) a y per box and wrench (``wrenches`` (N, K, k)), and (N, K) its first-order separation over the box: the
    largest y.w - sum_i max(b_i t_min_i, b_i t_max_i) with b_i = y.A_i(c) + sum_l h_l |y.G_il|,
    what a_i = y.A_i(p) may reach in the box, over |y|_inf <= 1. The LP, per box and wrench:

        max y.w - sum_i [t_min_i (y.A_i + sum_l h_l Z_il) + (t_max_i - t_min_i) S_i]
        subject to  |y.G_il| <= Z_il,  y.A_i + sum_l h_l Z_il <= S_i,  S_i >= 0,  -1 <= y <= 1

    (an unrated cable, t_max = inf, must keep b_i <= 0: S_i = 0). A positive separation is what
    the interval test (:func:`outside`) then proves, up to second order."""
    n, k, m = structure.shape
    count = wrenches.shape[1]
    width = k + m + 3 * m  # y, S, Z (m x 3, cable-major)
    blocks = n * count
    a = np.swapaxes(np.repeat(structure, count, axis=0), 1, 2)  # (B, m, k): rows y.A_i
    g = np.repeat(slopes, count, axis=0)  # (B, 3, k, m)
    h = np.repeat(half, count, axis=0)
    rated = np.isfinite(upper)
    spare = np.where(rated, upper - lower, 0.0)
    cost = np.zeros((blocks, width))
    w = wrenches.reshape(n * count, k)
    cost[:, :k] = -w + np.einsum("bmk,m->bk", a, lower)
    cost[:, k:k + m] = spare
    for axis in range(3):
        cost[:, k + m + axis::3] = lower * h[:, axis:axis + 1]
    reach = np.zeros((blocks, m, width))  # y.A_i + sum_l h_l Z_il - S_i <= 0
    reach[:, :, :k] = a
    reach[:, np.arange(m), k + np.arange(m)] = -1.0
    for axis in range(3):
        reach[:, np.arange(m), k + m + 3 * np.arange(m) + axis] = h[:, axis:axis + 1]
    spread = np.zeros((blocks, 6 * m, width))  # +-y.G_il - Z_il <= 0
    for sign, offset in ((1.0, 0), (-1.0, 3 * m)):
        for axis in range(3):
            rows = offset + 3 * np.arange(m) + axis
            spread[:, rows, :k] = sign * np.swapaxes(g[:, axis], 1, 2)
            spread[:, rows, k + m + 3 * np.arange(m) + axis] = -1.0
    a_ub = np.concatenate([reach, spread], axis=1)
    b_ub = np.zeros((blocks, 7 * m))
    bounds = np.tile(np.array([[-1.0, 1.0]] * k + [[0.0, np.inf]] * m + [[0.0, np.inf]] * (3 * m)), (blocks, 1, 1))
    bounds[:, k:k + m][:, ~rated] = (0.0, 0.0)
    x, ok = _block_lps(cost, a_ub, b_ub, bounds)
    value = np.where(ok, -np.einsum("bj,bj->b", cost, x), -np.inf)
    return x[:, :k].reshape(n, count, k), value.reshape(n, count)


def _block_lps(cost, a_ub, b_ub, bounds) -> tuple[np.ndarray, np.ndarray]:
    """Solve B small LPs (min cost.x, A_ub x <= b_ub, bounds; dense per-block arrays) as
    block-diagonal LPs of ``LP_BLOCKS``; (B, width) solutions and (B,) which solved (a batch HiGHS
    does not solve is halved until its blocks solve alone or fail alone)."""
    blocks, width = cost.shape
    x, ok = np.zeros((blocks, width)), np.zeros(blocks, dtype=bool)
    pending = [np.arange(start, min(start + LP_BLOCKS, blocks)) for start in range(0, blocks, LP_BLOCKS)]
    while pending:
        rows = pending.pop()
        solved = _solve_blocks(cost[rows], a_ub[rows], b_ub[rows], bounds[rows])
        if solved is not None:
            x[rows], ok[rows] = solved, True
        elif len(rows) > 1:
            pending += [rows[:len(rows) // 2], rows[len(rows) // 2:]]
    return x, ok


def _solve_blocks(cost, a_ub, b_ub, bounds) -> np.ndarray | None:
    """One block-diagonal LP of the blocks (B, r, width) through this thread's HiGHS: (B, width)
    its solution, or None if HiGHS does not find one."""
    import highspy

    blocks, rows, width = a_ub.shape
    infinity = highspy.kHighsInf
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = blocks * width, blocks * rows
    lp.col_cost_ = cost.ravel()
    lp.col_lower_ = np.where(np.isfinite(bounds[..., 0]), bounds[..., 0], -infinity).ravel()
    lp.col_upper_ = np.where(np.isfinite(bounds[..., 1]), bounds[..., 1], infinity).ravel()
    lp.row_lower_ = np.full(blocks * rows, -infinity)
    lp.row_upper_ = b_ub.ravel()
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_ = block_columns(a_ub)
    found = solved(lp)
    return None if found is None else found.reshape(blocks, width)

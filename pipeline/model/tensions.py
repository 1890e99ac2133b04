"""Cables that can only pull: the ``feasible`` tension model, shared by every robot (issue 8).

Per pose p and required wrench w (one of K), the cable forces x (m,) must satisfy the
equilibrium ``S_p x = w`` and one interval per cable and criterion. x and S are what the
robot's model multiplies: shaft torques M with S = J^T for CPR-8 (eq. 20, M_i = R_i t_i),
tensions s with S = A for the IRPM (eqs. 7-10). A criterion is a :class:`Family` of intervals
``lower <= x_i <= upper`` with a margin unit ``scale``: its margin is the capacity margin

    max_x  s   subject to   S x = w,   lower + s scale <= x <= upper - s scale,   s <= 1,

the largest uniform shrink of its intervals that still admits a valid x. Families are nested in
the order given (slack, then the tension rating, torque, voltage): each one's LP keeps the
earlier families' intervals, relaxed by their own margin where that is negative. So a pose is
feasible at w (every margin >= 0) exactly when one x satisfies all intervals at once, and the
margin of a later criterion is the best it can do while the earlier ones do their best. A
pose's margin of a criterion is the least over its K required wrenches (each wrench nested on
its own): what the criterion reads.

Exactness: for a fixed pose the set of wrenches w admitting a valid x is convex (the image of a
polytope under a linear map), so checking the vertices of a convex required-wrench set (the
acceleration box of eqs. 27-29 through the load mass) decides the whole set.

Cost: where S has full column rank (square IRPM, rank 6 = m) x is unique, x = S^+ w, and the
margins are closed forms (this is the paper's own criterion). Otherwise the margins come from
hyperplane shifting (``pipeline.model.capacity``), exact and batched over poses, and the LPs are
the reference and the fallback: for poses whose structure matrix is poorly conditioned (gram
ratio of S in its range below ``HSM_MIN_GRAM``), for robots with more candidate normals than
``capacity.MAX_NORMALS``, for a search that did not settle, and whenever the cable forces
themselves are wanted (``distribution``: per-pose tensions, the straight-line simulations).
The LPs of all (pose, wrench) pairs of a chunk go into one block-diagonal LP per family, solved
by HiGHS (scipy.optimize.linprog); maximising the sum of the independent s's maximises each.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import comb

import numpy as np

from pipeline.model.capacity import MAX_NORMALS, RELAX, range_coordinates, ray_reach, shifted_margins
from pipeline.model.linalg import gram, gram_ratio

LP_BLOCKS = 256  # (pose, wrench) pairs per HiGHS call; HiGHS time grows faster than linearly
HSM_MIN_GRAM = 1e-6  # gram ratio of S (in its range) below which a pose goes to the LP


@dataclass(frozen=True)
class TensionSpec:
    """Which cable forces the criteria check. ``model``: ``"pinv"`` (minimum-norm, eq. 20 of the
    CPR-8 paper / eq. 10 of the IRPM paper, any sign) or ``"feasible"`` (pulling cables only,
    solved as above). ``t_min``: smallest cable tension (N). ``t_max``: cable rating (N), None =
    the motor's torque limit / R_i only. Both a float or one value per cable (m,).
    ``residual_rtol``: a wrench is unreachable when |S S^+ w - w| > residual_rtol |w|
    (``feasible``); ``pinv_residual`` the same share for the minimum-norm forces (``pinv``:
    CPR-WWA's (J^T)^+ F, which on the paper's CPR-8 misses up to 1.4 % of F); ``residual_limit``
    is the one of the model. ``distribution``: which tensions the ``feasible`` model writes (``output.cables``):
    ``min_norm``, the least 2-norm within the limits (:func:`min_norm_distribution`, as CASPR
    and WireX give them), or ``lp``, the vertex its LPs end on. ``bounded``: the keys of the
    criteria with keys of their own that bound the forces (``criteria.<name>``, by name): the
    ``feasible`` model nests their intervals too."""

    model: str = "pinv"
    t_min: float | np.ndarray = 0.0
    t_max: float | np.ndarray | None = None
    residual_rtol: float = 1e-6
    distribution: str = "lp"
    pinv_residual: float = 0.05
    bounded: dict = field(default_factory=dict)

    @property
    def residual_limit(self) -> float:
        """The share of a required wrench the model's forces may miss (``unreachable``)."""
        return self.pinv_residual if self.model == "pinv" else self.residual_rtol


@dataclass(frozen=True)
class Family:
    """One criterion's intervals on x, each array broadcastable to (n, K, m); +-inf: no side."""

    name: str
    lower: np.ndarray
    upper: np.ndarray
    scale: np.ndarray

    def __post_init__(self):
        """+inf below or -inf above would read as no side at all (the LP rows keep finite sides
        only): a criterion whose bound overflows must say so, not pass every pose."""
        if np.any(np.asarray(self.lower) == np.inf) or np.any(np.asarray(self.upper) == -np.inf):
            raise ValueError(f"criterion {self.name}: a tension bound of +inf below or -inf above")

    def at(self, poses: np.ndarray, n: int) -> Family:
        """This family at ``poses`` of the n: arrays with a pose axis are indexed, others kept."""
        def pick(values):
            values = np.asarray(values, dtype=float)
            return values[poses] if values.ndim == 3 and values.shape[0] == n else values

        return Family(self.name, pick(self.lower), pick(self.upper), pick(self.scale))


def feasible_tensions(
    structure: np.ndarray, pinv: np.ndarray, rank: np.ndarray, wrenches: np.ndarray,
    families: list[Family], distribution: bool = False,
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray | None, np.ndarray]:
    """The nested capacity margins (n,) of ``families``, each the least over the K required
    wrenches; (n,) the worst relative residual |S S^+ w - w| / |w| over them
    (:func:`reachability`); with ``distribution`` the chosen x (n, K, m),
    else None; and (n,) which poses the LPs solved. ``wrenches`` (K, r) or (n, K, r)."""
    residual, projected = reachability(structure, pinv, wrenches)
    margins, chosen, by_lp = capacity_margins(structure, pinv, rank, projected, families, distribution)
    return margins, residual.max(axis=1), chosen, by_lp


def reachability(structure: np.ndarray, pinv: np.ndarray, wrenches: np.ndarray):
    """Relative residual (n, K) of the least-squares equilibrium S x = w and the wrenches
    projected onto the range of S (n, K, r). ``pinv`` (n, m, r) = S^+, ``wrenches`` (K, r) or
    (n, K, r)."""
    w = np.broadcast_to(wrenches, (structure.shape[0], *np.shape(wrenches)[-2:]))
    projected = w @ np.swapaxes(structure @ pinv, 1, 2)  # S S^+ w: matmul, not a 3-operand einsum
    size = np.linalg.norm(w, axis=2)
    residual = np.linalg.norm(projected - w, axis=2) / np.where(size > 0, size, 1.0)
    return residual, projected


def capacity_margins(
    structure: np.ndarray, pinv: np.ndarray, rank: np.ndarray, wrenches: np.ndarray,
    families: list[Family], distribution: bool = False,
) -> tuple[dict[str, np.ndarray], np.ndarray | None, np.ndarray]:
    """Nested capacity margins (n,) per family, each the least over the K wrenches; with
    ``distribution`` the chosen x (n, K, m), the solution of the last family's LP, else None;
    and (n,) the poses solved by LP. ``wrenches`` (n, K, r) must lie in the range of S (see
    :func:`reachability`); ``pinv`` and ``rank`` (n,) are S^+ and the rank of S."""
    n, _, m = structure.shape
    k = wrenches.shape[1]
    margins = {f.name: np.empty(n) for f in families}
    chosen = np.empty((n, k, m)) if distribution else None
    unique = rank == m
    if unique.any():  # x = S^+ w is the only candidate: the margins are closed forms
        x = np.einsum("nmr,nkr->nkm", pinv[unique], wrenches[unique])
        if distribution:
            chosen[unique] = x
        for f in families:
            lower, upper, scale = (a[unique] for a in _broadcast(f, (n, k, m))[1:])
            room = np.minimum(x - lower, upper - x) / scale
            margins[f.name][unique] = np.minimum(room.min(axis=(1, 2)), 1.0)
    by_lp, shifted = ~unique, np.zeros(n, dtype=bool)
    if not distribution:
        for q in np.unique(rank[by_lp]):
            if q == 0 or 2 * comb(m, int(q) - 1) > MAX_NORMALS:  # q = 0: no wrench at all, the LPs say
                continue
            poses = np.flatnonzero(by_lp & (rank == q))
            structure_q, wrenches_q = range_coordinates(structure[poses], wrenches[poses], int(q))
            found, unsettled = shifted_margins(structure_q, wrenches_q,
                                               [f.at(poses, n) for f in families])
            for name, value in found.items():
                margins[name][poses] = value
            shifted[poses[~unsettled]] = True
            conditioned = gram_ratio(gram(structure_q)) >= HSM_MIN_GRAM
            by_lp[poses[~unsettled & conditioned]] = False
    full = [_broadcast(f, (n, k, m)) for f in families]
    rest = np.flatnonzero(by_lp)
    by_lp[:] = False  # set again for the poses the LPs solve
    step = max(1, LP_BLOCKS // k)
    for start in range(0, len(rest), step):
        for poses, found, x in _solved(structure, wrenches, full, rest[start:start + step], shifted):
            if distribution:
                chosen[poses] = x
            for name, value in found.items():
                margins[name][poses] = value.min(axis=1)
            by_lp[poses] = True
    return margins, chosen, by_lp


def _solved(structure, wrenches, full, poses, shifted):
    """The nested LPs of ``poses`` as (poses, margins, x) parts: all at once, else one pose at a
    time when HiGHS declares the joint LP infeasible. A pose whose own LP still fails keeps
    its hyperplane-shifting margins when it has them (counted as not solved by LP, ``shifted``);
    otherwise the failure is raised."""
    try:
        found, x = _nested_lps(structure[poses], wrenches[poses],
                               [(f[0], *(a[poses] for a in f[1:])) for f in full])
        return [(poses, found, x)]
    except RuntimeError:
        if len(poses) == 1:
            if shifted[poses[0]]:
                return []
            raise
    return [part for pose in poses for part in _solved(structure, wrenches, full, [pose], shifted)]


def _broadcast(family: Family, shape) -> tuple:
    return (family.name, *(np.broadcast_to(np.asarray(a, dtype=float), shape)
                           for a in (family.lower, family.upper, family.scale)))


def _nested_lps(structure, wrenches, families) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The families' LPs in order, each one block-diagonal LP over all (pose, wrench) pairs."""
    from scipy.optimize import linprog

    n, r, m = structure.shape
    k = wrenches.shape[1]
    blocks, width = n * k, m + 1  # variables per block: x (scaled by ``unit``) and s
    unit = float(np.median(families[0][3]))
    equality = block_matrix(np.repeat(structure, k, axis=0) * unit, width)
    b_eq = wrenches.reshape(blocks * r)
    lower, upper = np.full((blocks, m), -np.inf), np.full((blocks, m), np.inf)
    margins, x = {}, None
    for name, f_lower, f_upper, f_scale in families:
        f_lower, f_upper, f_scale = (a.reshape(blocks, m) / unit for a in (f_lower, f_upper, f_scale))
        a_ub, b_ub = _shrink_rows(f_lower, f_upper, f_scale, width)
        bounds = np.empty((blocks, width, 2))
        bounds[:, :m, 0], bounds[:, :m, 1] = lower, upper
        bounds[:, m] = (-np.inf, 1.0)
        cost = np.zeros(blocks * width)
        cost[m::width] = -1.0
        # HiGHS's presolve has declared feasible LPs infeasible, and its simplex has ended in an
        # unknown status (numerical difficulties) on well-posed ones that its interior point solves
        # (a path's drive families, tests/test_path_drive.py): each is tried in turn
        for method, options in (("highs", {}), ("highs", {"presolve": False}), ("highs-ipm", {})):
            result = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=equality, b_eq=b_eq,
                             bounds=bounds.reshape(-1, 2), method=method, options=options)
            if result.status == 0:
                break
        if result.status != 0:
            raise RuntimeError(f"tension LP for {name!r} failed: {result.message}")
        solution = result.x.reshape(blocks, width)
        s = solution[:, m]
        margins[name] = s.reshape(n, k)
        x = solution[:, :m] * unit
        relax = (np.minimum(s, 0.0)[:, None] - RELAX) * f_scale
        # the next LP keeps these bounds, widened to hold this LP's own x: feasible by
        # construction, where HiGHS's tolerance could otherwise make it declare it infeasible
        lower = np.minimum(np.maximum(lower, f_lower + relax), solution[:, :m])  # -inf stays
        upper = np.maximum(np.minimum(upper, f_upper - relax), solution[:, :m])
    return margins, x.reshape(n, k, m)


def block_matrix(blocks: np.ndarray, width: int):
    """Block-diagonal (B r, B width) sparse matrix with blocks (B, r, m) in the first m columns."""
    import scipy.sparse as sparse

    count, r, m = blocks.shape
    rows = np.arange(count * r).reshape(count, r, 1).repeat(m, axis=2)
    cols = (np.arange(count)[:, None, None] * width + np.arange(m)[None, None, :]).repeat(r, axis=1)
    return sparse.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())),
                             shape=(count * r, count * width))


def _shrink_rows(lower, upper, scale, width):
    """Rows ``x_i + c_i s <= upper_i`` and ``-x_i + c_i s <= -lower_i`` for the finite sides."""
    import scipy.sparse as sparse

    m = lower.shape[1]
    rows, cols, values, rhs = [], [], [], []
    start = 0
    for sign, bound in ((1.0, upper), (-1.0, lower)):
        block, cable = np.nonzero(np.isfinite(bound))
        index = start + np.arange(len(block))
        rows += [index, index]
        cols += [block * width + cable, block * width + m]
        values += [np.full(len(block), sign), scale[block, cable]]
        rhs.append(sign * bound[block, cable])
        start += len(block)
    matrix = sparse.csr_matrix(
        (np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
        shape=(start, lower.shape[0] * width),
    )
    return matrix, np.concatenate(rhs)


MAX_PAYLOAD_KG = 1e8  # a payload the LPs reach is "unlimited" (inf): the cables never carry it


def payload_ranges(structure: np.ndarray, wrench: np.ndarray, per_kg: np.ndarray, t_min, t_max) -> np.ndarray:
    """(n, 2) the least and the largest mu >= 0 (kg) with S t = w + mu d for some t in [t_min,
    t_max]: the payloads of ``analysis=payload`` each pose holds (``S`` (n, r, m), ``w`` and
    ``d`` (r,) or each pose's own (n, r): the platform's load wrench and that of 1 kg of
    payload). The weight is linear in the mass and the tensions' box convex, so the payloads
    held form one interval: a pose whose cables need more weight than the platform's to reach
    t_min holds only from some mu > 0 on. The largest is inf where no tension bound is met below
    MAX_PAYLOAD_KG (the rows that carry the weight are not the cables': a table); both NaN
    where no payload is held. Three block-diagonal LPs per group of poses: the least violation
    of the equality over mu >= 0 (every block feasible), then, for the poses held exactly, the
    largest and the least mu; a group HiGHS cannot solve whole is solved pose by pose."""
    n = structure.shape[0]
    out = np.full((n, 2), np.nan)
    upper = np.inf if t_max is None else t_max
    unit = float(np.max(upper)) if np.isfinite(upper).all() else max(1.0, float(np.abs(wrench).max()))
    wrench, per_kg = (np.broadcast_to(a, (n, structure.shape[1])) for a in (wrench, per_kg))
    for start in range(0, n, LP_BLOCKS):
        group = slice(start, min(n, start + LP_BLOCKS))
        out[group] = _payload_group(structure[group], wrench[group], per_kg[group], t_min, upper, unit)
    return out


def _payload_group(structure, wrench, per_kg, t_min, t_max, unit) -> np.ndarray:
    from scipy.optimize import linprog

    count, r, m = structure.shape
    bounds_t = np.column_stack([np.broadcast_to(t_min, (m,)), np.broadcast_to(t_max, (m,))]) / unit
    size = 1.0 + np.abs(wrench).max(axis=1)  # (count,): each pose's own wrench
    # phase 1: the least |S t - mu d - w| over t in its bounds and mu >= 0
    width = m + 1 + 2 * r
    blocks = np.concatenate([structure * unit, -per_kg[:, :, None],
                             np.broadcast_to(np.eye(r), (count, r, r)), np.broadcast_to(-np.eye(r), (count, r, r))],
                            axis=2)
    bounds = np.empty((count, width, 2))
    bounds[:, :m], bounds[:, m] = bounds_t, (0.0, MAX_PAYLOAD_KG)
    bounds[:, m + 1:] = (0.0, np.inf)
    cost = np.zeros((count, width))
    cost[:, m + 1:] = 1.0
    first = linprog(cost.ravel(), A_eq=block_matrix(blocks, width), b_eq=wrench.ravel(),
                    bounds=bounds.reshape(-1, 2), method="highs")
    if first.status != 0:
        raise RuntimeError(f"payload LP (least violation) failed: {first.message}")
    held = first.x.reshape(count, width)[:, m + 1:].sum(axis=1) <= 1e-9 * size
    out = np.full((count, 2), np.nan)
    poses = np.flatnonzero(held)
    if len(poses):
        for column, sense in ((1, -1.0), (0, 1.0)):  # the largest, then the least
            out[poses, column] = _extreme_mu(structure[poses], wrench[poses], per_kg[poses], bounds_t, unit, sense)
    out = np.maximum(out, 0.0)  # keeps NaN
    out[out >= MAX_PAYLOAD_KG * (1 - 1e-12)] = np.inf
    out[out[:, 0] > out[:, 1] * (1 + 1e-12) + 1e-9] = np.nan  # HiGHS disagreeing with itself: none held
    return out


def _extreme_mu(structure, wrench, per_kg, bounds_t, unit, sense: float) -> np.ndarray:
    """max mu (``sense`` -1) or min mu (+1) with S t - mu d = w, t in bounds, mu >= 0, for poses
    that hold some mu; the block LP first, pose by pose if HiGHS's tolerance makes it declare
    the whole infeasible."""
    from scipy.optimize import linprog

    count, r, m = structure.shape
    width = m + 1
    blocks = np.concatenate([structure * unit, -per_kg[:, :, None]], axis=2)
    bounds = np.empty((count, width, 2))
    bounds[:, :m], bounds[:, m] = bounds_t, (0.0, MAX_PAYLOAD_KG)
    cost = np.zeros((count, width))
    cost[:, m] = sense
    done = linprog(cost.ravel(), A_eq=block_matrix(blocks, width), b_eq=wrench.ravel(),
                   bounds=bounds.reshape(-1, 2), method="highs")
    if done.status == 0:
        return done.x.reshape(count, width)[:, m]
    found = np.full(count, np.nan)
    for pose in range(count):
        single = linprog(cost[pose], A_eq=blocks[pose], b_eq=wrench[pose], bounds=bounds[pose], method="highs")
        if single.status == 0:
            found[pose] = single.x[m]
    return found


def wrench_reach(structure: np.ndarray, pinv: np.ndarray, rank: np.ndarray, wrench: np.ndarray, t_min,
                 t_max) -> np.ndarray:
    """(n, 2, r) the largest mu >= 0 with S t = w + mu e_j ([:, 0, j]) and S t = w - mu e_j
    ([:, 1, j]), t in [t_min, t_max], for each row j of ``structure`` (n, r, m); ``pinv`` and
    ``rank`` its S^+ and rank (n,), ``wrench`` (r,) or (n, r). Exact: where t is unique (rank
    m) in closed form (:func:`ray_interval`); else from hyperplane shifting's inequalities
    (``capacity.ray_reach``, in the range of S: a direction with a part outside it has mu = 0),
    or, for a poorly conditioned S or too many normals, the payload's LPs with e_j in place of a
    kilogram's weight (:func:`payload_ranges`). NaN where w is not held, inf where no limit binds."""
    n, r, m = structure.shape
    lower = np.broadcast_to(np.asarray(t_min, dtype=float), (m,))
    upper = np.broadcast_to(np.asarray(np.inf if t_max is None else t_max, dtype=float), (m,))
    w = np.broadcast_to(wrench, (n, r))
    size = np.abs(w).max(axis=1) + np.abs(structure).max(axis=(1, 2)) * np.where(
        np.isfinite(upper), np.abs(upper), np.abs(lower)).max()
    tolerance = 1e-9 * size  # how far outside an inequality w may stand and count as held (round-off)
    out = np.full((n, 2, r), np.nan)
    unique = np.flatnonzero(rank == m)
    if len(unique):
        x = np.einsum("nmr,nr->nm", pinv[unique], w[unique])
        held = ((x >= lower - tolerance[unique, None]) & (x <= upper + tolerance[unique, None])).all(axis=1)
        for j in range(r):
            for side, sign in ((0, 1.0), (1, -1.0)):
                largest = ray_interval(x, sign * pinv[unique][:, :, j], lower, upper)[1]
                out[unique, side, j] = np.where(held, np.maximum(largest, 0.0), np.nan)
    by_lp = np.zeros(n, dtype=bool)
    for q in np.unique(rank[rank != m]):
        poses = np.flatnonzero(rank == q)
        if q == 0 or 2 * comb(m, int(q) - 1) > MAX_NORMALS:
            by_lp[poses] = True
            continue
        basis = (np.broadcast_to(np.eye(r), (len(poses), r, r)) if q == r
                 else np.linalg.svd(structure[poses], full_matrices=False)[0][:, :, :q])  # (n_q, r, q)
        inside = np.swapaxes(basis, 1, 2) @ structure[poses]
        coords = np.einsum("nr,nrq->nq", w[poses], basis)
        outside = np.linalg.norm(w[poses] - np.einsum("nrq,nq->nr", basis, coords), axis=1) > tolerance[poses]
        conditioned = gram_ratio(gram(inside)) >= HSM_MIN_GRAM
        by_lp[poses[~conditioned]] = True
        chosen = np.flatnonzero(conditioned)
        found = ray_reach(inside[chosen], coords[chosen], basis[chosen], lower, upper, tolerance[poses[chosen]])
        apart = (1.0 - (basis[chosen] ** 2).sum(axis=2)) > 1e-9  # (n_c, r): e_j leaves the range of S
        found = np.where(apart[:, None, :] & ~np.isnan(found), 0.0, found)
        found[outside[chosen]] = np.nan
        out[poses[chosen]] = found
    if by_lp.any():
        for j in range(r):
            for side, sign in ((0, 1.0), (1, -1.0)):
                direction = np.zeros(r)
                direction[j] = sign
                ranges = payload_ranges(structure[by_lp], w[by_lp], direction, t_min, t_max)
                out[by_lp, side, j] = np.where(ranges[:, 0] <= 1e-9, ranges[:, 1], np.nan)  # w itself held
    return out


def ray_interval(tensions: np.ndarray, rate: np.ndarray, lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """(least, largest) (n,) of the mu >= 0 with lower <= t + mu rate <= upper for every cable
    (the tensions of a wrench along a ray, when they are unique or minimum-norm): each cable
    bounds mu from below at one limit and from above at the other, by the sign of its rate; a
    cable with rate 0 allows every mu or none. Empty where least > largest."""
    with np.errstate(divide="ignore", invalid="ignore"):
        to_lower, to_upper = (lower - tensions) / rate, (upper - tensions) / rate
        still = np.where((tensions >= lower) & (tensions <= upper), np.inf, -np.inf)  # rate 0
        lows = np.where(rate > 0, to_lower, np.where(rate < 0, to_upper, -still))
        highs = np.where(rate > 0, to_upper, np.where(rate < 0, to_lower, still))
    return np.maximum(lows.max(axis=1), 0.0), highs.min(axis=1)

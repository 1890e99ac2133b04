"""Certified workspaces (issue 57): interval enclosures with outward rounding, boxes proven inside
or outside, and branch and prune.

Oracles: exact rational arithmetic (fractions) and mpmath at 50 digits for the enclosures (a
computation without outward rounding fails them); the project's exact per-pose test
(``evaluate_chunk``, itself checked against LPs elsewhere) at random poses of every certified box,
on five robots (spatial, tilted with an off-centre payload and a length limit, a set of
orientations, a planar body with a wrench set, a planar point and a point in space); the volume
of a fine grid inside the certified bracket."""

import itertools
import math
from dataclasses import replace
from fractions import Fraction
from types import SimpleNamespace

import mpmath
import numpy as np
import pandas as pd
import pytest
from scipy.optimize import linprog

from conftest import CROSSED_ROBOT, SPREAD_ANCHORS, command, eq9_rotation
from pipeline.app.problem import build
from pipeline.model import certificates
from pipeline.model.certificates import INSIDE, OUTSIDE, UNDECIDED
from pipeline.model.geometry import rotation_matrix
from pipeline.model.intervals import Interval, rotation_enclosure
from pipeline.model.path import StraightMotion
from pipeline.workspace import paving
from pipeline.workspace.paving import Paving
from pipeline.workspace.criteria import REGISTRY
from pipeline.workspace.feasibility import null_space_verdicts
from pipeline.workspace.kernel import evaluate_chunk
from pipeline.workspace.tolerances import culprits, errors as tolerances_errors

IPANEMA = ["robot=points", f"robot.anchors={SPREAD_ANCHORS}",
           "robot.attachments=[[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0],"
           "[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0]]",
           "robot.search.lo=[-2,-1.5,0]", "robot.search.hi=[2,1.5,2]", "tension.t_min=1", "tension.t_max=10"]
PLANAR_BODY = ["robot=points", "robot.anchors=[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]",
               "robot.attachments=[[-0.1,0.05,0],[0.1,0.05,0],[0.1,-0.05,0],[-0.1,-0.05,0]]",
               "robot.dofs=[x,y,rz]", "robot.search.lo=[-0.9,-0.9,0]", "robot.search.hi=[0.9,0.9,0]",
               "tension.t_min=2", "tension.t_max=60", "wrench.set={min: [-5, 0, 0, 0, 0, -0.2], max: [5, 0, 0, 0, 0, 0.2]}",
               "orientation.phi=0.3"]
PLANAR_POINT = ["robot=points", "robot.anchors=[[-1,0,0],[1,0,0],[1.2,2,0],[-0.8,2,0]]",
                "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.up=[0,1,0]", "robot.dofs=[x,y]",
                "robot.search.lo=[-1,0.1,0]", "robot.search.hi=[1.2,1.9,0]", "robot.platform.mass=2",
                "tension.t_min=0", "tension.t_max=40"]
CRANE = ["robot=points", "robot.anchors=[[-1,-1,3],[1,-1,3],[1,1,3],[-1,1,3]]",
         "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.dofs=[x,y,z]",
         "robot.search.lo=[-1.5,-1.5,0]", "robot.search.hi=[1.5,1.5,2.8]", "robot.platform.mass=5",
         "tension.t_min=1", "tension.t_max=40", "wrench.fx=3"]
QUARTER = [o for o in IPANEMA if not o.startswith("robot.search")]  # IPAnema 1 in a corner of its frame
ROBOTS = {  # name -> (overrides, depth)
    "ipanema": ([*QUARTER, "robot.search.lo=[0,0,0]", "robot.search.hi=[2,1.5,2]"], 12),
    "tilted payload": ([*CROSSED_ROBOT, "tension.t_min=0", "tension.t_max=150", "load.mass=3", "load.com=[0.04,-0.03,0.02]",
                        "orientation.psi=0.1", "orientation.theta=-0.08", "orientation.phi=0.25", "robot.l_max=3.2"], 14),
    "orientation set": ([*QUARTER, "robot.search.lo=[0.2,0.1,0.8]", "robot.search.hi=[1.9,1.4,1.2]",
                         "orientation.total={bound: 0.03, n: 2}"], 9),
    "planar body": (PLANAR_BODY, 12),
    "planar point": (PLANAR_POINT, 12),
    "crane": (CRANE, 11),
}


def _problem(make_cfg, overrides, *more):
    return build(make_cfg(*overrides, "tension=feasible", "analysis=certified", *more), None)


def _min_margins(problem, positions: np.ndarray) -> np.ndarray:
    """The exact per-pose test: the least margin over the criteria (>= 0: feasible)."""
    margins = evaluate_chunk(problem, positions)
    return np.min([value for key, value in margins.items() if key.startswith("margin_")], axis=0)


# -- interval arithmetic: exact rationals and 50-digit references ---------------------------------

def _exact(values) -> list[Fraction]:
    return [Fraction(float(v)) for v in np.ravel(values)]


def test_outward_rounding_contains_the_exact_results_of_every_operation():
    rng = np.random.default_rng(0)
    a = rng.uniform(-3, 3, 2000) * 10.0 ** rng.integers(-5, 5, 2000)
    b = rng.uniform(0.1, 3, 2000) * 10.0 ** rng.integers(-5, 5, 2000)
    x, y = Interval.point(a), Interval.point(b)
    results = {"+": (x + y, lambda p, q: p + q), "-": (x - y, lambda p, q: p - q), "*": (x * y, lambda p, q: p * q),
               "/": (x / y, lambda p, q: p / q)}
    for name, (found, exact) in results.items():
        for lo, hi, p, q in zip(found.lo, found.hi, _exact(a), _exact(b)):
            assert Fraction(lo) <= exact(p, q) <= Fraction(hi), name
    roots = Interval.point(b).sqrt()
    with mpmath.workdps(50):
        for lo, hi, q in zip(roots.lo, roots.hi, b):
            exact = mpmath.sqrt(mpmath.mpf(q))
            assert mpmath.mpf(lo) <= exact <= mpmath.mpf(hi)
    # without the step outward, 0.1 + 0.2 rounds above the exact sum of the two doubles
    assert Fraction(0.1 + 0.2) > Fraction(0.1) + Fraction(0.2)
    assert Fraction((Interval.point(0.1) + 0.2).lo) < Fraction(0.1) + Fraction(0.2)


def test_the_compiled_steps_outward_are_numpys_nextafter_bit_for_bit():
    """``intervals.down`` and ``up`` (one compiled pass over the bit patterns, pipeline.model.rounding)
    against numpy's nextafter: zeros of both signs, subnormals, the largest doubles, infinities,
    NaNs and 200 000 random bit patterns; scalars stay scalars, shapes and strides are kept,
    read-only and empty arrays are taken."""
    from pipeline.model.intervals import down, up

    rng = np.random.default_rng(5)
    tiny, huge = np.nextafter(0.0, 1.0), np.finfo(float).max
    special = np.array([0.0, -0.0, tiny, -tiny, 2.2250738585072014e-308, -2.2250738585072014e-308, huge, -huge,
                        np.inf, -np.inf, np.nan, -np.nan, 1.0, -1.0, 0.1, -0.1])
    values = np.concatenate([special, rng.integers(-2**63, 2**63 - 1, 200_000, dtype=np.int64).view(np.float64)])
    with np.errstate(all="ignore"):
        for step, towards in ((down, -np.inf), (up, np.inf)):
            found, expected = step(values), np.nextafter(values, towards)
            same = (found.view(np.int64) == expected.view(np.int64)) | (np.isnan(found) & np.isnan(expected))
            assert same.all(), values[~same][:5]
            assert type(step(0.1)) is np.float64 and step(np.float64(-0.0)) == np.nextafter(-0.0, towards)
            strided = values[:1200].reshape(40, 30)[:, ::3]
            assert step(strided).shape == (40, 10)
            np.testing.assert_array_equal(step(strided), np.nextafter(strided, towards))
            frozen = values[16:100].copy()
            frozen.setflags(write=False)
            np.testing.assert_array_equal(step(frozen), np.nextafter(frozen, towards))
            assert step(np.empty((0, 3))).shape == (0, 3)


def test_interval_square_and_products_hold_every_member():
    rng = np.random.default_rng(1)
    lo = rng.uniform(-2, 2, (500, 2))
    hi = lo + rng.uniform(0, 2, (500, 2))
    x, y = Interval(lo[:, 0], hi[:, 0]), Interval(lo[:, 1], hi[:, 1])
    t = rng.uniform(0, 1, (50, 500, 2))
    px, py = lo[:, 0] + t[..., 0] * (hi[:, 0] - lo[:, 0]), lo[:, 1] + t[..., 1] * (hi[:, 1] - lo[:, 1])
    assert ((x * y).lo <= px * py).all() and (px * py <= (x * y).hi).all()
    assert (x.square().lo <= px**2).all() and (px**2 <= x.square().hi).all()
    assert (x.square().lo >= 0).all()


@pytest.mark.parametrize("angles", [(0.0, 0.0, 0.0), (0.3, -0.7, 2.1), (1e-9, 3.0, -1.2)])
def test_rotation_enclosure_contains_eq9_at_fifty_digits(angles):
    found = rotation_enclosure(*angles)
    with mpmath.workdps(50):
        a, b, c = (mpmath.mpf(v) for v in angles)
        rx = mpmath.matrix([[1, 0, 0], [0, mpmath.cos(a), -mpmath.sin(a)], [0, mpmath.sin(a), mpmath.cos(a)]])
        ry = mpmath.matrix([[mpmath.cos(b), 0, mpmath.sin(b)], [0, 1, 0], [-mpmath.sin(b), 0, mpmath.cos(b)]])
        rz = mpmath.matrix([[mpmath.cos(c), -mpmath.sin(c), 0], [mpmath.sin(c), mpmath.cos(c), 0], [0, 0, 1]])
        exact = rz * ry * rx
        for i in range(3):
            for j in range(3):
                assert mpmath.mpf(found.lo[i, j]) <= exact[i, j] <= mpmath.mpf(found.hi[i, j])
    assert np.allclose(found.lo, rotation_matrix(*angles), atol=1e-15)
    assert np.allclose(found.hi, eq9_rotation(*angles), atol=1e-15)


# -- the structure matrix's enclosure ---------------------------------------------------------

def _enclosure(problem, lo, hi):
    statics = paving.box_statics(problem, problem.orientations[0])
    return certificates.structure_enclosure(statics, lo, hi, lo + (hi - lo) / 2)


def test_structure_enclosure_holds_the_structure_matrix_at_random_points_of_its_box(make_cfg):
    problem = _problem(make_cfg, ROBOTS["tilted payload"][0])
    rng = np.random.default_rng(2)
    lo = rng.uniform([-1.4, -0.9, 0.3], [1.2, 0.7, 1.4], (100, 3))
    hi = lo + rng.uniform(0.01, 0.3, (100, 3))
    enclosure = _enclosure(problem, lo, hi)
    points = lo[:, None] + rng.uniform(0, 1, (100, 1000, 3)) * (hi - lo)[:, None]  # 10^5 points
    structure = problem.spec.state(problem.robot, points.reshape(-1, 3), tuple(problem.orientations[0])).structure
    structure = structure.reshape(100, 1000, *structure.shape[1:])
    assert (enclosure.structure.lo[:, None] <= structure).all() and (structure <= enclosure.structure.hi[:, None]).all()
    lengths = np.linalg.norm(problem.spec.state(problem.robot, points.reshape(-1, 3), tuple(problem.orientations[0]))
                             .vectors, axis=2).reshape(100, 1000, -1)
    assert (enclosure.lengths.lo[:, None] <= lengths).all() and (lengths <= enclosure.lengths.hi[:, None]).all()
    # the mean-value enclosure is of second order: a box 10 times smaller is about 10 times narrower
    small = _enclosure(problem, lo, lo + (hi - lo) / 10)
    ratio = np.median((enclosure.structure.hi - enclosure.structure.lo) / (small.structure.hi - small.structure.lo))
    assert 8 < ratio < 12, ratio


@pytest.mark.parametrize("combine", ["y.A_i", "A t"])
def test_the_taylor_form_holds_products_of_the_structure_matrix_at_random_points_of_its_box(make_cfg, combine):
    """BoxEnclosure.times (Taylor's form to second order, the certificates' products) against the
    products computed at 10^5 random points of 100 boxes of a tilted robot, and against the
    mean-value form built here from the same enclosure (A(c) + sum_l dA/dp_l(B) (p_l - c_l)):
    sound, and narrower. A wrong second derivative (a sign, a factor, a term left out) lets
    points out of the boxes of a few decimetres."""
    problem = _problem(make_cfg, ROBOTS["tilted payload"][0])
    rng = np.random.default_rng(4)
    lo = rng.uniform([-1.4, -0.9, 0.3], [1.2, 0.7, 1.4], (100, 3))
    hi = lo + rng.uniform(0.01, 0.4, (100, 3))
    enclosure = _enclosure(problem, lo, hi)
    points = lo[:, None] + rng.uniform(0, 1, (100, 1000, 3)) * (hi - lo)[:, None]
    structure = problem.spec.state(problem.robot, points.reshape(-1, 3), tuple(problem.orientations[0])).structure
    structure = structure.reshape(100, 1000, *structure.shape[1:])  # (N, P, k, m)
    k, m = structure.shape[-2:]
    if combine == "y.A_i":
        given, product = rng.normal(size=(100, 2, k)), certificates._separated
        exact = np.einsum("nKk,npkm->npKm", given, structure)
    else:
        given, product = rng.uniform(1.0, 10.0, (100, 2, m)), certificates._tension_wrench
        exact = np.einsum("nKm,npkm->npKk", given, structure)
    found = enclosure.times(given, product)
    assert (found.lo[:, None] <= exact).all() and (exact <= found.hi[:, None]).all()
    mean_value = product(enclosure.centre, given)
    for axis in range(3):
        step = enclosure.step[:, axis][(slice(None),) + (None,) * (mean_value.lo.ndim - 1)]
        mean_value = mean_value + product(enclosure.slopes[:, axis], given) * step
    assert np.median((found.hi - found.lo) / (mean_value.hi - mean_value.lo)) < 0.8


@pytest.mark.parametrize("rates", ["first order", "random"])
def test_the_residual_enclosure_holds_the_residual_at_random_points_and_is_of_second_order(make_cfg, rates):
    """certificates.residual_enclosure (the inside certificate's r(B)) against r(p) = A(p) (t0 +
    D (p - c)) - w computed at 10^5 random points of 100 boxes of a tilted robot, w = A(c) t0.
    With D the first-order rates (A(c) D_l = -(dA/dp_l)(c) t0, dA/dp by central differences
    here) r is of second order: boxes 10 times smaller give an enclosure at least 60 times narrower
    (10 at first order); with random D the enclosure still holds r (first order)."""
    problem = _problem(make_cfg, ROBOTS["tilted payload"][0])
    robot, angles = problem.robot, tuple(problem.orientations[0])
    rng = np.random.default_rng(5)
    lo = rng.uniform([-1.4, -0.9, 0.3], [1.2, 0.7, 1.4], (100, 3))
    size = rng.uniform(0.01, 0.3, (100, 3))

    def structure_at(points):
        return problem.spec.state(robot, points.reshape(-1, 3), angles).structure.reshape(*points.shape[:-1], 6, -1)

    tensions = rng.uniform(1.0, 10.0, (100, 1, robot.n_cables))
    random_rates = rng.normal(size=(100, 1, robot.n_cables, 3))
    widths = []
    for scale in (1.0, 0.1):
        hi = lo + scale * size
        middle = lo + (hi - lo) / 2
        at_centre = structure_at(middle)
        wrenches = np.einsum("nkm,nKm->nKk", at_centre, tensions)
        if rates == "random":
            given = random_rates
        else:
            h = 1e-6
            slopes = np.stack([(structure_at(middle + h * e) - structure_at(middle - h * e)) / (2 * h) for e in np.eye(3)],
                              axis=1)
            given = -np.einsum("nmk,nlkj,nKj->nKml", np.linalg.pinv(at_centre), slopes, tensions)
        enclosure = certificates.structure_enclosure(paving.box_statics(problem, angles), lo, hi, middle)
        found = certificates.residual_enclosure(enclosure, Interval.point(wrenches), tensions, given)
        points = lo[:, None] + rng.uniform(0, 1, (100, 1000, 3)) * (hi - lo)[:, None]
        moved = tensions[:, None, 0] + np.einsum("nml,npl->npm", given[:, 0], points - middle[:, None])
        exact = np.einsum("npkm,npm->npk", structure_at(points), moved) - wrenches[:, None, 0]
        assert (found.lo[:, 0, None] <= exact).all() and (exact <= found.hi[:, 0, None]).all()
        widths.append(found.hi - found.lo)
    if rates == "first order":
        assert np.median(widths[0] / widths[1]) > 60  # 10 at first order; above 100 where the third order shows


def _errors_case(make_cfg, errors, rates, sizes=(0.005, 0.05), points=1000):
    """A tilted robot built within 20 mm (anchors) and/or 10 mm (attachments), 100 boxes of
    positions (sides drawn in ``sizes``) and the certificates' data over them: t0, w = A(c) t0, the
    rates D and E (``first order``: through the pseudo-inverse, dA/dp and dA/ddelta by central
    differences; ``random``; or ``none``), the structure matrix written from the law (u from each
    moved anchor to the moved platform point p + R (b + delta_b), columns [u; R (b + delta_b) x u]),
    and ``points`` random points of each box with a robot drawn within the tolerances at each (a
    third at corners)."""
    problem = _problem(make_cfg, ROBOTS["tilted payload"][0])
    robot, angles = problem.robot, tuple(problem.orientations[0])
    rotation, m = eq9_rotation(*angles), robot.n_cables
    tolerances = paving.Tolerances(anchors=0.0 if errors == "attachments" else 0.02,
                                   attachments=0.0 if errors == "anchors" else 0.01)
    rng = np.random.default_rng(8)
    lo = rng.uniform([-1.4, -0.9, 0.3], [1.2, 0.7, 1.4], (100, 3))
    hi = lo + rng.uniform(*sizes, (100, 3))
    middle = lo + (hi - lo) / 2

    def structure_at(points, anchors, attachments):  # (..., 3), (..., m, 3) twice -> (..., 6, m)
        arms = attachments @ rotation.T
        vectors = points[..., None, :] + arms - anchors
        unit = vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)
        return np.swapaxes(np.concatenate([unit, np.cross(arms, unit)], axis=-1), -1, -2)

    designed = (np.broadcast_to(robot.anchors, (100, m, 3)), np.broadcast_to(robot.attachments, (100, m, 3)))
    assert np.allclose(structure_at(middle, *designed), problem.spec.state(robot, middle, angles).structure, atol=1e-14)
    at_centre = structure_at(middle, *designed)
    tensions = rng.uniform(1.0, 10.0, (100, 1, m))
    wrenches = np.einsum("nkm,nKm->nKk", at_centre, tensions)
    sizes = np.array([size for size in (tolerances.anchors, tolerances.attachments) if size])
    count = 3 * m * len(sizes)  # the parameters, per cable and axis: anchors then attachments
    if rates == "random":
        moving, following = rng.normal(size=(100, 1, m, 3)), rng.normal(size=(100, 1, m, count))
    elif rates == "none":  # t = t0 throughout: dg_j/dp_l is the mixed term (d2A/ddelta_j dp_l) t0 alone
        moving, following = np.zeros((100, 1, m, 3)), np.zeros((100, 1, m, count))
    else:
        h = 1e-6
        inverse = np.linalg.pinv(at_centre)
        slopes = np.stack([(structure_at(middle + h * e, *designed) - structure_at(middle - h * e, *designed)) / (2 * h)
                           for e in np.eye(3)], axis=1)  # (100, 3, 6, m)
        moving = -np.einsum("nmk,nlkj,nKj->nKml", inverse, slopes, tensions)
        columns = []
        for cable in range(m):
            for axis in range(3):
                for which, size in enumerate((tolerances.anchors, tolerances.attachments)):
                    if size:
                        step = np.zeros((m, 3))
                        step[cable, axis] = h
                        plus = [part + step if k == which else part for k, part in enumerate(designed)]
                        minus = [part - step if k == which else part for k, part in enumerate(designed)]
                        columns.append((structure_at(middle, *plus) - structure_at(middle, *minus)) / (2 * h))
        following = -np.einsum("nmk,nPkj,nKj->nKmP", inverse, np.stack(columns, axis=1), tensions)
    nominal = certificates.structure_enclosure(paving.box_statics(problem, angles), lo, hi, middle)
    statics = paving.box_statics(problem, angles, tolerances)
    within = certificates.structure_enclosure(statics, lo, hi, middle)
    moves, arms, given = paving.build_errors(problem, angles, tolerances)
    assert np.array_equal(given, np.tile(sizes, 3 * m))
    errors = certificates.BuildErrors(nominal, certificates.structure_enclosure(statics, middle, middle, middle),
                                      following, moves, arms, given)
    points = lo[:, None] + rng.uniform(0, 1, (100, points, 3)) * (hi - lo)[:, None]
    drawn = np.where(rng.uniform(size=(100, points.shape[1], 1, 1, 1)) < 0.3,
                     rng.choice([-1.0, 1.0], (100, points.shape[1], m, 3, len(sizes))),
                     rng.uniform(-1, 1, (100, points.shape[1], m, 3, len(sizes)))) * sizes  # (.., cable, axis, kind)
    kinds = iter(range(len(sizes)))
    built = [robot.anchors + drawn[..., next(kinds)] if tolerances.anchors else robot.anchors,
             robot.attachments + drawn[..., next(kinds)] if tolerances.attachments else robot.attachments]
    return SimpleNamespace(**locals())


@pytest.mark.parametrize("rates", ["first order", "random"])
@pytest.mark.parametrize("errors", ["anchors", "attachments", "both"])
def test_the_errors_residual_holds_the_residual_of_every_robot_within_the_tolerances(make_cfg, errors, rates):
    """certificates.followed with build errors (the robust inside certificate's t and r) against
    t = t0 + D s + E delta and r = A(p, a + delta_a, b + delta_b) t - w computed from the law
    (:func:`_errors_case`) for 10^5 robots built within 20 mm (anchors) or 10 mm (attachments), each
    at a random point of one of 100 boxes of a tilted robot, w = A(c) t0. With the first-order rates
    and with random ones (r then of first order in the errors: the errors' term must hold it)."""
    case = _errors_case(make_cfg, errors, rates)
    moved, residual = certificates.followed(case.statics, case.within, Interval.point(case.wrenches), case.tensions,
                                            case.moving, case.errors)
    t = (case.tensions[:, None, 0] + np.einsum("nml,npl->npm", case.moving[:, 0], case.points - case.middle[:, None])
         + np.einsum("nmP,npP->npm", case.following[:, 0], case.drawn.reshape(100, 1000, -1)))
    exact = np.einsum("npkm,npm->npk", case.structure_at(case.points, *case.built), t) - case.wrenches[:, None, 0]
    assert (moved.lo[:, 0, None] <= t).all() and (t <= moved.hi[:, 0, None]).all()
    assert (residual.lo[:, 0, None] <= exact).all() and (exact <= residual.hi[:, 0, None]).all()


@pytest.mark.parametrize("rates", ["first order", "random", "none"])
@pytest.mark.parametrize("sizes", [(0.005, 0.05), (0.1, 0.3)])
def test_each_enclosure_of_the_build_errors_gradient_holds_it_by_central_differences(make_cfg, sizes, rates):
    """Each of the two enclosures of g_j = dr/ddelta_j (certificates.error_gradients: the range and
    the centred form, each on its own) against central differences (h = 1e-7 m) of r = A(p, a +
    delta_a, b + delta_b) t from the law, t = t0 + D s + E delta, for every anchor and attachment
    coordinate j of 2 000 robots drawn within the tolerances, each at a point of one of 100 boxes;
    with zero rates the centred form's spread over the box is its mixed term alone."""
    case = _errors_case(make_cfg, "both", rates, sizes, points=20)
    moved, _ = certificates.followed(case.statics, case.within, Interval.point(case.wrenches), case.tensions,
                                     case.moving, case.errors)
    reach = (np.abs(case.following) * case.given).sum(axis=-1)
    still = Interval(case.tensions - reach, case.tensions + reach)
    deltas = case.drawn.reshape(100, 20, -1)  # (.., P): per cable and axis, anchors then attachments

    def residual(shift):
        built = [case.robot.anchors + shift[..., 0], case.robot.attachments + shift[..., 1]]
        t = (case.tensions[:, None, 0] + np.einsum("nml,npl->npm", case.moving[:, 0], case.points - case.middle[:, None])
             + np.einsum("nmP,npP->npm", case.following[:, 0], shift.reshape(100, 20, -1)))
        return np.einsum("npkm,npm->npk", case.structure_at(case.points, *built), t)

    h, count = 1e-7, 0
    for j, (tolerance, ranged, centred) in enumerate(certificates.error_gradients(
            case.statics, case.within, case.errors, moved, still, case.moving)):
        assert tolerance == (0.02, 0.01)[j % 2]
        step = (h * np.eye(deltas.shape[-1])[j]).reshape(case.drawn.shape[2:])
        gradient = (residual(case.drawn + step) - residual(case.drawn - step)) / (2 * h)  # (100, 20, 6)
        slack = 1e-6 * (1 + np.abs(gradient))  # the central difference's own error
        for form in (ranged, centred):
            assert (form.lo[:, 0, None] - slack <= gradient).all() and (gradient <= form.hi[:, 0, None] + slack).all(), j
        count += 1
    assert count == deltas.shape[-1] == 48


def test_structure_enclosure_of_a_point_contains_the_exact_matrix(make_cfg):
    """Boxes of zero width: the enclosure is a few doubles wide and must hold the matrix computed
    at 50 digits (without outward rounding it is one double, off the exact value)."""
    problem = _problem(make_cfg, ROBOTS["tilted payload"][0])
    rng = np.random.default_rng(3)
    points = rng.uniform([-1.4, -0.9, 0.3], [1.4, 0.9, 1.7], (40, 3))
    enclosure = _enclosure(problem, points, points)
    robot, angles = problem.robot, problem.orientations[0]
    outside_float = 0
    with mpmath.workdps(50):
        a, b, c = (mpmath.mpf(float(v)) for v in angles)
        rx = mpmath.matrix([[1, 0, 0], [0, mpmath.cos(a), -mpmath.sin(a)], [0, mpmath.sin(a), mpmath.cos(a)]])
        ry = mpmath.matrix([[mpmath.cos(b), 0, mpmath.sin(b)], [0, 1, 0], [-mpmath.sin(b), 0, mpmath.cos(b)]])
        rz = mpmath.matrix([[mpmath.cos(c), -mpmath.sin(c), 0], [mpmath.sin(c), mpmath.cos(c), 0], [0, 0, 1]])
        rotation = rz * ry * rx
        for n, point in enumerate(points):
            for i in range(robot.n_cables):
                arm = rotation * mpmath.matrix([mpmath.mpf(float(v)) for v in robot.attachments[i]])
                d = [mpmath.mpf(float(point[k])) + arm[k] - mpmath.mpf(float(robot.anchors[i, k])) for k in range(3)]
                length = mpmath.sqrt(sum(v * v for v in d))
                u = [v / length for v in d]
                column = u + [arm[1] * u[2] - arm[2] * u[1], arm[2] * u[0] - arm[0] * u[2], arm[0] * u[1] - arm[1] * u[0]]
                for row in range(6):
                    lo, hi = enclosure.structure.lo[n, row, i], enclosure.structure.hi[n, row, i]
                    assert mpmath.mpf(lo) <= column[row] <= mpmath.mpf(hi)
                    assert hi - lo <= 1e-13
                    nearest = float(column[row])
                    outside_float += mpmath.mpf(nearest) != column[row]
    assert outside_float > 1000  # the exact values are not doubles: a one-double enclosure would miss them


# -- certified boxes against the exact per-pose test -------------------------------------------

@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_no_pose_of_a_certified_box_contradicts_the_exact_test(make_cfg, name):
    overrides, depth = ROBOTS[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    found, _ = paving.pave(problem, depth, 600.0, make_cfg(*overrides, "compute.n_jobs=1").compute)
    checked = {verdict: _min_margins(problem, _drawn(found, problem, verdict)) for verdict in (INSIDE, OUTSIDE)}
    atol = problem.margin_atol
    assert (checked[INSIDE] >= -atol).all(), np.sort(checked[INSIDE])[:5]
    assert (checked[OUTSIDE] < atol).all(), np.sort(checked[OUTSIDE])[-5:]
    assert (checked[OUTSIDE] < -atol).mean() > 0.99  # (a corner may sit on the boundary of an outside box)
    assert np.array_equal(found.at >= 0, found.verdict == OUTSIDE) and (found.at < len(problem.orientations)).all()
    for k in np.unique(found.at[found.verdict == OUTSIDE]):  # each outside box infeasible at the orientation it names
        named = Paving(found.lo, found.hi, np.where(found.at == k, OUTSIDE, UNDECIDED), found.depth, found.at)
        at_k = replace(problem, orientations=problem.orientations[k][None])
        assert (_min_margins(at_k, _drawn(named, problem, OUTSIDE, seed=int(k)))[:4000] < -atol).all(), k


def _drawn(found, problem, verdict, seed: int = 4) -> np.ndarray:
    """5 000 positions in the boxes of ``verdict``: 4 000 uniform in them (a box drawn by its
    volume) and 1 000 of their corners."""
    rng = np.random.default_rng(seed)
    rows = np.flatnonzero(found.verdict == verdict)
    assert len(rows) > 0, verdict
    weights = found.volumes(np.flatnonzero(problem.robot.box_hi > problem.robot.box_lo))[rows]
    pick = rng.choice(rows, 4000, p=weights / weights.sum())
    points = found.lo[pick] + rng.uniform(0, 1, (4000, 3)) * (found.hi[pick] - found.lo[pick])
    corners = np.where(rng.uniform(size=(1000, 3)) < 0.5, found.lo[pick[:1000]], found.hi[pick[:1000]])
    return np.concatenate([points, corners])


def test_a_drive_at_rest_is_proven_as_its_tension_cap(make_cfg, catalogue):
    """A catalogue actuator at rest holds each cable up to min(M_lim, U/S_v)/R (eqs. 32, 34 at
    zero speed; Table 1's actuator 3: 29.80 N, under the crane's 40 N rating), so its boxes are
    proven with that cap. Checked against the exact statics with the drive (its own torque and
    voltage criteria per pose, another code path): no drawn pose of an inside box fails, none of
    an outside box holds; the drive binds (poses of its outside boxes hold without it, and its
    inside volume is smaller)."""
    found, volumes, statics = {}, {}, {}
    for case, drive in (("driven", ["actuator=3"]), ("bare", [])):
        problem = build(make_cfg(*CRANE, "tension=feasible", "analysis=certified", *drive), catalogue)
        found[case], _ = paving.pave(problem, 11, 600.0, make_cfg(*CRANE, "compute.n_jobs=1").compute)
        volumes[case] = found[case].volumes(np.arange(3))[found[case].verdict == INSIDE].sum()
        statics[case] = build(make_cfg(*CRANE, "tension=feasible", "analysis=statics", *drive), catalogue)
    assert set(statics["driven"].criteria) >= {"torque", "voltage"}
    atol = statics["driven"].margin_atol
    inside = _min_margins(statics["driven"], _drawn(found["driven"], statics["driven"], INSIDE))
    outside = _drawn(found["driven"], statics["driven"], OUTSIDE)
    assert (inside >= -atol).all() and (_min_margins(statics["driven"], outside) < atol).all()
    assert (_min_margins(statics["bare"], outside) > atol).mean() > 0.01  # 2.3 %: the outside is mostly far
    assert volumes["driven"] < 0.9 * volumes["bare"], volumes


def test_the_bracket_holds_a_fine_grid_and_narrows_with_depth(make_cfg):
    problem = _problem(make_cfg, PLANAR_BODY, "compute.n_jobs=1")
    compute = make_cfg(*PLANAR_BODY, "compute.n_jobs=1").compute
    axes = np.array([0, 1])
    brackets = []
    for depth in (8, 11, 14):
        found, ended = paving.pave(problem, depth, 600.0, compute)
        volumes = found.volumes(axes)
        inside, undecided = volumes[found.verdict == INSIDE].sum(), volumes[found.verdict == UNDECIDED].sum()
        assert np.isclose(volumes.sum(), 1.8 * 1.8)  # the boxes tile the search box
        brackets.append((inside, inside + undecided))
        assert ended["depth_reached"] == depth
    steps = np.linspace(-0.9, 0.9, 301)
    grid = np.stack(np.meshgrid(steps, steps, [0.0], indexing="ij"), axis=-1).reshape(-1, 3)
    area = (_min_margins(problem, grid) >= -problem.margin_atol).mean() * 1.8 * 1.8
    for low, high in brackets:
        assert low - 0.02 <= area <= high + 0.02, (low, area, high)
    assert brackets[0][0] < brackets[1][0] < brackets[2][0] and brackets[0][1] > brackets[1][1] > brackets[2][1]
    assert brackets[2][1] - brackets[2][0] < 0.5 * (brackets[0][1] - brackets[0][0])


@pytest.mark.parametrize("name", ["ipanema", "tilted payload"])
def test_a_box_spared_its_lp_has_a_corner_the_exact_test_decides(make_cfg, name):
    """The paving tries no inside certificate on a box with a corner that fails by more than the
    margins' tolerance, no outside one on a box with a corner that holds by more (no such
    certificate can hold there). Against the exact per-pose test of the cable forces at the 8
    corners of 3 000 random boxes (the tilted robot's cables limited in length too, which the
    paving proves apart): each box said to have a failing (holding) corner has one; and a box whose corners the
    exact test finds failing (holding) by 1e-6 is said to, but for the few the compiled test cannot
    decide (a corner on an anchor)."""
    problem = _problem(make_cfg, ROBOTS[name][0])
    robot = problem.robot
    rng = np.random.default_rng(6)
    size = (robot.box_hi - robot.box_lo) / 16
    lo = rng.uniform(robot.box_lo, robot.box_hi - size, (3000, 3))
    hi = lo + size * rng.uniform(0.2, 1.0, (3000, 3))
    statics = paving.box_statics(problem, problem.orientations[0])
    every = np.broadcast_to((statics.wrenches.lo + statics.wrenches.hi) / 2, (3000, *statics.wrenches.shape))
    fails, holds = paving._corners(problem, statics, tuple(problem.orientations[0]), lo, hi, every)
    corners = np.where(np.arange(8)[:, None] >> np.arange(3) & 1, hi[:, None], lo[:, None])
    found = evaluate_chunk(problem, corners.reshape(-1, 3))  # the forces' criteria (a cable's length is proven apart)
    forces = ("unreachable", "slack", "tension_max")
    margins = np.min([found[f"margin_{criterion}"] for criterion in forces], axis=0).reshape(-1, 8)
    atol = problem.margin_atol
    assert (margins[fails] < -atol).any(axis=1).all() and (margins[holds] > atol).any(axis=1).all()
    clearly_fails, clearly_holds = (margins < -1e-6).any(axis=1), (margins > 1e-6).any(axis=1)
    assert clearly_fails.sum() > 300 and clearly_holds.sum() > 300 and (clearly_fails & clearly_holds).sum() > 30
    assert fails[clearly_fails].mean() > 0.99 and holds[clearly_holds].mean() > 0.99


def test_a_load_no_cable_can_hold_is_outside_everywhere(make_cfg):
    """A weight the cables cannot hold anywhere (100 kg on cables rated 40 N): the whole search
    box certified outside within a few levels."""
    compute = make_cfg(*PLANAR_POINT, "compute.n_jobs=1").compute
    heavy = _problem(make_cfg, PLANAR_POINT, "robot.platform.mass=100", "compute.n_jobs=1")
    found, ended = paving.pave(heavy, 6, 60.0, compute)
    assert (found.verdict == OUTSIDE).all() and ended["stopped"] == "decided" and ended["depth_reached"] <= 3


# -- the command line ----------------------------------------------------------------------

def test_a_certified_job_writes_its_boxes_and_the_bracket(tmp_path):
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *PLANAR_BODY, "tension=feasible", "analysis=certified", "certified.depth=9",
                   f"hydra.run.dir={run}")
    assert done.returncode == 0, done.stderr[-2000:]
    boxes = pd.read_parquet(run / "boxes.parquet")
    assert list(boxes.columns) == ["lo_x", "lo_y", "lo_z", "hi_x", "hi_y", "hi_z", "verdict", "depth", "volume"]
    assert set(boxes.verdict) <= {"inside", "outside", "undecided"}
    summary = pd.read_parquet(run / "summary.parquet").iloc[0]
    assert summary.analysis == "certified" and summary.stopped == "depth" and summary.depth_reached == 9
    assert np.isclose(summary.inside_m3 + summary.outside_m3 + summary.undecided_m3, summary.box_m3)
    assert np.isclose(summary.inside_m3, boxes.volume[boxes.verdict == "inside"].sum())
    assert np.isclose(summary.undecided_pct, 100 * summary.undecided_m3 / summary.box_m3)
    assert "certified:" in done.stdout and "undecided" in done.stdout


def test_an_outside_box_names_the_orientation_it_fails_at_in_the_users_convention(tmp_path):
    """With an orientation set (CASPR's angles, xyz), boxes.parquet names, for each outside box, the
    orientation it was proven infeasible at: its number and its angles as the job gives them (the
    nominal +- 0.3 rad about z, written here), NaN for the other boxes; with one orientation no such
    column."""
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *PLANAR_BODY, "tension=feasible", "analysis=certified", "certified.depth=8",
                   "orientation.convention=xyz", "orientation.total={bound: 0.3, n: 3}", f"hydra.run.dir={run}")
    assert done.returncode == 0, done.stderr[-2000:]
    boxes = pd.read_parquet(run / "boxes.parquet")
    outside = boxes.verdict == "outside"
    assert outside.any() and boxes.loc[~outside, ["outside_orientation", "outside_phi"]].isna().all().all()
    named = boxes.loc[outside, ["outside_psi", "outside_theta", "outside_phi"]].to_numpy()
    assert set(boxes.loc[outside, "outside_orientation"]) <= set(range(1, 28))
    nominal = np.array([0.0, 0.0, 0.3])  # PLANAR_BODY's orientation.phi
    grid = nominal + np.array(list(itertools.product([-0.3, 0.0, 0.3], repeat=3)))
    assert all(np.isclose(grid, row, rtol=0, atol=1e-12).all(axis=1).any() for row in named)
    first = boxes.loc[outside & (boxes.outside_orientation == 1), ["outside_psi", "outside_theta", "outside_phi"]]
    assert np.allclose(first.to_numpy(), nominal)  # number 1: the nominal orientation
    single = tmp_path / "single"
    assert command(tmp_path, "pipeline", *PLANAR_BODY, "tension=feasible", "analysis=certified", "certified.depth=4",
                   f"hydra.run.dir={single}").returncode == 0
    assert "outside_orientation" not in pd.read_parquet(single / "boxes.parquet")


def test_the_time_budget_leaves_the_rest_undecided(make_cfg):
    problem = _problem(make_cfg, IPANEMA, "compute.n_jobs=1")
    found, ended = paving.pave(problem, 30, 1e-9, make_cfg(*IPANEMA, "compute.n_jobs=1").compute)
    assert ended["stopped"] == "time" and (found.verdict == UNDECIDED).all() and len(found.verdict) == 1


REFUSALS = {  # overrides -> what the one line names
    ("tension=pinv",): "tension.model=pinv",
    ("robot.dofs=[rx,ry,rz]", "robot.search.lo=[-0.3,-0.3,-0.3]", "robot.search.hi=[0.3,0.3,0.3]"): "robot.dofs",
    ("poses=[[0,0,1]]",): "poses",
    ("robot.pulleys={axis: [0, 0, 1], radius: 0.05}",): "robot.pulleys",
    ("model.moment_arm=base",): "model.moment_arm=base",
    ("output.mesh=true",): "output.mesh",
    ("output.cables=true",): "output.cables",
    ("compute.kernel=fused",): "compute.kernel=fused",
    ("workspace.home=[0,0,1]",): "workspace.home",
    ("robot.platform.shape={lo: [-0.06, -0.06, -0.02], hi: [0.06, 0.06, 0]}", "robust.attachments=0.001"):
        "robust.attachments: analysis=certified: an attachment built off its place",
    ("certified.depth=-1",): "certified.depth",
    ("certified.depth=41",): "certified.depth",
    ("certified.time=0",): "certified.time",
    ("certified.time=inf",): "certified.time",
    ("robot.search.lo=null", "robot.search.hi=null"): "robot.search",
    ("robust.anchors=-0.01",): "robust.anchors",
    ("robust.com=nan",): "robust.com",
    ("robust.anchors=1e300",): "robust.anchors=1e+300: must be in [0, 10000] m",  # numpy's overflow warning before
    ("orientation.total={bound: 0.1, n: 11}",): "orientation.total.n=11: analysis=certified: every box is proven at each",
    ("robust.mass=2",): "robust.mass=2",  # more than the load's mass (massless here)
    ("robot.platform.mass=1", "robust.mass=0.1", "platform_motion.acceleration=[[1,0,0,0,0,0]]"): "robust.mass",
    ("certified.path=[[0,0,1]]",): "certified.path",
    ("certified.path=[[0,0,1],[0,0,1]]",): "way-point 2 repeats way-point 1",
    ("certified.path=[[0,0,1],[1,nan,1]]",): "way-point 2",
    ("certified.path=[[0,0,1],[1,1]]",): "way-point 2: needs 3 values",
    ("certified.path=[[0,0,1],[1e5,0,1]]",): "way-point 2",
    ("certified.path=[0,0,1]",): "certified.path",
    # a moving path's times (certified.times)
    ("certified.times=1",): "certified.times",  # no path
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.times=[1,2]"): "certified.times=[1, 2]: 2 durations for 1 segments",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.times=-1"): "certified.times=-1",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.times=1e-200"): "certified.times: segment 1 accelerates at inf",
    ("certified.path=[[0,0,1],[0,0,2],[0,1,2]]", "certified.times=[1,0.01]"): "segment 2 accelerates at 5.77e+04",
    ("robot.platform.mass=1", "certified.path=[[0,0,1],[0,0,2]]", "certified.times=1",
     "platform_motion.acceleration=[[1,0,0,0,0,0]]"): "platform_motion: analysis=certified: a moving path's",
    ("robot.platform.mass=1", "certified.path=[[0,0,1],[0,0,2]]", "certified.times=1", "robust.mass=0.1"):
        "without platform_motion or a moving path",
    # a trapezoid's speed profile (certified.law=trapezoid)
    ("certified.law=trapezoid",): "certified.law=trapezoid: the motion along certified.path's segments",  # no path
    ("certified.v_max=1",): "certified.v_max: the motion along certified.path's segments",
    ("certified.law=linear",): "certified.law",
    # a box of orientations (certified.orientations=box)
    ("certified.orientations=all",): "certified.orientations",
    ("certified.orientations=box",): "certified.orientations=box: analysis=certified: orientation.total.bound is 0",
    ("certified.orientations=box", "orientation.total={bound: 0.01, n: 1}", "certified.path=[[0,0,1],[0,0,2]]",
     "certified.times=1"): "certified.orientations=box: analysis=certified: a moving platform's inertia turns",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.v_max=1"): "certified.v_max: a trapezoid's speed profile",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.law=trapezoid", "certified.v_max=1"):
        "certified.t_acc: certified.law=trapezoid needs v_max (m/s), t_acc and t_dec (s)",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.law=trapezoid", "certified.v_max=1", "certified.t_acc=1",
     "certified.t_dec=1", "certified.times=1"): "certified.times: law trapezoid times each segment",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.law=trapezoid", "certified.v_max=1", "certified.t_acc=1e-6",
     "certified.t_dec=1"): "certified.t_acc=1e-06: v_max / t_acc = 1e+06 m/s^2 at v_max=1 m/s; must be > 0 and at most",
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.law=trapezoid", "certified.v_max=1e-300", "certified.t_acc=1",
     "certified.t_dec=1e300"): "certified.t_dec=1e+300: v_max / t_dec = 0 m/s^2",  # a division by zero before
    ("certified.path=[[0,0,1],[0,0,2]]", "certified.law=trapezoid", "certified.v_max=1", "certified.t_acc=0",
     "certified.t_dec=1"): "certified.t_acc",
    ("robot.platform.mass=1", "certified.path=[[0,0,1],[0,0,2]]", "certified.law=trapezoid", "certified.v_max=1",
     "certified.t_acc=1", "certified.t_dec=1", "platform_motion.acceleration=[[1,0,0,0,0,0]]"):
        "platform_motion: analysis=certified: a moving path's",
}


@pytest.mark.parametrize("overrides", sorted(REFUSALS))
def test_what_a_paving_cannot_prove_is_refused_in_one_line(tmp_path, overrides):
    run = tmp_path / "run"
    base = [o for o in IPANEMA if not (o.startswith("robot.search") and any(x.startswith("robot.search") for x in overrides))]
    done = command(tmp_path, "pipeline", *base, "tension=feasible", "analysis=certified", *overrides,
                   f"hydra.run.dir={run}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and REFUSALS[overrides] in lines[0], done.stderr[-1500:]
    assert not run.exists()


# -- robust workspaces: build tolerances ---------------------------------------------------------

ROBUST = {  # name -> (overrides, depth, tolerances, what the perturbed robots change)
    "planar body": (PLANAR_BODY, 11, paving.Tolerances(anchors=0.01, attachments=0.005)),
    "crane": (CRANE, 12, paving.Tolerances(anchors=0.01, mass=0.2, com=0.01)),
    "ipanema": (ROBOTS["ipanema"][0], 11, paving.Tolerances(anchors=0.01)),
}


def _perturbed(overrides, robot, tolerances, rng, corner: bool) -> list[str]:
    """The overrides of a robot drawn within the tolerances (a corner of their box, or inside)."""
    def draw(shape, half):
        values = rng.choice([-1.0, 1.0], shape) if corner else rng.uniform(-1.0, 1.0, shape)
        return half * values
    anchors = robot.anchors + draw(robot.anchors.shape, tolerances.anchors)
    attachments = robot.attachments + draw(robot.attachments.shape, tolerances.attachments)
    mass = float(next(o for o in overrides if o.startswith("robot.platform.mass")).split("=")[1]) if any(
        o.startswith("robot.platform.mass") for o in overrides) else 0.0
    return [*[o for o in overrides if not o.startswith(("robot.anchors", "robot.attachments", "robot.platform.mass"))],
            f"robot.anchors={anchors.tolist()}", f"robot.attachments={attachments.tolist()}",
            f"robot.platform.mass={mass + float(draw((), tolerances.mass))}",
            f"robot.platform.com={draw(3, tolerances.com).tolist()}"]


LAW = {  # name -> (the rows of its freedoms, the applied wrenches' vertices, t_min, t_max, eq. 9's angles): its overrides
    "planar body": ([0, 1, 5], [[fx, 0, 0, 0, 0, mz] for fx in (-5, 5) for mz in (-0.2, 0.2)], 2.0, 60.0, (0, 0, 0.3)),
    "crane": ([0, 1, 2], [[3, 0, 0, 0, 0, 0]], 1.0, 40.0, (0, 0, 0)),
    "ipanema": ([0, 1, 2, 3, 4, 5], [[0, 0, 0, 0, 0, 0]], 1.0, 10.0, (0, 0, 0)),
}


def _law_feasible(name, anchors, attachments, mass, com, positions) -> np.ndarray:
    """(n,) pulling-cable feasibility of robot row j (anchors, attachments (n, m, 3), mass (n,),
    centre of mass (n, 3)) at positions[j], written from the law, not from the model's code: u_i
    from the anchor to the platform point p + R b_i, columns [u_i; R b_i x u_i], A t = w with w the
    applied wrench plus the weight m g (-z) at R com (docs/model.md), every vertex of the set
    balanced by tensions in [t_min, t_max]. The null-space test decides; what it leaves undecided
    goes to an LP."""
    rows, applied, t_min, t_max, angles = LAW[name]
    rotation = eq9_rotation(*angles)
    arms = attachments @ rotation.T
    vectors = positions[:, None, :] + arms - anchors
    unit = vectors / np.linalg.norm(vectors, axis=2, keepdims=True)
    structure = np.swapaxes(np.concatenate([unit, np.cross(arms, unit)], axis=2), 1, 2)[:, rows, :]
    weight = mass[:, None] * 9.81 * np.array([0.0, 0.0, -1.0])
    weight = np.concatenate([weight, np.cross(com @ rotation.T, weight)], axis=1)
    wrenches = np.asarray(applied, dtype=float)[None] + weight[:, None]
    m = anchors.shape[1]
    lower, upper = np.full(m, t_min - 1e-9), np.full(m, t_max + 1e-9)
    verdicts = null_space_verdicts(structure, wrenches[:, :, rows], lower, upper).astype(float)
    for j in np.flatnonzero(verdicts < 0):
        verdicts[j] = all(linprog(np.zeros(m), A_eq=structure[j], b_eq=w[rows], bounds=(t_min, t_max),
                                  method="highs").status == 0 for w in wrenches[j])
    return verdicts.astype(bool)


@pytest.mark.parametrize("name", sorted(ROBUST))
def test_no_robot_within_the_tolerances_contradicts_a_robust_box(make_cfg, name):
    """Monte-Carlo falsification (issue 57's check): 10^5 robots drawn within the tolerances (a
    third at corners of their box), each at 10 random poses of the robust inside boxes (boxes drawn
    alike, so the small ones along the boundary are sampled densely), all feasible by the law
    (``_law_feasible``, which first agrees with the model's exact test on the nominal robot across
    the whole search box, both verdicts present). Robots drawn within 4x the tolerances fail it
    (20 to 700 poses in 10^5, measured): the check can fail. The robust inside set lies in the
    nominal one and shrinks as the tolerances grow."""
    overrides, depth, tolerances = ROBUST[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    robot = problem.robot
    compute = make_cfg(*overrides, "compute.n_jobs=1").compute
    axes = np.flatnonzero(robot.box_hi > robot.box_lo)
    nominal, _ = paving.pave(problem, depth, 600.0, compute)
    robust, _ = paving.pave(problem, depth, 600.0, compute, tolerances)
    half = paving.Tolerances(**{k: v / 2 for k, v in vars(tolerances).items()})
    between, _ = paving.pave(problem, depth, 600.0, compute, half)
    volume = {key: found.volumes(axes)[found.verdict == INSIDE].sum() for key, found in
              (("nominal", nominal), ("half", between), ("robust", robust))}
    assert 0 < volume["robust"] < volume["half"] < volume["nominal"], volume
    outside = [found.volumes(axes)[found.verdict == OUTSIDE].sum() for found in (robust, nominal)]
    assert np.isclose(*outside)  # outside is the nominal robot's
    mass = float(next((o.split("=")[1] for o in overrides if o.startswith("robot.platform.mass")), 0.0))
    rng = np.random.default_rng(5)
    n = 10_000
    anywhere = robot.box_lo + rng.uniform(0, 1, (n, 3)) * (robot.box_hi - robot.box_lo)
    law = _law_feasible(name, np.broadcast_to(robot.anchors, (n, *robot.anchors.shape)),
                        np.broadcast_to(robot.attachments, (n, *robot.attachments.shape)), np.full(n, mass),
                        np.zeros((n, 3)), anywhere)
    assert 0.05 < law.mean() < 0.95 and (law == (_min_margins(problem, anywhere) >= -problem.margin_atol)).all()
    rows = np.flatnonzero(robust.verdict == INSIDE)
    robots, poses = 100_000, 10
    for chunk in range(10):  # 10^4 robots at a time
        count = robots // 10
        corner = (np.arange(count) % 3 == 0)[:, None, None]

        def draw(shape, half):
            values = np.where(corner.reshape((count,) + (1,) * (len(shape) - 1)), rng.choice([-1.0, 1.0], shape),
                              rng.uniform(-1.0, 1.0, shape))
            return np.repeat(half * values, poses, axis=0)
        anchors = robot.anchors + draw((count, *robot.anchors.shape), tolerances.anchors)
        attachments = robot.attachments + draw((count, *robot.attachments.shape), tolerances.attachments)
        masses = mass + draw((count,), tolerances.mass)
        com = draw((count, 3), tolerances.com)
        pick = rng.choice(rows, count * poses)
        points = robust.lo[pick] + rng.uniform(0, 1, (count * poses, 3)) * (robust.hi[pick] - robust.lo[pick])
        held = _law_feasible(name, anchors, attachments, masses, com, points)
        assert held.all(), (chunk, points[~held][:3], anchors[~held][:1])


def _inside(found: paving.Paving, points: np.ndarray) -> np.ndarray:
    """(n,) whether each point lies in an inside box of the paving."""
    lo, hi = found.lo[found.verdict == INSIDE], found.hi[found.verdict == INSIDE]
    return np.concatenate([((part[:, None] >= lo) & (part[:, None] <= hi)).all(axis=-1).any(axis=-1)
                           for part in np.array_split(points, 50)])


def test_a_mass_tolerance_proves_what_the_lightest_and_heaviest_robots_both_prove(make_cfg):
    """A crane of 10 kg within +-1 kg: the wrench is affine in the mass and the wrenches a robot
    balances at a pose are convex, so the robust set is the poses both the 9 and the 11 kg robots
    hold. At 10^5 random points the robust paving's inside set lies in both of theirs and holds at
    least 85 % of their common part (91 % measured; the hull of the two wrenches, certified as one
    interval wrench, held 43 %)."""
    pavings = {}
    for mass, tolerances in ((10, paving.Tolerances(mass=1.0)), (9, paving.Tolerances()), (11, paving.Tolerances())):
        overrides = [*CRANE, f"robot.platform.mass={mass}"]
        problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
        pavings[mass] = paving.pave(problem, 12, 600.0, make_cfg(*overrides, "compute.n_jobs=1").compute, tolerances)[0]
    robot = problem.robot
    points = robot.box_lo + np.random.default_rng(1).uniform(0, 1, (100_000, 3)) * (robot.box_hi - robot.box_lo)
    robust, both = _inside(pavings[10], points), _inside(pavings[9], points) & _inside(pavings[11], points)
    assert not (robust & ~both).any() and robust.sum() >= 0.85 * both.sum() > 0, (robust.sum(), both.sum())


def _with_error(overrides, robot, tolerances, name: str, share: float) -> list[str]:
    """The overrides of the robot built with one named error (``anchor 3 z-``, ``mass+``, ``com y+``)
    at ``share`` of its tolerance, written from the name (not by the code under test)."""
    words = name.split()
    sign = 1.0 if words[-1].endswith("+") else -1.0
    mass = float(next((o.split("=")[1] for o in overrides if o.startswith("robot.platform.mass")), 0.0))
    anchors, attachments, com = robot.anchors.copy(), robot.attachments.copy(), np.zeros(3)
    if words[0] in ("anchor", "attachment"):
        points = anchors if words[0] == "anchor" else attachments
        points[robot.cable_names.index(words[1]), "xyz".index(words[2][0])] += sign * share * getattr(
            tolerances, words[0] + "s")
    elif words[0].startswith("mass"):
        mass += sign * share * tolerances.mass
    else:
        com["xyz".index(words[1][0])] += sign * share * tolerances.com
    return [*[o for o in overrides if not o.startswith(("robot.anchors", "robot.attachments", "robot.platform.mass"))],
            f"robot.anchors={anchors.tolist()}", f"robot.attachments={attachments.tolist()}",
            f"robot.platform.mass={mass}", f"robot.platform.com={com.tolist()}"]


@pytest.mark.parametrize("name", sorted(ROBUST))
def test_the_named_build_error_breaks_the_centre_of_its_box_and_no_smaller_one_does(make_cfg, name):
    """tolerances.culprits on the undecided boxes of a robust paving, against the exact per-pose test
    of robots built from the overrides: a named box's centre holds as designed and fails with its
    error at the share named (a counterexample within the tolerances), not at 1/64 less, and no
    other single error breaks it at 1/64 less; a nominally feasible centre left unnamed holds with
    every single error at its whole tolerance."""
    overrides, depth, tolerances = ROBUST[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    compute = make_cfg(*overrides, "compute.n_jobs=1").compute
    robust, _ = paving.pave(problem, depth, 600.0, compute, tolerances)
    open_ = np.flatnonzero(robust.verdict == UNDECIDED)
    centres = robust.lo[open_] + (robust.hi[open_] - robust.lo[open_]) / 2
    names, shares = culprits(problem, tolerances, centres)
    threads = culprits(problem, tolerances, centres, n_jobs=2)  # the errors on two threads: the same names
    assert list(threads[0]) == list(names) and np.array_equal(threads[1], shares, equal_nan=True)
    is_named = np.array([found is not None for found in names], dtype=bool)
    named = np.flatnonzero(is_named)
    assert len(named), "no undecided box is lost to a single build error"
    atol = problem.margin_atol
    rng = np.random.default_rng(3)

    def least(error: str, share: float, points: np.ndarray) -> np.ndarray:
        return _min_margins(_problem(make_cfg, _with_error(overrides, problem.robot, tolerances, error, share),
                                     "compute.n_jobs=1"), points)

    for row in rng.choice(named, min(12, len(named)), replace=False):
        point = centres[row:row + 1]
        assert _min_margins(problem, point)[0] >= -atol
        assert least(names[row], shares[row], point)[0] < -atol, (names[row], shares[row])
        if shares[row] > 1 / 64:
            assert least(names[row], shares[row] - 1 / 64, point)[0] >= -atol
    errors = [error for error, _ in tolerances_errors(problem, tolerances)]
    assert len(errors) == 2 * (3 * problem.robot.n_cables * ((tolerances.anchors > 0) + (tolerances.attachments > 0))
                               + (tolerances.mass > 0) + 3 * (tolerances.com > 0))
    for row in rng.choice(named, 1, replace=False):
        if shares[row] > 1 / 64:
            below = [least(error, shares[row] - 1 / 64, centres[row:row + 1])[0] for error in errors]
            assert min(below) >= -atol, (names[row], shares[row], errors[int(np.argmin(below))])
    held = _min_margins(problem, centres) >= -atol
    unnamed = np.flatnonzero(held & ~is_named)
    if len(unnamed):
        points = centres[rng.choice(unnamed, min(20, len(unnamed)), replace=False)]
        assert min(least(error, 1.0, points).min() for error in errors) >= -atol
    assert not (~held & is_named).any()  # a centre failing as designed is not lost to the tolerances


def test_a_robust_job_names_the_errors_in_its_boxes_and_summary(tmp_path):
    run = tmp_path / "run"
    overrides = [*ROBOTS["ipanema"][0], "tension=feasible", "analysis=certified", "certified.depth=10"]
    done = command(tmp_path, "pipeline", *overrides, "robust.anchors=0.01", f"hydra.run.dir={run}")
    assert done.returncode == 0, done.stderr[-2000:]
    boxes, summary = pd.read_parquet(run / "boxes.parquet"), pd.read_parquet(run / "summary.parquet").iloc[0]
    named = boxes["lost_to"].notna()
    assert named.any() and (boxes.loc[named, "verdict"] == "undecided").all()
    assert boxes.loc[named, "lost_at"].between(1 / 64, 1).all() and boxes.loc[~named, "lost_at"].isna().all()
    by_error = boxes[named].groupby("lost_to", observed=True)["volume"].sum()
    assert summary["lost_named_m3"] == pytest.approx(boxes.loc[named, "volume"].sum())
    assert summary["lost_to_top_m3"] == pytest.approx(by_error.max()) and by_error[summary["lost_to_top"]] == by_error.max()
    nominal = tmp_path / "nominal"
    assert command(tmp_path, "pipeline", *overrides, f"hydra.run.dir={nominal}").returncode == 0
    assert "lost_to" not in pd.read_parquet(nominal / "boxes.parquet").columns
    assert "lost_named_m3" not in pd.read_parquet(nominal / "summary.parquet").columns


def test_a_vanishing_tolerance_gives_the_nominal_paving(make_cfg):
    problem = _problem(make_cfg, PLANAR_BODY, "compute.n_jobs=1")
    compute = make_cfg(*PLANAR_BODY, "compute.n_jobs=1").compute
    nominal, _ = paving.pave(problem, 10, 600.0, compute)
    tiny, _ = paving.pave(problem, 10, 600.0, compute, paving.Tolerances(anchors=1e-12, attachments=1e-12))
    assert np.array_equal(nominal.verdict, tiny.verdict) and np.array_equal(nominal.lo, tiny.lo)


@pytest.mark.parametrize("analysis", ["statics", "payload", "cpr_wwa", "lines", "trajectory"])
def test_the_paving_keys_belong_to_it_alone(tmp_path, analysis):
    for key in ("certified.depth=3", "robust.anchors=0.01", "certified.path=[[0,0,1],[1,0,1]]"):
        run = tmp_path / "run"
        done = command(tmp_path, "pipeline", f"analysis={analysis}", key, f"hydra.run.dir={run}")
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1 and key in lines[0], done.stderr[-1500:]
        assert not run.exists()


def test_the_paving_figure_cuts_the_boxes_and_its_areas_tile_the_plane(tmp_path):
    """A study of a planar body's paving: the figure kind ``paving`` draws its plane and its CSV
    gives the areas inside, outside and undecided, which add up to the search box and match the
    summary's volumes (areas for a planar robot)."""
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "plane.yaml").write_text(
        "title: a planar paving\nsource: test\noverrides:\n" + "".join(f"  - \"{o}\"\n" for o in PLANAR_BODY)
        + "  - tension=feasible\n  - analysis=certified\n  - certified.depth=9\n"
        "figures:\n  - kind: paving\n    file: plane.png\n    axis: z\n    layers: 2\n    title: plane\n")
    done = command(tmp_path, "pipeline.study", "--config-dir", str(tmp_path), "plane", "--out", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr[-2000:]
    series = pd.read_csv(tmp_path / "out" / "plane" / "series" / "plane.csv")
    assert len(series) == 1  # a plane: one section
    row = series.iloc[0]
    assert np.isclose(row.inside_m2 + row.outside_m2 + row.undecided_m2, 1.8 * 1.8)
    summary = pd.read_parquet(next((tmp_path / "out" / "plane").glob("**/summary.parquet"))).iloc[0]
    assert np.isclose(row.inside_m2, summary.inside_m3) and np.isclose(row.undecided_m2, summary.undecided_m3)
    assert (tmp_path / "out" / "plane" / "figures" / "plane.png").stat().st_size > 10_000


def test_the_api_runs_a_paving_and_draws_it(tmp_path, monkeypatch):
    from pipeline import api

    monkeypatch.chdir(tmp_path)
    ws = api.workspace([*PLANAR_BODY, "tension=feasible", "analysis=certified", "certified.depth=8"])
    assert ws.points is None and ws.samples is None and set(ws.boxes.verdict) <= {"inside", "outside", "undecided"}
    assert np.isclose(ws.boxes.volume.sum(), ws.summary["box_m3"]) and ws.summary["depth_reached"] == 8
    drawn = ws.figure("paving", out=tmp_path / "mine", layers=1)
    assert [p.name for p in drawn if p.suffix == ".png"] == ["paving.png"]
    with pytest.raises(api.ConfigError, match="no boxes.parquet"):
        api.workspace([*PLANAR_BODY, "tension=feasible", "analysis=statics", "robot.search.step=0.3"]).figure("paving")


# -- certified paths: every point of a segment proven -------------------------------------------

PATHS = {  # name -> (overrides, way-points, depth)
    "ipanema": (IPANEMA, [[-1, -0.5, 0.5], [1, 0.5, 1.5], [0.5, -1, 1], [1.9, 1.4, 1.9]], 12),
    "tilted payload": (ROBOTS["tilted payload"][0], [[-1.2, -0.8, 0.3], [1.2, 0.7, 1.6], [-0.5, 0.9, 1.2]], 12),
    "planar point": (PLANAR_POINT, [[-0.9, 0.2, 0], [1.1, 1.8, 0], [0, 1.0, 0]], 12),
}


@pytest.mark.parametrize("name", sorted(PATHS))
def test_a_certified_path_agrees_with_the_exact_test_along_it(make_cfg, name):
    """Every point sampled on a piece proven inside holds, none on a piece proven outside does,
    and the exact test's first failing sample lies after the last piece before the first one not
    proven inside and no later than where the first outside piece starts (within a sample)."""
    overrides, points, depth = PATHS[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    points = np.asarray(points, dtype=float)
    pieces, verdict, _, _, ended = paving.certify_path(problem, points, depth, 600.0,
                                                    make_cfg(*overrides, "compute.n_jobs=1").compute)
    starts, ends = points[:-1], points[1:]
    segment = pieces[:, 0].astype(int)
    rng = np.random.default_rng(7)
    for kind in (INSIDE, OUTSIDE):
        rows = np.flatnonzero(verdict == kind)
        if not len(rows):
            assert kind == OUTSIDE and name != "ipanema"
            continue
        pick = rng.choice(rows, 3000)
        t = rng.uniform(pieces[pick, 1], pieces[pick, 2])
        t[:200] = pieces[pick[:200], 1]  # the pieces' own ends too
        samples = starts[segment[pick]] + t[:, None] * (ends[segment[pick]] - starts[segment[pick]])
        least = _min_margins(problem, samples)
        if kind == INSIDE:
            assert (least >= -problem.margin_atol).all(), np.sort(least)[:5]
        else:
            assert (least < problem.margin_atol).all(), np.sort(least)[-5:]
    lengths = np.linalg.norm(ends - starts, axis=1)
    assert np.isclose(((pieces[:, 2] - pieces[:, 1]) * lengths[segment]).sum(), lengths.sum())  # the pieces tile the path
    step = 2e-3
    parts = [np.arange(0.0, 1.0, step / length) for length in lengths]
    along = np.concatenate(parts)[:, None]
    owner = np.concatenate([np.full(len(part), k) for k, part in enumerate(parts)])
    samples = starts[owner] + along * (ends[owner] - starts[owner])
    failing = np.flatnonzero(_min_margins(problem, samples) < -problem.margin_atol)
    position = np.concatenate([[0.0], np.cumsum(lengths)])[owner] + along[:, 0] * lengths[owner]
    before = np.concatenate([[0.0], np.cumsum(lengths)])[segment] + pieces[:, 1] * lengths[segment]
    open_ = before[verdict != INSIDE]
    if len(failing):
        assert position[failing[0]] >= open_.min() - 1e-9
        if (verdict == OUTSIDE).any():
            assert position[failing[0]] <= before[verdict == OUTSIDE].min() + step
    else:
        assert not (verdict == OUTSIDE).any()


def test_a_certified_path_job_writes_its_pieces_and_the_shares(tmp_path):
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *IPANEMA, "tension=feasible", "analysis=certified", "certified.depth=12",
                   "certified.path=[[-1,-0.5,0.5],[1,0.5,1.5],[0.5,-1,1],[1.9,1.4,1.9]]", f"hydra.run.dir={run}")
    assert done.returncode == 0, done.stderr[-2000:]
    pieces = pd.read_parquet(run / "segments.parquet")
    summary = pd.read_parquet(run / "summary.parquet").iloc[0]
    assert list(pieces.segment.unique()) == [1, 2, 3]
    assert np.isclose(pieces.length_m.sum(), summary.path_m) and np.isclose(summary.path_m, 7.028419, atol=1e-6)
    assert np.isclose(summary.inside_m + summary.outside_m + summary.undecided_m, summary.path_m)
    assert not summary.path_certified and summary.outside_m > 0.5  # the last segment runs into the frame's corner
    assert np.isclose(summary.first_outside_m, pieces.from_m[pieces.verdict == "outside"].min())
    assert (pieces.verdict[pieces.segment < 3] == "inside").all()  # the first two segments: every point proven
    assert np.allclose(pieces.from_m.to_numpy()[1:], (pieces.from_m + pieces.length_m).to_numpy()[:-1])  # in order
    assert "certified path:" in done.stdout


def test_a_path_off_a_planar_robots_plane_is_refused(tmp_path):
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *PLANAR_POINT, "tension=feasible", "analysis=certified",
                   "certified.path=[[0,0.5,0],[0.5,1,0.2]]", f"hydra.run.dir={run}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "way-point 2 leaves the robot's plane z = 0" in lines[0], lines
    assert not run.exists()


def test_a_robust_path_proves_no_more_than_the_nominal_one(make_cfg):
    """Anchors within +-10 mm: every piece proven inside holds for the robot as designed too, so the
    robust path's proven length is at most the nominal one's, and the nominal robot's exact test
    holds at points sampled on the robust inside pieces."""
    overrides, points, depth = PATHS["ipanema"]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    compute = make_cfg(*overrides, "compute.n_jobs=1").compute
    points = np.asarray(points, dtype=float)
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)

    def inside_length(tolerances):
        pieces, verdict, _, _, _ = paving.certify_path(problem, points, depth, 600.0, compute, tolerances)
        rows = verdict == INSIDE
        return ((pieces[rows, 2] - pieces[rows, 1]) * lengths[pieces[rows, 0].astype(int)]).sum(), pieces[rows]

    nominal, _ = inside_length(paving.Tolerances())
    robust, pieces = inside_length(paving.Tolerances(anchors=0.01))
    assert 0 < robust <= nominal + 1e-12
    rng = np.random.default_rng(11)
    t = rng.uniform(pieces[:, 1], pieces[:, 2])
    segment = pieces[:, 0].astype(int)
    samples = points[segment] + t[:, None] * (points[segment + 1] - points[segment])
    assert (_min_margins(problem, samples) >= -problem.margin_atol).all()


# -- certified paths of a moving platform: every instant of a rest-to-rest motion proven --------

def _quintic(s):
    """The rest-to-rest law written here from its definition: the share covered and its second
    derivative in s (h(0) = 0, h(1) = 1, h' = h'' = 0 at both ends)."""
    return 10 * s**3 - 15 * s**4 + 6 * s**5, 60 * s - 180 * s**2 + 120 * s**3


MOVING = {  # name -> (overrides, way-points, seconds per segment, depth)
    "crane, dropped faster than g": (CRANE, [[0, 0, 2], [0, 0, 1], [0.5, 0.3, 1.5]], 0.5, 13),
    "tilted payload": (ROBOTS["tilted payload"][0], [[-0.6, -0.4, 0.6], [0.6, 0.4, 1.3]], 0.4, 12),
}


@pytest.mark.parametrize("name", sorted(MOVING))
def test_a_moving_path_agrees_with_the_exact_test_at_each_instant(make_cfg, name):
    """At instants drawn in each piece proven inside (outside), the pose and the acceleration of the
    law written in this test hold (fail) by the exact per-pose test of the statics with that
    acceleration (``platform_motion``), a problem built apart from the paving."""
    overrides, points, seconds, depth = MOVING[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    points = np.asarray(points, dtype=float)
    durations = np.full(len(points) - 1, seconds)
    pieces, verdict, _, _, _ = paving.certify_path(problem, points, depth, 600.0,
                                                make_cfg(*overrides, "compute.n_jobs=1").compute,
                                                motion=StraightMotion.quintic(points, durations))
    assert (verdict == INSIDE).any() and (verdict == OUTSIDE).any()
    rng = np.random.default_rng(9)
    for kind in (INSIDE, OUTSIDE):
        for row in rng.choice(np.flatnonzero(verdict == kind), 25):
            k = int(pieces[row, 0])
            s = rng.uniform(pieces[row, 1], pieces[row, 2])
            share, curvature = _quintic(s)
            delta = points[k + 1] - points[k]
            acceleration = curvature * delta / seconds**2
            moving = build(make_cfg(*overrides, "tension=feasible", "analysis=statics", "compute.n_jobs=1",
                                    f"platform_motion.acceleration=[{[*acceleration.tolist(), 0, 0, 0]}]"), None)
            least = _min_margins(moving, (points[k] + share * delta)[None])[0]
            assert (least >= -problem.margin_atol) if kind == INSIDE else (least < problem.margin_atol), (kind, k, s, least)


def test_a_crane_dropped_faster_than_gravity_fails_where_the_law_says(tmp_path):
    """A 5 kg point under four anchors, pushed by 3 N along x, moved 1 m straight down in 0.5 s:
    its cables (1 to 40 N) hold it while some tensions give sum t_i u_i = m a - m g - f (an LP per
    instant, written here from the law), which the law's growing downward acceleration ends within
    0.03 s. The first piece proven infeasible starts there (within a piece), every piece before it
    holds; slowly (5 s a segment) the whole path is proven."""
    from scipy.optimize import linprog

    run = tmp_path / "fast"
    base = [*CRANE, "tension=feasible", "analysis=certified", "certified.depth=16",
            "certified.path=[[0,0,2],[0,0,1],[0.5,0.3,1.5]]"]
    done = command(tmp_path, "pipeline", *base, "certified.times=0.5", f"hydra.run.dir={run}")
    assert done.returncode == 0, done.stderr[-2000:]
    summary = pd.read_parquet(run / "summary.parquet").iloc[0]
    pieces = pd.read_parquet(run / "segments.parquet")
    anchors = np.array([[-1, -1, 3], [1, -1, 3], [1, 1, 3], [-1, 1, 3]], dtype=float)

    def holds(t: float) -> bool:
        share, curvature = _quintic(t / 0.5)
        point = np.array([0.0, 0.0, 2.0 - share])
        acceleration = np.array([0.0, 0.0, -curvature / 0.25])
        units = (anchors - point) / np.linalg.norm(anchors - point, axis=1)[:, None]
        needed = 5.0 * acceleration - 5.0 * np.array([0, 0, -9.81]) - np.array([3.0, 0, 0])
        return linprog(np.zeros(4), A_eq=units.T, b_eq=needed, bounds=[(1, 40)] * 4, method="highs").status == 0

    low, high = 0.0, 0.05
    assert holds(low) and not holds(high)
    for _ in range(40):
        middle = (low + high) / 2
        low, high = (middle, high) if holds(middle) else (low, middle)
    assert 0.01 < high < 0.03
    assert summary["first_outside_s"] >= low - 1e-9  # nothing proven infeasible where the law holds
    assert summary["first_outside_s"] == pytest.approx(high, abs=1e-4)
    assert (pieces.loc[pieces.to_s <= low, "verdict"] == "inside").all()
    assert summary["duration_s"] == 1.0 and not summary["path_certified"]
    assert np.isclose(pieces.to_s.max(), 1.0) and np.allclose(pieces.from_s.to_numpy()[1:], pieces.to_s.to_numpy()[:-1])
    assert np.isclose(pieces.length_m.sum(), summary["path_m"])
    slow = tmp_path / "slow"
    assert command(tmp_path, "pipeline", *base, "certified.times=[5, 5]", f"hydra.run.dir={slow}").returncode == 0
    assert pd.read_parquet(slow / "summary.parquet").iloc[0]["path_certified"]



def _trapezoid(distance: float, v_max: float, t_acc: float, t_dec: float, tau: float) -> tuple[float, float, float]:
    """The CPR-8 paper's speed profile written here from its definition (accelerate at v_max / t_acc,
    cruise at v_max, decelerate at v_max / t_dec; the peak speed lowered where the distance is too
    short): the distance covered and the acceleration at time tau, and the whole time."""
    acc, dec = v_max / t_acc, v_max / t_dec
    peak = min(v_max, math.sqrt(2 * distance * acc * dec / (acc + dec)))
    ramp_up, ramp_down = peak / acc, peak / dec
    cruise = (distance - peak * ramp_up / 2 - peak * ramp_down / 2) / peak
    if tau < ramp_up:
        return acc * tau**2 / 2, acc, ramp_up + cruise + ramp_down
    if tau < ramp_up + cruise:
        return peak * ramp_up / 2 + peak * (tau - ramp_up), 0.0, ramp_up + cruise + ramp_down
    late = tau - ramp_up - cruise
    return peak * ramp_up / 2 + peak * cruise + peak * late - dec * late**2 / 2, -dec, ramp_up + cruise + ramp_down


@pytest.mark.parametrize("distance", [1.0, 0.05])  # cruising at v_max; too short for it: the triangle
def test_the_trapezoid_of_a_certified_path_against_its_definition(distance):
    """StraightMotion's trapezoid against the profile written here: the share covered at 2 001
    instants, and each of 1 000 pieces' accelerations (and 50 pieces across a phase's end, where
    both values must be in the range) holding the law's at instants inside it."""
    points = np.array([[0.0, 0.0, 1.0], [distance, 0.0, 1.0]])
    motion = StraightMotion.trapezoid(points, 0.8, 0.2, 0.5)
    total = _trapezoid(distance, 0.8, 0.2, 0.5, 0.0)[2]
    assert motion.durations[0] == pytest.approx(total, rel=1e-14)
    t = np.linspace(0.0, 1.0, 2001)
    segment = np.zeros(len(t), dtype=int)
    written = np.array([_trapezoid(distance, 0.8, 0.2, 0.5, u * total)[0] for u in t]) / distance
    assert np.abs(motion.share(segment, t) - written).max() < 1e-14
    edges = np.linspace(0.0, 1.0, 1001)
    low, high = motion.acceleration_range(segment[:1000], edges[:-1], edges[1:])
    rng = np.random.default_rng(2)
    for k in range(1000):
        for u in rng.uniform(edges[k], edges[k + 1], 4):
            value = _trapezoid(distance, 0.8, 0.2, 0.5, u * total)[1] / distance
            assert low[k] <= value <= high[k], (k, u, value, low[k], high[k])
    ramp = min(0.8, math.sqrt(2 * distance * 4 * 1.6 / 5.6)) / 4  # the end of the first phase (s)
    across = np.full(50, ramp / total) + np.linspace(-1e-3, -1e-9, 50), np.full(50, ramp / total) + np.linspace(1e-9, 1e-3, 50)
    low, high = motion.acceleration_range(np.zeros(50, dtype=int), *across)
    after = 0.0 if distance == 1.0 else -1.6 / distance  # cruising, or already braking in the triangle
    assert (low <= min(4 / distance, after)).all() and (high >= 4 / distance).all()


def test_a_crane_on_the_papers_speed_profile_fails_only_while_it_drops_faster_than_gravity(tmp_path):
    """certified.law=trapezoid: the crane's 5 kg point moved 1 m down at 2 m/s, reaching it in 0.1 s
    (20 m/s^2 down: the cables, which only pull up, cannot hold it) and stopping in 0.5 s, then
    0.768 m up and sideways in the triangular profile. At instants drawn in every piece, the pose
    and acceleration of the law written here hold (fail) by an LP written from the law wherever the
    piece is proven inside (outside); the first 0.1 s are proven infeasible from the start, the
    cruise and the stop proven feasible."""
    from scipy.optimize import linprog

    run = tmp_path / "run"
    points = np.array([[0, 0, 2], [0, 0, 1], [0.5, 0.3, 1.5]], dtype=float)
    done = command(tmp_path, "pipeline", *CRANE, "tension=feasible", "analysis=certified", "certified.depth=12",
                   "certified.path=[[0,0,2],[0,0,1],[0.5,0.3,1.5]]", "certified.law=trapezoid", "certified.v_max=2",
                   "certified.t_acc=0.1", "certified.t_dec=0.5", f"hydra.run.dir={run}")
    assert done.returncode == 0, done.stderr[-2000:]
    summary = pd.read_parquet(run / "summary.parquet").iloc[0]
    pieces = pd.read_parquet(run / "segments.parquet")
    anchors = np.array([[-1, -1, 3], [1, -1, 3], [1, 1, 3], [-1, 1, 3]], dtype=float)
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    totals = [_trapezoid(length, 2, 0.1, 0.5, 0.0)[2] for length in lengths]
    assert summary["duration_s"] == pytest.approx(sum(totals), rel=1e-12)
    assert np.isclose(pieces.to_s.max(), sum(totals)) and np.allclose(pieces.from_s.to_numpy()[1:], pieces.to_s.to_numpy()[:-1])
    assert np.isclose(pieces.length_m.sum(), summary["path_m"])

    def holds(segment: int, tau: float) -> bool:
        covered, acceleration, _ = _trapezoid(lengths[segment], 2, 0.1, 0.5, tau)
        along = (points[segment + 1] - points[segment]) / lengths[segment]
        point = points[segment] + covered * along
        units = (anchors - point) / np.linalg.norm(anchors - point, axis=1)[:, None]
        needed = 5.0 * acceleration * along - 5.0 * np.array([0, 0, -9.81]) - np.array([3.0, 0, 0])
        return linprog(np.zeros(4), A_eq=units.T, b_eq=needed, bounds=[(1, 40)] * 4, method="highs").status == 0

    rng = np.random.default_rng(5)
    checked = {"inside": 0, "outside": 0}
    for row in pieces.itertuples():
        if row.verdict == "undecided":
            continue
        for t in rng.uniform(row.t0, row.t1, 3):
            assert holds(row.segment - 1, t * totals[row.segment - 1]) == (row.verdict == "inside"), (row, t)
            checked[row.verdict] += 1
    assert checked["inside"] > 20 and checked["outside"] > 5
    assert summary["first_outside_s"] == 0.0 and not summary["path_certified"]
    first = pieces[pieces.segment == 1]
    assert (first.loc[first.to_s <= 0.099, "verdict"] == "outside").all()
    assert (first.loc[first.from_s >= 0.101, "verdict"] == "inside").all()


# -- the interference criteria proven on boxes ----------------------------------------------------

ROTATED = ["robot=points", "robot.anchors=[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]",
           "robot.attachments=[[0.1,0.05,0],[0.1,-0.05,0],[-0.1,-0.05,0],[-0.1,0.05,0]]", "robot.dofs=[x,y]",
           "robot.search.lo=[-0.9,-0.9,0]", "robot.search.hi=[0.9,0.9,0]", "tension.t_min=1", "tension.t_max=60",
           "wrench.fy=-5", "robot.cable_diameter=0.02"]  # each cable to the next corner's point: they cross in half the square
FLOORED = [*CRANE, "obstacles=[{name: floor, point: [0, 0, 0.6], normal: [0, 0, 1]}, "
           "{name: slope, point: [1.2, 0, 0], normal: [-0.6, 0, 0.8]}]"]
BODIED = ["robot=points", "robot.anchors=[[0.2,0,3],[1.5,1,3],[1.5,-1,3],[-1.5,0,3]]",
          "robot.attachments=[[0.3,0,-0.05],[0,0,0],[0,0,0],[0,0,0]]", "robot.dofs=[x,y,z]", *CRANE[6:],
          "robot.search.lo=[-1.2,-0.8,0.5]", "robot.search.hi=[0.4,0.8,2.5]",
          "robot.platform.shape={lo: [-0.3, -0.3, -0.1], hi: [0.3, 0.3, 0]}", "orientation.psi=0.2"]
# a crane whose first cable leaves the middle of its platform's side x = 0.3 (the others its top face),
# tilted by 0.2 rad about x: that cable clears the body while its anchor, at x = 0.2, is on the face's
# outer side (x < -0.1), and enters it on the rest of the region where the cables hold the platform
# (the certified statics alone prove 1.00 m^3 inside at depth 13, with the body 0.24 m^3)
PILLARED = [*CRANE, "obstacles=[{name: pillar, lo: [0.3, -0.15, 0], hi: [0.5, 0.15, 2]}]"]
# a pillar in the crane's cell: the positions in it are lost (the attachment point inside), and so
# are those whose cables pass through it (behind it, seen from the anchors at x = +1)
INTERFERENCE = {  # name -> (overrides, depth, tolerances, the criterion that decides part of the box)
    "a pillar": (PILLARED, 13, paving.Tolerances(), "cable_obstacle"),
    "a pillar, anchors within 10 mm": (PILLARED, 13, paving.Tolerances(anchors=0.01), "cable_obstacle"),
    "crossing cables": (ROTATED, 12, paving.Tolerances(), "cable_cable"),
    "crossing cables, anchors within 10 mm": (ROTATED, 12, paving.Tolerances(anchors=0.01), "cable_cable"),
    "a floor and a slope": (FLOORED, 11, paving.Tolerances(), "cable_obstacle"),
    "a tilted platform's body": (BODIED, 13, paving.Tolerances(), "cable_platform"),
    "a tilted platform's body, anchors within 10 mm": (BODIED, 13, paving.Tolerances(anchors=0.01), "cable_platform"),
}


@pytest.mark.parametrize("name", sorted(INTERFERENCE))
def test_interference_proven_on_boxes_agrees_with_the_exact_test(make_cfg, name):
    """3 000 random points of the boxes proven inside hold every criterion by the exact per-pose
    test (within tolerances: of robots drawn at the corners of their box), none of the outside
    boxes' does; the criterion decides boxes both ways; the grid's volume at a fine step lies in
    the bracket."""
    overrides, depth, tolerances, criterion = INTERFERENCE[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=1")
    assert criterion in problem.criteria
    found, _ = paving.pave(problem, depth, 600.0, make_cfg(*overrides, "compute.n_jobs=1").compute, tolerances)
    axes = np.flatnonzero(problem.robot.box_hi > problem.robot.box_lo)
    volumes = found.volumes(axes)
    rng = np.random.default_rng(4)
    for kind in (INSIDE, OUTSIDE):
        rows = np.flatnonzero(found.verdict == kind)
        assert volumes[rows].sum() > 0.02 * volumes.sum(), kind
        pick = rng.choice(rows, 3000, p=volumes[rows] / volumes[rows].sum())
        points = found.lo[pick] + rng.uniform(0, 1, (3000, 3)) * (found.hi[pick] - found.lo[pick])
        if kind == INSIDE and not tolerances.nominal:
            for number in range(6):
                drawn = _problem(make_cfg, _perturbed(overrides, problem.robot, tolerances, rng, corner=True),
                                 "compute.n_jobs=1")
                assert (_min_margins(drawn, points[number::6]) >= -problem.margin_atol).all()
            continue
        margins = evaluate_chunk(problem, points)
        least = np.min([value for key, value in margins.items() if key.startswith("margin_")], axis=0)
        if kind == INSIDE:
            assert (least >= -problem.margin_atol).all(), np.sort(least)[:5]
        else:
            assert (least < problem.margin_atol).all(), np.sort(least)[-5:]
    own = replace_criteria(problem, criterion)
    alone = paving.pave(own, depth, 600.0, make_cfg(*overrides, "compute.n_jobs=1").compute, tolerances)[0]
    assert (alone.verdict == OUTSIDE).any()  # the criterion itself proves boxes outside, not only the statics
    if tolerances.nominal:  # its own margin holds at points of the boxes proven inside with it alone
        sizes = alone.volumes(axes)
        rows = np.flatnonzero(alone.verdict == INSIDE)
        pick = rng.choice(rows, 3000, p=sizes[rows] / sizes[rows].sum())
        points = alone.lo[pick] + rng.uniform(0, 1, (3000, 3)) * (alone.hi[pick] - alone.lo[pick])
        assert (evaluate_chunk(own, points)[f"margin_{criterion}"] >= -problem.margin_atol).all()
    if tolerances.nominal:
        step = (volumes.sum() / 2e5) ** (1 / len(axes))  # about 200 000 points
        axes_points = [np.arange(lo + step / 2, hi, step) if hi > lo else np.array([lo])
                       for lo, hi in zip(problem.robot.box_lo, problem.robot.box_hi)]
        grid = np.stack(np.meshgrid(*axes_points, indexing="ij"), axis=-1).reshape(-1, 3)
        held = (_min_margins(problem, grid) >= -problem.margin_atol).mean() * volumes.sum()
        inside = volumes[found.verdict == INSIDE].sum()
        assert inside <= held <= inside + volumes[found.verdict == UNDECIDED].sum()


def test_a_box_obstacles_bound_agrees_with_the_exact_clearance_on_small_boxes_about_it(make_cfg):
    """The pillar's bound alone (``clearance_bounds.box_verdicts``) on 3 000 small boxes of
    positions in it and within 8 cm of it, each checked at 8 random points by the exact criterion alone (the
    separating-axis gap): no point of an inside box touches the pillar, none of an outside box
    clears it, and both verdicts are common (boxes in the pillar, and beside it with cables that
    pass it on either side)."""
    problem = replace_criteria(_problem(make_cfg, PILLARED), "cable_obstacle")
    statics = paving.box_statics(problem, problem.orientations[0])
    rng = np.random.default_rng(6)
    centre = rng.uniform([0.22, -0.23, 0.0], [0.58, 0.23, 2.08], (3000, 3))  # the pillar and 8 cm about it
    half = rng.uniform(0.002, 0.02, (3000, 1))
    lo, hi = centre - half, centre + half
    found = REGISTRY["cable_obstacle"].boxes(problem.robot, statics, statics, lo, hi, centre, problem.margin_atol)
    points = lo[:, None] + rng.uniform(0, 1, (3000, 8, 3)) * (hi - lo)[:, None]
    margin = evaluate_chunk(problem, points.reshape(-1, 3))["margin_cable_obstacle"].reshape(3000, 8)
    assert (margin[found == INSIDE] >= -problem.margin_atol).all()
    assert (margin[found == OUTSIDE] < problem.margin_atol).all()
    assert (found == INSIDE).mean() > 0.02 and (found == OUTSIDE).mean() > 0.1, np.unique(found, return_counts=True)


def replace_criteria(problem, criterion):
    """The problem checking ``criterion`` and the zero-length gate only: the criterion's own boxes."""
    return replace(problem, criteria=tuple(name for name in problem.criteria if name in (criterion, "zero_length")))

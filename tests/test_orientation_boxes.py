"""Certified boxes over a box of orientations (``certified.orientations=box``, issue 57 item 1):
the rotation's enclosure over a box of angles against 50-digit references, and every pose of a
box proven inside, at every orientation of the box of angles, against the exact per-pose test."""

from __future__ import annotations

from dataclasses import replace

import mpmath
from types import SimpleNamespace

import numpy as np
import pytest

from conftest import CROSSED_ROBOT, SPREAD_ANCHORS
from pipeline.app.problem import build, orientation_cells
from pipeline.model import certificates
from pipeline.model.certificates import INSIDE, OUTSIDE
from pipeline.model.intervals import Interval
from pipeline.model.geometry import eq9_angles
from pipeline.model.intervals import rotation_box_enclosure
from pipeline.workspace import paving
from pipeline.workspace.kernel import evaluate_chunk


def _rotation(angles, convention: str):
    """R at 50 digits from the elementary rotations written out here: eq. (9)'s Rz(phi) Ry(theta)
    Rx(psi) (zyx) or CASPR's Rx(psi) Ry(theta) Rz(phi) (xyz)."""
    a, b, c = angles
    rx = mpmath.matrix([[1, 0, 0], [0, mpmath.cos(a), -mpmath.sin(a)], [0, mpmath.sin(a), mpmath.cos(a)]])
    ry = mpmath.matrix([[mpmath.cos(b), 0, mpmath.sin(b)], [0, 1, 0], [-mpmath.sin(b), 0, mpmath.cos(b)]])
    rz = mpmath.matrix([[mpmath.cos(c), -mpmath.sin(c), 0], [mpmath.sin(c), mpmath.cos(c), 0], [0, 0, 1]])
    return rz * ry * rx if convention == "zyx" else rx * ry * rz


BOXES = {  # name -> (lo, hi): small, across a turning point of sin (pi/2) and of cos (0, pi), wider than a turn
    "small": ([0.1, -0.2, 0.3], [0.11, -0.19, 0.32]),
    "turning": ([1.5, -0.05, 3.1], [1.65, 0.05, 3.2]),
    "wide": ([-3.3, -1.0, 2.0], [3.3, 1.0, 2.5]),
}


@pytest.mark.parametrize("convention", ["zyx", "xyz"])
@pytest.mark.parametrize("name", sorted(BOXES))
def test_the_rotation_box_enclosure_holds_every_rotation_and_its_partials_at_fifty_digits(name, convention):
    """R and dR/dangle at 60 random angles and the 8 corners of the box, at 50 digits (the partials
    by mpmath's numerical differentiation, not by the product rule the code uses), lie in the
    enclosures; the enclosure of a degenerate box is within 1e-14 of the rotation there."""
    lo, hi = np.array(BOXES[name][0]), np.array(BOXES[name][1])
    rotation, partials = rotation_box_enclosure(lo, hi, convention)
    rng = np.random.default_rng(7)
    corners = np.where(np.arange(8)[:, None] >> np.arange(3) & 1, hi, lo)
    with mpmath.workdps(50):
        for angles in np.concatenate([corners, rng.uniform(lo, hi, (60, 3))]):
            point = [mpmath.mpf(float(v)) for v in angles]
            exact = _rotation(point, convention)
            for i in range(3):
                for j in range(3):
                    assert mpmath.mpf(rotation.lo[i, j]) <= exact[i, j] <= mpmath.mpf(rotation.hi[i, j])
                    for axis in range(3):
                        def entry(x, axis=axis, i=i, j=j):
                            moved = list(point)
                            moved[axis] = x
                            return _rotation(moved, convention)[i, j]
                        rate = mpmath.diff(entry, point[axis])
                        assert mpmath.mpf(partials.lo[axis, i, j]) - mpmath.mpf(10) ** -30 <= rate
                        assert rate <= mpmath.mpf(partials.hi[axis, i, j]) + mpmath.mpf(10) ** -30
    at = rotation_box_enclosure(lo, lo, convention)[0]
    with mpmath.workdps(50):
        exact = np.array(_rotation([mpmath.mpf(float(v)) for v in lo], convention).tolist(), dtype=float)
    assert np.abs(at.hi - at.lo).max() < 1e-14 and (at.lo <= exact).all() and (exact <= at.hi).all()


def _turned(angles: np.ndarray, convention: str) -> np.ndarray:
    """(..., 3, 3) R at angles (..., 3), the elementary rotations written out here (numpy)."""
    a, b, c = np.moveaxis(np.asarray(angles, dtype=float), -1, 0)
    one, zero = np.ones_like(a), np.zeros_like(a)
    rx = np.stack([np.stack([one, zero, zero], -1), np.stack([zero, np.cos(a), -np.sin(a)], -1),
                   np.stack([zero, np.sin(a), np.cos(a)], -1)], -2)
    ry = np.stack([np.stack([np.cos(b), zero, np.sin(b)], -1), np.stack([zero, one, zero], -1),
                   np.stack([-np.sin(b), zero, np.cos(b)], -1)], -2)
    rz = np.stack([np.stack([np.cos(c), -np.sin(c), zero], -1), np.stack([np.sin(c), np.cos(c), zero], -1),
                   np.stack([zero, zero, one], -1)], -2)
    return rz @ ry @ rx if convention == "zyx" else rx @ ry @ rz


def _angles_case(make_cfg, convention, bound, sizes, rates):
    """A tilted robot with 30 kg at c = [0.2, -0.1, 0.3] m, its box of orientations (+-``bound``
    rad about (0.1, -0.08, 0.25)) and 100 boxes of positions (sides drawn in ``sizes``), with the
    certificates' data over them: t0, the rates D and E (``first order``: through the
    pseudo-inverse, dA/dp and dA/dtheta by central differences; ``random``; or ``none``), and A and w
    written from the law (u from each anchor to p + R(theta) b_i, columns [u; R(theta) b_i x u]; w
    the weight and its moment about the reference point, (R(theta) c) x m g)."""
    overrides = [o for o in TURNING["tilted payload"][0] if not o.startswith(("orientation.", "load."))]
    cfg, problem = _problem(make_cfg, [*overrides, "load.mass=30", "load.com=[0.2,-0.1,0.3]", "orientation.psi=0.1",
                                       "orientation.theta=-0.08", "orientation.phi=0.25",
                                       f"orientation.convention={convention}", f"orientation.total={{bound: {bound}, n: 1}}"])
    (low, high, middle_angles, _), = orientation_cells(cfg.orientation)
    robot, angles, m = problem.robot, problem.orientations[0], problem.robot.n_cables
    rng = np.random.default_rng(9)
    lo = rng.uniform([-1.4, -0.9, 0.3], [1.2, 0.7, 1.4], (100, 3))
    hi = lo + rng.uniform(*sizes, (100, 3))
    middle = lo + (hi - lo) / 2

    def structure_at(points, turned):  # (..., 3), (..., 3) angles -> (..., 6, m)
        arms = np.einsum("...ij,mj->...mi", _turned(turned, convention), robot.attachments)
        vectors = points[..., None, :] + arms - robot.anchors
        unit = vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)
        return np.swapaxes(np.concatenate([unit, np.cross(arms, unit)], axis=-1), -1, -2)

    def wrench_at(turned):  # (..., 3) angles -> (..., 6)
        weight = -30.0 * 9.81 * np.asarray(robot.up, dtype=float)
        arm = np.einsum("...ij,j->...i", _turned(turned, convention), [0.2, -0.1, 0.3])
        return np.concatenate([np.broadcast_to(weight, arm.shape), np.cross(arm, weight)], axis=-1)

    centre_angles = np.broadcast_to(middle_angles, (100, 3))
    at_centre = structure_at(middle, centre_angles)
    assert np.allclose(at_centre, problem.spec.state(robot, middle, tuple(angles)).structure, atol=1e-13)
    assert np.allclose(wrench_at(middle_angles), problem.spec.state(robot, middle[:1], tuple(angles)).required_wrenches[0])
    tensions = rng.uniform(1.0, 150.0, (100, 1, m))
    if rates == "random":
        moving, following = rng.normal(size=(100, 1, m, 3)) * 100, rng.normal(size=(100, 1, m, 3)) * 100
    elif rates == "none":  # t = t0 throughout: dg_j/dp_l is the mixed term (d2A/dtheta_j dp_l) t0 alone
        moving, following = np.zeros((100, 1, m, 3)), np.zeros((100, 1, m, 3))
    else:
        h = 1e-6
        inverse = np.linalg.pinv(at_centre)
        slopes = np.stack([(structure_at(middle + h * e, centre_angles) - structure_at(middle - h * e, centre_angles))
                           / (2 * h) for e in np.eye(3)], axis=1)  # (100, 3, 6, m)
        turning = np.stack([(structure_at(middle, centre_angles + h * e) - structure_at(middle, centre_angles - h * e))
                            / (2 * h) for e in np.eye(3)], axis=1)
        moving = -np.einsum("nmk,nlkj,nKj->nKml", inverse, slopes, tensions)
        following = -np.einsum("nmk,nPkj,nKj->nKmP", inverse, turning, tensions)
    turn = (low, high, middle_angles, convention)
    at = (middle_angles, middle_angles, middle_angles, convention)
    nominal = certificates.structure_enclosure(paving.box_statics(problem, angles, turn=at), lo, hi, middle)
    statics = paving.box_statics(problem, angles, turn=turn)
    within = certificates.structure_enclosure(statics, lo, hi, middle)
    moves, arms, given = paving.build_errors(problem, angles, paving.NOMINAL, turn)
    assert np.allclose(given, bound) and (given >= high - middle_angles).all() and (given >= middle_angles - low).all()
    errors = certificates.BuildErrors(nominal, certificates.structure_enclosure(statics, middle, middle, middle),
                                      following, moves, arms, given)
    points = lo[:, None] + rng.uniform(0, 1, (100, 1000, 3)) * (hi - lo)[:, None]
    drawn = np.where(rng.uniform(size=(100, 1000, 1)) < 0.3, np.where(rng.uniform(size=(100, 1000, 3)) < 0.5, low, high),
                     rng.uniform(low, high, (100, 1000, 3)))
    return SimpleNamespace(**locals())


@pytest.mark.parametrize("rates", ["first order", "random"])
@pytest.mark.parametrize("convention, bound, sizes", [("zyx", 0.05, (0.005, 0.05)), ("xyz", 0.05, (0.005, 0.05)),
                                                     ("zyx", 0.005, (0.1, 0.3))])
def test_the_followed_residual_holds_the_residual_at_every_orientation_of_the_box(make_cfg, convention, bound, sizes, rates):
    """certificates.followed over a box of orientations (+-0.05 rad about a tilted one) against
    t = t0 + D s + E delta and r = A(p, theta) t - w(theta) from the law (:func:`_angles_case`) at
    10^5 poses: a random point of one of 100 boxes of positions at a random orientation of the box
    (a third at its corners). With the first-order rates and with random ones (r then of first
    order in the angles: the errors' term must hold it)."""
    case = _angles_case(make_cfg, convention, bound, sizes, rates)
    statics, points, drawn, middle = case.statics, case.points, case.drawn, case.middle
    wrenches = Interval(np.broadcast_to(statics.wrenches.lo, (100, 1, 6)), np.broadcast_to(statics.wrenches.hi, (100, 1, 6)))
    moved, residual = certificates.followed(statics, case.within, wrenches, case.tensions, case.moving, case.errors)
    t = (case.tensions[:, None, 0] + np.einsum("nml,npl->npm", case.moving[:, 0], points - middle[:, None])
         + np.einsum("nmP,npP->npm", case.following[:, 0], drawn - case.middle_angles))
    exact = np.einsum("npkm,npm->npk", case.structure_at(points, drawn), t) - case.wrench_at(drawn)
    assert (moved.lo[:, 0, None] <= t).all() and (t <= moved.hi[:, 0, None]).all()
    assert (residual.lo[:, 0, None] <= exact).all() and (exact <= residual.hi[:, 0, None]).all()
    # the angles' part alone, A(p, theta) t(p, theta) - A(p, theta_c) t(p, theta_c), against its own enclosure
    reach = (np.abs(case.following) * case.given).sum(axis=-1)
    part = certificates.errors_residual(statics, case.within, case.errors, moved,
                                        Interval(case.tensions - reach, case.tensions + reach), case.moving)
    level = t - np.einsum("nmP,npP->npm", case.following[:, 0], drawn - case.middle_angles)
    exact = (np.einsum("npkm,npm->npk", case.structure_at(points, drawn), t)
             - np.einsum("npkm,npm->npk", case.structure_at(points, np.broadcast_to(case.middle_angles, drawn.shape)), level))
    assert (part.lo[:, 0, None] <= exact).all() and (exact <= part.hi[:, 0, None]).all()


@pytest.mark.parametrize("rates", ["first order", "random", "none"])
@pytest.mark.parametrize("bound, sizes", [(0.05, (0.005, 0.05)), (0.005, (0.1, 0.3)), (0.001, (0.3, 0.6))])
def test_each_enclosure_of_the_angles_gradient_holds_it_by_central_differences(make_cfg, bound, sizes, rates):
    """Each of the two enclosures of g_j = dr/dtheta_j (certificates.error_gradients) on its own,
    not only their intersection: its range over the box and its centred form must each hold g_j at
    every drawn point and orientation, g_j by central differences (h = 1e-6 rad) of
    r = A(p, theta) t(p, theta) from the law, t = t0 + D s + E (theta - theta_c). Wide boxes of
    positions with narrow boxes of angles make the centred form's terms of the first order in the
    box its width: the mixed term (d2A/dtheta_j dp_l) t, (dA/dtheta_j) D_l and (dA/dp_l) E_j each
    carry a share of it (with D = E = 0 the mixed term all of it)."""
    case = _angles_case(make_cfg, "zyx", bound, sizes, rates)
    statics, points, drawn, middle = case.statics, case.points[:, :200], case.drawn[:, :200], case.middle
    moved, _ = certificates.followed(statics, case.within, Interval.point(np.zeros((100, 1, 6))), case.tensions,
                                     case.moving, case.errors)
    reach = (np.abs(case.following) * case.given).sum(axis=-1)
    still = Interval(case.tensions - reach, case.tensions + reach)
    forms = list(certificates.error_gradients(statics, case.within, case.errors, moved, still, case.moving))
    assert len(forms) == 3 and [tolerance for tolerance, _, _ in forms] == pytest.approx([bound] * 3)

    def residual(turned):
        t = (case.tensions[:, None, 0] + np.einsum("nml,npl->npm", case.moving[:, 0], points - middle[:, None])
             + np.einsum("nmP,npP->npm", case.following[:, 0], turned - case.middle_angles))
        return np.einsum("npkm,npm->npk", case.structure_at(points, turned), t)

    h = 1e-6
    for j, (_, ranged, centred) in enumerate(forms):
        step = h * np.eye(3)[j]
        gradient = (residual(drawn + step) - residual(drawn - step)) / (2 * h)  # (100, points, 6)
        slack = 1e-6 * (1 + np.abs(gradient))  # the central difference's own error
        for form in (ranged, centred):
            assert (form.lo[:, 0, None] - slack <= gradient).all() and (gradient <= form.hi[:, 0, None] + slack).all()


IPANEMA_QUARTER = ["robot=points", f"robot.anchors={SPREAD_ANCHORS}",
                   "robot.attachments=[[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0],"
                   "[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0]]",
                   "robot.search.lo=[0,0,0]", "robot.search.hi=[2,1.5,2]", "tension.t_min=1", "tension.t_max=10"]
TURNING = {  # name -> (overrides, depth): each with a box of orientations
    # an off-centre payload on a tilted platform, its weight's moment turning with it; CASPR's angles
    "tilted payload": ([*CROSSED_ROBOT, "tension.t_min=0", "tension.t_max=150", "load.mass=3",
                        "load.com=[0.04,-0.03,0.02]", "orientation.psi=0.1", "orientation.theta=-0.08",
                        "orientation.phi=0.25", "orientation.convention=xyz", "robot.l_max=3.2",
                        "orientation.total={bound: 0.01, n: 1}"], 13),
    "ipanema": ([*IPANEMA_QUARTER, "orientation.total={bound: 0.01, n: 1}"], 12),
    "planar body in two per angle": (["robot=points", "robot.anchors=[[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]]",
                     "robot.attachments=[[-0.1,0.05,0],[0.1,0.05,0],[0.1,-0.05,0],[-0.1,-0.05,0]]",
                     "robot.dofs=[x,y,rz]", "robot.search.lo=[-0.9,-0.9,0]", "robot.search.hi=[0.9,0.9,0]",
                     "tension.t_min=2", "tension.t_max=60", "orientation.phi=0.3",
                     "orientation.total={bound: 0.15, n: 2}", "robust.anchors=0.005"], 11),
}


def _problem(make_cfg, overrides):
    cfg = make_cfg(*overrides, "tension=feasible", "analysis=certified", "certified.orientations=box", "compute.n_jobs=1")
    return cfg, build(cfg, None)


def _paved(make_cfg, name):
    overrides, depth = TURNING[name]
    cfg, problem = _problem(make_cfg, overrides)
    tolerances = paving.Tolerances(**{key: float(value) for key, value in cfg.robust.items()})
    found, _ = paving.pave(problem, depth, 600.0, cfg.compute, tolerances, orientation_cells(cfg.orientation))
    return cfg, problem, found


def _margins(problem, positions, angles) -> np.ndarray:
    """The exact per-pose test at one orientation (eq. 9's angles): the least margin (>= 0: feasible)."""
    margins = evaluate_chunk(replace(problem, orientations=np.asarray(angles, dtype=float)[None]), positions)
    return np.min([value for key, value in margins.items() if key.startswith("margin_")], axis=0)


@pytest.mark.parametrize("name", sorted(TURNING))
def test_no_pose_at_any_orientation_of_its_box_contradicts_the_exact_test(make_cfg, name):
    """Inside: 40 orientations drawn in the boxes of angles (a third at their corners), each at 100
    positions drawn in the inside boxes, all feasible by the exact test at that orientation (the
    planar body's anchors at the corners of their +-5 mm box). Outside: 4 000 positions of the
    outside boxes, each infeasible at one of the boxes' centres (the orientation its proof used)."""
    cfg, problem, found = _paved(make_cfg, name)
    cells = orientation_cells(cfg.orientation)
    convention = cells[0][3]
    rng = np.random.default_rng(11)
    axes = np.flatnonzero(problem.robot.box_hi > problem.robot.box_lo)
    volumes = found.volumes(axes)

    def drawn(verdict, count):
        rows = np.flatnonzero(found.verdict == verdict)
        assert len(rows), verdict
        pick = rng.choice(rows, count, p=volumes[rows] / volumes[rows].sum())
        return found.lo[pick] + rng.uniform(0, 1, (count, 3)) * (found.hi[pick] - found.lo[pick])

    inside = []
    robots = [problem]
    if cfg.robust.anchors:
        robots = [replace(problem, robot=replace(problem.robot, anchors=problem.robot.anchors
                                                 + rng.choice([-1.0, 1.0], problem.robot.anchors.shape) * cfg.robust.anchors))
                  for _ in range(4)]
    for draw in range(40):
        lo, hi, _, _ = cells[rng.integers(len(cells))]
        angles = np.where(rng.uniform(size=3) < 0.5, lo, hi) if draw % 3 == 0 else rng.uniform(lo, hi)
        eq9 = eq9_angles(*angles) if convention == "xyz" else angles
        inside.append(_margins(robots[draw % len(robots)], drawn(INSIDE, 100), eq9))
    inside = np.concatenate(inside)
    assert (inside >= -problem.margin_atol).all(), np.sort(inside)[:5]
    outside = drawn(OUTSIDE, 4000)
    least = np.min([_margins(problem, outside, angles) for angles in problem.orientations], axis=0)
    assert (least < problem.margin_atol).all(), np.sort(least)[-5:]


def test_a_vanishing_box_of_orientations_gives_the_constant_orientation_paving(make_cfg):
    overrides, depth = TURNING["tilted payload"]
    constant = [o for o in overrides if not o.startswith("orientation.total")]
    cfg, problem = _problem(make_cfg, [*constant, "orientation.total={bound: 1e-12, n: 1}"])
    tiny, _ = paving.pave(problem, depth, 600.0, cfg.compute, turns=orientation_cells(cfg.orientation))
    cfg = make_cfg(*constant, "tension=feasible", "analysis=certified", "compute.n_jobs=1")
    nominal, _ = paving.pave(build(cfg, None), depth, 600.0, cfg.compute)
    assert np.array_equal(nominal.verdict, tiny.verdict) and np.array_equal(nominal.lo, tiny.lo)
    assert (nominal.verdict == INSIDE).sum() > 50


def test_a_wider_box_of_orientations_proves_less_and_cutting_it_proves_more(make_cfg):
    """Every orientation of a wider box must hold: the proven area of the planar body shrinks as
    the bound grows (2.49 m^2 at +-0.05 rad, 1.48 at +-0.15 of 2.67 at its one orientation, depth
    11); cut into 2 x 2 x 2 boxes, each followed about its own centre, +-0.15 rad proves 2.16."""
    overrides = [o for o in TURNING["planar body in two per angle"][0] if not o.startswith(("orientation.total", "robust"))]
    areas = {}
    for total in ("{bound: 0.05, n: 1}", "{bound: 0.15, n: 1}", "{bound: 0.15, n: 2}"):
        cfg, problem = _problem(make_cfg, [*overrides, f"orientation.total={total}"])
        found, _ = paving.pave(problem, 11, 600.0, cfg.compute, turns=orientation_cells(cfg.orientation))
        areas[total] = found.volumes(np.arange(2))[found.verdict == INSIDE].sum()
    assert areas["{bound: 0.05, n: 1}"] > 1.5 * areas["{bound: 0.15, n: 1}"] > 0
    assert areas["{bound: 0.15, n: 2}"] > 1.3 * areas["{bound: 0.15, n: 1}"]


def test_the_boxes_of_orientations_tile_the_whole_box_without_gaps(make_cfg):
    cfg, problem = _problem(make_cfg, [*IPANEMA_QUARTER, "orientation.psi=0.1", "orientation.total={bound: 0.3, n: 3}"])
    cells = orientation_cells(cfg.orientation)
    assert len(cells) == 27 == len(problem.orientations)
    assert np.allclose(cells[0][2], [0.1, 0.0, 0.0], atol=1e-15)  # the nominal orientation's box first
    for axis, (low, high) in enumerate(((0.1 - 0.3, 0.1 + 0.3), (-0.3, 0.3), (-0.3, 0.3))):
        edges = sorted({(float(lo[axis]), float(hi[axis])) for lo, hi, _, _ in cells})
        assert edges[0][0] <= low and edges[-1][1] >= high
        assert all(edges[k][1] == edges[k + 1][0] for k in range(len(edges) - 1))  # shared doubles: no gap
        assert all(lo[axis] <= centre[axis] <= hi[axis] for lo, hi, centre, _ in cells)
    assert np.allclose(problem.orientations, [cell[2] for cell in cells])

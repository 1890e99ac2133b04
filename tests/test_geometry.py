import numpy as np
import pytest

from pipeline.model.dynamics import Load, MotionSpec, PoseDynamics
from pipeline.model.geometry import cable_vectors, rotation_matrix, rotation_partials
from pipeline.model.robots import cpr8

ROBOT = cpr8(3.2, 2.2, 2.2, 0.224, 0.154, 0.140)
RNG = np.random.default_rng(7)


def _dyn(positions, orientation, radius=0.08):
    motion = MotionSpec(np.zeros((1, 3)), np.zeros((1, 3)), Load(2.0, 9.81), np.full(8, radius),
                        pinv_columns="full")
    return PoseDynamics(ROBOT, positions, orientation, motion)


def test_rotation_matches_eq9_element_by_element():
    psi, th, ph = 0.3, -0.4, 1.1
    c, s = np.cos, np.sin
    eq9 = np.array([
        [c(ph) * c(th), c(ph) * s(th) * s(psi) - s(ph) * c(psi), c(ph) * s(th) * c(psi) + s(ph) * s(psi)],
        [s(ph) * c(th), s(ph) * s(th) * s(psi) + c(ph) * c(psi), s(ph) * s(th) * c(psi) - c(ph) * s(psi)],
        [-s(th), c(th) * s(psi), c(th) * c(psi)],
    ])
    r = rotation_matrix(psi, th, ph)
    np.testing.assert_allclose(r, eq9, atol=1e-15)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-15)


def test_rotation_partials_match_finite_differences():
    angles = np.array([0.5, 0.5, 0.5])
    h = 1e-6
    for q in range(3):
        up, dn = angles.copy(), angles.copy()
        up[q] += h
        dn[q] -= h
        fd = (rotation_matrix(*up) - rotation_matrix(*dn)) / (2 * h)
        np.testing.assert_allclose(rotation_partials(*angles)[q], fd, atol=1e-9)


def test_lengths_are_eqs_10_to_17_at_zero_orientation():
    p = np.array([[1.0, 0.7, -1.2]])
    l, w, h = 0.224, 0.154, 0.140
    x, y, z = p[0]
    k = np.sqrt((x - l / 2) ** 2 + (y - w / 2) ** 2 + (z + h / 2) ** 2)  # eq. (10), vertex A
    n_prime = np.sqrt((x - l / 2) ** 2 + (2.2 - y - w / 2) ** 2 + (h + z - h / 2) ** 2)  # (17), D'
    lengths = _dyn(p, (0, 0, 0)).lengths[0]
    assert lengths[0] == pytest.approx(k, rel=1e-14)
    assert lengths[7] == pytest.approx(n_prime, rel=1e-14)


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.5, 0.5, 0.5), (-0.3, 0.2, 1.0)])
def test_analytic_jacobian_matches_finite_differences(orientation):
    positions = ROBOT.box_lo + RNG.random((20, 3)) * (ROBOT.box_hi - ROBOT.box_lo)
    jac = _dyn(positions, orientation).jacobian
    h = 1e-6
    for j in range(6):
        up = [positions.copy(), list(orientation)]
        dn = [positions.copy(), list(orientation)]
        if j < 3:
            up[0][:, j] += h
            dn[0][:, j] -= h
        else:
            up[1][j - 3] += h
            dn[1][j - 3] -= h
        l_up = np.linalg.norm(cable_vectors(ROBOT, up[0], rotation_matrix(*up[1])), axis=2)
        l_dn = np.linalg.norm(cable_vectors(ROBOT, dn[0], rotation_matrix(*dn[1])), axis=2)
        fd = (l_up - l_dn) / (2 * h) / 0.08
        np.testing.assert_allclose(jac[:, :, j], fd, atol=1e-7)


def test_cpr8_jacobian_is_rank_5_at_zero_orientation_and_6_when_rotated():
    """docs/model.md section 1: J loses one rank wherever the carrier is level (psi = theta = 0),
    at every yaw; tilted it has full rank."""
    positions = ROBOT.box_lo + RNG.random((50, 3)) * (ROBOT.box_hi - ROBOT.box_lo)
    sigma0 = np.linalg.svd(_dyn(positions, (0, 0, 0)).jacobian, compute_uv=False)
    sigma1 = np.linalg.svd(_dyn(positions, (0.5, 0.5, 0.5)).jacobian, compute_uv=False)
    assert (sigma0[:, 5] / sigma0[:, 0]).max() < 1e-12
    assert (sigma1[:, 5] / sigma1[:, 0]).min() > 1e-4
    assert (_dyn(positions, (0, 0, 0)).jacobian_rank == 5).all()
    assert (_dyn(positions, (0.5, 0.5, 0.5)).jacobian_rank == 6).all()


def vertical_screw(robot, position, phi):
    """docs/model.md section 1: with psi = theta = 0 every lower cable is its upper partner moved
    down by h_o, so a rotation about a vertical axis through Q with a vertical speed keeps both
    of a pair at constant length when it keeps the upper one. For the four upper cables
    (anchors a_i at z = 0, attachments p_i) that asks cross(p_i - Q, p_i - a_i) = c for all
    four, a linear system in (Q_x, Q_y, c). Returns p-dot (unit yaw rate) and the system's
    residual; the residual is zero when the four equations are dependent."""
    rot = rotation_matrix(0.0, 0.0, phi)
    upper = robot.anchors[:, 2] == 0.0
    points = (position + robot.attachments[upper] @ rot.T)[:, :2]
    arms = points - robot.anchors[upper, :2]

    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    # cross(p - Q, arm) = cross(p, arm) - cross(Q, arm) = c  ->  Q_x arm_y - Q_y arm_x + c = cross(p, arm)
    system = np.column_stack([arms[:, 1], -arms[:, 0], np.ones(4)])
    (qx, qy, c), residual, *_ = np.linalg.lstsq(system, cross(points, arms), rcond=None)
    drop = position[2] + robot.attachments[upper, 2][0]  # (p_i - a_i)_z, the same for all four
    velocity = np.array([-(position[1] - qy), position[0] - qx, -c / drop])
    return np.concatenate([velocity, [0.0, 0.0, 1.0]]), float(np.sum(residual))


@pytest.mark.parametrize("phi", [0.0, 0.5, 1.2, -2.0])
def test_a_level_carrier_has_a_vertical_screw_in_the_null_space_at_every_yaw(phi):
    """The carrier's top face has the frame's aspect ratio (l s = d w: 0.224 x 2.2 = 0.154 x 3.2),
    which makes the four upper equations dependent at every yaw (their alternating sum is
    2 cos(phi) (s l / 2 - d w / 2) = 0), so the screw exists and J has rank 5."""
    positions = ROBOT.box_lo + RNG.random((30, 3)) * (ROBOT.box_hi - ROBOT.box_lo)
    jac = _dyn(positions, (0.0, 0.0, phi)).jacobian
    for position, rows in zip(positions, jac):
        twist, residual = vertical_screw(ROBOT, position, phi)
        assert residual < 1e-20
        assert np.abs(rows @ twist).max() < 1e-12 * np.abs(rows).max() * np.abs(twist).max()
    sigma = np.linalg.svd(jac, compute_uv=False)
    assert (sigma[:, 5] / sigma[:, 0]).max() < 1e-12
    assert (_dyn(positions, (0.0, 0.0, phi)).jacobian_rank == 5).all()


def test_another_aspect_ratio_has_full_rank_except_at_a_quarter_turn():
    """A carrier 20 % longer (l s != d w): the alternating sum 2 cos(phi) (s l / 2 - d w / 2)
    vanishes only at phi = +-90 deg, so level J has full rank at phi = 0 and 0.5 rad (the screw's
    equations are inconsistent) and rank 5 at a quarter turn."""
    longer = cpr8(3.2, 2.2, 2.2, 0.224 * 1.2, 0.154, 0.140)
    positions = longer.box_lo + RNG.random((30, 3)) * (longer.box_hi - longer.box_lo)
    motion = MotionSpec(np.zeros((1, 3)), np.zeros((1, 3)), Load(2.0, 9.81), np.full(8, 0.08))
    for phi, rank in ((0.0, 6), (0.5, 6), (np.pi / 2, 5)):
        dyn = PoseDynamics(longer, positions, (0.0, 0.0, phi), motion)
        sigma = np.linalg.svd(dyn.jacobian, compute_uv=False)
        ratio = sigma[:, 5] / sigma[:, 0]
        residual = vertical_screw(longer, positions[0], phi)[1]
        if rank == 5:
            assert (ratio < 1e-12).all() and residual < 1e-20
        else:
            assert (ratio > 1e-6).all() and residual > 1e-8
        assert (dyn.jacobian_rank == rank).all()

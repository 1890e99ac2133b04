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
    """Carrier top face is a 0.07 scale copy of the frame top: the four upper cables meet in one
    point, the four lower ones in the point h_o below it, so J loses rank (issue 2)."""
    positions = ROBOT.box_lo + RNG.random((50, 3)) * (ROBOT.box_hi - ROBOT.box_lo)
    sigma0 = np.linalg.svd(_dyn(positions, (0, 0, 0)).jacobian, compute_uv=False)
    sigma1 = np.linalg.svd(_dyn(positions, (0.5, 0.5, 0.5)).jacobian, compute_uv=False)
    assert (sigma0[:, 5] / sigma0[:, 0]).max() < 1e-12
    assert (sigma1[:, 5] / sigma1[:, 0]).min() > 1e-4
    assert (_dyn(positions, (0, 0, 0)).jacobian_rank == 5).all()
    assert (_dyn(positions, (0.5, 0.5, 0.5)).jacobian_rank == 6).all()

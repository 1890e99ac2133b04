"""``orientation.convention``: CASPR's XYZ Euler angles (R = Rx(a) Ry(b) Rz(c)) name the same
pose as eq. (9)'s angles of that rotation (R = Rz(phi) Ry(theta) Rx(psi)); the points table
reports the angles as given. Rotations written out here, not taken from the model."""

import numpy as np
import pytest

from pipeline.app.problem import build_problem
from conftest import compute_workspace


def rx(a):
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def ry(a):
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def rz(a):
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


@pytest.mark.parametrize("angles", [(0.3, -0.2, 0.5), (1.2, 0.4, -2.0), (0.1, np.pi / 2, 0.3), (0.0, 0.0, 0.7)])
def test_xyz_angles_give_the_rotation_caspr_gives_them(make_cfg, catalogue, angles):
    a, b, c = angles
    cfg = make_cfg("robot=irpm6", "orientation.convention=xyz", f"orientation.psi={a!r}",
                   f"orientation.theta={b!r}", f"orientation.phi={c!r}")
    problem, _ = build_problem(cfg, catalogue)
    psi, theta, phi = problem.orientations[0]
    np.testing.assert_allclose(rz(phi) @ ry(theta) @ rx(psi), rx(a) @ ry(b) @ rz(c), atol=1e-12)
    assert problem.nominal == (a, b, c)


def test_a_job_in_xyz_angles_is_the_job_in_the_same_rotations_eq9_angles(make_cfg, catalogue):
    """Same verdicts and margins pose by pose; the table keeps the angles each was given in."""
    xyz, _ = compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1", "orientation.convention=xyz",
                                        "orientation.psi=0.2", "orientation.theta=-0.15", "orientation.phi=0.3"),
                               catalogue)
    r = rx(0.2) @ ry(-0.15) @ rz(0.3)
    psi, theta, phi = (float(v) for v in (np.arctan2(r[2, 1], r[2, 2]), np.arcsin(-r[2, 0]), np.arctan2(r[1, 0], r[0, 0])))
    zyx, _ = compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1", f"orientation.psi={psi!r}",
                                        f"orientation.theta={theta!r}", f"orientation.phi={phi!r}"), catalogue)
    assert xyz["feasible"].tolist() == zyx["feasible"].tolist() and 0 < xyz["feasible"].sum() < len(xyz)
    margins = [c for c in xyz.columns if c.startswith("margin_")]
    np.testing.assert_allclose(xyz[margins].to_numpy(), zyx[margins].to_numpy(), rtol=1e-9, atol=1e-9)
    assert (xyz["psi"] == 0.2).all() and (zyx["psi"] == psi).all()
    # the conventions differ: the same three numbers in eq. (9) give another pose
    other, _ = compute_workspace(make_cfg("robot=irpm6", "robot.search.step=1", "orientation.psi=0.2",
                                          "orientation.theta=-0.15", "orientation.phi=0.3"), catalogue)
    assert not np.allclose(other[margins].to_numpy(), xyz[margins].to_numpy())

"""Generic cable-robot kinematics: anchors, attachment points, Euler angles, lengths, Jacobian.

A robot is data: frame anchor points ``a_i`` and platform attachment points ``b_i`` (body frame).
The cable vector of cable ``i`` at pose ``p = [x y z psi theta phi]`` is

    c_i = T + R(psi, theta, phi) b_i - a_i,     l_i = |c_i|

which is eqs. (1)-(17) of Filipovic & Kevac (2018) for the CPR-8 and eqs. (1)-(3) of Hamed & Zohoor
for the IRPM. ``R`` is eq. (9) of the CPR-8 paper (identical to eq. (2) of the IRPM paper):
R = Rz(phi) Ry(theta) Rx(psi).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CableRobot:
    """A cable robot as plain arrays; every kernel works from this and nothing else.

    anchors: (m, 3) frame points where cables leave the frame (hanging points), fixed frame, m.
    attachments: (m, 3) platform points in the body frame, m.
    box_lo, box_hi: (3,) corners of the region searched for the workspace, m.
    cable_names: m labels used in results and plots.
    """

    name: str
    anchors: np.ndarray
    attachments: np.ndarray
    box_lo: np.ndarray
    box_hi: np.ndarray
    cable_names: tuple[str, ...]

    @property
    def n_cables(self) -> int:
        return self.anchors.shape[0]


def rotation_matrix(psi: float, theta: float, phi: float) -> np.ndarray:
    """Eq. (9): R = Rz(phi) Ry(theta) Rx(psi), angles in rad."""
    return _rz(phi) @ _ry(theta) @ _rx(psi)


def rotation_partials(psi: float, theta: float, phi: float) -> np.ndarray:
    """(3, 3, 3) array: dR/dpsi, dR/dtheta, dR/dphi of eq. (9)."""
    rx, ry, rz = _rx(psi), _ry(theta), _rz(phi)
    return np.stack([rz @ ry @ _drx(psi), rz @ _dry(theta) @ rx, _drz(phi) @ ry @ rx])


def cable_vectors(robot: CableRobot, positions: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """(n, m, 3) vectors from each anchor to its attachment point, for n positions (n, 3)."""
    attached = robot.attachments @ rotation.T
    return positions[:, None, :] + attached[None, :, :] - robot.anchors[None, :, :]


def length_jacobian(
    robot: CableRobot, unit: np.ndarray, rotation_derivatives: np.ndarray
) -> np.ndarray:
    """(n, m, 6) analytic dl_i/dp for p = [x y z psi theta phi] (eq. 19 without the 1/R_i of eq. 18).

    Translation columns are the unit cable vectors; the column of Euler angle q is
    u_i . (dR/dq b_i). Columns 4-6 are derivatives with respect to the Euler angles themselves
    (the paper's p-dot holds Euler-angle rates, not the angular velocity).
    """
    lever = np.einsum("qjk,mk->qmj", rotation_derivatives, robot.attachments)  # (3, m, 3)
    angular = np.einsum("nmj,qmj->nmq", unit, lever)
    return np.concatenate([unit, angular], axis=2)


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _drx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])


def _dry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])


def _drz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])

"""Robot builders: turn a robot's design parameters into the generic :class:`CableRobot`.

Each builder only places points; kinematics, dynamics and workspace criteria are shared.
"""

from __future__ import annotations

import numpy as np

from pipeline.geometry import CableRobot


def carrier_half_diagonal(l: float, w: float, h: float) -> float:
    """d_e of section 3 (CPR-8 paper): half the carrier's main diagonal."""
    return float(np.sqrt((l / 2) ** 2 + (w / 2) ** 2 + (h / 2) ** 2))


def cpr8(
    d: float, s: float, v: float, l: float, w: float, h: float, lower_anchor_drop: float | None = None
) -> CableRobot:
    """CPR-8 of Filipovic & Kevac (2018), Fig. 1, eqs. (1)-(17).

    z points up (gravity enters eq. (31) as -g). Upper hanging points O, F, G, H lie in the plane
    z = 0 at the frame's top corners (eqs. 10-13); lower hanging points O', F', G', H' lie
    ``lower_anchor_drop`` below them (eqs. 14-17 read literally: h_o). Cables 1-4 join the
    carrier's upper vertices A, B, C, D, cables 5-8 its lower vertices A', B', C', D' (eqs. 1-8).
    The search box is the geometric workspace of Fig. 3: the frame d*s*v hanging below z = 0,
    shrunk by d_e on every side.
    """
    drop = h if lower_anchor_drop is None else lower_anchor_drop
    corners = np.array([[0.0, 0.0], [d, 0.0], [d, s], [0.0, s]])
    anchors = np.vstack(
        [np.column_stack([corners, np.zeros(4)]), np.column_stack([corners, np.full(4, -drop)])]
    )
    vertex = np.array([[-l / 2, -w / 2], [l / 2, -w / 2], [l / 2, w / 2], [-l / 2, w / 2]])
    attachments = np.vstack(
        [np.column_stack([vertex, np.full(4, h / 2)]), np.column_stack([vertex, np.full(4, -h / 2)])]
    )
    de = carrier_half_diagonal(l, w, h)
    return CableRobot(
        name="cpr8",
        anchors=anchors,
        attachments=attachments,
        box_lo=np.array([de, de, -(v - de)]),
        box_hi=np.array([d - de, s - de, -de]),
        cable_names=("k", "h", "m", "n", "k'", "h'", "m'", "n'"),
        up=np.array([0.0, 0.0, 1.0]),
    )


def irpm6(
    r_base: float, r_end: float, gamma_deg: float, box_lo, box_hi
) -> CableRobot:
    """6-cable IRPM of Hamed & Zohoor, Figs. 1-4, eqs. (1)-(2) (docs/model.md: our reading).

    Base points C_i lie on a circle of radius r_base in the base plane Z = 0, platform points D_i
    on a circle of radius r_end in the platform plane z = 0 (body frame, origin O_M). Points come
    in pairs separated by the angle gamma: base pairs (C1, C2), (C3, C4), (C5, C6) centred at
    0, 120, 240 deg; platform pairs (D2, D3), (D4, D5), (D6, D1) centred at 60, 180, 300 deg,
    so that each base pair feeds two neighbouring platform pairs (gamma = 0: two triangles
    rotated by 60 deg, the 3-3 Stewart arrangement). Z points down from the base plane, into
    the search box, so the weight is +f_z.
    """
    half = gamma_deg / 2.0
    base_deg = np.array([-half, half, 120 - half, 120 + half, 240 - half, 240 + half])
    platform_deg = np.array([300 + half, 60 - half, 60 + half, 180 - half, 180 + half, 300 - half])
    return CableRobot(
        name="irpm6",
        anchors=_circle(r_base, base_deg),
        attachments=_circle(r_end, platform_deg),
        box_lo=np.asarray(box_lo, dtype=float),
        box_hi=np.asarray(box_hi, dtype=float),
        cable_names=tuple(f"C{i}D{i}" for i in range(1, 7)),
        up=np.array([0.0, 0.0, -1.0]),
    )


def _circle(radius: float, degrees: np.ndarray) -> np.ndarray:
    angles = np.deg2rad(degrees)
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(len(angles))])

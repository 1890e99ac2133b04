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
    )

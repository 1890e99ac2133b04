"""Swivelling pulleys at the anchors (Pott, "Influence of pulley kinematics on cable-driven
parallel robots", ARK 2012; the guiding pulleys of IPAnema and WireX's PULLEY model).

A cable comes from its winch along the pulley's swivel axis and reaches the pulley at the anchor
D (the pulley's fixed point). The pulley turns about that axis until its plane holds the
platform's attachment point B; the cable wraps around it by an angle beta and leaves it at C,
tangent to it, straight to B. With the axis a (the way the cable runs into the pulley), e the
unit direction from the axis towards B in the plane normal to a, and the pulley's centre
M = D + r e, the plane coordinates of B - M are x = (B - M) . e, z = (B - M) . a, d = |B - M|:

    free length      l_f  = sqrt(d^2 - r^2)                        (C B is tangent at C)
    wrap angle       beta = pi - arccos(r / d) - atan2(z, x)         (in [0, 2 pi]; B lies on the
                                                                      e side, so below 0 is rounding)
    exit point       C    = M + r (-cos(beta) e + sin(beta) a)
    cable length     l    = l_f + r beta                             (from D; the rest is constant)

The cable's direction u = (B - C) / l_f is the one every criterion reads (the structure matrix,
the interference segments C B); dl/dB = u (the arc's change cancels the exit point's motion),
so the length Jacobian keeps its form. A pulley of radius 0 is the fixed anchor exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Pulleys:
    """One swivelling pulley per cable at its anchor: ``axes`` (m, 3) unit swivel axes, each the
    way its cable runs into the pulley from the winch; ``radii`` (m,) pulley radii, m (0: the
    cable leaves the anchor itself)."""

    axes: np.ndarray
    radii: np.ndarray

    @property
    def across(self) -> np.ndarray:
        """(m, 3) a unit vector normal to each axis: the pulley's plane when B lies on its axis
        (any plane through the axis then gives the same cable)."""
        helper = np.where(np.abs(self.axes[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
        normal = np.cross(self.axes, helper)
        return normal / np.linalg.norm(normal, axis=1, keepdims=True)


def pulley_exits(anchors: np.ndarray, pulleys: Pulleys, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, m, 3) the exit points C and (n, m) the wrapped arcs r beta of cables from their pulleys
    at ``anchors`` (m, 3) to the attachment points ``points`` (n, m, 3), fixed frame (above)."""
    axes, radii = pulleys.axes, pulleys.radii
    offset = points - anchors
    along = np.einsum("nmk,mk->nm", offset, axes)
    radial = offset - along[..., None] * axes
    size = np.linalg.norm(radial, axis=2)
    toward = np.where(size[..., None] > 0, radial / np.where(size > 0, size, 1.0)[..., None], pulleys.across)
    x, z = size - radii, along
    d = np.hypot(x, z)
    ratio = np.divide(radii, d, out=np.ones_like(d), where=d > 0)
    beta = np.clip(np.pi - np.arccos(np.minimum(ratio, 1.0)) - np.arctan2(z, x), 0.0, 2 * np.pi)  # 0: B ahead on the axis
    rim = -np.cos(beta)[..., None] * toward + np.sin(beta)[..., None] * axes
    exits = anchors + radii[:, None] * toward + radii[:, None] * rim
    return exits, radii * beta

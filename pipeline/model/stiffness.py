"""The platform's stiffness held by elastic cables (Behzadipour & Khajepour 2006; Verhoeven 2004):
K = sum_i k_i a_i a_i^T + sum_i t_i da_i/dx, for a small displacement x = [dp; dtheta] (m, and a
small rotation vector, rad, fixed axes), with a_i = [u_i; b_i x u_i] the structure matrix's column
(u_i the unit cable vector from its anchor to its attachment point, b_i = R b_i' the attachment
from the platform's reference point), t_i the cable's tension and k_i its axial stiffness: a cable
of stretched length L = l_i + w_i (from the anchor, and the winch side's in series) and
unstrained length L0 pulls with t = EA (L - L0) / L0, so dt/dL = EA / L0 = (EA + t) / L
(:func:`axial_rates`; L0 = L / (1 + t / EA), :func:`unstrained_lengths`). The wrench the
cables balance, A t, then changes by K dx to first order: the elastic term because each cable
stretches along a_i (dl_i = a_i . dx), the geometric (tension) term because each cable turns:

    du   = P (dp - [b]x dtheta) / l,        P = I - u u^T
    d(b x u) = [b]x du + [u]x [b]x dtheta

so, per cable, t/l [[P, -P [b]x], [[b]x P, -[b]x P [b]x + l [u]x [b]x]]. The geometric term is
not symmetric in general (the moment's own turn); the criterion reads the symmetric part of the
translational and rotational blocks (N/m and N m/rad kept apart). Not included: the load's own
rotational term (its weight's moment turning with the platform) and the pulleys' (a robot with
``robot.pulleys`` is refused)."""

from __future__ import annotations

import numpy as np


def axial_rates(ea: np.ndarray, stretched: np.ndarray, tensions: np.ndarray) -> np.ndarray:
    """(n, m) k = dt/dL = (EA + t) / L, N/m, of cables of axial stiffness EA (m,) stretched to
    L (n, m) under tensions t (n, m); NaN where a cable has no length."""
    return np.divide(ea + tensions, stretched, out=np.full(stretched.shape, np.nan), where=stretched > 0)


def unstrained_lengths(ea: np.ndarray, stretched: np.ndarray, tensions: np.ndarray) -> np.ndarray:
    """(n, m) L0 = L / (1 + t / EA), m: the unstrained length a cable stretched to L under t needs
    (what its winch must have paid out)."""
    return stretched / (1.0 + tensions / ea)


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3, 3) [v]x with [v]x w = v x w."""
    zero = np.zeros(v.shape[:-1])
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([zero, -z, y, z, zero, -x, -y, x, zero], axis=-1).reshape(*v.shape[:-1], 3, 3)


def stiffness_matrices(unit: np.ndarray, arms: np.ndarray, lengths: np.ndarray, tensions: np.ndarray,
                       rates: np.ndarray) -> np.ndarray:
    """(n, 6, 6) K of each pose from the unit cable vectors and the arms (n, m, 3), the cables'
    lengths, tensions (N) and axial stiffnesses k_i (N/m) (n, m) (above); NaN where a cable has
    no length."""
    columns = np.concatenate([unit, np.cross(arms, unit)], axis=2)
    stiffness = np.einsum("nm,nmi,nmj->nij", rates, columns, columns)
    across = np.eye(3) - unit[..., :, None] * unit[..., None, :]
    arm, along = skew(arms), skew(unit)
    per_length = np.divide(tensions, lengths, out=np.full(lengths.shape, np.nan), where=lengths > 0)[..., None, None]
    stiffness[:, :3, :3] += (per_length * across).sum(axis=1)
    stiffness[:, :3, 3:] -= (per_length * across @ arm).sum(axis=1)
    stiffness[:, 3:, :3] += (per_length * arm @ across).sum(axis=1)
    stiffness[:, 3:, 3:] += (per_length * (-(arm @ across @ arm)) + tensions[..., None, None] * along @ arm).sum(axis=1)
    return stiffness


def least_stiffness(stiffness: np.ndarray, dofs=(0, 1, 2, 3, 4, 5)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n,) the least eigenvalue of the symmetric part of the translational block (N/m) and of
    the rotational block (N m/rad), each over the platform's freedoms ``dofs`` among them (NaN
    where it has none), and (n, 3) the unit direction of the least translational stiffness (its
    eigenvector, over x, y, z; its largest component positive). NaN where K is not finite."""
    n = len(stiffness)
    least = [np.full(n, np.nan), np.full(n, np.nan)]
    weakest = np.full((n, 3), np.nan)
    for k, block in enumerate(((0, 1, 2), (3, 4, 5))):
        rows = [d for d in dofs if d in block]
        if not rows:
            continue
        part = stiffness[:, rows][:, :, rows]
        finite = np.isfinite(part).all(axis=(1, 2))
        values, vectors = np.linalg.eigh((part[finite] + np.swapaxes(part[finite], 1, 2)) / 2)
        least[k][finite] = values[:, 0]
        if k == 0:  # the direction, in x, y, z (a freedom the platform lacks: 0)
            first = vectors[:, :, 0]
            largest = np.take_along_axis(first, np.abs(first).argmax(axis=1)[:, None], axis=1)
            found = np.zeros((finite.sum(), 3))
            found[:, rows] = first * np.sign(largest)
            weakest[finite] = found
    return least[0], least[1], weakest


def spatial_inertia(mass: float, com: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """(n, 6, 6) or (6, 6) M of a body about the platform's reference point, fixed axes, for
    x = [dp; dtheta]: [[m I, -m [c]x], [m [c]x, I_c - m [c]x [c]x]] with c the centre of mass from
    the reference point and I_c the inertia about it, both turned with the platform (kinetic
    energy 1/2 x' M x: the centre moves with dp + dtheta x c)."""
    arm = skew(com)
    top = np.concatenate([np.broadcast_to(mass * np.eye(3), arm.shape), -mass * arm], axis=-1)
    bottom = np.concatenate([mass * arm, inertia - mass * arm @ arm], axis=-1)
    return np.concatenate([top, bottom], axis=-2)


def lowest_frequency(stiffness: np.ndarray, inertia: np.ndarray, dofs) -> np.ndarray:
    """(n,) the lowest natural frequency, Hz, of K x = omega^2 M x over the freedoms ``dofs``
    (the symmetric part of K; 0 where it has a direction of no or negative stiffness, NaN where K
    is not finite): with M = L L^T, the least eigenvalue of L^-1 K L^-T."""
    rows = list(dofs)
    part = stiffness[:, rows][:, :, rows]
    mass = np.broadcast_to(inertia, stiffness.shape)[:, rows][:, :, rows]
    found = np.full(len(stiffness), np.nan)
    finite = np.isfinite(part).all(axis=(1, 2))
    lower = np.linalg.inv(np.linalg.cholesky(mass[finite]))
    reduced = lower @ ((part[finite] + np.swapaxes(part[finite], 1, 2)) / 2) @ np.swapaxes(lower, 1, 2)
    found[finite] = np.sqrt(np.maximum(np.linalg.eigvalsh(reduced)[:, 0], 0.0)) / (2 * np.pi)
    return found

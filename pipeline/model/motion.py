"""Velocity and acceleration sets of CPR-WWA, eqs. (23)-(29) of Filipovic & Kevac (2018)."""

from __future__ import annotations

import itertools

import numpy as np

BOUNDARY_TOL = 1e-9  # relative; decides which grid velocities lie *on* the sphere |v| = V_cmax


def velocity_set(v_max: float, n: int, boundary: str = "exclude") -> np.ndarray:
    """(k, 3) carrier velocities: each axis on {-V : 2V/n : +V} (eqs. 23-25, n+1 values), kept
    where v_c <= V (eq. 26).

    ``boundary`` says what happens to grid velocities lying exactly on |v| = V (e.g. the axis
    velocities and the (2, 2, 1) V/3 family for n = 6): ``"include"`` keeps them (eq. 26 read
    literally), ``"exclude"`` keeps only |v| < V. The comparison uses a relative tolerance so the
    choice does not depend on floating-point rounding (plain ``<=`` keeps 24 of the 30 on-sphere
    velocities for n = 6, asymmetrically).
    """
    candidates = cartesian_cube(np.linspace(-v_max, v_max, n + 1))
    speed = np.linalg.norm(candidates, axis=1)
    if boundary == "include":
        keep = speed <= v_max * (1 + BOUNDARY_TOL)
    elif boundary == "exclude":
        keep = speed < v_max * (1 - BOUNDARY_TOL)
    else:
        raise ValueError(f"unknown velocity boundary {boundary!r}")
    return candidates[keep]


def cartesian_cube(axis: np.ndarray) -> np.ndarray:
    """(k^3, 3) every triple of values of ``axis`` (k,), in ``itertools.product`` order, as one
    array (no Python tuple per point)."""
    return np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)


def extreme_points(points: np.ndarray, step: float) -> np.ndarray:
    """The points of a grid set (spacing ``step``) that are not the midpoint of two other points
    of the set along one of the 13 grid directions {-1, 0, 1}^3 / +-.

    A midpoint v = (a + b) / 2 satisfies f(v) <= max(f(a), f(b)) for every linear f, so the
    maximum (and minimum) of any linear function over the set is attained among the points
    kept: for the 93 velocities of N = 6 these are 12. The CPR-WWA speed and voltage criteria
    (without J-dot) are linear in the velocity, so they need only these (tested against the
    whole set).
    """
    index = np.round((points - points.min(axis=0)) / step).astype(int) + 1
    occupied = np.zeros(index.max(axis=0) + 2, dtype=bool)
    occupied[tuple(index.T)] = True
    removable = np.zeros(len(points), dtype=bool)
    for direction in itertools.product((-1, 0, 1), repeat=3):
        if direction > (0, 0, 0):  # each line once: d and -d give the same test
            d = np.array(direction)
            removable |= occupied[tuple((index + d).T)] & occupied[tuple((index - d).T)]
    return points[~removable]


def acceleration_set(v_max: float, t_acc: float, t_dec: float, kind: str = "corners") -> np.ndarray:
    """(k, 3) carrier accelerations of eqs. (27)-(29), each axis in [-V/t_dec, +V/t_acc].

    ``"corners"``: the 8 vertices of that box. Every CPR-WWA check is a maximum of |terms linear
    in the acceleration|, so the vertices give the same result as any finer grid of the box.
    ``"colon"``: MATLAB's literal ``-V/t_dec : V/t_acc`` with its default step of 1 m/s^2.
    """
    lo, hi = -v_max / t_dec, v_max / t_acc
    if kind == "corners":
        axis = np.array([lo, hi])
    elif kind == "colon":
        axis = np.arange(lo, hi + 1e-12, 1.0)
    else:
        raise ValueError(f"unknown acceleration set {kind!r}")
    return np.array(list(itertools.product(axis, axis, axis)))

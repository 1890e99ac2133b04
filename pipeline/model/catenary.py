"""Irvine's elastic catenary (H. M. Irvine, *Cable Structures*, MIT Press 1981, eqs. 2.5-2.6 of
chapter 2): one cable of weight w per unstrained length (N/m) and axial stiffness EA (N), hanging in
the vertical plane through its two ends, vectorised over any array of cables.

The cable runs from end A (s = 0, the platform's attachment) to end B (s = L0, its anchor or pulley),
s the unstrained arc length. x is horizontal, from A towards B; z is up. The cable pulls A with the
force (H, V) towards B along its tangent (H >= 0 its horizontal component, the same all along, V
vertical, up > 0); a piece [0, s] carries its weight w s, so the tension's vertical component at s
is V + w s and its magnitude T(s) = sqrt(H^2 + (V + w s)^2). Hooke's law on the tangent,
ds_stretched = (1 + T/EA) ds, integrates in closed form:

    x(s) = H s / EA + (H / w) (asinh((V + w s) / H) - asinh(V / H))
    z(s) = (V s + w s^2 / 2) / EA + (T(s) - T(0)) / w

Those differences cancel catastrophically for light cables (w -> 0) and for nearly vertical ones
(H -> 0), where the usual parametrisations degenerate; :func:`point` evaluates them without a
difference of large numbers (P = V + w s, Q = V, both ends' vertical forces): where P and Q have
one sign, asinh(P/H) - asinh(Q/H) = asinh(w s / M) with M = (P T_Q + Q T_P) / (P + Q), a mean of
the ends' tensions, and T_P - T_Q = w s (P + Q) / (T_P + T_Q); where they differ (the cable has a
low point inside), the two asinh terms add. So w = 0 gives the straight elastic cable exactly and
H = 0 the vertical one.

:func:`solve` finds the catenary through two given ends (span a >= 0, rise h of B over A) with one
more condition: the unstrained length L0, the chord tension tau (H = tau a / l, the force a
straight cable along the chord l would carry; it also names vertical cables, where H = 0), or the
largest tension along the cable (at its upper end). Newton's method on (H, V, L0) with the Jacobian
by complex steps (exact to round-off: no difference quotient), damped to keep H >= 0 and L0 > 0,
from the parabolic (small-sag) guess; converged when both ends meet within ``RTOL`` of the chord
(the tests: every case within ``MAX_ITERATIONS``, nearly vertical and nearly level cables too)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

RTOL = 1e-12  # the ends met within this share of the chord (and the third condition of its value)
MAX_ITERATIONS = 60
GIVEN = ("length", "chord_tension", "top_tension", "sag_ratio")  # the third condition of :func:`solve`


def _asinhc(y):
    """asinh(y) / y, 1 at 0 (complex steps pass through)."""
    small = np.abs(y) < 1e-6
    safe = np.where(small, 1.0, y)
    return np.where(small, 1.0 - y * y / 6.0, np.arcsinh(safe) / safe)


def point(horizontal, vertical, s, weight, ea):
    """(x, z) of the point at unstrained arc length s from end A (above): H = ``horizontal`` >= 0
    and V = ``vertical`` the force the cable pulls A with, ``weight`` w >= 0 (N/m), ``ea`` EA > 0
    (N; inf: inextensible). Arrays broadcast; complex values pass through (the Jacobian of
    :func:`solve`)."""
    h, q = horizontal, vertical
    p = q + weight * s
    t_p, t_q = np.sqrt(h * h + p * p), np.sqrt(h * h + q * q)
    ends = t_p + t_q
    z = (q * s + weight * s * s / 2.0) / ea + s * (p + q) / np.where(np.real(ends) == 0, 1.0, ends)
    return h * _reach(h, q, p, t_p, t_q, s, weight, ea), z


def _reach(h, q, p, t_p, t_q, s, weight, ea):
    """x / H of :func:`point`, without dividing by H where both ends' vertical forces have one
    sign (H = 0 allowed: a vertical cable)."""
    both = p + q
    level = np.real(both) == 0  # both ends level: the mean tension is H
    mean = np.where(level, t_p, (p * t_q + q * t_p) / np.where(level, 1.0, both))
    mean = np.where(np.real(mean) == 0, 1.0, mean)  # a cable with no tension at all
    one_sign = s / mean * _asinhc(weight * s / mean)
    with np.errstate(divide="ignore", invalid="ignore"):
        lowest = (np.arcsinh(p / h) + np.arcsinh(-q / h)) / np.where(weight == 0, 1.0, weight)
    return s / ea + np.where(np.real(p) * np.real(q) >= 0, one_sign, lowest)


@dataclass(frozen=True)
class Catenary:
    """Solved cables (arrays of one shape): ``horizontal`` H and ``vertical`` V, the force on end A
    (N, above), ``length`` L0 the unstrained length (m), ``weight`` w, ``ea`` EA, the ends' ``span``
    and ``rise`` (m), and whether each ``converged``."""

    horizontal: np.ndarray
    vertical: np.ndarray
    length: np.ndarray
    weight: np.ndarray
    ea: np.ndarray
    span: np.ndarray
    rise: np.ndarray
    converged: np.ndarray

    @property
    def chord(self) -> np.ndarray:
        return np.hypot(self.span, self.rise)

    @property
    def top_vertical(self) -> np.ndarray:
        """V + w L0: the vertical force the cable pulls its end B with, upwards seen from A."""
        return self.vertical + self.weight * self.length

    @property
    def tension_a(self) -> np.ndarray:
        return np.hypot(self.horizontal, self.vertical)

    @property
    def tension_b(self) -> np.ndarray:
        return np.hypot(self.horizontal, self.top_vertical)

    @property
    def top_tension(self) -> np.ndarray:
        """The largest tension along the cable: T(s)^2 = H^2 + (V + w s)^2 is largest at an end."""
        return np.maximum(self.tension_a, self.tension_b)

    @property
    def chord_tension(self) -> np.ndarray:
        """tau = H l / a, the tension a straight cable along the chord l would need for the same
        horizontal force; l / (x / H) (:func:`point`), so also on a vertical cable."""
        top = self.top_vertical
        reach = _reach(self.horizontal, self.vertical, top, self.tension_b, self.tension_a, self.length,
                       self.weight, self.ea)
        return self.chord / reach

    @property
    def angles(self) -> tuple[np.ndarray, np.ndarray]:
        """The tangent's elevation at A (towards B) and at B (away from A), rad."""
        return np.arctan2(self.vertical, self.horizontal), np.arctan2(self.top_vertical, self.horizontal)

    @property
    def sag(self) -> np.ndarray:
        """The largest distance between the cable and its chord, m, positive below it (:func:`sag`)."""
        return sag(self.horizontal, self.vertical, self.length, self.weight, self.ea, self.span, self.rise)


def sag(horizontal, vertical, length, weight, ea, span, rise):
    """The largest distance between a cable (above) and its chord, m, positive below it: where its
    tangent is parallel to the chord, V + w s = H h / a; 0 where that is not inside, or for a
    vertical or weightless cable (complex values pass through)."""
    inside = np.real(weight * span) > 0
    s = (horizontal * rise - vertical * span) / np.where(inside, weight * span, 1.0)
    s = np.where(np.real(s) < 0, 0.0, np.where(np.real(s) > np.real(length), length, s))
    x, z = point(horizontal, vertical, s, weight, ea)
    chord = np.hypot(span, rise)
    return np.where(inside, (x * rise - z * span) / np.where(chord > 0, chord, 1.0), 0.0)


def solve(span, rise, weight, ea, given: str, value) -> Catenary:
    """The catenaries with ends ``span`` a >= 0 apart horizontally and B ``rise`` h above A, weight
    w (N/m), EA (N; inf: inextensible) and ``given`` (:data:`GIVEN`) ``value``: the unstrained
    length L0 (m), the chord tension tau (N), the largest tension (N) or the sag's share of the
    chord, from the parabolic cable. Arrays broadcast. Not ``converged``
    where no catenary meets the condition (a top tension below the cable's own weight's share,
    an unstrained length shorter than the chord under ``ea=inf``)."""
    if given not in GIVEN:
        raise ValueError(f"given={given!r}: one of {', '.join(GIVEN)}")
    a, h, w, ea, value = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (span, rise, weight, ea, value)))
    chord = np.hypot(a, h)
    y = _start(a, h, w, ea, given, value, chord)
    scale = np.stack([chord, chord, chord if given != "top_tension" else np.maximum(np.abs(value), 1.0)])
    scale = np.where(scale > 0, scale, 1.0)

    f = _residual(y, a, h, w, ea, value, chord, given) / scale
    active = np.flatnonzero(np.isfinite(np.abs(f).max(axis=0)) & (np.abs(f).max(axis=0) > RTOL))  # flat indices
    flat_y, flat_f = y.reshape(3, -1), f.reshape(3, -1)
    flat = [v.reshape(-1) for v in np.broadcast_arrays(a, h, w, ea, value, chord)]
    scale_flat = scale.reshape(3, -1)
    for _ in range(MAX_ITERATIONS):
        if not len(active):
            break
        sub = [v[active] for v in flat]

        def local(y, sub=sub, active=active):
            return _residual(y, *sub, given) / scale_flat[:, active]

        step = 1e-20 * (np.abs(flat_y[:, active]) + 1.0)
        columns = []
        for k in range(3):  # complex steps: d f / d y_k to round-off
            probe = flat_y[:, active].astype(complex)
            probe[k] += 1j * step[k]
            columns.append(np.imag(local(probe)) / step[k])
        jacobian = np.moveaxis(np.stack(columns, axis=-1), 0, -2)  # (p, 3, 3): d f_i / d y_k
        with np.errstate(all="ignore"):
            delta = -np.linalg.solve(_regular(jacobian), flat_f[:, active].T[..., None])[..., 0].T
        moved, f_new = _damped(flat_y[:, active], flat_f[:, active], delta, local)
        stuck = (moved == flat_y[:, active]).all(axis=0)  # no step lowered the residual
        flat_y[:, active], flat_f[:, active] = moved, f_new
        size = np.abs(f_new).max(axis=0)
        active = active[np.isfinite(size) & (size > RTOL) & ~stuck]
    y, f = flat_y.reshape(y.shape), flat_f.reshape(f.shape)  # (views of them)
    size = np.abs(f).max(axis=0)
    converged = np.isfinite(size) & (size <= 10 * RTOL) & (y[2] > 0)
    return Catenary(y[0], y[1], y[2], w, ea, a, h, converged)


def _residual(y, a, h, w, ea, value, chord, given):
    """The three conditions of :func:`solve` at (H, V, L0) = y (3, ...), unscaled."""
    p = y[1] + w * y[2]
    t_p, t_q = np.sqrt(y[0] ** 2 + p ** 2), np.sqrt(y[0] ** 2 + y[1] ** 2)
    reach = _reach(y[0], y[1], p, t_p, t_q, y[2], w, ea)
    ends = t_p + t_q
    z = (y[1] * y[2] + w * y[2] ** 2 / 2.0) / ea + y[2] * (p + y[1]) / np.where(np.real(ends) == 0, 1.0, ends)
    if given == "length":
        third = y[2] - value
    elif given == "chord_tension":
        third = value * reach - chord  # tau = H l / a = l / (x / H): also when a = 0
    elif given == "top_tension":
        third = np.where(np.real(p + y[1]) >= 0, t_p, t_q) - value
    else:
        third = sag(y[0], y[1], y[2], w, ea, a, h) - value * chord
    return np.stack([y[0] * reach - a, z - h, third])


def _regular(matrices):
    """The Jacobians with singular ones (a cable that met its ends already) made the identity."""
    bad = ~np.isfinite(matrices).all(axis=(-2, -1)) | (np.abs(np.linalg.det(np.nan_to_num(matrices))) < 1e-300)
    return np.where(bad[..., None, None], np.eye(3), np.nan_to_num(matrices))


def _damped(y, f, delta, residual):
    """The Newton step, halved (up to 16 times) until the residual falls, H kept >= 0 and L0 > 0."""
    size = np.abs(f).max(axis=0)
    factor = np.ones(size.shape)
    best_y, best_f = y, f
    done = ~np.isfinite(size) | (size <= RTOL) | ~np.isfinite(delta).all(axis=0)
    for _ in range(16):
        trial = y + factor * delta
        trial = np.stack([np.maximum(trial[0], 0.0), trial[1], np.maximum(trial[2], y[2] * 1e-3)])
        with np.errstate(all="ignore"):
            g = residual(trial)
        better = ~done & np.isfinite(g).all(axis=0) & (np.abs(g).max(axis=0) < size)
        best_y = np.where(better, trial, best_y)
        best_f = np.where(better, g, best_f)
        done = done | better
        if done.all():
            break
        factor = np.where(done, factor, factor / 2)
    return best_y, best_f


def _start(a, h, w, ea, given, value, chord):
    """The parabolic cable (small sag): H, V = H h / a - w l / 2 and L0 = the chord (or given)."""
    cos = np.divide(a, chord, out=np.ones_like(chord), where=chord > 0)
    sin = np.divide(h, chord, out=np.zeros_like(chord), where=chord > 0)
    if given == "chord_tension":
        tau = value
    elif given == "sag_ratio":  # mid-span sag w cos(beta) l^2 / (8 tau)
        tau = w * chord * cos / (8 * np.maximum(value, 1e-9))
    elif given == "top_tension":
        tau = np.maximum(value - w * chord * np.maximum(sin, 0.0) - w * chord / 2, value / 2)
    else:
        extra = np.maximum(value - chord, 1e-6 * chord)
        tau = np.maximum(w * chord * chord * cos / (8 * np.sqrt(3 * chord * extra / 8)), w * chord)
        with np.errstate(invalid="ignore", divide="ignore"):
            tau = np.where(value < chord, ea * (chord / value - 1.0), tau)
    tau = np.where(np.isfinite(tau) & (tau > 0), tau, np.maximum(w * chord, 1.0))
    length = value if given == "length" else chord / (1.0 + tau / ea)
    return np.stack([tau * cos, tau * sin - w * chord / 2, length])

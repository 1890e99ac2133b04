"""The platform's path in time (``analysis=trajectory``; docs/model.md section 11): way-points with
a time law, or a CASPR trajectory, as piecewise polynomials of the coordinates

    q(t) = [x, y, z, a, b, c]   (m; rad, the angles in ``orientation.convention``),

sampled with their exact derivatives, and the platform's angular velocity and acceleration from
the angles' rates.

Time laws, per segment between two way-points (each at rest at both ends, except ``spline``):

- ``quintic``: q = q_i + (10 s^3 - 15 s^4 + 6 s^5) (q_(i+1) - q_i), s = tau / T_i over the
  segment's duration T_i: the quintic with zero velocity and acceleration at both ends (CASPR's
  quintic spline with its points' rates zero);
- ``spline``: one cubic spline through every way-point at its time, at rest at both ends
  (clamped): continuous accelerations, for timed samples;
- ``trapezoid``: the CPR-8 paper's trapezoidal speed profile (section 3, assumption 1) along each
  straight segment: accelerate to v_max in t_acc, cruise, decelerate in t_dec (a segment too
  short for v_max: the triangular profile with the same accelerations); the angles move in
  proportion to the distance covered;
- CASPR's ``quintic_spline_trajectory`` and ``cubic_spline_trajectory``: the Hermite polynomials
  through each point's q, q_dot (and q_ddot) (``hermite``).

A path is sampled piece by piece (``Path.sample``): each polynomial piece (a segment, or a phase
of a trapezoid) on its own closed interval, both ends included and evaluated by that piece, so
an acceleration that jumps between pieces (a trapezoid's phases, a way-point between two
rest-to-rest segments) is checked on both sides of the jump; every piece in ``MIN_STEPS`` steps
at least, so a segment shorter than the step is still checked where it accelerates.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass

import numpy as np

from pipeline.errors import ConfigError
from pipeline.model.geometry import elementary_rotations, rotation_matrices

COORDINATES = ("x", "y", "z", "psi", "theta", "phi")  # q's columns (the angles in orientation.convention)
MIN_STEPS = 10  # steps a piece is sampled in, at least, whatever trajectory.dt
MAX_SAMPLES = 1_000_000  # the samples table is built whole (about 0.5 GB at 64 columns): a path's largest


@dataclass(frozen=True)
class Profile:
    """Path coordinate s(t) (m), speed v(t) (m/s) and acceleration a(t) (m/s^2) at times t (s)."""

    t: np.ndarray
    s: np.ndarray
    v: np.ndarray
    a: np.ndarray


@dataclass(frozen=True)
class Phases:
    """A trapezoidal profile over one distance: acceleration ``acc`` until ``t1``, cruise at
    ``peak`` for ``cruise`` until ``t2``, deceleration ``dec`` until ``total`` (s, m/s, m/s^2)."""

    acc: float
    dec: float
    peak: float
    cruise: float
    t1: float
    t2: float
    total: float


def trapezoid_phases(distance: float, v_max: float, t_acc: float, t_dec: float) -> Phases:
    """Trapezoidal speed profile over ``distance``: accelerate at v_max / t_acc, cruise at v_max,
    decelerate at v_max / t_dec (section 3, assumption 1). A segment too short to reach v_max
    gets the triangular profile with the same accelerations and a lower peak speed."""
    acc, dec = v_max / t_acc, v_max / t_dec
    with np.errstate(over="ignore"):  # v_max past 1e154 m/s: ramps too long for a double, the triangle
        ramps = float(np.float64(v_max) ** 2 / (2 * acc) + np.float64(v_max) ** 2 / (2 * dec))
    if distance >= ramps:
        peak, cruise = v_max, (distance - ramps) / v_max
    else:
        peak, cruise = math.sqrt(2 * distance * acc * dec / (acc + dec)), 0.0
    t1 = peak / acc
    t2 = t1 + cruise
    return Phases(acc, dec, peak, cruise, t1, t2, t2 + peak / dec)


def trapezoid(distance: float, v_max: float, t_acc: float, t_dec: float, dt: float) -> Profile:
    """:func:`trapezoid_phases` sampled every ``dt`` or less from 0 to the end, as the paper's
    straight lines are (``pipeline.workspace.lines``): at a phase's first instant the new phase."""
    ph = trapezoid_phases(distance, v_max, t_acc, t_dec)
    acc, dec, peak, t1, t2 = ph.acc, ph.dec, ph.peak, ph.t1, ph.t2
    t = np.linspace(0.0, ph.total, max(math.ceil(ph.total / dt), 2) + 1)
    accelerating, cruising = t < t1, (t >= t1) & (t < t2)
    decelerating = ~(accelerating | cruising)
    v = np.where(accelerating, acc * t, np.where(cruising, peak, peak - dec * (t - t2)))
    a = np.where(accelerating, acc, np.where(cruising, 0.0, -dec))
    s_t2 = peak * t1 / 2 + peak * ph.cruise
    s = np.where(
        accelerating, acc * t**2 / 2,
        np.where(cruising, peak * t1 / 2 + peak * (t - t1),
                 s_t2 + peak * (t - t2) - dec * (t - t2) ** 2 / 2),
    )
    v[decelerating] = np.maximum(v[decelerating], 0.0)
    return Profile(t=t, s=np.minimum(s, distance), v=v, a=a)


@dataclass(frozen=True)
class Samples:
    """A path sampled: times ``t`` (n,), s; the segment (between way-points i and i + 1: i) each
    sample lies on; the coordinates ``q`` and their first and second time derivatives (n, 6)."""

    t: np.ndarray
    segment: np.ndarray
    q: np.ndarray
    q_dot: np.ndarray
    q_ddot: np.ndarray


@dataclass(frozen=True)
class Path:
    """q(t) as polynomial pieces: piece p holds for t in [breaks[p], breaks[p + 1]] as
    sum_k coefficients[k, p] (t - breaks[p])^(D - k) (scipy's ``PPoly`` layout, D the degree;
    ``coefficients`` (D + 1, P, 6)); ``segments`` (P,): the way-point segment of each piece."""

    breaks: np.ndarray
    coefficients: np.ndarray
    segments: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.breaks[-1] - self.breaks[0])

    def counts(self, dt: float) -> np.ndarray:
        """(P,) samples per piece: both ends, at most ``dt`` apart, and at least ``MIN_STEPS``
        steps a piece (a piece shorter than ``dt`` is still sampled inside, where its acceleration
        peaks: a rest-to-rest quintic is at rest at both ends). Floats, exact integers up to 2^53:
        a path of 1e300 s counts its samples without overflowing before the caller bounds them."""
        spans = np.diff(self.breaks)
        return np.maximum(np.ceil(spans / dt - 1e-9), MIN_STEPS) + 1

    def sample(self, dt: float) -> Samples:
        """Every piece at equal steps of at most ``dt`` (s), both ends included (module doc), in
        time order; value and derivatives by Horner's scheme, exact for the polynomials."""
        counts = self.counts(dt).astype(np.int64)
        piece = np.repeat(np.arange(len(counts)), counts)
        index = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        spans = np.diff(self.breaks)
        tau = (spans[piece] * (index / (counts[piece] - 1)))[:, None]
        value, rate, accel = np.zeros((len(piece), 6)), np.zeros((len(piece), 6)), np.zeros((len(piece), 6))
        for coefficient in self.coefficients[:, piece, :]:  # D + 1 steps, each over every sample
            accel = accel * tau + 2 * rate
            rate = rate * tau + value
            value = value * tau + coefficient
        return Samples(self.breaks[piece] + tau[:, 0], self.segments[piece], value, rate, accel)


QUINTIC = (6.0, -15.0, 10.0)  # h(s) = 10 s^3 - 15 s^4 + 6 s^5: the share of a rest-to-rest segment covered at s = tau / T
QUINTIC_PEAK = 10 / math.sqrt(3)  # the largest |h''(s)| on [0, 1], at s = (3 -+ sqrt 3) / 6


def rest_to_rest(points: np.ndarray, durations: np.ndarray) -> Path:
    """``quintic``: each segment q_i -> q_(i+1) in its duration T_i (s) by the quintic
    h(s) = 10 s^3 - 15 s^4 + 6 s^5 of s = tau / T_i, at rest at every way-point."""
    points, durations = np.asarray(points, float), np.asarray(durations, float)
    delta = np.diff(points, axis=0)  # (P, 6)
    scale = durations[:, None]
    zero = np.zeros_like(delta)
    fifth, fourth, third = QUINTIC
    coefficients = np.stack([fifth * delta / scale**5, fourth * delta / scale**4, third * delta / scale**3, zero, zero,
                             points[:-1]])
    return Path(_breaks(durations), coefficients, np.arange(len(delta)))


def durations(times, segments: int, key: str) -> np.ndarray:
    """(segments,) each segment's duration (s) from ``times`` (plain values: a number, or a list),
    the value of the key ``key``: one value for every segment, or one per segment, each > 0 and
    finite; ConfigError naming the key for anything else."""
    values = times if isinstance(times, list) else [times]
    if not all(isinstance(value, (int, float)) and not isinstance(value, bool) for value in values):
        raise ConfigError(f"{key}={values}: every duration must be a number of seconds")
    if len(values) not in (1, segments):
        raise ConfigError(f"{key}={values}: {len(values)} durations for {segments} segments; "
                          f"give one for every segment or one per segment")
    found = np.array(values, dtype=float)
    if not (np.isfinite(found).all() and (found > 0).all()):
        raise ConfigError(f"{key}={times}: every duration must be > 0 and finite (s)")
    return np.broadcast_to(found, (segments,)).copy()


def quintic_share(s: np.ndarray) -> np.ndarray:
    """h(s), the share of a rest-to-rest segment covered at s in [0, 1] (increasing: h' = 30 s^2 (1 - s)^2)."""
    fifth, fourth, third = QUINTIC
    return s**3 * (third + s * (fourth + s * fifth))


def quintic_curvature_range(s0: np.ndarray, s1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The least and largest h''(s) = 60 s - 180 s^2 + 120 s^3 over each [s0, s1] (within [0, 1]):
    its values at both ends and at its turning points (3 -+ sqrt 3) / 6 where they fall inside,
    widened by 1e-12 for their rounding. A segment's acceleration is h''(s) (q_(i+1) - q_i) / T_i^2."""
    fifth, fourth, third = QUINTIC
    turns = (3 - math.sqrt(3)) / 6, (3 + math.sqrt(3)) / 6
    points = np.stack([s0, s1, *(np.clip(turn, s0, s1) for turn in turns)])
    values = points * (6 * third + points * (12 * fourth + points * 20 * fifth))
    return values.min(axis=0) - 1e-12, values.max(axis=0) + 1e-12


@dataclass(frozen=True)
class StraightMotion:
    """A rest-to-rest time law along the straight segments between way-points, for a certified
    path in motion (``pipeline.workspace.paving.certify_path``): segment i lasts ``durations[i]`` s
    and at t = tau / T_i in [0, 1] has covered :meth:`share` of its vector q_(i+1) - q_i, with an
    acceleration that vector times a factor (1/s^2) within :meth:`acceleration_range` over an
    interval of t. ``law``: ``quintic`` (:func:`rest_to_rest`) or ``trapezoid``
    (:func:`trapezoid_phases` over each segment's length: ``phases`` (P, 7) its acc, dec, peak,
    cruise, t1, t2 and total, ``lengths`` (P,) m)."""

    law: str
    durations: np.ndarray
    lengths: np.ndarray
    phases: np.ndarray | None = None

    @classmethod
    def quintic(cls, points: np.ndarray, durations: np.ndarray) -> "StraightMotion":
        lengths = np.linalg.norm(np.diff(np.asarray(points, float), axis=0), axis=1)
        return cls("quintic", np.asarray(durations, float), lengths)

    @classmethod
    def trapezoid(cls, points: np.ndarray, v_max: float, t_acc: float, t_dec: float) -> "StraightMotion":
        lengths = np.linalg.norm(np.diff(np.asarray(points, float), axis=0), axis=1)
        phases = np.array([astuple(trapezoid_phases(float(length), v_max, t_acc, t_dec)) for length in lengths])
        return cls("trapezoid", phases[:, 6].copy(), lengths, phases)

    def peaks(self) -> np.ndarray:
        """(P,) each segment's largest acceleration (m/s^2)."""
        if self.phases is None:
            with np.errstate(divide="ignore", over="ignore"):
                return QUINTIC_PEAK * self.lengths / self.durations ** 2
        return np.maximum(self.phases[:, 0], self.phases[:, 1])

    def share(self, segment: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The share of segment ``segment`` covered at ``t`` (each in [0, 1]; increasing in t)."""
        if self.phases is None:
            return quintic_share(t)
        acc, dec, peak, cruise, t1, t2, _ = self.phases[segment].T
        tau = t * self.durations[segment]
        covered = np.where(tau < t1, acc * tau ** 2 / 2, np.where(
            tau < t2, peak * t1 / 2 + peak * (tau - t1),
            peak * t1 / 2 + peak * cruise + peak * (tau - t2) - dec * (tau - t2) ** 2 / 2))
        return np.clip(covered / self.lengths[segment], 0.0, 1.0)

    def acceleration_range(self, segment: np.ndarray, t0: np.ndarray, t1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The least and largest factor of the segment's vector that its acceleration takes over
        [t0, t1] (1/s^2): the quintic's h''(t) / T^2 (:func:`quintic_curvature_range`); the
        trapezoid's acc / L, 0 (cruising) and -dec / L, those of every phase the interval meets
        (within 1e-12 of its time at a phase's end, for the rounding of the phases' times), each
        widened by 1e-12 of itself."""
        if self.phases is None:
            low, high = quintic_curvature_range(t0, t1)
            return low / self.durations[segment] ** 2, high / self.durations[segment] ** 2
        acc, dec, _, cruise, end_acc, end_cruise, total = self.phases[segment].T
        tolerance = 1e-12 * total
        start, end = t0 * total, t1 * total
        values = np.stack([acc, np.zeros_like(acc), -dec]) / self.lengths[segment]
        meets = np.stack([start <= end_acc + tolerance,
                          (cruise > 0) & (end >= end_acc - tolerance) & (start <= end_cruise + tolerance),
                          end >= end_cruise - tolerance])
        low = np.where(meets, values, np.inf).min(axis=0)
        high = np.where(meets, values, -np.inf).max(axis=0)
        return low - 1e-12 * np.abs(low), high + 1e-12 * np.abs(high)


def spline(points: np.ndarray, durations: np.ndarray) -> Path:
    """``spline``: one cubic spline through every way-point at its time, first derivative zero
    at both ends (scipy's ``CubicSpline``, clamped): continuous velocity and acceleration."""
    from scipy.interpolate import CubicSpline

    breaks = _breaks(np.asarray(durations, float))
    curve = CubicSpline(breaks, np.asarray(points, float), axis=0, bc_type="clamped")
    return Path(breaks, curve.c, np.arange(len(durations)))


def hermite(points: np.ndarray, durations: np.ndarray, rates: list[np.ndarray]) -> Path:
    """CASPR's splines: on each segment the polynomial of least degree with each end's q and the
    derivatives ``rates`` give there ([q_dot] for a cubic, [q_dot, q_ddot] for a quintic, each
    (k, 6)); scipy's ``BPoly.from_derivatives``, in the power basis."""
    from scipy.interpolate import BPoly, PPoly

    breaks = _breaks(np.asarray(durations, float))
    known = [[np.asarray(points[i], float), *(np.asarray(r[i], float) for r in rates)] for i in range(len(points))]
    curve = PPoly.from_bernstein_basis(BPoly.from_derivatives(breaks, known))
    return Path(breaks, curve.c, np.arange(len(durations)))


def trapezoidal(points: np.ndarray, v_max: float, t_acc: float, t_dec: float) -> Path:
    """``trapezoid``: each straight segment by :func:`trapezoid_phases` over its length (the
    positions' distance, which must be > 0), the angles in proportion; three pieces a segment
    (two where the profile is triangular). ValueError for a segment that does not move the
    platform's reference point."""
    points = np.asarray(points, float)
    breaks, pieces, segments = [0.0], [], []
    for i, (start, end) in enumerate(zip(points[:-1], points[1:])):
        distance = float(np.linalg.norm(end[:3] - start[:3]))
        if not distance > 0:
            raise ValueError(f"way-points {i + 1} and {i + 2} are at the same position: a trapezoidal profile runs "
                             "along a distance (law quintic or spline turns the platform in place)")
        ph = trapezoid_phases(distance, v_max, t_acc, t_dec)
        along = (end - start) / distance  # q per metre of the path
        cruise_start = ph.peak * ph.t1 / 2
        phases = [(ph.t1, ph.acc / 2, 0.0, 0.0), (ph.cruise, 0.0, ph.peak, cruise_start),
                  (ph.total - ph.t2, -ph.dec / 2, ph.peak, cruise_start + ph.peak * ph.cruise)]
        for span, half_acc, speed, covered in phases:
            if span > 0:  # a triangular profile has no cruise
                pieces.append(np.stack([half_acc * along, speed * along, start + covered * along]))
                breaks.append(breaks[-1] + span)
                segments.append(i)
    return Path(np.array(breaks), np.stack(pieces, axis=1), np.array(segments))


def _breaks(durations: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(durations)])


SEQUENCES = {"zyx": (2, 1, 0), "xyz": (0, 1, 2)}  # the axes (= the angles: psi x, theta y, phi z) in product order


def angular_motion(angles: np.ndarray, rates: np.ndarray, accelerations: np.ndarray,
                   convention: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R (n, 3, 3), omega (n, 3), alpha (n, 3)): the rotation of Euler angles (n, 3) in
    ``convention`` (``geometry.rotation_matrices``), its angular velocity and acceleration
    (rad/s, rad/s^2, fixed axes) from the angles' first and second time derivatives.

    With R = R1(q1) R2(q2) R3(q3) in product order, about the unit axes e1, e2, e3, each factor
    turns the axes after it: omega = q1' e1 + q2' R1 e2 + q3' R1 R2 e3 = w1 + w2 + w3, and, as
    R1 e2 turns at w1 and R1 R2 e3 at w1 + w2,
    alpha = q1'' e1 + q2'' R1 e2 + q3'' R1 R2 e3 + w1 x w2 + (w1 + w2) x w3."""
    rotations = elementary_rotations(angles)
    turned, parts, alpha = None, [], 0.0
    for axis in SEQUENCES[convention]:
        column = np.zeros((len(angles), 3))
        column[:, axis] = 1.0
        if turned is not None:
            column = np.einsum("nij,nj->ni", turned, column)
        turned = rotations[axis] if turned is None else turned @ rotations[axis]
        parts.append(column * rates[:, axis, None])
        alpha = alpha + column * accelerations[:, axis, None]
    alpha = alpha + np.cross(parts[0], parts[1]) + np.cross(parts[0] + parts[1], parts[2])
    return rotation_matrices(angles, convention), parts[0] + parts[1] + parts[2], alpha

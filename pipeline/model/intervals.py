"""Interval arithmetic with outward rounding, batched over numpy arrays (issue 57).

An :class:`Interval` is two arrays ``lo <= hi`` that enclose a set of real numbers; every
operation returns an enclosure of every result its operands' members can give. Sound by
directed rounding done after the fact: IEEE 754 rounds +, -, *, / and sqrt correctly (to the
nearest double), so the exact result lies between the computed double's two neighbours, and each
bound is moved one neighbour outward (``np.nextafter``'s, computed by ``pipeline.model.rounding``)
after every operation. Nothing here depends on the processor's rounding mode, and an operation
costs a few numpy passes: fast enough to enclose the structure matrices of 10^5 boxes of poses
per second (python-flint's arb balls would be exact to more digits but a Python call per number;
the certificates need enclosures tight to the box's width, not to the last bit).

The one transcendental input, the platform's rotation, is enclosed by :func:`rotation_enclosure`
from mpmath at 113 bits, rounded to doubles and widened the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.model.jit import compiled_loops


def down(values: np.ndarray) -> np.ndarray:
    """The next double below each value: a lower bound of the exact value it rounds."""
    return _next(values, False)


def up(values: np.ndarray) -> np.ndarray:
    """The next double above each value: an upper bound of the exact value it rounds."""
    return _next(values, True)


def _next(values, upward: bool) -> np.ndarray:
    """``np.nextafter(values, +-inf)`` bit for bit, by ``pipeline.model.rounding.step`` over the
    values' bit patterns (a numpy scalar for a scalar)."""
    given = np.asarray(values, dtype=np.float64)
    bits = np.ascontiguousarray(given).reshape(-1).view(np.int64)
    if not bits.flags.writeable:  # the compiled signature takes writable arrays
        bits = bits.copy()
    out = np.empty(given.shape, np.int64)
    compiled_loops("pipeline.model.rounding").step(bits, out.reshape(-1), upward)
    result = out.view(np.float64)
    return result[()] if result.ndim == 0 else result


@dataclass(frozen=True)
class Interval:
    """Arrays of intervals [lo, hi] (same shape); numbers and arrays of doubles combine with them
    as exact points."""

    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def point(cls, values) -> Interval:
        values = np.asarray(values, dtype=float)
        return cls(values, values)

    @property
    def shape(self) -> tuple[int, ...]:
        return np.shape(self.lo)

    def __getitem__(self, index) -> Interval:
        return Interval(self.lo[index], self.hi[index])

    def __add__(self, other) -> Interval:
        other = _interval(other)
        return Interval(down(self.lo + other.lo), up(self.hi + other.hi))

    __radd__ = __add__

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __sub__(self, other) -> Interval:
        other = _interval(other)
        return Interval(down(self.lo - other.hi), up(self.hi - other.lo))

    def __rsub__(self, other) -> Interval:
        return _interval(other) - self

    def __mul__(self, other) -> Interval:
        """The least and largest of the four products of the bounds; two where either factor is a
        point (:meth:`point`: its bounds one array), the same doubles at half the work."""
        other = _interval(other)
        if self.lo is self.hi:
            self, other = other, self
        if other.lo is other.hi:
            low, high = self.lo * other.lo, self.hi * other.lo
            return Interval(down(np.minimum(low, high)), up(np.maximum(low, high)))
        products = (self.lo * other.lo, self.lo * other.hi, self.hi * other.lo, self.hi * other.hi)
        return Interval(down(np.minimum(np.minimum(products[0], products[1]), np.minimum(products[2], products[3]))),
                        up(np.maximum(np.maximum(products[0], products[1]), np.maximum(products[2], products[3]))))

    __rmul__ = __mul__

    def __truediv__(self, other) -> Interval:
        """Division by an interval of positive numbers only (a cable's length, its radius)."""
        other = _interval(other)
        if np.any(other.lo <= 0):
            raise ValueError("interval division by an interval reaching 0")
        return self * Interval(down(1.0 / other.hi), up(1.0 / other.lo))

    def square(self) -> Interval:
        """x^2 over the interval: [0, ...] where it holds 0 (tighter than x * x)."""
        low, high = self.lo * self.lo, self.hi * self.hi
        straddles = (self.lo <= 0) & (self.hi >= 0)
        lower = np.where(straddles, 0.0, np.minimum(low, high))
        return Interval(np.maximum(down(lower), 0.0), up(np.maximum(low, high)))

    def sqrt(self) -> Interval:
        """Square root of an interval of non-negative numbers (its negative part dropped)."""
        return Interval(np.maximum(down(np.sqrt(np.maximum(self.lo, 0.0))), 0.0), up(np.sqrt(np.maximum(self.hi, 0.0))))

    def sum(self, axis: int) -> Interval:
        """Sum along ``axis``, each partial sum rounded outward."""
        lo, hi = np.moveaxis(self.lo, axis, 0), np.moveaxis(self.hi, axis, 0)
        total = Interval(lo[0], hi[0])
        for k in range(1, lo.shape[0]):
            total = total + Interval(lo[k], hi[k])
        return total

    def intersect(self, other: Interval) -> Interval:
        """Both enclosures at once (each encloses the same set): the tighter bounds."""
        return Interval(np.maximum(self.lo, other.lo), np.minimum(self.hi, other.hi))

    def magnitude(self) -> np.ndarray:
        """max |x| over each interval."""
        return np.maximum(np.abs(self.lo), np.abs(self.hi))


def _interval(value) -> Interval:
    return value if isinstance(value, Interval) else Interval.point(value)


def stack(parts: list[Interval], axis: int) -> Interval:
    return Interval(np.stack([p.lo for p in parts], axis=axis), np.stack([p.hi for p in parts], axis=axis))


def cross(a: Interval, b: Interval) -> Interval:
    """a x b along the last axis (3) of broadcastable interval arrays."""
    return stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                  a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                  a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def rotation_enclosure(psi: float, theta: float, phi: float) -> Interval:
    """(3, 3) an enclosure of R = Rz(phi) Ry(theta) Rx(psi) of eq. (9) at the given angles
    (doubles taken as exact): mpmath at 113 bits, each entry rounded to the nearest double and
    widened by one neighbour each way (mpmath's error, below 2^-100, is far inside that step)."""
    import mpmath

    with mpmath.workprec(113):
        a, b, c = (mpmath.mpf(float(angle)) for angle in (psi, theta, phi))
        ca, sa, cb, sb, cc, sc = mpmath.cos(a), mpmath.sin(a), mpmath.cos(b), mpmath.sin(b), mpmath.cos(c), mpmath.sin(c)
        entries = [[cc * cb, cc * sb * sa - sc * ca, cc * sb * ca + sc * sa],
                   [sc * cb, sc * sb * sa + cc * ca, sc * sb * ca - cc * sa],
                   [-sb, cb * sa, cb * ca]]
        nearest = np.array([[float(value) for value in row] for row in entries])
    return Interval(down(nearest), up(nearest))


def rotation_box_enclosure(lo, hi, convention: str = "zyx") -> tuple[Interval, Interval]:
    """Enclosures of every rotation R whose angles (psi, theta, phi) lie in [lo, hi] (rad, each
    (3,)), eq. (9)'s Rz(phi) Ry(theta) Rx(psi) (``zyx``) or CASPR's Rx(psi) Ry(theta) Rz(phi)
    (``xyz``), and of its partial derivatives dR/dpsi, dR/dtheta, dR/dphi over the box: (3, 3) and
    (3, 3, 3). Products of the elementary rotations' enclosures (:func:`_cos_sin`), which keep no
    correlation between the factors' entries: wider than the set of rotations, never narrower."""
    cos, sin = _cos_sin(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    one, zero = Interval.point(1.0), Interval.point(0.0)
    factors, rates = [], []
    for k, (plain, turned) in enumerate((
            (lambda c, s: [[one, zero, zero], [zero, c, -s], [zero, s, c]],
             lambda c, s: [[zero, zero, zero], [zero, -s, -c], [zero, c, -s]]),
            (lambda c, s: [[c, zero, s], [zero, one, zero], [-s, zero, c]],
             lambda c, s: [[-s, zero, c], [zero, zero, zero], [-c, zero, -s]]),
            (lambda c, s: [[c, -s, zero], [s, c, zero], [zero, zero, one]],
             lambda c, s: [[-s, -c, zero], [c, -s, zero], [zero, zero, zero]]))):
        c, s = cos[k], sin[k]
        factors.append(_matrix(plain(c, s)))
        rates.append(_matrix(turned(c, s)))
    order = (2, 1, 0) if convention == "zyx" else (0, 1, 2)  # the angles' factors, left to right

    def product(turned: int | None) -> Interval:
        total = None
        for k in order:
            factor = rates[k] if k == turned else factors[k]
            total = factor if total is None else (total[:, :, None] * factor[None, :, :]).sum(axis=1)
        return total

    return product(None), stack([product(k) for k in range(3)], axis=0)


def _matrix(rows: list[list[Interval]]) -> Interval:
    return stack([stack(row, axis=0) for row in rows], axis=0)


def _cos_sin(lo: np.ndarray, hi: np.ndarray) -> tuple[Interval, Interval]:
    """Enclosures (3,) of cos and sin over each [lo, hi] (rad): their values at both ends (mpmath
    at 113 bits, each rounded to the nearest double and widened one neighbour each way, as
    :func:`rotation_enclosure`), and +-1 where the interval holds a point where the function turns
    (k pi for cos, pi/2 + k pi for sin; looked for 1e-9 rad beyond either end, so a turning point
    within rounding of an end counts as inside)."""
    import mpmath

    with mpmath.workprec(113):
        values = np.array([[[float(f(mpmath.mpf(float(v)))) for f in (mpmath.cos, mpmath.sin)] for v in bound]
                           for bound in (lo, hi)])  # (2 ends, 3 angles, cos and sin)
    low, high = down(values.min(axis=0)), up(values.max(axis=0))
    found = []
    for k, shift in enumerate((0.0, np.pi / 2)):  # cos turns at k pi (its value (-1)^k), sin at pi/2 + k pi
        first, last = np.ceil((lo - shift - 1e-9) / np.pi), np.floor((hi - shift + 1e-9) / np.pi)
        some = first <= last
        top = some & ((first % 2 == 0) | (last > first))  # a turning point of value +1 inside
        bottom = some & ((first % 2 != 0) | (last > first))  # one of value -1
        found.append(Interval(np.where(bottom, -1.0, low[:, k]), np.where(top, 1.0, high[:, k])))
    return found[0], found[1]

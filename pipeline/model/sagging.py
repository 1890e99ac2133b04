"""Statics with sagging cables (issue 55 item 3; Gouttefarde, Collard, Riehl and Baradat, ICRA 2012;
Kozak, Zhou and Wang, IEEE T-RO 22(3), 2006): each cable an elastic catenary
(``pipeline.model.catenary``) in the vertical plane through its attachment point A and its anchor B.

One variable per cable keeps the structure matrix linear. The force a catenary pulls A with is
(H, V) along its plane's level direction and up; with the chord tension tau = H l / a (the force a
straight cable along the chord would need for the same H, ``Catenary.chord_tension``) it is

    f = tau d + g up,        g = V - tau h / l  in [-w L0, 0],

d the chord's direction from A to B (-u of the straight model) and g the share of the cable's own
weight w L0 that hangs on the platform (the moment of the cable's weight about A: g = -w L0 (1 -
x_c / a), x_c its centroid). Equilibrium -A tau + sum_i g_i [up; b_i x up] + w = 0 is the straight
statics A tau = w' with w' = w + sum_i g_i(tau_i) q_i: the same A, its right-hand side moved by the
cables' weight, which depends on tau itself. A cable's tension is largest at one of its ends (its
upper one for an inclined cable); the criteria's intervals bound that top tension, each mapped to
tau (``variables_of``, ``forces_of``) on the taut branch, where pulling harder raises every tension
(below the pull of its least top tension a cable hangs deeper the less it is pulled):
``robot.catenary`` also keeps every cable's sag within its share of the chord.

The forces (:meth:`SaggingStatics.balanced_wrenches`): a fixed point, w' from tau, the least-norm
tau within the intervals for w', until w' moves by less than ``SETTLED_RTOL`` of the wrench. The
proof that it is an equilibrium within the intervals, and where there is none the proof of that,
are the criterion ``catenary``'s (``pipeline.workspace.criteria.catenary``)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from pipeline.model.catenary import Catenary, solve
from pipeline.model.distribution import face_distribution, min_norm_tensions
from pipeline.model.statics import PoseStatics, StaticsSpec
from pipeline.model.tensions import Family

SETTLED_RTOL = 1e-12  # the fixed point has settled when w' moves by less than this share of |w| (at least 1 N)
MAX_SETTLING = 30  # fixed-point iterations at most (a contraction of about w L0 / tau per step)
TAUT_STEPS = 32  # golden-section steps for the least top tension's pull (a 2e-7 share of the bracket)
MAX_CABLES = 12  # the proof checks 2^m wrenches per required wrench
SAGGING_WORK = 6.0  # a pose's work against the straight statics' (SaggingSpec.work)


@dataclass(frozen=True)
class SaggingSpec(StaticsSpec):
    """``analysis=statics`` of a robot with sagging cables (``robot.catenary``): its states are
    :class:`SaggingStatics`; the summary gives min, median and max of the proven equilibria's
    largest sag share and added length."""

    summarised: ClassVar[tuple[str, ...]] = ("sag_max_ratio", "added_length_max")

    def state(self, robot, positions: np.ndarray, orientation) -> "SaggingStatics":
        return SaggingStatics(robot, positions, orientation, self)

    def fused_unfit(self) -> str | None:
        return "its cables are straight (robot.catenary: sagging cables)"

    def work(self) -> float:
        """A pose with sagging cables costs three to nine of the straight statics (catenaries solved
        for the intervals, the settling and the proofs; benchmarks/LOG.md, 2026-11-28: IPAnema 1
        x3.0, 819 poses of an 8-cable robot with its cable output x5.2, a 4-cable crane x8.8)."""
        return SAGGING_WORK * super().work()


class SaggingStatics(PoseStatics):
    """The statics of a chunk with sagging cables (above): the chord tensions tau are the
    ``feasible`` model's variables, the top tensions its forces."""

    settles = True
    catenary_undecided: np.ndarray | None = None  # (n,) set by the criterion catenary, with the next two
    sag_share: np.ndarray | None = None  # (n,) the largest sag / chord of a proven equilibrium (NaN: none)
    added_length: np.ndarray | None = None  # (n,) its largest unstrained length beyond the chord, m

    @cached_property
    def ends(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) span a >= 0 (level distance) and rise h of each anchor over its attachment point."""
        chord = self.exits - self.attachment_points
        rise = chord @ self.robot.up
        return np.linalg.norm(chord - rise[..., None] * self.robot.up, axis=2), rise

    @property
    def weight(self) -> np.ndarray:
        """(m,) w, N/m: each cable's weight per unstrained length."""
        return self.robot.cable_mass * self.load.gravity

    @property
    def ea(self) -> np.ndarray:
        """(m,) EA, N (inf: inextensible)."""
        return np.full(self.robot.n_cables, np.inf) if self.robot.cable_ea is None else self.robot.cable_ea

    def catenaries(self, given: str, value, poses=slice(None)) -> Catenary:
        """The catenaries of the ``poses`` (all: every pose) and their cables meeting ``given`` =
        ``value`` (``catenary.solve``): ``value`` (p, K, m), (p, m), or one per cable or for all
        (then (p, 1, m))."""
        value = np.asarray(value, dtype=float)
        span, rise = (e[poses] for e in self.ends)
        if value.ndim != 2:
            span, rise = span[:, None, :], rise[:, None, :]
            value = value if value.ndim == 3 else np.broadcast_to(value, (self.robot.n_cables,))[None, None, :]
        with np.errstate(all="ignore"):
            return solve(span, rise, self.weight, self.ea, given, np.where(np.isfinite(value), value, 1.0))

    def _picked(self, where: np.ndarray, given: str, value: np.ndarray) -> Catenary:
        """The catenaries of the cables ``where`` (a mask over (n, m) or (n, K, m)) meeting
        ``given`` = ``value`` (one per cable picked)."""
        span, rise = (np.broadcast_to(e if where.ndim == 2 else e[:, None, :], where.shape)[where] for e in self.ends)
        weight, ea = (np.broadcast_to(v, where.shape)[where] for v in (self.weight, self.ea))
        with np.errstate(all="ignore"):
            return solve(span, rise, weight, ea, given, value)

    def forces_of(self, tau) -> np.ndarray:
        """The top tension (N) of each cable pulled with chord tension tau (inf: inf)."""
        tau = np.asarray(tau, dtype=float)
        top = self.catenaries("chord_tension", tau).top_tension
        return np.where(np.isfinite(tau), top, np.inf)

    def variables_of(self, tensions) -> np.ndarray:
        """The chord tension tau on the taut branch whose top tension is ``tensions`` (N); below the
        taut floor's top tension, a tau below the floor in proportion (the floor decides). Cached
        per value: every gathering of the criteria's intervals asks for the same limits."""
        tensions = np.asarray(tensions, dtype=float)
        cache = self.__dict__.setdefault("_variables", {})
        key = (tensions.shape, tensions.tobytes())
        if key not in cache:
            cache[key] = self._variables_of(tensions)
        return cache[key]

    def _variables_of(self, tensions: np.ndarray) -> np.ndarray:
        floor, floor_top = self.taut_floor, self.taut_top
        if tensions.ndim != 2:
            floor, floor_top = floor[:, None, :], floor_top[:, None, :]
        shape = np.broadcast_shapes(floor.shape, tensions.shape)
        wanted, floor = np.broadcast_to(tensions, shape), np.broadcast_to(floor, shape)
        tau = floor * np.clip(wanted, 0.0, None) / np.where(floor_top > 0, floor_top, 1.0)  # below the floor's top
        above = np.isfinite(wanted) & (wanted > floor_top)
        if above.any():  # the taut branch's root: Newton, else (the slack branch's found) bisection
            found = self._picked(above, "top_tension", wanted[above])
            root = np.where(found.converged & (found.chord_tension >= floor[above]), found.chord_tension, np.nan)
            missed = ~np.isfinite(root)
            if missed.any():
                where = np.zeros(shape, dtype=bool)
                where[tuple(index[missed] for index in np.nonzero(above))] = True
                root[missed] = self._bisected(where, wanted[where], floor[where])
            tau = tau.copy()
            tau[above] = root
        return np.where(np.isfinite(wanted), tau, np.inf)

    def _top(self, where: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """The top tensions of the cables ``where`` at chord tensions tau (one per cable picked)."""
        return self._picked(where, "chord_tension", tau).top_tension

    def _bisected(self, where, tensions, floor):
        """tau in [floor, 2 tension + floor] with top tension ``tensions`` (T rises with tau there),
        for the cables ``where``."""
        low, high = floor.copy(), 2 * tensions + floor
        for _ in range(80):
            middle = (low + high) / 2
            rises = self._top(where, middle) < tensions
            low, high = np.where(rises, middle, low), np.where(rises, high, middle)
        return (low + high) / 2

    @cached_property
    def taut_floor(self) -> np.ndarray:
        """(n, m) the least chord tension a cable may have: its sag within ``robot.catenary`` of its
        chord and on the taut branch (at least the pull of its least top tension)."""
        sagged = self.catenaries("sag_ratio", np.full((len(self.positions), self.robot.n_cables), self.robot.catenary))
        span = self.ends[0]
        floor = np.where(sagged.converged & (self.weight * span > 0), sagged.chord_tension, 0.0)
        falling = self.forces_of(floor * (1 + 1e-6) + 1e-9) < self.forces_of(floor)  # below the least top's pull
        if falling.any():
            floor = floor.copy()
            floor[falling] = self._least_top(falling, floor[falling])
        return floor

    @cached_property
    def taut_top(self) -> np.ndarray:
        """(n, m) the top tension at :attr:`taut_floor`."""
        return self.forces_of(self.taut_floor)

    def _least_top(self, where, floor):
        """The pull of the least top tension above ``floor``: golden sections, for the cables ``where``."""
        reach = np.hypot(*(e[where] for e in self.ends)) * np.broadcast_to(self.weight, where.shape)[where]
        low, high = floor.copy(), floor + 4 * reach
        ratio = (np.sqrt(5) - 1) / 2
        left, right = high - ratio * (high - low), low + ratio * (high - low)
        at_left, at_right = self._top(where, left), self._top(where, right)
        for _ in range(TAUT_STEPS):  # one new top tension a step: the other inner point is kept
            lower_left = at_left < at_right
            low, high = np.where(lower_left, low, left), np.where(lower_left, right, high)
            left, right = np.where(lower_left, high - ratio * (high - low), right), np.where(
                lower_left, left, low + ratio * (high - low))
            fresh = self._top(where, np.where(lower_left, left, right))
            at_left, at_right = np.where(lower_left, fresh, at_right), np.where(lower_left, at_left, fresh)
        return high  # the bracket's upper end: on the taut side

    def sag_tensions(self, ratio: float) -> np.ndarray:
        """(n, m) the top tension of each cable whose sag is ``ratio`` of its chord (criterion
        ``sag``, exact here)."""
        sagged = self.catenaries("sag_ratio", np.full((len(self.positions), self.robot.n_cables), ratio))
        return np.where(sagged.converged, sagged.top_tension, 0.0)

    @cached_property
    def weight_columns(self) -> np.ndarray:
        """(n, k, m) q_i = [up; b_i x up] along the robot's freedoms: the wrench of a unit upward
        force at each attachment point (moments as the structure matrix takes them)."""
        arms = self.arms if self.spec.moment_arm == "platform" else self.arms + self.positions[:, None, :]
        up = np.broadcast_to(self.robot.up, arms.shape)
        return np.transpose(np.concatenate([up, np.cross(arms, up)], axis=2), (0, 2, 1))[:, list(self.robot.dofs), :]

    def hanging(self, tau: np.ndarray, poses=slice(None)) -> np.ndarray:
        """(p, K, m) g = V - tau h / l of each cable of the ``poses`` at chord tension tau (p, K, m):
        the upward force beyond the chord's that the cable's weight leaves on the platform (0 where
        undefined)."""
        cables = self.catenaries("chord_tension", tau, poses)
        g = cables.vertical - tau * cables.rise / np.where(cables.chord > 0, cables.chord, 1.0)
        return np.where(cables.converged & np.isfinite(g), g, 0.0)

    def shifted(self, hanging: np.ndarray, poses=slice(None)) -> np.ndarray:
        """(p, K, k) w' = w + sum_i g_i q_i of the ``poses`` for g (p, K, m)."""
        required = self.required_wrenches
        wrenches = np.broadcast_to(required, (len(self.positions), *required.shape[-2:]))[poses]
        return wrenches + np.einsum("nrm,nkm->nkr", self.weight_columns[poses], hanging)

    def balanced_wrenches(self, families: list[Family]) -> np.ndarray:
        """(n, K, k) the wrenches the chord tensions balance at the settled equilibrium (the
        module's fixed point, :meth:`settled_forces`), within the families' intervals and the
        taut floor; cached per family names."""
        key = tuple(f.name for f in families)
        cache = self.__dict__.setdefault("_balanced", {})
        if key in cache:
            return cache[key]
        lower, upper = self.intervals(families)
        size = np.maximum(np.linalg.norm(self.required_wrenches, axis=-1).max(), 1.0)
        pinv, rank = self.wrench_pinv
        weights = np.ones(lower.shape[-1])
        hanging = np.zeros(lower.shape)
        active = np.arange(len(self.positions))  # the poses whose forces still move
        for _ in range(MAX_SETTLING):  # least-norm by the faces alone (a pose without any: the clipped S^+ w')
            wrenches = self.shifted(hanging[active], active)
            tau, found = face_distribution(self.structure[active], wrenches, lower[active], upper[active], weights,
                                           rank[active], self.tension.residual_rtol)
            tau = np.where(found[..., None], tau, np.einsum("nmr,nkr->nkm", pinv[active], wrenches))
            moved = self.hanging(np.clip(tau, lower[active], upper[active]), active)
            change = np.abs(np.einsum("nrm,nkm->nkr", self.weight_columns[active], moved - hanging[active]))
            hanging[active] = moved
            active = active[change.max(axis=(1, 2)) > SETTLED_RTOL * size]
            if not len(active):
                break
        cache[key] = self.shifted(hanging)
        return cache[key]

    def settled_forces(self, families: list[Family]) -> np.ndarray:
        """(n, K, m) the chord tensions of the settled equilibrium (:meth:`balanced_wrenches`): the
        least-norm within the intervals (faces, then LPs and HiGHS's QP where they find none)."""
        lower, upper = self.intervals(families)
        tau = min_norm_tensions(self.structure, *self.wrench_pinv, self.balanced_wrenches(families),
                                [Family("bounds", lower, upper, np.ones(1))], np.ones(lower.shape[-1]),
                                self.tension.residual_rtol)
        return np.clip(np.nan_to_num(tau), lower, upper)

    def intervals(self, families: list[Family]) -> tuple[np.ndarray, np.ndarray]:
        """(n, K, m) the intersection of the families' intervals and the taut floor."""
        shape = (len(self.positions), np.shape(self.required_wrenches)[-2], self.robot.n_cables)
        lower = np.max([np.broadcast_to(self.taut_floor[:, None, :], shape),
                        *(np.broadcast_to(f.lower, shape) for f in families)], axis=0)
        upper = np.min([np.full(shape, np.inf), *(np.broadcast_to(f.upper, shape) for f in families)], axis=0)
        return lower, upper

    def shapes(self, tau: np.ndarray) -> dict[str, np.ndarray]:
        """(n, m) per quantity of the catenaries pulled with chord tensions tau (n, m): ``sag`` (m, the
        largest distance below the chord), ``angle_platform`` and ``angle_anchor`` (rad, the
        tangent's elevation leaving the platform and arriving at the anchor), ``unstrained`` (m,
        the unstrained length L0) and ``added_length`` (m, L0 minus the chord: what the winch pays
        out beyond a straight cable's length)."""
        cables = self.catenaries("chord_tension", tau[:, None, :])
        first, last = cables.angles
        found = {"sag": cables.sag, "angle_platform": first, "angle_anchor": last, "unstrained": cables.length,
                 "added_length": cables.length - cables.chord}
        return {name: np.where(cables.converged, value, np.nan)[:, 0, :] for name, value in found.items()}

    def diagnostics(self) -> dict[str, np.ndarray]:
        found = super().diagnostics()
        if self.catenary_undecided is not None:
            found.update(catenary_undecided=self.catenary_undecided, sag_max_ratio=self.sag_share,
                         added_length_max=self.added_length)
        return found

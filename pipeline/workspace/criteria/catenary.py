"""The criterion ``catenary`` (issue 55 item 3): the proof behind the verdict of a robot whose cables
sag (``robot.catenary``, ``pipeline.model.sagging``). The other criteria read the forces of the
settled equilibrium, a fixed point computed in floating point; this one proves the verdict or says
that it cannot, so that no tolerance calls a pose feasible. The intervals are every criterion's
and the taut floor's (``SaggingStatics.intervals``); the room is their capacity margin at the
settled wrench (one family, ``pipeline.model.tensions``).

*Feasible*, where the room is >= 0: tau_c, the chord tensions with the most room at the wrench
that the weight of the previous tau_c leaves (``CENTRING`` LPs from the settled wrench), and the
box X = tau_c +- delta inside the intervals (delta ``PROOF_SHARE`` of each, at most half its
room). Over X each cable's hanging force g (``SaggingStatics.hanging``) lies in [g_lo, g_hi], its
values at tau_c and at the box's ends widened by their second difference (a bound wherever g
keeps one curvature over the box, which tests/test_sagging.py checks of the catenary). If at
each of the 2^m corners G of that box of g some tau in X balances w + sum_i G_i q_i (the
``feasible`` model's margin >= 0 at every corner, and every corner in the range of the structure
matrix within ``tension.residual_rtol``, the straight model's own rule), then every G in the box
has one (the wrenches that X balances form a convex set); a continuous choice tau(G) makes
G -> g(tau(G)) a map of the box into itself, and Brouwer's fixed-point theorem gives an
equilibrium of catenaries with every tau in X.

*Infeasible*, where the room is < 0: a relaxation that holds every equilibrium has none, tau
within the intervals and each g within bounds that hold for every tau there
(:func:`hanging_bounds`), one LP with the g's as m more variables. The bounds read the catenary
at the intervals' ends: that a cable pulled harder is shorter and its ends' angles nearer its
chord's is the catenary's (checked on random cables in tests/test_sagging.py).

Margin 1 where feasibility is proven; where infeasibility is, the room (negative); -1 where
neither is (``catenary_undecided``, a per-pose column): such a pose is counted out, never in.
Where it is proven, the cables at the centre of the box (an equilibrium lies within +-1 % of
their chord tensions) give the per-pose columns ``sag_max_ratio`` (the largest sag, a share of its
chord) and ``added_length_max`` (m, the largest unstrained length beyond the chord)."""

from __future__ import annotations

from itertools import product

import numpy as np

from pipeline.model.linalg import batched_pinv
from pipeline.model.tensions import Family, feasible_tensions
from pipeline.workspace.criteria.registry import force_families

CENTRING = 3  # LPs for the centre, each at the wrench its previous one's weight share gives
PROOF_SHARE = 1e-2  # the box's half-width about the centre, a share of each chord tension (at most half its room)
DISPROVEN = 1e-6  # the least margin of a pose proven infeasible (a proof is not a tolerance's to snap)
PROOF_POSES = 64  # poses whose 2^m corners go to the feasible model at once (memory)


def catenary(state, limits) -> np.ndarray:
    """(n,) 1 where feasibility is proven, the room the settled wrench leaves (< 0) where
    infeasibility is, -1 where neither is (above)."""
    families = force_families(state, limits)
    lower, upper = state.intervals(families)  # every criterion's and the taut floor
    wrenches = state.balanced_wrenches(families)
    pinv, rank = state.wrench_pinv
    room = feasible_tensions(state.structure, pinv, rank, wrenches, [Family("centre", lower, upper, limits.scale)])[0]
    room = room["centre"]
    holds = np.flatnonzero(room >= 0)
    proven = np.zeros(len(room), dtype=bool)
    state.sag_share, state.added_length = np.full(len(room), np.nan), np.full(len(room), np.nan)
    if len(holds):
        centre = _centre(state, holds, wrenches[holds], lower[holds], upper[holds], limits.scale)
        for part in np.array_split(np.arange(len(holds)), -(-len(holds) // PROOF_POSES)):
            proven[holds[part]] = _proven(state, holds[part], centre[part], lower[holds[part]], upper[holds[part]])
        shown = proven[holds]  # the proven equilibria's cables, at the centre of their box
        cables = state.catenaries("chord_tension", centre[shown], holds[shown])
        state.sag_share[holds[shown]] = (cables.sag / cables.chord).max(axis=(1, 2))
        state.added_length[holds[shown]] = (cables.length - cables.chord).max(axis=(1, 2))
    disproven = np.zeros(len(room), dtype=bool)
    failing = np.flatnonzero(room < 0)
    if len(failing):
        disproven[failing] = _disproven(state, failing, lower[failing], upper[failing], limits.scale)
    state.catenary_undecided = ~(proven | disproven)
    return np.where(proven, 1.0, np.where(disproven, np.minimum(room, -DISPROVEN), -1.0))


def _centre(state, poses, wrenches, lower, upper, scale) -> np.ndarray:
    """(p, K, m) the chord tensions of the ``poses`` with the most room to every bound, the
    wrench moved by the weight's share of the last (``CENTRING`` LPs)."""
    structure, (pinv, rank) = state.structure[poses], (value[poses] for value in state.wrench_pinv)
    for _ in range(CENTRING):
        centre = feasible_tensions(structure, pinv, rank, wrenches, [Family("centre", lower, upper, scale)],
                                   distribution=True)[2]
        wrenches = state.shifted(state.hanging(np.clip(centre, lower, upper), poses), poses)
    return centre


def _proven(state, poses, tau, lower, upper) -> np.ndarray:
    """Whether Brouwer's argument (above) holds at each of ``poses`` about tau (p, K, m)."""
    room = np.minimum(tau - lower, upper - tau)
    delta = np.minimum(room / 2, PROOF_SHARE * np.maximum(tau, 1.0))
    first, last = tau - delta, tau + delta
    inside = (delta > 0).all(axis=(1, 2))
    if not inside.any():
        return inside
    ends = [state.hanging(value, poses) for value in (first, tau, last)]
    pad = np.abs(ends[0] + ends[2] - 2 * ends[1])
    low, high = np.min(ends, axis=0) - pad, np.max(ends, axis=0) + pad
    corners = np.array(list(product((False, True), repeat=tau.shape[2])))  # (2^m, m)
    hanging = np.where(corners[None, None], high[:, :, None], low[:, :, None])  # (p, K, 2^m, m)
    columns = state.weight_columns[poses]
    required = np.broadcast_to(state.required_wrenches, (len(poses), *state.required_wrenches.shape[-2:]))
    wrenches = required[:, :, None, :] + np.einsum("prm,pkcm->pkcr", columns, hanging)
    flat = wrenches.reshape(len(poses), -1, wrenches.shape[-1])
    box = Family("proof", np.repeat(first, len(corners), axis=1), np.repeat(last, len(corners), axis=1),
                 np.repeat(delta, len(corners), axis=1))
    pinv, rank = (value[poses] for value in state.wrench_pinv)
    margin, residual, _, _ = feasible_tensions(state.structure[poses], pinv, rank, flat, [box])
    return inside & (margin["proof"] >= 0) & (residual <= state.tension.residual_rtol)  # every corner in reach


def _disproven(state, poses, lower, upper, scale) -> np.ndarray:
    """Whether the relaxation (above) has no equilibrium at each of ``poses``."""
    low, high = hanging_bounds(state, poses, lower, upper)
    structure = np.concatenate([state.structure[poses], -state.weight_columns[poses]], axis=2)
    pinv, rank = batched_pinv(structure, state.spec.rank_rtol)
    outer = Family("outer", np.concatenate([lower, low], axis=2), np.concatenate([upper, high], axis=2), scale)
    required = np.broadcast_to(state.required_wrenches, (len(poses), *state.required_wrenches.shape[-2:]))
    return feasible_tensions(structure, pinv, rank, required, [outer])[0]["outer"] < 0


def hanging_bounds(state, poses, lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """(p, K, m) bounds on g over every chord tension in [lower, upper]: g = -W (1 - x_c / a), W =
    w L0 between the cable's weight pulled hardest and least, x_c the centroid of its weight along
    the span, whose density per level metre w sec(theta) / (1 + T / EA) varies by at most a factor
    r (slopes between the end angles of the cable pulled least, tensions up to the top tension
    pulled hardest): a density within a factor r puts the centroid between a / (1 + sqrt r) and
    a sqrt(r) / (1 + sqrt r) (the extreme densities are two steps meeting at the centroid)."""
    slack = state.catenaries("chord_tension", lower, poses)  # the longest cable, the steepest ends
    taut = state.catenaries("chord_tension", np.where(np.isfinite(upper), upper, 1.0), poses)
    weight = np.broadcast_to(state.weight, lower.shape)
    heaviest = np.where(slack.converged, weight * slack.length, np.inf)
    inextensible = np.isinf(np.broadcast_to(state.ea, lower.shape))
    lightest = np.where(np.isfinite(upper) & taut.converged, weight * taut.length,
                        np.where(inextensible, weight * slack.chord, 0.0))
    first, last = slack.angles
    steepest = np.maximum(np.abs(first), np.abs(last))
    flattest = np.where((first <= 0) & (last >= 0), 0.0, np.minimum(np.abs(first), np.abs(last)))
    top = np.where(np.isfinite(upper) & taut.converged, taut.top_tension, np.inf)
    with np.errstate(all="ignore"):
        ratio = np.cos(flattest) / np.cos(steepest) * (1.0 + np.where(inextensible, 0.0, top / state.ea))
        root = np.sqrt(np.where(slack.converged & np.isfinite(ratio) & (ratio > 0), ratio, np.inf))
        far, near = np.where(np.isfinite(root), root / (1 + root), 1.0), np.where(np.isfinite(root), 1 / (1 + root), 0.0)
    return -heaviest * far, -np.where(np.isfinite(heaviest), lightest, 0.0) * near

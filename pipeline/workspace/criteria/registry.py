"""The registry the criteria enter (``pipeline.workspace.criteria`` fills it with the package's own,
:func:`register` adds one from outside), kept apart from the criteria's modules so that any of
them, and the ``feasible`` model's, can read it: a :class:`Criterion` per name, the colours of the
figures, and the intervals the registered criteria put on the cable forces (:func:`force_families`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from pipeline.model.tensions import Family

ANY, DYNAMICS, STATICS, GEOMETRY = "any", "dynamics", "statics", "geometry"


@dataclass(frozen=True)
class Criterion:
    """``function(state, limits) -> (n,) margins``; ``reads``: ``any``, ``dynamics`` (a
    ``PoseDynamics`` and an ``ActuatorModel``), ``statics`` (a ``PoseStatics`` and
    ``StaticLimits``) or ``geometry`` (the pose alone: any ``PoseGeometry``, one code in
    every kernel); ``gate``: priority among gates (0 first) or None; ``colour``: figures;
    ``remedy``: what to try next when it limits every pose (a job with none feasible says it);
    ``applies(analysis, spec, robot)``: whether a problem of ``analysis`` (cpr_wwa, lines,
    statics, payload) with that per-chunk spec and robot checks it; ``keys``: its own config
    keys ``criteria.<name>.<key>``, each with the rule its value must pass (a check as in
    ``pipeline.app.config``: None, or what the value must be), given to ``function`` as keyword
    arguments. A criterion with keys is checked where the config gives them (null: not checked).
    ``bounds(state, limits) -> (lower, upper, scale) | None``: the interval it puts on every
    cable's force variable (``state.variables_of``; arrays broadcastable to (n, K, m)) under the
    ``feasible`` tension model, None where it puts none on that state; there its margin is the
    model's nested capacity margin of that interval (``criteria.forces``), and ``function``
    gives the minimum-norm model's. ``refuses(spec, robot, keys)``: why a problem cannot evaluate it
    with the keys given (one line: the job is refused before it runs), None when it can.
    ``certified``: whether ``analysis=certified`` proves it on boxes of poses
    (``pipeline.model.certificates``, or ``boxes``); a certified problem that checks a criterion without one
    is refused. ``boxes(robot, within, nominal, lo, hi, centre, atol) -> (N,)``: its own verdicts on boxes
    of positions (1 inside, -1 outside, 0 undecided), from the enclosures ``within`` the tolerances
    (inside) and ``nominal`` (outside) (``pipeline.model.certificates.BoxStatics``)."""

    name: str
    function: Callable[[Any, Any], np.ndarray]
    reads: str
    gate: int | None
    colour: str
    remedy: str
    applies: Callable[[str, Any, Any], bool]
    keys: dict[str, Callable[[Any], str | None]] = field(default_factory=dict)
    bounds: Callable[[Any, Any], tuple | None] | None = None
    refuses: Callable[[Any, Any, dict], str | None] | None = None
    certified: bool = False
    boxes: Callable[..., np.ndarray] | None = None


REGISTRY: dict[str, Criterion] = {}
COLOURS: dict[str, str] = {}


def register(criterion: Criterion) -> None:
    """Add ``criterion`` to the registry (after the package's own, a name of its own): from then
    on every problem it applies to checks it, every kernel evaluates it, figures colour it."""
    if criterion.name in REGISTRY:
        raise ValueError(f"criterion {criterion.name!r} is already registered")
    REGISTRY[criterion.name] = criterion
    COLOURS[criterion.name] = criterion.colour


def force_families(state, limits) -> list[Family]:
    """The intervals on the state's force variables under the ``feasible`` model, one
    :class:`Family` per registered criterion that bounds this kind of state (``Criterion.bounds``;
    registry order, which nests them: an earlier family does its best first); one with keys of its
    own where the problem gives them (``TensionSpec.bounded``), given them as keyword arguments."""
    found = []
    for criterion in REGISTRY.values():
        if criterion.bounds is None or (criterion.reads != ANY and criterion.reads not in state.kinds):
            continue
        if criterion.keys and criterion.name not in state.tension.bounded:
            continue  # its keys are not given: not checked
        interval = criterion.bounds(state, limits, **state.tension.bounded.get(criterion.name, {}))
        if interval is not None:
            found.append(Family(criterion.name, *interval))
    return found

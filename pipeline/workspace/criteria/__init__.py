"""Workspace criteria, first-class: each maps a chunk of poses to a relative margin per pose
(>= 0 satisfied, comparable across criteria) and is one entry of :data:`REGISTRY`.

A :class:`Criterion` says what it reads (``reads``: the CPR-WWA dynamics, the statics, or any
chunk state), whether it is a gate (a violated gate decides the verdict whatever the other
margins say; gates in priority order) and its colour in every figure. One module per family:
``actuator`` (eqs. 30, 32-34 of the CPR-8 paper), ``tension`` (unreachable, slack, tension
rating), ``geometry`` (zero_length, singular, cable length), ``payload`` (the largest payload); ``forces``
holds the ``feasible`` tension model they share. A new criterion is one function in its family's module and one entry here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from pipeline.workspace.criteria import actuator, geometry, payload, tension

ANY, DYNAMICS, STATICS = "any", "dynamics", "statics"


@dataclass(frozen=True)
class Criterion:
    """``function(state, limits) -> (n,) margins``; ``reads``: ``any``, ``dynamics`` (a
    ``PoseDynamics`` and an ``ActuatorModel``) or ``statics`` (a ``PoseStatics`` and
    ``StaticLimits``); ``gate``: priority among gates (0 first) or None; ``colour``: figures."""

    name: str
    function: Callable[[Any, Any], np.ndarray]
    reads: str
    gate: int | None
    colour: str


REGISTRY: dict[str, Criterion] = {c.name: c for c in (
    Criterion("zero_length", geometry.zero_length, ANY, 0, "#999933"),
    Criterion("singular", geometry.singular, STATICS, 1, "#000000"),
    Criterion("unreachable", tension.unreachable, ANY, 2, "#777777"),
    Criterion("slack", tension.slack, ANY, 3, "#882255"),
    Criterion("tension_max", tension.tension_max, ANY, None, "#0072B2"),
    Criterion("length", geometry.length, ANY, None, "#CC79A7"),
    Criterion("payload", payload.payload, STATICS, None, "#56B4E9"),
    Criterion("speed", actuator.speed, DYNAMICS, None, "#0072B2"),
    Criterion("torque", actuator.torque, DYNAMICS, None, "#D55E00"),
    Criterion("acceleration", actuator.acceleration, DYNAMICS, None, "#CC79A7"),
    Criterion("voltage", actuator.voltage, DYNAMICS, None, "#E69F00"),
)}
GATES = tuple(sorted((c.name for c in REGISTRY.values() if c.gate is not None),
                     key=lambda name: REGISTRY[name].gate))
COLOURS = {c.name: c.colour for c in REGISTRY.values()}
FEASIBLE_COLOUR = "#009E73"  # feasible points and shares, in every figure and view

"""Workspace criteria, first-class: each maps a chunk of poses to a relative margin per pose
(>= 0 satisfied, comparable across criteria) and is one entry of :data:`REGISTRY`.

A :class:`Criterion` says what it reads (``reads``: the CPR-WWA dynamics, the statics, or any
chunk state), whether it is a gate (a violated gate decides the verdict whatever the other
margins say; gates in priority order) and its colour in every figure. One module per family:
``actuator`` (eqs. 30, 32-34 of the CPR-8 paper), ``tension`` (unreachable, slack, tension
rating), ``geometry`` (zero_length, singular, cable length), ``interference`` (cable_cable,
cable_platform, cable_obstacle),
``payload`` (the largest payload), ``sag`` and ``catenary`` (heavy cables); ``forces``
holds the ``feasible`` tension model they share. A criterion also says when it applies
(``applies``: a predicate on the analysis, its spec and the robot), and :func:`selected` gives a
problem its criteria from the registry, in registry order (gates first). A new criterion is one
function in its family's module and one entry here, or, from outside the package, one
:func:`register` call: every analysis it applies to evaluates it (a ``geometry`` criterion in
every kernel and on the lines; ``tests/test_registry.py`` registers one).
"""

from __future__ import annotations

import numpy as np

from pipeline.workspace.criteria import actuator, catenary, geometry, interference, payload, sag, stiffness, tension
from pipeline.workspace.criteria.forces import feasible_margins, feasible_model
from pipeline.workspace.criteria.registry import (ANY, COLOURS, DYNAMICS, GEOMETRY, REGISTRY, STATICS, Criterion,
                                                  force_families, register)

__all__ = ["ANY", "COLOURS", "DYNAMICS", "GEOMETRY", "REGISTRY", "STATICS", "Criterion", "checked_settings",
           "force_families", "gates", "margins", "register", "selected"]
# the names other modules refer a criterion by (a kernel's compiled columns, the degeneracy notes,
# the papers' evidence): spelled here only
ZERO_LENGTH, SINGULAR, UNREACHABLE, SLACK, TENSION_MAX = "zero_length", "singular", "unreachable", "slack", "tension_max"
LENGTH, SPEED, TORQUE, ACCELERATION, VOLTAGE = "length", "speed", "torque", "acceleration", "voltage"
CATENARY, CABLE_OBSTACLE = "catenary", "cable_obstacle"


def _dynamics(analysis: str, spec=None, robot=None) -> bool:
    """Whether the analysis moves the carrier (CPR-WWA, on the grid or on lines)."""
    return analysis in ("cpr_wwa", "lines")


def _driven(analysis: str, spec, robot=None) -> bool:
    """Whether a catalogue actuator drives the cables: CPR-WWA's, or a static pose's or a path's
    with ``actuator`` (``StaticsSpec.winch_radius``); the actuator's criteria apply to exactly these."""
    return _dynamics(analysis) or (analysis in ("statics", "trajectory") and spec.winch_radius is not None)


# the analyses whose cables hold the platform's load: at a pose, along a path, over a box of poses
HELD = ("statics", "trajectory", "certified")


def _straight_heavy(analysis: str, spec, robot) -> bool:
    """Heavy straight cables (``robot.cable_mass`` without ``robot.catenary``): the rules of
    ``criteria.sag`` other than the sag itself apply to them."""
    return analysis in (*HELD, "cpr_wwa", "lines") and robot.cable_mass is not None and robot.catenary is None


def _feasible(spec) -> bool:
    return spec.tension.model == "feasible"


for criterion in (
    Criterion(ZERO_LENGTH, geometry.zero_length, ANY, 0, "#999933",
              "a search box that does not reach the anchors (robot.search.lo, hi)",
              lambda analysis, spec, robot: True, certified=True),
    Criterion(SINGULAR, geometry.singular, STATICS, 1, "#000000",
              "robot.dofs=[x,y,z] for a point platform (every attachment at one point), else anchors and "
              "attachments that give the cables independent directions (the log names the wrench they cannot "
              "produce), or tension=feasible",
              lambda analysis, spec, robot: analysis in (*HELD, "payload") and not _feasible(spec), certified=True),
    Criterion(UNREACHABLE, tension.unreachable, ANY, 2, "#777777",
              "anchors and attachments that give the cables independent directions (the log names the "
              "wrench they cannot produce), or more cables",
              lambda analysis, spec, robot: _dynamics(analysis) or (analysis in HELD and _feasible(spec)), certified=True),
    Criterion(SLACK, tension.slack, ANY, 3, "#882255",
              "under tension=pinv, tension=feasible if the cables may not push (minimum-norm forces often do); "
              "else a lower tension.t_min, more cables or anchors around the load",
              lambda analysis, spec, robot: analysis in HELD or (_dynamics(analysis) and _feasible(spec)),
              bounds=tension.slack_bounds, certified=True),
    Criterion(TENSION_MAX, tension.tension_max, ANY, None, "#0072B2",
              "stronger cables (a higher tension.t_max) or a lighter load",
              lambda analysis, spec, robot: analysis != "payload" and spec.tension.t_max is not None,
              bounds=tension.tension_max_bounds, certified=True),
    Criterion("payload", payload.payload, STATICS, None, "#56B4E9", "a lighter payload (load.mass) or stronger cables",
              lambda analysis, spec, robot: analysis == "payload"),
    Criterion(LENGTH, geometry.length, ANY, None, "#CC79A7", "longer cables (robot.l_max) or a smaller box",
              lambda analysis, spec, robot: robot.l_max is not None, certified=True),
    Criterion(SPEED, actuator.speed, DYNAMICS, None, "#0072B2",
              "a lower motion.v_max (on a path: longer trajectory.times), a larger drive.winch_radius or a smaller "
              "drive.gear_ratio",
              _driven),
    Criterion(TORQUE, actuator.torque, DYNAMICS, None, "#D55E00",
              "a stronger actuator, a higher drive.gear_ratio or a smaller drive.winch_radius",
              _driven, bounds=actuator.torque_bounds),
    Criterion(ACCELERATION, actuator.acceleration, DYNAMICS, None, "#CC79A7",
              "longer motion.t_acc and motion.t_dec (on a path: longer trajectory.times), or a larger drive.winch_radius",
              _driven),
    Criterion(VOLTAGE, actuator.voltage, DYNAMICS, None, "#E69F00",
              "a lower motion.v_max (on a path: longer trajectory.times) or another actuator (its voltage and speed "
              "constants)",
              _driven, bounds=lambda dyn, act: dyn.voltage_bounds(act)),
    Criterion("cable_cable", interference.cable_cable, GEOMETRY, None, "#DDCC77",
              "thinner cables (robot.cable_diameter), anchors and attachments that keep the cables apart, "
              "or a smaller box",
              lambda analysis, spec, robot: robot.cable_radii is not None, certified=True,
              boxes=interference.cable_cable_boxes),
    Criterion("cable_platform", interference.cable_platform, GEOMETRY, None, "#332288",
              "attachments on the platform's outer corners or edges, a platform shape that holds them on its "
              "surface (robot.platform.shape), or a smaller box",
              lambda analysis, spec, robot: robot.platform_shape is not None, certified=True,
              boxes=interference.cable_platform_boxes),
    Criterion(CABLE_OBSTACLE, interference.cable_obstacle, GEOMETRY, None, "#994F00",
              "anchors that route the cables around the obstacles, a smaller box, or obstacles moved",
              lambda analysis, spec, robot: bool(robot.obstacles), certified=True,
              boxes=interference.cable_obstacle_boxes),
    Criterion("stiffness", stiffness.stiffness, STATICS, None, "#44AA99",
              "stiffer cables (robot.cable_ea), shorter cable to the winches (robot.winch_length), more "
              "pretension (a higher tension.t_min) or anchors around the pose",
              lambda analysis, spec, robot: (analysis in HELD and robot.cable_ea is not None and robot.pulleys is None
                                             and robot.catenary is None),
              keys={"translational": stiffness.required, "rotational": stiffness.required,
                    "frequency": stiffness.required}, refuses=stiffness.refuses),
    Criterion("sag", sag.sag, ANY, None, "#88CCEE",
              "more pretension (a higher tension.t_min), lighter cables (robot.cable_mass) or a larger sag allowed",
              lambda analysis, spec, robot: analysis in (*HELD, "cpr_wwa", "lines") and robot.cable_mass is not None,
              keys={"ratio": sag.ratio}, bounds=sag.sag_bounds),
    Criterion("cable_contraction", sag.contraction, ANY, None, "#117733",
              "more pretension (a higher tension.t_min), lighter cables (robot.cable_mass) or more cable allowed",
              _straight_heavy, keys={"share": sag.share}, bounds=sag.contraction_bounds),
    Criterion("cable_frequency", sag.frequency, ANY, None, "#999999",
              "more pretension (a higher tension.t_min), lighter or shorter cables, or a lower frequency required",
              _straight_heavy, keys={"hz": sag.hertz}, bounds=sag.frequency_bounds),
    Criterion(CATENARY, catenary.catenary, STATICS, None, "#AA4499",
              "a pose on the workspace's boundary, where the proof cannot decide: a finer grid shows it; or "
              "more pretension (a higher tension.t_min)",
              lambda analysis, spec, robot: analysis == "statics" and robot.catenary is not None),
):
    register(criterion)


def gates() -> tuple[str, ...]:
    """The gates in priority order: a violated gate decides the verdict (the first listed wins)."""
    return tuple(sorted((c.name for c in REGISTRY.values() if c.gate is not None), key=lambda name: REGISTRY[name].gate))


def selected(analysis: str, spec, robot, settings: dict | None = None) -> tuple[str, ...]:
    """The criteria a problem of ``analysis`` with ``spec``, ``robot`` and the criteria's own keys
    (``settings``, :func:`checked_settings`) checks, in registry order."""
    settings = settings or {}
    return tuple(c.name for c in REGISTRY.values()
                 if c.applies(analysis, spec, robot) and (not c.keys or c.name in settings))


def checked_settings(node) -> dict[str, dict]:
    """The criteria's own keys of a config's ``criteria`` node (plain containers), each value
    checked by the rule its criterion declares beside it: ``{name: {key: value}}``, without the
    criteria whose keys are null (not checked). ConfigError in one line for a name no criterion
    with keys has, a key it does not declare or misses, or a value its rule refuses."""
    from pipeline.errors import ConfigError

    if not isinstance(node, dict):
        raise ConfigError(f"criteria={node}: a mapping of criterion names to their keys, {{name: {{key: value}}}}")
    settings = {}
    for name, given in node.items():
        criterion = REGISTRY.get(name)
        if criterion is None or not criterion.keys:
            with_keys = ", ".join(c.name for c in REGISTRY.values() if c.keys) or "none is registered"
            raise ConfigError(f"criteria.{name}: no criterion with keys of its own is called that ({with_keys})")
        if not isinstance(given, dict) or set(given) != set(criterion.keys):
            raise ConfigError(f"criteria.{name}={given}: its keys are {', '.join(criterion.keys)}")
        for key, check in criterion.keys.items():
            try:
                broken = None if given[key] is None else check(given[key])
            except TypeError:
                broken = "not a value this key takes"
            if broken:
                raise ConfigError(f"criteria.{name}.{key}={given[key]}: {broken}")
        if all(value is not None for value in given.values()):
            settings[name] = dict(given)
    return settings


def margins(names, state, limits, settings: dict | None = None) -> dict[str, np.ndarray]:
    """The one evaluation every analysis and kernel goes through: criterion name -> (n,) margins
    of the chunk ``state`` (a grid chunk's, a trajectory's samples') against ``limits``, each
    criterion given its own keys (``settings``); under the ``feasible`` tension model a criterion
    that bounds the forces (``Criterion.bounds``) reads the model's margin of its family."""
    settings = settings or {}
    bounds = any(REGISTRY[name].bounds for name in names)  # a geometric state has no tension model
    bounded = feasible_margins(state, limits, force_families(state, limits)) if bounds and feasible_model(state) else {}
    return {name: bounded[name] if name in bounded else REGISTRY[name].function(state, limits, **settings.get(name, {}))
            for name in names}


FEASIBLE_COLOUR = "#009E73"  # feasible points and shares, in every figure and view

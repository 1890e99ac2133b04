"""Layout synthesis (a study's ``layout`` block, issue 58): where to put the anchors (and the
attachments) of a ``points`` robot so that its workspace is largest.

The study's overrides build one problem (its robot, analysis, tensions, load and grid), planned
and checked as ``python -m pipeline`` would. Each trial moves the anchors inside the
installation box (``anchors``) and, when ``attachments`` is given, the attachments inside the
platform's box, and counts the grid's feasible poses in this process
(:func:`pipeline.workspace.feasibility.feasible_flags`: the exact verdict of every pose, by the
null-space test where it applies; no Hydra composition, no process per trial), on
``n_jobs`` worker threads (the compiled test and numpy release the GIL: one process's
memory), a batch of trials at a time (Optuna's ask and tell, seeded). With
``symmetry: quadrants`` the frame's mirror planes x = 0 and y = 0 hold: the robot's cables come
in fours, (-x, +y), (+x, +y), (+x, -y), (-x, -y) (IPAnema 1's order), and each four is one
designed anchor in the quarter x, y >= 0 and one designed attachment, mirrored with it. With
``anchors_on: faces`` or ``edges`` the anchors stay on the installation box's faces (a frame's walls,
ceiling and floor) or edges (its posts and beams): each designed anchor is a face or edge (a
categorical variable) and a place on it; with ``frame_scale`` the frame's size is designed too (each of its
sides a share of the installation box's: :meth:`LayoutSpec.frame`), the anchors on the smaller frame's
faces or edges. With ``refine`` the last share of the budget steps around
the best trial so far (:class:`Steps`, a (1+1) evolution strategy): a sampler over many variables
finds the region, the steps climb its ridge (on IPAnema 1's frame TPE alone found 10.58 m^3 in 400
trials, with three quarters of them refining 10.94).

Objectives (:data:`OBJECTIVES`): ``volume_m3`` (the feasible poses' cells), ``feasible_pct``,
``longest_cable_m`` (the longest cable over the feasible poses: the drum a design needs) and
``payload_kg`` (:func:`largest_payload`: the largest mass added to the load with which every
grid pose of the required box still holds), ``tension_factor`` (:func:`least_tension_factor`: Pham et
al.'s tension factor, ``output.metrics``' column, least over the required box's grid poses: how
evenly the cables can be tensed where the robot must work) and ``frame_m3`` (the volume of the
anchors' bounding box: the frame a layout needs, so that a two-objective search trades workspace
for frame) and ``actuator_cost`` (:func:`cheapest_drive`: the cheapest actuator of the layout's
``catalogue``, by its ``cost`` column, that holds the required box at rest, times the cables).
A ``required`` box of positions must be feasible at
every grid pose inside it (a constraint; the grid's verdicts, not a certificate). With ``step``
the variables lie on a lattice, and a lattice no larger than the budget is searched exhaustively
(every layout once, in order), so its best is the best. The best trial is then run again as an
ordinary job (``jobs/best``), whose count must equal the search's, and written as a robot file
the user runs (``layout_best.yaml``).
"""

from __future__ import annotations

import logging
import math
from itertools import combinations, product
from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np
import pandas as pd

from pipeline.app.config import rule, sampler_seed
from pipeline.errors import ConfigError, require

log = logging.getLogger("pipeline.study")
SAMPLERS = ("tpe", "nsga2")
SYMMETRIES = ("none", "quadrants")
PLACES = ("box", "faces", "edges")
QUADRANTS = np.array([[-1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [-1.0, -1.0, 1.0]])  # IPAnema 1's order
OBJECTIVES = {"volume_m3": ("maximize", "feasible volume (m^3)"),
              "feasible_pct": ("maximize", "feasible share of the grid (%)"),
              "longest_cable_m": ("minimize", "longest cable over the feasible poses (m)"),
              "payload_kg": ("maximize", "largest payload the required box holds (kg)"),
              "tension_factor": ("maximize", "least tension factor over the required box"),
              "frame_m3": ("minimize", "the anchors' bounding box (m^3)"),
              "actuator_cost": ("minimize", "the cheapest catalogue actuators that hold the required box")}
# objective -> (what it is of the required box, what it asks of the statics, whether at rest)
NEEDS = {"payload_kg": ("is the largest payload the required box holds", "adds mass to a platform at rest", True),
         "tension_factor": ("is the least over the required box", "is of a static pose's structure matrix", False),
         "actuator_cost": ("is the cheapest catalogue actuator that holds the required box", "holds a platform at rest",
                           True)}
PAYLOAD_RTOL = 1e-6  # the largest payload, bisected to this share of itself
PAYLOAD_MAX = 1e9  # kg: past it the payload is taken as unbounded (cables without an upper limit)
AXES = "xyz"


@dataclass
class Box:
    """An axis-aligned box, ``lo`` <= ``hi`` (3 numbers each, m)."""

    lo: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    hi: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])

    def check(self, where: str) -> None:
        for name in ("lo", "hi"):
            value = getattr(self, name)
            if len(value) != 3 or not all(math.isfinite(v) and abs(v) <= 1e4 for v in value):
                raise ConfigError(f"{where}.{name}={value}: three finite coordinates (m, at most 1e4)")
        if any(lo > hi for lo, hi in zip(self.lo, self.hi)):
            raise ConfigError(f"{where}: lo={self.lo} exceeds hi={self.hi}")

    def contains(self, points: np.ndarray) -> np.ndarray:
        return np.all((points >= np.asarray(self.lo) - 1e-12) & (points <= np.asarray(self.hi) + 1e-12), axis=-1)


@dataclass
class LayoutSpec:
    """``anchors``: the installation box every anchor stays in; ``attachments``: the platform's
    box the attachments stay in (None: the robot's attachments kept); ``symmetry``: ``none`` or
    ``quadrants`` (see the module); ``step``: the variables' lattice (m; None: continuous);
    ``objectives``: one or two of :data:`OBJECTIVES`; ``required``: a box of positions that
    must be feasible (None: none); ``budget``: trials; ``seed``; ``sampler``: ``tpe`` (one
    objective) or ``nsga2``; ``anchors_on``: ``box`` (anywhere in the installation box),
    ``faces`` (on its faces: a frame's walls, ceiling and floor; a planar robot's: the rectangle's
    sides) or ``edges`` (on its edges: a frame's posts and beams; a planar robot's: its corners);
    ``refine``: the share of the budget spent last around the best trial so far (:func:`nearby`);
    ``catalogue`` (a CSV; None: the shipped Table 1) and ``cost`` (its column that prices one
    actuator) for the objective ``actuator_cost``; ``frame_scale`` ([lo, hi], with anchors on faces or
    edges; None: the installation box is the frame): each side of the frame a variable share in
    [lo, hi] of the installation box's side (:meth:`frame`)."""

    anchors: Box = field(default_factory=Box)
    attachments: Optional[Box] = None
    symmetry: str = "none"
    step: Optional[float] = None
    objectives: list[str] = field(default_factory=lambda: ["volume_m3"])
    required: Optional[Box] = None
    budget: int = 200
    seed: int = rule(sampler_seed, default=0)
    sampler: str = "tpe"
    anchors_on: str = "box"
    refine: float = 0.0
    catalogue: Optional[str] = None
    cost: Optional[str] = None
    frame_scale: Optional[list[float]] = None

    def check_across(self, where: str) -> None:
        """ConfigError naming the first field that cannot be used."""
        where = f"{where}: layout"
        for name in ("anchors", "attachments", "required"):
            if getattr(self, name) is not None:
                getattr(self, name).check(f"{where}.{name}")
        if self.symmetry not in SYMMETRIES:
            raise ConfigError(f"{where}.symmetry={self.symmetry!r}: one of {', '.join(SYMMETRIES)}")
        if self.symmetry == "quadrants":
            for name in ("anchors", "attachments"):
                box = getattr(self, name)
                if box is not None and (box.lo[0] != -box.hi[0] or box.lo[1] != -box.hi[1]):
                    raise ConfigError(f"{where}.{name}: symmetry=quadrants mirrors x and y: the box must be "
                                      f"symmetric about x = 0 and y = 0 (lo={box.lo}, hi={box.hi})")
        if not 0.0 <= self.refine < 1.0:
            raise ConfigError(f"{where}.refine={self.refine}: a share of the budget in [0, 1)")
        if self.refine and self.step is not None:
            raise ConfigError(f"{where}.refine={self.refine}: a lattice (step={self.step}) is searched by its sampler "
                              "or whole; refine takes continuous variables")
        if self.anchors_on not in PLACES:
            raise ConfigError(f"{where}.anchors_on={self.anchors_on!r}: one of {', '.join(PLACES)}")
        if self.anchors_on != "box" and self.step is not None:
            raise ConfigError(f"{where}.step={self.step}: a lattice of the box's coordinates; anchors on its "
                              f"{self.anchors_on} are continuous (step: null)")
        if self.anchors_on != "box" and not self.pieces():
            raise ConfigError(f"{where}.anchors_on={self.anchors_on}: the box {self.anchors.lo}..{self.anchors.hi} has no "
                              f"{self.anchors_on}")
        if self.step is not None:
            if not (math.isfinite(self.step) and self.step > 0):
                raise ConfigError(f"{where}.step={self.step}: a positive length (m), or null (continuous)")
            for name, (lo, hi) in self.ranges().items():
                if abs((hi - lo) / self.step - round((hi - lo) / self.step)) > 1e-9:
                    raise ConfigError(f"{where}.step={self.step}: {name} spans [{lo}, {hi}], not a whole number of steps")
        unknown = [o for o in self.objectives if o not in OBJECTIVES]
        if unknown or not 1 <= len(self.objectives) <= 2 or len(set(self.objectives)) < len(self.objectives):
            raise ConfigError(f"{where}.objectives={self.objectives}: one or two of {', '.join(OBJECTIVES)}")
        if not 0 < self.budget <= 100_000:
            raise ConfigError(f"{where}.budget={self.budget}: must be in [1, 100000]")
        if self.sampler not in SAMPLERS:
            raise ConfigError(f"{where}.sampler={self.sampler!r}: one of {', '.join(SAMPLERS)}")
        if ("actuator_cost" in self.objectives) != (self.cost is not None):
            raise ConfigError(f"{where}.cost={self.cost}: objective actuator_cost prices the cheapest catalogue actuator "
                              "that holds the required box by a column of the catalogue: give both, or neither")
        if self.catalogue is not None and self.cost is None:
            raise ConfigError(f"{where}.catalogue={self.catalogue}: read for objective actuator_cost only")
        if self.frame_scale is not None:
            scale = self.frame_scale
            if len(scale) != 2 or not all(math.isfinite(v) for v in scale) or not 0 < scale[0] <= scale[1] <= 1:
                raise ConfigError(f"{where}.frame_scale={scale}: [lo, hi], each side of the frame a share of the "
                                  "installation box's, 0 < lo <= hi <= 1")
            if self.anchors_on == "box":
                raise ConfigError(f"{where}.frame_scale={scale}: sizes the frame whose faces or edges hold the anchors "
                                  "(anchors_on: faces or edges); anchors anywhere in the box choose their frame already")

    def designed_cables(self, n_cables: int) -> range:
        """The cables whose points are variables (all; with quadrants the second of each four)."""
        return range(1, n_cables, 4) if self.symmetry == "quadrants" else range(n_cables)

    def anchor_box(self) -> tuple[np.ndarray, np.ndarray]:
        """Where a designed anchor may be: the installation box, with quadrants its quarter x, y >= 0
        (the mirror images cover the rest)."""
        lo, hi = np.array(self.anchors.lo, dtype=float), np.array(self.anchors.hi, dtype=float)
        if self.symmetry == "quadrants":
            lo[:2] = 0.0
        return lo, hi

    def pieces(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The faces or edges of the installation box a designed anchor may be on, each as its
        origin (3,) and its spans (3, k): the point origin + spans @ p for p in [0, 1]^k. Faces hold
        one of the box's own axes at a bound, edges two (a flat axis is not counted: a planar
        robot's faces are its rectangle's sides); with quadrants only the quarter's parts that lie on
        the box's boundary (not on the mirror planes)."""
        lo, hi = self.anchor_box()
        spread = [axis for axis in range(3) if self.anchors.hi[axis] > self.anchors.lo[axis]]
        fixed_count = 1 if self.anchors_on == "faces" else 2
        found = []
        for fixed in combinations(spread, fixed_count):
            for bounds in product(*[[(axis, self.anchors.lo[axis]), (axis, self.anchors.hi[axis])] for axis in fixed]):
                if any(not lo[axis] <= value <= hi[axis] for axis, value in bounds):
                    continue  # a bound outside the quarter: its mirror image is one of the quarter's
                origin = lo.copy()
                for axis, value in bounds:
                    origin[axis] = value
                free = [axis for axis in spread if axis not in fixed]
                spans = np.zeros((3, len(free)))
                for column, axis in enumerate(free):
                    spans[axis, column] = hi[axis] - lo[axis]
                found.append((origin, spans))
        return found

    def frame_axes(self) -> list[int]:
        """The axes along which ``frame_scale`` sizes the frame (``frame_x``, ...): the installation
        box's axes that are not flat."""
        if self.frame_scale is None:
            return []
        return [axis for axis in range(3) if self.anchors.hi[axis] > self.anchors.lo[axis]]

    def frame(self, up: np.ndarray, values: dict) -> tuple[np.ndarray, np.ndarray]:
        """The frame of a trial's ``values`` as the point it is scaled about and its scale (3,) each:
        a placed anchor q on the installation box's faces or edges moves to pivot + scale (q - pivot),
        on the frame's. The frame stands where the box does: centred in it, and on its floor along
        the robot's ``up`` when that is a coordinate axis (a frame on the ground grows upwards)."""
        lo, hi = np.array(self.anchors.lo, dtype=float), np.array(self.anchors.hi, dtype=float)
        pivot, scale = (lo + hi) / 2, np.ones(3)
        vertical = np.flatnonzero(np.abs(up) == 1.0)
        if len(vertical):
            axis = int(vertical[0])
            pivot[axis] = lo[axis] if up[axis] > 0 else hi[axis]
        for axis in self.frame_axes():
            scale[axis] = values[f"frame_{AXES[axis]}"]
        return pivot, scale

    def ranges(self, n_cables: int = 4) -> dict[str, tuple[float, float]]:
        """Each continuous design variable's range, for every designed cable c: ``anchor{c}_{axis}``
        (m; with anchors on faces or edges ``anchor{c}_p1``, ``_p2`` in [0, 1], along the piece
        :meth:`choices` picks), and ``attachment{c}_{axis}`` (m); with ``frame_scale`` the frame's
        sides ``frame_{axis}`` (shares of the installation box's, :meth:`frame`)."""
        found = {f"frame_{AXES[axis]}": (float(self.frame_scale[0]), float(self.frame_scale[1]))
                 for axis in self.frame_axes()}
        lo, hi = self.anchor_box()
        width = max((spans.shape[1] for _, spans in self.pieces()), default=0) if self.anchors_on != "box" else 0
        for cable in self.designed_cables(n_cables):
            if self.anchors_on == "box":
                found.update({f"anchor{cable + 1}_{AXES[axis]}": (float(lo[axis]), float(hi[axis])) for axis in range(3)})
            else:
                found.update({f"anchor{cable + 1}_p{k + 1}": (0.0, 1.0) for k in range(width)})
            if self.attachments is not None:
                found.update({f"attachment{cable + 1}_{AXES[axis]}": (float(self.attachments.lo[axis]),
                                                                       float(self.attachments.hi[axis])) for axis in range(3)})
        return found

    def choices(self, n_cables: int) -> dict[str, list[int]]:
        """The categorical variables: ``anchor{c}_piece``, which face or edge (:meth:`pieces`)."""
        if self.anchors_on == "box":
            return {}
        return {f"anchor{cable + 1}_piece": list(range(len(self.pieces()))) for cable in self.designed_cables(n_cables)}

    def layouts(self, n_cables: int) -> int | None:
        """The number of points of the lattice (None when continuous)."""
        if self.step is None:
            return None
        return math.prod(int(round((hi - lo) / self.step)) + 1 for lo, hi in self.ranges(n_cables).values())


def check_robot(spec: LayoutSpec, problem, grid) -> None:
    """ConfigError unless ``problem``'s robot can take the layout's variables, its ``grid``
    (``pipeline.workspace.grid.Grid``) the objectives and the required box (at least one of its
    poses: an empty box would hold every layout, and its payload and tension factor say nothing)."""
    robot, cell_volume = problem.robot, grid.cell_volume
    for name in spec.objectives:
        needs, kind, at_rest = NEEDS.get(name, (None, None, False))
        if needs is not None and spec.required is None:
            raise ConfigError(f"layout.objectives: {name} {needs}; give layout.required")
        if kind is not None and (problem.spec.kind != "statics" or (at_rest and problem.spec.moves)):
            raise ConfigError(f"layout.objectives: {name} {kind} (analysis=statics"
                              f"{' without platform_motion' if at_rest else ''})")
    if "actuator_cost" in spec.objectives:
        if problem.spec.winch_radius is not None:
            raise ConfigError("layout.objectives: actuator_cost chooses the actuator from layout.catalogue; leave the "
                              "job's own actuator=null")
        drives(spec, robot.n_cables)  # the catalogue and its cost column, refused in one line
    if "frame_m3" in spec.objectives and (np.asarray(spec.anchors.hi) <= np.asarray(spec.anchors.lo)).any():
        raise ConfigError(f"layout.objectives: frame_m3 is the anchors' bounding volume; the installation box "
                          f"{spec.anchors.lo}..{spec.anchors.hi} is flat (a planar robot's frame has no volume)")
    if "volume_m3" in spec.objectives and not math.isfinite(cell_volume):
        raise ConfigError("layout.objectives: volume_m3: the grid has no volume (a planar robot's plane, or listed "
                          "poses); use feasible_pct")
    if spec.symmetry == "quadrants" and robot.n_cables % 4:
        raise ConfigError(f"layout.symmetry=quadrants: the robot has {robot.n_cables} cables; quadrants take them "
                          "in fours, (-x, +y), (+x, +y), (+x, -y), (-x, -y)")
    if spec.symmetry == "quadrants" and spec.attachments is None:
        kept = robot.attachments.reshape(-1, 4, 3)
        if not np.allclose(kept, kept[:, 1:2, :] * QUADRANTS[None], rtol=0, atol=1e-12):
            raise ConfigError("layout.symmetry=quadrants: the robot's attachments, which the search keeps, are not "
                              "mirrored in the cables' order (-x, +y), (+x, +y), (+x, -y), (-x, -y); order the cables "
                              "so, or give layout.attachments to design them too")
    if robot.pulleys is not None:
        raise ConfigError("layout: the robot has pulleys at its anchors; a layout search moves bare anchors")
    if spec.required is not None and not spec.required.contains(grid[0:len(grid)]).any():
        raise ConfigError(f"layout.required: the box {spec.required.lo}..{spec.required.hi} holds no pose of the "
                          "grid; a box around some of its points (robot.search, its step)")
    if spec.attachments is not None and robot.platform_shape is not None:
        raise ConfigError("layout.attachments: the robot's platform has a shape (robot.platform.shape) whose surface "
                          "holds the attachments; moving them inside a box would leave it: not searched yet")


def placed(spec: LayoutSpec, robot, values: dict) -> tuple[np.ndarray, np.ndarray]:
    """The anchors and attachments (m, 3) of a trial's ``values`` (with quadrants, each designed
    cable's points mirrored into its four; with ``frame_scale`` on the trial's frame)."""
    anchors, attachments = robot.anchors.copy(), robot.attachments.copy()
    pieces = spec.pieces() if spec.anchors_on != "box" else []
    pivot, scale = spec.frame(robot.up, values) if spec.frame_scale is not None else (np.zeros(3), np.ones(3))
    quadrants = spec.symmetry == "quadrants"
    for cable in range(robot.n_cables):
        designed = cable - cable % 4 + 1 if quadrants else cable
        sign = QUADRANTS[cable % 4] if quadrants else 1.0
        if f"anchor{designed + 1}_x" in values:
            anchors[cable] = np.array([values[f"anchor{designed + 1}_{axis}"] for axis in AXES]) * sign
        elif f"anchor{designed + 1}_piece" in values:
            origin, spans = pieces[int(values[f"anchor{designed + 1}_piece"])]
            along = [values[f"anchor{designed + 1}_p{k + 1}"] for k in range(spans.shape[1])]
            anchors[cable] = (pivot + scale * (origin + spans @ np.asarray(along, dtype=float) - pivot)) * sign
        if f"attachment{designed + 1}_x" in values:
            attachments[cable] = np.array([values[f"attachment{designed + 1}_{axis}"] for axis in AXES]) * sign
    return anchors, attachments


def _flags(problem, positions: np.ndarray) -> np.ndarray:
    """The exact verdict of every one of ``positions``, a bounded chunk at a time."""
    from pipeline.workspace.dispatch import bounded_chunk_size
    from pipeline.workspace.feasibility import feasible_flags

    chunk = bounded_chunk_size(problem, None)
    return np.concatenate([feasible_flags(problem, positions[start:start + chunk])
                           for start in range(0, len(positions), chunk)] or [np.zeros(0, dtype=bool)])


def largest_payload(problem, positions: np.ndarray, payload: float, com: np.ndarray) -> float:
    """The largest payload (kg) at ``com`` (m, platform frame: ``load.com``) with which every one of
    ``positions`` holds, the job's own ``payload`` (``load.mass``, already in the problem's load)
    included, as ``analysis=payload``'s ``max_payload_kg`` counts it; NaN when a pose fails with
    the job's own, inf past ``PAYLOAD_MAX``. At a pose the wrench is affine in the added mass and
    the wrenches the cables balance form a convex set, so the masses a pose holds form an interval;
    every pose holding 0 added, the masses they all hold form an interval from 0, whose end is
    bisected to ``PAYLOAD_RTOL`` of itself: what is returned holds."""
    base = problem.spec.load

    def holds(extra: float) -> bool:  # one body: the masses added, the centre of mass their weighted mean
        total = base.mass + extra
        load = replace(base, mass=total, com=(base.mass * np.asarray(base.com, dtype=float) + extra * com) / total
                       if total > 0 else np.asarray(base.com, dtype=float))
        return bool(_flags(replace(problem, spec=replace(problem.spec, load=load)), positions).all())

    if not holds(0.0):
        return math.nan
    low, high = 0.0, 1.0
    while holds(high):
        low, high = high, 2 * high
        if high > PAYLOAD_MAX:
            return math.inf
    while high - low > PAYLOAD_RTOL * high:
        middle = (low + high) / 2
        low, high = (middle, high) if holds(middle) else (low, middle)
    return payload + low


def least_tension_factor(problem, positions: np.ndarray) -> float:
    """The least tension factor (:func:`pipeline.model.metrics.tension_factor`, 0 where the
    structure matrix lacks a rank, as ``output.metrics`` writes it) over ``positions`` at every
    orientation of the job's set; 1 for none."""
    from pipeline.model.metrics import tension_factor

    least = 1.0
    for at, orientation in problem.poses(positions):
        if len(at):
            state = problem.spec.state(problem.robot, at, orientation)
            structure, rank = state.structure, state.wrench_pinv[1]
            least = min(least, float(np.where(rank == structure.shape[1], tension_factor(structure), 0.0).min()))
    return least


@dataclass(frozen=True)
class Drive:
    """A catalogue actuator on every cable at rest: its ``id``, ``cost`` (the catalogue's ``cost``
    column times the cables) and ``cap`` (N), the largest tension it holds at rest
    (:func:`pipeline.model.actuators.rest_tension_cap`: eqs. 32 and 34, the catalogue's winch and
    gearbox)."""

    id: int
    cost: float
    cap: float


def drives(spec: LayoutSpec, n_cables: int) -> tuple[Drive, ...]:
    """The catalogue's actuators, cheapest first (then by id); ConfigError in one line for a
    catalogue that cannot be read or a ``cost`` that is not a column of finite numbers >= 0."""
    from pipeline.model.actuators import actuator_model, rest_tension_cap
    from pipeline.model.catalogue import load_catalogue

    catalogue = load_catalogue(spec.catalogue)
    if spec.cost not in catalogue.columns or spec.cost == "name":
        raise ConfigError(f"layout.cost={spec.cost}: not a numeric column of catalogue={catalogue.source} (its columns: "
                          f"{', '.join(c for c in catalogue.columns if c != 'name')})")
    found = []
    for row in catalogue.rows:
        try:
            price = float(row[spec.cost])
        except ValueError:
            price = math.nan
        if not (math.isfinite(n_cables * price) and price >= 0):
            raise ConfigError(f"layout.cost={spec.cost}: catalogue={catalogue.source}, actuator {row['id']}: "
                              f"{row[spec.cost]!r} is not a price (a number >= 0, finite times {n_cables} cables)")
        found.append(Drive(row["id"], n_cables * price, rest_tension_cap(actuator_model(row))))
    return tuple(sorted(found, key=lambda drive: (drive.cost, drive.id)))


def cheapest_drive(problem, positions: np.ndarray, catalogue: tuple[Drive, ...]) -> Drive | None:
    """The first drive of ``catalogue`` (cheapest first) with which every one of ``positions`` holds at
    rest: the statics job with ``tension.t_max`` lowered to the drive's cap (the criteria selected
    again, as the job's builder selects them: a robot without a rating gains the rating's); None
    when none does. A cap no larger than one that failed is not tried (a lower cap holds fewer
    poses)."""
    from pipeline.workspace.criteria import selected

    failed = -math.inf
    rating = problem.spec.tension.t_max
    for drive in catalogue:
        if drive.cap <= failed:
            continue
        t_max = drive.cap if rating is None else np.minimum(rating, drive.cap)
        spec = replace(problem.spec, tension=replace(problem.spec.tension, t_max=t_max))
        capped = replace(problem, spec=spec, criteria=selected(spec.kind, spec, problem.robot, problem.settings),
                         limits=replace(problem.limits, t_max=t_max, scale=float(np.max(t_max))))
        if _flags(capped, positions).all():
            return drive
        failed = drive.cap
    return None


def evaluate(problem, positions: np.ndarray, cell_volume: float, required: np.ndarray | None,
             payload: tuple[float, np.ndarray] | None = None, objectives: tuple[str, ...] = (),
             catalogue: tuple[Drive, ...] = ()) -> dict:
    """A layout's numbers over the grid ``positions``: feasible poses, volume, share, the longest
    cable over them, the required poses that fail, the anchors' bounding volume and, with ``payload``
    (the job's ``load.mass`` and ``load.com``), the largest payload the required ones hold
    (:func:`largest_payload`; NaN without it); with ``tension_factor`` among ``objectives``, the least
    over the required ones (:func:`least_tension_factor`; NaN without it); with ``catalogue`` (its
    drives, cheapest first, :func:`drives`) the cheapest that holds the required ones at rest
    (:func:`cheapest_drive`: ``actuator``, its id, and ``actuator_cost``, NaN for none; without
    ``catalogue`` neither key)."""
    from pipeline.model.geometry import cable_vectors, rotation_matrices

    flags = _flags(problem, positions)
    longest = 0.0
    if flags.any() and problem.angles is None:
        for orientation in problem.orientations:
            rotation = rotation_matrices(orientation[None, :])[0]
            lengths = np.linalg.norm(cable_vectors(problem.robot, positions[flags], rotation), axis=-1)
            longest = max(longest, float(lengths.max()))
    n = int(flags.sum())
    failing = int((~flags[required]).sum()) if required is not None else 0
    return {"n_feasible": n, "n_points": len(positions), "volume_m3": n * cell_volume,
            "feasible_pct": 100.0 * n / len(positions), "longest_cable_m": longest if n else math.nan,
            "required_failing": failing,
            "payload_kg": largest_payload(problem, positions[required], *payload) if payload and not failing else math.nan,
            "tension_factor": (least_tension_factor(problem, positions[required])
                               if "tension_factor" in objectives and not failing else math.nan),
            "frame_m3": float(np.prod(np.ptp(problem.robot.anchors, axis=0))),
            **(_drive_numbers(None if failing else cheapest_drive(problem, positions[required], catalogue))
               if catalogue else {})}


def _drive_numbers(drive: Drive | None) -> dict:
    return {"actuator": math.nan if drive is None else drive.id, "actuator_cost": math.nan if drive is None else drive.cost}


def search_layouts(spec: LayoutSpec, problem, positions: np.ndarray, cell_volume: float, n_jobs: int,
                   payload: tuple[float, np.ndarray] = (0.0, np.zeros(3))) -> pd.DataFrame:
    """Run the trials; one row per trial: its variables, :func:`evaluate`'s numbers, ``meets``
    (the required box holds) and ``pareto`` (not dominated among those that meet it). ``payload``:
    the job's ``load.mass`` and ``load.com``, where objective ``payload_kg`` adds mass."""
    from joblib import Parallel, delayed, effective_n_jobs

    n_jobs = max(1, effective_n_jobs(n_jobs))  # compute.n_jobs=-1: every core, in batches of that many trials
    optuna = require("optuna", "design", "a layout study")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    ranges = spec.ranges(problem.robot.n_cables)
    lattice = spec.layouts(problem.robot.n_cables)
    exhaustive = lattice is not None and lattice <= spec.budget
    sampler = (optuna.samplers.NSGAIISampler(seed=spec.seed) if spec.sampler == "nsga2" else
               optuna.samplers.TPESampler(seed=spec.seed, multivariate=True))
    study = optuna.create_study(directions=[OBJECTIVES[o][0] for o in spec.objectives], sampler=sampler)
    choices = spec.choices(problem.robot.n_cables)
    catalogue = drives(spec, problem.robot.n_cables) if "actuator_cost" in spec.objectives else ()
    current = designed(spec, problem.robot)
    if current is not None:
        study.enqueue_trial(current)  # the robot as the overrides give it: the search starts from it
    if exhaustive:  # every other layout of the lattice, in order
        axes = [np.linspace(lo, hi, int(round((hi - lo) / spec.step)) + 1) for lo, hi in ranges.values()]
        for point in product(*axes):
            values = dict(zip(ranges, map(float, point)))
            if values != current:
                study.enqueue_trial(values)
    required = None if spec.required is None else spec.required.contains(positions)
    budget = min(spec.budget, lattice) if exhaustive else spec.budget
    rows = []
    refine_from = budget - int(round(spec.refine * budget))
    steps, best, best_numbers = Steps(spec.seed), None, None
    log.info("layout: %d trials of %d poses (%s%s), %d variables, %d worker(s)", budget, len(positions),
             "every layout of the lattice" if exhaustive else spec.sampler, f", step {spec.step} m" if spec.step else "",
             len(ranges) + len(choices), n_jobs)
    with Parallel(n_jobs=n_jobs, backend="threading") as parallel:
        while len(rows) < budget:
            count = min(n_jobs, budget - len(rows))
            if len(rows) >= refine_from and best is not None:  # the last share of the budget: around the best
                for _ in range(count):
                    study.enqueue_trial(steps.nearby(best, ranges))
            trials = [study.ask() for _ in range(count)]
            values = [{**{key: trial.suggest_categorical(key, options) for key, options in choices.items()},
                       **{key: trial.suggest_float(key, lo, hi, step=spec.step) for key, (lo, hi) in ranges.items()}}
                      for trial in trials]
            layouts = [placed(spec, problem.robot, v) for v in values]
            found = parallel(delayed(evaluate)(replace(problem, robot=replace(problem.robot, anchors=a, attachments=b)),
                                               positions, cell_volume, required,
                                               payload if "payload_kg" in spec.objectives else None,
                                               tuple(spec.objectives), catalogue)
                             for a, b in layouts)
            improved = False
            for trial, value, numbers in zip(trials, values, found):
                if numbers["required_failing"] == 0 and (best is None or _better(spec, numbers, best_numbers)):
                    best, best_numbers, improved = value, numbers, True
                trial.set_constraint("required_failing", float(numbers["required_failing"]))  # <= 0: met
                study.tell(trial, [_objective(numbers, o) for o in spec.objectives])
                rows.append({"trial": trial.number, **value, **_coordinates(spec, problem.robot, value), **numbers})
                if len(rows) % 50 == 0 or len(rows) == budget:
                    first = spec.objectives[0]
                    top = (min if OBJECTIVES[first][0] == "minimize" else max)(r[first] for r in rows)
                    log.info("layout: trial %d/%d, best %s %.6g", len(rows), budget, first, top)
            if len(rows) > refine_from:
                steps.adapt(improved)
    table = pd.DataFrame(rows)
    table["symmetry"] = spec.symmetry
    table["meets"] = table["required_failing"] == 0
    signs = np.array([1.0 if OBJECTIVES[o][0] == "minimize" else -1.0 for o in spec.objectives])
    costs = np.nan_to_num(table[spec.objectives].to_numpy(dtype=float) * signs, nan=np.inf)
    meets = table["meets"].to_numpy()
    table["pareto"] = [bool(meets[i]) and not ((costs[meets] <= costs[i]).all(axis=1)
                                              & (costs[meets] < costs[i]).any(axis=1)).any() for i in range(len(table))]
    first = np.where(meets, costs[:, 0], np.inf)  # the search's progress: its best so far, in trial order
    table["best_so_far"] = np.where(np.isfinite(np.minimum.accumulate(first)), np.minimum.accumulate(first) * signs[0], np.nan)
    return table


class Steps:
    """The refinement's steps (``LayoutSpec.refine``): a (1+1) evolution strategy around the best
    trial so far, each continuous variable moved by a normal step of ``size`` times its range
    (clipped to it; the face or edge kept), the size grown by half after a batch that improved the
    best and shrunk by a fifth after one that did not (Rechenberg's rule), seeded."""

    START, LARGEST, SMALLEST = 0.05, 0.5, 1e-4

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)
        self.size = self.START

    def nearby(self, best: dict, ranges: dict[str, tuple[float, float]]) -> dict:
        moved = dict(best)
        for key, (lo, hi) in ranges.items():
            moved[key] = float(np.clip(best[key] + self.size * (hi - lo) * self.rng.normal(), lo, hi))
        return moved

    def adapt(self, improved: bool) -> None:
        self.size = min(self.LARGEST, self.size * 1.5) if improved else max(self.SMALLEST, self.size * 0.8)


def _better(spec: LayoutSpec, numbers: dict, best: dict) -> bool:
    """Whether a trial beats the best so far on the first objective."""
    first = spec.objectives[0]
    value, incumbent = _objective(numbers, first), _objective(best, first)
    return value < incumbent if OBJECTIVES[first][0] == "minimize" else value > incumbent


def designed(spec: LayoutSpec, robot) -> dict[str, float] | None:
    """The robot's own layout as the search's variables, when it is one of the space's layouts
    (inside the ranges, on the lattice, on a face or edge where the anchors must be, and with
    quadrants mirror-symmetric), its frame the installation box; else None."""
    ranges = spec.ranges(robot.n_cables)
    values = {key: 1.0 for key in ranges if key.startswith("frame_")}
    for cable in spec.designed_cables(robot.n_cables):
        if spec.anchors_on == "box":
            values.update({f"anchor{cable + 1}_{axis}": float(robot.anchors[cable, k]) for k, axis in enumerate(AXES)})
        else:
            on = _on_piece(spec.pieces(), robot.anchors[cable])
            if on is None:
                return None
            values[f"anchor{cable + 1}_piece"] = on[0]
            values.update({f"anchor{cable + 1}_p{k + 1}": float(p) for k, p in enumerate(on[1])})
        if spec.attachments is not None:
            values.update({f"attachment{cable + 1}_{axis}": float(robot.attachments[cable, k])
                           for k, axis in enumerate(AXES)})
    for key, (lo, hi) in ranges.items():
        lattice = spec.step is None or abs((values[key] - lo) / spec.step - round((values[key] - lo) / spec.step)) < 1e-9
        if not (lo <= values[key] <= hi and lattice):
            return None
    anchors, attachments = placed(spec, robot, values)
    same = np.allclose(anchors, robot.anchors, rtol=0, atol=1e-12) and np.array_equal(attachments, robot.attachments)
    return values if same else None


def _on_piece(pieces: list, point: np.ndarray) -> tuple[int, np.ndarray] | None:
    """The first face or edge holding ``point``, and its parameters there (None: on none)."""
    for number, (origin, spans) in enumerate(pieces):
        along = np.linalg.lstsq(spans, point - origin, rcond=None)[0] if spans.shape[1] else np.zeros(0)
        if np.allclose(origin + spans @ along, point, rtol=0, atol=1e-12) and ((along >= -1e-12) & (along <= 1 + 1e-12)).all():
            return number, np.clip(along, 0.0, 1.0)
    return None


def _coordinates(spec: LayoutSpec, robot, values: dict) -> dict[str, float]:
    """With anchors on faces or edges, each designed anchor's coordinates (m), for the summary."""
    if spec.anchors_on == "box":
        return {}
    anchors = placed(spec, robot, values)[0]
    return {f"anchor{cable + 1}_{axis}": float(anchors[cable, k])
            for cable in spec.designed_cables(robot.n_cables) for k, axis in enumerate(AXES)}


def _objective(numbers: dict, name: str) -> float:
    value = numbers[name]
    return (math.inf if OBJECTIVES[name][0] == "minimize" else -math.inf) if value != value else value


def best_trial(table: pd.DataFrame, spec: LayoutSpec) -> pd.Series | None:
    """The trial that meets the requirement with the best first objective (ties: the earliest)."""
    met = table[table["meets"]]
    if met.empty:
        return None
    first = spec.objectives[0]
    return met.sort_values([first, "trial"], ascending=[OBJECTIVES[first][0] == "minimize", True]).iloc[0]


def best_layout(results) -> pd.DataFrame:
    """A layout study's analysis ``best_layout``: the best trial's own job summary (``jobs/best``:
    its settings, box and counts, what a ``cloud`` figure of it reads) with its ``trial``; no row
    when no trial met the requirement."""
    summary = results.summary
    best = summary[summary["job"] == "best"]
    if best.empty:
        return pd.DataFrame({"job": pd.Series(dtype=str), "trial": pd.Series(dtype=int)})
    return results.job_summary("best").assign(trial=int(best["trial"].iloc[0]))


PROVE_DEPTH, PROVE_SECONDS = 15, 120.0  # the required box's paving for the best layout


def prove_required(spec: LayoutSpec, problem, compute) -> tuple[float | None, str]:
    """The share (%) of the ``required`` box proven feasible for the best layout's ``problem``
    (``analysis=certified``'s branch and prune over that box, ``PROVE_DEPTH`` levels or
    ``PROVE_SECONDS``), and what it says; None where the certificates cannot speak: no required box,
    another analysis or tension model than statics with pulling cables, or a criterion without a
    certified bound (``Criterion.certified``)."""
    from pipeline.workspace.criteria import REGISTRY
    from pipeline.model.certificates import INSIDE
    from pipeline.workspace.paving import pave

    if spec.required is None:
        return None, "no required box"
    unproven = [name for name in problem.criteria if not REGISTRY[name].certified]
    if problem.spec.kind != "statics" or problem.spec.tension.model != "feasible" or unproven:
        why = f"criterion {unproven[0]} has no certified bound" if unproven else "certified for pulling cables at rest only"
        return None, f"the required box is not proven: {why}"
    lo, hi = np.asarray(spec.required.lo, dtype=float), np.asarray(spec.required.hi, dtype=float)
    box = replace(problem, robot=replace(problem.robot, box_lo=lo, box_hi=hi))
    paving, ended = pave(box, PROVE_DEPTH, PROVE_SECONDS, compute)
    axes = np.flatnonzero(hi > lo)
    volumes = paving.volumes(axes)
    share = 100.0 * float(volumes[paving.verdict == INSIDE].sum() / volumes.sum())
    return share, f"{share:.2f}% of the required box proven feasible ({ended['depth_reached']} levels, {ended['stopped']})"

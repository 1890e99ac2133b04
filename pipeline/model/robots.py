"""Robot builders: turn a robot's design parameters into the generic :class:`CableRobot`.

Each builder only places points; kinematics, dynamics and workspace criteria are shared. The
papers' two robots are parametric builders (:func:`cpr8`, :func:`irpm6`); any other robot is
given by its points (:class:`PointsRobot`, ``robot=points`` or a user's YAML file).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import ConfigError, text_number
from pipeline.model.geometry import FREEDOMS, CableRobot


def carrier_half_diagonal(l: float, w: float, h: float) -> float:
    """d_e of section 3 (CPR-8 paper): half the carrier's main diagonal."""
    return float(np.sqrt((l / 2) ** 2 + (w / 2) ** 2 + (h / 2) ** 2))


def cpr8(
    d: float, s: float, v: float, l: float, w: float, h: float, lower_anchor_drop: float | None = None
) -> CableRobot:
    """CPR-8 of Filipovic & Kevac (2018), Fig. 1, eqs. (1)-(17).

    z points up (gravity enters eq. (31) as -g). Upper hanging points O, F, G, H lie in the plane
    z = 0 at the frame's top corners (eqs. 10-13); lower hanging points O', F', G', H' lie
    ``lower_anchor_drop`` below them (eqs. 14-17 read literally: h_o). Cables 1-4 join the
    carrier's upper vertices A, B, C, D, cables 5-8 its lower vertices A', B', C', D' (eqs. 1-8).
    The search box is the geometric workspace of Fig. 3: the frame d*s*v hanging below z = 0,
    shrunk by d_e on every side.
    """
    drop = h if lower_anchor_drop is None else lower_anchor_drop
    corners = np.array([[0.0, 0.0], [d, 0.0], [d, s], [0.0, s]])
    anchors = np.vstack(
        [np.column_stack([corners, np.zeros(4)]), np.column_stack([corners, np.full(4, -drop)])]
    )
    vertex = np.array([[-l / 2, -w / 2], [l / 2, -w / 2], [l / 2, w / 2], [-l / 2, w / 2]])
    attachments = np.vstack(
        [np.column_stack([vertex, np.full(4, h / 2)]), np.column_stack([vertex, np.full(4, -h / 2)])]
    )
    de = carrier_half_diagonal(l, w, h)
    return CableRobot(
        name="cpr8",
        anchors=anchors,
        attachments=attachments,
        box_lo=np.array([de, de, -(v - de)]),
        box_hi=np.array([d - de, s - de, -de]),
        cable_names=("k", "h", "m", "n", "k'", "h'", "m'", "n'"),
        up=np.array([0.0, 0.0, 1.0]),
    )


def irpm6(
    r_base: float, r_end: float, gamma_deg: float, box_lo, box_hi, l_max: float | None = None
) -> CableRobot:
    """6-cable IRPM of Hamed & Zohoor, Figs. 1-4, eqs. (1)-(2) (docs/evidence.md section 2: our reading).

    Base points C_i lie on a circle of radius r_base in the base plane Z = 0, platform points D_i
    on a circle of radius r_end in the platform plane z = 0 (body frame, origin O_M). Points come
    in pairs separated by the angle gamma: base pairs (C1, C2), (C3, C4), (C5, C6) centred at
    0, 120, 240 deg; platform pairs (D2, D3), (D4, D5), (D6, D1) centred at 60, 180, 300 deg,
    so that each base pair feeds two neighbouring platform pairs (gamma = 0: two triangles
    rotated by 60 deg, the 3-3 Stewart arrangement). Z points down from the base plane, into
    the search box, so the weight is +f_z.
    """
    half = gamma_deg / 2.0
    base_deg = np.array([-half, half, 120 - half, 120 + half, 240 - half, 240 + half])
    platform_deg = np.array([300 + half, 60 - half, 60 + half, 180 - half, 180 + half, 300 - half])
    return CableRobot(
        name="irpm6",
        anchors=_circle(r_base, base_deg),
        attachments=_circle(r_end, platform_deg),
        box_lo=np.asarray(box_lo, dtype=float),
        box_hi=np.asarray(box_hi, dtype=float),
        cable_names=tuple(f"C{i}D{i}" for i in range(1, 7)),
        up=np.array([0.0, 0.0, -1.0]),
        l_max=l_max,
    )


def _circle(radius: float, degrees: np.ndarray) -> np.ndarray:
    angles = np.deg2rad(degrees)
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(len(angles))])


@dataclass(frozen=True)
class PointsRobot:
    """A robot given by its points (``robot=points``): every field is checked here, once, and a
    bad one raises ConfigError naming ``robot.<key>`` and its value.

    anchors (m, 3) fixed-frame points and attachments (m, 3) platform-frame points, m >= 2 in
    the same order; cable_names (m labels, default "1".."m"); up, the frame's up direction
    (normalised, gravity acts along -up); l_max, the longest cable (m, None = none); the search
    box lo, hi (3,) with step (m) and spacing ``faces`` or ``centres``; dofs, the platform's
    freedoms (indices into ``geometry.FREEDOMS``, in that order)."""

    anchors: np.ndarray
    attachments: np.ndarray
    cable_names: tuple[str, ...]
    up: np.ndarray
    l_max: float | None
    lo: np.ndarray
    hi: np.ndarray
    step: float
    spacing: str
    dofs: tuple[int, ...]

    @classmethod
    def from_config(cls, robot) -> "PointsRobot":
        search = robot.search
        anchors = point_list("robot.anchors", robot.anchors)
        attachments = point_list("robot.attachments", robot.attachments)
        if len(anchors) != len(attachments):
            raise ConfigError(f"robot.attachments: {len(attachments)} points for {len(anchors)} "
                              "anchors (one attachment per cable, in the same order)")
        if len(anchors) < 2:
            raise ConfigError(f"robot.anchors: {len(anchors)} cable(s); a cable robot needs >= 2")
        names = robot.cable_names
        if names is None:
            names = [str(i) for i in range(1, len(anchors) + 1)]
        if len(names) != len(anchors) or len(set(names)) != len(names):
            raise ConfigError(f"robot.cable_names={list(names)}: needs {len(anchors)} distinct names")
        up = _vector("robot.up", robot.up)
        if not np.linalg.norm(up) > 0:
            raise ConfigError(f"robot.up={list(robot.up)}: must be a non-zero vector (gravity acts along -up)")
        if robot.l_max is not None and not 0 < robot.l_max < np.inf:
            raise ConfigError(f"robot.l_max={robot.l_max}: must be > 0 and finite (or null)")
        given = [key for key in ("lo", "hi", "step") if search.get(key) is not None]
        if not given:  # a job that lists its poses (``poses``) searches no box
            lo = hi = np.full(3, np.nan)
        else:
            missing = [key for key in ("lo", "hi") if key not in given]  # step: a grid's (checked by pipeline.app.problem)
            if missing:
                raise ConfigError(f"robot.search.{missing[0]}: no value given (the searched box needs lo, hi and step)")
            lo, hi = _vector("robot.search.lo", search.lo), _vector("robot.search.hi", search.hi)
            for axis, a, b in zip("xyz", lo, hi):
                if not a <= b:
                    raise ConfigError(f"robot.search: {axis} from {a} to {b}: lo must be <= hi")
            if search.step is not None and not 0 < search.step < np.inf:
                raise ConfigError(f"robot.search.step={search.step}: must be > 0 and finite")
        if search.spacing not in ("faces", "centres"):
            raise ConfigError(f"robot.search.spacing={search.spacing}: must be faces or centres")
        dofs = [str(d) for d in robot.dofs]
        if not dofs or not set(dofs) <= set(FREEDOMS) or len(set(dofs)) != len(dofs):
            raise ConfigError(f"robot.dofs={dofs}: must be distinct freedoms among {', '.join(FREEDOMS)}")
        return cls(anchors, attachments, tuple(str(n) for n in names), up / np.linalg.norm(up),
                   None if robot.l_max is None else float(robot.l_max), lo, hi,
                   np.nan if search.step is None else float(search.step), str(search.spacing),
                   tuple(sorted(FREEDOMS.index(d) for d in dofs)))

    def build(self) -> CableRobot:
        return CableRobot(name="points", anchors=self.anchors, attachments=self.attachments,
                          box_lo=self.lo, box_hi=self.hi, cable_names=self.cable_names, up=self.up,
                          l_max=self.l_max, dofs=self.dofs)


def point_list(key: str, value) -> np.ndarray:
    """(m, 3) finite floats from a non-empty list of [x, y, z]; ConfigError naming the first bad
    point."""
    try:
        rows = list(value)
    except TypeError:
        rows = []
    if not rows or isinstance(value, str):
        raise ConfigError(f"{key}={value}: must be a list of [x, y, z] points")
    for i, row in enumerate(rows):
        _vector(f"{key}[{i}]", row)
    return np.array([[float(v) for v in row] for row in rows], dtype=float).reshape(-1, 3)


def _vector(key: str, value) -> np.ndarray:
    """(3,) finite floats, or ConfigError '<key>=<value>: ...'."""
    try:
        items = list(value)
    except TypeError:
        items = None
    if items is None or len(items) != 3 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in items):
        shown = items if items is not None else value
        raise ConfigError(f"{key}={shown}: must be 3 finite numbers [x, y, z] (m){text_number(items or [])}")
    return np.array(items, dtype=float)

"""Import a CASPR model (``<name>_cables.xml`` and ``<name>_bodies.xml``) as a robot file.

``python -m pipeline.caspr NAME_cables.xml [--bodies NAME_bodies.xml] [--cable-set ID]
[--lo x y z --hi x y z] [--step 0.1] [--out DIR/robot/NAME.yaml]`` writes a robot YAML file for
``robot=points`` (run it with ``python -m pipeline --config-dir DIR robot=NAME``). CASPR's files
as its model library has them: an XML declaration, a ``<!DOCTYPE ... SYSTEM ...>`` reference
(never fetched) and comments before the root; the cables file's ``<cable_set>``s (the
``default_cable_set`` unless ``--cable-set`` names another), each ``<cable_ideal>`` attached on
link 0 (the frame: our anchor) and link 1 (the platform: our attachment point, platform frame),
relative to the joint (``attachment_reference="joint"``) or to the centre of mass (``"com"``,
which needs the bodies file), with ``force_min``/``force_max`` (N); the bodies file's
``<bodies_system>`` (or, in older files, a bare ``<links>``) with one ``<link_rigid>``: its
``<joint type q_min q_max>``, ``<physical>`` ``mass`` (kg), ``com_location`` (m) and ``inertia``
(about the centre of mass or the joint: ``robot.platform.inertia`` about the centre), and its
``<parent>`` ``location`` (the joint's origin in the frame: the anchors are written relative to
it, so the searched positions are CASPR's joint coordinates q).

The file written sets the robot's points, ``robot.platform`` (mass and centre of mass; 0 kg
without ``--bodies``, said so), ``tension.t_min``/``t_max`` (one value, or one per cable where
they differ) and the search box: ``--lo``/``--hi`` when given, else the joint's position limits
(their position values of ``q_min``/``q_max``), else the anchors' bounding box when it spans
the joint's axes; never the display range (a plot extent). The box used is printed.

The joint gives the platform's freedoms (``robot.dofs``): ``SPATIAL_EULER_XYZ`` and
``SPATIAL_QUATERNION`` all six, ``T_XYZ`` x, y, z, ``PLANAR_XY`` x, y, rz (and ``PLANAR_XZ``,
``PLANAR_YZ``), ``P_XY`` and ``P_XZ`` a point in a plane; a planar joint's box is its plane
through the joint's origin. A joint that holds the platform's reference point (``S_EULER_XYZ``,
``S_FIXED_XYZ``: rx, ry, rz; ``R_X``, ``R_Y``, ``R_Z``: one of them) makes the grid one of
orientations at the origin: the box is the joint's angle limits (else CASPR's own, [-pi, pi]),
in rad, with ``S_EULER_XYZ``'s angles in the xyz convention. Refused, in one line and exit status
2, with the reason: a quaternion, universal, prismatic or free-axis joint, a
multi-link (MCDM) model, a cable that is not ``<cable_ideal>`` or ``<cable_linear_spring>`` (whose
``K``, CASPR's k = K / length, becomes ``robot.cable_ea``; variable stiffness is refused), a
cable routed through more than two points or through a pulley other than a swivelling one at its
frame end (a screw-drive pulley), two cables of one name (both named), and a file that is not
such XML. A ``<base_rotating_pulley>`` at a cable's frame end (CASPR's swivelling pulley:
``fixed_location``, ``pulley_radius``, ``cable_entry_vector``) becomes its ``robot.pulleys``
entry, the anchor its fixed location and the axis its entry direction (docs/model.md section 6).
CASPR's ``SPATIAL_EULER_XYZ`` orientation is R = Rx Ry Rz of its angles (eq. (9)'s is
R = Rz(phi) Ry(theta) Rx(psi)): the file sets ``orientation.convention: xyz`` so that CASPR's
angles mean the same pose, and says so.

The importer writes only a new file of the user's: an existing file is replaced only with
``--force``, a target inside the package's own ``conf/`` (where it would replace or hide a
shipped file: run from a checkout, ``conf/robot/`` is that folder) is refused, and so is a
shipped robot's name (``cpr8``, ``irpm6``, ``points``), which the file would hide under
``--config-dir``. Names from the files (the sources', the cables', the link's) are written as
quoted YAML scalars or with control characters replaced, so no name can become a key.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

from pipeline.errors import ConfigError
from pipeline.app.config import MAX_FORCE, MAX_MASS
from pipeline.app.resources import CONF_DIR
from pipeline.app.results import code_version, write_text
from pipeline.app.xmlfiles import parse_xml
from pipeline.model.dynamics import inertia_fault, inertia_tensor

SHIPPED_ROBOTS = tuple(sorted(p.stem for p in (CONF_DIR / "robot").glob("*.yaml")))


# CASPR's joint types (src/Model/Bodies/Joints/) that move a platform through positions: its
# freedoms (robot.dofs) and which of x, y, z the first values of q_min/q_max are (the others 0)
JOINTS = {  # type -> (freedoms, the grid axes its q values fill, the angle convention of its rotation)
    "SPATIAL_EULER_XYZ": (["x", "y", "z", "rx", "ry", "rz"], "xyz", "xyz"),
    "SPATIAL_QUATERNION": (["x", "y", "z", "rx", "ry", "rz"], "xyz", "zyx"),
    "T_XYZ": (["x", "y", "z"], "xyz", "zyx"),  # a platform that only translates
    "PLANAR_XY": (["x", "y", "rz"], "xy", "zyx"), "PLANAR_XZ": (["x", "z", "ry"], "xz", "zyx"),
    "PLANAR_YZ": (["y", "z", "rx"], "yz", "zyx"),
    "P_XY": (["x", "y"], "xy", "zyx"), "P_XZ": (["x", "z"], "xz", "zyx"),  # a point in a plane
    # the joint holds the reference point: the grid is of angles (psi, theta, phi fill x, y, z)
    "S_EULER_XYZ": (["rx", "ry", "rz"], "xyz", "xyz"),  # R = Rx(a) Ry(b) Rz(c)
    "S_FIXED_XYZ": (["rx", "ry", "rz"], "xyz", "zyx"),  # R = Rz(c) Ry(b) Rx(a): eq. (9)'s
    "R_X": (["rx"], "x", "zyx"), "R_Y": (["ry"], "y", "zyx"), "R_Z": (["rz"], "z", "zyx"),
}
# joints this version cannot model, and what they move
ORIENTING = {
    "S_QUATERNION": "rx, ry, rz by a quaternion (four coordinates; S_EULER_XYZ or S_FIXED_XYZ give angles)",
    "R_AXIS": "one rotation about its own axis (a revolute joint)", "U_XY": "rx, ry (a universal joint)",
    "U_XZ": "rx, rz (a universal joint)", "U_YZ": "ry, rz (a universal joint)",
    "P_X": "x (a prismatic joint)", "P_AXIS": "one translation (a prismatic joint)",
}
SPRING = "cable_linear_spring"  # CASPR's elastic cable: k = K / length, K the robot's cable_ea
PULLEY = "base_rotating_pulley"  # CASPR's swivelling pulley at the frame (BaseRotatingPulleyAttachment)
DEFAULT_ANGLE_LIMIT = np.pi  # CASPR's own q_lb/q_ub of its angle joints, without q_min/q_max


def read_cables(path: Path, cable_set: str | None = None, number: bool = False) -> dict:
    """Anchors, attachments (link 1, as given), names, force limits and the attachment
    reference of every cable of one cable set (the file's default set unless named); ``number``:
    name the cables 1, 2, ... in the file's order instead (a file that names two alike)."""
    root = parse_xml(path)
    if root.tag != "cables":
        raise ConfigError(f"{path}: root element <{root.tag}>, a CASPR cables file has <cables>")
    wanted = cable_set or root.get("default_cable_set")
    sets = root.findall("cable_set")
    chosen = [s for s in sets if s.get("id") == wanted] if wanted else sets[:1]
    if not chosen:
        ids = ", ".join(str(s.get("id")) for s in sets) or "none"
        raise ConfigError(f"{path}: no cable_set {wanted!r} (cable sets: {ids})")
    cables = [c for c in chosen[0] if isinstance(c.tag, str)]  # comments are not cables
    if not cables:
        raise ConfigError(f"{path}: cable_set {wanted!r} has no cables")
    out = {"set": chosen[0].get("id"), "names": [], "anchors": [], "attachments": [], "force_min": [],
           "force_max": [], "reference": [], "pulleys": [], "ea": []}
    for index, cable in enumerate(cables, start=1):
        where = f"{path}: cable {cable.get('name') or index}"
        if cable.tag not in ("cable_ideal", SPRING):
            raise ConfigError(f"{where}: <{cable.tag}> is not an ideal or a linear-spring cable (variable-stiffness "
                              f"cables are not supported, only <cable_ideal> and <{SPRING}>)")
        stiffness = _number(cable, "properties/K", where) if cable.tag == SPRING else None
        if stiffness is not None and not 0 < stiffness <= MAX_FORCE:
            raise ConfigError(f"{where}: K {stiffness:g} N: need 0 < K <= {MAX_FORCE:g} (CASPR's k = K / length)")
        out["ea"].append(stiffness)
        name = str(index) if number else cable.get("name") or str(index)
        if name in out["names"]:
            raise ConfigError(f"{path}: cables {out['names'].index(name) + 1} and {index} are both named "
                              f"{name!r} (each cable names its own columns); --number-cables names them "
                              "1, 2, ... in the file's order")
        out["names"].append(name)
        out["reference"].append(cable.get("attachment_reference", "joint"))
        if out["reference"][-1] not in ("joint", "com"):
            raise ConfigError(f"{where}: attachment_reference={out['reference'][-1]!r} (joint or com)")
        low, high = _number(cable, "properties/force_min", where), _number(cable, "properties/force_max", where)
        if not 0 <= low < high <= MAX_FORCE:
            raise ConfigError(f"{where}: force_min {low:g} and force_max {high:g} N: need 0 <= force_min < "
                              f"force_max <= {MAX_FORCE:g} (a cable only pulls)")
        out["force_min"].append(low)
        out["force_max"].append(high)
        points = [a for a in cable.findall("attachments/*")]
        pulley = points.pop(0) if points and points[0].tag == PULLEY else None  # the frame's end of the cable
        other = [a.tag for a in points if a.tag != "attachment"]
        if other:
            raise ConfigError(f"{where}: <{other[0]}>: only straight cables from a frame point (or from a "
                              f"<{PULLEY}> there) to a platform point are supported")
        links = [(_text(attachment, "link", where), _vector(attachment, "location", where)) for attachment in points]
        if pulley is not None:
            links.insert(0, ("0", _vector(pulley, "fixed_location", f"{where}: <{PULLEY}>")))
        out["pulleys"].append(None if pulley is None else _pulley(pulley, f"{where}: <{PULLEY}>"))
        found = sorted(link for link, _ in links)
        if any(link not in ("0", "1") for link in found):
            raise ConfigError(f"{where}: attached to links {found}: multi-link models are not supported "
                              "(link 0, the frame, and link 1, the platform)")
        if found != ["0", "1"]:
            raise ConfigError(f"{where}: {len(found)} attachments on links {found or 'none'}: only straight cables "
                              "from one frame point (link 0) to one platform point (link 1) are supported "
                              "(a cable routed through several points is not)")
        out["anchors"].append(dict(links)["0"])
        out["attachments"].append(dict(links)["1"])
    springs = [ea is not None for ea in out["ea"]]
    if any(springs) and not all(springs):
        raise ConfigError(f"{path}: cable {springs.index(False) + 1} is ideal and cable {springs.index(True) + 1} a "
                          "linear spring: the cables' stiffness is given for all of them or for none")
    if all(springs):
        out["robot"] = {"cable_ea": _limit(out["ea"])}
    return out


def _pulley(element, where: str) -> dict:
    """CASPR's swivelling pulley at the frame (BaseRotatingPulleyAttachment): the cable enters it
    at ``fixed_location`` along ``cable_entry_vector``, on a pulley of ``pulley_radius`` (m)."""
    radius = _number(element, "pulley_radius", where)
    axis = np.asarray(_vector(element, "cable_entry_vector", where))
    if radius < 0 or not np.linalg.norm(axis) > 0:
        raise ConfigError(f"{where}: pulley_radius {radius:g} m and cable_entry_vector {axis.tolist()}: need a radius "
                          ">= 0 and a direction that is not zero")
    return {"axis": (axis / np.linalg.norm(axis)).tolist(), "radius": radius}


def read_body(path: Path) -> dict:
    """The single rigid link of a bodies file: name, joint type, position limits (first three
    values of ``q_min``/``q_max``, or None), mass (kg), centre of mass and the joint's origin in
    the frame (m)."""
    root = parse_xml(path)
    links = root.find("links") if root.tag == "bodies_system" else root if root.tag == "links" else None
    if links is None:
        raise ConfigError(f"{path}: root element <{root.tag}>, a CASPR bodies file has <bodies_system> "
                          "with <links> (or, in older files, <links>)")
    rigid = links.findall("link_rigid")
    if len(rigid) != 1:
        raise ConfigError(f"{path}: {len(rigid)} <link_rigid> links: only single-body models (SCDM, one "
                          "platform) are imported, not multi-link ones (MCDM)")
    link = rigid[0]
    where = f"{path}: link {link.get('num', '1')}"
    joint = link.find("joint")
    kind = "" if joint is None else joint.get("type", "")
    if kind not in JOINTS:
        freedoms = ORIENTING.get(kind)
        what = f"joint {kind or '(none)'}" + (f" moves the platform in {freedoms}" if freedoms else ", not a CASPR joint type")
        raise ConfigError(f"{where}: {what}; imported are the joints {', '.join(JOINTS)}")
    dofs, axes, convention = JOINTS[kind]
    mass = _number(link, "physical/mass", where)
    if not 0 <= mass <= MAX_MASS:
        raise ConfigError(f"{where}: mass {mass:g} must be in [0, {MAX_MASS:g}] kg")
    box = None
    if joint.get("q_min") is not None or joint.get("q_max") is not None:
        limits = [_numbers(joint.get(key) or "", f"{where}: joint {key}", len(axes)) for key in ("q_min", "q_max")]
        if not (limits[0] < limits[1]).all():
            raise ConfigError(f"{where}: joint q_min {joint.get('q_min')!r} and q_max {joint.get('q_max')!r}: "
                              f"need q_min < q_max in {', '.join(axes)}")
        box = tuple(np.zeros(3) for _ in limits)  # the plane of a planar joint through the joint's origin
        for corner, values in zip(box, limits):
            for axis, value in zip(axes, values):
                corner["xyz".index(axis)] = value
    origin = link.find("parent/location")
    return {"name": link.get("name") or "", "joint": kind, "dofs": dofs, "mass": mass, "box": box,
            "convention": convention, "angles": all(d.startswith("r") for d in dofs),
            "com": _vector(link, "physical/com_location", where), "inertia": _inertia(link, mass, where),
            "origin": np.zeros(3) if origin is None else np.asarray(_vector(link, "parent/location", where))}


def _inertia(link, mass: float, where: str) -> list[float] | None:
    """The link's ``<inertia>`` about its centre of mass as ``robot.platform.inertia`` [Ixx, Iyy,
    Izz, Ixy, Ixz, Iyz] (CASPR's matrix [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]]; one
    given about the joint, ref="joint", moved to the centre by parallel axes); None without one
    or without a mass (a planar model's may give Izz alone). ConfigError for one no rigid body has
    (:func:`pipeline.model.dynamics.inertia_fault`)."""
    node = link.find("physical/inertia")
    if node is None or not mass > 0:
        return None
    matrix = inertia_tensor(*(_number(node, key, f"{where}: <inertia>") for key in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")))
    if node.get("ref") == "joint":
        com = np.asarray(_vector(link, "physical/com_location", where))
        matrix = matrix - mass * (com @ com * np.eye(3) - np.outer(com, com))
    elif node.get("ref") != "com":
        raise ConfigError(f"{where}: <inertia ref={node.get('ref')!r}>: com or joint")
    fault = inertia_fault(matrix)
    if fault:
        raise ConfigError(f"{where}: <inertia> about the centre of mass {matrix.round(12).tolist()} {fault}")
    return [float(matrix[0, 0]), float(matrix[1, 1]), float(matrix[2, 2]), float(matrix[0, 1]), float(matrix[0, 2]),
            float(matrix[1, 2])]


def search_box(cables: dict, body: dict | None, box=None) -> tuple[np.ndarray, np.ndarray, str]:
    """(lo, hi, where it came from): ``box`` (``--lo``/``--hi``), the joint's position limits,
    or the anchors' bounding box (in joint coordinates) when it has a volume; else ConfigError."""
    if box is not None:
        return np.asarray(box[0], float), np.asarray(box[1], float), "--lo/--hi"
    if body is not None and body["box"] is not None:
        return body["box"][0], body["box"][1], "the joint's q_min/q_max"
    if body is not None and body["angles"]:  # the grid is of angles: CASPR's own limits
        turning = np.array([axis in JOINTS[body["joint"]][1] for axis in "xyz"])
        return -DEFAULT_ANGLE_LIMIT * turning, DEFAULT_ANGLE_LIMIT * turning, "CASPR's joint limits [-pi, pi]"
    anchors = np.asarray(cables["anchors"]) - (0.0 if body is None else body["origin"])
    lo, hi = anchors.min(axis=0), anchors.max(axis=0)
    moving = np.array([axis in (JOINTS[body["joint"]][1] if body else "xyz") for axis in "xyz"])
    lo, hi = np.where(moving, lo, 0.0), np.where(moving, hi, 0.0)  # a planar joint's plane through its origin
    if not (hi - lo > 1e-9 * max(1.0, float(np.abs(anchors).max())))[moving].all():
        flat = ", ".join(axis for axis, span, free in zip("xyz", hi - lo, moving) if free and not span > 0)
        raise ConfigError(f"no search box: {'the bodies file gives no joint q_min/q_max' if body else 'no --bodies'}, "
                          f"and the anchors span nothing along {flat} (a suspended robot); give --lo x y z --hi x y z")
    return lo, hi, "the anchors' bounding box"


def robot_yaml(cables: dict, body: dict | None, step: float, header: list[str], box) -> str:
    """The robot file's text (YAML flow style, one cable per line) under the comment lines
    ``header``; ``box``: (lo, hi, origin) of :func:`search_box`; ``cables["robot"]``: other robot
    keys the source gives (an importer's own: cable diameter, stiffness, longest cable)."""
    com = np.zeros(3) if body is None else np.asarray(body["com"])
    origin = np.zeros(3) if body is None else body["origin"]
    attachments = [np.asarray(a) + (com if ref == "com" else 0.0)
                   for a, ref in zip(cables["attachments"], cables["reference"])]
    anchors = np.asarray(cables["anchors"]) - origin  # relative to the joint's origin: positions are q
    lo, hi, _ = box
    spacing = "centres" if (np.asarray(hi) > np.asarray(lo)).all() else "faces"  # a plane: its one layer
    lines = ["# @package _global_", *(f"# {_one_line(line)}" for line in header)]
    xyz = body is not None and body["convention"] == "xyz"
    if xyz:
        lines.append("# Orientation: CASPR's angles (a, b, c), R = Rx(a) Ry(b) Rz(c): orientation.convention=xyz "
                     "(psi, theta, phi = a, b, c).")
    lines += [
        "defaults:",
        "  - /robot/points",
        "  - _self_",
        "robot:",
        "  anchors:",
        *[f"    - {_flow(a)}" for a in anchors],
        "  attachments:",
        *[f"    - {_flow(a)}" for a in attachments],
        f"  cable_names: [{', '.join(_quoted(n) for n in cables['names'])}]",
        f"  platform: {{mass: {0.0 if body is None else body['mass']!r}, com: {_flow(com)}"
        + (f", inertia: {_flow(body['inertia'])}}}" if body is not None and body.get("inertia") else "}"),
        *([f"  dofs: [{', '.join(body['dofs'])}]"] if body is not None and len(body["dofs"]) < 6 else []),
        f"  search: {{lo: {_flow(lo)}, hi: {_flow(hi)}, step: {step!r}, spacing: {spacing}}}",
        *(["  pulleys:", *[f"    - {{axis: {_flow(p['axis'] if p else [0.0, 0.0, 1.0])}, radius: {p['radius'] if p else 0.0!r}}}"
                            for p in cables["pulleys"]]] if any(cables["pulleys"]) else []),
        *(f"  {key}: {value}" for key, value in cables.get("robot", {}).items()),
        f"tension: {{t_min: {_limit(cables['force_min'])}, t_max: {_limit(cables['force_max'])}}}",
        *(["orientation: {convention: xyz}"] if xyz else []),
    ]
    return "\n".join(lines) + "\n"


def _text(element, tag: str, where: str) -> str:
    found = element.find(tag)
    if found is None or not (found.text or "").strip():
        raise ConfigError(f"{where}: missing <{tag}>")
    return found.text.strip()


def _number(element, tag: str, where: str) -> float:
    text = _text(element, tag, where)
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"{where}: <{tag}> {text!r} is not a number") from None
    if not np.isfinite(value):
        raise ConfigError(f"{where}: <{tag}> {text!r} is not finite")
    return value


def _vector(element, tag: str, where: str) -> list[float]:
    text = _text(element, tag, where)
    parts = text.split()
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 3 or not np.isfinite(values).all():
        raise ConfigError(f"{where}: <{tag}> {text!r} is not 3 finite numbers")
    return values


def _numbers(text: str, where: str, first: int) -> np.ndarray:
    """The first ``first`` of the whitespace-separated finite numbers in ``text``."""
    try:
        values = np.array([float(p) for p in text.split()])
    except ValueError:
        values = np.array([])
    if len(values) < first or not np.isfinite(values[:first]).all():
        raise ConfigError(f"{where} {text!r}: needs {first} finite numbers first (the joint's positions, m)")
    return values[:first]


def _flow(values) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def _limit(values: list[float]) -> str:
    return repr(values[0]) if len(set(values)) == 1 else _flow(values)


def _quoted(name: str) -> str:
    """A single-quoted YAML scalar: a quote doubled, control characters (a line break would end
    the scalar) replaced by '?'."""
    return "'" + _one_line(name).replace("'", "''") + "'"


def _one_line(text: str) -> str:
    """``text`` without control characters (a newline in a comment would start a YAML key)."""
    return re.sub(r"[\x00-\x1f\x7f\x85\u2028\u2029]", "?", text)


def checked_target(out: Path, force: bool) -> Path:
    """``out`` if the importer may write it, else ConfigError saying why and what to do: a
    ``.yaml`` file in a folder named ``robot`` (the config group ``--config-dir`` holds), its name
    a robot's (letters, digits, _ and -), not a shipped robot's, outside the package, new unless
    ``force``."""
    if out.suffix != ".yaml" or out.parent.name != "robot" or not re.fullmatch(r"[A-Za-z0-9_-]+", out.stem):
        raise ConfigError(f"--out={out}: a robot file DIR/robot/NAME.yaml (NAME of letters, digits, _ and -), which "
                          "python -m pipeline --config-dir DIR robot=NAME then runs")
    if out.stem in SHIPPED_ROBOTS:
        raise ConfigError(f"--out={out}: robot={out.stem} is a shipped robot, which this file would hide "
                          f"under --config-dir; choose another name (shipped: {', '.join(SHIPPED_ROBOTS)})")
    if out.resolve().is_relative_to(CONF_DIR.resolve()):
        raise ConfigError(f"--out={out}: inside the package's own configs ({CONF_DIR.resolve()}); write to a "
                          "folder of your own, e.g. --out myconf/robot/NAME.yaml, and run with --config-dir myconf")
    if out.exists() and not force:
        raise ConfigError(f"--out={out}: exists; give --force to replace it")
    return out


def target_arguments(parser: argparse.ArgumentParser) -> None:
    """The options every importer takes: the search grid and the file it writes."""
    parser.add_argument("--step", type=float, default=0.1, help="search grid step, m (default 0.1)")
    parser.add_argument("--out", type=Path, help="file to write (default conf/robot/<name>.yaml)")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file")
    parser.add_argument("--lo", type=float, nargs=3, help="search box corner x y z, m")
    parser.add_argument("--hi", type=float, nargs=3, help="search box corner x y z, m")


def given_box(args) -> tuple | None:
    """``--lo``/``--hi`` as a box, None without them; ConfigError for a bad step or box."""
    if not 0 < args.step < np.inf:
        raise ConfigError(f"--step={args.step}: must be > 0 and finite")
    if (args.lo is None) != (args.hi is None):
        raise ConfigError("--lo and --hi: give both corners of the search box, or neither")
    if args.lo is None:
        return None
    box = np.array(args.lo), np.array(args.hi)
    if not (np.isfinite(box).all() and (box[0] <= box[1]).all()):
        raise ConfigError(f"--lo={args.lo} --hi={args.hi}: must be finite with lo <= hi")
    return box


def write_robot(args, name: str, cables: dict, body: dict | None, header: list[str], box) -> tuple[Path, tuple]:
    """Write the robot file of an import (:func:`checked_target`, :func:`search_box`,
    :func:`robot_yaml`): its path and its search box."""
    out = checked_target(args.out or Path("conf") / "robot" / f"{name}.yaml", args.force)
    box = search_box(cables, body, box)
    text = robot_yaml(cables, body, args.step, header, box)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_text(out, text)
    except OSError as exc:
        raise ConfigError(f"--out={out}: cannot write ({exc.strerror or exc})") from None
    return out, box


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m pipeline.caspr", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"cdpr-studies {code_version()}")
    parser.add_argument("cables", type=Path, help="CASPR <name>_cables.xml")
    parser.add_argument("--bodies", type=Path, help="CASPR <name>_bodies.xml (joint, limits, mass, centre of mass)")
    parser.add_argument("--cable-set", help="cable_set id (default: the file's default_cable_set)")
    target_arguments(parser)
    parser.add_argument("--number-cables", action="store_true",
                        help="name the cables 1, 2, ... in the file's order (for a file that names two alike)")
    args = parser.parse_args(argv)
    try:
        box = given_box(args)
        cables = read_cables(args.cables, args.cable_set, args.number_cables)
        body = read_body(args.bodies) if args.bodies is not None else None
        if body is None and "com" in cables["reference"]:
            raise ConfigError(f"{args.cables}: attachments relative to the centre of mass need --bodies")
        bodies = f" with {args.bodies.name} (link {body['name']!r}, joint {body['joint']})" if body else ""
        header = [f"Imported from CASPR: {args.cables.name} (cable set {str(cables['set'])!r}){bodies}.",
                  "Anchors: link 0, relative to the joint's origin; attachments: link 1 (platform frame, joint origin)."]
        out, box = write_robot(args, re.sub(r"_cables$", "", args.cables.stem).lower(), cables, body, header, box)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    lo, hi, origin = box
    mass = (f"platform {body['mass']:g} kg (bodies file)" if body is not None else
            "platform 0 kg (no --bodies: give the model's bodies file for its mass)")
    angles = body is not None and body["angles"]
    extent = ", ".join(f"{axis} [{a:g}, {b:g}]" for axis, a, b in zip(("psi", "theta", "phi") if angles else "xyz", lo, hi))
    unit = "rad" if angles else "m"
    print(f"wrote {out}: {len(cables['names'])} cables, {mass}; search box {extent} {unit} from {origin}, "
          f"step {args.step:g} {unit}" + ("; the joint holds the platform at the origin, the grid is of its "
                                          "orientations" if angles else ""))
    if body is not None and body["convention"] == "xyz":
        print("orientation: the file sets orientation.convention=xyz, CASPR's XYZ Euler angles "
              "(orientation.psi, theta, phi are its a, b, c)")
    print(f"run: python -m pipeline --config-dir {out.parent.parent} robot={out.stem}")

if __name__ == "__main__":
    main()

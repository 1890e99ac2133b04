"""Import a WireX robot file (``.wcrfx``, WireLib's model writer; Fraunhofer IPA's IPAnema family
and the other sample robots WireX ships) as a robot of this project: ``python -m pipeline.wirex
IPAnema.wcrfx --out myconf/robot/ipanema.yaml``.

Each ``<chain>`` is a cable: its ``<base>`` x, y, z the anchor and the pulley's fixed point, the
base frame's third column (a13, a23, a33) the pulley's swivel axis, along which the cable runs
into it (WireLib's ``doInverseKinematicsPulleyEx``: the pulley turns about the base frame's z axis),
and ``radius`` the pulley's radius (``robot.pulleys``; 0 for all: none written); its
``<platform>`` x, y, z the attachment point. ``<platform mass>`` and ``<centerofgravity>`` are the
platform's; the robot's ``motionpattern`` its freedoms (3R3T all six, 3T x, y, z, 1R2T x, y, rz,
2T x, y). The cable type (``<cable>``: ``elasticity`` E in Pa and ``radius`` in m) gives
``robot.cable_diameter`` and ``robot.cable_ea`` = E pi r^2, its ``weight`` (N/m, as WireLib's
cable sagging reads it) ``robot.cable_mass`` = weight / g, its ``max_length`` (when > 0)
``robot.l_max``, its ``minimum_load`` the tension's floor; each chain's winch type (``<winch>``)
its ``f_max``, the cable's rating. A file names no search box: ``--lo``/``--hi`` give one, else
the anchors' bounding box. Refused, in one line and exit status 2: a file that is not such XML, a
chain without a base or platform point, a base frame that is not a rotation, a winch type the file
does not describe, a motion pattern this project cannot model, values a cable cannot have. The
file written follows the CASPR importer's rules (``pipeline.caspr``): a new file of the user's,
never the package's.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from pipeline.app.config import MAX_FORCE, MAX_MASS
from pipeline.app.results import code_version
from pipeline.app.xmlfiles import parse_xml
from pipeline.caspr import JOINTS, _flow, given_box, target_arguments, write_robot
from pipeline.errors import ConfigError

# motion pattern -> the CASPR joint with the same freedoms and grid axes (pipeline.caspr.JOINTS)
PATTERNS = {"3R3T": "SPATIAL_QUATERNION", "3T": "T_XYZ", "1R2T": "PLANAR_XY", "2T": "P_XY"}
ROTATION = [f"a{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
GRAVITY = 9.81  # m/s^2: WireLib's cable weight is a force per length (its sagging code's w, N/m)
MAX_WEIGHT = 1000.0  # N/m: a cable heavier than 100 kg/m is a unit typed wrong  # a_ij: row i, column j of the base frame


def _floats(element, names, where: str) -> np.ndarray:
    """The attributes ``names`` of ``element`` as finite numbers, or ConfigError naming the first
    missing or bad one."""
    values = []
    for name in names:
        text = element.get(name)
        try:
            value = float(text)
        except (TypeError, ValueError):
            raise ConfigError(f"{where}: {name}={text!r} is not a number") from None
        if not np.isfinite(value):
            raise ConfigError(f"{where}: {name}={text!r} is not finite")
        values.append(value)
    return np.array(values)


def read_wirex(path: Path) -> tuple[dict, dict]:
    """The cables (the importers' dict of ``pipeline.caspr``) and the platform of a WireX file."""
    root = parse_xml(path)
    robot = root.find("robot")
    if root.tag != "models" or robot is None:
        raise ConfigError(f"{path}: root element <{root.tag}>, a WireX robot file has <models> with <robot>")
    pattern = robot.get("motionpattern", "3R3T")
    if pattern not in PATTERNS:
        raise ConfigError(f"{path}: motionpattern {pattern!r}: imported are {', '.join(PATTERNS)}")
    chains = robot.findall("geometry/chain")
    if not chains:
        raise ConfigError(f"{path}: no <geometry>/<chain> (a cable each)")
    winches = {w.get("name"): w for w in root.findall("winch")}
    kinds = root.findall("cable")
    if len(kinds) != 1:
        raise ConfigError(f"{path}: {len(kinds)} <cable> types: one is imported, the type of every chain")
    kind = kinds[0]
    where = f"{path}: <cable name={kind.get('name')!r}>"
    young, radius, floor, longest = _floats(kind, ("elasticity", "radius", "minimum_load", "max_length"), where)
    if not (0 < young and 0 < radius < 1 and 0 <= floor <= MAX_FORCE and 0 <= longest):
        raise ConfigError(f"{where}: elasticity {young:g} Pa, radius {radius:g} m, minimum_load {floor:g} N, "
                          f"max_length {longest:g} m: need E > 0, 0 < r < 1, 0 <= minimum_load <= {MAX_FORCE:g}")
    cables = {"names": [], "anchors": [], "attachments": [], "force_min": [], "force_max": [], "reference": [],
              "pulleys": []}
    for index, chain in enumerate(chains, start=1):
        where = f"{path}: chain {chain.get('id') or index}"
        base, platform = chain.find("base"), chain.find("platform")
        if base is None or platform is None:
            raise ConfigError(f"{where}: needs a <base> and a <platform> point")
        frame = _floats(base, ROTATION, f"{where} <base>").reshape(3, 3)
        if not (np.allclose(frame.T @ frame, np.eye(3), atol=1e-6) and np.linalg.det(frame) > 0):
            raise ConfigError(f"{where} <base>: a11..a33 are not a rotation (orthonormal, det +1)")
        pulley = _floats(base, ("radius",), f"{where} <base>")[0] if base.get("radius") is not None else 0.0
        if not 0 <= pulley < 1:
            raise ConfigError(f"{where} <base>: radius {pulley:g} m: need 0 <= radius < 1")
        winch = winches.get(chain.get("winchtype"))
        if winch is None or winch.find("cable") is None:
            raise ConfigError(f"{where}: winchtype {chain.get('winchtype')!r} is not a <winch> of the file")
        rating = _floats(winch.find("cable"), ("f_max",), f"{path}: <winch name={chain.get('winchtype')!r}>")[0]
        if not floor < rating <= MAX_FORCE:
            raise ConfigError(f"{where}: its winch's f_max {rating:g} N: need minimum_load {floor:g} < f_max <= "
                              f"{MAX_FORCE:g}")
        cables["names"].append(chain.get("id") or str(index))
        cables["anchors"].append(_floats(base, "xyz", f"{where} <base>").tolist())
        cables["attachments"].append(_floats(platform, "xyz", f"{where} <platform>").tolist())
        cables["reference"].append("joint")
        cables["force_min"].append(float(floor))
        cables["force_max"].append(float(rating))
        cables["pulleys"].append({"axis": frame[:, 2].tolist(), "radius": float(pulley)} if pulley > 0 else None)
    if len(set(cables["names"])) != len(chains):
        raise ConfigError(f"{path}: two chains share an id (each cable names its own columns)")
    weight = _floats(kind, ("weight",), where)[0] if kind.get("weight") is not None else 0.0
    if not 0 <= weight < MAX_WEIGHT:
        raise ConfigError(f"{where}: weight {weight:g} N/m: need 0 <= weight < {MAX_WEIGHT:g}")
    cables["robot"] = {"cable_diameter": repr(float(2 * radius)), "cable_ea": repr(float(young * np.pi * radius ** 2)),
                       **({"l_max": repr(float(longest))} if longest > 0 else {}),
                       **({"cable_mass": repr(float(weight / GRAVITY))} if weight > 0 else {})}
    platform = robot.find("platform")
    mass, com = 0.0, np.zeros(3)
    if platform is not None:
        mass = _floats(platform, ("mass",), f"{path}: <platform>")[0]
        gravity = platform.find("centerofgravity")
        com = _floats(gravity, "xyz", f"{path}: <centerofgravity>") if gravity is not None else com
        if not 0 <= mass <= MAX_MASS:
            raise ConfigError(f"{path}: <platform> mass {mass:g} must be in [0, {MAX_MASS:g}] kg")
    body = {"name": robot.get("name") or "", "joint": PATTERNS[pattern], "dofs": JOINTS[PATTERNS[pattern]][0],
            "mass": float(mass), "box": None,
            "convention": "zyx", "angles": False, "com": com.tolist(), "origin": np.zeros(3)}
    return cables, body


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m pipeline.wirex", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"cdpr-studies {code_version()}")
    parser.add_argument("robot", type=Path, help="WireX robot file (.wcrfx)")
    target_arguments(parser)
    args = parser.parse_args(argv)
    try:
        box = given_box(args)
        cables, body = read_wirex(args.robot)
        header = [f"Imported from WireX: {args.robot.name} (robot {body['name']!r}).",
                  "Anchors: the chains' base points (the pulleys' fixed points); attachments: their platform points."]
        out, box = write_robot(args, args.robot.stem.lower(), cables, body, header, box)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    lo, hi, origin = box
    pulleys = sum(p is not None for p in cables["pulleys"])
    print(f"wrote {out}: {len(cables['names'])} cables ({pulleys} over pulleys), platform {body['mass']:g} kg; "
          f"search box {_flow(lo)} to {_flow(hi)} m from {origin}, step {args.step:g} m")
    print(f"run: python -m pipeline --config-dir {out.parent.parent} robot={out.stem}")


if __name__ == "__main__":
    main()

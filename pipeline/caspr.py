"""Import a CASPR model (``<name>_cables.xml`` and ``<name>_bodies.xml``) as a robot file.

``python -m pipeline.caspr NAME_cables.xml [--bodies NAME_bodies.xml] [--cable-set ID]
[--step 0.1] [--out conf/robot/NAME.yaml]`` writes a robot YAML file for ``robot=points``
(run it with ``python -m pipeline --config-dir conf robot=NAME``). CASPR's spatial models
(IPAnema, CoGiRo, ...) describe each cable by its attachment on link 0 (the frame: our anchor)
and on link 1 (the platform: our attachment point, in the platform frame) with ``force_min`` and
``force_max`` (N); the bodies file gives the platform's ``mass`` (kg) and ``com_location`` (m).
The file written sets ``tension.t_min``/``t_max`` (one value, or one per cable where they differ)
and ``load.mass``/``load.com``, so it is a global-package robot file like ``irpm6.yaml``. The
search box is ``--lo``/``--hi`` when given, else the bodies file's ``display_range``, else the
anchors' bounding box; it is sampled at the cell centres of side ``--step``.

Only single-body models with straight cables are imported (one rigid link, two attachments per
cable); anything else, or a file that is not such XML, stops with one line and exit status 2.

The importer writes only a new file of the user's: an existing file is replaced only with
``--force``, a target inside the package's own ``conf/`` (where it would replace or hide a
shipped file: run from a checkout, ``conf/robot/`` is that folder) is refused, and so is a
shipped robot's name (``cpr8``, ``irpm6``, ``points``), which the file would hide under
``--config-dir``. Names from the files (the source's, the cables') are written as quoted YAML
scalars or with control characters replaced, so no name can become a key.
"""

from __future__ import annotations

import argparse
import re
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np

from pipeline.errors import ConfigError
from pipeline.app.config import MAX_FORCE
from pipeline.app.resources import CONF_DIR
from pipeline.app.results import code_version, write_text

SHIPPED_ROBOTS = tuple(sorted(p.stem for p in (CONF_DIR / "robot").glob("*.yaml")))


def read_cables(path: Path, cable_set: str | None = None) -> dict:
    """Anchors, attachments (link 1, as given), names, force limits and the attachment
    reference of every cable of one cable set (the file's default set unless named)."""
    root = _parse(path)
    if root.tag != "cables":
        raise ConfigError(f"{path}: root element <{root.tag}>, a CASPR cables file has <cables>")
    wanted = cable_set or root.get("default_cable_set")
    sets = root.findall("cable_set")
    chosen = [s for s in sets if s.get("id") == wanted] if wanted else sets[:1]
    if not chosen:
        ids = ", ".join(str(s.get("id")) for s in sets) or "none"
        raise ConfigError(f"{path}: no cable_set {wanted!r} (cable sets: {ids})")
    cables = list(chosen[0])
    if not cables:
        raise ConfigError(f"{path}: cable_set {wanted!r} has no cables")
    out = {"names": [], "anchors": [], "attachments": [], "force_min": [], "force_max": [], "reference": []}
    for number, cable in enumerate(cables, start=1):
        where = f"{path}: cable {cable.get('name') or number}"
        if cable.tag != "cable_ideal":
            raise ConfigError(f"{where}: <{cable.tag}> is not supported (only <cable_ideal>)")
        name = cable.get("name") or str(number)
        if name in out["names"]:
            raise ConfigError(f"{where}: a second cable of this name (each cable names its own columns)")
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
        links = [(_text(attachment, "link", where), _vector(attachment, "location", where))
                 for attachment in cable.findall("attachments/attachment")]
        if sorted(link for link, _ in links) != ["0", "1"]:
            raise ConfigError(f"{where}: needs one attachment on link 0 and one on link 1, found "
                              f"links {sorted(link for link, _ in links) or 'none'} (multi-link models are not supported)")
        out["anchors"].append(dict(links)["0"])
        out["attachments"].append(dict(links)["1"])
    return out


def read_body(path: Path) -> dict:
    """Mass (kg) and centre of mass (m, joint frame) of the single rigid link of a bodies file."""
    root = _parse(path)
    links = root.findall("link_rigid")
    if root.tag != "links" or len(links) != 1:
        raise ConfigError(f"{path}: needs <links> with exactly one <link_rigid> (found {len(links)})")
    where = f"{path}: link {links[0].get('num', '1')}"
    mass = _number(links[0], "physical/mass", where)
    if not mass >= 0:
        raise ConfigError(f"{where}: mass {mass:g} must be >= 0")
    box = None
    if root.get("display_range"):
        try:
            box = np.array([float(v) for v in root.get("display_range").split()]).reshape(3, 2)
        except ValueError:
            raise ConfigError(f"{path}: display_range {root.get('display_range')!r} is not 6 numbers") from None
        if not np.isfinite(box).all() or not (box[:, 0] < box[:, 1]).all():
            raise ConfigError(f"{path}: display_range {root.get('display_range')!r} is not lo < hi per axis")
    return {"mass": mass, "com": _vector(links[0], "physical/com_location", where), "box": box}


def robot_yaml(cables: dict, body: dict | None, step: float, source: str, box=None) -> str:
    """The robot file's text (YAML flow style, one cable per line); ``box`` (lo, hi) or None."""
    com = np.zeros(3) if body is None else np.asarray(body["com"])
    attachments = [np.asarray(a) + (com if ref == "com" else 0.0)
                   for a, ref in zip(cables["attachments"], cables["reference"])]
    anchors = np.asarray(cables["anchors"])
    if box is not None:
        lo, hi = box
    elif body is not None and body["box"] is not None:
        lo, hi = body["box"][:, 0], body["box"][:, 1]
    else:
        lo, hi = anchors.min(axis=0), anchors.max(axis=0)
    lines = [
        "# @package _global_",
        f"# Imported from CASPR: {_one_line(source)}. Anchors: link 0; attachments: link 1 (platform frame).",
        "defaults:",
        "  - /robot/points",
        "  - _self_",
        "robot:",
        "  anchors:",
        *[f"    - {_flow(a)}" for a in anchors],
        "  attachments:",
        *[f"    - {_flow(a)}" for a in attachments],
        f"  cable_names: [{', '.join(_quoted(n) for n in cables['names'])}]",
        f"  search: {{lo: {_flow(lo)}, hi: {_flow(hi)}, step: {step!r}, spacing: centres}}",
        f"tension: {{t_min: {_limit(cables['force_min'])}, t_max: {_limit(cables['force_max'])}}}",
    ]
    if body is not None:
        lines.append(f"load: {{mass: {body['mass']!r}, com: {_flow(com)}}}")
    return "\n".join(lines) + "\n"


def _parse(path: Path) -> ElementTree.Element:
    try:
        return ElementTree.parse(path).getroot()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read ({exc.strerror or exc})") from None
    except ElementTree.ParseError as exc:
        raise ConfigError(f"{path}: not well-formed XML ({exc})") from None


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
    """``out`` if the importer may write it, else ConfigError saying why and what to do."""
    if out.stem in SHIPPED_ROBOTS:
        raise ConfigError(f"--out={out}: robot={out.stem} is a shipped robot, which this file would hide "
                          f"under --config-dir; choose another name (shipped: {', '.join(SHIPPED_ROBOTS)})")
    if out.resolve().is_relative_to(CONF_DIR.resolve()):
        raise ConfigError(f"--out={out}: inside the package's own configs ({CONF_DIR.resolve()}); write to a "
                          "folder of your own, e.g. --out myconf/robot/NAME.yaml, and run with --config-dir myconf")
    if out.exists() and not force:
        raise ConfigError(f"--out={out}: exists; give --force to replace it")
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m pipeline.caspr", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"cdpr-studies {code_version()}")
    parser.add_argument("cables", type=Path, help="CASPR <name>_cables.xml")
    parser.add_argument("--bodies", type=Path, help="CASPR <name>_bodies.xml (mass, centre of mass)")
    parser.add_argument("--cable-set", help="cable_set id (default: the file's default_cable_set)")
    parser.add_argument("--step", type=float, default=0.1, help="search grid step, m (default 0.1)")
    parser.add_argument("--out", type=Path, help="file to write (default conf/robot/<name>.yaml)")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file")
    parser.add_argument("--lo", type=float, nargs=3, help="search box corner x y z, m")
    parser.add_argument("--hi", type=float, nargs=3, help="search box corner x y z, m")
    args = parser.parse_args(argv)
    try:
        if not 0 < args.step < np.inf:
            raise ConfigError(f"--step={args.step}: must be > 0 and finite")
        box = None
        if (args.lo is None) != (args.hi is None):
            raise ConfigError("--lo and --hi: give both corners of the search box, or neither")
        if args.lo is not None:
            box = np.array(args.lo), np.array(args.hi)
            if not (np.isfinite(box).all() and (box[0] <= box[1]).all()):
                raise ConfigError(f"--lo={args.lo} --hi={args.hi}: must be finite with lo <= hi")
        cables = read_cables(args.cables, args.cable_set)
        body = read_body(args.bodies) if args.bodies is not None else None
        if body is None and "com" in cables["reference"]:
            raise ConfigError(f"{args.cables}: attachments relative to the centre of mass need --bodies")
        name = re.sub(r"_cables$", "", args.cables.stem).lower()
        out = checked_target(args.out or Path("conf") / "robot" / f"{name}.yaml", args.force)
        text = robot_yaml(cables, body, args.step, args.cables.name, box)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            write_text(out, text)
        except OSError as exc:
            raise ConfigError(f"--out={out}: cannot write ({exc.strerror or exc})") from None
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    print(f"wrote {out}: {len(cables['names'])} cables; run python -m pipeline --config-dir "
          f"{out.parent.parent} robot={out.stem}")


if __name__ == "__main__":
    main()

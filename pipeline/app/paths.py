"""The ``trajectory`` node becomes the platform's path, sampled (``analysis=trajectory``;
``pipeline.model.path``; docs/model.md section 11).

The way-points come from ``trajectory.points`` or ``trajectory.file``, one of them:

- ``trajectory.points``: [[x, y, z], ...] (m; at the orientation ``orientation.*``), or
  [[x, y, z, psi, theta, phi], ...] (rad, in ``orientation.convention``); for a robot whose
  reference point a joint holds, its angles [[psi, theta, phi], ...]. The time law
  ``trajectory.law``: ``quintic`` or ``spline`` with each segment's duration ``trajectory.times``
  (one value for every segment, or one per segment), ``trapezoid`` with ``trajectory.v_max``,
  ``t_acc`` and ``t_dec``.
- ``trajectory.file``: a CASPR trajectories file (``.xml``: its spline with each point's rates
  and times; its q lists the robot's freedoms, ``robot.dofs``, in order, as CASPR's joints do;
  ``trajectory.name`` picks one of several) or a CSV of timed way-points (``.csv``: a header
  ``t,x,y,z`` or ``t,x,y,z,psi,theta,phi``, a joint's ``t,psi,theta,phi``; s, m, rad), followed
  by ``quintic`` or ``spline``.

Samples every ``trajectory.dt`` or less (null: 0.01 s, or a CASPR file's ``time_step``); at most
``compute.max_poses`` of them, and 10^6 (the samples table is built whole). Anything else is refused in one line naming the key.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path as FilePath

import numpy as np
from omegaconf import DictConfig, OmegaConf

from pipeline.app.config import MAX_ACCELERATION, TRAPEZOID_KEYS, trapezoid_speeds
from pipeline.app.xmlfiles import parse_xml
from pipeline.errors import ConfigError
from pipeline.model.geometry import CableRobot
from pipeline.model.path import (MAX_SAMPLES, Path, Samples, StraightMotion, durations, hermite, rest_to_rest, spline,
                                 trapezoidal)

DEFAULT_DT = 0.01  # s between samples, when neither trajectory.dt nor a CASPR file gives one
MAX_WAY_POINTS = 1_000_000
MAX_COORDINATE = 1e6  # m or rad: past any cable robot's workspace, a unit typed wrong
TIMED = ("quintic", "spline")  # the laws that take each segment's duration


def path_samples(cfg: DictConfig, robot: CableRobot) -> Samples:
    """The path ``cfg.trajectory`` gives (module doc), sampled."""
    node = cfg.trajectory
    law = node.law.name if hasattr(node.law, "name") else str(node.law)
    if node.points is None and node.file is None:
        raise ConfigError("trajectory.points: no value given (the way-points, or trajectory.file: a file of them)")
    if node.points is not None and node.file is not None:
        raise ConfigError("trajectory.points: the way-points come from trajectory.points or trajectory.file, "
                          "not both")
    if node.file is None and node.name is not None:
        raise ConfigError(f"trajectory.name={node.name}: names a trajectory of a CASPR file (trajectory.file)")
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # times too short: refused below, by the peak
        path, step = (_from_file(node, law, robot, cfg.orientation) if node.file is not None
                      else (_from_points(node, law, robot, cfg.orientation), None))
    dt = float(node.dt) if node.dt is not None else (step or DEFAULT_DT)
    count = float(path.counts(dt).sum())
    if count > min(cfg.compute.max_poses, MAX_SAMPLES):
        bound = (f"compute.max_poses={cfg.compute.max_poses}" if cfg.compute.max_poses < MAX_SAMPLES else
                 f"{MAX_SAMPLES:,} (a path's samples are held whole: about 0.5 kB each)")
        raise ConfigError(f"trajectory.dt={dt:g}: {count:.3g} samples over the path's {path.duration:g} s, more than "
                          f"{bound}; a longer step, or the path in parts")
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        samples = path.sample(dt)
    peak = float(np.abs(samples.q_ddot).max(initial=0.0)) if np.isfinite(samples.q_ddot).all() else math.inf
    if peak > MAX_ACCELERATION:
        key = "trajectory.file" if node.file is not None else "trajectory.times" if law in TIMED else "trajectory.t_acc"
        raise ConfigError(f"{key}: the path accelerates at {peak:.3g} m/s^2 (or rad/s^2), more than {MAX_ACCELERATION:g}: "
                          "a unit typed wrong, or times too short")
    return samples


def _from_points(node: DictConfig, law: str, robot: CableRobot, orientation: DictConfig) -> Path:
    points = _placed(_table(_shown(node.points), "trajectory.points"), robot, orientation, "trajectory.points")
    if law == "trapezoid":
        if node.times is not None:
            raise ConfigError(f"trajectory.times={_shown(node.times)}: law trapezoid times each segment by its "
                              "length and trajectory.v_max, t_acc, t_dec; times are for law quintic or spline")
        speeds = trapezoid_speeds(node, "trajectory")
        try:
            return trapezoidal(points, *speeds)
        except ValueError as exc:
            raise ConfigError(f"trajectory.points: {exc}") from None
    _no_speeds(node, law)
    if node.times is None:
        raise ConfigError("trajectory.times: each segment's duration (s), one value for every segment or one per "
                          "segment; or law trapezoid (trajectory.v_max, t_acc, t_dec)")
    return _timed(law, points, durations(_shown(node.times), len(points) - 1, "trajectory.times"))


def _from_file(node: DictConfig, law: str, robot: CableRobot, orientation: DictConfig) -> tuple[Path, float | None]:
    given = FilePath(str(node.file)).expanduser()
    if node.times is not None:
        raise ConfigError(f"trajectory.times={_shown(node.times)}: trajectory.file gives the times")
    suffix = given.suffix.lower()
    if suffix not in (".xml", ".csv"):
        raise ConfigError(f"trajectory.file={node.file}: a CASPR trajectories file (.xml) or a CSV of timed "
                          "way-points (.csv)")
    if not given.is_file():
        raise ConfigError(f"trajectory.file={node.file}: no such file")
    _no_speeds(node, law)
    if suffix == ".xml":
        if law != "quintic":
            raise ConfigError(f"trajectory.law={law}: a CASPR file is followed by its own splines (quintic or cubic, "
                              "with each point's rates); leave trajectory.law at quintic")
        found = read_caspr_trajectory(given, None if node.name is None else str(node.name))
        where = f"trajectory.file={node.file} ({found['id']})"
        q = found["q"]
        if q.shape[1] != len(robot.dofs):
            raise ConfigError(f"{where}: its q has {q.shape[1]} coordinates, the robot {len(robot.dofs)} freedoms "
                              "(robot.dofs); a CASPR trajectory lists the coordinates of its model's joint")
        _bounded(q, where)
        points, rates = _on_freedoms(q, robot, orientation), [_on_freedoms(r, robot, None) for r in found["rates"]]
        return hermite(points, found["durations"], rates), found["time_step"]
    if node.name is not None:
        raise ConfigError(f"trajectory.name={node.name}: names a trajectory of a CASPR file (.xml), not of a CSV")
    times, values = _read_csv(given, robot, f"trajectory.file={node.file}")
    points = _placed(values, robot, orientation, f"trajectory.file={node.file}")
    return _timed(law, points, np.diff(times)), None


# CASPR's trajectory elements (its _trajectories.xml): the derivatives each point gives its
# Hermite polynomials (pipeline.model.path.hermite), by element
SPLINES = {"quintic_spline_trajectory": ("q_dot", "q_ddot"), "cubic_spline_trajectory": ("q_dot",)}


def read_caspr_trajectory(path: FilePath, name: str | None = None) -> dict:
    """One trajectory of a CASPR ``<name>_trajectories.xml`` (its ``<joint_trajectories>``; the
    operational-space ones are not read): ``id``, its points' coordinates ``q`` (k, d), the
    derivatives its spline matches at each point (``rates``: [q_dot] for a cubic, [q_dot,
    q_ddot] for a quintic, each (k, d), zeros where a point gives none), each segment's duration (``durations``, s: each point's
    ``time`` after the previous one, ``time_definition="relative"``, or from the start,
    ``"absolute"``) and its ``time_step`` (s). ``name``: the trajectory's id (None: the file's
    only one). ConfigError in one line for a file without such a trajectory, an id it lacks, a
    linear spline (its velocity jumps at every point), a point without finite coordinates of
    the first point's count, or times that do not increase."""
    root = parse_xml(path)
    groups = [root] if root.tag == "joint_trajectories" else root.findall(".//joint_trajectories")
    found = [element for group in groups for element in group]  # operational-space ones are not the joint's
    ids = [str(element.get("id")) for element in found]
    if not found:
        raise ConfigError(f"{path}: no joint trajectory (CASPR's <joint_trajectories> with a "
                          "<quintic_spline_trajectory> or <cubic_spline_trajectory>)")
    if name is None and len(found) > 1:
        raise ConfigError(f"trajectory.name: {path.name} holds {len(found)} trajectories ({', '.join(ids)}); name one")
    if name is not None and name not in ids:
        raise ConfigError(f"trajectory.name={name}: {path.name} has no trajectory of that id ({', '.join(ids)})")
    element = found[0] if name is None else found[ids.index(name)]
    where = f"{path.name}: trajectory {element.get('id')!r}"
    if element.tag not in SPLINES:
        why = ("a linear spline's velocity jumps at every point (an infinite acceleration)"
               if element.tag == "linear_spline_trajectory" else "its interpolation is not CASPR's quintic or cubic spline")
        raise ConfigError(f"{where}: <{element.tag}>: {why}; a quintic_spline_trajectory or "
                          "cubic_spline_trajectory, or trajectory.points with a time law, can be followed")
    points = element.findall("./points/point")
    if len(points) < 2:
        raise ConfigError(f"{where}: needs at least 2 <point>s, has {len(points)}")
    q = [_coordinates(point, "q", f"{where}, point {i + 1}", None) for i, point in enumerate(points)]
    size = len(q[0])
    q = [_coordinates(point, "q", f"{where}, point {i + 1}", size) for i, point in enumerate(points)]
    rates = [np.array([_coordinates(point, tag, f"{where}, point {i + 1}", size, missing=True)
                       for i, point in enumerate(points)]) for tag in SPLINES[element.tag]]
    times = []
    for i, point in enumerate(points[1:], start=2):
        try:
            times.append(float(point.get("time", "")))
        except ValueError:
            raise ConfigError(f"{where}, point {i}: time={point.get('time')!r} is not a number of seconds") from None
    times = np.array(times)
    durations = np.diff(np.concatenate([[0.0], times])) if element.get("time_definition") == "absolute" else times
    if not (np.isfinite(durations).all() and (durations > 0).all()):
        raise ConfigError(f"{where}: each point's time must come after the previous point's (times {times.tolist()} s, "
                          f"time_definition={element.get('time_definition')!r})")
    try:
        step = float(element.get("time_step", "nan"))
    except ValueError:
        step = float("nan")
    return {"id": element.get("id"), "q": np.array(q), "rates": rates, "durations": durations,
            "time_step": step if np.isfinite(step) and step > 0 else None}


def _coordinates(point, tag: str, where: str, size: int | None, missing: bool = False) -> np.ndarray:
    """The finite numbers of a point's ``<tag>`` (``size`` of them when given); zeros when
    ``missing`` allows the tag to be absent."""
    found = point.find(tag)
    if found is None and missing:
        return np.zeros(size)
    text = "" if found is None else (found.text or "")
    try:
        values = np.array([float(p) for p in text.split()])
    except ValueError:
        values = np.array([np.nan])
    if not len(values) or not np.isfinite(values).all() or (size is not None and len(values) != size):
        count = "finite numbers" if size is None else f"{size} finite numbers, as the first point's <q>"
        raise ConfigError(f"{where}: <{tag}> {text.strip()!r} is not {count}")
    return values


def _timed(law: str, points: np.ndarray, durations: np.ndarray) -> Path:
    return rest_to_rest(points, durations) if law == "quintic" else spline(points, durations)


def _no_speeds(node: DictConfig, law: str) -> None:
    given = [key for key in TRAPEZOID_KEYS if node[key] is not None]
    if given:
        raise ConfigError(f"trajectory.{given[0]}={node[given[0]]}: the trapezoidal law's; law {law} times the "
                          "segments by trajectory.times or the file's times")


def _table(values, key: str) -> np.ndarray:
    """(k, d) the way-points of a list of lists, at least 2, of one length, finite and bounded."""
    if not isinstance(values, list) or len(values) < 2 or not all(isinstance(row, list) for row in values):
        raise ConfigError(f"{key}={_shown(values)}: a list of at least 2 way-points, each a list of numbers")
    if len(values) > MAX_WAY_POINTS:
        raise ConfigError(f"{key}: {len(values)} way-points, at most {MAX_WAY_POINTS}")
    sizes = sorted({len(row) for row in values})
    if len(sizes) != 1:
        raise ConfigError(f"{key}: way-points of {' and '.join(map(str, sizes))} values; every way-point has the same")
    if not all(_number(value) for row in values for value in row):
        raise ConfigError(f"{key}={values}: every value must be a number")
    table = np.array(values, dtype=float)
    _bounded(table, key)
    return table


def _bounded(table: np.ndarray, key: str) -> None:
    if not np.isfinite(table).all() or (np.abs(table) > MAX_COORDINATE).any():
        row = int(np.flatnonzero(~(np.abs(table) <= MAX_COORDINATE).all(axis=1))[0])
        raise ConfigError(f"{key}: way-point {row + 1} {table[row].tolist()}: every value must be finite and at most "
                          f"{MAX_COORDINATE:g} in magnitude (m, rad)")


def _placed(table: np.ndarray, robot: CableRobot, orientation: DictConfig, key: str) -> np.ndarray:
    """(k, 6) q of way-points of 3 or 6 values (module doc)."""
    q = np.zeros((len(table), 6))
    size = table.shape[1]
    if robot.fixed_point:
        if size != 3:
            raise ConfigError(f"{key}: way-points of {size} values; the robot's joint holds its reference point, "
                              "so a way-point is its orientation [psi, theta, phi] (rad, orientation.convention)")
        q[:, 3:] = table
    elif size in (3, 6):
        q[:, :size] = table
        if size == 3:
            q[:, 3:] = [float(orientation[angle]) for angle in ("psi", "theta", "phi")]
    else:
        raise ConfigError(f"{key}: way-points of {size} values; [x, y, z] (m, at orientation.*) or "
                          "[x, y, z, psi, theta, phi] (m, rad in orientation.convention)")
    return q


def _on_freedoms(values: np.ndarray, robot: CableRobot, orientation: DictConfig | None) -> np.ndarray:
    """(k, 6) CASPR's coordinates (k, d) on the robot's freedoms, in their order (x y z rx ry rz,
    as its joints list them); the other positions 0 (the joint's origin), the other angles
    ``orientation``'s (rates: 0)."""
    q = np.zeros((len(values), 6))
    if orientation is not None and not robot.fixed_point:
        q[:, 3:] = [float(orientation[angle]) for angle in ("psi", "theta", "phi")]
    q[:, list(robot.dofs)] = values
    return q


def _read_csv(path: FilePath, robot: CableRobot, key: str) -> tuple[np.ndarray, np.ndarray]:
    """(times (k,), values (k, d)) of a CSV of timed way-points (module doc)."""
    headers = ([["t", "psi", "theta", "phi"]] if robot.fixed_point
               else [["t", "x", "y", "z"], ["t", "x", "y", "z", "psi", "theta", "phi"]])
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:  # a spreadsheet's byte-order mark too
            rows = [row for row in csv.reader(handle) if any(cell.strip() for cell in row)]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ConfigError(f"{key}: cannot read it as CSV text ({exc})") from None
    header = [cell.strip() for cell in rows[0]] if rows else []
    if header not in headers:
        raise ConfigError(f"{key}: its header is {','.join(header) or 'empty'}; needs "
                          + " or ".join(",".join(h) for h in headers))
    if len(rows) > MAX_WAY_POINTS + 1:
        raise ConfigError(f"{key}: {len(rows) - 1} way-points, at most {MAX_WAY_POINTS}")
    table = []
    for number, row in enumerate(rows[1:], start=2):
        try:
            values = [float(cell) for cell in row]
        except ValueError:
            values = []
        if len(values) != len(header):
            raise ConfigError(f"{key}: row {number} {','.join(row)!r} is not {len(header)} numbers")
        table.append(values)
    if len(table) < 2:
        raise ConfigError(f"{key}: needs at least 2 way-points, has {len(table)}")
    table = np.array(table)
    _bounded(table, key)
    times = table[:, 0]
    if not (np.diff(times) > 0).all():
        row = int(np.flatnonzero(np.diff(times) <= 0)[0]) + 3  # file row of the first time that does not increase
        raise ConfigError(f"{key}: row {row}: t={times[row - 2]:g} s does not come after the previous row's")
    return times, table[:, 1:]


def _shown(value):
    return OmegaConf.to_container(value) if OmegaConf.is_config(value) else value


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def certified_motion(cfg: DictConfig, points: np.ndarray) -> StraightMotion | None:
    """``certified.path``'s motion (``analysis=certified``): None at rest (law quintic without
    ``times``), else the law of ``certified.law``; ConfigError naming the key for a key of the
    other law, one missing, or an acceleration past MAX_ACCELERATION."""
    node = cfg.certified
    given = [key for key in TRAPEZOID_KEYS if node[key] is not None]
    if node.law == "quintic":
        if given:
            raise ConfigError(f"certified.{given[0]}: a trapezoid's speed profile; set certified.law=trapezoid "
                              "(the quintic law takes certified.times)")
        if node.times is None:
            return None
        motion = StraightMotion.quintic(points, durations(_shown(node.times), len(points) - 1, "certified.times"))
        key = "certified.times"
    else:
        if node.times is not None:
            raise ConfigError("certified.times: law trapezoid times each segment by certified.v_max, t_acc and t_dec; "
                              "leave certified.times null")
        motion = StraightMotion.trapezoid(points, *trapezoid_speeds(node, "certified"))
        key = "certified.t_acc"
    peaks = motion.peaks()
    if not peaks.max() <= MAX_ACCELERATION:
        raise ConfigError(f"{key}: segment {int(np.argmax(peaks)) + 1} accelerates at {peaks.max():.3g} m/s^2, "
                          f"more than {MAX_ACCELERATION:g}: a unit typed wrong, or times too short")
    return motion

"""One job (:func:`execute`): points.parquet (samples.parquet for lines) and, last, summary.parquet
in its folder.

A job whose folder already holds a summary.parquet written with the same resolved config and
the same code version is not recomputed: every file is written to a temporary name and renamed
(``pipeline.app.results.write_parquet``), and the summary is written last, so its presence proves
the job finished. A sweep killed mid-way therefore resumes with only the missing jobs. Before a
finished job is reused its data files are checked against the sha256 digests its summary
recorded; an unreadable summary or a changed data file is recomputed, with a log line.

One writer per folder: a job holds an exclusive lock on ``<folder>/.lock`` while it works, and
a second job started into the same folder stops at once with one line and exit status 2.
"""

from __future__ import annotations

import fcntl
import json
import logging
from contextlib import contextmanager
from pathlib import Path
from typing import Callable

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from omegaconf import DictConfig

from pipeline.app.plan import Job
from pipeline.errors import ConfigError
from pipeline.app.readings import describe_reading
from pipeline.app.yamltext import to_yaml
from pipeline.app.results import (
    CONFIG_KEY, DIGESTS_KEY, READ_ERRORS, VERSION_KEY, ParquetSink, code_version, digests_json, file_digest,
    read_metadata, read_verified, replacing, write_parquet,
)
from pipeline.workspace.arrow import one_row
from pipeline.app.problem import ANALYSES, build_grid
from pipeline.model.geometry import PoseGeometry
from pipeline.workspace.criteria import REGISTRY
from pipeline.workspace.criteria.interference import pair_clearances
from pipeline.workspace.kernel import WorkspaceProblem

log = logging.getLogger("pipeline")
TENSION_MODELS = {  # what each tension model checks, for the job's log
    "pinv": "the papers' minimum-norm cable forces, which may push; tension=feasible: cables that only pull",
    "feasible": "cables that only pull; tension=pinv: the papers' minimum-norm forces, which may push",
}


def execute(job: Job) -> dict:
    """Run one planned job (:mod:`pipeline.app.plan`) into its folder, made if needed, under its
    lock (or reuse it when finished); returns the summary. Output errors (a full disk, a folder
    gone read-only while writing) are raised as ConfigError naming the path."""
    out = job.folder
    try:
        out.mkdir(parents=True, exist_ok=True)
        with folder_lock(out):
            return _run_locked(job.cfg, job.problem, out, job.fused, job.robot_file)
    except OSError as exc:
        raise ConfigError(f"cannot write {exc.filename or out}: {exc.strerror or exc}") from None


@contextmanager
def folder_lock(out: Path, busy: str = "another run is writing this folder; wait for it or "
                                        "choose another (hydra.run.dir=...)"):
    """An exclusive lock on ``out/.lock`` for the duration of the block, or ConfigError
    ``{out}: {busy}`` at once when another process holds it."""
    with open(out / ".lock", "a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(f"{out}: {busy}") from None
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


# what a job writes
JOB_FILES = ("summary.parquet", "points.parquet", "samples.parquet", "boxes.parquet", "segments.parquet", "boundary.stl",
             "boundary.ply")


def _run_locked(cfg: DictConfig, problem: WorkspaceProblem, out: Path, sweep_pays: bool, robot_file: str) -> dict:
    config_yaml = to_yaml(cfg, resolve=True)
    done = finished_summary(out, config_yaml)
    if done is not None:
        log.info("reused the finished job in %s (same config and code version)", out)
        return done
    for name in JOB_FILES:  # found only when the file is written, after the computation
        if (out / name).exists() and not (out / name).is_file():
            raise ConfigError(f"{out / name}: not a file, where the job writes its {name}; move it or "
                              "choose another folder (hydra.run.dir=...)")
    log.info("reading: %s (docs/evidence.md, sections 1-2)", describe_reading(cfg.model))
    log.info("tension model: %s (%s)", cfg.tension.model.value, TENSION_MODELS[cfg.tension.model.value])
    crossing = touching_at_centre(problem)
    if crossing:
        log.warning("cables %s touch at the centre of the search box (robot.cable_diameter): cables that cross "
                    "in one plane touch at every pose; leave their attachments at staggered heights "
                    "(docs/robots.md)", ", ".join(crossing))
    files = JobFiles(out, config_yaml)
    kind = ANALYSES[cfg.analysis]
    summary = kind.files(cfg, problem, build_grid(cfg, problem.robot) if kind.gridded else None, files, sweep_pays)
    summary["robot_file"] = robot_file  # which of a study's robot files (robot.name: its kind)
    write_parquet(one_row(summary), out / "summary.parquet", config_yaml,
                  {DIGESTS_KEY: digests_json(files.written)})
    if kind.certified:  # its own line: the volume's bracket (pipeline.workspace.paving)
        return summary
    lost = ", ".join(
        f"{key[len('lost_'):]} {value}" for key, value in summary.items() if key.startswith("lost_")
    )
    subject = (f"actuator {cfg.actuator} ({summary['actuator_name']})"
               if "actuator_name" in summary else f"{cfg.robot.name} {summary['analysis']}")
    headroom = ", ".join(f"{key[len('least_margin_'):]} {100 * value:.1f}%" for key, value in summary.items()
                         if key.startswith("least_margin_") and value == value)  # NaN: none feasible
    poses = "poses" if kind.gridded else "samples"
    log.info(
        "%s: %d/%d %s feasible = %.2f%%%s; lost to %s%s", subject, summary["n_feasible"], summary["n_points"], poses,
        summary["feasible_pct"], f" ({summary['volume_m3']:.4f} m^3)" if kind.gridded else "",
        lost, f"; headroom of the feasible {poses}: {headroom}" if headroom else "",
    )
    if summary["n_feasible"] == 0 and summary["n_points"] > 0:
        log.warning("no %s is feasible: %s", poses[:-1], zero_cause(summary))
    return summary


def touching_at_centre(problem: WorkspaceProblem) -> list[str]:
    """The pairs of cables (``i-j`` by their names) that touch at the search box's centre at the
    nominal orientation, under ``robot.cable_diameter``: a design check before the grid runs."""
    robot = problem.robot
    if robot.cable_radii is None or problem.angles is not None or not np.isfinite(robot.box_lo).all():
        return []
    state = PoseGeometry(robot, ((robot.box_lo + robot.box_hi) / 2)[None], problem.orientations[0])
    names, (i, j) = robot.cable_names, robot.cable_pairs
    return [f"{names[a]}-{names[b]}" for a, b, gap in zip(i, j, pair_clearances(state)[0]) if gap < 0]


def zero_cause(summary: dict) -> str:
    """Why a job kept no pose, and what to try: the criterion most poses are lost to first (a
    violated gate decides first) and, where another criterion alone removes poses (every other
    criterion holding there), the one that removes the most and its remedy: relaxing it alone
    would win them."""
    def largest(prefix: str) -> tuple[int, str | None]:
        return max(((value, key[len(prefix):]) for key, value in summary.items()
                    if key.startswith(prefix) and key[len(prefix):] in REGISTRY), default=(0, None))

    count, name = largest("lost_")
    alone, culprit = largest("alone_")
    first = f"{count} of {summary['n_points']} are lost to {name} first"
    if alone == 0 or culprit == name:
        return f"{first}; to try next: {REGISTRY[name].remedy}"
    return (f"{first}, but {culprit} alone removes {alone} (every other criterion holds there); "
            f"to try next: {REGISTRY[culprit].remedy}")


class JobFiles:
    """The data files of one job in its folder, each under a temporary name until complete
    (``pipeline.app.results``): a table written whole (:meth:`write`) or chunk by chunk
    (:meth:`stream`); ``written``: their paths in the order they were completed, whose digests
    the summary records."""

    def __init__(self, folder: Path, config_yaml: str):
        self.folder = folder
        self.config_yaml = config_yaml
        self.written: list[Path] = []

    def write(self, name: str, frame) -> None:
        """``name``.parquet holding ``frame`` (an Arrow table or a pandas DataFrame)."""
        write_parquet(frame, self.folder / f"{name}.parquet", self.config_yaml)
        self.written.append(self.folder / f"{name}.parquet")

    @contextmanager
    def stream(self, name: str, then: Callable[[pa.Table, int], pa.Table] | None = None):
        """A :class:`ParquetSink` for ``name``.parquet, complete when the block ends. ``then``:
        (chunk, its first row) -> the chunk as written, for columns known only once every chunk
        is in (the connected reach): the chunks wait in a scratch file meanwhile."""
        if then is None:
            with ParquetSink(self.folder / f"{name}.parquet", self.config_yaml) as sink:
                yield sink
        else:
            scratch = self.folder / f".{name}.unfinished.parquet"
            try:
                with ParquetSink(scratch, self.config_yaml) as first:
                    yield first
                with ParquetSink(self.folder / f"{name}.parquet", self.config_yaml) as sink:
                    start, chunks = 0, pq.ParquetFile(scratch)
                    for group in range(chunks.num_row_groups):
                        table = chunks.read_row_group(group).replace_schema_metadata(None)
                        sink.write(then(table, start))
                        start += table.num_rows
            finally:
                scratch.unlink(missing_ok=True)
        self.written.append(sink.path)

    def mesh(self, name: str, vertices, triangles, title: str) -> None:
        """``name``.stl and ``name``.ply: a triangle mesh (``pipeline.workspace.boundary``)."""
        from pipeline.workspace.boundary import write_ply, write_stl

        for suffix, writer in ((".stl", write_stl), (".ply", write_ply)):
            path = self.folder / f"{name}{suffix}"
            with replacing(path) as tmp:
                writer(tmp, vertices, triangles, title)
            self.written.append(path)


def changed_files(out: Path, meta: dict | None = None) -> list[str]:
    """The data files of the finished job in ``out`` that are missing or no longer have the
    digest its summary recorded (``meta``: the summary's metadata, read if not given); a job
    whose summary has no record of them reports so."""
    meta = read_metadata(out / "summary.parquet") if meta is None else meta
    if DIGESTS_KEY not in meta:  # "{}" is recorded by a job that writes its summary only
        return ["its data files are not recorded"]
    recorded = json.loads(meta[DIGESTS_KEY])
    return [name for name, digest in recorded.items()
            if not (out / name).exists() or file_digest(out / name) != digest]


def finished_summary(out: Path, config_yaml: str) -> dict | None:
    """The summary of a job already finished in ``out`` with this config and code, whose data
    files still have the digests it recorded; else None (and a log line when something in the
    folder is unreadable or changed)."""
    path = out / "summary.parquet"
    if not path.exists():
        return None
    try:
        meta = read_metadata(path)
        if meta.get(CONFIG_KEY) != config_yaml or meta.get(VERSION_KEY) != code_version():
            return None
        changed = changed_files(out, meta)
        if changed:
            log.warning("recomputing %s: %s changed since the job finished", out, ", ".join(changed))
            return None
        return read_verified(path).to_pylist()[0]
    except READ_ERRORS as exc:  # a corrupt file: pyarrow's errors
        log.warning("recomputing %s: unreadable summary.parquet (%s)", out, exc)
        return None

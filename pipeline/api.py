"""The Python API, for notebooks and scripts: the command line's jobs and studies without its
command line (docs/api.md).

    from pipeline import api
    ws = api.workspace(["actuator=3", "orientation.psi=0.5"])
    ws.summary["feasible_pct"], ws.points.head()
    choice = api.actuator_choice(["choice.required_pct=80"])
    print(choice.verdict)
    study = api.load_study("actuator_choice")      # a study the command line finished

Overrides are the command line's ``key=value`` (and ``group=option``) strings. Bad input
raises :class:`pipeline.errors.ConfigError` with the command line's one-line message, before
anything is written; it never exits the interpreter. Importing this module changes no global
state: no matplotlib backend, no logging handlers.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Iterable

import pandas as pd

from pipeline.analyses.choice import choose, verdict
from pipeline.errors import ConfigError
from pipeline.analyses.results import StudyResults, table
from pipeline.app.job import changed_files
from pipeline.app.plan import Plan, plan, quoted
from pipeline.app.run import run
from pipeline.app.results import read_metadata
from pipeline.study import OUTPUT_DIR, available, first_actuator_job, study_dir

API_DIR = Path("outputs") / "api"
FIGURE_KINDS = ("cloud", "slices", "map", "path", "path_view", "paving")  # the kinds of one job's poses, path or boxes

__all__ = ["ConfigError", "Workspace", "Choice", "workspace", "actuator_choice", "load_study"]


@dataclass(frozen=True)
class Workspace:
    """One finished job: its folder, summary (one row as a dict), per-pose table (None for a
    job run with ``output.points=false`` and for a path), per-sample table (``samples``: the
    samples of ``analysis=trajectory`` or ``lines``; None for the others), certified boxes
    (``boxes``: ``analysis=certified``'s; None for the others), a certified path's pieces
    (``segments``: with ``certified.path``), and the resolved config and code version recorded in
    its files."""
    folder: Path
    summary: dict
    points: pd.DataFrame | None
    config: str
    version: str
    samples: pd.DataFrame | None = None
    boxes: pd.DataFrame | None = None
    segments: pd.DataFrame | None = None

    def figure(self, kind: str = "cloud", out: str | Path | None = None, **keys) -> list[Path]:
        """Draw this job as a study draws one (``pipeline.analyses.figures``): ``kind`` cloud, slices
        or map, with a figure's keys (e.g. ``axis="z", layers=4``, ``value="max_payload_kg"``,
        ``invert_z=True``), a path's samples against time (``path``) or inside its robot
        (``path_view``), or a certified job's boxes in sections (``paving``), into ``out`` (default
        ``<folder>/figures``); returns the PNG files. A cloud also writes its interactive 3-D view
        beside it (with the report extra)."""
        from pipeline.analyses.figures import FigureSpec, render
        from pipeline.analyses.results import JobResults
        from pipeline.app.config import check_declared

        if kind not in FIGURE_KINDS:
            raise ConfigError(f"kind={kind!r}: a job draws as a cloud, slices, map, path, path_view or paving (a "
                              "study's other kinds compare jobs)")
        drawn, name = ((self.samples, "samples") if kind.startswith("path") else (self.boxes, "boxes")
                       if kind == "paving" else (self.points, "points"))
        if drawn is None:
            raise ConfigError(f"{self.folder}: no {name}.parquet (a path's with analysis=trajectory, boxes with "
                              "analysis=certified; run with output.points=true) to draw")
        try:
            spec = FigureSpec(kind=kind, file=f"{kind}.png", **keys)
        except TypeError as exc:  # a key no figure has
            raise ConfigError(f"figure: {exc}") from None
        check_declared(spec, "figure")
        return render(spec, JobResults(self.folder), Path(out) if out is not None else self.folder / "figures")

    @classmethod
    def read(cls, folder: Path) -> "Workspace":
        """A finished job's folder, written by the command line or by :func:`workspace`."""
        folder = Path(folder)
        meta = read_metadata(folder / "summary.parquet")
        changed = changed_files(folder, meta)
        try:
            summary = table(folder / "summary.parquet").iloc[0].to_dict()
        except ValueError as exc:
            changed.append(f"summary.parquet ({exc})")
        if changed:
            raise ConfigError(f"{folder}: {', '.join(changed)} changed since the job finished; run it again")
        def written(name: str) -> pd.DataFrame | None:
            return pd.read_parquet(folder / name) if (folder / name).exists() else None

        return cls(folder, summary, written("points.parquet"), meta.get("cdpr.config", ""), meta.get("cdpr.version", ""),
                   written("samples.parquet"), written("boxes.parquet"), written("segments.parquet"))


@dataclass(frozen=True)
class Choice:
    """CPR-ACM (section 4 of Filipovic & Kevac): one CPR-WWA job per catalogue actuator."""
    table: pd.DataFrame  # pipeline.analyses.choice.choose: rank, x(i_a), accepted, losses per constraint
    verdict: str
    workspaces: dict[int, Workspace]


def workspace(overrides: Iterable[str] = (), folder: str | Path | None = None,
              config_dir: str | Path | None = None) -> Workspace:
    """Check and run one job, as ``python -m pipeline OVERRIDES`` would, into ``folder``
    (default ``outputs/api/<date-time>``); a finished job with the same config and code in
    that folder is reused. ``config_dir``: a folder with the user's own ``robot/NAME.yaml``
    (the command line's ``--config-dir``). Raises ConfigError for bad input (nothing written)."""
    overrides = _listed(overrides, config_dir)
    folder = Path(folder) if folder is not None else _new_folder()
    return _run(plan([*overrides, f"hydra.run.dir={quoted(folder)}"]))[0]


def actuator_choice(overrides: Iterable[str] = (), folder: str | Path | None = None,
                    config_dir: str | Path | None = None) -> Choice:
    """CPR-ACM over every actuator of the configured catalogue (``catalogue=...`` for the
    user's own): one job per actuator in ``folder/actuator=<id>``, then the ranking and the
    verdict at ``choice.required_pct``. Raises ConfigError for bad input (nothing written)."""
    overrides = _listed(overrides, config_dir)
    if any(o.split("=", 1)[0].lstrip("+~") == "actuator" for o in overrides):
        raise ConfigError("actuator=...: the choice runs every actuator of the catalogue; "
                          "use workspace() for one")
    folder = Path(folder) if folder is not None else _new_folder()
    first = first_actuator_job(overrides, folder)
    ids = ",".join(str(i) for i in first.catalogue.ids)
    planned = plan(["-m", f"actuator={ids}", *overrides, f"hydra.sweep.dir={quoted(folder)}",
                    "hydra.sweep.subdir='actuator=${actuator}'"])  # every job checked before the first runs
    done = {int(ws.summary["actuator"]): ws for ws in _run(planned)}
    table = choose(pd.DataFrame([ws.summary for ws in done.values()]))
    return Choice(table, verdict(table), done)


def load_study(name: str, out_root: str | Path | None = None,
               overrides: Iterable[str] = ()) -> StudyResults:
    """The results of a study the command line ran (``python -m pipeline.study NAME
    OVERRIDES``): its summary, analysis tables and per-job points. ``name``: a declared study
    (``python -m pipeline.study --list``), never a path."""
    if name not in available():
        raise ConfigError(f"study {name!r} not found (available: {', '.join(available())})")
    directory = study_dir(name, _listed(overrides), Path(out_root) if out_root else None)
    if not (directory / "summary.parquet").exists():
        raise ConfigError(f"study {name}: no results in {directory}; run `cdpr-study {name}` first"
                          + ("" if out_root else f" (or give out_root; default {OUTPUT_DIR})"))
    return StudyResults(directory)


def _run(planned: Plan) -> list[Workspace]:
    """The plan's jobs as the command line runs them (``pipeline.app.run.run``: Hydra's records in
    each folder, a sweep's summary), logging through the caller's logging as it is."""
    run(planned, hydra_logging=False)
    return [Workspace.read(job.folder) for job in planned.jobs]


def _listed(overrides: Iterable[str], config_dir: str | Path | None = None) -> list[str]:
    """The overrides as a list of strings (one bare string is one override), refusing
    command-line flags, with ``--config-dir`` for ``config_dir``."""
    listed = [overrides] if isinstance(overrides, str) else [str(o) for o in overrides]
    flags = [o for o in listed if o.startswith("-")]
    if flags:
        raise ConfigError(f"{flags[0]}: the API takes key=value overrides only (one job per "
                          "call: loop over values for a sweep; config_dir= for --config-dir)")
    return listed if config_dir is None else ["--config-dir", str(config_dir), *listed]


def _new_folder() -> Path:
    return API_DIR / datetime.now().strftime("%Y-%m-%d_%H-%M-%S-%f")

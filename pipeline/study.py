"""Declared studies: ``python -m pipeline.study NAME [key=value ...]``.

A study (one paper figure or table) is a YAML file ``studies/NAME.yaml`` holding only data:
fixed overrides, the swept keys, the analyses that turn the sweep summary into tables, and the
figures. Running it is always the same three steps:

1. the sweep, as one ``python -m pipeline -m`` command (planned, then run in this process:
   ``pipeline.app.plan``, ``pipeline.app.run``), into ``outputs/studies/NAME/jobs/`` (one command per case, into ``jobs/CASE/``,
   when the study declares ``cases``), gathered into ``outputs/studies/NAME/summary.parquet``;
2. the analyses (``ANALYSES``), each written as ``outputs/studies/NAME/<analysis>.parquet``;
3. the figures (``pipeline.analyses.figures``), drawn from those Parquet files only, into
   ``outputs/studies/NAME/figures/``.

``--figures-only`` repeats steps 2-3 from the existing Parquet files. Extra ``key=value``
arguments are appended to every job (e.g. ``catalogue=my_motors.csv``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import multiprocessing
import os
import re
import shutil
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Optional

import numpy as np
import pandas as pd
import yaml
from omegaconf import DictConfig, OmegaConf

from pipeline.model.catalogue import load_catalogue
from pipeline.analyses.choice import acceptance, choose, verdict
from pipeline.app.config import check_declared, rule
from pipeline.errors import ConfigError, one_line
from pipeline.analyses.evidence import evidence, scores
from pipeline.analyses.layout import (LayoutSpec, best_layout, best_trial, check_robot, placed, prove_required,
                                      search_layouts)
from pipeline.analyses.figures import SERIES_DIR, FigureSpec, render
from pipeline.analyses.results import StudyResults, table as read_table
from pipeline.app.job import changed_files, execute, folder_lock
from pipeline.analyses.optimise import (OptimiseSpec, best_drive, check_catalogue_objectives, corner_overrides, optimise,
                               trial_folder)
from pipeline.app.plan import Job, Plan, Reuse, nearest_key, parse, plan, quoted, refuse_aliases
from pipeline.app.run import run as run_jobs
from pipeline.app.resources import STUDIES_DIR
from pipeline.app.results import READ_ERRORS, code_version, file_digest, read_verified, write_csv, write_parquet, write_text
from pipeline.analyses.search import SearchSpec, exact_drive, search
from pipeline.analyses.survival import survival

OUTPUT_DIR = Path("outputs") / "studies"
ALWAYS_EXCLUDED = ["compute.n_jobs", "compute.backend", "compute.chunk_size", "compute.scheduler",
                   "compute.max_poses", "compute.kernel"]
# Studies are many small jobs: by default two at a time on two worker processes kept for every
# sweep of the command, where they pay for their start (pipeline.workspace.dispatch.workers_pay, else
# in this process), each job on one core (one level of parallelism); "serial": one after
# another in this process, each with its own compute.n_jobs (large grids, Dask); "one_core": one
# after another, each job on one core (what each of the concurrent studies of --all uses)
LAUNCHERS = {
    "pool": ["hydra.launcher.n_jobs=2", "compute.n_jobs=1"],
    "serial": ["hydra.launcher.n_jobs=1"],
    "one_core": ["hydra.launcher.n_jobs=1", "compute.n_jobs=1"],
}
# Several studies with the default launcher: this many at a time, each in its own process with
# its jobs on one core (one level of parallelism); the optimiser and search studies, which run
# their jobs one after another anyway, start first (measured: docs/performance.md)
STUDY_WORKERS = 2
ANALYSES: dict[str, Callable[[StudyResults], pd.DataFrame]] = {
    "choice": lambda results: choose(results.summary),
    "acceptance": lambda results: acceptance(results.summary),
    "survival": survival,
    "evidence": lambda results: evidence(results.summary),
    "best_drive": lambda results: best_drive(results.summary),
    "exact_drive": lambda results: exact_drive(results.table("search"), results.summary),
    "best_layout": best_layout,
}
log = logging.getLogger("pipeline.study")


@dataclass
class StudySpec:
    """A study file. ``sweep`` maps a key to Hydra sweep values (``"0,15,30,45"``,
    ``"range(1,6)"``); the value ``catalogue`` sweeps ``actuator`` over every id of the
    configured catalogue. ``cases`` (name -> overrides) repeats the sweep once per case, for
    settings that are not a cartesian product (e.g. the radii pairs of one paper figure each);
    ``case_labels`` (name -> words) is what a reader calls a case, in the summary's
    ``case_label`` column for titles, captions, legends and report tables (default: the name,
    which stays the folder name). ``extra_overrides: false``: the study checks published facts
    on the papers' own settings, so a command may add ``compute.*`` overrides only.
    ``optimise`` (:class:`pipeline.analyses.optimise.OptimiseSpec`) replaces the sweep by trials that an
    optimiser proposes; ``search`` (:class:`pipeline.analyses.search.SearchSpec`), alone or with it, by
    the exact search over the drive train (``search.parquet``): no ``sweep`` or ``cases`` then.
    ``layout`` (:class:`pipeline.analyses.layout.LayoutSpec`), alone, by a search over the anchors and
    attachments of the robot the overrides build (its trials in this process).
    ``name`` and ``config_dir`` are not read from the file: the study's name, and the user's
    folder it came from (its jobs read that folder's robots), None for the package's studies."""

    title: str
    source: str
    overrides: list[str] = rule(lambda overrides: _overrides_error(overrides), default_factory=list)
    sweep: dict[str, str] = rule(lambda sweep: _strings_error(sweep.values()) or _hydra_error(sweep), default_factory=dict)
    cases: dict[str, list[str]] = rule(lambda cases: next((f"{case}: {_overrides_error(overrides)}" for case, overrides
                                                           in cases.items() if _overrides_error(overrides)), None),
                                       default_factory=dict)
    case_labels: dict[str, str] = field(default_factory=dict)
    extra_overrides: bool = True
    optimise: Optional[OptimiseSpec] = None
    search: Optional[SearchSpec] = None
    layout: Optional[LayoutSpec] = None
    analyses: list[str] = rule(lambda analyses: _strings_error(analyses) or next(
        (f"unknown {a!r} (known: {', '.join(ANALYSES)})" for a in analyses if a not in ANALYSES), None), default_factory=list)
    figures: list[FigureSpec] = field(default_factory=list)
    name: Optional[str] = None
    config_dir: Optional[str] = None

    def check_across(self, where: str) -> None:
        designs = [name for name in ("optimise", "search", "layout") if getattr(self, name) is not None]
        if "layout" in designs and len(designs) > 1:
            raise ConfigError(f"{where}: layout: a layout study searches the anchors alone (drop {designs[0]})")
        if designs and (self.sweep or self.cases):
            raise ConfigError(f"{where}: {designs[0]}: a study either sweeps or optimises and searches "
                              "(drop sweep and cases)")
        if self.search is not None and self.optimise is not None and {
                key: value for key, value in self.optimise.variables.items() if key != "actuator"} != self.search.variables:
            raise ConfigError(f"{where}: search.variables: must be the optimise block's drive "
                              "variables, so that the two answer the same question")
        files = [figure.file for figure in self.figures]
        twice = sorted({file for file in files if files.count(file) > 1})
        if twice:
            raise ConfigError(f"{where}: figures: {twice[0]}: the file of {files.count(twice[0])} figures; each needs its own")
        for case in self.case_labels:
            if case not in self.cases:
                raise ConfigError(f"{where}: case_labels: {case!r} is not a case (cases: "
                                  f"{', '.join(self.cases) or 'none'})")

    @property
    def location(self) -> list[str]:
        """``--config-dir DIR`` for a user's study (its jobs read her robots), else nothing."""
        return ["--config-dir", self.config_dir] if self.config_dir else []

    @property
    def arguments(self) -> list[str]:
        """The study's overrides as a job's command-line arguments, after its :attr:`location`."""
        return [*self.location, *self.overrides]

    @property
    def designs(self) -> bool:
        """Whether trials or a search replace the sweep (jobs run one after another here)."""
        return self.optimise is not None or self.search is not None or self.layout is not None


def _strings_error(values) -> str | None:
    """OmegaConf lets a list through where list[str] declares strings."""
    return next((f"{value!r} is not a string" for value in values if not isinstance(value, str)), None)


def _hydra_error(keys) -> str | None:
    """Hydra's callbacks and plugins run code: a study file (data) may not set them."""
    return next((f"{key}: a study file may not set Hydra's own settings" for key in keys
                 if re.split(r"[./]", key)[0] == "hydra"), None)


def _overrides_error(overrides) -> str | None:
    return _strings_error(overrides) or _hydra_error(_key(o) for o in overrides)


STUDY_NAME = re.compile(r"[A-Za-z0-9][\w-]*")  # a study's name is its folder's name under --out


def available(directory: Path = STUDIES_DIR) -> list[str]:
    """The studies of ``directory``: its ``NAME.yaml`` files whose NAME is letters, digits, ``_``
    and ``-`` (a name like ``..`` would name another folder)."""
    return sorted(path.stem for path in directory.glob("*.yaml") if STUDY_NAME.fullmatch(path.stem))


def studies_folder(config_dir: Path | str | None) -> Path:
    """Where the studies are: the package's, or ``studies/`` of a user's ``--config-dir``
    (ConfigError when it has none)."""
    if config_dir is None:
        return STUDIES_DIR
    folder = Path(config_dir) / "studies"
    if not folder.is_dir():
        raise ConfigError(f"--config-dir={config_dir}: no studies folder (put study files in {folder}/)")
    return folder


def load_study(name: str, directory: Path | None = None, config_dir: Path | str | None = None) -> StudySpec:
    """Read and check ``studies/NAME.yaml`` of ``directory``, by default the package's or, given
    a user's ``config_dir``, that folder's ``studies/``: unknown keys and wrong types fail as
    OmegaConf reads it, then every rule the study's dataclasses declare beside their fields
    (:func:`pipeline.app.config.check_declared`)."""
    directory = directory or studies_folder(config_dir)
    path = directory / f"{name}.yaml"
    if name not in available(directory):  # a declared name, never a path to another file
        hint = "" if STUDY_NAME.fullmatch(name) else "; a study's name is letters, digits, _ and -"
        raise ConfigError(f"study {name!r} not found (available: {', '.join(available(directory))}){hint}")
    try:
        refuse_aliases(path.read_text(encoding="utf-8"), str(path))
        spec = OmegaConf.merge(OmegaConf.structured(StudySpec), OmegaConf.load(path))
        study: StudySpec = OmegaConf.to_object(spec)  # a missing mandatory value fails here
    except ConfigError:
        raise
    except Exception as exc:  # YAML, OmegaConf key and type errors (the key, and type hints in words)
        key = getattr(exc, "full_key", None)
        text = re.sub(r"<class '(\w+)'>", r"\1", one_line(exc))
        raise ConfigError(f"{path}: {f'{key}: ' if key else ''}{text}") from exc
    study.name = name
    study.config_dir = None if config_dir is None else str(config_dir)
    check_declared(study, str(path))
    return study


def sweep_command(study: StudySpec, extra: list[str], jobs_dir: Path,
                  launcher: str = "pool") -> list[str]:
    """The ``python -m pipeline`` arguments of a study's sweep. Job folders are named by the
    swept keys only: those of ``sweep`` and any override of ``extra`` (a case's) that sweeps,
    e.g. ``robot.r_end=1.2,6``; fixed values are excluded from the folder name."""
    fixed = [*study.overrides, *extra]
    swept = [f"{key}={_sweep_values(key, values, fixed)}" for key, values in study.sweep.items()]
    excluded = ALWAYS_EXCLUDED + [o.key_or_group for o in parse(fixed)
                                  if o.key_or_group not in study.sweep and not o.is_sweep_override()]
    return [
        *study.location, "-m", f"hydra.sweep.dir={quoted(jobs_dir)}",  # a study folder name may hold = and ,
        f"hydra.job.config.override_dirname.exclude_keys=[{','.join(excluded)}]",
        *LAUNCHERS[launcher], *study.overrides, *swept, *extra,
    ]


def study_dir(name: str, extra: list[str], out_root: Path | None = None) -> Path:
    """Where a study's results go. Given ``--out`` (``out_root``): ``out_root/NAME``. Otherwise
    ``outputs/studies/NAME``, or with extra overrides that change results (not ``compute.*``)
    ``outputs/studies/NAME+<overrides>``: a run with a user's catalogue never replaces the
    paper's reproduction."""
    if out_root is not None:
        return Path(out_root) / name
    differs = [o for o in extra if _key(o) not in ALWAYS_EXCLUDED]
    if not differs:
        return OUTPUT_DIR / name
    slug = re.sub(r"[^A-Za-z0-9._,=+-]", "_", ",".join(differs))  # no quotes, slashes, spaces
    if len(slug) > 120:  # a folder name stays well under the 255-byte limit
        slug = slug[:100] + "-" + hashlib.sha256(slug.encode()).hexdigest()[:12]
    return OUTPUT_DIR / f"{name}+{slug}"


RECORD_BYTES = 1 << 20  # a study's record is a few lines; a larger file is not one


def claim_study_dir(out: Path, name: str, extra: list[str], force: bool) -> str:
    """The provenance record of ``out`` (``study.yaml``: study and extra overrides). A folder
    that holds another configuration's results is refused unless ``force``."""
    record = out / "study.yaml"
    wanted = OmegaConf.to_yaml({"study": name, "extra_overrides": extra})
    if record.exists() and record.read_text(errors="replace") != wanted and not force:
        try:  # a file read back from an output folder is outside data too
            if record.stat().st_size > RECORD_BYTES:
                raise ValueError(f"{record.stat().st_size} bytes, a record is a few lines")
            text = record.read_text(encoding="utf-8")
            refuse_aliases(text, "study.yaml")
            held = OmegaConf.create(text)
            if not isinstance(held, DictConfig) or not isinstance(held.get("study"), str):
                raise ValueError("not a mapping with the key study")
            what = f"study {held.study} with overrides {list(held.get('extra_overrides') or [])}"
        except Exception as exc:  # YAML and OmegaConf errors, or not a record
            what = f"an unreadable study record ({one_line(exc)})"
        raise ConfigError(f"{out}: holds {what}; --force replaces them, --out DIR writes elsewhere")
    return wanted


def run_study(name: str, extra: list[str], out_root: Path | None = None,
              figures_only: bool = False, launcher: str = "pool",
              checked: list[tuple[list[str], Plan]] | None = None, force: bool = False,
              config_dir: Path | None = None) -> list[Path]:
    """Sweep (unless ``figures_only``), analyses and figures of one study; returns the files.
    The jobs of an interrupted run of the same study are reused (``_start_or_resume``).
    ``checked``: the study's sweep commands if already checked (:func:`checked_commands`);
    ``config_dir``: a user's folder (:func:`checked_commands`)."""
    out = study_dir(name, extra, out_root)
    if not figures_only:
        claim_study_dir(out, name, extra, force)  # refused here: nothing written
        checked = checked or checked_commands(name, extra, out_root, launcher, config_dir)
        out.mkdir(parents=True, exist_ok=True)
    if not out.is_dir():
        raise ConfigError(f"study {name}: no results in {out}; run it without --figures-only")
    with folder_lock(out, f"another run of study {name} is writing this folder; wait for it or "
                          "write elsewhere (--out DIR)"):  # two runs would share the jobs
        return _run_study(load_study(name, config_dir=config_dir), extra, out, figures_only, checked, force)


def _run_study(study: StudySpec, extra: list[str], out: Path, figures_only: bool,
               checked: list[tuple[list[str], Plan]] | None, force: bool) -> list[Path]:
    """:func:`run_study` once the study's folder is held."""
    name = study.name
    cases = study.cases or {"": []}
    provenance = OmegaConf.to_yaml({"study": name, "extra_overrides": extra})
    if not figures_only:
        provenance = claim_study_dir(out, name, extra, force)
        commands = [command for command, _ in checked]
        write_text(out / "study.yaml", provenance)
        log.info("study %s: %s", name, study.title)
        if study.layout is not None:
            _start_or_resume(out / "jobs", [[OmegaConf.to_yaml({"layout": asdict(study.layout), "extra_overrides": extra})]])
            summary = _layouts(study, extra, out, checked[0][1].jobs[0])
        elif study.designs:
            _start_or_resume(out / "jobs", [[OmegaConf.to_yaml({
                "optimise": study.optimise and asdict(study.optimise),
                "search": study.search and asdict(study.search), "extra_overrides": extra})]])
            first = checked[0][1].jobs[0]
            summary, searched = _designs(study, extra, out / "jobs", first.catalogue, first.cfg)
            if searched is not None:
                write_parquet(searched, out / "search.parquet", provenance)
                write_csv(searched, out / "search.csv")
        else:
            _start_or_resume(out / "jobs", commands)
            every_job = [job for _, planned in checked for job in planned.jobs]  # one pool serves them all
            for _, planned in checked:
                run_jobs(planned, sharing=every_job)
                _log_to_console()  # the jobs had Hydra's logging
            summary = _gather(out / "jobs", cases, study.case_labels)
        write_parquet(summary, out / "summary.parquet", provenance)
    results = StudyResults(out)
    inputs = ["summary", *(["search"] if study.search is not None else [])]  # what the analyses read
    for table in inputs:  # read once each: a missing or corrupt file fails here, clearly
        try:
            jobs = results.table(table)["job"].dropna()
        except FileNotFoundError:
            raise ConfigError(f"study {name}: no results in {out} ({table}.parquet); run it without "
                              "--figures-only") from None
        except READ_ERRORS as exc:  # a corrupt file: pyarrow's errors, a missing column
            raise ConfigError(f"{out / f'{table}.parquet'}: not a readable Parquet file of this "
                              f"study ({one_line(exc)}); rerun the study") from exc
        if figures_only:  # redraw from intact results only, before any old figure is removed
            _check_jobs(out / "jobs", jobs)
    written = [out / "summary.parquet"]
    tables = {}
    for analysis in study.analyses:
        path = out / f"{analysis}.parquet"
        table = tables[analysis] = ANALYSES[analysis](results)
        write_parquet(table, path, provenance)
        write_csv(table, path.with_suffix(".csv"))  # the same table for a spreadsheet
        written.extend([path, path.with_suffix(".csv")])
        if analysis == "choice":
            log.info("study %s: %s", name, verdict(table))
    write_text(out / "metrics.json", json.dumps(metrics(results.summary, tables), indent=2, sort_keys=True))
    written.append(out / "metrics.json")
    for folder in ("figures", SERIES_DIR):  # no figure or series of an earlier run lingers
        shutil.rmtree(out / folder, ignore_errors=True)
    for figure in study.figures:
        written.extend(render(figure, results, out / "figures"))
    written.append(record_figures(out))
    return written


FIGURES_RECORD = "figures.json"  # in a study's folder: each file of figures/ and its sha256


def record_figures(out: Path) -> Path:
    """The record of the files a study drew into ``out/figures`` (relative path -> sha256), which
    the report checks before it shows them, as the tables' digests guard the tables."""
    folder = out / "figures"
    files = sorted(p for p in folder.rglob("*") if p.is_file()) if folder.is_dir() else []
    record = {p.relative_to(out).as_posix(): file_digest(p) for p in files}
    write_text(out / FIGURES_RECORD, json.dumps(record, indent=1, sort_keys=True) + "\n")
    return out / FIGURES_RECORD


def verified_figures(out: Path) -> list[Path]:
    """The PNG figures of the study in ``out``, each as the study drew it; ValueError naming the
    first that is missing, changed or not the study's (a figure is outside data too)."""
    record_path = out / FIGURES_RECORD
    try:
        record = json.loads(record_path.read_text(encoding="utf-8"))
        if not isinstance(record, dict) or not all(isinstance(v, str) for v in record.values()):
            raise ValueError("not a record of figures")
    except FileNotFoundError:
        raise ValueError(f"{record_path}: missing (the figures are not recorded); rerun the study") from None
    except (OSError, ValueError) as exc:
        raise ValueError(f"{record_path}: unreadable ({one_line(exc)}); rerun the study") from None
    drawn = sorted(p for p in (out / "figures").rglob("*") if p.is_file()) if (out / "figures").is_dir() else []
    for path in drawn:
        name = path.relative_to(out).as_posix()
        if name not in record:
            raise ValueError(f"{path}: not a figure the study drew; rerun the study")
        if file_digest(path) != record[name]:
            raise ValueError(f"{path}: changed since the study drew it; rerun the study (--figures-only)")
    missing = [name for name in record if not (out / name).is_file()]
    if missing:
        raise ValueError(f"{out / missing[0]}: missing; rerun the study (--figures-only)")
    return [p for p in drawn if p.suffix == ".png"]


def _check_jobs(jobs_dir: Path, jobs) -> None:
    """Every job's summary and data files as it finished them (their recorded digests), or
    ConfigError naming the first that changed."""
    for job in jobs:
        try:
            read_verified(jobs_dir / job / "summary.parquet")
            changed = changed_files(jobs_dir / job)
        except READ_ERRORS as exc:  # a missing, corrupt or edited summary.parquet
            changed = [f"summary.parquet ({one_line(exc)})"]
        if changed:
            raise ConfigError(f"{jobs_dir / job}: {', '.join(changed)} changed since the job "
                              "finished; rerun the study without --figures-only to recompute it")


NEEDS_POINTS = {"cloud", "map", "slices", "survival"}  # figure kinds and analyses that read jobs/*/points.parquet


def metrics(summary: pd.DataFrame, tables: dict[str, pd.DataFrame]) -> dict:
    """A study's headline numbers (``metrics.json``, read by ``dvc metrics``), a few keys shared
    by every study so that ``dvc metrics show`` stays one narrow table: the jobs, the feasible
    share and volume over them (min, median, max), and where the study has them, the actuators
    its choice accepts (and how many), the accepted (actuator, value) pairs of a design study, the
    actuators for which a drive synthesis found a drive (the exact search's where it has one),
    and the published facts the default reading matches. Each job's numbers are in
    summary.parquet and the report."""
    found: dict = {"jobs": len(summary)}
    for column in ("feasible_pct", "volume_m3"):
        values = summary[column].dropna()
        found[column] = {stat: round(float(getattr(values, stat)()), 6) if len(values) else None
                         for stat in ("min", "median", "max")}
    if "choice" in tables:
        choice = tables["choice"]
        accepted = choice.loc[choice["accepted"], "actuator"].tolist()
        found["accepted"] = ", ".join(map(str, accepted)) or "none"
        found["n_accepted"] = len(accepted)
    if "acceptance" in tables:
        found["n_accepted_pairs"] = int(tables["acceptance"]["accepted"].sum())
    drives = tables.get("exact_drive", tables.get("best_drive"))
    if drives is not None:
        found["drives_found"] = int(drives["found"].sum())
    if "evidence" in tables:
        default = scores(tables["evidence"]).set_index("reading").loc["default"]
        found["facts_matched"], found["facts"] = int(default["matched"]), int(default["facts"])
    return found


def checked_commands(name: str, extra: list[str], out_root: Path | None = None,
                     launcher: str = "pool", config_dir: Path | None = None) -> list[tuple[list[str], Plan]]:
    """The sweep commands of a study (one per case), each with its plan (every job checked):
    bad input fails here, before anything is written or removed. A design study: its lowest
    and highest designs, planned the same way. ``config_dir``: a user's folder, whose
    ``studies/`` holds the study and whose robots its jobs read."""
    study = load_study(name, config_dir=config_dir)
    for override in extra:
        if re.split(r"[./]", _key(override))[0] == "hydra":
            raise ConfigError(f"{override}: a study places and launches its own jobs (--out, --launcher); "
                              "Hydra's settings are not study overrides")
    changed = [o for o in extra if _key(o) not in ALWAYS_EXCLUDED]
    if changed and not study.extra_overrides:
        raise ConfigError(f"{changed[0]}: study {name} checks the papers' published facts on "
                          "their own settings; it takes compute.* overrides only")
    out = study_dir(name, extra, out_root)
    if study.layout is not None:
        return [(["layout"], _layout_plan(study, extra, out, launcher))]
    if study.designs:  # the lowest and highest designs
        job = first_actuator_job([*study.arguments, *extra], out)
        cfg, catalogue = job.cfg, job.catalogue
        if cfg.analysis == "certified":
            raise ConfigError(f"analysis=certified: study {name} reads each job's margins and share of poses; a "
                              "paving's boxes have verdicts (design the drive with analysis=statics, then certify it)")
        if study.search is not None:
            _check_searchable(cfg, name)
        if study.optimise is not None:
            check_catalogue_objectives(study.optimise, catalogue)
        ids = catalogue.ids
        variables = study.optimise.variables if study.optimise is not None else {
            "actuator": study.search.actuators, **study.search.variables}
        corners = [(["design"], plan([*study.arguments, *extra, *corner,
                                      f"hydra.run.dir={quoted(trial_folder(out / 'jobs', 0))}"]))
                   for corner in corner_overrides(variables, ids)]
        return corners
    commands = [sweep_command(study, [*overrides, *extra], out / "jobs" / case, launcher)
                for case, overrides in (study.cases or {"": []}).items()]
    reuse = Reuse()  # the cases share their config files: composed once
    checked = [(command, plan(command, reuse)) for command in commands]
    _check_figure_keys(study, checked[0][1].jobs[0].cfg)
    needs = [f.kind for f in study.figures if f.kind in NEEDS_POINTS] + [
        a for a in study.analyses if a in NEEDS_POINTS]
    if needs and any(not job.cfg.output.points for _, planned in checked for job in planned.jobs):
        raise ConfigError(f"output.points=false: study {name} reads every job's points.parquet "
                          f"({', '.join(dict.fromkeys(needs))})")
    return checked


def _concurrently(names: list[str], extra: list[str], out_root: Path | None, launcher: str,
                  force: bool, workers: int, config_dir: Path | None) -> list[Path]:
    """Every study checked (:func:`checked_commands`), then run (:func:`run_study`), ``workers``
    at a time in forked processes (the code is imported once, in this one): no study starts
    before all are checked, the first failing check is raised as in a serial run, and the
    designing studies start first. The files of all, in the given order; the first failure is
    raised once the running studies end, and none not yet started starts."""
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork")) as pool:
        try:
            checks = [pool.submit(checked_commands, name, extra, out_root, launcher, config_dir) for name in names]
            checked = {name: check.result() for name, check in zip(names, checks)}
            designing = [name for name in names if load_study(name, config_dir=config_dir).designs]
            futures = {name: pool.submit(run_study, name, extra, out_root, False, launcher,
                                         checked[name], force, config_dir)
                       for name in designing + [name for name in names if name not in designing]}
            return [path for name in names for path in futures[name].result()]
        except BaseException:
            pool.shutdown(cancel_futures=True)
            raise


def _check_figure_keys(study: StudySpec, cfg) -> None:
    """Every config key a figure names (``hue``, ``facet``, ``per``, ``select``, and ``x`` or ``y``
    when a bare name: a name with a dot, ``box.*`` aside, is a config key) must be a key of the
    study's jobs: ConfigError naming the figure, the key and the nearest one, before any job runs
    (it failed as a traceback after them)."""
    from pipeline.workspace.compute import flatten

    plain = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    keys = set(flatten(plain))
    for figure in study.figures:
        for field_ in ("hue", "facet", "per", "select", "x", "y"):
            value = getattr(figure, field_)
            if field_ in ("x", "y") and not re.fullmatch(r"[\w.]+", str(value or "")):
                continue  # an expression: pandas evaluates it against the summary's columns
            names = list(value) if isinstance(value, (list, dict)) else [value] if value else []
            for name in names:
                if "." in str(name) and not str(name).startswith("box.") and name not in keys:
                    near = nearest_key(str(name), plain)
                    hint = f" (did you mean {near}?)" if near else ""
                    raise ConfigError(f"studies/{study.name}.yaml: figures: {figure.file}: {field_}={name!r}: not a key "
                                      f"of the study's jobs{hint}")


def _check_searchable(cfg, name: str) -> None:
    """The search is exact for a drive with minimum-norm tensions (``pipeline.analyses.search``):
    CPR-WWA's, or a static grid's or a path's with an actuator (in each required motion a pose's
    or sample's shaft speed and acceleration scale with the ratio, its load torque with the
    inverse, its tensions do not move), and it reads every job's margins: ConfigError otherwise."""
    if cfg.analysis == "lines":  # a grid point's verdict there is its lines' samples', not its own margins
        raise ConfigError(f"analysis=lines: study {name} searches the drive train; analysis=cpr_wwa has one, "
                          "and analysis=statics or trajectory with actuator=ID")
    if cfg.tension.model.name != "pinv":
        raise ConfigError(f"tension.model={cfg.tension.model.name}: study {name}'s search is exact for "
                          "minimum-norm tensions only (tension=pinv); use an optimise block")
    if not cfg.output.points:
        raise ConfigError(f"output.points=false: study {name}'s search reads every job's margins")


def _start_or_resume(jobs_dir: Path, commands: list[list[str]]) -> None:
    """Keep ``jobs/`` when it was started by exactly these commands (a rerun after an
    interruption then computes only the missing jobs); otherwise start it afresh, so no job of
    a different sweep lingers."""
    record = jobs_dir / "commands.yaml"
    wanted = OmegaConf.to_yaml({"commands": commands, "version": code_version()})
    if record.exists() and record.read_text() == wanted:
        log.info("resuming %s: finished jobs are reused", jobs_dir)
        return
    shutil.rmtree(jobs_dir, ignore_errors=True)
    jobs_dir.mkdir(parents=True)
    write_text(record, wanted)


def _designs(study: StudySpec, extra: list[str], jobs_dir: Path, catalogue,
             cfg) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """The optimiser's trials (``jobs/trial_NNNN``) and the search's jobs
    (``jobs/search_a<id>_r<R_i>_n<N_V>``), each an ordinary job (a finished one with the same
    config is reused). Returns the summary (one row per trial, else per search job) and the
    search's table (:func:`pipeline.analyses.search.search`), or None without a search block."""
    quiet, progress = logging.getLogger("pipeline"), logging.getLogger("pipeline.study")
    required = cfg.choice.required_pct
    searched_rows = []
    reuse = Reuse()  # every trial has the same config files and catalogue: read once

    def run(folder: Path, overrides: list[str]) -> dict:
        (job,) = plan([*study.arguments, *extra, *overrides, f"hydra.run.dir={quoted(folder)}"], reuse).jobs
        return {"job": folder.name, **execute(job)}

    def run_searched(actuator: int, overrides: list[str]) -> tuple[dict, pd.DataFrame]:
        folder = jobs_dir / "_".join([f"search_a{actuator}", *(
            ("r" if key == "drive.winch_radius" else "n") + value
            for key, value in (o.split("=", 1) for o in overrides))])
        searched_rows.append(run(folder, [f"actuator={actuator}", *overrides]))
        samples = folder / "samples.parquet"  # a path's, whose samples the search reads as poses
        return searched_rows[-1], pd.read_parquet(samples if samples.exists() else folder / "points.parquet")

    levels = quiet.level, progress.level
    quiet.setLevel(logging.WARNING)  # one line per 20 trials or per actuator, not three per job
    progress.setLevel(logging.INFO)
    try:
        summary = None if study.optimise is None else optimise(
            study.optimise, lambda number, overrides: run(trial_folder(jobs_dir, number), overrides),
            catalogue, required)
        searched = None if study.search is None else search(
            study.search, catalogue, required, run_searched, cfg.model.margin_atol)
    finally:
        quiet.setLevel(levels[0])
        progress.setLevel(levels[1])
    return (pd.DataFrame(searched_rows) if summary is None else summary), searched


def _layout_plan(study: StudySpec, extra: list[str], out: Path, launcher: str) -> Plan:
    """The plan of a layout study's robot as the overrides build it (the job its best layout runs
    as, ``jobs/best``), refused in one line where a layout cannot be searched. Its trials run on
    ``compute.n_jobs`` workers; on one core under the ``one_core`` launcher (``--all`` runs studies
    side by side: one level of parallelism)."""
    one_core = ["compute.n_jobs=1"] if launcher == "one_core" else []
    planned = plan([*study.arguments, *extra, *one_core, f"hydra.run.dir={quoted(out / 'jobs' / 'best')}"])
    job = planned.jobs[0]
    if job.cfg.robot.name != "points":
        raise ConfigError(f"robot={job.robot_file}: study {study.name} moves the anchors of a robot given by its "
                          "points (robot=points, or a robot file of points); this one is built from parameters")
    if job.cfg.analysis not in ("statics", "cpr_wwa") or job.problem.angles is not None:
        raise ConfigError(f"analysis={job.cfg.analysis}: study {study.name} counts a grid of positions "
                          "(analysis=statics or cpr_wwa)")
    from pipeline.app.problem import build_grid

    check_robot(study.layout, job.problem, build_grid(job.cfg, job.problem.robot))
    return planned


def _layouts(study: StudySpec, extra: list[str], out: Path, job: Job) -> pd.DataFrame:
    """A layout study's trials (:func:`pipeline.analyses.layout.search_layouts`, in this process);
    the best one run again as an ordinary job (``jobs/best``, its count checked against the
    search's) and written as a robot file, ``layout_best.yaml``; each layout of the Pareto front as
    ``layouts/trial_NNNN.yaml``."""
    from pipeline.app.problem import build_grid
    from pipeline.app.yamltext import to_yaml

    grid = build_grid(job.cfg, job.problem.robot)
    table = search_layouts(study.layout, job.problem, grid[0:len(grid)], grid.cell_volume, int(job.cfg.compute.n_jobs),
                           (float(job.cfg.load.mass), np.asarray(OmegaConf.to_container(job.cfg.load.com), dtype=float)))
    table["job"] = None
    best = best_trial(table, study.layout)
    if best is None:
        log.warning("layout: no trial holds the required box; no robot file written")
        return table
    anchors, attachments = placed(study.layout, job.problem.robot, best.to_dict())
    points = {"anchors": anchors.tolist(), "attachments": attachments.tolist()}
    (rerun,) = plan([*study.arguments, *extra, *(f"robot.{key}={value}" for key, value in points.items()),
                     f"compute.n_jobs={job.cfg.compute.n_jobs}", f"hydra.run.dir={quoted(out / 'jobs' / 'best')}"]).jobs
    found = execute(rerun)
    if found["n_feasible"] != best["n_feasible"]:
        raise RuntimeError(f"layout: the best trial's job found {found['n_feasible']} feasible poses, "
                           f"its search {best['n_feasible']}")
    table.loc[table["trial"] == best["trial"], "job"] = "best"
    proven, said = prove_required(study.layout, rerun.problem, rerun.cfg.compute)
    if study.layout.required is not None:
        table["required_proven_pct"] = np.where(table["job"] == "best", np.nan if proven is None else proven, np.nan)
        log.info("layout: the best layout: %s", said)
    robot = OmegaConf.to_container(rerun.config.robot, resolve=True)

    def robot_file(path: Path, row: pd.Series, what: str) -> None:
        anchors, attachments = placed(study.layout, job.problem.robot, row.to_dict())
        text = to_yaml(OmegaConf.create({"defaults": ["points", "_self_"], **robot, "anchors": anchors.tolist(),
                                         "attachments": attachments.tolist()}))
        write_text(path, f"# {what} of study {study.name}, trial {int(row['trial'])}: {row['n_feasible']} of "
                         f"{row['n_points']} poses feasible{_drive_said(row, study.layout.cost)}\n" + text)

    robot_file(out / "layout_best.yaml", best, "the best layout")
    front = table[table["pareto"]]
    shutil.rmtree(out / "layouts", ignore_errors=True)  # no file of an earlier run lingers
    (out / "layouts").mkdir()
    for _, row in front.iterrows():  # the Pareto front's layouts, for a designer to choose along it
        robot_file(out / "layouts" / f"trial_{int(row['trial']):04d}.yaml", row, "a layout on the Pareto front")
    log.info("layout: the best, trial %d: %d/%d poses feasible (%.3f m^3)%s; robot files %s and %d in %s", best["trial"],
             best["n_feasible"], best["n_points"], best["volume_m3"], _drive_said(best, study.layout.cost),
             out / "layout_best.yaml", len(front), out / "layouts")
    return table


def _drive_said(row: pd.Series, cost: str | None) -> str:
    """A layout trial's actuator (objective actuator_cost: the cheapest that holds the required box), as said after its count."""
    chosen = row.get("actuator")
    return ("" if chosen is None or pd.isna(chosen) else
            f"; actuator {int(chosen)} of the catalogue on every cable ({cost} {row['actuator_cost']:g} in all)")


def _gather(jobs_dir: Path, cases: dict[str, list[str]], labels: dict[str, str]) -> pd.DataFrame:
    """The sweep summaries of every case, with ``case``, ``case_label`` and ``job`` (relative
    to jobs/)."""
    parts = []
    for case in cases:
        part = read_table((jobs_dir / case if case else jobs_dir) / "summary.parquet")
        if case:
            part["job"] = case + "/" + part["job"]
        part.insert(0, "case", case)
        part.insert(1, "case_label", labels.get(case, case))
        parts.append(part)
    return pd.concat(parts, ignore_index=True)


def _sweep_values(key: str, values: str, fixed: list[str]) -> str:
    if values != "catalogue":
        return values
    if key != "actuator":
        raise ConfigError(f"sweep {key}=catalogue: only 'actuator' can sweep the catalogue")
    return ",".join(str(i) for i in catalogue_of(fixed).ids)


def first_actuator_job(overrides: list[str], folder: Path) -> Job:
    """The one job of ``overrides`` (into ``folder``) checked with the first id of the catalogue
    they name, which a user's may not number 1 (an ``actuator=`` among the overrides wins)."""
    return plan([f"actuator={catalogue_of(overrides).ids[0]}", *overrides, f"hydra.run.dir={quoted(folder)}"]).jobs[0]


def catalogue_of(overrides: list[str]):
    """The catalogue the jobs of ``overrides`` read (the last ``catalogue=``, else Table 1)."""
    paths = [o.split("=", 1)[1] for o in overrides if _key(o) == "catalogue"]
    return load_catalogue(paths[-1] if paths and paths[-1] not in ("null", "") else None)


def params_overrides(path: Path) -> list[str]:
    """The overrides a parameters file holds (``--params``; the DVC stages pass ``params.yaml``,
    which ``dvc exp run -S`` edits instead of conf/): each leaf of its nested mappings as
    ``dotted.key=value`` in Hydra's grammar, in the file's order; an empty file or ``{}``: none.
    A file that is not a mapping of names to plain values is refused in one line."""
    try:
        text = Path(path).read_text()
        refuse_aliases(text, f"--params {path}")
        data = yaml.safe_load(text)
    except OSError as exc:
        raise ConfigError(f"--params {path}: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"--params {path}: not YAML ({one_line(exc)})") from None
    if data is None:
        return []
    if not isinstance(data, dict):
        raise ConfigError(f"--params {path}: needs a mapping of keys to values (found {type(data).__name__})")
    found: list[str] = []

    def walk(node: dict, prefix: str) -> None:
        for key, value in node.items():
            if not isinstance(key, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", key):
                raise ConfigError(f"--params {path}: {prefix}{key}: not a key name")
            if isinstance(value, dict) and value:
                walk(value, f"{prefix}{key}.")
            else:
                found.append(f"{prefix}{key}={_grammar(value, f'{prefix}{key}', path)}")

    walk(data, "")
    return found


def _grammar(value, key: str, path: Path) -> str:
    """``value`` (a YAML scalar, list or mapping) in Hydra's override grammar."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return quoted(value)
    if isinstance(value, list):
        return "[" + ",".join(_grammar(item, key, path) for item in value) + "]"
    if isinstance(value, dict):
        return "{" + ",".join(f"{name}:{_grammar(item, key, path)}" for name, item in value.items()) + "}"
    raise ConfigError(f"--params {path}: {key}={value}: not a number, string, list or mapping")


def _log_to_console() -> None:
    logging.basicConfig(level=logging.INFO, format="[%(name)s] %(message)s", force=True)


def _key(override: str) -> str:
    return override.split("=", 1)[0].lstrip("+~")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m pipeline.study", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"cdpr-studies {code_version()}")
    parser.add_argument("items", nargs="*", help="study names, then key=value overrides for every job")
    parser.add_argument("--all", action="store_true", help="run every study in studies/")
    parser.add_argument("--config-dir", type=Path, default=None,
                        help="your own folder: its studies/ holds your study files and its robot/ "
                             "your robots (default: the package's studies)")
    parser.add_argument("--list", action="store_true", help="list the studies and exit")
    parser.add_argument("--figures-only", action="store_true", help="redo analyses and figures from Parquet")
    parser.add_argument("--out", type=Path, default=None,
                        help="output root (default outputs/studies, where extra overrides give "
                             "the study its own folder NAME+<overrides>)")
    parser.add_argument("--params", type=Path, default=None, metavar="FILE",
                        help="a YAML file of keys and values added to every study's overrides (the DVC "
                             "stages pass params.yaml, which `dvc exp run -S` edits instead of conf/)")
    parser.add_argument("--force", action="store_true",
                        help="replace a study folder that holds another configuration's results")
    parser.add_argument("--launcher", choices=sorted(LAUNCHERS), default="pool",
                        help="pool (default): one study's jobs 2 at a time on worker processes where they "
                             "pay for their start (cost model), "
                             "several studies 2 at a time, each with its jobs on one core; "
                             "serial: one after another in this process, each job with its "
                             "compute.n_jobs; one_core: one after another, each job on one core")
    args = parser.parse_intermixed_args(argv)
    _log_to_console()
    names = [i for i in args.items if "=" not in i]
    extra = [i for i in args.items if "=" in i]
    try:
        extra = [*(params_overrides(args.params) if args.params else []), *extra]
        if args.list:
            for name in available(studies_folder(args.config_dir)):
                print(f"{name}: {load_study(name, config_dir=args.config_dir).title}")
            return
        names = available(studies_folder(args.config_dir)) if args.all else names
        if not names:
            raise ConfigError("no study given (use --all or --list)")
        workers = min(STUDY_WORKERS, os.cpu_count() or 1, len(names))
        concurrent = workers > 1 and args.launcher == "pool" and not args.figures_only
        launcher = "one_core" if concurrent else args.launcher
        checked = {}  # every study of the command checked before the first one runs
        for name in names:
            load_study(name, config_dir=args.config_dir)
            if not args.figures_only:
                claim_study_dir(study_dir(name, extra, args.out), name, extra, args.force)
                if not concurrent:
                    checked[name] = checked_commands(name, extra, args.out, launcher, args.config_dir)
        for path in (_concurrently(names, extra, args.out, launcher, args.force, workers, args.config_dir) if concurrent
                     else (path for name in names for path in run_study(
                         name, extra, args.out, args.figures_only, launcher, checked.get(name), args.force,
                         args.config_dir))):
            log.info("wrote %s", path)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None


if __name__ == "__main__":
    main()

"""Run a plan (:func:`pipeline.app.plan.plan`): every job into its folder, then the sweep summary.

Each job gets what Hydra gives a job: its folder, its records (``.hydra/config.yaml``,
``hydra.yaml``, ``overrides.yaml``, unless ``hydra.output_subdir=null``), its log
(``hydra/job_logging``, ``hydra.verbose``), ``hydra.job.env_set`` and ``hydra.job.chdir``; then
:func:`pipeline.app.job.execute` computes it. Jobs run one after another here, or
``hydra.launcher.n_jobs`` at a time on joblib's worker processes (loky's reusable executor: a
process that runs many plans, ``python -m pipeline.study``, starts its workers once). A sweep
ends with its summary (:func:`pipeline.app.callbacks.gather`).
"""

from __future__ import annotations

import logging
import os
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, replace
from pathlib import Path

from hydra.core.utils import configure_log, env_override
from omegaconf import DictConfig, ListConfig, OmegaConf, open_dict

from pipeline.app.callbacks import gather
from pipeline.app.job import execute
from pipeline.app.plan import Job, Plan
from pipeline.app.problem import grid_size
from pipeline.workspace.dispatch import decide, workers_pay
from pipeline.app.yamltext import to_yaml

log = logging.getLogger("pipeline")
LISTED_JOBS = 10  # jobs named before a sweep starts; every job is named as it ends


@dataclass(frozen=True)
class Setting:
    """What a job needs besides itself where it runs (a worker process): Hydra's logging, the
    environment and the working folder it asks for."""

    configure: bool  # Hydra's logging for the job (else the caller's, as it is)
    logging: DictConfig | None  # hydra.job_logging, resolved for the job's folder
    verbose: object  # hydra.verbose
    env: dict
    chdir: bool


def run(plan: Plan, hydra_logging: bool = True, sharing: list[Job] | None = None) -> list[dict]:
    """Every job of ``plan`` (with Hydra's records and logs; ``hydra_logging=False``: the
    caller's logging as it is, no log file) and, for a sweep, its summary; returns the jobs'
    summaries in plan order. A job's error stops the run (the jobs already finished are reused
    by a rerun). Worker processes are started only where they pay (cost model:
    :func:`pipeline.workspace.dispatch.workers_pay`) for the plan's jobs, or for ``sharing``: every job
    of the process's plans, which share the workers once started (a study's cases)."""
    for address in sorted({str(job.cfg.compute.scheduler) for job in plan.jobs
                           if job.cfg.compute.backend == "dask" and job.cfg.compute.scheduler}):
        from pipeline.workspace.parallel import check_scheduler

        check_scheduler(address)  # before any folder: a scheduler that does not answer is an error
    first = plan.record(plan.jobs[0])
    if hydra_logging:
        configure_log(first.hydra.hydra_logging, first.hydra.verbose)
    workers = min(plan.workers, os.cpu_count() or 1, len(plan.jobs))  # more would only thrash memory
    if workers < plan.workers and len(plan.jobs) > plan.workers:
        log.warning("hydra.launcher.n_jobs=%d: capped at the %d cores of this machine", plan.workers, workers)
    shared = plan.jobs if sharing is None else sharing
    if workers > 1 and not workers_pay(((job.cfg, job.problem, grid_size(job.cfg)) for job in shared), workers):
        log.info("hydra.launcher.n_jobs=%d: %d jobs too short to pay for starting worker processes "
                 "(cost model); they run in this process", plan.workers, len(shared))
        workers = 1
    if plan.multirun:
        plan.sweep_dir.mkdir(parents=True, exist_ok=True)
        (plan.sweep_dir / "multirun.yaml").write_text(to_yaml(plan.sweep_record()), encoding="utf-8")
        log.info("Launching %d jobs %s", len(plan.jobs), "locally" if workers == 1 else f"on {workers} worker processes")
        if len(plan.jobs) <= LISTED_JOBS:
            for job in plan.jobs:
                log.info("\t#%d : %s", job.number, " ".join(_task(job)))
    from pipeline.workspace.progress import Progress

    progress = Progress("jobs", len(plan.jobs), log) if plan.multirun else None
    once = Once()
    if plan.multirun:  # the jobs of one robot repeat its notes (the CPR-8's rank 5, twice a job): once each
        logging.getLogger("pipeline.degeneracy").addFilter(once)
    try:
        summaries = _run_jobs(plan, progress, workers, hydra_logging, first)
    finally:
        logging.getLogger("pipeline.degeneracy").removeFilter(once)
    if plan.multirun and plan.gather:
        gather(plan.sweep_dir, [job.folder for job in plan.jobs], plan.task_overrides)
    elif not plan.multirun:
        log.info("results in %s", plan.jobs[0].folder.absolute())
    return summaries


class Once(logging.Filter):
    """Each distinct message once while attached."""

    def __init__(self):
        super().__init__()
        self.seen: set[str] = set()

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        new = text not in self.seen
        self.seen.add(text)
        return new


def _run_jobs(plan: Plan, progress, workers: int, hydra_logging: bool, first) -> list[dict]:
    """The plan's jobs, here or on ``workers`` job processes, each with its Hydra records."""
    started = ((job, _prepare(plan, job, hydra_logging)) for job in plan.jobs)
    summaries = []
    if workers == 1:
        with _shared_cluster(plan.jobs):
            for job, setting in started:
                summaries.append(run_job(job, setting))
                if hydra_logging and plan.multirun:
                    configure_log(first.hydra.hydra_logging, first.hydra.verbose)
                if progress:
                    progress.step(_outcome(job, summaries[-1]))
    else:
        from joblib import Parallel, delayed

        runner = Parallel(n_jobs=workers, backend="loky", return_as="generator")
        for job, summary in zip(plan.jobs, runner(delayed(run_job)(job, setting) for job, setting in started)):
            summaries.append(summary)
            progress.step(_outcome(job, summary))
    return summaries


def _shared_cluster(jobs: list[Job]):
    """One local Dask cluster for the jobs run here that would each start their own
    (``compute.backend=dask``, no ``compute.scheduler``, more poses than a chunk), started once
    for them all while the block runs (``pipeline.workspace.parallel.local_cluster``: starting
    one costs about 1.8 s here); nothing when fewer than two would, or their ``compute.n_jobs``
    differ."""
    local = [job for job in jobs if job.cfg.compute.backend == "dask" and not job.cfg.compute.scheduler
             and grid_size(job.cfg) > decide(job.cfg, job.problem, grid_size(job.cfg), job.fused).chunk_size]
    sizes = {job.cfg.compute.n_jobs for job in local}
    if len(local) < 2 or len(sizes) != 1:
        return nullcontext()
    from pipeline.workspace.parallel import local_cluster, local_workers

    return local_cluster(local_workers(sizes.pop()))


def _prepare(plan: Plan, job: Job, hydra_logging: bool) -> Setting:
    """The job's folder and Hydra's records in it, written here (the plan's compositions stay
    in this process); the settings it runs with."""
    record = plan.record(job)  # a fresh copy, ours to change
    hydra = record.hydra
    logging_cfg = None if hydra.job_logging is None else OmegaConf.create(
        OmegaConf.to_container(hydra.job_logging, resolve=True))
    verbose = OmegaConf.create(OmegaConf.to_container(hydra.verbose)) if isinstance(hydra.verbose, ListConfig) \
        else hydra.verbose
    setting = Setting(hydra_logging, logging_cfg, verbose, {str(k): str(v) for k, v in hydra.job.env_set.items()},
                      bool(hydra.job.chdir))
    job.folder.mkdir(parents=True, exist_ok=True)
    if hydra.output_subdir is not None:
        saved = job.folder / str(hydra.output_subdir)
        saved.mkdir(parents=True, exist_ok=True)
        with open_dict(record):  # Hydra's record of its own node: the config but the job's keys
            for key in [key for key in record if key != "hydra"]:
                del record[key]
        for name, node in (("config.yaml", job.config), ("hydra.yaml", record), ("overrides.yaml", hydra.overrides.task)):
            (saved / name).write_text(to_yaml(node), encoding="utf-8")
    return setting


def run_job(job: Job, setting: Setting) -> dict:
    """One job with its settings (here or in a worker process); returns its summary."""
    if setting.configure:
        configure_log(setting.logging, setting.verbose)
    job = replace(job, folder=job.folder.absolute())  # the same folder after hydra.job.chdir
    with env_override(setting.env), _working_folder(job.folder if setting.chdir else None):
        return execute(job)


@contextmanager
def _working_folder(folder: Path | None):
    """``hydra.job.chdir=true``: the job runs in its folder (the paths it reads are absolute)."""
    if folder is None:
        yield
        return
    before = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(before)


def _task(job: Job) -> list[str]:
    return [o for o in job.overrides if not o.startswith("hydra.")]


def _outcome(job: Job, summary: dict) -> str:
    """A finished job for the progress line: its overrides and feasible count."""
    name = " ".join(_task(job)) or "job"
    return f"{name}: {summary['n_feasible']}/{summary['n_points']} feasible ({summary['feasible_pct']:.2f} %)"

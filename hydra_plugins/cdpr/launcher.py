"""Hydra launcher that composes each set of config files once (``hydra/launcher=cdpr``, the
default of ``python -m pipeline``).

Hydra's basic launcher composes every job of a sweep from the config files (about 80 ms each).
Jobs that choose the same files (the same config-group choices and ``hydra.*`` overrides)
differ only in plain ``key=value`` overrides, so this launcher composes those files once, with
Hydra's own config loader and the job's group and ``hydra.*`` overrides, and makes each job
from a copy (unpickled: ``preflight.Copies``): its plain overrides applied in command order
with ``OmegaConf.update(..., merge=True)`` (what the loader does after composing),
``hydra.overrides.task`` and ``hydra.job.override_dirname`` set by the loader's rules. The
files of the command itself need no composition: Hydra's sweep config is theirs. A job with
``+``, ``++`` or ``~`` overrides, or a plain override whose value is a dict (merged into the
key, so not replaced by the next job's value), is composed in full. The ``.hydra`` files and results equal the basic
launcher's (tests/test_launcher.py).

``n_jobs`` > 1 runs the jobs on a pool of worker processes (at most one per core; loky's
reusable executor, the one joblib uses): a process that runs many sweeps
(``python -m pipeline.study``) starts its workers once, and each worker imports the code once.
Jobs composed here are sent to the workers whole, with the preflight's typed config. Each job
runs as Hydra's ``run_job`` runs it, with fewer copies of its config (``runner.run_job``).
Built on Hydra's public plugin interface (Launcher, ``hydra.core.utils``).
"""

import logging
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional, Sequence, Tuple

from hydra.core.config_store import ConfigStore
from hydra.core.singleton import Singleton
from hydra.core.utils import JobReturn, JobStatus, configure_log, filter_overrides, setup_globals
from hydra.plugins.launcher import Launcher
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, open_dict

from hydra_plugins.cdpr.runner import run_job

log = logging.getLogger(__name__)
LISTED_JOBS = 10  # jobs named before a sweep starts; every job is named as it ends


@dataclass
class CdprLauncherConf:
    _target_: str = "hydra_plugins.cdpr.launcher.CdprLauncher"
    n_jobs: int = 1  # jobs at a time; > 1: that many worker processes, kept for the next sweep


def n_jobs_rule(n_jobs: Any) -> Optional[str]:
    """What is wrong with an ``n_jobs`` (None: nothing); the preflight applies it too, so that a
    bad value is one line before any folder is made."""
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or n_jobs < 1:
        return "must be a whole number >= 1 (jobs at a time)"
    return None


ConfigStore.instance().store(group="hydra/launcher", name="cdpr", node=CdprLauncherConf,
                             provider="cdpr-studies")


class CdprLauncher(Launcher):
    """Jobs composed once per set of config files, run here one after another or on a pool."""

    def __init__(self, n_jobs: int = 1) -> None:
        broken = n_jobs_rule(n_jobs)
        if broken:
            raise ValueError(f"hydra.launcher.n_jobs={n_jobs}: {broken}")
        self.n_jobs = n_jobs
        self.config: Optional[DictConfig] = None
        self.hydra_context: Optional[HydraContext] = None
        self.task_function: Optional[TaskFunction] = None
        self._composed: Dict[Tuple[str, ...], Any] = {}  # preflight.Copies: composition, task

    def setup(self, *, hydra_context: HydraContext, task_function: TaskFunction,
              config: DictConfig) -> None:
        self.config = config
        self.hydra_context = hydra_context
        self.task_function = task_function

    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int) -> Sequence[JobReturn]:
        setup_globals()
        configure_log(self.config.hydra.hydra_logging, self.config.hydra.verbose)
        Path(str(self.config.hydra.sweep.dir)).mkdir(parents=True, exist_ok=True)
        workers = min(self.n_jobs, os.cpu_count() or 1)  # more would only thrash memory
        if workers < self.n_jobs:
            log.warning("hydra.launcher.n_jobs=%d: capped at the %d cores of this machine", self.n_jobs, workers)
        from pipeline.workspace.progress import Progress

        log.info("Launching %d jobs %s", len(job_overrides),
                 "locally" if workers == 1 else f"on {workers} worker processes")
        if len(job_overrides) <= LISTED_JOBS:  # a long sweep is named job by job as they end
            for idx, overrides in enumerate(job_overrides, start=initial_job_idx):
                log.info("\t#%d : %s", idx, " ".join(filter_overrides(overrides)))
        progress = Progress("jobs", len(job_overrides), log)
        configs = (self.job_config(idx, list(overrides))
                   for idx, overrides in enumerate(job_overrides, start=initial_job_idx))
        runs = []
        fused = _fused_pays()
        if workers == 1 or len(job_overrides) == 1:
            for config, task in configs:
                runs.append(_run(config, task, self.hydra_context, self.task_function, fused=fused))
                configure_log(self.config.hydra.hydra_logging, self.config.hydra.verbose)
                progress.step(_outcome(runs[-1]))
            return runs
        from joblib import Parallel, delayed

        state = Singleton.get_state()
        for ret in Parallel(n_jobs=workers, backend="loky", return_as="generator")(
                delayed(_run)(config, task, self.hydra_context, self.task_function, state, _prepared(task), fused)
                for config, task in configs):
            runs.append(ret)
            progress.step(_outcome(ret))
        return runs

    def job_config(self, idx: int, overrides: Sequence[str]) -> Tuple[DictConfig, DictConfig]:
        """The config Hydra's loader composes for these overrides, with job id and number, and
        the task's config: the same without Hydra's node."""
        from pipeline.app.preflight import Copies, applies_after_composing, derived, parse, structural, without_hydra

        parsed = parse(overrides)
        loader = self.hydra_context.config_loader
        if all(applies_after_composing(o) for o in parsed):
            files = tuple(o.input_line for o in parsed if structural(o))
            if files not in self._composed:
                # the command's own files: Hydra's sweep config is their composition (the fixed
                # values applied, which each job applies again with its swept ones; the task
                # overrides and folder name are each job's own), about 80 ms saved
                composed = (self.config if files == self._sweep_files()
                            else loader.load_sweep_config(self.config, list(files)))
                self._composed[files] = Copies(composed), Copies(without_hydra(composed))
            config, task = derived(*(copies() for copies in self._composed[files]), parsed)
        else:
            config = loader.load_sweep_config(self.config, overrides)
            task = without_hydra(config)
        with open_dict(config):
            config.hydra.job.id = idx
            config.hydra.job.num = idx
        return config, task

    def _sweep_files(self) -> Tuple[str, ...]:
        """The structural overrides of the sweep's command that are not swept (its config files)."""
        from pipeline.app.preflight import parse, structural

        return tuple(o.input_line for o in parse(list(self.config.hydra.overrides.task))
                     if structural(o) and not o.is_sweep_override())


def _outcome(ret: JobReturn) -> str:
    """A finished job for the progress line: its overrides and feasible count."""
    name = " ".join(filter_overrides(ret.overrides or [])) or "job"
    if ret.status != JobStatus.COMPLETED:
        return f"{name}: failed"
    summary = ret.return_value
    if isinstance(summary, dict) and "n_feasible" in summary:
        return (f"{name}: {summary['n_feasible']}/{summary['n_points']} feasible "
                f"({summary['feasible_pct']:.2f} %)")
    return name


def _fused_pays() -> bool:
    """Whether the jobs the preflight prepared in this process would, together, pay for loading
    the compiled kernels (``pipeline.workspace.compute.fused_pays``)."""
    from pipeline.app.job import PREPARED
    from pipeline.workspace.compute import fused_pays

    return fused_pays(cfg for cfg, _ in PREPARED.values())


def _prepared(task: DictConfig) -> Tuple[str, Any]:
    """The YAML of the job's config without Hydra's node (``task``: its ``.hydra/config.yaml``),
    and the preflight's typed config and catalogue for it, taken out of
    ``pipeline.app.job.PREPARED`` (None when the preflight of this process has none: the job
    types its config itself)."""
    from pipeline.app.job import PREPARED
    from pipeline.app.yamltext import to_yaml

    text = to_yaml(task)
    return text, PREPARED.pop(text, None)


def _run(config: DictConfig, task: DictConfig, hydra_context: HydraContext, task_function: TaskFunction,
         singleton_state: Optional[Dict[Any, Any]] = None,
         prepared: Optional[Tuple[str, Any]] = None, fused: bool = False) -> JobReturn:
    """One job (``config``, and ``task``: the same without Hydra's node), as Hydra's launchers run
    it (:func:`hydra_plugins.cdpr.runner.run_job`); in a worker process, with the parent's Hydra
    state. ``prepared``: :func:`_prepared` of ``task`` if the parent made it; the job takes its
    typed config from it (``pipeline.app.job.CURRENT``). ``fused``: the sweep pays for the
    compiled kernels (:func:`_fused_pays`), so the job uses them where they apply."""
    from pipeline.app.job import CURRENT
    from pipeline.workspace.compute import SWEEP_FUSED

    if singleton_state is not None:
        setup_globals()
        Singleton.set_state(singleton_state)
    text, entry = _prepared(task) if prepared is None else prepared
    tokens = SWEEP_FUSED.set(fused), CURRENT.set(entry)
    try:
        return run_job(config, task, task_function, hydra_context, task_yaml=text)
    finally:
        SWEEP_FUSED.reset(tokens[0])
        CURRENT.reset(tokens[1])

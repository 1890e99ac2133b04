"""One job, run as Hydra's ``hydra.core.utils.run_job`` runs it, with one copy of the config
where Hydra makes four: a job of a sweep (the ``cdpr`` launcher), or the one job of a command
of run mode (:func:`run`, what Hydra's ``run`` does once it has composed the config).

Hydra's function sets ``HydraConfig`` twice (a masked copy of the config each time), deep-copies
the whole config for the task and Hydra's node again for the job's record: about 15 ms a job,
where a study's job computes in 10 to 70 ms. Here ``HydraConfig`` is set once and its copy is
the record, and the task's config is the launcher's (one unpickled copy, with the job's
overrides, of the composition without Hydra's node). The rest is Hydra's: the job's folder,
``hydra.job.chdir`` (unset is false, Hydra's rule from version_base 1.2, which the app uses),
its logging, ``.hydra/config.yaml``, ``hydra.yaml`` and ``overrides.yaml`` (the same text:
OmegaConf's YAML, emitted by libyaml: ``pipeline.app.yamltext``, UTF-8), ``hydra.job.env_set``, the callbacks, the ``JobReturn``
(tests/test_launcher.py compares the files with Hydra's basic launcher's).
"""

import logging
import os
import warnings
from pathlib import Path
from typing import Any, Optional

from hydra.core.hydra_config import HydraConfig
from hydra.core.utils import JobReturn, JobRuntime, JobStatus, configure_log, env_override, setup_globals
from hydra.types import HydraContext, TaskFunction
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf, open_dict, read_write

from pipeline.app.yamltext import to_yaml


def run(config: DictConfig, task_cfg: DictConfig, task_function: TaskFunction,
        task_yaml: Optional[str] = None) -> JobReturn:
    """What Hydra's ``run`` does with the config it composed for a command of run mode
    (``config``, ``hydra.mode`` RUN; ``task_cfg``: the same without Hydra's node): Hydra's
    logging, the callbacks of ``hydra.callbacks`` (``on_run_start``, ``on_run_end``, and the
    job's), the job in ``hydra.run.dir``, and the task's exception raised if it failed."""
    setup_globals()
    JobRuntime.instance().set("name", task_function.__module__.rsplit(".", 1)[-1])  # Hydra's task name
    configure_log(config.hydra.hydra_logging, config.hydra.verbose)
    callbacks = Callbacks(config)
    callbacks.on_run_start(config=config, config_name=config.hydra.job.config_name)
    ret = run_job(config, task_cfg, task_function, HydraContext(config_loader=None, callbacks=callbacks),
                  task_yaml, job_dir_key="hydra.run.dir", job_subdir_key=None)
    callbacks.on_run_end(config=config, config_name=config.hydra.job.config_name, job_return=ret)
    _ = ret.return_value  # the task's exception, raised
    return ret


class Callbacks:
    """The callbacks of ``hydra.callbacks``, called as Hydra calls them (its own class is not
    public): in order when something starts, in reverse when it ends, a callback's exception
    turned into a warning."""

    def __init__(self, config: DictConfig) -> None:
        self.callbacks = [instantiate(params) for params in (OmegaConf.select(config, "hydra.callbacks") or {}).values()]

    def _notify(self, name: str, reverse: bool = False, **kwargs: Any) -> None:
        for callback in reversed(self.callbacks) if reverse else self.callbacks:
            try:
                getattr(callback, name)(**kwargs)
            except Exception as exc:  # Hydra's rule: a callback does not stop the run
                warnings.warn(f"Callback {type(callback).__name__}.{name} raised {type(exc).__name__}: {exc}",
                              stacklevel=2)

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        self._notify("on_run_start", config=config, **kwargs)

    def on_run_end(self, config: DictConfig, **kwargs: Any) -> None:
        self._notify("on_run_end", reverse=True, config=config, **kwargs)

    def on_job_start(self, config: DictConfig, *, task_function: TaskFunction, **kwargs: Any) -> None:
        self._notify("on_job_start", config=config, task_function=task_function, **kwargs)

    def on_job_end(self, config: DictConfig, job_return: JobReturn, **kwargs: Any) -> None:
        self._notify("on_job_end", reverse=True, config=config, job_return=job_return, **kwargs)


def run_job(config: DictConfig, task_cfg: DictConfig, task_function: TaskFunction,
            hydra_context: HydraContext, task_yaml: Optional[str] = None,
            job_dir_key: str = "hydra.sweep.dir", job_subdir_key: Optional[str] = "hydra.sweep.subdir") -> JobReturn:
    """Run ``task_function`` on a job's ``task_cfg`` (``config`` without Hydra's node, the
    caller's copy) in the folder ``job_dir_key``/``job_subdir_key`` (Hydra's arguments: a sweep
    job's by default). ``config`` is the job's own object: its output folder is set in it.
    ``task_yaml``: ``to_yaml(task_cfg)`` if the caller has it (``.hydra/config.yaml``). The
    task's exception, if any, is the return value of a FAILED ``JobReturn``, as with Hydra."""
    old_cwd = os.getcwd()
    hydra_config = HydraConfig.instance()
    orig_hydra_cfg = hydra_config.cfg
    hydra_config.set_config(config)  # the folder's interpolations may read Hydra's node
    output_dir = str(OmegaConf.select(config, job_dir_key))
    if job_subdir_key is not None:
        output_dir = os.path.join(output_dir, str(OmegaConf.select(config, job_subdir_key)))
    record = hydra_config.cfg  # Hydra's node, copied by set_config: the job's record
    for node in (config, record):
        with read_write(node.hydra.runtime), open_dict(node.hydra.runtime):
            node.hydra.runtime.output_dir = os.path.abspath(output_dir)
    chdir = bool(record.hydra.job.chdir)
    try:
        ret = JobReturn()
        ret.cfg = task_cfg
        ret.hydra_cfg = record
        ret.overrides = OmegaConf.to_container(config.hydra.overrides.task)
        Path(output_dir).mkdir(parents=True, exist_ok=True)
        if chdir:
            os.chdir(output_dir)
        ret.working_dir = os.getcwd()
        configure_log(config.hydra.job_logging, config.hydra.verbose)
        if config.hydra.output_subdir is not None:
            saved = Path(config.hydra.runtime.output_dir) / str(config.hydra.output_subdir)
            saved.mkdir(parents=True, exist_ok=True)
            for name, text in (("config.yaml", task_yaml or to_yaml(task_cfg)),
                               ("hydra.yaml", to_yaml(record)),
                               ("overrides.yaml", to_yaml(config.hydra.overrides.task))):
                (saved / name).write_text(text, encoding="utf-8")
        with env_override(record.hydra.job.env_set):
            hydra_context.callbacks.on_job_start(config=config, task_function=task_function)
            try:
                ret.return_value = task_function(task_cfg)
                ret.status = JobStatus.COMPLETED
            except Exception as exc:  # the sweeper raises it, as with Hydra
                ret.return_value = exc
                ret.status = JobStatus.FAILED
        ret.task_name = JobRuntime.instance().get("name")
        _flush_logs()
        hydra_context.callbacks.on_job_end(config=config, job_return=ret)
        return ret
    finally:
        hydra_config.cfg = orig_hydra_cfg
        if chdir:
            os.chdir(old_cwd)


def _flush_logs() -> None:
    """Every logging handler flushed (the job's log file complete on disk)."""
    loggers = [logging.getLogger(), *(logger for logger in logging.getLogger().manager.loggerDict.values()
                                      if isinstance(logger, logging.Logger))]
    for handler in {handler for logger in loggers for handler in logger.handlers}:
        handler.flush()

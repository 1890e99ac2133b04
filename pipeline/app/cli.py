"""The command line: ``python -m pipeline [-m] [key=value ...]`` (``pipeline/__main__.py``).

Hydra composes, the pipeline plans and runs: every job of the command is planned and checked
(:func:`pipeline.app.plan.plan`: a bad key or value exits with status 2 and one line on stderr,
and no folder is made), then run (:func:`pipeline.app.run.run`). A command that names one of
Hydra's own launchers or sweepers (``hydra/launcher=submitit_slurm``, ``hydra/sweeper=optuna``),
or a flag that Hydra answers (``--cfg``, ``--info``, ``--run``, ``--hydra-help``,
``--shell-completion``), is checked the same way and then handed to Hydra's stock application
(:func:`main`), whose task runs each job through the same :func:`pipeline.app.job.execute`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from omegaconf import DictConfig

from pipeline.app.config import register
from pipeline.app.resources import CONF_DIR
from pipeline.errors import ConfigError

register()
OURS = {"-m", "--multirun", "--config-dir", "-cd"}  # the flags the pipeline's own runner takes


@hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name="config")
def main(cfg: DictConfig) -> dict:
    """Hydra's stock application: one job of the config Hydra composed, in the folder Hydra made
    (any Hydra launcher runs it: a worker, a SLURM task)."""
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    from pipeline.app.problem import validate
    from pipeline.app.job import execute, log
    from pipeline.app.plan import Job
    from pipeline.model.catalogue import load_catalogue

    hydra_cfg = HydraConfig.get()
    try:
        catalogue = load_catalogue(cfg.catalogue) if "catalogue" in cfg else None
        typed, problem = validate(cfg, catalogue)
        summary = execute(Job(None, tuple(hydra_cfg.overrides.task), Path(hydra_cfg.runtime.output_dir),
                              typed, catalogue, problem, cfg, (), str(hydra_cfg.runtime.choices.robot)))
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    if hydra_cfg.mode == RunMode.RUN:  # a sweep says where its folder is when it ends (its summary)
        log.info("results in %s", hydra_cfg.runtime.output_dir)
    return summary


def hydra_flag(argv: list[str]) -> bool:
    """Whether the command has a flag Hydra answers (``--cfg``, ``--run``, ...)."""
    return any(a.split("=", 1)[0] not in OURS for a in argv if a.startswith("-"))


def cli() -> None:
    argv = sys.argv[1:]
    if argv == ["--version"]:  # the project's version (Hydra's flag prints Hydra's)
        from pipeline.app.results import code_version

        print(f"cdpr-studies {code_version()} (Hydra {hydra.__version__})")
        return
    if "--help" in argv or "-h" in argv:  # the keys of this composition, with meanings
        _help([a for a in argv if a not in ("--help", "-h")])
        return
    from pipeline.app.plan import plan

    try:
        for flag in ("--config-name", "-cn", "--config-path", "-cp", "--experimental-rerun"):
            if flag in argv or any(a.startswith(flag + "=") for a in argv):
                raise ConfigError(f"{flag}: the pipeline composes conf/config.yaml; your own files: "
                                  "--config-dir DIR (DIR/robot/NAME.yaml, ...)")
        planned = plan(argv)  # None: a command that launches no job
        if planned is None or planned.by_hydra or hydra_flag(argv):
            main()
            return
        from pipeline.app.run import run

        run(planned)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None


def _help(argv: list[str]) -> None:
    from pipeline.app.helppage import page
    from pipeline.app.plan import composed, plan
    from pipeline.app.results import code_version

    argv = [a for a in argv if a not in ("-m", "--multirun")]
    try:
        planned = plan(argv)
        if planned is None or len(planned.jobs) != 1:
            raise ValueError
        config = planned.jobs[0].cfg
    except ConfigError as exc:
        if "no value given" not in str(exc):
            print(f"error: {exc}", file=sys.stderr)
            raise SystemExit(2) from None
        config = composed(argv)  # a robot whose points are still to give: its keys, ??? where required
    except ValueError:  # a sweep, several jobs
        print("error: give one value per key with --help", file=sys.stderr)
        raise SystemExit(2) from None
    print(page(argv, config, code_version()), end="")

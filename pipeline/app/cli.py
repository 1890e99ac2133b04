"""The Hydra application: ``python -m pipeline [-m] [key=value ...]`` (``pipeline/__main__.py``).

Every job's config is validated before Hydra starts (``pipeline.app.preflight``): a bad key or value
exits with status 2 and one line on stderr, and no output folder is created. A command of run
mode made of plain overrides then runs on the preflight's composition
(``pipeline.app.preflight.hydra_run``, ``hydra_plugins.cdpr.runner.run``: the files, logs and
output of Hydra's run, without its two compositions of the same files); any other command
(``-m``, a flag such as ``--run`` or ``--config-dir``, ``+``/``~`` overrides) goes through Hydra.
"""

from __future__ import annotations

import sys

import hydra
from omegaconf import DictConfig

from pipeline.app.config import register
from pipeline.errors import ConfigError
from pipeline.app.preflight import Reuse, check, hydra_run
from pipeline.app.resources import CONF_DIR

register()


@hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name="config")
def main(cfg: DictConfig) -> dict:
    from pipeline.app.job import run_job

    return run_job(cfg)  # the summary: the launcher's progress line reports it


def launch(argv: list[str]) -> None:
    """Run a command the preflight has checked in this process, as if it were Hydra's command
    line (``python -m pipeline.study`` runs its sweeps so: the code is imported, and the jobs'
    worker processes started, once). Hydra reads its command line from ``sys.argv`` only."""
    saved = sys.argv
    sys.argv = [saved[0], *argv]
    try:
        main()
    finally:
        sys.argv = saved


def cli() -> None:
    from pipeline.app.job import PREPARED

    if sys.argv[1:] == ["--version"]:  # the project's version (Hydra's flag prints Hydra's)
        from pipeline.app.results import code_version

        print(f"cdpr-studies {code_version()} (Hydra {hydra.__version__})")
        return
    if "--help" in sys.argv[1:] or "-h" in sys.argv[1:]:  # the keys of this composition, with meanings
        _help([a for a in sys.argv[1:] if a not in ("--help", "-h")])
        return
    reuse = Reuse(folders_after=False)  # the composition, kept for the job of run mode
    try:
        PREPARED.update(check(sys.argv[1:], reuse))
        composed = hydra_run(sys.argv[1:], reuse)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    if composed is None:
        main()
    else:  # what Hydra's run would compose again twice (pipeline.app.preflight.hydra_run)
        from hydra_plugins.cdpr.runner import run

        run(*composed, main.__wrapped__)


def _help(argv: list[str]) -> None:
    from pipeline.app.helppage import page
    from pipeline.app.results import code_version

    try:
        ((typed, _),) = check([a for a in argv if a not in ("-m", "--multirun")]).values()
    except (ConfigError, ValueError) as exc:  # ValueError: a sweep, several jobs
        print(f"error: {exc if isinstance(exc, ConfigError) else 'give one value per key with --help'}",
              file=sys.stderr)
        raise SystemExit(2) from None
    print(page(argv, typed, code_version()), end="")

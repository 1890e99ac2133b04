"""Entry point: ``python -m pipeline [-m] [key=value ...]`` (Hydra command line).

Every job's config is validated before Hydra starts (``pipeline.preflight``): a bad key or value
exits with status 2 and one line on stderr, and no output folder is created.
"""

from __future__ import annotations

import sys

import hydra
from omegaconf import DictConfig

from pipeline.config import register
from pipeline.errors import ConfigError

register()


@hydra.main(version_base="1.3", config_path="../conf", config_name="config")
def main(cfg: DictConfig) -> None:
    from pipeline.job import run_job

    run_job(cfg)


def cli() -> None:
    from pipeline.job import PREPARED
    from pipeline.preflight import check

    try:
        PREPARED.update(check(sys.argv[1:]))
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    main()


if __name__ == "__main__":
    cli()

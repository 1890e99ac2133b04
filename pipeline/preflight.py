"""Validate every job of a command line before Hydra creates any output folder.

Hydra makes the run (or sweep) folder before the task function starts, so a bad value found
inside a job would leave folders behind. The preflight expands the command's sweep exactly as
Hydra's basic sweeper does, composes each job's config, validates it, and stops at the first
problem with a one-line message naming the key and value.
"""

from __future__ import annotations

import re
from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
from hydra.core.override_parser.overrides_parser import OverridesParser

from pipeline.actuators import load_catalogue
from pipeline.config import validate
from pipeline.errors import ConfigError

CONF_DIR = Path(__file__).resolve().parent.parent / "conf"
NO_JOB_FLAGS = {"--help", "-h", "--hydra-help", "--info", "-i", "--cfg", "-c", "--version",
                "--shell-completion", "-sc", "--resolve", "-p", "--package"}
FLAGS_WITH_VALUE = {"--config-path", "-cp", "--config-name", "-cn", "--config-dir", "-cd",
                    "--experimental-rerun"}
_NOISE = re.compile(r"^\s*(full_key|reference_type|object_type|object_type=).*$")


def job_overrides(argv: list[str]) -> list[list[str]] | None:
    """The override list of every job the command would launch; None when it launches none."""
    overrides, skip = [], False
    for arg in argv:
        if skip:
            skip = False
        elif arg in NO_JOB_FLAGS:
            return None
        elif arg in FLAGS_WITH_VALUE:
            skip = True
        elif not arg.startswith("-"):
            overrides.append(arg)
    if not ("-m" in argv or "--multirun" in argv):
        return [overrides]
    parsed = OverridesParser.create().parse_overrides(overrides)
    return BasicSweeper.split_arguments(parsed, max_batch_size=None)[0]


def check(argv: list[str]) -> None:
    """Raise ConfigError for the first job whose config cannot be composed or is invalid."""
    try:
        jobs = job_overrides(argv)
    except Exception as exc:  # Hydra's override grammar errors have several types
        raise ConfigError(one_line(exc)) from exc
    if jobs is None:
        return
    catalogues = {}
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name="preflight"):
        for overrides in jobs:
            try:
                cfg = compose(config_name="config", overrides=overrides)
            except Exception as exc:  # composition errors come as Hydra and OmegaConf types
                raise ConfigError(one_line(exc)) from exc
            if cfg.catalogue not in catalogues:
                catalogues[cfg.catalogue] = load_catalogue(cfg.catalogue)
            validate(cfg, catalogues[cfg.catalogue].index)


def one_line(exc: BaseException) -> str:
    """Hydra/OmegaConf messages span several lines; keep the informative ones, joined."""
    parts = []
    while exc is not None:
        for line in str(exc).splitlines():
            line = line.strip()
            if line and not _NOISE.match(line) and line not in parts:
                parts.append(line)
        exc = exc.__cause__
    return ": ".join(parts)

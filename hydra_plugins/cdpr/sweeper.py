"""Hydra's basic sweep without its second composition of every job (``hydra/sweeper=cdpr``, the
default of ``python -m pipeline``).

Hydra's basic sweeper composes each job's config once to validate it and once more to run it,
about 80 ms each, serially in the parent. ``python -m pipeline`` has already composed and
validated every job before Hydra starts (``pipeline.app.preflight``), so this sweeper expands the
sweep the same way (same jobs, same order: ``preflight.expand_sweep``) and hands the whole batch
to the launcher. Built on Hydra's public plugin interface only; it lives in the
``hydra_plugins`` namespace because Hydra accepts plugins from there only.
"""

from dataclasses import dataclass
from pathlib import Path
from typing import Any, List, Optional

from hydra.core.config_store import ConfigStore
from hydra.core.plugins import Plugins
from hydra.plugins.sweeper import Sweeper
from omegaconf import DictConfig, OmegaConf


@dataclass
class CdprSweeperConf:
    _target_: str = "hydra_plugins.cdpr.sweeper.CdprSweeper"


ConfigStore.instance().store(group="hydra/sweeper", name="cdpr", node=CdprSweeperConf,
                             provider="cdpr-studies")


class CdprSweeper(Sweeper):
    """The basic sweeper's expansion and launch, for jobs the preflight already validated."""

    def __init__(self) -> None:
        self.config: Optional[DictConfig] = None
        self.launcher = None

    def setup(self, *, hydra_context, task_function, config: DictConfig) -> None:
        self.config = config
        self.launcher = Plugins.instance().instantiate_launcher(
            hydra_context=hydra_context, task_function=task_function, config=config)

    def sweep(self, arguments: List[str]) -> Any:
        from pipeline.app.preflight import expand_sweep, parse

        jobs = expand_sweep(parse(arguments))
        sweep_dir = Path(self.config.hydra.sweep.dir)
        sweep_dir.mkdir(parents=True, exist_ok=True)
        OmegaConf.save(self.config, sweep_dir / "multirun.yaml")
        results = self.launcher.launch(jobs, initial_job_idx=0)
        for result in results:
            _ = result.return_value  # raises the job's exception, as the basic sweeper does
        return [results]

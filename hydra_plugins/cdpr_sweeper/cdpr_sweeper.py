"""The basic sweeper without its second composition of every job.

Hydra's basic sweeper composes each job's config once to validate it and once more to run it,
about 80 ms each. ``python -m pipeline`` has already composed and validated every job of the
command before Hydra starts (``pipeline.preflight``), so this sweeper skips that repetition and
otherwise behaves exactly like ``hydra/sweeper=basic`` (same expansion, order and batches).
"""

from dataclasses import dataclass
from typing import Dict, Optional, Sequence

from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
from hydra.core.config_store import ConfigStore


@dataclass
class CdprSweeperConf:
    _target_: str = "hydra_plugins.cdpr_sweeper.cdpr_sweeper.CdprSweeper"
    max_batch_size: Optional[int] = None
    params: Optional[Dict[str, str]] = None


ConfigStore.instance().store(
    group="hydra/sweeper", name="cdpr", node=CdprSweeperConf, provider="cdpr-studies"
)


class CdprSweeper(BasicSweeper):
    """Basic sweeper whose jobs were validated by the preflight of ``python -m pipeline``."""

    def validate_batch_is_legal(self, batch: Sequence[Sequence[str]]) -> None:
        return None

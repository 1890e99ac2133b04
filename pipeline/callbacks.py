"""Hydra callbacks: at the end of a multirun, one summary table for the whole sweep."""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd
from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from pipeline.results import write_parquet

log = logging.getLogger("pipeline")
REPORTED = ["n_points", "n_feasible", "feasible_pct", "volume_m3"]


class SweepSummary(Callback):
    """Concatenate every job's summary.parquet into <sweep dir>/summary.parquet."""

    def on_multirun_end(self, config: DictConfig, **kwargs) -> None:
        sweep_dir = Path(config.hydra.sweep.dir)
        rows = [pd.read_parquet(path) for path in sorted(sweep_dir.glob("*/summary.parquet"))]
        if not rows:
            return
        table = pd.concat(rows, ignore_index=True)
        varying = [
            c for c in table.columns
            if c not in REPORTED and table[c].astype(str).nunique() > 1 and not c.startswith("lost_")
        ]
        table = table.sort_values(varying, kind="stable").reset_index(drop=True) if varying else table
        sweep_yaml = OmegaConf.to_yaml(
            {"overrides": list(config.hydra.overrides.task), "jobs": len(table)}
        )
        write_parquet(table, sweep_dir / "summary.parquet", sweep_yaml)
        shown = [c for c in varying if c not in ("actuator_name",)] + REPORTED
        log.info("sweep summary (%s):\n%s", sweep_dir / "summary.parquet",
                 table[shown].to_string(index=False))

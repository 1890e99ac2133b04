"""Hydra callbacks: at the end of a multirun, one summary table for the whole sweep."""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd
from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from pipeline.app.results import varying_settings, write_parquet

log = logging.getLogger("pipeline")
REPORTED = ["n_points", "n_feasible", "feasible_pct", "volume_m3"]


class SweepSummary(Callback):
    """Concatenate the summary.parquet of every job of this sweep into <sweep dir>/summary.parquet,
    with a ``job`` column naming each job's folder, in folder-name order whatever order the jobs
    ran in. When jobs run in this process they are collected as they end, so folders left by an
    earlier sweep into the same directory are not included; with a launcher that runs jobs
    elsewhere (worker processes), every job folder of the sweep directory is read."""

    def __init__(self) -> None:
        self.job_dirs: list[Path] = []

    def on_job_end(self, config: DictConfig, **kwargs) -> None:
        self.job_dirs.append(Path(config.hydra.runtime.output_dir))

    def on_multirun_end(self, config: DictConfig, **kwargs) -> None:
        sweep_dir = Path(config.hydra.sweep.dir)
        rows = []
        job_dirs = sorted(self.job_dirs or (p.parent for p in sweep_dir.glob("*/summary.parquet")))
        for job_dir in job_dirs:
            if (job_dir / "summary.parquet").exists():
                row = pd.read_parquet(job_dir / "summary.parquet")
                row.insert(0, "job", job_dir.name)
                rows.append(row)
        if not rows:
            return
        table = pd.concat(rows, ignore_index=True)
        varying = varying_settings(table, ignore=("job",))
        table = table.sort_values(varying, kind="stable").reset_index(drop=True) if varying else table
        sweep_yaml = OmegaConf.to_yaml(
            {"overrides": list(config.hydra.overrides.task), "jobs": len(table)}
        )
        write_parquet(table, sweep_dir / "summary.parquet", sweep_yaml)
        shown = [c for c in varying if c not in ("actuator_name",)] + REPORTED
        log.info("sweep summary (%s):\n%s", sweep_dir / "summary.parquet",
                 table[shown].to_string(index=False))
        log.info("results in %s (%d job folders)", sweep_dir, len(table))

"""The Hydra task: one job writes points.parquet (samples.parquet for lines) and, last,
summary.parquet in its folder.

A job whose folder already holds a summary.parquet written with the same resolved config and
the same code version is not recomputed: every file is written to a temporary name and renamed
(``pipeline.results.write_parquet``), and the summary is written last, so its presence proves
the job finished. A sweep killed mid-way therefore resumes with only the missing jobs.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from pipeline.actuators import load_catalogue
from pipeline.config import validate
from pipeline.results import (
    CONFIG_KEY, VERSION_KEY, ParquetSink, code_version, read_metadata, write_parquet,
)
from pipeline.lines import simulate_lines
from pipeline.workspace import analysis_name, compute_workspace

log = logging.getLogger("pipeline")


def run_job(cfg: DictConfig) -> dict:
    """Validate, compute the feasible workspace, write the Parquet files; returns the summary."""
    catalogue = load_catalogue(cfg.catalogue) if "catalogue" in cfg else None
    cfg = validate(cfg, None if catalogue is None else catalogue.index)
    out = Path(HydraConfig.get().runtime.output_dir)
    config_yaml = OmegaConf.to_yaml(cfg, resolve=True)
    done = finished_summary(out, config_yaml)
    if done is not None:
        log.info("reused the finished job in %s (same config and code version)", out)
        return done
    if analysis_name(cfg) == "lines":
        samples, points, summary = simulate_lines(cfg, catalogue)
        write_parquet(samples, out / "samples.parquet", config_yaml)
        log.info("%d lines, %d samples; simulated %d vs grid %d feasible points, agreement %.1f%%",
                 summary["n_lines"], summary["n_samples"], summary["n_feasible"],
                 summary["n_feasible_grid"], summary["agreement_pct"])
        write_parquet(points, out / "points.parquet", config_yaml)
    else:  # streamed chunk by chunk: memory bounded by a chunk, not by the grid
        with ParquetSink(out / "points.parquet", config_yaml) as sink:
            _, summary = compute_workspace(cfg, catalogue, sink.write)
    write_parquet(pd.DataFrame([summary]), out / "summary.parquet", config_yaml)
    lost = ", ".join(
        f"{key[len('lost_'):]} {value}" for key, value in summary.items() if key.startswith("lost_")
    )
    subject = (f"actuator {cfg.actuator} ({summary['actuator_name']})"
               if "actuator_name" in summary else f"{cfg.robot.name} {summary['analysis']}")
    log.info(
        "%s: %d/%d feasible = %.2f%% (%.4f m^3); lost to %s", subject,
        summary["n_feasible"], summary["n_points"], summary["feasible_pct"], summary["volume_m3"],
        lost,
    )
    return summary


def finished_summary(out: Path, config_yaml: str) -> dict | None:
    """The summary of a job already finished in ``out`` with this config and code, else None."""
    path = out / "summary.parquet"
    if not path.exists():
        return None
    meta = read_metadata(path)
    if meta.get(CONFIG_KEY) != config_yaml or meta.get(VERSION_KEY) != code_version():
        return None
    return pd.read_parquet(path).iloc[0].to_dict()

"""The sweep summary: at the end of a sweep, one table for all its jobs (:func:`gather`, called by
``pipeline.app.run``, and by Hydra's callback :class:`SweepSummary` when Hydra runs the sweep).

Arrow tables read and built without pandas (``pipeline.workspace.arrow``), like the jobs' own
files: the main job's process never imports it."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import pyarrow as pa
from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from pipeline.app.results import READ_ERRORS, read_verified, varying_settings, write_parquet
from pipeline.errors import ConfigError, one_line
from pipeline.workspace.arrow import sorted_by, texts

log = logging.getLogger("pipeline")
REPORTED = ["n_points", "n_feasible", "feasible_pct", "volume_m3"]


def gather(sweep_dir: Path, job_dirs: list[Path], overrides: list[str]) -> None:
    """Concatenate the summary.parquet of every job of a sweep into <sweep dir>/summary.parquet,
    with a ``job`` column naming each job's folder, in folder-name order whatever order the jobs
    ran in, then sorted (stably) by the settings the sweep varied. A column some jobs lack (a
    sweep over analyses) is empty (null) in their rows, and integers meeting floats become
    floats. ``job_dirs``: the sweep's jobs (folders left by an earlier sweep into the same
    directory are not included); empty: every job folder of the sweep directory.
    ``overrides``: the sweep command's, recorded in the table's metadata."""
    rows = []
    for job_dir in sorted(job_dirs or (p.parent for p in sweep_dir.glob("*/summary.parquet"))):
        if (job_dir / "summary.parquet").exists():
            try:
                row = read_verified(job_dir / "summary.parquet").replace_schema_metadata(None)
            except READ_ERRORS as exc:  # a corrupt file: pyarrow's errors
                raise ConfigError(f"{job_dir / 'summary.parquet'}: {one_line(exc)}; rerun the sweep") from None
            rows.append(row.add_column(0, "job", texts([job_dir.name])))
    if not rows:
        return
    table = pa.concat_tables(rows, promote_options="permissive")
    varying = varying_settings(table.to_pydict(), ignore=("job",))
    if varying:
        table = sorted_by(table, varying)
    sweep_yaml = OmegaConf.to_yaml({"overrides": list(overrides), "jobs": table.num_rows})
    write_parquet(table, sweep_dir / "summary.parquet", sweep_yaml)
    shown = [c for c in varying if c not in ("actuator_name",)] + REPORTED
    log.info("sweep summary (%s):\n%s", sweep_dir / "summary.parquet",
             text_table(table.select([name for name in shown if name in table.column_names]).to_pydict()))
    log.info("results in %s (%d job folders)", sweep_dir, table.num_rows)


class SweepSummary(Callback):
    """:func:`gather` at the end of a sweep Hydra runs (its launchers: the jobs may run
    elsewhere: without a job that ended in this process, every job folder of the sweep
    directory is read)."""

    def __init__(self) -> None:
        self.job_dirs: list[Path] = []

    def on_job_end(self, config: DictConfig, **kwargs) -> None:
        self.job_dirs.append(Path(config.hydra.runtime.output_dir))

    def on_multirun_end(self, config: DictConfig, **kwargs) -> None:
        gather(Path(config.hydra.sweep.dir), self.job_dirs, list(config.hydra.overrides.task))


def text_table(columns: dict[str, list]) -> str:
    """Columns (name -> values) as right-aligned text, floats with six decimals (in exponent
    form when a column spans beyond 1e6 or below 1e-4)."""
    texts = []
    for name, values in columns.items():
        finite = [abs(v) for v in values if isinstance(v, float) and math.isfinite(v) and v != 0]
        wide = any(v >= 1e6 or v < 1e-4 for v in finite)
        cells = [name] + [(f"{v:.6e}" if wide else f"{v:.6f}") if isinstance(v, float) else str(v)
                          for v in values]
        width = max(map(len, cells))
        texts.append([cell.rjust(width) for cell in cells])
    return "\n".join("  ".join(line) for line in zip(*texts))

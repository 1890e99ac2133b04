"""Read access to one study's outputs (what the analyses, the figures, the report and the API
read): its summary, analysis tables and each job's points and samples, each checked against the
digest written with it before it is used (``pipeline.app.results``: a table's rows, a job's data
files); a file changed since it was written raises ValueError naming it."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from omegaconf import DictConfig, OmegaConf

from pipeline.app.job import changed_files
from pipeline.app.results import CONFIG_KEY, READ_ERRORS, read_metadata, read_verified


class StudyResults:
    """One study's folder: ``summary.parquet``, ``<analysis>.parquet``, ``jobs/<job>/*.parquet``."""

    def __init__(self, directory: Path):
        self.directory = Path(directory)

    @property
    def summary(self) -> pd.DataFrame:
        return table(self.directory / "summary.parquet")

    def table(self, name: str) -> pd.DataFrame:
        return table(self.directory / f"{name}.parquet")

    def points(self, job: str) -> pd.DataFrame:
        return self._data(job, "points.parquet")

    def samples(self, job: str) -> pd.DataFrame:
        return self._data(job, "samples.parquet")

    def boxes(self, job: str) -> pd.DataFrame:
        return self._data(job, "boxes.parquet")

    def config(self, job: str) -> DictConfig:
        """The resolved config ``job`` ran with, as its summary records it."""
        return OmegaConf.create(read_metadata(self.folder(job) / "summary.parquet")[CONFIG_KEY])

    def folder(self, job: str) -> Path:
        return self.directory / "jobs" / job

    def job_summary(self, job: str) -> pd.DataFrame:
        """One job's own summary row (its settings, box and counts), with ``job``."""
        return table(self.folder(job) / "summary.parquet").assign(job=job)

    def _data(self, job: str, name: str) -> pd.DataFrame:
        folder = self.folder(job)
        try:
            changed = changed_files(folder)
        except READ_ERRORS as exc:  # its summary unreadable: outside data
            raise ValueError(f"{folder}: unreadable summary.parquet ({exc})") from None
        if changed:
            raise ValueError(f"{folder}: {', '.join(changed)} changed since the job finished")
        return pd.read_parquet(folder / name)


class JobResults(StudyResults):
    """One job's folder read as a study of that one job (``job``: its folder's name), so that the
    API draws a job with the studies' figure code (``pipeline.api.Workspace.figure``)."""

    @property
    def summary(self) -> pd.DataFrame:
        return table(self.directory / "summary.parquet").assign(job=self.directory.name)

    def folder(self, job: str) -> Path:
        return self.directory


def table(path: Path) -> pd.DataFrame:
    """A table written whole (a summary, a study's analysis), as pandas, its rows verified;
    ValueError naming the file otherwise."""
    try:
        return read_verified(path).to_pandas()
    except FileNotFoundError:
        raise
    except READ_ERRORS as exc:  # a corrupt file: pyarrow's errors
        raise ValueError(f"{path}: {exc}") from None

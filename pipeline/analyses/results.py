"""Read access to one study's outputs (what the analyses, the figures, the report and the API
read): its summary, analysis tables and each job's points and samples."""

from __future__ import annotations

from pathlib import Path

import pandas as pd


class StudyResults:
    """One study's folder: ``summary.parquet``, ``<analysis>.parquet``, ``jobs/<job>/*.parquet``."""

    def __init__(self, directory: Path):
        self.directory = Path(directory)

    @property
    def summary(self) -> pd.DataFrame:
        return pd.read_parquet(self.directory / "summary.parquet")

    def table(self, name: str) -> pd.DataFrame:
        return pd.read_parquet(self.directory / f"{name}.parquet")

    def points(self, job: str) -> pd.DataFrame:
        return pd.read_parquet(self.directory / "jobs" / job / "points.parquet")

    def samples(self, job: str) -> pd.DataFrame:
        return pd.read_parquet(self.directory / "jobs" / job / "samples.parquet")

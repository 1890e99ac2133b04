"""Parquet output: atomic writes, with the resolved config and the code version in the schema."""

from __future__ import annotations

import os
import subprocess
from functools import lru_cache
from importlib import metadata
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

CONFIG_KEY = "cdpr.config"
VERSION_KEY = "cdpr.version"


@lru_cache(maxsize=1)
def code_version() -> str:
    """Package version, plus the git commit (and '.dirty') when run from a checkout."""
    try:
        version = metadata.version("cdpr-studies")
    except metadata.PackageNotFoundError:
        version = "0+unknown"
    here = Path(__file__).resolve().parent
    try:
        sha = subprocess.run(
            ["git", "rev-parse", "--short=12", "HEAD"], cwd=here, capture_output=True,
            text=True, check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", "pipeline", "conf"],
            cwd=here.parent, capture_output=True, text=True, check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return version
    return f"{version}+g{sha}{'.dirty' if dirty else ''}"


def write_parquet(frame: pd.DataFrame, path: Path, config_yaml: str) -> None:
    """Write ``frame`` to ``path`` via a temporary file and a rename: no half-written file ever
    carries the final name."""
    table = pa.Table.from_pandas(frame, preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[CONFIG_KEY.encode()] = config_yaml.encode()
    meta[VERSION_KEY.encode()] = code_version().encode()
    table = table.replace_schema_metadata(meta)
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, path)


def read_metadata(path: Path) -> dict[str, str]:
    """The cdpr.* schema metadata of a Parquet file written by :func:`write_parquet`."""
    meta = pq.read_schema(path).metadata or {}
    return {k.decode(): v.decode() for k, v in meta.items() if k.startswith(b"cdpr.")}

"""Parquet output: atomic writes, with the resolved config and the code version in the schema.

pyarrow only: a job's own files (points, summary) are Arrow tables, so a job process never
imports pandas; a pandas DataFrame (the studies' tables) is written as well."""

from __future__ import annotations

import hashlib
import json
import os
import secrets
from contextlib import contextmanager
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING

import pyarrow as pa
import pyarrow.parquet as pq

if TYPE_CHECKING:
    import pandas as pd

CONFIG_KEY = "cdpr.config"
VERSION_KEY = "cdpr.version"
DIGESTS_KEY = "cdpr.digests"  # in a job's summary: sha256 of every data file the job wrote
CONTENT_KEY = "cdpr.content"  # in a table written whole: sha256 of its rows (content_digest)


@lru_cache(maxsize=1)
def code_version() -> str:
    """Package version plus the first 12 hex digits of a sha256 over the package's own files
    (code, configs, studies, Table 1, the plot style; their paths and contents), so the version
    names what computes, whatever the git history: committing results, tests or docs leaves
    finished jobs reusable and their files byte-identical, and any edit of the code, a checkout or
    an install, makes them stale."""
    try:
        version = metadata.version("cdpr-studies")
    except metadata.PackageNotFoundError:
        version = "0+unknown"
    package = Path(__file__).resolve().parents[1]  # pipeline/, above app/
    digest = hashlib.sha256()
    files = []
    for folder, subfolders, names in os.walk(package, followlinks=True):  # conf/ and studies/ are links in a checkout
        subfolders[:] = sorted(s for s in subfolders if s != "__pycache__")  # bytecode, numba's cache
        files += [Path(folder, name) for name in names]
    for path in sorted(files, key=lambda p: p.relative_to(package).as_posix()):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return f"{version}+{digest.hexdigest()[:12]}"


def write_parquet(frame: pa.Table | pd.DataFrame, path: Path, config_yaml: str,
                  extra: dict | None = None) -> None:
    """Write ``frame`` (an Arrow table or a pandas DataFrame) to ``path`` via a temporary file
    and a rename: no half-written file ever carries the final name. ``extra``: more ``cdpr.*``
    schema metadata (str values). The digest of its rows goes with it (``cdpr.content``), which
    :func:`read_verified` checks: a value changed in the file is found before it is used."""
    table = _arrow(frame)
    with ParquetSink(path, config_yaml, {**(extra or {}), CONTENT_KEY: content_digest(table)}) as sink:
        sink.write(table)


def content_digest(table: pa.Table) -> str:
    """sha256 of a table's columns: names and types (its schema without metadata) and values
    as Python reads them (floats by their exact repr, nulls as None), the same for the table
    written and the table read back; for the tables written whole (summaries, study tables),
    not the streamed points (whose file digest the summary records)."""
    text = repr((table.schema.remove_metadata().to_string(), table.to_pydict()))
    return hashlib.sha256(text.encode()).hexdigest()


# What reading a file from outside (an output folder, a user's results) may raise: pyarrow's
# errors on a corrupt file are OSError and ValueError, and also NotImplementedError ("Integers
# with less than 8 bits", a flipped bit in a type), TypeError, KeyError and IndexError.
READ_ERRORS = (OSError, ValueError, LookupError, TypeError, NotImplementedError, pa.ArrowException)


def read_verified(path: Path) -> pa.Table:
    """A table written by :func:`write_parquet`, whose rows still have the digest it recorded;
    else ValueError naming what is wrong (pyarrow's read errors are OSError or ValueError)."""
    with pq.ParquetFile(path) as handle:  # no pandas import
        table = handle.read()
    recorded = (table.schema.metadata or {}).get(CONTENT_KEY.encode())
    if recorded is None:
        raise ValueError("no record of its content (not written whole by this version)")
    if content_digest(table) != recorded.decode():
        raise ValueError("its rows changed since it was written")
    return table


def _arrow(frame: pa.Table | pd.DataFrame) -> pa.Table:
    return frame if isinstance(frame, pa.Table) else pa.Table.from_pandas(frame, preserve_index=False)


ZSTD_ROWS = 1000  # zstd for tables that stream chunks of at least this many rows (points), snappy
# for the small ones (a summary's one row, where zstd costs more than it gains)


class ParquetSink:
    """Write a table chunk by chunk (one row group per :meth:`write`) to a temporary file,
    renamed to ``path`` only when the ``with`` block ends without an error. The temporary name
    is unique to this writer (process id and a random part), so two writers never share one."""

    def __init__(self, path: Path, config_yaml: str, extra: dict | None = None):
        self.path = Path(path)
        self.tmp = _temporary(self.path)
        self.config_yaml = config_yaml
        self.extra = extra or {}
        self.writer: pq.ParquetWriter | None = None

    def write(self, frame: pa.Table | pd.DataFrame) -> None:
        table = _arrow(frame)
        if self.writer is None:
            meta = dict(table.schema.metadata or {})
            meta[CONFIG_KEY.encode()] = self.config_yaml.encode()
            meta[VERSION_KEY.encode()] = code_version().encode()
            meta.update({key.encode(): value.encode() for key, value in self.extra.items()})
            floats = {f.name for f in table.schema if pa.types.is_floating(f.type)}
            self.writer = pq.ParquetWriter(  # dictionaries only where values repeat: half the
                self.tmp, table.schema.with_metadata(meta),  # time and size of a points table
                compression="zstd" if table.num_rows >= ZSTD_ROWS else "snappy",
                use_dictionary=[name for name in table.column_names if name not in floats])
        self.writer.write_table(table.replace_schema_metadata(self.writer.schema.metadata))

    def __enter__(self) -> "ParquetSink":
        return self

    def __exit__(self, kind, value, traceback) -> None:
        try:
            if self.writer is not None:
                self.writer.close()
            if kind is None and self.writer is not None:
                os.replace(self.tmp, self.path)
        finally:
            self.tmp.unlink(missing_ok=True)


def _temporary(path: Path) -> Path:
    """A temporary name beside ``path`` unique to this writer (process id and a random part)."""
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")


@contextmanager
def replacing(path: Path):
    """Yield a temporary path to write; it becomes ``path`` when the block ends without an error
    and is removed otherwise, so no half-written file ever carries the final name."""
    tmp = _temporary(Path(path))
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_text(path: Path, text: str) -> None:
    """A small text file (YAML records), written via :func:`replacing`."""
    with replacing(path) as tmp:
        tmp.write_text(text)


def write_csv(frame: pd.DataFrame, path: Path) -> None:
    """A table as CSV for a spreadsheet (beside its Parquet file), written via :func:`replacing`."""
    with replacing(path) as tmp:
        frame.to_csv(tmp, index=False)


def read_metadata(path: Path) -> dict[str, str]:
    """The cdpr.* schema metadata of a Parquet file written by :func:`write_parquet`."""
    meta = pq.read_schema(path).metadata or {}
    return {k.decode(): v.decode() for k, v in meta.items() if k.startswith(b"cdpr.")}


def file_digest(path: Path) -> str:
    """sha256 of a file's bytes (hex)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def digests_json(paths: list[Path]) -> str:
    """The ``cdpr.digests`` metadata of a job's summary: file name -> sha256."""
    return json.dumps({p.name: file_digest(p) for p in paths}, sort_keys=True)


# A job summary's result columns (summarize, and simulate_lines' additions); the rest is config
RESULT_COLUMNS = {"analysis", "actuator_name", "actuator_power_W", "n_orientations", "n_points",
                  "n_feasible", "feasible_pct", "volume_m3", "n_lines", "n_samples",
                  "n_feasible_grid", "agreement_pct", "mesh_volume_m3", "mesh_surface_m2", "volume_spread_m3", "n_connected",
                  "connected_pct", "connected_volume_m3"}
RESULT_PREFIXES = ("box.", "lost_", "alone_", "least_margin_", "limit_", "line0_margin_", "home_")


def varying_settings(columns: dict[str, list], ignore=()) -> list[str]:
    """The config columns of a table of job summaries (``columns``: name -> the jobs' values,
    in column order) whose value differs between the jobs (what their sweep varied), except
    ``ignore``. Values are compared as text (a list setting is a string in the summary)."""
    return [c for c, values in columns.items()
            if c not in RESULT_COLUMNS and c not in ignore and not c.startswith(RESULT_PREFIXES)
            and len({str(v) for v in values}) > 1]

"""Arrow columns built from their buffers, without pandas.

pyarrow's own constructors (``pa.array``, ``pa.scalar``, ``pa.Table.from_pylist``) and
``pq.read_table`` import pandas, when it is installed, to check whether their input is a pandas
object, in a job process that holds none (``docs/performance.md``, "What a process imports"). A
job's tables are therefore built here with ``pa.Array.from_buffers``, which checks nothing
(numbers without a copy), and read back with ``pq.ParquetFile``
(``pipeline.app.results.read_verified``). The columns have the types ``pa.Table.from_pandas``
gives the same values, and a table read back with pandas is the same DataFrame
(``tests/test_results.py``).
"""

from __future__ import annotations


import numpy as np
import pyarrow as pa


def numbers(values: np.ndarray) -> pa.Array:
    """A numeric or boolean numpy array as an Arrow array (numbers share its memory)."""
    values = np.ascontiguousarray(values)
    if values.dtype == np.bool_:
        return pa.Array.from_buffers(pa.bool_(), len(values), [None, _bits(values)])
    return pa.Array.from_buffers(pa.from_numpy_dtype(values.dtype), len(values),
                                 [None, pa.py_buffer(values)])


def values(column: pa.ChunkedArray | pa.Array) -> np.ndarray:
    """A numeric or boolean column without nulls as a numpy array, read from its buffers (the
    reverse of :func:`numbers`; pyarrow's ``to_numpy`` imports pandas)."""
    parts = []
    for chunk in column.chunks if isinstance(column, pa.ChunkedArray) else [column]:
        data = chunk.buffers()[1]
        if pa.types.is_boolean(chunk.type):
            bits = np.unpackbits(np.frombuffer(data, dtype=np.uint8), bitorder="little")
            parts.append(bits[chunk.offset:chunk.offset + len(chunk)].astype(bool))
        else:
            stored = np.frombuffer(data, dtype=chunk.type.to_pandas_dtype())
            parts.append(stored[chunk.offset:chunk.offset + len(chunk)])
    return np.concatenate(parts) if parts else np.zeros(0)


def texts(values: list[str | None]) -> pa.Array:
    """Strings as an Arrow string array; None is null."""
    encoded = [b"" if value is None else value.encode() for value in values]
    offsets = np.zeros(len(values) + 1, dtype=np.int32)
    np.cumsum([len(text) for text in encoded], out=offsets[1:])
    valid = np.array([value is not None for value in values], dtype=bool)
    validity = None if valid.all() else _bits(valid)
    return pa.Array.from_buffers(pa.string(), len(values),
                                 [validity, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))],
                                 null_count=int(np.count_nonzero(~valid)))


def _bits(flags: np.ndarray) -> pa.Buffer:
    """Booleans packed as Arrow packs them (values and validity): one bit each, least first."""
    return pa.py_buffer(np.packbits(flags, bitorder="little"))


def categories(codes: np.ndarray, names: list[str]) -> pa.DictionaryArray:
    """A dictionary column (pandas reads it as a Categorical): ``codes`` index ``names``."""
    return pa.DictionaryArray.from_arrays(numbers(codes), texts(names))


def one_row(row: dict) -> pa.Table:
    """A table of one row: bool, int, float, str and None values become bool, int64, float64,
    string and null columns (numpy scalars as their Python kind)."""
    columns = {}
    for name, value in row.items():
        if value is None:
            columns[name] = pa.nulls(1)
        elif isinstance(value, str):
            columns[name] = texts([value])
        elif isinstance(value, (bool, np.bool_)):
            columns[name] = numbers(np.array([value], dtype=bool))
        elif isinstance(value, (int, np.integer)):
            columns[name] = numbers(np.array([value], dtype=np.int64))
        elif isinstance(value, (float, np.floating)):
            columns[name] = numbers(np.array([value], dtype=np.float64))
        else:
            raise TypeError(f"{name}: {type(value).__name__} is not a summary value")
    return pa.table(columns)


def sorted_by(table: pa.Table, names: list[str]) -> pa.Table:
    """``table`` (a sweep's summary: a row a job) sorted stably by the columns ``names``
    (ascending, nulls and NaN last, as pandas' ``sort_values``), the same schema; pyarrow's
    ``sort_by`` would import pandas, its ``take`` pyarrow.compute (25 ms of the main job) and
    ``pa.array`` pandas again: the rows are sliced (no copy) and put together in order."""
    columns = [table[name].to_pylist() for name in names]

    def key(i: int) -> tuple:
        return tuple((missing, 0 if missing else value) for value in (column[i] for column in columns)
                     for missing in [value is None or value != value])

    order = sorted(range(table.num_rows), key=key)
    return pa.concat_tables([table.slice(i, 1) for i in order]).combine_chunks() if order else table

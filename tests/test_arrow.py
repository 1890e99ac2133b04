"""Arrow columns built from buffers (pipeline.workspace.arrow) against pyarrow's pandas route, and
a job process that never imports pandas."""

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from conftest import job_imports
from pipeline.app.results import read_verified, write_parquet
from pipeline.workspace.arrow import categories, numbers, one_row, sorted_by, texts, values


def _round_trip(table: pa.Table, path) -> pd.DataFrame:
    pq.write_table(table, path)
    return pd.read_parquet(path)


@pytest.mark.parametrize("dtype", [np.float64, np.int64, np.int8, np.int32, bool])
@pytest.mark.parametrize("n", [0, 1, 7, 9, 1000])
def test_numbers_equal_pyarrow_s_own_conversion(tmp_path, dtype, n):
    rng = np.random.default_rng(n)
    values = (rng.random(n) > 0.5 if dtype is bool else (rng.normal(size=n) * 100).astype(dtype))
    if dtype is np.float64 and n:
        values[::3] = np.nan  # NaN is a value, not null, in both
    theirs = pa.array(values)
    strided = np.column_stack([values, values])[:, 1]  # a column of a 2-D array
    for ours in (numbers(values), numbers(strided)):
        assert ours.type == theirs.type and ours.null_count == theirs.null_count == 0
        np.testing.assert_array_equal(ours.to_numpy(zero_copy_only=False),
                                      theirs.to_numpy(zero_copy_only=False))  # NaN equal to NaN


def test_texts_and_categories_equal_the_pandas_route(tmp_path):
    words = ["speed", None, "", "couple µ", "torque", None]
    assert texts(words).equals(pa.array(words, pa.string()))
    assert texts([]).equals(pa.array([], pa.string()))
    codes = np.array([0, 2, 1, 1, 0], dtype=np.int8)
    names = ["speed", "torque", "voltage"]
    frame = pd.DataFrame({"limiting": pd.Categorical.from_codes(codes, categories=names)})
    ours = _round_trip(pa.table({"limiting": categories(codes, names)}), tmp_path / "a.parquet")
    theirs = _round_trip(pa.Table.from_pandas(frame, preserve_index=False), tmp_path / "b.parquet")
    pd.testing.assert_frame_equal(ours, theirs)
    pd.testing.assert_frame_equal(ours, frame)


def test_a_summary_row_reads_back_as_pandas_wrote_it(tmp_path):
    row = {"analysis": "cpr_wwa", "n_points": 216, "feasible": True, "pct": 85.185185,
           "nan": float("nan"), "none": None, "np_float": np.float64(1.5), "np_int": np.int64(-3),
           "np_bool": np.bool_(False), "com": "[0, 0, 0]", "big": 2**62}
    ours = one_row(row)
    theirs = pa.Table.from_pandas(pd.DataFrame([row]), preserve_index=False)
    assert [f.name for f in ours.schema] == [f.name for f in theirs.schema]
    pd.testing.assert_frame_equal(_round_trip(ours, tmp_path / "a.parquet"),
                                  _round_trip(theirs, tmp_path / "b.parquet"))
    write_parquet(ours, tmp_path / "c.parquet", "config")
    back = read_verified(tmp_path / "c.parquet").to_pylist()[0]
    assert back["n_points"] == 216 and back["none"] is None and np.isnan(back["nan"])
    with pytest.raises(TypeError, match="x: list is not a summary value"):
        one_row({"x": [1, 2]})


def test_sorted_by_is_pandas_stable_sort_with_missing_values_last():
    rng = np.random.default_rng(3)
    n = 200
    a = rng.integers(0, 4, n).astype(float)
    a[rng.random(n) < 0.1] = np.nan
    b = [None if r < 0.1 else f"v{k}" for r, k in zip(rng.random(n), rng.integers(0, 3, n))]
    table = pa.table({"job": texts([f"{i:03d}" for i in range(n)]), "a": numbers(a), "b": texts(b),
                      "flag": numbers(rng.random(n) < 0.5), "count": numbers(rng.integers(-5, 5, n)),
                      "unset": pa.nulls(n)}).replace_schema_metadata({"note": "kept"})
    for keys in (["a"], ["b"], ["a", "b"], ["b", "a"]):
        expected = table.to_pandas().sort_values(keys, kind="stable", na_position="last")
        ours = sorted_by(table, keys)
        assert ours["job"].to_pylist() == expected["job"].tolist(), keys
        assert parquet_bytes(ours) == parquet_bytes(table.take(expected.index.to_numpy()))  # every column, its type


def parquet_bytes(table: pa.Table) -> bytes:
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


def test_the_main_job_and_a_grid_job_never_import_pandas(tmp_path):
    """pandas costs 0.25 s of CPU to import: a job that writes points and summaries, a sweep
    with its summary table, and a rerun that reuses the finished job do without it."""
    sweep = ["-m", "actuator=1,2,3", "grid.n=4", "hydra.sweep.dir=sweep"]
    first = job_imports(tmp_path, *sweep, modules=("pandas", "pyarrow.compute"))
    assert "pandas imported: False" in first and "pyarrow.compute imported: False" in first
    again = job_imports(tmp_path, *sweep)  # each job's summary read back, not recomputed
    assert "reused the finished job" in again and "pandas imported: False" in again
    irpm = ["robot=irpm6", "robot.search.step=1", "hydra.run.dir=irpm"]
    assert "pandas imported: False" in job_imports(tmp_path, *irpm)
    table = pd.read_parquet(tmp_path / "sweep" / "summary.parquet")
    assert table["actuator"].tolist() == [1, 2, 3] and table["job"].is_unique


def test_values_reads_back_what_numbers_wrote_also_from_slices_and_several_chunks():
    flags, floats = np.arange(37) % 3 == 0, np.linspace(-1, 1, 37)
    for start, stop in ((0, 37), (3, 20), (9, 10), (17, 17)):
        np.testing.assert_array_equal(values(numbers(flags).slice(start, stop - start)), flags[start:stop])
        np.testing.assert_array_equal(values(numbers(floats).slice(start, stop - start)), floats[start:stop])
    several = pa.chunked_array([numbers(flags[:10]), numbers(flags[10:])]).slice(5, 20)
    np.testing.assert_array_equal(values(several), flags[5:25])
    assert values(pa.array(np.array([1, -2], dtype=np.int8))).dtype == np.int8

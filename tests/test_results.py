"""Parquet output: streamed by chunks equals the in-memory table; nothing half-written."""

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from pipeline.app.results import ParquetSink, read_metadata, write_parquet
from conftest import compute_workspace


def test_points_streamed_chunk_by_chunk_equal_the_in_memory_table(tmp_path, make_cfg, catalogue):
    cfg = make_cfg("grid.n=12", "compute.chunk_size=300", "actuator=4")
    table, summary = compute_workspace(cfg, catalogue)
    with ParquetSink(tmp_path / "points.parquet", "config: x\n") as sink:
        nothing, streamed_summary = compute_workspace(cfg, catalogue, sink.write)
    assert nothing is None and streamed_summary == summary
    assert pq.ParquetFile(tmp_path / "points.parquet").metadata.num_row_groups == 6
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "points.parquet"), table)
    assert read_metadata(tmp_path / "points.parquet")["cdpr.config"] == "config: x\n"
    assert summary["n_feasible"] == table["feasible"].sum() == 1332
    for name in ("speed", "torque", "acceleration", "voltage"):  # headroom, reduced over the chunks
        assert summary[f"least_margin_{name}"] == table.loc[table["feasible"], f"margin_{name}"].min()
    assert summary["least_margin_speed"] == pytest.approx(0.0929, abs=1e-4)  # actuator 4, 12^3 poses
    _, none = compute_workspace(make_cfg("grid.n=4", "actuator=5"), catalogue)
    assert none["n_feasible"] == 0 and np.isnan(none["least_margin_torque"])


def test_a_failed_write_leaves_no_file_under_either_name(tmp_path):
    frame = pd.DataFrame({"a": [1.0, 2.0]})
    with pytest.raises(RuntimeError):
        with ParquetSink(tmp_path / "x.parquet", "c") as sink:
            sink.write(frame)
            raise RuntimeError("killed mid-way")
    assert list(tmp_path.iterdir()) == []
    write_parquet(frame, tmp_path / "x.parquet", "c")
    assert [p.name for p in tmp_path.iterdir()] == ["x.parquet"]

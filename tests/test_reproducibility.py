"""Reruns are byte-identical, and a sweep killed mid-way resumes with only the missing jobs."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest

from conftest import command

pytestmark = pytest.mark.slow


def study(cwd, *args):
    """``python -m pipeline.study ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, "pipeline.study", *args)


def files(root: Path) -> dict[str, bytes]:
    """Every Parquet and PNG file under root, by relative path (logs and Hydra's own YAML,
    which carry timestamps, are not results)."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.suffix in (".parquet", ".png", ".json", ".csv")}


def test_rerun_gives_byte_identical_parquet_and_figures(tmp_path):
    for out in ("a", "b"):
        proc = study(tmp_path, "actuator_choice", "--out", out)
        assert proc.returncode == 0, proc.stderr
    first, second = files(tmp_path / "a"), files(tmp_path / "b")
    # jobs, sweep summary, study summary + choice (+ CSV), 9 figures, 5 views, 2 slices' series, metrics.json,
    # the figures' record (figures.json)
    assert len(first) == 5 * 2 + 1 + 2 + 1 + 9 + 5 + 2 + 1 + 1
    assert first == second


def test_killed_sweep_resumes_with_only_the_missing_jobs(tmp_path):
    reference = study(tmp_path, "design_mass", "--out", "reference")
    assert reference.returncode == 0, reference.stderr

    argv = [sys.executable, "-m", "pipeline.study", "design_mass", "--out", "killed"]  # a process, to kill
    proc = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    jobs = tmp_path / "killed" / "design_mass" / "jobs"
    deadline = time.monotonic() + 120
    while len(list(jobs.glob("*/summary.parquet"))) < 8 and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)  # the runner, the sweep and its joblib workers
    proc.wait()
    finished = {p.parent.name for p in jobs.glob("*/summary.parquet")}
    assert 8 <= len(finished) < 40
    for path in jobs.rglob("*.parquet"):  # nothing half-written under a final name
        pq.read_metadata(path)

    resumed = study(tmp_path, "design_mass", "--out", "killed")
    assert resumed.returncode == 0, resumed.stderr
    logs = "".join(p.read_text() for p in jobs.glob("*/pipeline.log"))
    assert logs.count("reused the finished job") == len(finished)
    assert files(tmp_path / "killed") == files(tmp_path / "reference")
    summary = pd.read_parquet(tmp_path / "killed" / "design_mass" / "summary.parquet")
    assert len(summary) == 40

"""Output problems (issue 16, item 7): one line naming the path, exit 2, nothing written and no
temporary file left, whether found before the job (the plan) or while it writes."""

import subprocess

import pytest

from conftest import command

pytestmark = pytest.mark.slow


def run(cwd, *args):
    """``python -m pipeline ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, "pipeline", *args)


def one_line_exit_2(proc, needle):
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and needle in lines[0], proc.stderr


@pytest.fixture
def tiny_disk(tmp_path):
    """A tmpfs of the given size mounted in tmp_path (needs root; skipped where it cannot)."""
    mounted = []

    def mount(size: str):
        folder = tmp_path / f"disk{len(mounted)}"
        folder.mkdir()
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                              capture_output=True)
        if done.returncode != 0:
            pytest.skip("cannot mount a tmpfs here")
        mounted.append(folder)
        return folder
    yield mount
    for folder in mounted:
        subprocess.run(["umount", str(folder)], check=False)


@pytest.mark.parametrize("where, needle", [
    ("afile/run", "afile is a file, not a folder"),
    ("d" * 300, "a folder name of 300 bytes (at most 255)"),
])
def test_a_run_folder_that_cannot_exist_is_named_before_anything_is_written(tmp_path, where, needle):
    (tmp_path / "afile").write_text("")
    one_line_exit_2(run(tmp_path, f"hydra.run.dir={where}"), needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_a_sweep_whose_job_folder_names_are_too_long_is_refused(tmp_path):
    poses = ",".join(["[0.1,0.2,-1]"] * 40)
    one_line_exit_2(run(tmp_path, "-m", f"poses=[{poses}],[[1,1,-1]]"), "(at most 255)")
    assert not list(tmp_path.iterdir())


def test_a_full_disk_is_refused_before_the_job(tiny_disk, tmp_path):
    disk = tiny_disk("64k")
    one_line_exit_2(run(tmp_path, f"hydra.run.dir={disk}/run"), "MiB free on its disk")
    assert not list(disk.iterdir())


def test_a_disk_that_fills_while_writing_stops_the_job_and_leaves_no_temporary_file(tiny_disk, tmp_path):
    disk = tiny_disk("2m")  # passes the estimate (a 216-pose grid); every line's samples (5 MB) fill it
    proc = run(tmp_path, f"hydra.run.dir={disk}/run", "analysis=lines", "lines.samples=all",
               "compute.n_jobs=1")
    one_line_exit_2(proc, "No space left on device")
    left = {p.name for p in (disk / "run").iterdir()}
    assert not {"samples.parquet", "points.parquet", "summary.parquet"} & left
    assert not [name for name in left if name.endswith(".tmp")]


def test_outputs_inside_the_config_folder_are_named_as_the_cause(tmp_path):
    """``--config-dir .`` with the outputs below it: the second run met the first job's Hydra
    record and said only that a file sets Hydra's settings; it names the job folder and the fix."""
    import shutil
    from pathlib import Path

    robot = Path(__file__).resolve().parents[1] / "examples" / "my_robot" / "robot"
    shutil.copytree(robot, tmp_path / "robot")
    first = command(tmp_path, "pipeline", "--config-dir", ".", "robot=myrobot", "hydra.run.dir=out1")
    assert first.returncode == 0, first.stderr[-2000:]
    second = command(tmp_path, "pipeline", "--config-dir", ".", "robot=myrobot", "hydra.run.dir=out2")
    lines = second.stderr.strip().splitlines()
    assert second.returncode == 2 and len(lines) == 1, lines
    assert "out1/ is a job's output folder, inside your config folder" in lines[0]
    assert "write outputs elsewhere (hydra.run.dir=" in lines[0] and not (tmp_path / "out2").exists()

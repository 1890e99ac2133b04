"""The command line as a user types it: `python -m pipeline ...` in a fresh working directory."""

import subprocess
import sys

import pandas as pd
import pytest

from conftest import command, job_at_exit
from golden import values
from pipeline.app.results import read_metadata

pytestmark = pytest.mark.slow


def run(cwd, *args):
    """``python -m pipeline ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, "pipeline", *args)


def test_main_job_writes_points_summaries_and_sweep_summary(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "pipeline", "-m", "actuator=1,2,3,4,5"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)  # the main job, a process of its own
    assert proc.returncode == 0, proc.stderr
    (sweep,) = (tmp_path / "outputs" / "sweeps").iterdir()
    summary = pd.read_parquet(sweep / "summary.parquet")
    assert summary["actuator"].tolist() == [1, 2, 3, 4, 5]
    assert summary["n_feasible"].tolist() == values("full_default_zero")
    for actuator in range(1, 6):
        job = sweep / f"actuator={actuator}"
        points = pd.read_parquet(job / "points.parquet")
        assert len(points) == 216
        assert {"x", "y", "z", "psi", "theta", "phi", "feasible", "limiting", "margin_speed",
                "margin_torque", "margin_acceleration", "margin_voltage"} <= set(points.columns)
        assert not points.isna().any().any()
        meta = read_metadata(job / "points.parquet")
        assert f"actuator: {actuator}" in meta["cdpr.config"]
        assert meta["cdpr.version"].startswith("0.1.0")
        assert read_metadata(job / "summary.parquet")["cdpr.config"] == meta["cdpr.config"]
    assert "feasible = 85.19%" in (sweep / "actuator=3" / "pipeline.log").read_text()


def test_single_run_with_parallel_chunks(tmp_path):
    proc = run(tmp_path, "grid.n=12", "compute.chunk_size=500", "actuator=4")
    assert proc.returncode == 0, proc.stderr
    (job,) = (tmp_path / "outputs" / "runs").iterdir()
    assert len(pd.read_parquet(job / "points.parquet")) == 12**3
    log = (job / "pipeline.log").read_text()
    assert "chunks 4/4 (100%), 0:0" in log  # the last chunk is always reported
    assert "actuator 4" in log


def test_irpm_gamma_sweep_summary_decreases_with_gamma(tmp_path):
    proc = run(tmp_path, "-m", "robot=irpm6", "robot.gamma_deg=0,15,30,45")
    assert proc.returncode == 0, proc.stderr
    (sweep,) = (tmp_path / "outputs" / "sweeps").iterdir()
    summary = pd.read_parquet(sweep / "summary.parquet")
    assert summary["robot.gamma_deg"].tolist() == [0, 15, 30, 45]
    assert summary["n_feasible"].tolist() == values("irpm_gamma")
    assert summary["volume_m3"].to_numpy() == pytest.approx(summary["n_feasible"] * 0.4**3)
    points = pd.read_parquet(sweep / "robot.gamma_deg=30,robot=irpm6" / "points.parquet")
    assert len(points) == values("irpm_gamma", "n_points")[2] and not points.isna().any().any()


def test_line_simulation_job_writes_samples(tmp_path):
    proc = run(tmp_path, "analysis=lines", "actuator=2")
    assert proc.returncode == 0, proc.stderr
    (job,) = (tmp_path / "outputs" / "runs").iterdir()
    samples = pd.read_parquet(job / "samples.parquet")
    assert {"line", "t", "x", "y", "z", "theta_dot_8", "torque_1", "voltage_5", "margin_torque",
            "ok"} <= set(samples.columns)
    summary = pd.read_parquet(job / "summary.parquet").iloc[0]
    assert [summary["n_feasible"], summary["n_feasible_grid"]] == [values("lines_full_zero", key)[1]
                                                                   for key in ("n_feasible", "n_feasible_grid")]
    assert f"agreement {values('lines_full_zero', 'agreement_pct')[1]:.1f}%" in (job / "pipeline.log").read_text()
    assert samples["line"].unique().tolist() == [0]  # lines.samples=first: line O''-F'' (Fig. 6)
    assert summary["n_lines"] == 72 and summary["lines.samples"] == "first"
    every = run(tmp_path, "analysis=lines", "actuator=2", "lines.samples=all", "hydra.run.dir=all")
    assert every.returncode == 0, every.stderr
    all_samples = pd.read_parquet(tmp_path / "all" / "samples.parquet")
    assert all_samples["line"].nunique() == 72 and len(all_samples) == summary["n_samples"]
    pd.testing.assert_frame_equal(all_samples[all_samples["line"] == 0].reset_index(drop=True), samples)
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "all" / "points.parquet"),
                                  pd.read_parquet(job / "points.parquet"))  # the same verdicts


@pytest.mark.parametrize(
    "args, key",
    [
        (("actuator=9",), "actuator=9"),
        (("-m", "actuator=1,2,9"), "actuator=9"),
        (("load.mass=inf",), "load.mass=inf"),
        (("load.mass=-2",), "load.mass=-2"),
        (("drive.winch_radius=-0.1",), "drive.winch_radius=-0.1"),
        (("grid.n=0",), "grid.n=0"),
        (("grid.n_vel=0",), "grid.n_vel=0"),
        (("motion.v_max=0",), "motion.v_max=0"),
        (("motion.v_max=-1.3",), "motion.v_max=-1.3"),
        (("robot.carrier.l=4",), "robot.frame.d=3.2"),
        (("grid.n=six",), "grid.n=six"),
        (("load.mass=abc",), "load.mass=abc"),
        (("no_such_key=1",), "no_such_key"),
        (("model.acceleration_set=sphere",), "model.acceleration_set=sphere"),
        (("robot=irpm6", "robot.r_end=0"), "robot.r_end=0"),
        (("-m", "robot=irpm6", "tension.t_max=55000,-1"), "tension.t_max=-1"),
        (("robot=irpm7",), "irpm7"),
    ],
)
def test_bad_input_one_line_error_nonzero_exit_no_files(tmp_path, args, key):
    proc = run(tmp_path, *args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and key in lines[0], proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_help_lists_the_choices_and_every_key_with_its_meaning(tmp_path):
    """The page is built from the schemas' docstrings for the composition asked for."""
    done = run(tmp_path, "--help")
    assert done.returncode == 0, done.stderr
    page = done.stdout
    assert "  robot: cpr8, irpm6, points (or your own robot/NAME.yaml with --config-dir DIR)" in page
    assert "schema" not in page.split("keys of this composition")[0]  # no internal names
    assert ("motion: Trapezoidal reference motion: V_cmax (m/s, from 1e-6 to 1e3), t_acc and t_dec (s); the accelerations "
            "V_cmax / t_acc and V_cmax / t_dec at most 1e4 m/s^2.") in " ".join(page.split())
    assert "  motion.v_max = 1.3" in page and "  actuator = 1" in page
    assert "``" not in page and ":func:" not in page
    irpm = run(tmp_path, "--help", "robot=irpm6", "robot.gamma_deg=30").stdout
    assert "  robot.gamma_deg = 30.0" in irpm and "pair angle gamma (deg)" in " ".join(irpm.split())
    assert "  motion.v_max =" not in irpm and "  actuator = null" in irpm and "  tension.t_max = 55000.0" in irpm
    bad = run(tmp_path, "--help", "robot=nosuch")
    assert bad.returncode == 2 and bad.stderr.startswith("error: robot=nosuch: no such option")
    points = run(tmp_path, "--help", "robot=points", "robot.l_max=3")  # it refused: its points are required
    assert points.returncode == 0, points.stderr
    assert "  robot.anchors = ??? (required)" in points.stdout and "  robot.l_max = 3" in points.stdout
    assert "  robot.dofs = [x, y, z, rx, ry, rz]" in points.stdout
    typo = run(tmp_path, "--help", "robot=points", "robot.l_mx=3")
    assert typo.returncode == 2 and "did you mean robot.l_max?" in typo.stderr
    assert list(tmp_path.iterdir()) == []


def test_version_names_the_project(tmp_path):
    done = run(tmp_path, "--version")
    assert done.returncode == 0 and done.stdout.startswith("cdpr-studies 0.1.0")


@pytest.mark.parametrize("args, status", [(("actuator=3", "hydra.run.dir=out"), 0), (("grid.n=six",), 2)])
def test_the_process_leaves_its_objects_to_the_exit_unscanned(tmp_path, args, status):
    """``python -m pipeline`` freezes what it imported and, when the command ends (an error
    too), every object, so that the interpreter's shutdown collects nothing it must scan
    (pipeline/__main__.py): at exit no tracked object is left outside the frozen generation
    but the few the exit itself makes, and the collector is on again."""
    report = ("print('left', len(gc.get_objects()), 'frozen', gc.get_freeze_count(), 'enabled', "
              "gc.isenabled(), file=sys.stderr)")
    out = job_at_exit(tmp_path, *args, report=report, status=status)
    _, left, _, frozen, _, enabled = out.strip().splitlines()[-1].split()
    assert int(left) < 200 and int(frozen) > 20_000 and enabled == "True", out[-500:]

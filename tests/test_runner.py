"""The pipeline's runner (``pipeline.app.plan`` then ``pipeline.app.run``: one composition per set
of config files, jobs derived from it) writes exactly what Hydra's own application writes with its
basic launcher (``hydra/launcher=basic`` hands the command to Hydra: ``pipeline.app.cli.main``)."""

import logging
import subprocess
import sys
from pathlib import Path

import yaml
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

import pipeline.app.run
from pipeline.app.problem import grid_size, validate
from pipeline.workspace.dispatch import workers_pay
from pipeline.app.plan import parse, plan, sweep_jobs
from pipeline.app.run import run
from pipeline.app.resources import CONF_DIR

# group choices (composed per set of files), plain values (derived), and a dict value (merged
# into the key, so every such job is composed in full): psi must not leak into the theta job
SWEEP = ["tension=pinv,feasible", "actuator=1,2", "load.mass=1.5", "grid.n=4",
         "orientation={psi:0.1},{theta:0.1}"]


def sweep(folder: Path, *launcher: str) -> Path:
    done = subprocess.run([sys.executable, "-m", "pipeline", "-m", *SWEEP, f"hydra.sweep.dir={folder}",
                           *launcher], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return folder


def job_files(folder: Path) -> dict[str, bytes]:
    """Every file of the sweep but logs, by relative path; Hydra's own config without the keys
    that name the launcher or the sweep folder (the job's folder relative to the sweep's)."""
    files = {}
    for path in sorted(folder.rglob("*")):
        name = str(path.relative_to(folder))
        if path.is_dir() or path.suffix == ".log" or path.name == ".lock":
            continue
        if path.name in ("hydra.yaml", "multirun.yaml"):
            hydra = yaml.safe_load(path.read_text())["hydra"]
            for key in ("launcher", "sweep"):
                hydra.pop(key)
            hydra["runtime"]["choices"].pop("hydra/launcher")
            if hydra["runtime"].get("output_dir", "???") != "???":  # the job's folder, in the sweep's
                hydra["runtime"]["output_dir"] = str(Path(hydra["runtime"]["output_dir"]).relative_to(
                    folder.resolve()))
            hydra["overrides"]["hydra"] = [o for o in hydra["overrides"]["hydra"]
                                           if not o.startswith(("hydra/launcher", "hydra.sweep.dir", "hydra.launcher"))]
            files[name] = yaml.safe_dump(hydra).encode()
        else:
            files[name] = path.read_bytes()
    return files


def test_the_runner_writes_what_hydras_basic_launcher_writes(tmp_path, monkeypatch, caplog):
    """In this process, one job after another, and on two worker processes (which the cost model
    keeps for jobs that pay for their start: forced here, these eight are too short)."""
    basic = job_files(sweep(tmp_path / "basic", "hydra/launcher=basic"))
    assert len([n for n in basic if n.endswith("points.parquet")]) == 8
    assert job_files(sweep(tmp_path / "serial", "hydra/launcher=cdpr")) == basic
    pooled = plan(["-m", *SWEEP, f"hydra.sweep.dir={tmp_path / 'pool'}", "hydra.launcher.n_jobs=2"])
    assert not workers_pay([(job.cfg, job.problem, grid_size(job.cfg)) for job in pooled.jobs], 2)
    monkeypatch.setattr(pipeline.app.run, "workers_pay", lambda jobs, workers: True)
    with caplog.at_level(logging.INFO, logger="pipeline"):
        run(pooled, hydra_logging=False)
    assert "Launching 8 jobs on 2 worker processes" in caplog.text
    assert job_files(tmp_path / "pool") == basic
    theta = next(n for n in basic if "theta" in n and n.endswith("config.yaml"))
    orientation = yaml.safe_load(basic[theta])["orientation"]
    assert orientation["theta"] == 0.1 and orientation["psi"] == 0.0


def test_jobs_too_short_for_workers_run_in_this_process_and_long_ones_get_them(tmp_path, caplog):
    """The cost model of hydra.launcher.n_jobs: eight jobs of 64 poses do not pay for starting
    two workers (about a second each); five of 1.2 million poses, or the straight lines of 40
    CPR-8 jobs, do."""
    small = plan(["-m", *SWEEP, f"hydra.sweep.dir={tmp_path / 'small'}", "hydra.launcher.n_jobs=2"])
    with caplog.at_level(logging.INFO, logger="pipeline"):
        run(small, hydra_logging=False)
    assert "hydra.launcher.n_jobs=2: 8 jobs too short to pay for starting worker processes" in caplog.text
    assert "Launching 8 jobs locally" in caplog.text
    large = plan(["-m", "actuator=1,2,3,4,5", "grid.n=106", "hydra.launcher.n_jobs=2"])
    assert workers_pay([(job.cfg, job.problem, grid_size(job.cfg)) for job in large.jobs], 2)
    lines = plan(["-m", "analysis=lines", "actuator=1,2,3,4,5", "load.mass=1,1.5,2,2.5,3,3.5,4,4.5",
                  "hydra.launcher.n_jobs=2"])
    assert len(lines.jobs) == 40 and workers_pay([(job.cfg, job.problem, grid_size(job.cfg)) for job in lines.jobs], 2)
    assert not workers_pay([(job.cfg, job.problem, grid_size(job.cfg)) for job in lines.jobs[:5]], 2)


def test_planned_configs_are_those_a_job_would_type_itself():
    """Every planned job holds the config Hydra composes for it and the typed config Hydra's own
    task (``pipeline.app.cli.main``) would type and validate from it."""
    argv = ["-m", *SWEEP[:3], "load.mass=1.5,2", "robot=cpr8", "model.pinv_columns=full"]
    planned = plan(argv).jobs
    jobs = sweep_jobs(parse(argv[1:]))
    assert len(jobs) == len(planned) == 8
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name="test"):
        for job, overrides in zip(planned, jobs):
            composed = compose(config_name="config", overrides=overrides)
            assert OmegaConf.to_yaml(job.config) == OmegaConf.to_yaml(composed)
            assert OmegaConf.to_yaml(job.cfg) == OmegaConf.to_yaml(validate(composed, job.catalogue)[0])


def test_job_folder_settings_are_honoured_as_by_the_basic_launcher(tmp_path):
    """``hydra.job.chdir=true`` and ``hydra.job.env_set``: the runner writes the files the basic
    launcher writes, and nothing in the folder the command was started from. A sweep over
    values only: its jobs are derived from one composition, fixed values and group choice
    included."""
    settings = ["robot=cpr8", "actuator=1,2", "load.mass=3", "grid.n=3", "hydra.job.chdir=true",
                "+hydra.job.env_set.CDPR_NOTE=x"]

    def files(name: str, *launcher: str) -> dict[str, bytes]:
        done = subprocess.run([sys.executable, "-m", "pipeline", "-m", *settings,
                               f"hydra.sweep.dir={tmp_path / name}", *launcher],
                              capture_output=True, text=True, cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        return job_files(tmp_path / name)

    basic = files("basic", "hydra/launcher=basic")
    assert len([n for n in basic if n.endswith("hydra.yaml")]) == 2
    assert files("cdpr") == basic
    assert sorted(p.name for p in tmp_path.iterdir()) == ["basic", "cdpr"]  # nothing written beside

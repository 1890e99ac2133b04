"""A command of run mode (``python -m pipeline key=value ...``) runs its job on the preflight's
composition (pipeline.app.preflight.hydra_run, hydra_plugins/cdpr/runner.run) instead of
Hydra's two compositions: it must write, log and print exactly what Hydra's own run does
(``--run``, a flag, keeps Hydra's path), and leave to Hydra every command it cannot derive."""

import re
import subprocess
import sys
import warnings
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from hydra import compose, initialize_config_dir
from hydra.experimental.callback import Callback
from omegaconf import OmegaConf

from hydra_plugins.cdpr.runner import run
from pipeline.app.preflight import Reuse, check, hydra_run
from pipeline.app.resources import CONF_DIR

STAMP = re.compile(r"^\[\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3}\]", re.MULTILINE)


def outcome(cwd: Path, folder: str, *args: str) -> dict:
    """Everything a run leaves in ``folder`` and prints, with the folder's name and the log's
    time stamps replaced, so two runs into two folders compare."""
    done = subprocess.run([sys.executable, "-m", "pipeline", *args, f"hydra.run.dir={folder}"], cwd=cwd,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]

    def neutral(text: str) -> str:
        return STAMP.sub("[T]", text.replace(str(cwd / folder), "<out>").replace(folder, "<out>"))

    files = {}
    for path in sorted((cwd / folder).rglob("*")):
        if path.is_file() and path.name != ".lock":
            name = str(path.relative_to(cwd / folder))
            files[name] = (pq.read_table(path).to_pylist() if path.suffix == ".parquet"
                           else neutral(path.read_text()))
    return {"files": files, "stdout": neutral(done.stdout), "stderr": neutral(done.stderr)}


@pytest.mark.slow
@pytest.mark.parametrize("args", [
    ["actuator=3", "grid.n=4"],
    ["robot=irpm6", "robot.search.step=1", "robot.gamma_deg=20", "wrench.fx=100", "hydra/job_logging=none"],
    ["tension=feasible", "grid.n=3", "hydra.job.chdir=true", "load.mass=3"],
])
def test_a_command_of_run_mode_does_what_hydras_run_does(tmp_path, args):
    ours, hydras = outcome(tmp_path, "ours", *args), outcome(tmp_path, "hydras", "--run", *args)
    assert ours == hydras
    logged = () if "hydra/job_logging=none" in args else ("pipeline.log",)
    assert {".hydra/config.yaml", ".hydra/hydra.yaml", ".hydra/overrides.yaml", "summary.parquet",
            "points.parquet", *logged} == set(ours["files"])
    assert "mode: RUN" in ours["files"][".hydra/hydra.yaml"]


def test_only_commands_hydra_would_compose_the_same_way_are_derived():
    def derived(*argv):
        reuse = Reuse(folders_after=False)
        check(list(argv), reuse)
        return hydra_run(list(argv), reuse)

    for argv in (["actuator=3"], ["robot=irpm6", "wrench.fx=5", "hydra.run.dir=x"], []):
        config, task = derived(*argv)
        assert config.hydra.mode.name == "RUN" and "hydra" not in task
        assert list(config.hydra.overrides.task) == [a for a in argv if not a.startswith("hydra.")]
    for argv in (["-m", "actuator=1,2"], ["--run", "actuator=3"], ["+hydra.job.env_set.CDPR_X=1"],
                 ["~hydra.callbacks.sweep_summary"],
                 ["++load.mass=3"], ["orientation={psi:0.1}"], ["hydra.mode=MULTIRUN", "actuator=2"],
                 ["hydra.verbose=true"]):
        assert derived(*argv) is None, argv


CALLS = []  # what the Recorder callbacks were told, in order


class Recorder(Callback):
    """A callback that records what it is told in CALLS, or raises there."""

    def __init__(self, name: str, fail: str = "") -> None:
        self.name, self.fail = name, fail

    def _record(self, event: str) -> None:
        CALLS.append(f"{event} {self.name}")
        if event == self.fail:
            raise RuntimeError("boom")

    def on_run_start(self, config, **kwargs):
        self._record("on_run_start")

    def on_run_end(self, config, **kwargs):
        self._record("on_run_end")

    def on_job_start(self, config, **kwargs):
        self._record("on_job_start")

    def on_job_end(self, config, job_return, **kwargs):
        self._record("on_job_end")


def test_callbacks_are_called_in_hydras_order_and_a_failing_one_only_warns(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    CALLS.clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        config = compose(config_name="config", overrides=["hydra.mode=RUN", "hydra.run.dir=job"],
                         return_hydra_config=True)
    OmegaConf.set_struct(config, False)
    config.hydra.callbacks = {name: {"_target_": f"{__name__}.Recorder", "name": name,
                                     "fail": "on_job_end" if name == "b" else ""} for name in ("a", "b")}
    task = OmegaConf.masked_copy(config, [k for k in config if k != "hydra"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ret = run(config, task, lambda cfg: cfg.load.mass * 2)
    assert ret.return_value == 4.0 and (tmp_path / "job" / ".hydra" / "config.yaml").exists()
    assert CALLS == ["on_run_start a", "on_run_start b", "on_job_start a", "on_job_start b",
                     "on_job_end b", "on_job_end a", "on_run_end b", "on_run_end a"]
    assert [str(w.message) for w in caught] == ["Callback Recorder.on_job_end raised RuntimeError: boom"]
    with pytest.warns(UserWarning, match="boom"), pytest.raises(ZeroDivisionError):  # as Hydra's run
        run(config, task, lambda cfg: 1 / 0)
